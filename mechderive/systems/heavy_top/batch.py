"""The heavy top's per-motion quantities for N motions at once (a sweep's chunk), in NumPy.

The single-point path (:mod:`.summary`) sets each motion up at 40 digits with mpmath (~3 ms a
point, ~20 ms with its estimates).  Here the same derived quantities are compiled for NumPy and
evaluated over all points at once:

* the turning points measured from the start, u_k = u0 + w_k with w_k the roots of f(u0 + w)
  (``f_taylor_state``, derived: the coefficients of w³ ... 1 in the state; f(u0) = sin²θ0 θ̇0²): the
  amplitude w2 − w1 keeps its relative accuracy where u2 − u1 would lose it (a fast top's 1e-4 of
  u ~ 1 leaves 1e-12).  Eigenvalues of the companion matrices (the deflated quadratic when θ̇0 = 0,
  the start a turning point), polished by Newton, clamped as the single path clamps (w1 ≤ 0 ≤ w2,
  u in [-1, 1]);
* κ², m, 1 − m of the nutation ansatz from (w1, w2, w3) (derived; checked invariant under a common
  shift of the roots), the nutation period 2K(m)/κ with K = R_F(0, 1 − m, 1);
* Δφ per period (2/κ)[c0 K + Σ c_i Π(n_i | m)], Π = K + (n/3) R_J(0, 1 − m, 1, 1 − n) (DLMF 19.25.2),
  regrouped as (2/κ)[φ̇(u1) K + Σ (c_i n_i/3) R_J]: the c_i of a fast top are large and cancel,
  φ̇ at the turning point does not.  The partial fractions are derived in the shifted variables
  (``precession_fractions_shifted``: 1 ∓ u0 from the half angle, φ̇0 sin²θ0 for b − a u0);
* θ_min, θ_max = 2 atan2(√(1 ∓ u), √(1 ± u)) from 1 ∓ u = (1 ∓ u0) ∓ w; figure 44's class by the
  single path's rule (:func:`.exact.classify`) on b − a u_k = φ̇0 sin²θ0 − a w_k;
* E, p_φ, p_ψ by the derived invariants.

Two tiers of precision: every point in doubles first; the points whose estimates miss the mark
again in ``numpy.longdouble`` where it is wider (x87 extended precision on x86-64, ε = 1.1e-19;
Carlson's integrals from :mod:`mechderive.special._carlson` run in it too).  A fast top's mean
precession is a difference of terms ~10²-10⁴ times larger; the extended tier answers most of those.

Error estimates are measured per point, never a constant:

* the roots: f's rounding noise at each root, 8ε times the sizes of its coefficients' terms
  (:func:`mechderive.core.rounding.magnitude` of each derived coefficient, compiled beside it), turned
  into a root error through f'; f shifted up and down by the noise at the turning points widens and
  narrows the motion consistently, and every quantity is recomputed from those roots: the larger
  change is the propagated error;
* K: Carlson's R_F against the arithmetic-geometric mean, two independent algorithms;
* Δφ: each term's rounding (the sizes of its coefficient's terms, ε in R_J and the product) and the
  rounding of n in 1 − n, amplified by 1/(1 − n).

A point is answered here only if every estimate is below 1e-12 relative (the estimates are
first-order bounds: the value then equals the 40-digit single path's to 1e-12, which
tests/test_sweep.py checks on a random sample).  Otherwise — and for steady and near-steady motions,
sleeping and hanging tops, near passages of the pole or the bottom, near the separatrix (1 − m < 1e-6),
points the checks would refuse and quantities that are not plain numbers — it is ``fallback``: the
sweep runs it through the planner, which uses the 40-digit path.
"""

from __future__ import annotations

import functools
from typing import Any, Mapping

import numpy as np

from ..base import BatchSummary

__all__ = ["summarize_batch", "BATCHED", "TIERS"]

