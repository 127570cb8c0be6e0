"""Jacobi elliptic functions sn, cn, dn and the amplitude am, accurate for every 0 <= m <= 1.

Convention (as in mpmath's ``ellipfun``, DLMF §22.2 with k² = m)
----------------------------------------------------------------
For the parameter m = k² and the complementary parameter m1 = 1 - m = k'²,

    u = F(φ | m) = ∫₀^φ dθ / √(1 - m sin²θ),    φ = am(u | m),
    sn(u|m) = sin φ,   cn(u|m) = cos φ,   dn(u|m) = √(1 - m sn²(u|m)),

    K(m) = F(π/2 | m),   K'(m) = K(m1).

Periods (DLMF 22.4.iii): sn(u + 2K) = -sn u, cn(u + 2K) = -cn u, dn(u + 2K) = dn u,
so sn and cn have period 4K and dn period 2K; am(u + 2K) = am(u) + π.
Special cases: m = 0 gives sin, cos, 1 and am(u) = u; m = 1 gives tanh, sech,
sech and am(u) = gd(u) = arctan(sinh u) (K = ∞, no period).

Near the separatrix pass m1 explicitly (``m1=1e-14`` keeps all its digits, whereas
``m = 1 - 1e-14`` is already rounded); see :mod:`mechderive.special._parameter`
for which of m, m1 is taken as exact.

Algorithm
---------
1. Reduce u = j·2K + r, |r| <= K, with K = π/(2 AGM(1, √m1)) in double-double, so the
   reduction of the *double* u is exact to ~|u|·1e-32 (any period count below ~1e15
   costs nothing).  The remaining large-|u| error is the rounding of u itself,
   ulp(u) ≈ |u|·1.1e-16; callers who know the period count exactly pass
   ``periods=n`` and u = remainder, and lose nothing.
2. For K/2 < |r| <= K use the quarter-period shift (DLMF 22.4.iii, z = K - v)
   sn = cd v, cn = k' sd v, dn = k' nd v with v = K - |r| formed in double-double, so
   cn near its zero and dn ≈ k' keep full *relative* accuracy.
3. On 0 <= v <= K/2 use Bulirsch's descending Gauss/Landen algorithm ``sncndn``
   (Numer. Math. 7 (1965) 78-90), which is driven by m1 directly and has no
   cancellation; for v < 2⁻²⁰ the Maclaurin series (DLMF 22.10.1-3).
4. For m1 < 1e-2, where the Gauss algorithm's relative error in cn and dn grows like
   v·ulp (its phase is compressed by π/2K), take cn and dn from the rapidly convergent
   sech series (DLMF 22.12.8-9 for the modulus k', through Jacobi's imaginary
   transformation DLMF 22.6.iv) with the leading phase in double-double.

Accuracy, measured against mpmath on [0, 4K] for m1 from 1 to 1e-14: sn, cn, dn within
~4 ulp *relative* (cn near its zeros and dn ≈ √m1 included).

>>> import numpy as np
>>> sn, cn, dn = jacobi_sn_cn_dn(0.5, 0.3)
>>> print(f"{sn:.15f} {cn:.15f} {dn:.15f}")
0.474215622711821 0.880408736426463 0.965678964745951
>>> sn, cn, dn = jacobi_sn_cn_dn(1.0, 1.0)      # m = 1: tanh, sech, sech
>>> bool(np.isclose(sn, np.tanh(1.0))), bool(np.isclose(cn, 1 / np.cosh(1.0)))
(True, True)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.validate import as_finite_array
from ._doubledouble import PI_HI, PI_LO, two_prod, two_sum
from ._parameter import as_output, check_periods, parameter
from ._sncndn import reduced_sn_cn_dn

__all__ = ["jacobi_sn_cn_dn", "jacobi_am", "shift_by_quarter_periods"]


def jacobi_sn_cn_dn(u: Any, m: Any, *, m1: Any = None,
                    periods: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Jacobi sn(U|m), cn(U|m), dn(U|m) at U = u, or at U = periods·4K(m) + u.

    Defined by φ = am(U|m), U = ∫₀^φ dθ/√(1 - m sin²θ): sn = sin φ, cn = cos φ,
    dn = √(1 - m sn²) (DLMF 22.16.1, 22.2).  Vectorised: u, m, m1, periods broadcast.

    Parameters
    ----------
    u : argument (the remainder when ``periods`` is given).
    m : parameter m = k², 0 <= m <= 1.
    m1 : complementary parameter 1 - m, keyword-only.  Give it when it is known more
        accurately than 1 - m (near the separatrix); the smaller of m and m1 is taken
        as exact and the pair must satisfy |m + m1 - 1| <= 1e-15.
    periods : integer count n of full periods 4K(m), keyword-only.  The result is at
        n·4K + u with no rounding of n·4K at all (4K is an exact period of sn, cn, dn).

    Accuracy: sn, cn, dn to a few ulp *relative* to themselves (including cn near its
    zeros and dn ≈ √m1 near m = 1) as functions of the double u.  The reduction by the
    period is exact to ~|u|·1e-32, so for |u| up to ~1e15 the only large-argument loss is
    the representation of u itself (relative rounding 1.1e-16·|u| in the phase); pass
    ``periods`` to avoid it.  m = 0: (sin u, cos u, 1); m = 1: (tanh u, sech u, sech u).

    >>> sn, cn, dn = jacobi_sn_cn_dn(3.0, 1 - 1e-12, m1=1e-12)
    >>> print(f"{sn:.16f} {cn:.6e} {dn:.6e}")
    0.9950547536869718 9.932793e-02 9.932793e-02
    >>> a = jacobi_sn_cn_dn(0.7, 0.38, periods=10**6)[0]
    >>> b = jacobi_sn_cn_dn(0.7, 0.38)[0]
    >>> bool(a == b)
    True
    """
    p = parameter(m, m1)
    u_arr = as_finite_array(u, "u")
    if periods is not None:
        n = check_periods(periods)
        u_arr, _ = np.broadcast_arrays(u_arr, n)  # 4K is a period: n only shapes the result
    sn, cn, dn = reduced_sn_cn_dn(u_arr, p)[:3]
    return as_output(sn), as_output(cn), as_output(dn)


