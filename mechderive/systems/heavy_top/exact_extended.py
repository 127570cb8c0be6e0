"""The heavy top's closed-form setup in extended precision: one motion without mpmath (issue 15).

:func:`.exact.exact_heavy_top` sets a motion up at 40 digits with mpmath (:func:`._exact_setup.setup`); in a
warm ``mechderive run`` importing mpmath and the 40-digit setup were most of the solve stage.  Asked with
the time span to be evaluated (``horizon``), it first builds the same :class:`~.exact.HeavyTopSolution`
here, from the batched path (:mod:`.batch`) run on a batch of one in ``numpy.longdouble`` (x87 extended
precision on x86-64, ε = 1.1e-19):

* u_k = u0 + w_k from the roots w_k of f(u0 + w) (3.73), κ², m, 1 − m, K = R_F(0, 1 − m, 1) and the
  nutation period 2K/κ (3.71), with the batch's own per-point checks (:func:`.batch._tier`): a point the
  batch would not answer — near-steady, next to the separatrix (1 − m < 1e-6), within 1e-6 of a pole or
  bottom passage in 1 ∓ u, near figure 44's class boundaries, roots not to 1e-12 — goes to 40 digits;
* 1 ∓ u_k = (1 ∓ u0) ∓ w_k from the half angle, n₊ = (u2 − u1)/(1 − u1), n₋ = −(u2 − u1)/(1 + u1);
* the phase's start v0 = F(A0|m), sin²A0 = (u0 − u1)/(u2 − u1) = −w1/(u2 − u1), split at |A0| = π/4 as
  :func:`._exact_setup.setup` splits it (DLMF 19.7.8), with F(φ|m) = sin φ R_F(cos²φ, cos²φ + (1 − m) sin²φ, 1)
  (DLMF 19.25.5);
* on the first request for φ or ψ (:func:`angle_constants`): the partial fractions of φ̇/κ and ψ̇/κ
  (3.74)–(3.75) and the advance per nutation period (c0/κ)·2K + Σ (c_i/κ)·2Π(n_i|m),
  Π(n|m) = K + (n/3) R_J(0, 1 − m, 1, 1 − n) (DLMF 19.25.2).

The error of each constant is measured, not assumed: everything is computed twice by the same code, in
doubles and in extended precision.  Their difference is the doubles' rounding error; the extended values'
is that times ε_ext/ε_double = 2⁻¹¹, and :data:`SAFETY` times that is taken (plus a few ε_ext of the
value).  The motion is answered here only if those errors, carried over the requested span — the phase
κt + v0 and j whole periods 2K and per-period advances, j ≤ horizon/T + 2 — stay below :data:`TOLERANCE`
(relative, or in rad / in units of K for the accumulated angle and the phase): the outputs then equal the
40-digit path's to ~1e-14, a hundredth of the 1e-12 the batched path promises (tests/test_heavy_top_extended.py
compares both over a random sample of motions of every class).  Otherwise — and where longdouble is only a
double — the 40-digit setup is used, imported then and not before; for φ and ψ alone that fallback is taken
lazily, on their first request (:meth:`.exact.HeavyTopSolution.precise`).
"""

from __future__ import annotations

import functools
import math
from typing import Any, Mapping

import numpy as np

from ...core.phase import DD, EXTENDED, EPS_EXTENDED as _EPS_EXT, EXTENDED_SAFETY as SAFETY
from ...core.phase import EXTENDED_TO_DOUBLE as _RATIO, EXTENDED_TOLERANCE as TOLERANCE

__all__ = ["setup", "angle_constants", "fraction_jobs", "gap_jobs", "EXTENDED", "TOLERANCE"]

_PARAMS = ("I1", "I3", "M", "g", "l")
_STATE = ("theta", "theta_dot", "phi_dot", "psi_dot")
#: the batch's checks the point must pass: its period (with the roots' errors propagated), turning angles and
#: class.  Not u1, u2, u3 to 1e-12 relative: a root at u = 6e-17 (a start at θ = π/2 in doubles) is known to
#: 1e-33 absolutely, which is what u(t) = u1 + (u2 − u1) sn² needs (checked below)
_CHECKED = ("nutation_period", "theta_min", "theta_max", "motion_class")


def _binary_checked(build):
    """``build`` with the batch's check that the compiled constants are exact in binary (else the extended
    tier would be limited to double precision by a constant such as 1/3 compiled as a double)."""
    def inner():
        from .batch import _binary_exact

        args, exprs = build()
        return args, _binary_exact(list(exprs))
    return inner


