"""The heavy top's per-motion quantities for N motions at once (a sweep's chunk), in NumPy.

The single-point path (:mod:`.summary`) sets each motion up at 40 digits with mpmath (~3 ms a
point).  Here the same derived constants — a, b, α, β (3.66), (3.72); f's coefficients (3.73);
κ², m (the nutation ansatz); the partial fractions of φ̇ (3.74) — are compiled for NumPy and
evaluated over all points in double precision:

* the roots u1 ≤ u2 ≤ 1 ≤ u3 of f: eigenvalues of the N companion matrices, sorted, clamped as the
  single path clamps them (u1 ≤ cos θ0 ≤ u2, within [-1, 1]), and polished by two Newton steps;
* the nutation period 2K(m)/κ, K = K(m) from 1 - m (SciPy's ``ellipkm1``: no cancellation near the
  separatrix);
* Δφ per period (c0/κ)·2K + Σ (c_i/κ)·2Π(n_i | m) with Π(n | m) = R_F(0, 1-m, 1) + (n/3) R_J(0, 1-m, 1, 1-n)
  (DLMF 19.25.2, Carlson's integrals from SciPy);
* θ_min, θ_max = 2 atan2(√(1 ∓ u), √(1 ± u)); figure 44's class by the single path's rule (:func:`.exact.classify`);
* E, p_φ, p_ψ by the derived invariants.

Error estimates are measured per point, never a constant:

* the roots: f's coefficients come out of two independent derived evaluations (from the state
  directly, ``f_coefficients_state``, and through a, b, α, β), which round differently where they
  lose digits to cancellation; the roots of each, and every quantity built on them, are compared:
  and so are those of f shifted up and down by its rounding noise at the roots (4ε Σ|c_k||u|^k, as
  an error in the energy α would shift it: the motion widened and narrowed consistently); the
  largest difference (plus the last Newton steps and the rounding) is the propagated error;
* K: SciPy's ``ellipkm1`` against Carlson's R_F(0, 1 - m, 1), two independent algorithms;
* Π: the rounding of n in 1 - n, amplified by 1/(1 - n), and each term's rounding (Σ |terms|·ε).

A point is answered here only if every estimate is below 1e-12 relative (the estimates are
first-order bounds: the value then equals the 40-digit single path's to 1e-12, which
tests/test_sweep.py checks on a random sample); otherwise, and for steady motions, sleeping tops, exact or near passages through the
pole or the bottom (1 - n₊ < 1e-3: Π(n | m)'s sensitivity to n's rounding grows like 1/(1 - n)),
points the checks would refuse and quantities that are not plain numbers, it is ``fallback``: the
sweep runs it through the planner, which uses the 40-digit path.
"""

from __future__ import annotations

import functools
from typing import Any, Mapping

import numpy as np

from ..base import BatchSummary

__all__ = ["summarize_batch", "BATCHED"]

#: the quantities answered here; the others (``steady``, ``minimum_spin``: not plain numbers, or not
#: defined for most motions) always go one by one
BATCHED = ("nutation_period", "period", "theta_min", "theta_max", "u1", "u2", "u3", "mean_precession_rate",
           "precession_per_nutation", "motion_class", "energy", "p_phi", "p_psi")

_EPS = float(np.finfo(float).eps)
#: the largest estimated relative error a batched value may carry: the agreement promised.  The estimates
#: are first-order bounds (each term's rounding at its full size, the roots moved by their whole error),
#: 10-50 times the errors seen against the 40-digit path (tests/test_sweep.py measures both)
_RTOL = 1e-12
#: closest approach to 1 of a characteristic n answered here: the rounding of n costs ~ε/(1 - n) in Π
_N_MARGIN = 1e-3


@functools.cache
def _functions() -> dict[str, Any]:
    """The derived constants compiled for NumPy (disk cache: derived and compiled once per install)."""
    from ...core.codecache import cached_lambdify
    from . import exact
    from . import model as hm

    out = {key: cached_lambdify(label, build, module="numpy")[0]
           for key, (label, build) in zip(("state", "gaps", "f", "nutation"), exact.NUTATION_BUILDS)}

    def build_f_state():
        return [*hm.PARAMETERS, *hm.STATE], list(hm.model().f_coefficients_state)

    def build_invariants():
        m = hm.model()
        return [*hm.PARAMETERS, *hm.STATE], [m.energy, m.azimuthal_momentum, m.spin_momentum]

    out["f_state"] = cached_lambdify("heavy_top.f_coefficients_state", build_f_state, module="numpy")[0]
    out["invariants"] = cached_lambdify("heavy_top.invariants_state", build_invariants, module="numpy")[0]
    out["phi_fractions"] = cached_lambdify("heavy_top.precession_fractions",
                                           exact._fraction_build("precession_fractions"), module="numpy")[0]
    return out


