"""The evaluation core behind :mod:`mechderive.special.jacobi` (private).

Given u and a validated parameter, :func:`reduced_sn_cn_dn` returns sn, cn, dn with a few
ulp *relative* error:

1. u = j·2K + r, |r| <= K, reduced with K in double-double (:mod:`._parameter`).
2. For K/2 < |r| <= K, the quarter-period shift (DLMF 22.4.iii, z = K - v):
   sn = cd v, cn = k' sd v, dn = k' nd v with v = K - |r| formed in double-double.
3. On 0 <= v <= K/2, Bulirsch's descending Gauss/Landen ``sncndn`` (Numer. Math. 7 (1965)
   78-90), driven by m1 directly; for v < 2⁻²⁰ the Maclaurin series (DLMF 22.10.1-3).
4. For m1 < 1e-2 cn and dn instead come from the sech series (DLMF 22.12.8-9 for the
   modulus k' via Jacobi's imaginary transformation, DLMF 22.6.iv), whose error does not
   grow with v as the Gauss algorithm's does.

>>> from mechderive.special._parameter import parameter
>>> import numpy as np
>>> sn, cn, dn = reduced_sn_cn_dn(np.array([0.0]), parameter(0.5))[:3]
>>> float(sn[0]), float(cn[0]), float(dn[0])
(0.0, 1.0, 1.0)
"""

from __future__ import annotations

import functools

import numpy as np

from ..core.validate import every, some
from ..errors import InvalidInputError
from ._doubledouble import PI_HI, PI_LO, dd_div, two_prod, two_sum
from ._parameter import Parameter, quarter_period, reduce_by_half_periods

__all__ = ["reduced_sn_cn_dn"]

_SERIES_BELOW = 2.0**-20   # |v| below this: Maclaurin series, error O(v⁴) < 1e-24
_AGM_TOL = 2.0**-27        # stop the AGM when |a - b| <= tol·a; neglected terms O(tol²/16)
_SECH_SERIES_BELOW = 1e-2  # m1 below this: cn, dn from the sech series (DLMF 22.12.8-9 via 22.6.iv)
_MAX_PERIODS = 2.0**52     # |u| <= 2^52 K keeps the half-period count j an exact integer


def _agm_levels(m1: np.ndarray):
    """Forward Gauss (AGM) sequence of Bulirsch's sncndn for k'² = m1 > 0.

    Returns (a_levels, b_levels, n_levels, c): a_i, b_i = √(a_{i-1} b_{i-1}) per level, the
    number of levels used per element, and c = AGM(1, k') = π/(2K).
    """
    a = np.ones_like(m1)
    emc = m1.copy()
    a_levels, b_levels = [], []
    n_levels = np.zeros(m1.shape, dtype=int)
    done = np.zeros(m1.shape, dtype=bool)
    c = a
    for level in range(1, 40):
        b = np.sqrt(emc)
        a_levels.append(a)
        b_levels.append(b)
        c_new = 0.5 * (a + b)
        c = np.where(done, c, c_new)
        n_levels = np.where(done, n_levels, level)
        done = done | (np.abs(a - b) <= _AGM_TOL * a)
        if every(done):
            break
        emc = np.where(done, emc, a * b)
        a = np.where(done, a, c_new)
    return a_levels, b_levels, n_levels, c


def _sncndn_small(v: np.ndarray, v_lo: np.ndarray, m: np.ndarray, levels, g_hi, g_lo) -> tuple:
    """sn, cn, dn at v + v_lo, 0 <= v <~ K/2, m1 > 0, each with small *relative* error.

    g_hi + g_lo = π/(2K) = AGM(1, k') in double-double gives the Gauss-transformed phase
    x = v·π/(2K) in [0, π/4] to ~1e-32, so only the rounding of cos x / sin x enters.
    """
    a_levels, b_levels, n_levels, c_agm = levels
    tiny = v < _SERIES_BELOW
    v_safe = np.where(tiny, 0.5, v)
    x_hi, x_lo = two_prod(v_safe, g_hi)
    x_lo = x_lo + (v_safe * g_lo + np.where(tiny, 0.0, v_lo) * g_hi)
    s = np.sin(x_hi)
    cot = np.cos(x_hi) / s - x_lo / (s * s)      # cot(x_hi + x_lo) to first order: cot' = -csc²
    a = cot
    c = c_agm * cot
    dn = np.ones_like(c)
    for i in range(len(a_levels) - 1, -1, -1):
        b = a_levels[i]
        a_new = a * c
        c_new = c * dn
        dn_new = (b_levels[i] + a_new) / (b + a_new)
        a_new = c_new / b
        active = i < n_levels
        if every(active):
            a, c, dn = a_new, c_new, dn_new
        else:
            a, c, dn = np.where(active, a_new, a), np.where(active, c_new, c), np.where(active, dn_new, dn)
    sn = 1.0 / np.sqrt(c * c + 1.0)
    cn = c * sn
    # Maclaurin series (DLMF 22.10.1-3) below 2^-20, with the low word of the argument
    w = v + v_lo
    w2 = w * w
    sn = np.where(tiny, w * (1.0 - (1.0 + m) * w2 / 6.0), sn)
    cn = np.where(tiny, 1.0 - 0.5 * w2, cn)
    dn = np.where(tiny, 1.0 - 0.5 * m * w2, dn)
    return sn, cn, dn


