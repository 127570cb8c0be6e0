"""``python -m mechderive.cli``: the same as ``python -m mechderive``."""

import sys

from . import main

sys.exit(main())
