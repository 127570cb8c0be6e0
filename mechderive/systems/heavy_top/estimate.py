"""The closed form's error estimate, measured on each run (issue 11): :meth:`HeavyTopSolution.error_estimate`.

Nothing here is a constant.  Each check runs only when a requested quantity depends on it, and
reuses the evaluation's intermediates (the :class:`~.exact._Pass` of the same times):

1. **Nutation** (u, θ, θ̇, and R, the apex, ω built on them).
   (a) The residual of the derived u̇² = f(u) (3.73) at the samples, with u̇ = 2κ(u2 − u1) sn cn dn
   (the analytic derivative of the sn² form) and f = β(u − u1)(u − u2)(u − u3), each u − u_k formed
   from 1 ∓ u of the sample (as θ is) so that nothing cancels near the pole or the bottom.  An error
   e(t) of u, varying on the motion's time scale 1/κ, changes the residual by (2κ|u̇| + |f'(u)|)|e|:
   the residual divided by that is the error it indicates.  Near a turning point u̇ → 0 but
   f'(u) ≠ 0 (a simple root), so the sensitivity stays finite; in the middle of the swing the
   other way round.  A wrong κ or m shows here; a shift of the phase does not (it is a solution too).
   (b) The start: u(0) against cos θ0 (as 1 ∓ cos θ0, from the half angle).  A phase offset δτ
   gives δu(0) = |u̇0|δτ + ¼|f'(u0)|δτ² and δθ(t) ≤ max|θ̇|·δτ.
2. **Angles** φ, ψ (and the half sums and differences (φ ± ψ)/2 that R and ω are built from):
   φ(t_i) − φ0 at a few samples (the last, a spread, and the ones nearest the pole and the bottom)
   against Gauss–Legendre quadrature of the derived rates (3.74)–(3.75) in 1 ∓ u(t) from the sn²
   form — a path independent of the Π functions and their constants.  Whole nutation periods
   are one quadrature over [0, T] times their number (the rates have period T), checked against
   the closed form at n·T; the panels are split at the turning points and graded geometrically
   towards them when the rate has a narrow spike there (a near passage).
3. **Rates** φ̇, ψ̇ (and ω), output from the derived rates in 1 ∓ u: against the partial fractions in
   sn² (the angles' integrands) at the samples.
4. **Rounding** of what is output: the ulp of the continuous angles; the rounding of t itself
   amplified by the largest rate (near a pole passage |φ̇| ~ |b − a|/(1 − u2): the reasoning that
   was the planner's 3e-17 × conditioning); a few ulp of each quantity.

A check of a finite set of samples is an estimate, not a bound; the tests compare it with the
error against 30-digit references on ordinary and edge motions, and plant wrong constants.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...errors import DerivationError

__all__ = ["estimate"]

_EPS = float(np.finfo(float).eps)
#: Gauss–Legendre nodes per panel.  Panels are at most min(K/2, K') of phase long (K' the
#: imaginary quarter period, near whose multiples sn, cn, dn have poles) and graded towards
#: spikes.  Measured on one period of the rate: the chapter's top 5.5e-9, 1.3e-11, 1.6e-15, 2e-16
#: with 8, 12, 16, 24 nodes over half periods; a top falling from θ0 = 1e-2 (m1 = 3e-5) 2.6e-12
#: with 16 nodes, 2.7e-15 with 24 and 32 — 24 it is.
_NODES = 24
#: Samples whose accumulated angle is checked by quadrature (besides the last and the extremes).
_SPREAD = 3
#: Geometric grading towards a spike at most this deep (widths down to 4^-60 of the panel).
_MAX_LEVELS = 60

_NUTATION = ("u", "u_dot", "theta", "theta_dot")
_PHI = ("phi", "phi_wrapped", "phi_dot")
_PSI = ("psi", "psi_wrapped", "psi_dot")
_HALF = ("R", "omega")


#: The :data:`_NODES`-point Gauss–Legendre nodes (ascending) and weights on [-1, 1] (DLMF 3.5.19), nodes to an
#: ulp, weights to ~1e-14, written out: computing them (the eigenvalues of the Jacobi matrix, Golub and Welsch
#: 1969, then Newton's method on P_n by the three-term recurrence, DLMF 18.9.1) was ~3 % of every warm run's
#: solve stage, and ``numpy.polynomial``'s import ~6 ms.  tests/test_s3_6_heavy_top_edges.py derives them.
_GL_X = np.array([
    -0.9951872199970213, -0.9747285559713095, -0.9382745520027328, -0.8864155270044011, -0.820001985973903,
    -0.7401241915785544, -0.6480936519369755, -0.5454214713888396, -0.4337935076260451, -0.3150426796961634,
    -0.1911188674736163, -0.06405689286260562, 0.06405689286260562, 0.19111886747361634, 0.3150426796961634,
    0.4337935076260451, 0.5454214713888396, 0.6480936519369755, 0.7401241915785544, 0.820001985973903,
    0.8864155270044011, 0.9382745520027328, 0.9747285559713095, 0.9951872199970213,
])
_GL_W = np.array([
    0.012341229799987334, 0.02853138862893381, 0.044277438817419676, 0.05929858491543666, 0.07334648141108027,
    0.08619016153195322, 0.09761865210411391, 0.10744427011596562, 0.11550566805372561, 0.12167047292780338,
    0.12583745634682839, 0.12793819534675224, 0.12793819534675224, 0.1258374563468283, 0.12167047292780338,
    0.11550566805372561, 0.10744427011596562, 0.09761865210411391, 0.08619016153195322, 0.07334648141108027,
    0.05929858491543666, 0.044277438817419676, 0.02853138862893381, 0.012341229799987334,
])
_GL_X.flags.writeable = False
_GL_W.flags.writeable = False


def _gauss_legendre() -> tuple[np.ndarray, np.ndarray]:
    """The Gauss–Legendre rule of the panels: (:data:`_GL_X`, :data:`_GL_W`)."""
    return _GL_X, _GL_W


def estimate(sol: Any, ps: Any, names: list[str]) -> float:
    """The largest estimated absolute error among ``names`` at the pass's times (see the module docstring)."""
    if not names or ps.t.size == 0:
        return 0.0
    est = _Estimator(sol, ps)
    return float(max(est.of(q) for q in names))


