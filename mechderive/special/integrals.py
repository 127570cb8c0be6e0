"""Legendre's elliptic integrals F, E, Π for every real amplitude, via Carlson's R_F, R_D, R_J.

Convention (as in mpmath's ``ellipf``, ``ellipe``, ``ellippi``; DLMF §19.2 with k² = m)
-----------------------------------------------------------------------------------------
For parameter m = k² and complementary parameter m1 = 1 - m = k'², Δ(θ) = √(1 - m sin²θ):

    F(φ|m)    = ∫₀^φ dθ / Δ(θ),                 K(m) = F(π/2|m),  K'(m) = K(m1),
    E(φ|m)    = ∫₀^φ Δ(θ) dθ,                   E(m) = E(π/2|m),
    Π(n; φ|m) = ∫₀^φ dθ / ((1 - n sin²θ) Δ(θ)),  Π(n|m) = Π(n; π/2|m).

On |φ| <= π/2, with s = sin φ, c = cos φ, Δ² = c² + m1 s² (no cancellation as m → 1):

    F = s R_F(c², Δ², 1)                                                  (DLMF 19.25.5)
    E = m1 s R_F(c², Δ², 1) + (m m1/3) s³ R_D(c², 1, Δ²) + m s c/Δ        (DLMF 19.25.10)
    Π = s R_F(c², Δ², 1) + (n/3) s³ R_J(c², Δ², 1, 1 - n s²)              (DLMF 19.25.14)

(19.25.10 is a sum of positive terms, unlike 19.25.9, which cancels ~K-fold near m = 1.)
Beyond, with φ = jπ + ψ, |ψ| <= π/2, the quasi-periodicity (DLMF 19.2.10)

    F(φ|m) = 2jK(m) + F(ψ|m),  E(φ|m) = 2jE(m) + E(ψ|m),  Π(n; φ|m) = 2jΠ(n|m) + Π(n; ψ|m),

with ψ = φ - jπ formed in double-double so large φ lose nothing in the reduction.

Supported n: every n < 1; n = 1 for |φ| < π/2 only (the integrand has a double pole at
π/2, so Π(1|m) and anything past it diverge); n > 1 as the Cauchy principal value
through the simple pole at sin²θ = 1/n (SciPy's R_J returns the principal value for a
negative last argument, DLMF 19.20.14).  m = 1: F and Π exist only for |φ| < π/2
(F(φ|1) = artanh(sin φ)); E(φ|1) = 2j + sin ψ.  Where the integral diverges these
functions raise :class:`~mechderive.errors.InvalidInputError`.

>>> print(f"{float(elliptic_f(1.0, 0.5)):.15f}")
1.083216772845169
>>> import numpy as np
>>> K = ellipk_m1(0.5)
>>> print(f"{float(elliptic_f(np.pi, 0.5) - 2 * K):.1e}")
0.0e+00
"""

from __future__ import annotations

from typing import Any

import numpy as np
from ._carlson import elliprd, elliprf, elliprj

from ..core.validate import as_finite_array
from ..errors import InvalidInputError
from ._legendre import (
    NEG_N,
    assemble,
    check_m_one,
    check_pole,
    complete_e,
    complete_pi,
    complete_pi_rj,
    delta2,
    one_minus_n_s2,
    pi_half,
    periods_pi,
    reduce_angle,
)
from ._parameter import as_output, check_periods, check_unit_interval, parameter, quarter_period
from ._sncndn import reduced_sn_cn_dn

__all__ = [
    "ellipk_m1",
    "elliptic_e",
    "elliptic_pi",
    "elliptic_f",
    "elliptic_e_incomplete",
    "elliptic_pi_incomplete",
    "pi_of_am",
]


def _once_if_uniform(complete, n_arr: np.ndarray, p):
    """``complete(n, p)`` shaped like ``n_arr``, computed once per distinct n when m is one number.

    The usual call has one or a few characteristics and one parameter for thousands of phases;
    evaluating the complete integral per point would double the cost of Π(n; am u | m).
    """
    if n_arr.size > 1 and np.size(p.m) == 1 and np.all(n_arr == n_arr.flat[0]):
        return np.broadcast_to(complete(n_arr.flat[0:1], p), n_arr.shape)
    return complete(n_arr, p)