def _cn_dn_sech_series(v_hi, v_lo, K_hi, g_hi, g_lo, k, n_terms):
    """cn, dn at v ∈ [0, K/2] for small m1, each to a few ulp *relative*.

        dn(v|m) = (π/2K') Σₙ sech(π(v - 2nK)/(2K')),
        cn(v|m) = (π/2kK') Σₙ (-1)ⁿ sech(π(v - 2nK)/(2K'))

    These are DLMF 22.12.8 and 22.12.9 (dc and nc as sums over the poles) written for
    the complementary modulus k' and carried to real arguments by Jacobi's imaginary
    transformation dn(iz|m) = dc(z|m1), cn(iz|m) = nc(z|m1) (DLMF 22.6.iv); the tests
    check them against mpmath.  g = π/(2K') in double-double, k = √m.  For 0 <= v <= K/2
    the n = 0 term dominates and the others are at most e^{-(2|n|-1)K} of it, so there
    is no cancellation; the n = 0 phase is formed in double-double and its sech corrected
    to first order, so the error does not grow with v (the Gauss algorithm's relative
    error grows like v·ulp: ~20 ulp at m1 = 1e-14, v = K/2).
    """
    z_hi, z_lo = two_prod(v_hi, g_hi)
    z_lo = z_lo + (v_hi * g_lo + v_lo * g_hi)
    e = np.exp(-np.abs(z_hi))
    e2 = e * e
    t0 = 2.0 * e / (1.0 + e2)
    t0 = t0 * (1.0 - (1.0 - e2) / (1.0 + e2) * np.sign(z_hi) * z_lo)  # sech' = -tanh·sech
    even = np.zeros_like(t0)
    odd = np.zeros_like(t0)
    for n in range(1, n_terms + 1):
        for sgn in (1.0, -1.0):
            en = np.exp(-np.abs(g_hi * (v_hi - sgn * 2.0 * n * K_hi)))
            term = 2.0 * en / (1.0 + en * en)
            if n % 2:
                odd = odd + term
            else:
                even = even + term
    g = g_hi + g_lo
    return g * (t0 + (even - odd)) / k, g * (t0 + (even + odd))


def _per_parameter(p: Parameter) -> dict:
    """Everything that depends on m only, computed on the parameter's own shape.

    A scalar parameter (one motion evaluated at many times, in many calls) is computed once.
    """
    if np.ndim(p.m) == 0 and np.ndim(p.m1) == 0:
        return _per_scalar_parameter(float(p.m), float(p.m1), float(p.m1_lo), float(p.K_hi), float(p.K_lo))
    return _per_parameter_arrays(p)


@functools.lru_cache(maxsize=64)
def _per_scalar_parameter(m: float, m1: float, m1_lo: float, K_hi: float, K_lo: float) -> dict:
    out = _per_parameter_arrays(Parameter(*(np.asarray(x) for x in (m, m1, m1_lo, K_hi, K_lo))))
    for value in out.values():  # shared between calls: read-only
        for arr in (value if isinstance(value, (tuple, list)) else (value,)):
            for a in (arr if isinstance(arr, (tuple, list)) else (arr,)):
                if isinstance(a, np.ndarray):
                    a.flags.writeable = False
    return out


