"""The motion in t of a ``lagrangian`` system whose reduction in t has no elliptic closed form but whose orbit along a
cyclic coordinate c has (issue 16): Kepler's problem in polar coordinates, where u = 1/r gives u̇² of degree 6 in t
but Binet's (du/dφ)² = P(u) of degree 2 along φ.

The orbit (:class:`~.closed.ClosedMotion` with ``along=c``) gives, as functions of s = c − c(0): q(s), dq/ds, every
other cyclic coordinate and its ds-rate, and the time itself, t(s) = ∫ ds/ċ(u(s)) (ċ = N(u)/D(u) rational, so
dt/ds = D/N integrates by partial fractions or the Fourier series of :mod:`mechderive.solvers`).  Where ċ keeps one
sign over the motion — no real zero of N (nor of D) on the orbit's range of u, or only one the motion approaches as
t → ±∞ (the hyperbola's asymptote, where u = 1/r = 0) — t(s) is strictly monotone, and

    c(t) = c(0) + s(t),  s(t) the root of t(s) = t,
    q(t) = q(s(t)),  q̇ = (dq/ds)·ċ,  ċ = 1/(dt/ds),  c₂(t) = c₂(s(t)),  ċ₂ = (dc₂/ds)·ċ.

The root is found by :func:`mechderive.solvers.monotone_inverse.invert_monotone` (Newton with dt/ds from the closed
form, safeguarded by a bracket): the bracket and first guess come from a table of t(s) — one period of the orbit
(256 cells; t(s + P_c) = t(s) + Δt, Δt the time per period from the residues) for a periodic orbit, else nodes
approaching the ends of the orbit's domain geometrically (a pole of dt/ds: c → c∞ as t → ∞; an escape of u) — and
the cubic Hermite interpolant of the inverse s(t) on the cell (its slopes ds/dt = ċ at the nodes), so that Newton
starts within ~1e-7 of the root and takes two or three steps.

The outputs at the root (issue 16): s is a double, the root s* of t(s*) = t is not, and after many periods the half
ulp of s, times a rate along c, is many ulp of an output (1000 Kepler orbits: φ ≈ 6300, r, ṙ, φ̇ ~1000 ulp off).  c
is output as c(0) + s, its error that rounding; every other output X is moved to s* to first order,

    X(s*) ≈ X(s) + X'(s)·(s* − s),  s* − s ≈ −ρ/(dt/ds),

ρ = t(s) − t the residual the iteration left (formed without t's own rounding where the integral has a secular part,
:meth:`~mechderive.solvers.quadrature_rational.RationalRate.minus`), X' in closed form (:meth:`TimedOrbit._slopes`:
q' and c₂' are the orbit's columns, and q'', the rates' slopes, from u'' = P'(u)/2 and R'(u)·u').

The error estimate is a bound at every sample, measured on the run (:meth:`TimedOrbit.error_bounds`).  At a sample
the output differs from the exact motion at that t by (i) the doubles' error at the sample's own s = c − c(0), and
(ii) what remains of the distance from s to the exact root s*, |s − s*| ≤ δs = (|ρ| + δt)/|dt/ds|, δt the error of the
residual.  c moves by δs for (ii).  Every other output X was moved by the step −ρ/(dt/ds): its error from (ii) is
|X'|·|step − (s* − s)| (the residual's error δt/|dt/ds|, the second-order term of t, ½|t''|δs²/|dt/ds|, and dt/ds's
own relative error times the step) plus the first-order remainder ½|X''|δs² (X'' bounded by twice the larger mean of
|X''| over a step each side, from the slopes' differences) plus the slope's own rounding times the step, modelled as
the value's one order up.  (i) and δt come from a rounding model per sample, calibrated against 30
digits on the run: an output X at fixed s (q, q̇, ċ, another cyclic coordinate and its rate) is within
k·ε·(|X| + |dX/ds|/κ) of its exact value (the relative rounding of a few operations, and the rounding of the phase
κs + v_s and of u, an error of ~ε/κ in s: modelled per output, not per factor, because q̇ = (dq/ds)/(dt/ds) takes both
factors from the same rounded u, and near Kepler's asymptote their 1e-3 relative errors cancel), an integral within
k·its own first-order rounding bound (the sum of its terms' sizes and sensitivities,
:meth:`~mechderive.solvers.quadrature_rational.RationalRate.rounding`), k the larger of a floor (:data:`K_MODEL`,
:data:`K_SUM`) and :data:`SAFETY` times the largest ratio of the measured error to the model at up to 8 samples (the
last, five by the golden ratio, the slowest and the fastest in c), where every output is evaluated again at 30
digits.  c = c(0) + s is exact in s but for half an ulp.  With the step taken, the residual's error is the leading
term of r, ṙ, φ̇ after many Kepler orbits: at e = 0.9 the periodic part of t(φ) has terms ~a^{3/2} and the residual
is rounded to ~1e-14 there (ṙ within ~80 ulp, not a handful; the step removes only the known part of s* − s).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ...errors import InvalidInputError
from ..base import OutOfReach
from .closed import ClosedMotion, golden_picks

__all__ = ["TimedOrbit", "timed_motion"]

#: cells of the table of t(s) over one period of a periodic orbit
CELLS = 256
#: the floor of the rounding model's factor for an output at fixed s, k·ε·(|X| + |dX/ds|/κ): over 30000 samples of 500
#: random Kepler runs (ellipses to 2000 orbits, hyperbolae to r ~ 1e12) the doubles' error was at most 3.4 of
#: ε·(|X| + |dX/ds|/κ) — 6 leaves a margin of 1.8 where the 30-digit samples miss the worst rounding
K_MODEL = 6.0
#: the floor of the factor on an integral's own rounding bound (measured at most 0.27 of it, same samples)
K_SUM = 1.0
#: the factor on the largest ratio measured at the 30-digit samples (the others' roundings are other draws)
SAFETY = 2.0


def _mp():
    import mpmath

    return mpmath


class TimedOrbit:
    """The motion in t from the orbit along ``along`` (see the module docstring): the same interface as
    :class:`~.closed.ClosedMotion` (``columns``, ``estimate``, ``check_derivatives``, ``describe``, ``summary``,
    ``period``, ``kind``), t being the independent variable again."""

    estimate_kind = ("absolute, in the outputs' units, a bound at every sample: the doubles' error at the sample's c "
                     "from a rounding model calibrated against 30 digits at up to 8 of the times, plus, for c, "
                     "|c − c*| ≤ (|t(c) − t| + the residual's error)·|dc/dt|; the other outputs are moved to c* to "
                     "first order, and bounded by their rate along c times the residual's error·|dc/dt| and the "
                     "second-order remainder")
    #: the estimate bounds every sample (the run's report needs no floor of a column's rounding)
    bounds_every_sample = True

    def __init__(self, system: Any, parameters: dict, initial: dict, along: str, energy_shift: float = 0.0,
                 in_t: str = "") -> None:
        orbit = ClosedMotion(system, parameters, initial, energy_shift, along=along)
        self.orbit = orbit
        self.along = along
        #: why the reduction in t failed (the report says it)
        self.in_t = in_t
        self.system = system
        self.found, self.remaining, self.names = orbit.found, orbit.remaining, orbit.names
        self.values, self.motion, self.shape, self.kind = orbit.values, orbit.motion, orbit.shape, orbit.kind
        self.q0 = orbit.q0
        self.initial = dict(initial)
        #: the other cyclic coordinates, measured along c by the orbit
        self.others = tuple(c for c in orbit.cyclic if c != "t")
        self.cyclic = (along, *self.others)
        self.c0 = float(initial[along])
        rate0 = float(initial[along + "_dot"])
        # u constant (a circular orbit): ċ constant, t = s·(dt/ds) exactly
        motion_steady = orbit.kind == "steady"
        integral = orbit.rate("t")[0]
        self._integral = integral
        self.sigma = float(np.sign(rate0))
        self._check_one_sign(integral)
        lo, hi = -np.inf, np.inf
        if getattr(integral, "singular_times", None) is not None:
            lo, hi = getattr(integral, "singular_times", None)
        if self.motion.escape_times is not None:
            lo, hi = max(lo, self.motion.escape_times[0]), min(hi, self.motion.escape_times[1])
        #: the orbit's domain in s (open): a pole of dt/ds or an escape of u bounds it
        self.domain = (float(lo), float(hi))
        periodic = not motion_steady and np.isfinite(float(orbit.period)) and self.domain == (-np.inf, np.inf) \
            and not self.motion.asymptotic
        self.periodic = periodic
        if periodic:
            #: the orbit's period in s (c's advance per period of q) and the time it takes
            self.period_along = float(orbit.period)
            self.period = abs(orbit.summary("t_per_period"))
        else:
            self.period_along = None
            self.period = np.inf
        self.steady = motion_steady
        self.time_scale = float(self.period) if periodic else float(orbit.time_scale) / abs(rate0)
        self._table = None if motion_steady else self._build_table()
        self._cache: dict = {}
        #: the largest inversion so far (the run's samples, not the self-check's few): iterations, bisections, residual
        self.last_inversion: dict = {}

    # --- the sign of ċ, the table ---------------------------------------------------------------------

    def _check_one_sign(self, integral: Any) -> None:
        """Refuse unless ċ = N(u)/D(u) keeps one sign on the orbit's range of u: a real root of N or D inside it is a
        turn of c (or ċ infinite) — allowed only where the motion approaches it as t → ±∞ (dt/ds has a pole there,
        the integral's ``singular_times`` bound the orbit: c tends to a limit, monotonically)."""
        mp = _mp()
        num, den = self.orbit.rate_coefficients("t")  # dt/ds = num/den: den's zeros are ċ's
        a, b = (mp.mpf(x) for x in self.motion.interval)
        a, b = min(a, b), max(a, b)
        for coeffs, what in ((den, "vanishes"), (num, "is infinite")):
            if len(coeffs) < 2:
                continue
            with mp.workdps(40):
                roots = mp.polyroots(coeffs, maxsteps=400, extraprec=200)
            for r in roots:
                if abs(mp.im(r)) > mp.mpf(10) ** -20 * (1 + abs(r)):
                    continue
                x = mp.re(r)
                if a <= x <= b and not (what == "vanishes" and getattr(integral, "singular_times", None) is not None):
                    raise OutOfReach(f"d{self.along}/dt {what} at u = {float(x):.12g} on the orbit (u in "
                                     f"[{float(a):.6g}, {float(b):.6g}]): {self.along} does not move monotonically, "
                                     f"t({self.along}) has no inverse")

    def _t_and_rate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(t(s), dt/ds) in doubles: the orbit's integral and its rate D/N(u), no checks (s inside the domain)."""
        jac = self.motion.jacobi(s)
        return self._integral(s, jac), self.orbit._rate_values("t", s, jac)

    def _residual_and_rate(self, s: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(t(s) − target, dt/ds): the difference without t's own rounding where the integral forms it
        (:meth:`~mechderive.solvers.quadrature_rational.RationalRate.minus`)."""
        jac = self.motion.jacobi(s)
        minus = getattr(self._integral, "minus", None)
        value = minus(s, target) if minus is not None else self._integral(s, jac) - target
        return value, self.orbit._rate_values("t", s, jac)

    def _t_rounding(self, s: np.ndarray) -> np.ndarray | None:
        """The integral's own rounding bound of t(s) − target at s, or None where it has none (then the residual
        is rounded to ulp(t) and the generic model applies)."""
        rounding = getattr(self._integral, "rounding", None)
        return None if rounding is None or getattr(self._integral, "minus", None) is None else rounding(s)

    def _build_table(self) -> dict:
        """The nodes s_k, σ·t(s_k) (increasing) and ds/d(σt) there; refused if dt/ds changes sign at a node."""
        if self.periodic:
            s = np.linspace(0.0, self.period_along, CELLS + 1)
        else:
            s = np.concatenate([self._ladder(self.domain[0]), [0.0], self._ladder(self.domain[1])])
            s = np.unique(s)
        value, rate = self._t_and_rate(s)
        y, slope = self.sigma * value, self.sigma * rate
        ok = np.isfinite(y) & np.isfinite(slope)
        s, y, slope = s[ok], y[ok], slope[ok]
        if not np.all(slope > 0):
            bad = int(np.argmin(slope > 0))
            raise OutOfReach(f"d{self.along}/dt changes sign on the orbit (dt/d{self.along} = {self.sigma * slope[bad]:.6g}"
                             f" at {self.along} − {self.along}(0) = {s[bad]:.6g}): t({self.along}) has no inverse")
        if not self.periodic:
            # near an end, σt saturates in doubles (t ~ 1/(c∞ − c)): keep the strictly increasing part
            keep = np.concatenate([[True], np.diff(y) > 0])
            s, y, slope = s[keep], y[keep], slope[keep]
        return {"s": s, "y": y, "dsdy": 1.0 / slope}

    def _ladder(self, end: float) -> np.ndarray:
        """Nodes from 0 towards ``end``: a finite end approached by quarter-octaves of the distance to it (t ~ 1/(c∞ − c)
        near a double pole of dt/ds varies by 2^¼ over a cell, where a cubic fits it to ~1e-6), to within 2⁻⁵² of it,
        and uniformly near 0; an infinite end by quarter-octaves from a hundredth of the orbit's scale to 2⁴⁰ of it."""
        if end == 0:
            return np.zeros(0)
        if np.isfinite(end):
            near = end * np.arange(1, 6) / 32.0
            far = end * (1.0 - 2.0 ** -np.arange(0.25, 53.0, 0.25))
            nodes = np.concatenate([near, far])
            return nodes[np.abs(nodes) < abs(end)]
        scale = float(self.orbit.time_scale)
        return np.sign(end) * scale * 2.0 ** np.arange(-7.0, 40.0, 0.25)

    # --- the inverse --------------------------------------------------------------------------------

    def forget(self) -> None:
        """Drop the kept inversion (a benchmark times each call's own iteration)."""
        self._cache = {}

    def inverse(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, ρ): s = c − c(0) at the times t, and the residual ρ = t(s) − t evaluated there (cached per array)."""
        from ...solvers.monotone_inverse import invert_monotone

        t = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(t)):
            # (the double-double phase of an infinite time would recurse without end)
            raise InvalidInputError(f"expected finite times for the orbit solved in t, got {t[~np.isfinite(t)][:3]}")
        key = (t.shape, t.tobytes())
        if key in self._cache:
            return self._cache[key]
        if self.steady:
            # t(s) = s·(dt/ds), dt/ds constant: s = t·ċ, t(s) − t its rounding
            rate = float(self._t_and_rate(np.zeros(1))[1][0])
            s = t / rate
            result = (s, s * rate - t)
            self._cache = {key: result}
            return result
        table = self._table
        X, Y, dXdY = table["s"], table["y"], table["dsdy"]
        y = self.sigma * t
        if self.periodic:
            span = Y[-1] - Y[0]
            turns = np.floor((y - Y[0]) / span)
            y_cell = y - turns * span
            shift = turns * self.period_along
        else:
            if np.any(y < Y[0]) or np.any(y > Y[-1]):
                far = float(t[np.argmax((y < Y[0]) | (y > Y[-1]))])
                end = self.domain[1] if self.sigma * far > 0 else self.domain[0]
                what = ("where its u reaches ∞" if self.motion.escape_times is not None and
                        end in self.motion.escape_times else f"as {self.along} approaches its limit")
                raise OutOfReach(f"t = {far:.12g} is beyond the orbit's reach in doubles: the motion ends {what} "
                                 f"({self.along} − {self.along}(0) → {end:.12g}, t → {self.sigma * Y[-1 if far > 0 else 0]:.6g} "
                                 f"at the last representable {self.along})")
            y_cell, shift = y, np.zeros(t.shape)
        k = np.clip(np.searchsorted(Y, y_cell, side="right") - 1, 0, len(Y) - 2)
        h = Y[k + 1] - Y[k]
        theta = np.clip((y_cell - Y[k]) / h, 0.0, 1.0)
        # the cubic Hermite interpolant of s(σt) on the cell, its slopes ds/d(σt) at both nodes
        guess = ((2 * theta**3 - 3 * theta**2 + 1) * X[k] + (theta**3 - 2 * theta**2 + theta) * h * dXdY[k]
                 + (-2 * theta**3 + 3 * theta**2) * X[k + 1] + (theta**3 - theta**2) * h * dXdY[k + 1])
        # one cell of margin each side: the table's t and the reduction by whole periods are rounded
        lo = X[np.maximum(k - 1, 0)] + shift
        hi = X[np.minimum(k + 2, len(X) - 1)] + shift
        if self.periodic:
            lo = np.where(k == 0, X[-2] - self.period_along + shift, lo)
            hi = np.where(k == len(X) - 2, X[1] + self.period_along + shift, hi)
        start = guess + shift
        rounding = self._t_rounding(start)
        if rounding is not None:
            # t(s) − t formed without t's rounding: the iteration goes on to the double s nearest the root, or until the
            # residual is below an eighth of the integral's own rounding bound (its actual rounding, measured at most
            # 0.27 of the bound, makes further steps noise)
            noise = rounding / 8
        else:
            # t(s) is a sum of terms of the size of the table's times (the periodic part, G(x) − G(x0)): rounded to
            # a few ulp of those even where t itself is small, and to a few ulp of t
            noise = 4 * float(np.spacing(max(abs(Y[0]), abs(Y[-1])) if self.periodic else
                                         max(abs(Y[len(Y) // 2]), 1.0))) + 4 * np.spacing(np.abs(t))
        result = invert_monotone(self._residual_and_rate, t, lo, hi, start, increasing=self.sigma > 0, noise=noise,
                                 differences=True, step_ulps=0.0)
        if t.size >= self.last_inversion.get("samples", 0):
            self.last_inversion = {"samples": int(t.size), "iterations": result.iterations, "bisections": result.bisections,
                                   "unconverged": int(np.count_nonzero(~result.converged)),
                                   "largest_residual": float(np.max(np.abs(result.residual))) if t.size else 0.0}
        out = (result.s, result.residual)
        self._cache = {key: out}  # the last array only (a scene's run asks for the same times twice)
        return out

    # --- the columns ----------------------------------------------------------------------------------

    def _state_names(self) -> list[str]:
        """The state columns in t: every coordinate and its rate."""
        return [self.along, self.along + "_dot", self.remaining, self.remaining + "_dot", *self.others,
                *(c + "_dot" for c in self.others)]

    def _orbit_names(self) -> list[str]:
        r = self.remaining
        return [r, r + "_dot", *self.others, *(c + "_dot" for c in self.others), "t_dot"]

    def _orbit_at(self, s: np.ndarray) -> tuple[dict, tuple]:
        """(the orbit's columns at s, the Jacobi functions there): one evaluation of the Jacobi functions serves the
        columns and their slopes."""
        jac = self.motion.jacobi(s)
        return self.orbit.columns(s, self._orbit_names(), jac=jac), jac

    def _state(self, s: np.ndarray, cols: dict) -> dict:
        """Every column in t at the orbit's s, before the correction to s* (see the module docstring)."""
        with np.errstate(all="ignore"):
            rate = 1.0 / cols["t_dot"]
        r, c = self.remaining, self.along
        out = {c: self.c0 + s, c + "_dot": rate, r: cols[r], r + "_dot": cols[r + "_dot"] * rate}
        for other in self.others:
            out[other], out[other + "_dot"] = cols[other], cols[other + "_dot"] * rate
        return out

    def _slopes(self, s: np.ndarray, cols: dict, jac: tuple) -> dict:
        """{name: d/ds} of every state column but c (whose own is 1), and of dt/ds (``t_dot``: d²t/ds²), in closed
        form at the orbit's s: q' = dq/ds and c₂' = dc₂/ds are the orbit's columns; with T = dt/ds, ċ = 1/T and
        ċ' = −T'ċ²; q̇ = q'ċ gives q̇' = q''ċ + q'ċ', ċ₂ = c₂'ċ gives ċ₂' = c₂''ċ + c₂'ċ' (q'' and the rates' slopes
        T', c₂'' from :meth:`~.closed.ClosedMotion._q_ddot` and :meth:`~.closed.ClosedMotion._rate_slope`)."""
        orbit, r, c = self.orbit, self.remaining, self.along
        zero = np.zeros(s.shape)
        with np.errstate(all="ignore"):
            rate = 1.0 / cols["t_dot"]
            # u constant on a steady orbit: every rate along s is 0 but the cyclic coordinates' own
            t_curve = zero if self.steady else orbit._rate_slope("t", s, jac, cols["t_dot"])
            q_curve = orbit._q_ddot(s, jac, cols[r], cols[r + "_dot"])
            rate_slope = -t_curve * rate * rate
            out = {r: cols[r + "_dot"], r + "_dot": q_curve * rate + cols[r + "_dot"] * rate_slope,
                   c + "_dot": rate_slope, "t_dot": t_curve}
            for other in self.others:
                along = cols[other + "_dot"]
                curve = zero if self.steady else orbit._rate_slope(other, s, jac, along)
                out[other], out[other + "_dot"] = along, curve * rate + along * rate_slope
        return out

    def _step(self, residual: np.ndarray, cols: dict) -> np.ndarray:
        """s* − s to first order, −ρ/(dt/ds): the distance from the double s to the exact root of t(s) = t."""
        with np.errstate(all="ignore"):
            return -residual / cols["t_dot"]

    def columns(self, t: np.ndarray, wanted: Sequence[str]) -> dict:
        """The state columns (each q and q̇) at the times t: every one is computed (the inverse gives them all).  c is
        c(0) + s, the double s the inversion found; every other column X is moved from s to the exact root s* to first
        order, X(s) + (dX/ds)·(s* − s) with s* − s = −ρ/(dt/ds) from the residual ρ (issue 16: after 1000 Kepler
        orbits r, ṙ, φ̇ at s were ~1000 ulp off, the half ulp of s ≈ 6000 times their rate along φ)."""
        s, residual = self.inverse(np.asarray(t, dtype=float))
        cols, jac = self._orbit_at(s)
        out = self._state(s, cols)
        step = self._step(residual, cols)
        for name, slope in self._slopes(s, cols, jac).items():
            if name in out:
                out[name] = out[name] + slope * step
        return out

    # --- the estimate, the self-check ------------------------------------------------------------------

    def estimate(self, t: np.ndarray, wanted: Sequence[str]) -> tuple[float, dict]:
        """The largest bound of the requested columns over the samples, and each column's (see :meth:`error_bounds`)."""
        bounds = self.error_bounds(t, wanted)
        worst = {name: float(np.max(b)) if b.size else 0.0 for name, b in bounds.items()}
        chosen = [worst[n] for n in wanted if n in worst]
        return (max(chosen) if chosen else 0.0), worst

    def _length(self) -> float:
        """The orbit's scale in s, 1/κ (the phase κs + v_s): its rounding, and u's, is an error ~ε/κ in s."""
        mo = self.motion
        if getattr(mo, "elementary", False) and mo.form == "polynomial":
            return float(self.orbit.time_scale)  # u polynomial in s: κ = 1 is a unit, not a scale
        return 1.0 / float(mo.kappa) if not mo.steady else float(self.orbit.time_scale)

    def _steps(self, s: np.ndarray, length: float) -> np.ndarray:
        """Central-difference steps along s: 2⁻¹⁶ of the orbit's scale, at most 2⁻⁸ of the distance to a finite end of
        the domain (near Kepler's asymptote the columns vary on that distance), never below 4 ulp of s."""
        h = np.full(s.shape, 2.0**-16 * length)
        lo, hi = self.domain
        with np.errstate(invalid="ignore"):
            if np.isfinite(hi):
                h = np.minimum(h, 2.0**-8 * (hi - s))
            if np.isfinite(lo):
                h = np.minimum(h, 2.0**-8 * (s - lo))
        return np.maximum(h, 4 * np.spacing(np.abs(s)))

    def error_bounds(self, t: np.ndarray, wanted: Sequence[str] | None = None) -> dict:
        """{column: array}: at each sample a bound of the output's error against the exact motion at that t (see the
        module docstring); raises :class:`OutOfReach` where a bound is not finite (the motion's error is then not
        known).  ``wanted`` is accepted for the interface; every state column is bounded."""
        mp = _mp()
        from ...solvers.quadrature_motion import REFERENCE_DPS

        eps = 2.0**-52
        t = np.asarray(t, dtype=float)
        if not t.size:
            return {name: np.zeros(0) for name in self._state_names()}
        s, residual = self.inverse(t)
        r, c = self.remaining, self.along
        names = self._orbit_names()
        cols, jac = self._orbit_at(s)
        # the outputs at the double s (the rounding model's and the calibration's subject), and each one's rate along
        # s in closed form (c's is 1), with which :meth:`columns` moved it to s*
        here = self._state(s, cols)
        slope = self._slopes(s, cols, jac)
        step = self._step(residual, cols)
        length = self._length()
        outputs = [n for n in self._state_names() if n != c]
        rate_abs = np.abs(cols["t_dot"])

        # the rounding model at fixed s, per output (in its units): generic ε(|X| + |dX/ds|·L [+ an integral's terms'
        # size]), or an integral's own bound
        offset = {other: float(np.median(np.abs(slope[other]))) * length for other in self.others}

        def model(name: str, index: Any = slice(None)) -> tuple[np.ndarray, float]:
            integral = self.orbit.rate(name)[0] if name in self.others else None
            if getattr(integral, "rounding", None) is not None:
                return integral.rounding(s[index]) + eps * np.abs(here[name][index]), K_SUM
            return eps * (np.abs(here[name][index]) + np.abs(slope[name][index]) * length + offset.get(name, 0.0)), \
                K_MODEL

        t_rounding = self._t_rounding(s)
        if self.steady:
            t_model, t_floor = None, K_MODEL
        elif t_rounding is not None:
            t_model, t_floor = t_rounding, K_SUM
        else:
            # the residual of a plain integral: t's own rounding, its rate over the orbit's scale, and the size of its
            # terms (the time over the orbit's scale)
            t_model = eps * (np.abs(t) + (rate_abs + float(np.median(rate_abs))) * length)
            t_floor = K_MODEL
        # --- calibration: every output at fixed s and the residual, against 30 digits at up to 8 samples -----------
        extra = [int(np.argmax(rate_abs)), int(np.argmin(rate_abs))]
        picks = np.unique(np.concatenate([golden_picks(len(t)), extra])).astype(int)
        got = self.orbit.columns(s[picks], names + ["t"])
        refs = self.orbit.reference_values(s[picks], got)
        factors: dict = {}

        def ratio(measured: float, scale: float) -> float:
            return measured / scale if scale > 0 else (np.inf if measured > 0 else 0.0)

        with mp.workdps(REFERENCE_DPS):
            for i, ref in enumerate(refs):
                p = picks[i]
                inverse_rate = 1 / ref["t_dot"]
                want = {c + "_dot": inverse_rate, r: ref[r], r + "_dot": ref[r + "_dot"] * inverse_rate}
                for other in self.others:
                    want[other], want[other + "_dot"] = ref[other], ref[other + "_dot"] * inverse_rate
                for name, value in want.items():
                    measured = float(abs(mp.mpf(float(here[name][p])) - value))
                    scale, _ = model(name, slice(p, p + 1))
                    factors[name] = max(factors.get(name, 0.0), ratio(measured, float(scale[0])))
                # the residual's own error: t(s) − t as formed against 30 digits
                measured = float(abs(mp.mpf(float(residual[p])) - (ref["t"] - mp.mpf(float(t[p])))))
                scale = abs(float(s[p])) * eps * rate_abs[p] if self.steady else float(t_model[p])
                factors["t"] = max(factors.get("t", 0.0), ratio(measured, scale))
        #: the last run's measured ratios of the error to the model at the 30-digit samples, per output and "t"
        self.calibration = dict(factors)
        if self.steady:
            # t(s) = s·(dt/ds): the rate's error (ċ's, relative) times t, and the product's rounding
            relative = max(K_MODEL, SAFETY * factors.get(c + "_dot", 0.0)) * eps
            t_error = np.abs(t) * (relative + eps)
        else:
            t_error = max(t_floor, SAFETY * factors.get("t", 0.0)) * t_model
        # --- the distance to the exact root, the correction's error, and each output's bound ------------------------
        with np.errstate(all="ignore"):
            delta_s = (np.abs(residual) + t_error) / rate_abs
            # sup |X''| over [s − δs, s + δs], the Taylor remainder's: twice the larger mean of |X''| over a step each
            # side (the slopes' differences), the step at least δs (X'' varies far less than 2× over it: at most 2⁻⁸
            # of the distance to a pole of dt/ds, 2⁻¹⁶ of the orbit's scale); t'' = T' from its own slopes likewise
            curve = {n: np.zeros(s.shape) for n in [*outputs, "t_dot"]}
            if not self.steady:
                h = np.maximum(self._steps(s, length), delta_s)
                up, down = s + h, s - h
                plus, minus = self._slopes(up, *self._orbit_at(up)), self._slopes(down, *self._orbit_at(down))
                for n in outputs:
                    curve[n] = 2 * np.maximum(np.abs(plus[n] - slope[n]) / (up - s),
                                              np.abs(slope[n] - minus[n]) / (s - down))
                curve["t_dot"] = 2 * np.maximum.reduce([np.abs(slope["t_dot"]), np.abs(plus["t_dot"]),
                                                        np.abs(minus["t_dot"])])
            # |step − (s* − s)|: 0 = t(s*) − t = ρ + T·(s* − s) + ½t''(ξ)(s* − s)², the step −ρ̂/T̂ taken from the
            # residual as formed (its error t_error) and T = dt/ds at s (its relative error ċ's at fixed s, ċ = 1/T;
            # the division's rounding ε)
            scale_rate, floor_rate = model(c + "_dot")
            k_rate = max(floor_rate, SAFETY * factors.get(c + "_dot", 0.0))
            relative_rate = k_rate * scale_rate / np.abs(here[c + "_dot"])
            step_error = (t_error + 0.5 * curve["t_dot"] * delta_s**2) / rate_abs + (relative_rate + eps) * np.abs(step)
            out = {c: 0.5 * np.spacing(np.abs(here[c])) + delta_s}
            for name in outputs:
                scale, floor = model(name)
                k = max(floor, SAFETY * factors.get(name, 0.0))
                out[name] = (k * scale                                    # X at the double s
                             + np.abs(slope[name]) * step_error           # the step's own error, first order
                             + 0.5 * curve[name] * delta_s**2             # the remainder of the first-order Taylor step
                             # the slope's rounding, modelled as its value's one order up (X' for X, X''·L for X'L):
                             # it enters times |step| ≤ δs, ~ulp(s) of the model's term
                             + k * eps * (np.abs(slope[name]) + curve[name] * length) * np.abs(step)
                             # the product's and the sum's rounding
                             + eps * (np.abs(here[name]) + np.abs(slope[name] * step)))
        for name, values in out.items():
            if not np.all(np.isfinite(values)):
                i = int(np.argmax(~np.isfinite(values)))
                raise OutOfReach(f"the error of {name} is not bounded at t = {t[i]:.12g} (the orbit's columns or their "
                                 f"rates along {c} are not finite there): no estimate, no answer")
        return out

    def check_derivatives(self, t: np.ndarray, names: Sequence[str]) -> str | None:
        """None, or what failed: each requested angle's central difference in t over ±h (h = 10⁻⁴ of the time scale)
        against its rate, at up to 5 of the times — a wrong branch of the inverse is an O(1) mismatch."""
        t = np.asarray(t, dtype=float)
        picks = t[np.unique(np.linspace(0, len(t) - 1, min(len(t), 5)).astype(int))]
        h = 1e-4 * self.time_scale
        angles = [n for n in names if n in (self.remaining, *self.cyclic)]
        if not angles or not picks.size:
            return None
        plus, minus, here = (self.columns(picks + d, angles) for d in (h, -h, 0.0))
        for n in angles:
            diff = (plus[n] - minus[n]) / (2 * h)
            rate = here[n + "_dot"]
            scale = np.max(np.abs(rate)) + abs(float(self.initial[n])) / self.time_scale + 1e-300
            bad = np.abs(diff - rate) > 1e-4 * scale
            if np.any(bad):
                i = int(np.argmax(bad))
                return (f"d{n}/dt from the closed form ({rate[i]:.6g}) disagrees with the difference of {n} "
                        f"({diff[i]:.6g}) at t = {picks[i]:.6g}")
        return None

    # --- the report, the summaries --------------------------------------------------------------------

    def describe(self) -> dict:
        """The orbit's constants (in s = c − c(0): its m, κ, period along c) and how t was inverted, and why."""
        orbit = self.orbit.describe()
        c, r = self.along, self.remaining
        out = {"substitution": orbit["substitution"], "degree": orbit["degree"], "motion": self.kind,
               "along": c, "interval": orbit["interval"], "m": orbit["m"], f"kappa_along_{c}": orbit["kappa"],
               "period": float(self.period) if np.isfinite(self.period) else None,
               f"{c}_per_period": self.period_along,
               "solved_as": (f"the orbit {r}({c}) along {c} ((du/d{c})² = P(u), degree {orbit['degree']}, "
                             f"{orbit['substitution']}) and t({c}) = ∫ d{c}/{c}_dot in closed form, inverted for "
                             f"{c}(t) by a bracketed Newton iteration: d{c}/dt keeps the sign "
                             f"{'+' if self.sigma > 0 else '−'} over the motion"),
               "in_t": self.in_t}
        if self.last_inversion:
            out["inversion"] = dict(self.last_inversion)
        return out

    @property
    def note(self) -> str:
        """The method and why, for the run's report (as ``auto`` says why it integrates): exact in t through the orbit
        along c, because the reduction in t has no closed form."""
        orbit = self.orbit.describe()
        c, r = self.along, self.remaining
        along = " and ".join(f"{q}({c})" for q in (r, *self.others))
        return (f"exact in t through the orbit along {c}: {along} in closed form ({orbit['substitution']}, "
                f"(du/d{c})² of degree {orbit['degree']}) and t({c}) = ∫ d{c}/{c}_dot, inverted for {c}(t) by Newton "
                f"— the reduction in t has no closed form ({self.in_t})")

    def summary(self, name: str) -> float:
        """``<q>_min``, ``<q>_max`` (the orbit's turning points: the same in t), ``<c>_per_period`` (the orbit's period
        in s for c itself; the orbit's advance of another cyclic coordinate)."""
        if name == f"{self.along}_per_period":
            if not self.periodic:
                raise OutOfReach(f"{name}: no period ({self.kind})")
            return self.period_along * self.sigma
        return self.orbit.summary(name)


def timed_motion(system: Any, parameters: dict, initial: dict, energy_shift: float = 0.0,
                 in_t: str = "") -> TimedOrbit:
    """The :class:`TimedOrbit` along the first cyclic coordinate whose orbit has a closed form on which t inverts;
    raises :class:`OutOfReach` with every reason (in t: ``in_t``; along each cyclic coordinate) where none does."""
    reasons = [f"no closed form: {in_t}"]
    model = system.reduced_model()
    for q in model.cyclic_coordinates:
        c = q.func.__name__
        found, why = system.reduction(c)
        if found is None:
            reasons.append(f"along {c}: {why}")
            continue
        if float(initial[c + "_dot"]) == 0:
            reasons.append(f"along {c}: d{c}/dt = 0 at the start (no orbit to measure t along)")
            continue
        try:
            return TimedOrbit(system, parameters, initial, c, energy_shift, in_t)
        except OutOfReach as exc:
            reasons.append(f"along {c}: {exc}")
    raise OutOfReach("; ".join(reasons))