#: the quantities answered here; the others (``steady``, ``minimum_spin``: not plain numbers, or not
#: defined for most motions) always go one by one
BATCHED = ("nutation_period", "period", "theta_min", "theta_max", "u1", "u2", "u3", "mean_precession_rate",
           "precession_per_nutation", "motion_class", "energy", "p_phi", "p_psi", "steady", "minimum_spin")
#: answered without computation for a nutating top launched off the poles (as the single path answers them):
#: ``steady`` is {"kind": "none"}, ``minimum_spin`` does not apply (the top is not sleeping)
_DESCRIPTIVE = ("steady", "minimum_spin")

#: the precisions tried in turn: doubles, then extended precision where the platform has it
TIERS = (np.float64,) + ((np.longdouble,) if np.finfo(np.longdouble).eps < 1e-18 else ())
_EPS64 = float(np.finfo(np.float64).eps)
#: the largest estimated relative error a batched value may carry: the agreement promised.  The estimates
#: are first-order bounds (each term's rounding at its full size, the roots moved by their whole error),
#: 10-50 times the errors seen against the 40-digit path (tests/test_sweep.py measures both)
_RTOL = 1e-12
#: closest approach to 1 of a characteristic n answered in doubles: the rounding of n costs ~ε/(1 - n) in Π
_N_MARGIN = 1e-3


@functools.cache
def _functions() -> dict[str, Any]:
    """The derived constants compiled for NumPy (disk cache: derived and compiled once per install)."""
    from ...core.codecache import cached_lambdify
    from . import exact

    # (the model, and SymPy with it, imported in the builds only: a warm process loads the compiled code)
    def build_state():
        args, exprs = exact._build_state()
        return args, _binary_exact(exprs)

    def build_taylor():
        from ...core.rounding import magnitude
        from . import exact_model as em
        from . import model as hm

        coeffs = list(em.model().f_taylor_state)
        return [*hm.PARAMETERS, *hm.STATE], _binary_exact(coeffs + [magnitude(c) for c in coeffs])

    def build_shift_values():
        # [rate0, d_bottom, d_pole] as precession_fractions_shifted takes them: b − a u0 = φ̇0 sin²θ0 (3.74) from
        # the state, and cos θ0 ± 1 in the half angle, exact at the poles.  Derived from a, b of the state
        # (3.66) rather than with the partial fractions: the single-point closed form takes these for u(t)
        # alone, which must not derive φ's fractions (laziness)
        import sympy as sp

        from ...core.simplify import factor, trig_normal
        from . import model as hm

        cfs, th = hm.model().constants_from_state, hm.STATE[0]
        rate0 = factor(trig_normal(cfs[hm.b] - cfs[hm.a] * sp.cos(th)))
        half = {"d_bottom": 2 * sp.cos(th / 2) ** 2, "d_pole": -2 * sp.sin(th / 2) ** 2}
        return [*hm.PARAMETERS, *hm.STATE], _binary_exact([rate0, half["d_bottom"], half["d_pole"]])

    def build_fractions():
        import sympy as sp

        from ...core.rounding import magnitude
        from ...core.simplify import factor
        from . import exact_model as em

        # Δφ per period = (2/κ)[c0 K + Σ c_i Π(n_i | m)] with Π = K + (n/3) R_J (DLMF 19.25.2), regrouped as
        # (2/κ)[(c0 + Σ c_i) K + Σ (c_i n_i / 3) R_J(0, 1 − m, 1, 1 − n_i)]: c0 + Σ c_i is φ̇ at the turning
        # point u1, small for a fast top whose terms c_i are large and cancel (by ~a/φ̇, 10² to 10³)
        # (the 1/3 is applied in the pipeline: a constant 1/3 compiled into the code would be a double, and limit
        # the extended tier to double precision in a term that cancels)
        fr = em.model().precession_fractions_shifted
        at_u1 = factor(sp.together(fr["c0"] + sum(c for c, _ in fr["terms"])))
        flat = [at_u1] + [x for c, n in fr["terms"] for x in (factor(c * n), n)]
        sizes = [magnitude(at_u1)] + [magnitude(factor(c * n)) for c, n in fr["terms"]]
        return fr["args"], _binary_exact(flat + sizes)

    def build_nutation():
        import sympy as sp

        from . import exact_model as em
        from .exact_model import _is_zero_rational

        args, exprs = exact._build_nutation()
        shift = sp.Symbol("shift", real=True)
        moved = {em.u1: em.u1 + shift, em.u2: em.u2 + shift, em.u3: em.u3 + shift}
        for e in exprs:  # κ², m, 1 − m depend on the roots' differences only: they take w1, w2, w3 as well
            # (rational in the roots and β: cancel decides it exactly, without simplify's search)
            if not _is_zero_rational(e.subs(moved, simultaneous=True) - e):
                from ...errors import DerivationError

                raise DerivationError(f"expected κ², m of the nutation invariant under a shift of the roots, got {e}")
        return args, _binary_exact(exprs)

    def build_invariants():
        from . import model as hm

        m = hm.model()
        return [*hm.PARAMETERS, *hm.STATE], _binary_exact([m.energy, m.azimuthal_momentum, m.spin_momentum])

    builds = {"state": ("heavy_top.constants_from_state", build_state),
              "taylor": ("heavy_top.f_taylor_state", build_taylor),
              "shift_values": ("heavy_top.shift_values", build_shift_values),
              "fractions": ("heavy_top.precession_fractions_shifted", build_fractions),
              "nutation": ("heavy_top.nutation_constants_shifted", build_nutation),
              "invariants": ("heavy_top.invariants_state", build_invariants)}
    return _OnDemand({key: functools.partial(cached_lambdify, label, build, module="numpy")
                      for key, (label, build) in builds.items()})


