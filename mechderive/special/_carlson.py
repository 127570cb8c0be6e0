"""SciPy's Carlson symmetric elliptic integrals R_C, R_D, R_F, R_J, imported on first use.

``scipy.special`` takes ~0.3 s to import; a warm ``mechderive run`` must not pay it
when the requested quantities need no elliptic integral (θ(t) alone, say).
"""

from __future__ import annotations

import functools
from typing import Any


@functools.cache
def _scipy():
    import scipy.special

    return scipy.special


def elliprc(*args: Any):
    """R_C(x, y) (DLMF 19.2.17), vectorised; SciPy's implementation."""
    return _scipy().elliprc(*args)


def elliprd(*args: Any):
    """R_D(x, y, z) (DLMF 19.16.5), vectorised; SciPy's implementation."""
    return _scipy().elliprd(*args)


def elliprf(*args: Any):
    """R_F(x, y, z) (DLMF 19.16.1), vectorised; SciPy's implementation."""
    return _scipy().elliprf(*args)


def elliprj(*args: Any):
    """R_J(x, y, z, p) (DLMF 19.16.2), vectorised; SciPy's implementation."""
    return _scipy().elliprj(*args)