def fraction_jobs() -> list[tuple]:
    """(name, build, module) of the partial fractions of φ̇ and ψ̇ compiled for NumPy (:func:`_fractions`)."""
    from .exact import _fraction_build

    return [(f"heavy_top.{which}", _binary_checked(_fraction_build(which)), "numpy")
            for which in ("precession_fractions", "spin_fractions")]


def gap_jobs() -> list[tuple]:
    """(name, build, module) of b ∓ a from the state in half angles (:func:`_compiled`), the setup's last
    derived constants, for :func:`mechderive.core.codecache.prefetch`; none where this setup is not taken."""
    from .exact import _build_gaps

    return [("heavy_top.passage_factors", _binary_checked(_build_gaps), "numpy")] if EXTENDED else []


@functools.cache
def _compiled() -> dict[str, Any]:
    """f's coefficients (3.73) and b ∓ a from the state in half angles, compiled for NumPy (disk cache)."""
    from ...core.codecache import cached_lambdify
    from .exact import _build_f, _build_gaps

    return {key: cached_lambdify(label, _binary_checked(build), module="numpy")[0]
            for key, label, build in (("f", "heavy_top.f_coefficients", _build_f),
                                      ("gaps", "heavy_top.passage_factors", _build_gaps))}


@functools.cache
def _fractions() -> dict[str, Any]:
    """[c0, c_1, n_1, c_2, n_2] of φ̇ and ψ̇ in (I1, I3, a, b, u1, u2, u3), compiled for NumPy (disk cache)."""
    from ...core.codecache import cached_lambdify

    return {name: cached_lambdify(label, build, module=module)[0]
            for name, (label, build, module) in zip(("phi", "psi"), fraction_jobs())}


def _scalar(x: Any) -> Any:
    return np.asarray(x)[()] if np.ndim(x) == 0 else np.asarray(x).ravel()[0]


def _incomplete_f(phi: Any, m1: Any) -> Any:
    """F(φ|m) = sin φ R_F(cos²φ, cos²φ + (1 − m) sin²φ, 1) (DLMF 19.25.5), in φ's dtype; 1 − m sin²φ
    formed from 1 − m so that nothing cancels as m → 1."""
    from ...special._carlson import elliprf

    s, c = np.sin(phi), np.cos(phi)
    return s * _scalar(elliprf(c * c, c * c + m1 * s * s, np.ones_like(c)))


def _motion(P: list[np.ndarray], S: list[np.ndarray], dtype: type, *, checked: bool = True
            ) -> tuple[bool, dict[str, Any]]:
    """(the batch answers the point, the nutation's constants in ``dtype``) for one motion; without
    ``checked`` the batch's estimates are skipped (the values only, to compare with)."""
    from .batch import _tier

    keep: dict[str, Any] = {"values_only": not checked}
    _, _, ok = _tier(P, S, _CHECKED, dtype, keep=keep)
    k = {key: _scalar(v) for key, v in keep.items() if key not in ("w", "values_only")}
    w1, w2, w3 = (keep["w"][0, i] for i in range(3))
    amp = w2 - w1
    one, zero = dtype(1), dtype(0)
    half_pi = 2 * np.arctan(one)
    m1 = k["m1"]
    # sin²A0 = (u0 − u1)/(u2 − u1); A0's sign: u̇0 = −sin θ0 θ̇0 with sin θ0 > 0 (the batch takes θ0 in (0, π))
    s0 = min(max(-w1 / amp, zero), one)
    theta_dot0 = S[1][0]
    if theta_dot0 != 0:
        A0 = -np.sign(dtype(theta_dot0)) * np.arcsin(np.sqrt(s0))
    else:
        A0 = half_pi if s0 > one / 2 else zero
    if abs(A0) > half_pi / 2:
        # past π/4: v0 = ±(K − F(χ|m)), tan χ = cot A0 / k' (DLMF 19.7.8), cos²A0 = (u2 − u0)/(u2 − u1)
        anchor = 1 if A0 > 0 else -1
        chi = np.arctan2(np.sqrt(w2 / amp), np.sqrt(m1) * np.sqrt(s0))
        dv0 = -anchor * _incomplete_f(chi, m1)
    else:
        anchor, dv0 = 0, _incomplete_f(A0, m1)
    out = dict(k, w1=w1, w2=w2, w3=w3, amp=amp, A0=A0, anchor=anchor, dv0=dv0, v0=anchor * k["K"] + dv0,
               # 1 ∓ u_k from 1 ∓ u0 of the half angle (d_pole = u0 − 1, d_bottom = u0 + 1)
               gaps_minus=tuple(-k["d_pole"] - w for w in (w1, w2, w3)),
               gaps_plus=tuple(k["d_bottom"] + w for w in (w1, w2, w3)))
    out["roots"] = tuple(k["u0"] + w for w in (w1, w2, w3))
    out["n_plus"] = amp / out["gaps_minus"][0]
    out["n_minus"] = -amp / out["gaps_plus"][0]
    return bool(ok[0]), out


