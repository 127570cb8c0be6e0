"""``python -m mechderive``: the ``mechderive`` command line (see :mod:`mechderive.cli`).

Only ``python -m`` runs this module, so ``import mechderive`` stays as light as before.
"""

import sys

from .cli import main

sys.exit(main())