def _array(values: Any, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(values, dtype=float), (n,)).astype(float)


def _columns(f: Any, args: tuple, n: int) -> list[np.ndarray]:
    return [_array(v, n) for v in f(*args)]


def _valid(p: dict[str, np.ndarray], s: dict[str, np.ndarray], strict: bool) -> np.ndarray:
    """Points the parameter and state checks accept (:mod:`.parameters`); the rest go one by one (and are
    refused there, with the checks' own message)."""
    ok = np.ones(len(s["theta"]), dtype=bool)
    for v in (*p.values(), *s.values()):
        ok &= np.isfinite(v) & (np.abs(v) < 1e100)  # far from order one: the planner solves in scaled units
    ok &= (p["I1"] > 0) & (p["I3"] > 0) & (p["M"] > 0) & (p["g"] > 0) & (p["l"] > 0)
    ok &= (s["theta"] > 0) & (s["theta"] < np.pi)  # the poles: sleeping and hanging tops, steady there
    if strict:
        # the rigid-body condition, with a margin: on the boundary the single path's rounding decides
        ok &= (p["I1"] - p["M"] * p["l"] ** 2 - p["I3"] / 2) > 1e-12 * (p["I1"] + p["I3"])
    return ok


def _roots(c: list[np.ndarray], u0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots (N, 3) of c3 u³ + c2 u² + c1 u + c0, sorted, and each one's last Newton step (N, 3)."""
    c3, c2, c1, c0 = c
    n = len(c0)
    companion = np.zeros((n, 3, 3))
    companion[:, 0, :] = -np.stack([c2, c1, c0], axis=1) / c3[:, None]
    companion[:, 1, 0] = companion[:, 2, 1] = 1.0
    with np.errstate(all="ignore"):
        r = np.sort(np.linalg.eigvals(companion).real, axis=1)
    # as the single path: u1 ≤ u0 ≤ u2 (u0 is inside the motion), both in [-1, 1]
    r[:, 1] = np.minimum(np.maximum(r[:, 1], u0), 1.0)
    r[:, 0] = np.maximum(np.minimum(r[:, 0], u0), -1.0)
    step = np.zeros_like(r)
    with np.errstate(all="ignore"):
        for _ in range(2):
            fx = ((c3[:, None] * r + c2[:, None]) * r + c1[:, None]) * r + c0[:, None]
            d = (3 * c3[:, None] * r + 2 * c2[:, None]) * r + c1[:, None]
            step = np.where(d != 0, fx / d, 0.0)
            r = r - step
    return r, np.abs(step)


def _polish(c: list[np.ndarray], r: np.ndarray) -> np.ndarray:
    """Roots ``r`` (N, 3) of a nearby cubic moved to those of ``c`` by two Newton steps."""
    c3, c2, c1, c0 = (x[:, None] for x in c)
    with np.errstate(all="ignore"):
        for _ in range(2):
            d = (3 * c3 * r + 2 * c2) * r + c1
            r = r - np.where(d != 0, (((c3 * r + c2) * r + c1) * r + c0) / d, 0.0)
    return r


def _pi(n: np.ndarray, one_minus_n: np.ndarray, m1: np.ndarray) -> np.ndarray:
    """Π(n | m) = R_F(0, 1 - m, 1) + (n/3) R_J(0, 1 - m, 1, 1 - n) (DLMF 19.25.2), vectorised."""
    from scipy.special import elliprf, elliprj

    zero = np.zeros_like(m1)
    return elliprf(zero, m1, 1.0) + n / 3 * elliprj(zero, m1, 1.0, one_minus_n)


def _pipeline(F: dict, P: list, a: np.ndarray, b: np.ndarray, beta: np.ndarray, r: np.ndarray,
              want_advance: bool) -> dict[str, np.ndarray]:
    """T, Δφ, θ_min, θ_max (and what they are made of) from the roots ``r`` (N, 3)."""
    from scipy.special import ellipkm1

    u1, u2, u3 = r[:, 0], r[:, 1], r[:, 2]
    n = len(u1)
    with np.errstate(all="ignore"):
        kappa2, m, m1 = _columns(F["nutation"], (beta, u1, u2, u3), n)
        kappa = np.sqrt(kappa2)
        K = ellipkm1(m1)
        out = {"kappa": kappa, "m": m, "m1": m1, "K": K, "T": 2 * K / kappa,
               "theta_min": 2 * np.arctan2(np.sqrt(1 - u2), np.sqrt(1 + u2)),
               "theta_max": 2 * np.arctan2(np.sqrt(1 - u1), np.sqrt(1 + u1))}
        if want_advance:
            flat = _columns(F["phi_fractions"], (P[0], P[1], a, b, u1, u2, u3), n)
            advance = flat[0] / kappa * 2 * K
            spread = np.abs(advance)
            n_margin = np.full(n, np.inf)
            rounding = np.zeros(n)
            for c, nn in zip(flat[1::2], flat[2::2]):
                one_minus_n = 1 - nn
                term = c / kappa * 2 * _pi(nn, one_minus_n, m1)
                advance = advance + term
                spread = spread + np.abs(term)
                n_margin = np.minimum(n_margin, one_minus_n)
                # n's rounding, amplified in Π by ~1/(1 - n)
                rounding = rounding + np.abs(term) * _EPS * np.abs(nn) / np.abs(one_minus_n)
            out.update(advance=advance, advance_spread=spread, n_margin=n_margin, n_rounding=rounding)
    return out


def summarize_batch(parameters: Mapping[str, Any], initial: Mapping[str, Any], names: tuple[str, ...], *,
                    strict: bool = True) -> BatchSummary:
    """The heavy top's per-motion quantities ``names`` at N points (see the module's docstring).

    ``parameters``: I1 I3 M g l (or I1 I3 Mgl) arrays; ``initial``: theta theta_dot phi_dot psi_dot
    (phi, psi ignored: no summary depends on them) — SI units, as a checked scene holds them.
    """
    n = len(np.atleast_1d(initial["theta"]))
    p = {k: _array(v, n) for k, v in parameters.items()}
    if "Mgl" in p:  # as check_params realises it: M = 1, g = Mgl, l = 1 (the same M g l)
        p = {"I1": p["I1"], "I3": p["I3"], "M": np.ones(n), "g": p["Mgl"], "l": np.ones(n)}
    s = {k: _array(initial.get(k, 0.0), n) for k in ("theta", "theta_dot", "phi_dot", "psi_dot")}
    fallback = ~_valid(p, s, strict)
    values: dict[str, np.ndarray] = {}
    errors: dict[str, np.ndarray] = {}
    if any(name not in BATCHED for name in names):
        fallback[:] = True
    if fallback.all():
        return BatchSummary(values, errors, fallback)
    F = _functions()
    P = [p[k] for k in ("I1", "I3", "M", "g", "l")]
    S = [s[k] for k in ("theta", "theta_dot", "phi_dot", "psi_dot")]
    with np.errstate(all="ignore"):
        a, b, alpha, beta = _columns(F["state"], (*P, *S), n)
        c = _columns(F["f"], (a, b, alpha, beta), n)
        c_other = _columns(F["f_state"], (*P, *S), n)
        d_pole, d_bottom = _columns(F["gaps"], (*P, *S), n)
        u0 = np.cos(S[0])
        r, last_step = _roots(c, u0)
        # the same roots from the coefficients' second derivation: where f's coefficients lose digits to
        # cancellation the two evaluations round differently, and every quantity built on the roots shows it
        r_other, step_other = _roots(c_other, u0)
        # and from f shifted by its rounding noise near the roots, 4ε Σ|c_k||u|^k (as an error in the energy α
        # would shift it): f + δ widens the motion, f - δ narrows it, consistently for all three roots
        absr = np.abs(r)
        noise = 4 * _EPS * np.max(((np.abs(c[0])[:, None] * absr + np.abs(c[1])[:, None]) * absr
                                   + np.abs(c[2])[:, None]) * absr + np.abs(c[3])[:, None], axis=1)
        shifted = [_polish([c[0], c[1], c[2], c[3] + sign * noise], r) for sign in (1.0, -1.0)]
        du = np.max([np.abs(x - r) for x in (r_other, *shifted)], axis=0) + 2 * (last_step + step_other) \
            + 2 * _EPS * absr
        amp = r[:, 1] - r[:, 0]
        want_advance = any(k in names for k in ("mean_precession_rate", "precession_per_nutation"))
        base = _pipeline(F, P, a, b, beta, r, want_advance)
        others = [_pipeline(F, P, a, b, beta, x, want_advance) for x in (r_other, *shifted)]

        def propagated(key: str) -> np.ndarray:
            return np.max([np.abs(o[key] - base[key]) for o in others], axis=0)

        from scipy.special import elliprf

        K_other = elliprf(np.zeros(n), base["m1"], 1.0)
        T = base["T"]
        T_err = propagated("T") + np.abs(K_other - base["K"]) * 2 / base["kappa"] + 4 * _EPS * T
        # a nutating motion well inside the separatrix and away from the poles' passages
        fallback |= ~(amp > 1e-6 * np.maximum(np.abs(r[:, 1]), 1.0))  # near-steady: u1, u2 a near double root
        fallback |= ~(base["m1"] > 1e-6)
        fallback |= (d_pole == 0) | (d_bottom == 0) | ~(1 - r[:, 1] > 1e-6) | ~(1 + r[:, 0] > 1e-6)
        fallback |= ~np.all(np.isfinite(r), axis=1) | ~np.isfinite(T) | ~(du[:, 2] < 1e-6 * r[:, 2])
        theta_err = {k: propagated(k) + 4 * _EPS * base[k] for k in ("theta_min", "theta_max")}
        out: dict[str, tuple[np.ndarray, np.ndarray]] = {
            "nutation_period": (T, T_err), "period": (T, T_err),
            "theta_min": (base["theta_min"], theta_err["theta_min"]),
            "theta_max": (base["theta_max"], theta_err["theta_max"]),
            "u1": (r[:, 0], du[:, 0]), "u2": (r[:, 1], du[:, 1]), "u3": (r[:, 2], du[:, 2]),
        }
        if want_advance:
            adv = base["advance"]
            adv_err = propagated("advance") + base["n_rounding"] + 8 * _EPS * base["advance_spread"]
            fallback |= ~(base["n_margin"] > _N_MARGIN)
            rate = adv / T
            out["precession_per_nutation"] = (adv, adv_err)
            out["mean_precession_rate"] = (rate, np.abs(rate) * (adv_err / np.abs(adv) + T_err / T))
        if any(k in names for k in ("energy", "p_phi", "p_psi")):
            inv = _columns(F["invariants"], (*P, *S), n)
            # the rounding of each invariant is bounded by its terms' sizes (E = T + V, p_φ = I1 sin²θ φ̇ + I3 cos θ ω3
            # (3.64) cancel), and checked against (a, b) of the same state: I1 b = p_φ, I1 a = p_ψ (3.66)
            w3 = np.abs(S[3]) + np.abs(S[2])
            size_e = np.abs(inv[0]) + P[0] * (S[1] ** 2 + S[2] ** 2) + P[1] * w3 ** 2 + P[2] * P[3] * P[4]
            size_p = P[0] * np.abs(S[2]) + P[1] * w3
            out["energy"] = (inv[0], 8 * _EPS * size_e)
            out["p_phi"] = (inv[1], np.abs(inv[1] - P[0] * b) + 8 * _EPS * size_p)
            out["p_psi"] = (inv[2], np.abs(inv[2] - P[0] * a) + 8 * _EPS * P[1] * w3)
        for name in names:
            if name == "motion_class":
                continue
            value, err = out[name]
            fallback |= ~(err <= _RTOL * np.abs(value)) | ~np.isfinite(value)
            values[name], errors[name] = value, err
        if "motion_class" in names:
            u1, u2 = r[:, 0], r[:, 1]
            g1, g2 = b - a * u1, b - a * u2
            scale = np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-300)
            # figure 44's rule as exact.classify applies it; a point whose u2 - u1 or |b - a u_k| lies within
            # its error of the rule's thresholds (1e-12) could be classed differently at 40 digits: one by one
            g_err = np.abs(a)[:, None] * du[:, :2] + 4 * _EPS * scale[:, None]
            near = np.abs(np.stack([g1, g2], axis=1)) - 1e-12 * scale[:, None]
            fallback |= np.any(np.abs(near) <= 4 * g_err, axis=1)
            g_min = np.minimum(np.abs(g1), np.abs(g2))
            classes = np.where(u2 - u1 <= 1e-12, "uniform precession",
                               np.where(g_min <= 1e-12 * scale, "cusps",
                                        np.where(g1 * g2 > 0, "monotonic precession", "looping"))).astype(object)
            values["motion_class"] = classes
            errors["motion_class"] = np.full(n, np.nan)
    return BatchSummary(values, errors, fallback)