def _error(ext: Any, dbl: Any) -> float:
    """The estimated error of the extended value ``ext`` from the same computation in doubles ``dbl``."""
    diff = abs(np.longdouble(dbl) - np.longdouble(ext))
    return float(SAFETY * _RATIO * diff + 4 * _EPS_EXT * abs(np.longdouble(ext)))


def setup(params: Mapping[str, float], init: Mapping[str, float], horizon: float, *, strict: bool,
          mgl: bool) -> Any:
    """The :class:`~.exact.HeavyTopSolution` of one checked motion set up in extended precision, for
    |t| ≤ ``horizon``; None where the 40-digit setup is needed (see the module's docstring).

    ``params``, ``init``: as :func:`.parameters.check_params` and ``check_initial`` return them (``mgl``: the
    top was given by M g l, realised as M = 1, g = Mgl, l = 1).
    """
    from .batch import _valid
    from .exact import HeavyTopSolution, _passage_sign, classify

    if not EXTENDED or not math.isfinite(horizon):
        return None
    P = [np.array([float(params[k])]) for k in _PARAMS]
    S = [np.array([float(init[k])]) for k in _STATE]
    if not _valid(dict(zip(_PARAMS, P)), dict(zip(_STATE, S)), strict, mgl)[0]:
        return None  # the poles, a body on the rigid-body boundary, numbers far from order one
    with np.errstate(all="ignore"):
        answered, ext = _motion(P, S, np.longdouble)
        if not answered:
            return None
        _, dbl = _motion(P, S, np.float64, checked=False)
        K, T = ext["K"], float(ext["T"])
        if not (math.isfinite(T) and T > 0):
            return None
        periods = math.floor(abs(horizon) / T) + 2
        # the phase κt + v0 and its reduction by j periods 2K, in units of K
        phase = (_error(ext["kappa"], dbl["kappa"]) * abs(horizon) + _error(ext["v0"], dbl["v0"])
                 + periods * 2 * _error(K, dbl["K"]))
        if not phase <= TOLERANCE * float(K):
            return None
        # what is kept as a double: to ~1e-14 relative (then rounded as the 40-digit value is); the roots u_k
        # relative to 1 (|u| ≤ 1 but for u3; 1 ∓ u_k, which carry the passages, relative to themselves)
        singles = [(ext[k], dbl[k], 0.0) for k in ("m", "m1", "amp", "T", "n_plus", "n_minus")]
        singles += [(x, y, 0.0) for k in ("gaps_minus", "gaps_plus") for x, y in zip(ext[k], dbl[k])]
        singles += [(x, y, 1.0) for x, y in zip(ext["roots"], dbl["roots"])]
        if not all(_error(x, y) <= TOLERANCE * max(abs(float(x)), floor) for x, y, floor in singles):
            return None

        Pl = [x.astype(np.longdouble) for x in P]
        Sl = [x.astype(np.longdouble) for x in S]
        a, b, alpha, beta = ext["a"], ext["b"], ext["alpha"], ext["beta"]
        d_pole, d_bottom = (_scalar(x) for x in _compiled()["gaps"](*Pl, *Sl))
        coeffs = [_scalar(c) for c in _compiled()["f"](a, b, alpha, beta)]
        # E = ½ I1 (θ̇² + φ̇² sin²θ) + ½ I3 ω3² + M g l cos θ (3.63)-(3.65), as the 40-digit setup forms it
        I1_, I3_, M_, g_, l_ = (x[0] for x in Pl)
        th, thd, phd, psd = (x[0] for x in Sl)
        u0 = ext["u0"]
        energy = (I1_ * (thd**2 + phd**2 * np.sin(th) ** 2) + I3_ * (psd + phd * u0) ** 2) / 2 + M_ * g_ * l_ * u0
    I1, I3 = Pl[0][0], Pl[1][0]
    u1, u2, u3 = ext["roots"]
    gm, gp = ext["gaps_minus"], ext["gaps_plus"]
    A0 = ext["A0"]
    theta_dot0 = float(init["theta_dot"])
    return HeavyTopSolution(
        parameters=dict(params), initial=dict(init), energy=float(energy), p_phi=float(I1 * b),
        p_psi=float(I1 * a), f_coefficients=tuple(float(c) for c in coeffs),
        kind="nutating", roots=(float(u1), float(u2), float(u3)), m=float(ext["m"]), m1=float(ext["m1"]),
        nutation_period=T,
        conditioning=float(max(1 / (1 - ext["n_plus"]), 1 - ext["n_minus"])),
        motion_class=classify(float(u1), float(u2), float(a), float(b)),
        _kappa=DD.of(ext["kappa"]), _v0=DD.of(ext["v0"]), _period=DD.of(2 * K), _u1=float(u1),
        _amp=float(ext["amp"]), _one_minus_u2=float(gm[1]), _one_plus_u1=float(gp[0]),
        _theta_const=float(init["theta"]),
        _mp=dict(steady=False, I1=I1, I3=I3, a=a, b=b, roots=ext["roots"], kappa=ext["kappa"], m=ext["m"],
                 m1=ext["m1"], A0=A0, K=K, anchor=ext["anchor"], dv0=DD.of(ext["dv0"]),
                 gaps_minus=tuple(float(g) for g in gm), gaps_plus=tuple(float(g) for g in gp),
                 d_minus=float(d_pole), d_plus=float(d_bottom), beta=float(beta),
                 # sn v0 = sin A0, cn v0 = cos A0 (v0 = F(A0|m), DLMF 22.16.1)
                 pole_sign=_passage_sign(float(np.cos(A0)), -float(np.sin(A0)), theta_dot0),
                 bottom_sign=_passage_sign(float(np.sin(A0)), float(np.cos(A0)), -theta_dot0),
                 extended=dict(double=dbl, periods=periods, strict=strict)))


