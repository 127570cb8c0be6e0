"""The heavy top's per-motion quantities for N motions at once (a sweep's chunk), in NumPy.

The single-point path (:mod:`.summary`) sets each motion up at 40 digits with mpmath (~3 ms a
point).  Here the same derived constants — a, b, α, β (3.66), (3.72); f's coefficients (3.73);
κ², m (the nutation ansatz); the partial fractions of φ̇ (3.74) — are compiled for NumPy and
evaluated over all points in double precision:

* the roots u1 ≤ u2 ≤ 1 ≤ u3 of f: eigenvalues of the N companion matrices, sorted, clamped as the
  single path clamps them (u1 ≤ cos θ0 ≤ u2, within [-1, 1]), and polished by two Newton steps;
* the nutation period 2K(m)/κ, K = K(m) from 1 - m (SciPy's ``ellipkm1``: no cancellation near the
  separatrix);
* Δφ per period (2/κ)[c0 K + Σ c_i Π(n_i | m)] with Π(n | m) = K + (n/3) R_J(0, 1-m, 1, 1-n)
  (DLMF 19.25.2, Carlson's R_J from SciPy), regrouped as (2/κ)[φ̇(u1) K + Σ (c_i n_i/3) R_J]: the c_i of
  a fast top are large and cancel, φ̇ at the turning point does not;
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
    import sympy as sp  # noqa: F401  (only inside the builds, on a cold cache)

    from ...core.codecache import cached_lambdify
    from . import exact
    from . import model as hm

    def build_state():
        return exact._build_state()

    def build_taylor():
        from ...core.rounding import magnitude
        from . import exact_model as em

        coeffs = list(em.model().f_taylor_state)
        return [*hm.PARAMETERS, *hm.STATE], coeffs + [magnitude(c) for c in coeffs]

    def build_shift_values():
        from . import exact_model as em

        fr = em.model().precession_fractions_shifted
        return [*hm.PARAMETERS, *hm.STATE], [fr["values"][s] for s in fr["args"][3:-2]]

    def build_fractions():
        import sympy as sp

        from ...core.rounding import magnitude
        from . import exact_model as em

        # Δφ per period = (2/κ)[c0 K + Σ c_i Π(n_i | m)] with Π = K + (n/3) R_J (DLMF 19.25.2), regrouped as
        # (2/κ)[(c0 + Σ c_i) K + Σ (c_i n_i / 3) R_J(0, 1 − m, 1, 1 − n_i)]: c0 + Σ c_i is φ̇ at the turning
        # point u1, small for a fast top whose terms c_i are large and cancel (by ~a/φ̇, 10² to 10³)
        fr = em.model().precession_fractions_shifted
        at_u1 = sp.factor(sp.together(fr["c0"] + sum(c for c, _ in fr["terms"])))
        flat = [at_u1] + [x for c, n in fr["terms"] for x in (sp.factor(c * n / 3), n)]
        sizes = [magnitude(at_u1)] + [magnitude(sp.factor(c * n / 3)) for c, n in fr["terms"]]
        return fr["args"], flat + sizes

    def build_nutation():
        import sympy as sp

        from . import exact_model as em

        args, exprs = exact._build_nutation()
        shift = sp.Symbol("shift", real=True)
        moved = {em.u1: em.u1 + shift, em.u2: em.u2 + shift, em.u3: em.u3 + shift}
        for e in exprs:  # κ², m, 1 − m depend on the roots' differences only: they take w1, w2, w3 as well
            if sp.simplify(e.subs(moved, simultaneous=True) - e) != 0:
                from ...errors import DerivationError

                raise DerivationError(f"expected κ², m of the nutation invariant under a shift of the roots, got {e}")
        return args, exprs

    builds = {"state": ("heavy_top.constants_from_state", build_state),
              "taylor": ("heavy_top.f_taylor_state", build_taylor),
              "shift_values": ("heavy_top.shift_values", build_shift_values),
              "fractions": ("heavy_top.precession_fractions_shifted", build_fractions),
              "nutation": ("heavy_top.nutation_constants_shifted", build_nutation)}
    out = {key: cached_lambdify(label, build, module="numpy")[0] for key, (label, build) in builds.items()}

    def build_invariants():
        m = hm.model()
        return [*hm.PARAMETERS, *hm.STATE], [m.energy, m.azimuthal_momentum, m.spin_momentum]

    out["invariants"] = cached_lambdify("heavy_top.invariants_state", build_invariants, module="numpy")[0]
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


def _newton(c: list[np.ndarray], r: np.ndarray, steps: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Roots ``r`` (N, 3) of the cubic ``c`` (coefficients of w³, w², w, 1) polished by Newton; the last step."""
    c3, c2, c1, c0 = (x[:, None] for x in c)
    step = np.zeros_like(r)
    with np.errstate(all="ignore"):
        for _ in range(steps):
            d = (3 * c3 * r + 2 * c2) * r + c1
            step = np.where(d != 0, (((c3 * r + c2) * r + c1) * r + c0) / d, 0.0)
            step = np.where(np.isfinite(step), step, 0.0)
            r = r - step
    return r, np.abs(step)