class _Estimator:
    """Each part computed once, on demand."""

    def __init__(self, sol: Any, ps: Any) -> None:
        self.sol, self.ps, self.t = sol, ps, ps.t
        self._memo: dict[str, Any] = {}
        # what depends on the motion only (the start, the quadrature segments), kept with it
        self._motion: dict[str, Any] = sol._mp.setdefault("estimate", {})

    def _get(self, key: str, make):
        if key not in self._memo:
            self._memo[key] = make()
        return self._memo[key]

    def _once(self, key: str, make):
        if key not in self._motion:
            self._motion[key] = make()
        return self._motion[key]

    # --- composition -------------------------------------------------------------------------

    def of(self, q: str) -> float:
        if self.sol.kind == "steady":
            return self._steady(q)
        if q == "u":
            return self.nutation()["u"]
        if q == "u_dot":
            return self.nutation()["u_dot"]
        if q == "theta":
            return self.nutation()["theta"]
        if q == "theta_dot":
            return self.nutation()["theta_dot"]
        if q in ("phi", "psi", "phi_wrapped", "psi_wrapped"):
            return self.angle(q[:3], wrapped=q.endswith("wrapped"))
        if q in ("phi_dot", "psi_dot"):
            return self.rate_check()[q[:3]]
        if q == "R":
            nut = self.nutation()
            s, c = self._half_theta_weights()
            return 2 * (self.angle("sigma") * c + self.angle("delta") * s) + nut["theta"] + 8 * _EPS
        if q == "apex":
            return self.nutation()["theta"] + self._max_sin_theta() * self.angle("phi", wrapped=True) + 8 * _EPS
        if q == "omega":
            nut = self.nutation()
            rates = self.rate_check()
            w = self._omega_scale()
            return (2 * (rates["sigma"] + rates["delta"]) + nut["theta_dot"]
                    + w * (self.angle("sigma") + self.angle("delta") + nut["theta"]) + 8 * _EPS * w)
        raise DerivationError(f"no error estimate for the quantity {q!r}")  # pragma: no cover - internal

    # --- steady motion (a double root of f): constant θ and rates --------------------------------

    def _steady(self, q: str) -> float:
        sol, t = self.sol, self.t
        tmax = float(np.max(np.abs(t)))
        ini = sol.initial
        rate = {k: abs(ini[k + "_dot"]) for k in ("phi", "psi")}
        w = max(math.hypot(math.hypot(ini["phi_dot"], ini["theta_dot"]), ini["psi_dot"]), 1e-300)
        # φ0 + φ̇0·t: the product and the sum rounded, and t's own rounding times the rate
        angle = {k: 4 * float(np.spacing(abs(ini[k]) + rate[k] * tmax)) + 2 * _EPS * rate[k] * tmax
                 for k in ("phi", "psi")}
        if q in ("u", "theta", "u_dot", "theta_dot"):
            return 4 * _EPS * max(1.0, abs(ini["theta"]))
        if q in ("phi", "psi"):
            return angle[q]
        if q in ("phi_wrapped", "psi_wrapped"):
            return 4 * _EPS * math.pi + 2 * _EPS * rate[q[:3]] * tmax
        if q in ("phi_dot", "psi_dot"):
            return 2 * _EPS * rate[q[:3]]
        wrapped = 4 * _EPS * math.pi + 2 * _EPS * max(rate.values()) * tmax
        if q in ("R", "apex"):
            return 4 * wrapped + 8 * _EPS
        return 8 * _EPS * w + w * 4 * wrapped  # omega

    # --- 1. nutation --------------------------------------------------------------------------

    def _differences(self, x: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
        """u - u_k (k = 1, 2, 3) from 1 ∓ u of the samples and 1 ∓ u_k (no cancellation near ±1)."""
        gm, gp = self.sol._mp["gaps_minus"], self.sol._mp["gaps_plus"]
        upper = x <= y
        return [np.where(upper, m - x, y - p) for m, p in zip(gm, gp)]

    def _f_and_slope(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._f_slope_noise(x, y)[:2]

    def _f_slope_noise(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """f (3.73) in its roots, f', and the rounding of f from that of each u − u_k (ulp of 1 ∓ u_k, 1 ∓ u)."""
        beta = self.sol._mp["beta"]
        d1, d2, d3 = self._differences(x, y)
        gm, gp = self.sol._mp["gaps_minus"], self.sol._mp["gaps_plus"]
        upper = x <= y
        nearer = np.where(upper, x, y)  # the smaller of 1 ∓ u
        r = [_EPS * np.maximum(np.where(upper, abs(m), abs(p)), nearer) for m, p in zip(gm, gp)]
        noise = beta * (r[0] * np.abs(d2 * d3) + r[1] * np.abs(d1 * d3) + r[2] * np.abs(d1 * d2))
        return beta * d1 * d2 * d3, beta * (d2 * d3 + d1 * d3 + d1 * d2), noise

    def _kappa(self) -> float:
        return self.sol._kappa.hi + self.sol._kappa.lo

    def nutation(self) -> dict[str, float]:
        return self._get("nutation", self._nutation)

    def _nutation(self) -> dict[str, float]:
        sol, ps = self.sol, self.ps
        kappa, amp = self._kappa(), sol._amp
        sn, cn, dn = ps.jacobi()
        x, y = ps.one_minus_plus_u()
        u_dot = 2 * kappa * amp * sn * cn * dn
        f, slope, f_noise = self._f_slope_noise(x, y)
        residual = np.abs(u_dot * u_dot - f)
        with np.errstate(divide="ignore", invalid="ignore"):
            du = np.where(residual > 0, residual / (np.abs(slope) + 2 * kappa * np.abs(u_dot)), 0.0)
        # u(t) = u1 + (u2 - u1) sn² never leaves [u1, u2]: no residual can mean more than that
        # (next to a double root the differences u - u_k are below their own rounding)
        du = np.minimum(np.nan_to_num(du, nan=np.inf), amp + 4 * _EPS)
        sin_theta = np.sqrt(x * y)
        with np.errstate(divide="ignore", invalid="ignore"):
            dtheta = np.where(du > 0, du / np.maximum(sin_theta, np.sqrt(du)), 0.0)
            theta_rate = np.where(sin_theta > 0, np.abs(u_dot) / sin_theta, 0.0)
        theta_rate_max = max(float(np.max(theta_rate)), 2 * kappa * math.sqrt(amp / 2) if sol._one_minus_u2 == 0.0
                             or sol._one_plus_u1 == 0.0 else 0.0, abs(sol.initial["theta_dot"]))
        # (b) the start: 1 ∓ u(0) against 1 ∓ cos θ0 from the half angle
        start = self._start()
        th0 = sol.initial["theta"]
        x0, y0 = 2 * math.sin(th0 / 2) ** 2, 2 * math.cos(th0 / 2) ** 2
        dx0 = abs(start["x"] - x0) if x0 <= y0 else abs(start["y"] - y0)
        dx0 = max(dx0 - 2 * _EPS * min(x0, y0), 0.0)  # less the rounding of 1 ∓ cos θ0 itself
        f0, slope0 = self._f_and_slope(np.array([x0]), np.array([y0]))
        u_dot0 = math.sin(th0) * abs(sol.initial["theta_dot"])
        tau = 2 * dx0 / (u_dot0 + math.sqrt(u_dot0**2 + abs(float(slope0[0])) * dx0)) if dx0 > 0 else 0.0
        theta_max = float(np.max(2 * np.arctan2(np.sqrt(x), np.sqrt(y))))
        u_dot_max = float(np.max(np.abs(u_dot)))
        # (c) a wrong rate of the phase (κ, or m through the period) is a residual that does not
        # average out: u̇² = (1 + e)² f, e = residual/(2f) away from the turning points, less the
        # residual's own rounding (u̇² and f each to ~4 ulp); its phase error grows like e·|t|
        swing = (u_dot * u_dot >= 0.25 * u_dot_max**2) & (np.abs(f) > 100 * f_noise)
        rate_error = 0.0
        if np.any(swing):
            significant = residual[swing] - 4 * _EPS * (u_dot[swing] ** 2 + np.abs(f[swing])) - 2 * f_noise[swing]
            rate_error = max(float(np.max(significant / (2 * np.abs(f[swing])))), 0.0)
        t_abs = np.abs(self.t)
        drift = rate_error * t_abs  # the time shift the phase has accumulated by each sample
        d_theta = (float(np.max(dtheta + theta_rate * drift)) + theta_rate_max * tau + abs(start["theta"] - th0)
                   + 4 * float(np.spacing(theta_max)) + 4 * _EPS)
        d_u = float(np.max(du + np.abs(u_dot) * drift)) + u_dot_max * tau + 4 * _EPS
        d_theta_dot = 2 * kappa * d_theta + 8 * _EPS * theta_rate_max
        if "theta_dot" in start:
            d_theta_dot += abs(start["theta_dot"] - sol.initial["theta_dot"])
        return {"u": d_u, "u_dot": 2 * kappa * d_u + 8 * _EPS * u_dot_max, "theta": d_theta, "theta_dot": d_theta_dot,
                "time_shift": drift + tau}

    def _start(self) -> dict[str, float]:
        """1 ∓ u, θ, θ̇ at t = 0 by the evaluation's path (one point)."""
        def make():
            p0 = self.sol._at_start
            x, y = p0.one_minus_plus_u()
            out = {"x": float(x[0]), "y": float(y[0]), "theta": float(self.sol._quantity(p0, "theta")[0]),
                   "theta_dot": float(self.sol._quantity(p0, "theta_dot")[0])}
            if not math.isfinite(out["theta_dot"]):
                out["theta_dot"] = math.inf
            return out
        return self._once("start", make)

    def _half_theta_weights(self) -> tuple[float, float]:
        s, c = self.ps.half_theta()
        norm = np.hypot(s, c)
        return float(np.max(np.abs(s) / norm)), float(np.max(np.abs(c) / norm))

    def _max_sin_theta(self) -> float:
        x, y = self.ps.one_minus_plus_u()
        return float(np.max(np.sqrt(x * y)))

    # --- 3. rates -----------------------------------------------------------------------------

    def _derived_rates(self, x: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
        from .exact import _derived_rates

        v = self.sol._mp
        with np.errstate(divide="ignore", invalid="ignore"):
            out = _derived_rates()(float(v["I1"]), float(v["I3"]), v["d_minus"], v["d_plus"], x, y)
        return [np.broadcast_to(np.asarray(r, dtype=float), np.shape(x)) for r in out]

    def rate_check(self) -> dict[str, float]:
        return self._get("rates", self._rate_check)

    def _rate_check(self) -> dict[str, float]:
        """The output rates (3.74)–(3.75) in 1 ∓ u against the partial fractions in sn² the angles are
        integrated from — an independent path whose own rounding (terms ~1/(1 − n₊) cancelling
        near the pole) makes the difference an overestimate there."""
        sol, ps = self.sol, self.ps
        phi_dot, psi_dot, sig_dot, del_dot = ps.derived_rates()
        a, b = sol._angles["phi"], sol._angles["psi"]
        closed = {"phi": ps.rate(a), "psi": ps.rate(b), "sigma": ps.half_rate(a, b, +1), "delta": ps.half_rate(a, b, -1)}
        derived = {"phi": phi_dot, "psi": psi_dot, "sigma": sig_dot, "delta": del_dot}
        out = {}
        for k in closed:
            diff = np.abs(closed[k] - derived[k])
            finite = np.isfinite(diff)
            out[k] = float(np.max(np.where(finite, diff, 0.0))) + 8 * _EPS * float(
                np.max(np.where(finite, np.abs(derived[k]), 0.0)))
        return out

    def _omega_scale(self) -> float:
        ini = self.sol.initial
        return max(math.hypot(math.hypot(ini["phi_dot"], ini["theta_dot"]), ini["psi_dot"]), self._kappa(),
                   abs(float(self.sol._mp["d_minus"])), abs(float(self.sol._mp["d_plus"])))

    # --- 2. angles ----------------------------------------------------------------------------

    def angle(self, which: str, *, wrapped: bool = False) -> float:
        """Estimated error of φ, ψ, σ = (φ + ψ)/2 or δ = (φ - ψ)/2 (continuous, or reduced with ``wrapped``)."""
        check = self._get(f"angle:{which}", lambda: self._angle_check(which))
        return check["wrapped" if wrapped or which in ("sigma", "delta") else "continuous"]

    def _closed_angle(self, ps: Any, which: str) -> np.ndarray:
        """The closed form's φ or ψ (continuous, with its passages) or σ, δ (reduced), at a pass."""
        sol = self.sol
        a, b = sol._angles["phi"], sol._angles["psi"]
        if which in ("phi", "psi"):
            return ps.angle(a if which == "phi" else b, reduced=False) + np.pi * ps.passages()
        return ps.half_angle(a, b, +1 if which == "sigma" else -1)

    def _angle_check(self, which: str) -> dict[str, float]:
        """φ(t_i) − φ0 (or ψ, σ, δ) at the picked samples against F(v(t_i)) − F(v0), F the integral of the
        derived rate over the phase (:meth:`_cumulative`), plus the rounding of what is output."""
        sol, ps = self.sol, self.ps
        if sol._period is None:  # m = 1 exactly (no period): no quadrature in the phase; say so
            return {"continuous": math.inf, "wrapped": math.inf}
        reduced = which in ("sigma", "delta")
        values = self._closed_angle(ps, which).ravel()
        start = {"phi": sol.initial["phi"], "psi": sol.initial["psi"],
                 "sigma": 0.5 * (sol.initial["phi"] + sol.initial["psi"]),
                 "delta": 0.5 * (sol.initial["phi"] - sol.initial["psi"])}[which]
        picks = self._picks()
        q0, d0 = self._once("start_phase", lambda: self._phase_points(sol._at_start))
        q, d = self._get("phase_points", lambda: self._phase_points(ps))
        q, d = q.ravel()[picks], d.ravel()[picks]
        # the start and the picked samples in one call: their segments' rates in one evaluation
        F, size = self._cumulative(which, np.concatenate([np.ravel(q0)[:1], q]), np.concatenate([np.ravel(d0)[:1], d]))
        F0, size0, F, size = F[:1], size[:1], F[1:], size[1:]
        jumps = 0.0
        if which in ("phi", "psi") and (sol._one_minus_u2 == 0.0 or sol._one_plus_u1 == 0.0):
            jumps = np.pi * ps.passages().ravel()[picks]  # φ, ψ turn by π at each exact passage; the rates do not
        closed = values[picks] - start
        quadrature = (F - F0[0]) + jumps
        diff = closed - quadrature
        if reduced:
            diff = (diff + np.pi) % (2 * np.pi) - np.pi
        # rounding of both sides: the values, the quadrature sums
        x, y = ps.one_minus_plus_u()
        # (8 ulp of the larger rather than 4 of the sum: the sum overflows for angles near the double range)
        noise = 8 * np.spacing(np.maximum(np.abs(values[picks]), abs(start))) + 4 * _EPS * (size + size0[0])
        worst = float(np.max(np.abs(diff) + noise)) if len(picks) else 0.0
        # A shift of the time the phase stands for moves the angle by rate × shift, and the
        # quadrature (along the same phase) cannot see it: the shift the nutation checks measured
        # (a wrong phase rate or start), and the rounding of the reduced phase itself, a few ulp of
        # K, i.e. 4ε·K/κ in time — amplified by the rate at each sample (near a pole passage
        # |φ̇| ~ |b − a|/(1 − u2): this is what the planner's 3e-17 × conditioning stood for)
        # (the four rates at the samples, evaluated once for the checks of φ, ψ, σ and δ)
        all_rates = np.abs(self._get("sample_rates", lambda: self._derived_rates(x, y))[self._INDEX[which]])
        all_rates = np.where(np.isfinite(all_rates), all_rates, 0.0)
        shift = self.nutation()["time_shift"] + 4 * _EPS * (sol._period.hi / 2) / self._kappa()
        t_rounding = float(np.max(all_rates * np.broadcast_to(shift, all_rates.shape)))
        ulp_values = 4 * float(np.spacing(float(np.max(np.abs(values))) if values.size else 0.0))
        continuous = worst + t_rounding + ulp_values + 4 * _EPS
        wrapped = worst + t_rounding + 4 * _EPS * math.pi
        return {"continuous": continuous, "wrapped": wrapped if reduced else min(continuous, wrapped)}

    _INDEX = {"phi": 0, "psi": 1, "sigma": 2, "delta": 3}

    def _picks(self) -> list[int]:
        """Flat sample indices whose accumulated angle is checked: the last, a spread, the extremes of u."""
        def make():
            t = self.t.ravel()
            order = np.argsort(np.abs(t), kind="stable")
            idx = {int(order[-1])}
            idx.update(int(order[k]) for k in np.linspace(0, len(order) - 1, _SPREAD + 1).astype(int)[1:])
            x, y = self.ps.one_minus_plus_u()
            idx.update((int(np.argmin(x.ravel())), int(np.argmin(y.ravel()))))
            return sorted(i for i in idx if t[i] != 0.0)
        return self._get("picks", make)

    @staticmethod
    def _phase_points(ps: Any) -> tuple[np.ndarray, np.ndarray]:
        """(q, δ): the phase v = qK + δ of each time of a pass, q an integer (the nearest turning point:
        q even at u1, odd at u2) and δ in [−K/2, K/2] to full relative accuracy (from the pass)."""
        j, _, _ = ps.phase_dd()
        kind, xh, xl = ps.turning()
        return 2 * j + kind, xh + xl

    def _cumulative(self, which: str, q: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(F, F_abs): F(qK + δ) = ∫_0^{qK+δ} rate dv/κ, the derived rate integrated over the phase, and
        the same of |rate| (for the rounding of the sum).

        The phase line is cut into segments [qK − K/2, qK + K/2] around each turning point; one
        period 2K is the segments at q = 0 and 1 (the rates have period 2K in v).  Quadrature in δ,
        the distance to the turning point, keeps the nodes exact next to a spike there (nodes in t
        would be rounded to ulp(t), ~1e-3 of a 1e-13 s spike's width).
        """
        K = self.sol._period.hi / 2
        half = K / 2
        col = self._INDEX[which]
        pieces = []  # per point: [(sign, key)], n
        for qk, dk in zip(q.tolist(), d.tolist()):
            n, parity = divmod(int(qk), 2)
            if parity == 0:
                parts = [(1.0, (0, 0.0, dk))] if dk >= 0 else [(-1.0, (0, dk, 0.0))]
            else:
                parts = [(1.0, (0, 0.0, half)), (1.0, (1, -half, dk))]
            pieces.append((n, parts))
        keys = {(0, -half, half), (1, -half, half)} | {key for _, parts in pieces for _, key in parts}
        seg = self._segments(keys)
        per, per_abs = (seg[(0, -half, half)][i][col] + seg[(1, -half, half)][i][col] for i in (0, 1))
        kappa = self._kappa()
        F = np.array([n * per + sum(sg * seg[key][0][col] for sg, key in parts) for n, parts in pieces]) / kappa
        G = np.array([abs(n) * per_abs + sum(seg[key][1][col] for _, key in parts) for n, parts in pieces]) / kappa
        return F, G

    def _segments(self, keys) -> dict:
        """{(parity, lo, hi): (∫ rates dδ, ∫ |rates| dδ)} for δ in [lo, hi] of the segment around turning
        point ``parity`` (0: u1, 1: u2), all four rates (φ̇, ψ̇, σ̇, δ̇) at once, one evaluation of u for
        every node: Gauss–Legendre panels at most K/4 long, graded geometrically towards δ = 0 by
        the spike width there."""
        from .exact import _Pass

        memo = self._motion.setdefault("segments", {})
        todo = [k for k in keys if k not in memo]
        if todo:
            K = self.sol._period.hi / 2
            xg, wg = _gauss_legendre()
            all_nodes, all_weights, all_parity, owner = [], [], [], []
            stop = 0
            for key_index, (parity, lo, hi) in enumerate(todo):
                if hi <= lo:
                    continue
                width = self._spike_widths()[parity]
                # panels no longer than K' (the imaginary quarter period, where sn, cn, dn have their
                # poles; as m → 1, K grows like ln(4/k') while K' → π/2) nor K/2; graded by 4 from
                # the spike's width up to that length: each graded panel [d, 4d] is 3d long at a
                # distance ≥ d from the spike's poles (Bernstein parameter ≳ 3)
                longest = min(K / 2, self._kprime())
                edges = {lo, hi}
                for sgn in (-1.0, 1.0):
                    d = width
                    for _ in range(_MAX_LEVELS):
                        if d >= longest / 2:
                            break
                        if lo < sgn * d < hi:
                            edges.add(sgn * d)
                        d *= 4
                edges.update(c for c in (0.0,) if lo < c < hi)
                # gaps longer than ``longest`` cut evenly (linspace's ends are the gap's own: only a gap in
                # more than one piece needs it); sorted(set(...)), not np.unique: NumPy 2's unique imports
                # numpy.ma, ~20 ms of a warm run
                e = sorted(edges)
                cuts = set(e)
                for a, b in zip(e[:-1], e[1:]):
                    pieces = math.ceil((b - a) / longest)
                    if pieces > 1:
                        cuts.update(np.linspace(a, b, pieces + 1).tolist())
                e = np.array(sorted(cuts))
                mid, halfw = 0.5 * (e[1:] + e[:-1]), 0.5 * (e[1:] - e[:-1])
                nodes = (mid[:, None] + halfw[:, None] * xg[None, :]).ravel()
                all_nodes.append(nodes)
                all_weights.append((halfw[:, None] * wg[None, :]).ravel())
                all_parity.append(np.full(nodes.shape, parity))
                owner.append((key_index, stop, stop + nodes.size))  # each key's nodes, contiguous
                stop += nodes.size
            out = {k: (np.zeros(4), np.zeros(4)) for k in todo}
            if all_nodes:
                nodes, weights = np.concatenate(all_nodes), np.concatenate(all_weights)
                ps = _Pass(self.sol, np.zeros(nodes.shape))
                ps._cache["turning"] = (np.concatenate(all_parity), nodes, np.zeros(nodes.shape))
                x, y = ps.one_minus_plus_u()
                rates = np.array(self._derived_rates(x, y))
                rates = np.where(np.isfinite(rates), rates, 0.0)
                abs_rates = np.abs(rates)
                # each key's columns as fresh Fortran-ordered copies, the layout a boolean mask's selection
                # has: the products' order of summation (BLAS) follows the operands' layout
                for key_index, start, end in owner:
                    w = weights[start:end].copy()
                    out[todo[key_index]] = (np.asfortranarray(rates[:, start:end]) @ w,
                                            np.asfortranarray(abs_rates[:, start:end]) @ w)
            memo.update(out)
        return memo

    def _peak_rate(self, which: str) -> float:
        """The largest |rate| over the motion: at the turning points (where 1 ∓ u is smallest)."""
        gm, gp = self.sol._mp["gaps_minus"], self.sol._mp["gaps_plus"]
        rates = self._derived_rates(np.array([gm[1], gm[0]]), np.array([gp[1], gp[0]]))[self._INDEX[which]]
        finite = rates[np.isfinite(rates)]
        return float(np.max(np.abs(finite))) if finite.size else 0.0

    def _kprime(self) -> float:
        """K' = K(m1) = π/(2 AGM(1, √m)) (DLMF 19.8.5 for the complementary parameter)."""
        def make():
            a, b = 1.0, math.sqrt(self.sol.m)
            for _ in range(60):
                if abs(a - b) <= 1e-15 * a:
                    break
                a, b = 0.5 * (a + b), math.sqrt(a * b)
            return math.pi / (a + b) if b > 0 else math.inf
        return self._once("kprime", make)

    def _spike_widths(self) -> tuple[float, float]:
        """Widths in phase of the rate's spike at the turning points (at u1 — the bottom side —, at u2).

        Near u2, 1 − u = (1 − u2) + (u2 − u1) m1 δ² + …, so the 1/(1 − u) part of the rate has width
        √((1 − u2)/((u2 − u1) m1)); near u1, 1 + u = (1 + u1) + (u2 − u1) δ²: width √((1 + u1)/(u2 − u1)).
        """
        def make():
            sol = self.sol
            gm, gp = sol._mp["gaps_minus"], sol._mp["gaps_plus"]
            amp = sol._amp
            pole = math.sqrt(gm[1] / (amp * sol.m1)) if sol.m1 > 0 and gm[1] > 0 else math.inf
            bottom = math.sqrt(gp[0] / amp) if gp[0] > 0 else math.inf
            return bottom, pole
        return self._once("spikes", make)


def _wrap(x: float) -> float:
    return (x + math.pi) % (2 * math.pi) - math.pi
