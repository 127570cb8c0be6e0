"""The free top's closed-form setup in extended precision: one motion without mpmath (issue 15).

:func:`.exact.exact_free_top` sets a motion up at 40 digits with mpmath (:mod:`._exact_setup`); in a warm
``mechderive run`` of a free-top scene importing mpmath (~0.13 s) was most of the solve stage.  Asked with
the time span to be evaluated (``horizon``), it first builds the same :class:`~.exact.FreeTopSolution` here,
in ``numpy.longdouble`` (x87 extended precision on x86-64, ε = 1.1e-19), as the heavy top's
:mod:`~mechderive.systems.heavy_top.exact_extended` does:

* the decisions are the 40-digit setup's, made exactly (:mod:`._exact_gaps`): a steady rotation, the gaps
  G_k = 2T·I_k − L² as rationals, the relabelling from the sign of G_y;
* P², S², λ², m, 1 − m from the same derived expressions in the gaps (:attr:`.exact_model.
  FreeTopExactModel.gap_constants`, compiled for NumPy), each G_k rounded once from its exact value, so that
  near the separatrix 1 − m keeps its relative digits; the smaller of m and 1 − m gives the other;
* Q, K = R_F(0, 1 − m, 1), the initial phase q0·K + v0 with v0 = F(φ|m) (DLMF 19.25.5) from the nearest
  quarter period, exactly as :func:`._exact_setup.elliptic_constants` forms them, and its self-check
  (ω(0) reproduced, Euler's equations (3.33)) to 1e-15;
* on the first request for R (:func:`orientation`): the partial fractions (c1, c2, n) of φ̇, the L frame's
  angles θ'0, ψ'0, φ'0 and Π(n|m) = K + (n/3) R_J(0, 1 − m, 1, 1 − n) (DLMF 19.25.2).

The error of each constant is measured, not assumed: everything is computed twice by the same code, in
doubles and in extended precision (the branches taken as the extended run takes them).  Their difference is
the doubles' rounding error; the extended values' is that times ε_ext/ε_double = 2⁻¹¹, and :data:`SAFETY`
times that is taken (plus a few ε_ext of the value).  The motion is answered here only if those errors,
carried over the requested span — the phase λt + u0 reduced by whole quarter periods K, the mean
precession rate times t — stay below :data:`TOLERANCE` (relative; in units of K for the phase, in rad for
the angles): the outputs then equal the 40-digit path's to ~1e-14 (tests/test_free_top_extended.py compares
them over a random sample).  Otherwise — on and next to the separatrix (1 − m < :data:`MIN_M1`), for
inputs or gaps beyond 2^±400, where longdouble is only a double — the 40-digit setup is used, imported then
and not before; for the orientation alone that fallback is taken lazily, on the first request for R.
"""

from __future__ import annotations

import functools
import math
from fractions import Fraction
from typing import Any

import numpy as np

from ...core.phase import DD, EXTENDED, EPS_EXTENDED as _EPS_EXT, EXTENDED_SAFETY as SAFETY
from ...core.phase import EXTENDED_TO_DOUBLE as _RATIO, EXTENDED_TOLERANCE as TOLERANCE
from . import _exact_gaps as exact_gaps

__all__ = ["setup", "orientation", "EXTENDED", "TOLERANCE", "SAFETY", "MIN_M1"]

#: 1 − m below this goes to 40 digits: the Jacobi functions' piecewise-separatrix regime (1 − m < 1e-34) and
#: the decades before it, where K ~ ln(4/k') and the doubles' comparison says little about the extended values
MIN_M1 = 1e-30
#: nonzero moments, components of ω and gaps within 2^±400: every step stays normal in both precisions
_RANGE = 2.0**400
#: the self-check of the extended constants (ω(0) reproduced, Euler's equations), relative
_SELF_CHECK = 1e-15


def _binary_checked(build):
    """``build`` with the check that the compiled constants are exact in binary (a constant compiled as a
    rounded double would limit the extended values to double precision)."""
    def inner():
        from ..heavy_top.batch import _binary_exact

        args, exprs = build()
        return args, _binary_exact(list(exprs))
    return inner


def jobs() -> list[tuple]:
    """(name, build, module) of the derived expressions compiled for NumPy that this setup evaluates."""
    return [(f"free_top.{name}", _binary_checked(build), "numpy")
            for name, build in (("gap_constants", exact_gaps.build_gap_constants),
                                ("elliptic_Q_of_PS", exact_gaps.build_q),
                                ("precession_fractions", exact_gaps.build_precession))]


