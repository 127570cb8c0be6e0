"""``mechderive derive``: the toolkit's derived equations out, as text, LaTeX, SymPy, Python, C or JSON.

Modules, one job each:

- :mod:`.catalog` — what each system can print (description, equation number, derivation);
- :mod:`.options` — shapes, pivots, numeric moments and values substituted into the results;
- :mod:`.sequences` — the twelve Euler sequences, body- or space-fixed, and SciPy's names for them;
- :mod:`.api` — :func:`derive` (SymPy objects) and :func:`derive_entries` (with descriptions);
- :mod:`.formats` — :func:`to_text`, :func:`to_latex`, :func:`to_sympy_source`,
  :func:`to_python_source`, :func:`to_c_source`, :func:`to_json` and :func:`render`.

Everything is derived by the toolkit's models; nothing printed is typed in.
"""

from .api import Derived, derive, derive_entries
from .catalog import SYSTEMS, listing
from .formats import FORMATS, render, to_c_source, to_json, to_latex, to_python_source, to_sympy_source, to_text
from .sequences import SEQUENCES, angular_velocity_sequence, rotation_sequence, scipy_sequence

__all__ = [
    "FORMATS",
    "SEQUENCES",
    "SYSTEMS",
    "Derived",
    "angular_velocity_sequence",
    "derive",
    "derive_entries",
    "listing",
    "render",
    "rotation_sequence",
    "scipy_sequence",
    "to_c_source",
    "to_json",
    "to_latex",
    "to_python_source",
    "to_sympy_source",
    "to_text",
]