class _OnDemand(dict):
    """The compiled functions, each loaded (or derived) on its first use: the single-point closed form takes
    the batch's nutation constants for u(t) alone, and must not derive φ's partial fractions for it (laziness)."""

    def __init__(self, makers: dict) -> None:
        super().__init__()
        self._makers = makers

    def __missing__(self, key: str) -> Any:
        value = self[key] = self._makers[key]()[0]
        return value


def _binary_exact(exprs: list) -> list:
    """``exprs``, checked to hold only constants exact in binary (integers, halves, quarters...): compiled
    code holds its constants as doubles, which would cap the extended tier at double precision."""
    import sympy as sp

    from ...errors import DerivationError

    for e in exprs:
        for c in (e.atoms(sp.Rational, sp.Float) if isinstance(e, sp.Basic) else ()):
            if isinstance(c, sp.Float) or c.q & (c.q - 1):
                raise DerivationError(f"expected constants exact in binary in the batched closed form, got {c} in {e}")
    return exprs


def _array(values: Any, n: int, dtype: type = np.float64) -> np.ndarray:
    """``values`` (a compiled column, or a constant) as a fresh array of n points in ``dtype``."""
    arr = np.asarray(values, dtype=dtype)
    if arr.shape == (n,):  # the usual column: a copy, without broadcast_to's Python wrapper (~76 calls a warm run)
        return arr.copy()
    return np.broadcast_to(arr, (n,)).astype(dtype)


def _columns(f: Any, args: tuple, n: int) -> list[np.ndarray]:
    dtype = args[0].dtype.type
    return [_array(v, n, dtype) for v in f(*args)]


