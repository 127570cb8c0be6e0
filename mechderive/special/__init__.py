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

from .integrals import (
    ellipk_m1,
    elliptic_e,
    elliptic_e_incomplete,
    elliptic_f,
    elliptic_pi,
    elliptic_pi_incomplete,
    pi_of_am,
)
from .jacobi import jacobi_am, jacobi_sn_cn_dn

__all__ = [
    "jacobi_sn_cn_dn",
    "jacobi_am",
    "ellipk_m1",
    "elliptic_e",
    "elliptic_f",
    "elliptic_e_incomplete",
    "elliptic_pi",
    "elliptic_pi_incomplete",
    "pi_of_am",
]