def ellipk_m1(m1: Any) -> np.ndarray:
    """K(m) = ∫₀^{π/2} dθ/√(1 - m sin²θ) as a function of the complementary parameter m1 = 1 - m.

    K = π / (2 AGM(1, √m1)) (DLMF 19.8.5), computed in double-double and rounded, so it
    is correctly rounded but for rare ties.  K'(m) = ellipk_m1(m).  m1 = 1 gives π/2;
    K ~ ln(4/√m1) as m1 → 0 (DLMF 19.12.1) and m1 = 0 gives inf.

    >>> print(f"{float(ellipk_m1(1e-14)):.15f}")
    17.504390012078250
    >>> float(ellipk_m1(1.0)) == np.pi / 2
    True
    """
    m1_arr = as_finite_array(m1, "m1")
    check_unit_interval(m1_arr, "m1")
    return as_output(quarter_period(m1_arr, np.zeros_like(m1_arr))[0])


def elliptic_e(m: Any, *, m1: Any = None) -> np.ndarray:
    """Complete E(m) = ∫₀^{π/2} √(1 - m sin²θ) dθ, accurate for m1 = 1 - m down to 0.

    DLMF 19.25.10 at φ = π/2 (positive terms only).  E(0) = π/2, E(1) = 1.

    >>> print(f"{float(elliptic_e(0.5)):.14f}")
    1.35064388104768
    """
    return as_output(complete_e(parameter(m, m1)))


def elliptic_pi(n: Any, m: Any, *, m1: Any = None) -> np.ndarray:
    """Complete Π(n|m) = ∫₀^{π/2} dθ / ((1 - n sin²θ)√(1 - m sin²θ)) = K + (n/3) R_J(0, m1, 1, 1 - n).

    DLMF 19.25.2; for n < -1/4, where the R_J term would cancel most of K, the change of
    parameter DLMF 19.21.12 gives π/(2√((1 - n)(1 + m/|n|))) + (m/3|n|) R_J(0, m1, 1, 1 + m/|n|).
    n < 1 any; n > 1 gives the Cauchy principal value (then Π(n|m) = K - Π(m/n|m),
    DLMF 19.6.5); n = 1 or m = 1 diverge and raise.
    Π(0|m) = K(m); Π(n|0) = π / (2√(1 - n)) for n < 1.

    >>> print(f"{float(elliptic_pi(0.3, 0.5)):.14f}")
    2.25037682194395
    """
    n_arr = as_finite_array(n, "n")
    p = parameter(m, m1)
    if np.any(n_arr == 1):
        raise InvalidInputError("expected `n` != 1 (Π(1|m) diverges), got n = 1.0")
    if np.any(p.m1 == 0):
        raise InvalidInputError("expected `m` < 1 (Π(n|1) diverges), got m = 1.0")
    return as_output(complete_pi(n_arr, p))


def elliptic_f(phi: Any, m: Any, *, m1: Any = None) -> np.ndarray:
    """Incomplete F(φ|m) = ∫₀^φ dθ/√(1 - m sin²θ) for every real φ (quasi-periodic, DLMF 19.2.10).

    F(φ|0) = φ; F(φ|1) = artanh(sin φ) for |φ| < π/2 (raises beyond).  F(am(u|m)|m) = u.

    >>> print(f"{float(elliptic_f(100.0, 0.9)):.13f}")
    164.4430976901965
    """
    p = parameter(m, m1)
    phi_arr = as_finite_array(phi, "phi")
    phi_arr, _ = np.broadcast_arrays(phi_arr, p.m)
    j, s, c = reduce_angle(phi_arr)
    check_m_one(p, j, c, phi_arr, "F(phi|1) = artanh(sin phi)")
    d2 = delta2(s, c, p)
    half = s * elliprf(c * c, d2, 1.0)
    return as_output(assemble(j, s, c, half, p.K_hi + p.K_lo))


