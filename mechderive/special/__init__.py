"""Elliptic functions and integrals, accurate for every parameter and argument, vectorised in NumPy.

Convention (mpmath's and DLMF's, §19.2 and §22.2, with k² = m)
---------------------------------------------------------------
Parameter m = k², complementary parameter m1 = 1 - m = k'², and

    F(φ|m) = ∫₀^φ dθ/√(1 - m sin²θ),   K(m) = F(π/2|m),   K'(m) = K(m1),
    u = F(φ|m)  ⇔  φ = am(u|m),   sn u = sin φ,   cn u = cos φ,   dn u = √(1 - m sn²u).

Every function accepts ``m1`` keyword-only: near the separatrix (m → 1) pass it, since
``m1=1e-14`` is exact while ``1 - 1e-14`` is already rounded.  The smaller of m and m1
is taken as exact; both given must agree to |m + m1 - 1| <= 1e-15.

Why not ``scipy.special.ellipj``: it is wrong for 1 - m <= 1e-10 (sn off by 2, cn and dn
by 3e11) and loses phase at large u.  Here sn, cn, dn, am are reduced by the period with
K known to ~32 digits and evaluated to a few ulp *relative* (dn ≈ √m1 and cn near its
zeros included); ``periods=`` takes an exact count of periods 4K.

At u = K (rounded to double) near the separatrix, cn is the tiny value -k'·(u - K) and
dn = k' = √m1, both to full relative accuracy:

>>> from mechderive.special import jacobi_sn_cn_dn, ellipk_m1
>>> sn, cn, dn = jacobi_sn_cn_dn(ellipk_m1(1e-12), 1 - 1e-12, m1=1e-12)
>>> print(f"{sn:.16f} {cn:.10e} {dn:.10e}")
1.0000000000000000 -1.7779607518e-22 1.0000000000e-06
"""

from __future__ import annotations

import importlib
from typing import Any

#: public name -> the module that defines it, imported on first use: the closed forms import the private
#: modules they need (``_doubledouble``, ``_sncndn``, ...), which runs this file first; importing every
#: function here made a warm run load the incomplete integrals it does not use
_PUBLIC = {
    "jacobi_sn_cn_dn": "jacobi",
    "jacobi_am": "jacobi",
    "ellipk_m1": "integrals",
    "elliptic_e": "integrals",
    "elliptic_f": "integrals",
    "elliptic_e_incomplete": "integrals",
    "elliptic_pi": "integrals",
    "elliptic_pi_incomplete": "integrals",
    "pi_of_am": "integrals",
}

__all__ = list(_PUBLIC)


def __getattr__(name: str) -> Any:
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