def _valid(p: dict[str, np.ndarray], s: dict[str, np.ndarray], strict: bool, mgl: bool) -> np.ndarray:
    """Points the parameter and state checks accept (:mod:`.parameters`); the rest go one by one (and are
    refused there, with the checks' own message).  ``mgl``: the top was given by M g l alone (realised as
    M = 1, g = Mgl, l = 1), whose rigid-body condition is I1 ≥ I3/2."""
    ok = np.ones(len(s["theta"]), dtype=bool)
    for v in (*p.values(), *s.values()):
        ok &= np.isfinite(v) & (np.abs(v) < 1e100)  # far from order one: the planner solves in scaled units
    ok &= (p["I1"] > 0) & (p["I3"] > 0) & (p["M"] > 0) & (p["g"] > 0) & (p["l"] > 0)
    ok &= (s["theta"] > 0) & (s["theta"] < np.pi)  # the poles: sleeping and hanging tops, steady there
    if strict:
        # the rigid-body condition, with a margin: on the boundary the single path's rounding decides
        arm = 0.0 if mgl else p["M"] * p["l"] ** 2
        ok &= (p["I1"] - arm - p["I3"] / 2) > 1e-12 * (p["I1"] + p["I3"])
    return ok


def _newton(c: list[np.ndarray], r: np.ndarray, steps: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Roots ``r`` (N, 3) of the cubic ``c`` (coefficients of w³, w², w, 1) polished by Newton; the last step."""
    c3, c2, c1, c0 = (x[:, None] for x in c)
    step = np.zeros_like(r)
    with np.errstate(all="ignore"):
        for _ in range(steps):
            d = (3 * c3 * r + 2 * c2) * r + c1
            step = np.where(d != 0, (((c3 * r + c2) * r + c1) * r + c0) / d, 0)
            step = np.where(np.isfinite(step), step, 0)
            r = r - step
    return r, np.abs(step)


def _roots(c: list[np.ndarray], lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots w1 ≤ w2 ≤ w3 (N, 3) of f(u0 + w) (coefficients ``c`` of w³, w², w, 1) and each one's last Newton
    step.  w = 0 lies in [w1, w2] (u0 is inside the motion) and [u1, u2] in [-1, 1] (w in [``lo``, ``hi``]):
    clamped there as the single path clamps.  Where f(u0) = 0 exactly (θ̇0 = 0: the start is a turning
    point) w = 0 is a root and the other two come from the deflated quadratic without cancellation.
    The eigenvalues are found in doubles; Newton polishes them in the coefficients' precision."""
    c3, c2, c1, c0 = c
    n = len(c0)
    companion = np.zeros((n, 3, 3))
    with np.errstate(all="ignore"):
        companion[:, 0, :] = -np.stack([c2, c1, c0], axis=1).astype(float) / c3[:, None].astype(float)
    companion[:, 1, 0] = companion[:, 2, 1] = 1.0
    companion[~np.isfinite(companion)] = 0.0
    r = np.sort(np.linalg.eigvals(companion).real, axis=1).astype(c0.dtype)
    at_turning = c0 == 0
    if at_turning.any():
        with np.errstate(all="ignore"):
            # c3 w² + c2 w + c1 = 0 (Numerical Recipes 5.6)
            disc = np.sqrt(np.maximum(c2 * c2 - 4 * c3 * c1, 0))
            q = -(c2 + np.copysign(disc, c2)) / 2
            pair = np.sort(np.stack([q / c3, np.where(q != 0, c1 / q, 0)], axis=1), axis=1)
        zero = np.zeros((int(at_turning.sum()), 1), dtype=c0.dtype)
        r[at_turning] = np.sort(np.concatenate([zero, pair[at_turning]], axis=1), axis=1)
    r, step = _newton(c, r, steps=2 if c0.dtype == np.float64 else 3)
    r[at_turning] = np.where(np.abs(r[at_turning]) < 1e-300, 0, r[at_turning])
    r[:, 1] = np.minimum(np.maximum(r[:, 1], 0), hi)
    r[:, 0] = np.maximum(np.minimum(r[:, 0], 0), lo)
    return r, step


def _twice(x: np.ndarray) -> np.ndarray:
    """The points of ``x`` twice over, as :func:`_tier` stacks its two moved motions."""
    return np.concatenate([x, x])


def _thrice(x: np.ndarray) -> np.ndarray:
    """The points of ``x`` three times over, as :func:`_tier` stacks a motion with its two moved ones."""
    return np.concatenate([x, x, x])


def _agm_k(m1: np.ndarray) -> np.ndarray:
    """K(m) by the arithmetic-geometric mean in double-double (:func:`mechderive.special._parameter.quarter_period`,
    DLMF 19.8.5), from 1 − m split into two doubles: the second, independent evaluation of K, in ``m1``'s dtype."""
    from ...special._parameter import quarter_period

    hi = m1.astype(float)
    lo = (m1 - hi.astype(m1.dtype)).astype(float)
    K_hi, K_lo = quarter_period(hi, lo)
    return K_hi.astype(m1.dtype) + K_lo.astype(m1.dtype)


def _pipeline(F: dict, P: list, a: np.ndarray, beta: np.ndarray, shift: list[np.ndarray], w: np.ndarray,
              want_advance: bool) -> dict[str, np.ndarray]:
    """T, Δφ, θ_min, θ_max (and what they are made of) from the roots ``w`` (N, 3) of f(u0 + w)."""
    from ...special._carlson import elliprf, elliprj

    rate0, d_bottom, d_pole = shift
    w1, w2, w3 = w[:, 0], w[:, 1], w[:, 2]
    n = len(w1)
    eps = float(np.finfo(w.dtype).eps)
    zero = np.zeros_like(w1)
    with np.errstate(all="ignore"):
        kappa2, m, m1 = _columns(F["nutation"], (beta, w1, w2, w3), n)
        kappa = np.sqrt(kappa2)
        K = elliprf(zero, m1, np.ones_like(m1))
        # θ from 1 ∓ u = (1 ∓ u0) ∓ w: exact at the poles (d_pole = u0 − 1, d_bottom = u0 + 1 in the half angle)
        out = {"kappa": kappa, "m": m, "m1": m1, "K": K, "T": 2 * K / kappa,
               "theta_min": 2 * np.arctan2(np.sqrt(np.maximum(-d_pole - w2, 0)), np.sqrt(d_bottom + w2)),
               "theta_max": 2 * np.arctan2(np.sqrt(np.maximum(-d_pole - w1, 0)), np.sqrt(d_bottom + w1))}
        if want_advance:
            flat = _columns(F["fractions"], (P[0], P[1], a, rate0, d_bottom, d_pole, w1, w2 - w1), n)
            k = (len(flat) - 1) // 3
            pairs, sizes = flat[1:1 + 2 * k], flat[1 + 2 * k:]
            term = flat[0] * 2 * K / kappa
            advance = term
            spread = np.abs(term) * np.where(flat[0] != 0, sizes[0] / np.abs(flat[0]), 1)
            n_margin = np.full(n, np.inf)
            rounding = np.zeros(n)
            for c, nn, size in zip(pairs[0::2], pairs[1::2], sizes[1:]):
                one_minus_n = 1 - nn
                term = c * 2 * elliprj(zero, m1, np.ones_like(m1), one_minus_n) / (3 * kappa)
                advance = advance + term
                # each term's rounding: its coefficient's terms' sizes, then ~ε in R_J and the product
                spread = spread + np.abs(term) * np.where(c != 0, size / np.abs(c), 1)
                n_margin = np.minimum(n_margin, one_minus_n.astype(float))
                # n's rounding, amplified in R_J by ~1/(1 - n)
                rounding = rounding + (np.abs(term) * eps * np.abs(nn) / np.abs(one_minus_n)).astype(float)
            out.update(advance=advance, advance_spread=spread, n_margin=n_margin, n_rounding=rounding)
    return out


def _tier(P: list[np.ndarray], S: list[np.ndarray], names: tuple[str, ...], dtype: type,
          keep: dict | None = None) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], np.ndarray]:
    """(values, estimates, answered) of the points (P, S) computed in ``dtype``; values and estimates as doubles.

    ``keep``, if given, receives the intermediates in ``dtype`` (a, b, α, β; the roots ``w`` of f(u0 + w);
    u0; the shifted values; κ, m, 1 − m, K, T of the nutation): the single-point closed form's setup in
    extended precision (:mod:`.exact_extended`) is this batch of one.  With ``keep["values_only"]`` set,
    only those are computed (no estimates; nothing answered)."""
    F = _functions()
    P = [x.astype(dtype) for x in P]
    S = [x.astype(dtype) for x in S]
    n = len(S[0])
    eps = float(np.finfo(dtype).eps)
    ok = np.ones(n, dtype=bool)
    values: dict[str, np.ndarray] = {}
    errors: dict[str, np.ndarray] = {}
    with np.errstate(all="ignore"):
        a, b, alpha, beta = _columns(F["state"], (*P, *S), n)
        taylor = _columns(F["taylor"], (*P, *S), n)
        c, sizes = taylor[:4], taylor[4:]
        shift = _columns(F["shift_values"], (*P, *S), n)
        rate0, d_bottom, d_pole = shift
        u0 = np.cos(S[0])
        w, last_step = _roots(c, -d_bottom, -d_pole)
        want_advance = any(k in names for k in ("mean_precession_rate", "precession_per_nutation"))
        values_only = keep is not None and keep.get("values_only")
        if not values_only:
            # f's rounding noise at each root, from the sizes of its coefficients' terms (8ε each); f shifted up and
            # down by the noise at the turning points widens and narrows the motion, u1, u2 and u3 consistently
            absw = np.abs(w)
            noise = 8 * eps * (((sizes[0][:, None] * absw + sizes[1][:, None]) * absw + sizes[2][:, None]) * absw
                               + sizes[3][:, None])
            slope = np.abs((3 * c[0][:, None] * w + 2 * c[1][:, None]) * w + c[2][:, None])
            near = np.maximum(noise[:, 0], noise[:, 1])
            # the two moved motions, then with the roots themselves, as one batch of 2n and one of 3n: each element's
            # arithmetic is as in separate batches, in a third of the calls (the calls are the cost of a batch of one,
            # the single-point closed form).  (Carlson's loops run to the batch's slowest point, as they do for any
            # batch: the moved motions are within the roots' rounding of the motion itself.)
            both = _newton([_twice(c[0]), _twice(c[1]), _twice(c[2]), np.concatenate([c[3] + near, c[3] - near])],
                           _twice(w))[0]
            moved = [both[:n], both[n:]]
            dw = (np.max([np.abs(x - w) for x in moved], axis=0) + noise / slope + 2 * last_step).astype(float)
            amp = (w[:, 1] - w[:, 0]).astype(float)
            stacked = _pipeline(F, [_thrice(x) for x in P[:2]], _thrice(a), _thrice(beta),
                                [_thrice(x) for x in shift], np.concatenate([w, both]), want_advance)
            base, *others = ({k: v[i * n:(i + 1) * n] for k, v in stacked.items()} for i in range(3))
        else:
            base = _pipeline(F, P, a, beta, shift, w, want_advance)
        if keep is not None:
            keep.update(a=a, b=b, alpha=alpha, beta=beta, w=w, u0=u0, rate0=rate0, d_bottom=d_bottom, d_pole=d_pole,
                        **{k: base[k] for k in ("kappa", "m", "m1", "K", "T")})
            if values_only:  # the same values in another precision, to compare with: no estimates
                return values, errors, np.zeros(n, dtype=bool)

        def propagated(key: str) -> np.ndarray:
            return np.max([np.abs(o[key] - base[key]) for o in others], axis=0).astype(float)

        T = base["T"]
        T_err = propagated("T") + (np.abs(_agm_k(base["m1"]) - base["K"]) * 2 / base["kappa"]).astype(float) \
            + 4 * eps * np.abs(T.astype(float)) + _EPS64 * np.abs(T.astype(float))
        one_minus_u2, one_plus_u1 = (-d_pole - w[:, 1]).astype(float), (d_bottom + w[:, 0]).astype(float)
        # a nutating motion, inside the separatrix, away from the poles' passages
        ok &= (amp > 1e-9 * np.maximum(absw[:, 2].astype(float), 1e-300)) & (amp > 0)  # not steady, nor nearly
        ok &= base["m1"].astype(float) > 1e-6
        ok &= (one_minus_u2 > 1e-6) & (one_plus_u1 > 1e-6)
        ok &= np.all(np.isfinite(w.astype(float)), axis=1) & np.isfinite(T.astype(float))
        u = u0[:, None] + w
        out: dict[str, tuple[np.ndarray, np.ndarray]] = {
            "nutation_period": (T, T_err), "period": (T, T_err),
            # u0 + w_k: cos θ0's rounding and the sum's, at the size of the larger term
            **{f"u{k + 1}": (u[:, k], dw[:, k] + (2 * eps * (np.abs(u0) + absw[:, k])).astype(float)) for k in range(3)},
        }
        for key in ("theta_min", "theta_max"):
            out[key] = (base[key], propagated(key) + 4 * eps * np.abs(base[key].astype(float)))
        if want_advance:
            adv = base["advance"]
            adv_err = propagated("advance") + base["n_rounding"] + 8 * eps * base["advance_spread"].astype(float)
            ok &= base["n_margin"] > (_N_MARGIN if dtype == np.float64 else 1e-6)
            rate = adv / T
            out["precession_per_nutation"] = (adv, adv_err)
            rate_f, adv_f = rate.astype(float), adv.astype(float)
            out["mean_precession_rate"] = (rate, np.abs(rate_f) * (adv_err / np.abs(adv_f) + T_err / T.astype(float)))
        if any(k in names for k in ("energy", "p_phi", "p_psi")):
            inv = _columns(F["invariants"], (*P, *S), n)
            # the rounding of each invariant is bounded by its terms' sizes (E = T + V, p_φ = I1 sin²θ φ̇ + I3 cos θ ω3
            # (3.64) cancel), and checked against (a, b) of the same state: I1 b = p_φ, I1 a = p_ψ (3.66)
            w3 = np.abs(S[3]) + np.abs(S[2])
            size_e = np.abs(inv[0]) + P[0] * (S[1] ** 2 + S[2] ** 2) + P[1] * w3 ** 2 + P[2] * P[3] * P[4]
            size_p = P[0] * np.abs(S[2]) + P[1] * w3
            out["energy"] = (inv[0], (8 * eps * size_e).astype(float))
            out["p_phi"] = (inv[1], (np.abs(inv[1] - P[0] * b) + 8 * eps * size_p).astype(float))
            out["p_psi"] = (inv[2], (np.abs(inv[2] - P[0] * a) + 8 * eps * P[1] * w3).astype(float))
        for name in names:
            if name in ("motion_class", *_DESCRIPTIVE):
                continue
            value, err = out[name]
            value = value.astype(float)
            # the value is reported as a double: its rounding is part of its error
            err = np.asarray(err, dtype=float) + _EPS64 / 2 * np.abs(value)
            ok &= (err <= _RTOL * np.abs(value)) & np.isfinite(value)
            values[name], errors[name] = value, err
        if "motion_class" in names:
            # figure 44's rule as exact.classify applies it to (u1, u2, a, b); here b − a u_k = φ̇0 sin²θ0 − a w_k
            # (rate0 − a w_k) without cancellation.  A point within its error of the rule's thresholds (1e-12)
            # could be classed differently at 40 digits: one by one
            g = (rate0[:, None] - a[:, None] * w[:, :2]).astype(float)
            af, bf, r0 = a.astype(float), b.astype(float), rate0.astype(float)
            scale = np.maximum(np.maximum(np.abs(af), np.abs(bf)), 1e-300)
            g_err = np.abs(af)[:, None] * dw[:, :2] + 8 * _EPS64 * (np.abs(r0)[:, None] + np.abs(af)[:, None]
                                                                    * absw[:, :2].astype(float))
            ok &= ~np.any(np.abs(np.abs(g) - 1e-12 * scale[:, None]) <= 4 * g_err + 4 * _EPS64 * scale[:, None],
                          axis=1)
            ok &= ~(np.abs(amp - 1e-12) <= 4 * (dw[:, 0] + dw[:, 1]))
            g_min = np.min(np.abs(g), axis=1)
            classes = np.where(amp <= 1e-12, "uniform precession",
                               np.where(g_min <= 1e-12 * scale, "cusps",
                                        np.where(g[:, 0] * g[:, 1] > 0, "monotonic precession", "looping")))
            values["motion_class"] = classes.astype(object)
            errors["motion_class"] = np.full(n, np.nan)
        if "steady" in names:
            ok &= amp > 1e-10  # far from figure 44's uniform precession (u2 − u1 ≤ 1e-12): a nutating top
    return values, errors, ok