def elliptic_e_incomplete(phi: Any, m: Any, *, m1: Any = None) -> np.ndarray:
    """Incomplete E(φ|m) = ∫₀^φ √(1 - m sin²θ) dθ for every real φ (DLMF 19.25.10, 19.2.10).

    E(φ|0) = φ; E(φ|1) = 2j + sin ψ with φ = jπ + ψ, |ψ| <= π/2.

    >>> print(f"{float(elliptic_e_incomplete(1.0, 0.5)):.15f}")
    0.927329883624440
    """
    p = parameter(m, m1)
    phi_arr = as_finite_array(phi, "phi")
    phi_arr, _ = np.broadcast_arrays(phi_arr, p.m)
    j, s, c = reduce_angle(phi_arr)
    m = np.broadcast_to(p.m, s.shape)
    m1 = np.broadcast_to(p.m1 + p.m1_lo, s.shape)
    one = m1 == 0
    d2 = np.where(one, 1.0, delta2(s, c, p))
    c2 = c * c
    with np.errstate(invalid="ignore", divide="ignore"):
        half = (m1 * s * elliprf(c2, d2, 1.0) + m * m1 / 3.0 * s**3 * elliprd(c2, 1.0, d2)
                + m * s * np.abs(c) / np.sqrt(d2))
    half = np.where(one, s, half)                      # E(ψ|1) = sin ψ
    return as_output(assemble(j, s, c, half, complete_e(p)))


def elliptic_pi_incomplete(n: Any, phi: Any, m: Any, *, m1: Any = None) -> np.ndarray:
    """Incomplete Π(n; φ|m) = ∫₀^φ dθ / ((1 - n sin²θ)√(1 - m sin²θ)) for every real φ.

    DLMF 19.25.14 on |φ| <= π/2 (for n < -1/4 its change of parameter, DLMF 19.21.12,
    which has no cancellation: see :mod:`mechderive.special._legendre`) and
    Π(n; φ + jπ|m) = Π(n; φ|m) + 2jΠ(n|m) beyond.
    n > 1: Cauchy principal value past sin²φ = 1/n; at the pole itself, and for n = 1
    at |φ| >= π/2, it raises.  Π(0; φ|m) = F(φ|m); Π(n; φ|0) = arctan(√(1-n) tan φ)/√(1-n)
    for n < 1, |φ| < π/2.

    >>> print(f"{float(elliptic_pi_incomplete(0.3, 1.0, 0.5)):.15f}")
    1.192325436934558
    >>> print(f"{float(elliptic_pi_incomplete(-10.0, 1e3, 0.9)):.12f}")
    376.223740949454
    """
    p = parameter(m, m1)
    n_arr = as_finite_array(n, "n")
    phi_arr = as_finite_array(phi, "phi")
    n_arr, phi_arr, _ = np.broadcast_arrays(n_arr, phi_arr, p.m)
    j, s, c = reduce_angle(phi_arr)
    check_m_one(p, j, c, phi_arr, "Π(n; phi|1)")
    bad = (n_arr == 1) & ((j != 0) | (c <= 0))
    if np.any(bad):
        raise InvalidInputError(
            f"expected |phi| < pi/2 when n = 1 (Π(1; phi|m) diverges at pi/2), got phi = {float(phi_arr[bad].ravel()[0])!r}"
        )
    q = one_minus_n_s2(n_arr, s, c)
    check_pole(q, n_arr, s, c, "phi", phi_arr)
    d2 = delta2(s, c, p)
    half = pi_half(n_arr, s, c, d2, np.broadcast_to(p.m, s.shape))
    needs_complete = (j != 0) | (c < 0)
    complete = np.zeros_like(half)
    if np.any(needs_complete):
        complete = _once_if_uniform(complete_pi, n_arr, p)
    return as_output(assemble(j, s, c, half, complete))