def _per_parameter_arrays(p: Parameter) -> dict:
    one = p.m1 == 0.0
    K_hi = np.where(one, 1.0, p.K_hi)     # placeholder where K = inf (m = 1 handled apart)
    K_lo = np.where(one, 0.0, p.K_lo)
    g_hi, g_lo = dd_div(PI_HI, PI_LO, 2.0 * K_hi, 2.0 * K_lo)          # π/(2K) = AGM(1, k')
    out = dict(one=one, K_hi=K_hi, K_lo=K_lo, g_hi=g_hi, g_lo=g_lo, kc=np.sqrt(p.m1 + p.m1_lo),
               levels=_agm_levels(np.where(one, 1.0, p.m1)), hyperbolic=(p.m1 < _SECH_SERIES_BELOW) & ~one)
    if some(out["hyperbolic"]):
        m_hi, m_lo = two_sum(1.0, -p.m1)
        m_lo = m_lo - p.m1_lo
        Kp_hi, Kp_lo = quarter_period(m_hi, m_lo)                        # K' = K(m1)
        out["gp"] = dd_div(PI_HI, PI_LO, 2.0 * Kp_hi, 2.0 * Kp_lo)        # π/(2K')
        out["k"] = np.sqrt(m_hi + m_lo)
        # N with (2N - 1)K >= 40: the terms |n| > N are below e^{-40} of the n = 0 term
        out["n_terms"] = int(np.ceil((40.0 / np.min(np.where(out["hyperbolic"], K_hi, np.inf)) + 1.0) / 2.0))
    return out


def reduced_sn_cn_dn(u: np.ndarray, p: Parameter):
    """sn, cn, dn at u (any finite float array) for the validated parameter ``p``.

    Also returns what :func:`jacobi_am` and :func:`mechderive.special.integrals.pi_of_am`
    reuse: the half-period count j with u = j·2K + r, sign(r), whether the quarter-period
    shift was used, and sn, cn at the shifted argument v.
    """
    q = _per_parameter(p)
    # u and the parameter's arrays are not broadcast up front: the ufuncs broadcast them (the same values;
    # every result below has the common shape through u - j·2K), and only a selection needs the full shape
    shape = np.broadcast(u, p.m).shape
    m = p.m
    one, K_hi, K_lo = q["one"], q["K_hi"], q["K_lo"]
    too_big = (np.abs(u) > _MAX_PERIODS * K_hi) & ~one
    if some(too_big):
        i = np.flatnonzero(too_big.ravel())[0]
        raise InvalidInputError(
            f"expected |u| <= 2**52·K(m) = {_MAX_PERIODS * np.broadcast_to(K_hi, shape).ravel()[i]:.6g} (beyond it "
            f"adjacent doubles are more than a quarter period apart), got u = {float(np.broadcast_to(u, shape).ravel()[i])!r}"
        )
    j, r_hi, r_lo = reduce_by_half_periods(u, np.where(one, np.inf, K_hi), K_lo)
    sign = np.where(r_hi < 0, -1.0, 1.0)
    a_hi, a_lo = sign * r_hi, sign * r_lo            # |r|
    flip = (a_hi > 0.5 * K_hi) & ~one
    v_hi, v_lo = two_sum(K_hi - a_hi, K_lo - a_lo)   # K - |r|; K_hi - a_hi exact (Sterbenz)
    v_hi = np.where(flip, v_hi, a_hi)
    v_lo = np.where(flip, v_lo, a_lo)
    vsign = np.where(v_hi < 0, -1.0, 1.0)            # v < 0 only by rounding of j
    v_hi, v_lo = vsign * v_hi, vsign * v_lo
    S, C, D = _sncndn_small(v_hi, v_lo, m, q["levels"], q["g_hi"], q["g_lo"])
    hyperbolic = q["hyperbolic"]
    if every(hyperbolic):
        C, D = _cn_dn_sech_series(v_hi, v_lo, K_hi, *q["gp"], q["k"], q["n_terms"])
    elif some(hyperbolic):
        sel = np.broadcast_to(hyperbolic, shape)
        gp_hi, gp_lo, k, K_sel = (np.broadcast_to(x, shape)[sel] for x in (*q["gp"], q["k"], K_hi))
        C_h, D_h = _cn_dn_sech_series(v_hi[sel], v_lo[sel], K_sel, gp_hi, gp_lo, k, q["n_terms"])
        C, D = C.copy(), D.copy()
        C[sel], D[sel] = C_h, D_h
    S = vsign * S
    kc = q["kc"]
    sn_a = np.where(flip, C / D, S)
    cn_a = np.where(flip, kc * S / D, C)
    dn_a = np.where(flip, kc / D, D)
    if some(one):                        # m = 1 exactly: tanh, sech, sech
        e = np.exp(-2.0 * np.abs(u))
        sech = 2.0 * np.sqrt(e) / (1.0 + e)
        sn_a = np.where(one, np.tanh(np.abs(u)), sn_a)
        cn_a = np.where(one, sech, cn_a)
        dn_a = np.where(one, sech, dn_a)
    parity = np.where(np.fmod(j, 2.0) == 0.0, 1.0, -1.0)
    return parity * sign * sn_a, parity * cn_a, dn_a, j, sign, flip, (S, C)