def jacobi_am(u: Any, m: Any, *, m1: Any = None, periods: Any = None) -> np.ndarray:
    """Jacobi amplitude φ = am(U|m), continuous in U, at U = u or U = periods·4K(m) + u.

    φ solves U = F(φ|m) = ∫₀^φ dθ/√(1 - m sin²θ) (DLMF 22.16.1); it is unwrapped:
    am(U + 2K) = am(U) + π (DLMF 22.16.2), so am(n·4K + u) = 2πn + am(u).  m = 0 gives
    am(u) = u; m = 1 gives the Gudermannian gd(u) = arctan(sinh u) (the k → 1 limit, DLMF §22.16(i)).
    Accuracy: ~1 ulp of the result plus the argument's own rounding (see
    :func:`jacobi_sn_cn_dn`).

    >>> print(f"{float(jacobi_am(0.5, 0.3)):.15f}")
    0.494072893711047
    >>> float(jacobi_am(2.0, 0.0))
    2.0
    >>> from mechderive.special.integrals import ellipk_m1
    >>> K = ellipk_m1(0.62)
    >>> print(f"{float(jacobi_am(2 * K, 0.38) / np.pi):.15f}")
    1.000000000000000
    """
    p = parameter(m, m1)
    u_arr = as_finite_array(u, "u")
    sn, cn, dn, j, sign, flip, (S, C) = reduced_sn_cn_dn(u_arr, p)
    kc = np.sqrt(np.broadcast_to(p.m1 + p.m1_lo, sn.shape))
    # am(|r|) in [0, K]: atan2(S, C), or atan2(C, k'S) after the quarter-period shift
    am_a = np.where(flip, np.arctan2(C, kc * S), np.arctan2(S, C))
    one = np.broadcast_to(p.m1 == 0.0, sn.shape)
    am_a = np.where(one, np.arctan2(np.abs(sn), cn), am_a)
    # j·π + sign·am_a, rounded once
    hi, lo = two_prod(j, PI_HI)
    hi, lo2 = two_sum(hi, sign * am_a)
    result = hi + (lo + lo2 + j * PI_LO)
    if periods is not None:
        n = check_periods(periods)
        hi, lo = two_prod(2.0 * n, PI_HI)
        s, e = two_sum(hi, result)
        result = s + (e + lo + 2.0 * n * PI_LO)
    return as_output(result)


def shift_by_quarter_periods(q: int, sn: Any, cn: Any, dn: Any, kc: Any) -> tuple[Any, Any, Any]:
    """(sn, cn, dn) at v + q·K from their values at v, with kc = √(1 − m) (DLMF 22.4.iii: sn(v + K) = cd v,
    cn(v + K) = −k' sd v, dn(v + K) = k' nd v; period 4K).  Plain arithmetic: doubles, longdoubles, mpmath
    numbers or arrays alike.

    >>> shift_by_quarter_periods(2, 0.5, 0.8, 0.9, 0.6)
    (-0.5, -0.8, 0.9)
    """
    q = q % 4
    if q % 2 == 0:
        sign = 1 if q == 0 else -1
        return sign * sn, sign * cn, dn
    sign = 1 if q == 1 else -1
    return sign * cn / dn, -sign * kc * sn / dn, kc / dn