@functools.cache
def _compiled() -> dict[str, Any]:
    """The gap constants, Q(P, S, λ) and φ̇'s partial fractions, compiled for NumPy (disk cache)."""
    from ...core.codecache import cached_lambdify

    return {key: cached_lambdify(name, build, module=module)[0]
            for key, (name, build, module) in zip(("gaps", "Q", "precession"), jobs())}


def _value(x: Fraction, dtype: type) -> Any:
    """The rational ``x`` in ``dtype``: rounded once to a double, or as the double-double hi + lo rounded once
    to extended precision (|x| within the doubles' normal range: :data:`_RANGE`)."""
    hi = float(x)
    if dtype is np.float64:
        return np.float64(hi)
    return dtype(hi) + dtype(float(x - Fraction(hi)))


def _error(ext: Any, dbl: Any) -> float:
    """The estimated error of the extended value ``ext`` from the same computation in doubles ``dbl``."""
    diff = abs(np.longdouble(dbl) - np.longdouble(ext))
    return float(SAFETY * _RATIO * diff + 4 * _EPS_EXT * abs(np.longdouble(ext)))


def _in_range(*values: Any) -> bool:
    return all(x == 0 or 1 / _RANGE <= abs(float(x)) <= _RANGE for x in values)


def _elliptic(Im: tuple, wr: tuple, G: tuple, dtype: type, decided: dict | None) -> dict[str, Any]:
    """The constants of :func:`._exact_setup.elliptic_constants` in ``dtype``; ``decided``: the branches the
    extended run took (q0, the shift of v0), taken again by the doubles so that the two runs compare."""
    from ...special._carlson import elliprf
    from ...special.jacobi import shift_by_quarter_periods

    one, zero = dtype(1), dtype(0)
    I = tuple(dtype(v) for v in Im)
    w = tuple(dtype(v) for v in wr)
    Gd = tuple(_value(g, dtype) for g in G)
    P2, S2, lam2, _, m, m1 = (dtype(np.asarray(v)[()]) for v in _compiled()["gaps"](*I, *Gd))
    if m <= m1:  # the smaller of m, 1 − m keeps its relative digits; the other follows exactly
        m1 = one - m
    else:
        m = one - m1
    P = np.sqrt(P2)
    S = (one if w[2] > 0 else -one) * np.sqrt(S2)
    lam = np.sqrt(lam2)
    Q = dtype(np.asarray(_compiled()["Q"](*I, P, S, lam)[0])[()])
    c0, s0 = w[0] / P, w[1] / Q
    kc = np.sqrt(m1)
    K = dtype(np.asarray(elliprf(zero, m1, one))[()])
    if decided is None:
        if abs(s0) <= abs(c0):
            q0 = 0 if c0 > 0 else (2 if s0 >= 0 else -2)
        else:
            q0 = 1 if s0 > 0 else -1
    else:
        q0 = decided["q0"]
    cp, sp_ = {0: (c0, s0), 1: (s0, -c0), -1: (-s0, c0), 2: (-c0, -s0), -2: (-c0, -s0)}[q0]
    ca = cp if q0 % 2 == 0 else kc * cp
    h = np.hypot(sp_, ca)
    sv, cv = sp_ / h, ca / h
    dv = np.sqrt(cv * cv + m1 * sv * sv)
    v0 = sv * dtype(np.asarray(elliprf(cv * cv, cv * cv + m1 * sv * sv, one))[()])
    sn, cn, dn = shift_by_quarter_periods(q0, sv, cv, dv, kc)
    Ix, Iy, Iz = I
    step = (1 if v0 > 0 else -1) if decided is None and abs(v0) > K / 2 else (decided or {}).get("step", 0)
    out = dict(m=m, m1=m1, P=P, Q=Q, S=S, lam=lam, K=K, kc=kc, q0=q0 + step, v0=v0 - step * K, step=step)
    if decided is None:  # the self-check, as the 40-digit setup's: ω(0) reproduced, Euler's equations (3.33)
        floor = max(abs(v) for v in w) * dtype(1e-15)
        recon = (P * cn, Q * sn, S * dn)
        out["check"] = max(float(max(abs(r - wk) / max(abs(wk), floor) for r, wk in zip(recon, w))),
                           float(abs(lam * P * Ix - (Iz - Iy) * Q * S) / abs(lam * P * Ix)),
                           float(abs(lam * m * S * Iz - (Iy - Ix) * P * Q) / abs(lam * S * Iz)))
    return out