def pi_of_am(n: Any, u: Any, m: Any, *, m1: Any = None, periods: Any = None,
             jacobi: tuple | None = None) -> np.ndarray:
    """∫₀^U du' / (1 - n sn²(u'|m)) = Π(n; am(U|m) | m) at U = u or U = periods·4K(m) + u.

    The form the heavy top's precession and spin angles take (substitute θ = am u', so
    dθ = dn u' du' = Δ(θ) du', DLMF 22.16.1).  With u = j·2K + r, |r| <= K, and
    F(am r) = r,

        pi_of_am = u + (n/3)·[2j R_J(0, m1, 1, 1 - n) + sn³ R_J(cn², dn², 1, 1 - n sn²)]

    (sn, cn, dn at r), so the reduction is exact and U = 1e6·K costs nothing; with
    ``periods`` the result adds periods·4Π(n|m) (in double).  n = 0 gives u; m = 0 gives
    Π(n; u|0); m = 1 gives ∫ du'/(1 - n tanh²u').  Same n support as
    :func:`elliptic_pi_incomplete` (n = 1 needs |U| < K; n > 1 is a principal value).
    ``jacobi``: optionally ``reduced_sn_cn_dn(u, parameter(m, m1))[:4]`` (sn, cn, dn, j at u,
    from :mod:`mechderive.special._sncndn`) when the caller has them already, e.g. for θ(t).

    >>> print(f"{float(pi_of_am(0.3, 1.2, 0.5)):.15f}")
    1.342965850035253
    >>> float(pi_of_am(0.0, 7.5, 0.9))
    7.5
    """
    p = parameter(m, m1)
    n_arr = as_finite_array(n, "n")
    u_arr = as_finite_array(u, "u")
    # sn, cn, dn on the shape of (u, m) only: several n (shape (k, 1) against u of shape (N,))
    # then share one evaluation of the Jacobi functions
    u_arr, _ = np.broadcast_arrays(u_arr, p.m)
    one = np.broadcast_to(p.m1 == 0, u_arr.shape)
    # m = 1 and |u| > 30: tanh u = ±1 in double, the integrand is 1/(1 - n) to e^-60
    cap = np.where(one & (np.abs(u_arr) > 30.0), np.sign(u_arr) * 30.0, u_arr)
    if jacobi is not None and not np.any(one):
        sn, cn, dn, j = jacobi
    else:
        sn, cn, dn, j = reduced_sn_cn_dn(cap, p)[:4]
    n_given = n_arr  # unbroadcast: the complete integrals depend on n and m only
    n_arr, u_arr, cap, one, sn, cn, dn, j = np.broadcast_arrays(n_arr, u_arr, cap, one, sn, cn, dn, j)
    parity = np.where(np.fmod(j, 2.0) == 0.0, 1.0, -1.0)
    sn, cn = parity * sn, parity * cn                  # sn(r), cn(r): u = j·2K + r
    bad = (n_arr == 1) & ~one & ((j != 0) | (cn <= 0))
    if np.any(bad):
        raise InvalidInputError(
            f"expected |u| < K(m) when n = 1 (the integrand 1/cn² has a double pole at K), got u = "
            f"{float(u_arr[bad].ravel()[0])!r}"
        )
    q = one_minus_n_s2(n_arr, sn, cn)
    check_pole(q, n_arr, sn, cn, "u", u_arr)
    neg = n_arr < NEG_N
    # cn(r) < 0 only by rounding at |r| = K: mirror as in assemble
    past = cn < 0
    jeff = j + np.where(past, np.where(sn < 0, -1.0, 1.0), 0.0)
    result = np.zeros_like(cap)
    if np.any(~neg):
        # u + (n/3)[2j R_J(0, m1, 1, 1 - n) + sn³ R_J(cn², dn², 1, 1 - n sn²)]: F(am r) = r exactly
        with np.errstate(all="ignore"):
            half = sn**3 * elliprj(cn * cn, dn * dn, 1.0, q)
        part = np.where(past, -half, half)
        if np.any(jeff != 0):
            with np.errstate(invalid="ignore"):
                part = part + np.where(jeff != 0, 2.0 * jeff * _once_if_uniform(complete_pi_rj, n_given, p), 0.0)
        result = cap + n_arr / 3.0 * part
    if np.any(neg):
        # n < -1/4: 2jΠ(n|m) + Π(n; am r|m), both by the change of parameter (no cancellation)
        half = pi_half(n_arr, sn, cn, dn * dn, np.broadcast_to(p.m, sn.shape))
        complete = np.broadcast_to(_once_if_uniform(complete_pi, n_given, p), half.shape) if np.any(jeff != 0) \
            else np.zeros_like(half)
        result = np.where(neg, assemble(j, sn, cn, half, complete), result)
    with np.errstate(all="ignore"):
        result = np.where(cap != u_arr, result + (u_arr - cap) / (1.0 - n_arr), result)
        # m = 1, n = 1: ∫ cosh² = (u + sinh u cosh u)/2
        result = np.where(one & (n_arr == 1), 0.5 * (u_arr + 0.5 * np.sinh(2.0 * u_arr)), result)
    if periods is not None:
        n_per = check_periods(periods)
        result = result + 4.0 * n_per * periods_pi(n_arr, p)
    return as_output(result)