def _roots(c: list[np.ndarray], lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots w1 ≤ w2 ≤ w3 (N, 3) of f(u0 + w) (coefficients ``c`` of w³, w², w, 1) and each one's last Newton
    step.  w = 0 lies in [w1, w2] (u0 is inside the motion) and [u1, u2] in [-1, 1] (w in [``lo``, ``hi``]):
    clamped there as the single path clamps.  Where f(u0) = 0 exactly (θ̇0 = 0: the start is a turning
    point) w = 0 is a root and the other two come from the deflated quadratic without cancellation."""
    c3, c2, c1, c0 = c
    n = len(c0)
    companion = np.zeros((n, 3, 3))
    with np.errstate(all="ignore"):
        companion[:, 0, :] = -np.stack([c2, c1, c0], axis=1) / c3[:, None]
    companion[:, 1, 0] = companion[:, 2, 1] = 1.0
    companion[~np.isfinite(companion)] = 0.0
    r = np.sort(np.linalg.eigvals(companion).real, axis=1)
    at_turning = c0 == 0
    if at_turning.any():
        with np.errstate(all="ignore"):
            # c3 w² + c2 w + c1 = 0 (Numerical Recipes 5.6)
            disc = np.sqrt(np.maximum(c2 * c2 - 4 * c3 * c1, 0.0))
            q = -(c2 + np.copysign(disc, c2)) / 2
            pair = np.sort(np.stack([q / c3, np.where(q != 0, c1 / q, 0.0)], axis=1), axis=1)
        r[at_turning] = np.sort(np.concatenate([np.zeros((at_turning.sum(), 1)), pair[at_turning]], axis=1), axis=1)
    r, step = _newton(c, r)
    r[at_turning] = np.where(np.abs(r[at_turning]) < 1e-300, 0.0, r[at_turning])
    r[:, 1] = np.minimum(np.maximum(r[:, 1], 0.0), hi)
    r[:, 0] = np.maximum(np.minimum(r[:, 0], 0.0), lo)
    return r, step


def _pi(n: np.ndarray, one_minus_n: np.ndarray, m1: np.ndarray) -> np.ndarray:
    """Π(n | m) = R_F(0, 1 - m, 1) + (n/3) R_J(0, 1 - m, 1, 1 - n) (DLMF 19.25.2), vectorised."""
    from scipy.special import elliprf, elliprj

    zero = np.zeros_like(m1)
    return elliprf(zero, m1, 1.0) + n / 3 * elliprj(zero, m1, 1.0, one_minus_n)


def _pipeline(F: dict, P: list, a: np.ndarray, beta: np.ndarray, shift: list[np.ndarray], w: np.ndarray,
              want_advance: bool) -> dict[str, np.ndarray]:
    """T, Δφ, θ_min, θ_max (and what they are made of) from the roots ``w`` (N, 3) of f(u0 + w)."""
    from scipy.special import ellipkm1

    rate0, d_bottom, d_pole = shift
    w1, w2, w3 = w[:, 0], w[:, 1], w[:, 2]
    n = len(w1)
    with np.errstate(all="ignore"):
        kappa2, m, m1 = _columns(F["nutation"], (beta, w1, w2, w3), n)
        kappa = np.sqrt(kappa2)
        K = ellipkm1(m1)
        # θ from 1 ∓ u = (1 ∓ u0) ∓ w: exact at the poles (d_pole = u0 − 1, d_bottom = u0 + 1 in the half angle)
        out = {"kappa": kappa, "m": m, "m1": m1, "K": K, "T": 2 * K / kappa,
               "theta_min": 2 * np.arctan2(np.sqrt(np.maximum(-d_pole - w2, 0)), np.sqrt(d_bottom + w2)),
               "theta_max": 2 * np.arctan2(np.sqrt(np.maximum(-d_pole - w1, 0)), np.sqrt(d_bottom + w1))}
        if want_advance:
            from scipy.special import elliprj

            flat = _columns(F["fractions"], (P[0], P[1], a, rate0, d_bottom, d_pole, w1, w2 - w1), n)
            k = (len(flat) - 1) // 3
            pairs, sizes = flat[1:1 + 2 * k], flat[1 + 2 * k:]
            term = flat[0] * 2 * K / kappa
            advance = term
            spread = np.abs(term) * np.where(flat[0] != 0, sizes[0] / np.abs(flat[0]), 1.0)
            n_margin = np.full(n, np.inf)
            rounding = np.zeros(n)
            for c, nn, size in zip(pairs[0::2], pairs[1::2], sizes[1:]):
                one_minus_n = 1 - nn
                term = c * 2 * elliprj(np.zeros(n), m1, 1.0, one_minus_n) / kappa
                advance = advance + term
                # each term's rounding: its coefficient's terms' sizes, then ~ε in R_J and the product
                spread = spread + np.abs(term) * np.where(c != 0, size / np.abs(c), 1.0)
                n_margin = np.minimum(n_margin, one_minus_n)
                # n's rounding, amplified in R_J by ~1/(1 - n)
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
        taylor = _columns(F["taylor"], (*P, *S), n)
        c, sizes = taylor[:4], taylor[4:]
        shift = _columns(F["shift_values"], (*P, *S), n)
        rate0, d_bottom, d_pole = shift
        u0 = np.cos(S[0])
        w, last_step = _roots(c, -d_bottom, -d_pole)
        # f's rounding noise at the roots, from the sizes of its coefficients' terms (8ε each): f shifted up and
        # down by it widens and narrows the motion consistently; every quantity is recomputed from those roots
        absw = np.abs(w)
        noise = 8 * _EPS * (((sizes[0][:, None] * absw + sizes[1][:, None]) * absw + sizes[2][:, None]) * absw
                            + sizes[3][:, None])
        slope = np.abs((3 * c[0][:, None] * w + 2 * c[1][:, None]) * w + c[2][:, None])
        # the turning points' noise moves f up and down: u1, u2 (and u3 with them) consistently
        near = np.maximum(noise[:, 0], noise[:, 1])
        moved = [_newton([c[0], c[1], c[2], c[3] + sign * near], w)[0] for sign in (1.0, -1.0)]
        dw = np.max([np.abs(x - w) for x in moved], axis=0) + noise / slope + 2 * last_step
        amp = w[:, 1] - w[:, 0]
        want_advance = any(k in names for k in ("mean_precession_rate", "precession_per_nutation"))
        base = _pipeline(F, P, a, beta, shift, w, want_advance)
        others = [_pipeline(F, P, a, beta, shift, x, want_advance) for x in moved]

        def propagated(key: str) -> np.ndarray:
            return np.max([np.abs(o[key] - base[key]) for o in others], axis=0)

        from scipy.special import elliprf

        K_other = elliprf(np.zeros(n), base["m1"], 1.0)
        T = base["T"]
        T_err = propagated("T") + np.abs(K_other - base["K"]) * 2 / base["kappa"] + 4 * _EPS * T
        one_minus_u2, one_plus_u1 = -d_pole - w[:, 1], d_bottom + w[:, 0]
        # a nutating motion, inside the separatrix, away from the poles' passages
        fallback |= ~(amp > 1e-9 * np.maximum(absw[:, 2], 1e-300)) | ~(amp > 0)  # steady, or nearly
        fallback |= ~(base["m1"] > 1e-6)
        fallback |= ~(one_minus_u2 > 1e-6) | ~(one_plus_u1 > 1e-6)
        fallback |= ~np.all(np.isfinite(w), axis=1) | ~np.isfinite(T)
        u = u0[:, None] + w
        theta_err = {k: propagated(k) + 4 * _EPS * base[k] for k in ("theta_min", "theta_max")}
        out: dict[str, tuple[np.ndarray, np.ndarray]] = {
            "nutation_period": (T, T_err), "period": (T, T_err),
            "theta_min": (base["theta_min"], theta_err["theta_min"]),
            "theta_max": (base["theta_max"], theta_err["theta_max"]),
            "u1": (u[:, 0], dw[:, 0] + _EPS * np.abs(u[:, 0])), "u2": (u[:, 1], dw[:, 1] + _EPS * np.abs(u[:, 1])),
            "u3": (u[:, 2], dw[:, 2] + _EPS * np.abs(u[:, 2])),
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
            # figure 44's rule as exact.classify applies it to (u1, u2, a, b); here b − a u_k = φ̇0 sin²θ0 − a w_k
            # (rate0 − a w_k) without cancellation.  A point within its error of the rule's thresholds (1e-12)
            # could be classed differently at 40 digits: one by one
            g = rate0[:, None] - a[:, None] * w[:, :2]
            scale = np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-300)
            g_err = np.abs(a)[:, None] * dw[:, :2] + 8 * _EPS * (np.abs(rate0) + np.abs(a) * absw[:, :2].T).T
            fallback |= np.any(np.abs(np.abs(g) - 1e-12 * scale[:, None]) <= 4 * g_err + 4 * _EPS * scale[:, None],
                               axis=1)
            fallback |= np.abs(amp - 1e-12) <= 4 * (dw[:, 0] + dw[:, 1])
            g_min = np.min(np.abs(g), axis=1)
            classes = np.where(amp <= 1e-12, "uniform precession",
                               np.where(g_min <= 1e-12 * scale, "cusps",
                                        np.where(g[:, 0] * g[:, 1] > 0, "monotonic precession", "looping")))
            values["motion_class"] = classes.astype(object)
            errors["motion_class"] = np.full(n, np.nan)
    return BatchSummary(values, errors, fallback)