def setup(I: np.ndarray, w0: np.ndarray, R0: np.ndarray, horizon: float) -> Any:
    """The :class:`~.exact.FreeTopSolution` of one checked, non-steady motion set up in extended precision,
    for |t| ≤ ``horizon``; None where the 40-digit setup is needed (see the module's docstring).

    ``I``, ``w0``, ``R0``: as :func:`.exact.exact_free_top` has checked them.
    """
    from .exact import FreeTopSolution, _t_max

    if not EXTENDED or not math.isfinite(horizon) or exact_gaps.is_steady(I, w0):
        return None
    two_T, L2, G = exact_gaps.gaps(I, w0)
    if not _in_range(*I, *w0, *G, two_T, L2):
        return None
    x, y, z = exact_gaps.relabelling(I, G)
    if G[y] == 0:  # the separatrix: the hyperbolic motion is the 40-digit setup's
        return None
    perm = exact_gaps.signed_permutation(x, y, z)
    wr = tuple(float(v) for v in perm @ w0)  # exact: a signed permutation of floats
    Im = tuple(float(I[k]) for k in (x, y, z))
    Gr = (G[x], G[y], G[z])
    with np.errstate(all="ignore"):
        ext = _elliptic(Im, wr, Gr, np.longdouble, None)
        if not (ext["check"] <= _SELF_CHECK and ext["m1"] >= MIN_M1):
            return None
        dbl = _elliptic(Im, wr, Gr, np.float64, ext)
        K, lam = ext["K"], ext["lam"]
        L_norm = np.sqrt(_value(L2, np.longdouble))
        nu = max(L_norm / np.longdouble(np.min(I)), lam / K)  # every angular rate of the motion is at most this
        # the phase λt + u0 and its reduction by quarter periods K over the span, in units of K
        quarters = float(abs(horizon) * lam / K) + 2
        phase = (_error(lam, dbl["lam"]) * abs(horizon) + _error(ext["v0"], dbl["v0"])
                 + (quarters + abs(ext["q0"])) * _error(K, dbl["K"]))
        if not phase <= TOLERANCE * float(K):
            return None
        # what is kept as a double: to TOLERANCE relative (then rounded as the 40-digit value is)
        if not all(_error(ext[k], dbl[k]) <= TOLERANCE * abs(float(ext[k])) for k in ("m", "m1", "P", "Q", "S", "kc")):
            return None
        P, Q, S = ext["P"], ext["Q"], ext["S"]
        I_rel = tuple(np.longdouble(v) for v in Im)
        amp_exp = int(np.frexp(max(abs(P), abs(Q), abs(S)))[1])
        ab = (I_rel[0] * P, I_rel[1] * Q)
        mant, ex = np.frexp(ext["kc"])
        u0 = ext["q0"] * K + ext["v0"]
    return FreeTopSolution(
        moments=tuple(map(float, I)), omega0=tuple(map(float, w0)), R0=R0, energy=float(two_T / 2),
        L_norm=float(L_norm), kind="elliptic", m=float(ext["m"]), m1=float(ext["m1"]),
        polhode_period=float(4 * K / lam), _perm=perm, _amp=(float(P), float(Q), float(S)), _lam=DD.scaled(lam),
        _u0=DD.of(u0), _period=DD.of(4 * K), _I_rel=Im, _quarter=DD.of(K), _q0=int(ext["q0"]),
        _v0=DD.of(ext["v0"]), _kc=(float(mant), int(ex)), _tiny=False,
        _L_unit=tuple(float(i * a / L_norm) for i, a in zip(I_rel, (P, Q, S))),
        _ab_unit=tuple(float(v / max(abs(ab[0]), abs(ab[1]))) for v in ab),
        _amp_scaled=(tuple(float(np.ldexp(a, -amp_exp)) for a in (P, Q, S)), amp_exp), _t_max=_t_max(float(nu)),
        _mp=dict(extended=dict(ext=ext, dbl=dbl, I_rel=Im, two_T=two_T, L2=L2, L=L_norm, horizon=abs(horizon))))