def summarize_batch(parameters: Mapping[str, Any], initial: Mapping[str, Any], names: tuple[str, ...], *,
                    strict: bool = True) -> BatchSummary:
    """The heavy top's per-motion quantities ``names`` at N points (see the module's docstring).

    ``parameters``: I1 I3 M g l (or I1 I3 Mgl) arrays; ``initial``: theta theta_dot phi_dot psi_dot
    (phi, psi ignored: no summary depends on them) — SI units, as a checked scene holds them.
    """
    n = len(np.atleast_1d(initial["theta"]))
    p = {k: _array(v, n) for k, v in parameters.items()}
    mgl = "Mgl" in p
    if mgl:  # as check_params realises it: M = 1, g = Mgl, l = 1 (the same M g l)
        p = {"I1": p["I1"], "I3": p["I3"], "M": np.ones(n), "g": p["Mgl"], "l": np.ones(n)}
    s = {k: _array(initial.get(k, 0.0), n) for k in ("theta", "theta_dot", "phi_dot", "psi_dot")}
    fallback = ~_valid(p, s, strict, mgl)
    if any(name not in BATCHED for name in names):
        fallback[:] = True
    values: dict[str, np.ndarray] = {name: np.full(n, np.nan) for name in names}
    errors: dict[str, np.ndarray] = {name: np.full(n, np.nan) for name in names}
    for name in ("motion_class", "steady"):
        if name in values:
            values[name] = np.full(n, "", dtype=object)
    todo = np.flatnonzero(~fallback)
    P = [p[k] for k in ("I1", "I3", "M", "g", "l")]
    S = [s[k] for k in ("theta", "theta_dot", "phi_dot", "psi_dot")]
    for dtype in TIERS:
        if not todo.size:
            break
        got, est, ok = _tier([x[todo] for x in P], [x[todo] for x in S], names, dtype)
        for name in names:
            if name not in _DESCRIPTIVE:
                values[name][todo[ok]] = got[name][ok]
                errors[name][todo[ok]] = est[name][ok]
        todo = todo[~ok]
    fallback[todo] = True
    reasons = {}
    answered = np.flatnonzero(~fallback)
    if "steady" in names:
        from .summary import NOT_STEADY

        for i in answered:
            values["steady"][i] = dict(NOT_STEADY)
    if "minimum_spin" in names:
        from .summary import not_sleeping

        why = np.full(n, None, dtype=object)
        for i in answered:  # θ0 in (0, π) at every answered point: none is sleeping
            why[i] = not_sleeping(float(s["theta"][i]), float(s["theta_dot"][i]))
        reasons["minimum_spin"] = why
    return BatchSummary(values, errors, fallback, reasons)