def angle_constants(sol: Any) -> tuple[dict, dict, dict] | None:
    """(fractions, 1 − n, advances) of φ and ψ for :func:`.exact._angle_setup`, in extended precision, or
    None where their estimated errors exceed :data:`TOLERANCE` (then the 40-digit constants are used).

    fractions: {name: (c0, [(c_i, n_i)])}; 1 − n: {n_i: 1 − n_i}; advances: {name: DD per period}.
    """
    from ...special._carlson import elliprj

    v, dbl = sol._mp, sol._mp["extended"]["double"]
    periods = sol._mp["extended"]["periods"]
    out: dict[str, dict] = {}
    for tag, mo in (("ext", v), ("dbl", dbl)):
        dtype = np.longdouble if tag == "ext" else np.float64
        I1, I3 = dtype(v["I1"]), dtype(v["I3"])
        kappa, K, m1 = mo["kappa"], mo["K"], mo["m1"]
        with np.errstate(all="ignore"):
            flat = {name: [_scalar(x) for x in f(I1, I3, mo["a"], mo["b"], *mo["roots"])]
                    for name, f in _fractions().items()}
            per, pis = {}, {}
            for name, fr in flat.items():
                total = (fr[0] / kappa) * 2 * K
                for c, n in zip(fr[1::2], fr[2::2]):
                    if n not in pis:  # φ and ψ share their characteristics n±
                        pis[n] = K + n / 3 * _scalar(elliprj(dtype(0), m1, dtype(1), 1 - n))
                    total = total + (c / kappa) * 2 * pis[n]
                per[name] = total
        out[tag] = {"flat": flat, "per": per}
    e, d = out["ext"], out["dbl"]
    scale = abs(float(v["a"])) + abs(float(v["b"])) + 1
    fractions, one_minus, advances = {}, {}, {}
    for name in ("phi", "psi"):
        fe, fd = e["flat"][name], d["flat"][name]
        if len(fe) != len(fd) or not all(math.isfinite(float(x)) for x in fe):
            return None
        kappa_e, kappa_d = v["kappa"], dbl["kappa"]
        # c0/κ, c_i/κ, n_i and 1 − n_i are kept as doubles: each to TOLERANCE
        pairs = [(fe[0] / kappa_e, fd[0] / kappa_d)]
        for (c, n), (cd, nd) in zip(zip(fe[1::2], fe[2::2]), zip(fd[1::2], fd[2::2])):
            # a term whose coefficient nearly vanishes (b = ±a: an exact passage) is for the 40-digit path to drop
            if not abs(float(c)) > 1e-12 * scale:
                return None
            pairs += [(c / kappa_e, cd / kappa_d), (n, nd), (1 - n, 1 - nd)]
        if not all(_error(x, y) <= TOLERANCE * abs(float(x)) for x, y in pairs):
            return None
        # j whole periods of the advance: to TOLERANCE rad over the span
        if not periods * _error(e["per"][name], d["per"][name]) <= TOLERANCE:
            return None
        fractions[name] = (fe[0], list(zip(fe[1::2], fe[2::2])))
        for n in fe[2::2]:
            one_minus[n] = 1 - n
        advances[name] = DD.of(e["per"][name])
    return fractions, one_minus, advances