def _precession(sol: Any, dtype: type, m_zero: bool) -> dict[str, Any]:
    """φ'(t)'s constants in ``dtype``: c1, c2, n of φ̇ = c1 + c2/(1 − n sn²), Π(n|m)/K, θ'0, ψ'0 and φ'0."""
    from ...special._carlson import elliprj
    from .exact import _l_frame

    v = sol._mp["extended"]
    mo = v["ext"] if dtype is np.longdouble else v["dbl"]
    I = tuple(dtype(x) for x in v["I_rel"])
    L = v["L"] if dtype is np.longdouble else np.sqrt(_value(v["L2"], dtype))
    c1, c2, n = (dtype(np.asarray(c)[()]) for c in _compiled()["precession"](
        *I, _value(v["two_T"], dtype), _value(v["L2"], dtype), L))
    if m_zero:
        n = dtype(0)
    K, m1, lam = mo["K"], mo["m1"], mo["lam"]
    pi_c_over_K = (K + n / 3 * dtype(np.asarray(elliprj(dtype(0), m1, dtype(1), 1 - n))[()])) / K
    # the L frame from L in space components, R0ᵀ L_body, its direction as the 40-digit setup rounds it
    L_dir = np.array([float(dtype(i) * dtype(w) / L) for i, w in zip(sol.moments, sol.omega0)])
    S_frame = _l_frame(sol.R0.T @ L_dir)
    # θ'0, ψ'0 of the relabelled body relative to the L frame: cos θ' = L_z/|L|, ψ' = atan2(L_x, L_y)
    Lx, Ly, Lz = (i * dtype(w) for i, w in zip(I, (sol._perm @ np.array(sol.omega0))))
    theta0, psi0 = np.arctan2(np.hypot(Lx, Ly), Lz), np.arctan2(Lx, Ly)
    # φ'0 from R3(φ'0) = R1(θ'0)ᵀ R3(ψ'0)ᵀ M, M = R_L(0) (:func:`._exact_setup.initial_precession_angle`)
    M = (sol._perm @ sol.R0 @ S_frame.T).astype(dtype)
    c, s = np.cos(theta0), np.sin(theta0)
    R1 = np.array([[1, 0, 0], [0, c, s], [0, -s, c]], dtype=dtype)
    c, s = np.cos(psi0), np.sin(psi0)
    R3 = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]], dtype=dtype)
    X = R1.T @ R3.T @ M
    return dict(c1=c1, c2=c2, n=n, pi_c_over_K=pi_c_over_K, rate=c1 + c2 * pi_c_over_K,
                dphi=(c1 + c2 * pi_c_over_K) * 4 * K / lam, c2_over_lam=c2 / lam, S=S_frame,
                phi0=np.arctan2(X[0, 1], X[0, 0]))


def orientation(sol: Any) -> Any:
    """The :class:`~.exact._Orientation` of a motion set up here, in extended precision, or None where the
    estimated errors of its constants exceed :data:`TOLERANCE` (then the 40-digit constants are used)."""
    from .exact import _Orientation

    m_zero = sol._mp["extended"]["ext"]["m"] == 0  # as the 40-digit setup decides it: n = 0 for m = 0
    with np.errstate(all="ignore"):
        e, d = _precession(sol, np.longdouble, m_zero), _precession(sol, np.float64, m_zero)
        horizon = sol._mp["extended"]["horizon"]
        kept = [(e["n"], d["n"], 0.0), (1 - e["n"], 1 - d["n"], 0.0), (e["pi_c_over_K"], d["pi_c_over_K"], 0.0),
                (e["dphi"], d["dphi"], 0.0), (e["phi0"], d["phi0"], 1.0)]
        if e["n"] != 0:
            kept.append((e["c2_over_lam"], d["c2_over_lam"], 0.0))
        if not all(math.isfinite(float(x)) and _error(x, y) <= TOLERANCE * max(abs(float(x)), floor)
                   for x, y, floor in kept):
            return None
        # the mean precession rate times t: to TOLERANCE rad over the span
        if not _error(e["rate"], d["rate"]) * horizon <= TOLERANCE:
            return None
        n, pi_c_over_K = e["n"], e["pi_c_over_K"]
        o = _Orientation(S=e["S"], phi0=float(e["phi0"]), nu=DD.scaled(e["rate"]),
                         c2_over_lam=0.0 if n == 0 else float(e["c2_over_lam"]), n=float(n),
                         slope=float(1 / (1 - n) - pi_c_over_K), pi_c_over_K=float(pi_c_over_K), p0=0.0,
                         dphi=DD.of(e["dphi"]))
    # p(u0) through the very evaluation used at every t: φ'(0) = φ'0 exactly (as the 40-digit setup)
    p0 = float(sol._periodic_pi(sol._jacobi(np.zeros(1), keep=False), o)[0])
    return _Orientation(**{**o.__dict__, "p0": p0})
