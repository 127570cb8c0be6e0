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

The error estimate is measured on the run.  At each sample the residual ρᵢ = t(sᵢ) − tᵢ left by the iteration, plus
the closed form's own error in t (doubles against 30 digits at up to six samples), is an error of δtᵢ in time, so of
δsᵢ = δtᵢ·|ċᵢ| in c; each output X moves by |X(sᵢ + δsᵢ) − X(sᵢ)| for it (evaluated, not linearised), and its own
evaluation error at fixed s is measured against a 30-digit evaluation of the same formulas (c = c(0) + s is exact
in s; q̇ = (dq/ds)/(dt/ds) from the 30-digit dq/ds and dt/ds).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..base import OutOfReach
from .closed import ClosedMotion, golden_picks

__all__ = ["TimedOrbit", "timed_motion"]

#: cells of the table of t(s) over one period of a periodic orbit
CELLS = 256


def _mp():
    import mpmath

    return mpmath


class TimedOrbit:
    """The motion in t from the orbit along ``along`` (see the module docstring): the same interface as
    :class:`~.closed.ClosedMotion` (``columns``, ``estimate``, ``check_derivatives``, ``describe``, ``summary``,
    ``period``, ``kind``), t being the independent variable again."""

    estimate_kind = ("absolute, in the outputs' units: at every sample the residual t(c) − t of the inversion plus "
                     "the closed form's error in t, times the rate (each output evaluated over that shift of c), plus "
                     "the doubles against 30 digits of the same formulas at fixed c at up to 6 of the times")

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
        # t(s) is a sum of terms of the size of the table's times (the periodic part, G(x) − G(x0)): rounded to
        # a few ulp of those even where t itself is small
        noise = 4 * float(np.spacing(max(abs(Y[0]), abs(Y[-1])) if self.periodic else max(abs(Y[len(Y) // 2]), 1.0)))
        result = invert_monotone(self._t_and_rate, t, lo, hi, guess + shift, increasing=self.sigma > 0, noise=noise)
        if t.size >= self.last_inversion.get("samples", 0):
            self.last_inversion = {"samples": int(t.size), "iterations": result.iterations, "bisections": result.bisections,
                                   "unconverged": int(np.count_nonzero(~result.converged)),
                                   "largest_residual": float(np.max(np.abs(result.residual))) if t.size else 0.0}
        out = (result.s, result.residual)
        self._cache = {key: out}  # the last array only (a scene's run asks for the same times twice)
        return out

    # --- the columns ----------------------------------------------------------------------------------

    def _orbit_names(self) -> list[str]:
        r = self.remaining
        return [r, r + "_dot", *self.others, *(c + "_dot" for c in self.others), "t_dot"]

    def _state(self, s: np.ndarray, orbit_cols: dict | None = None) -> dict:
        """Every column in t at the orbit's s (see the module docstring)."""
        cols = orbit_cols if orbit_cols is not None else self.orbit.columns(s, self._orbit_names())
        with np.errstate(all="ignore"):
            rate = 1.0 / cols["t_dot"]
        r, c = self.remaining, self.along
        out = {c: self.c0 + s, c + "_dot": rate, r: cols[r], r + "_dot": cols[r + "_dot"] * rate}
        for other in self.others:
            out[other], out[other + "_dot"] = cols[other], cols[other + "_dot"] * rate
        return out

    def columns(self, t: np.ndarray, wanted: Sequence[str]) -> dict:
        """The state columns (each q and q̇) at the times t: every one is computed (the inverse gives them all)."""
        s, _ = self.inverse(np.asarray(t, dtype=float))
        return self._state(s)

    # --- the estimate, the self-check ------------------------------------------------------------------

    def estimate(self, t: np.ndarray, wanted: Sequence[str]) -> tuple[float, dict]:
        """The largest estimated error of the requested columns, and each column's (see the module docstring):
        the evaluation at fixed s against 30 digits at up to six samples, plus |X(s + δs) − X(s)| with
        δs = (|t(s) − t| + the error of t(s))·|ċ| at every sample."""
        mp = _mp()
        t = np.asarray(t, dtype=float)
        s, residual = self.inverse(t)
        here = self._state(s)
        picks = golden_picks(len(t))
        names = self._orbit_names() + ["t"]
        got = self.orbit.columns(s[picks], names)
        refs = self.orbit.reference_values(s[picks], got)
        worst: dict = {}
        t_error = 0.0
        r, c = self.remaining, self.along
        from ...solvers.quadrature_motion import REFERENCE_DPS

        with mp.workdps(REFERENCE_DPS):
            for i, ref in enumerate(refs):
                t_error = max(t_error, abs(float(got["t"][i]) - float(ref["t"])) + 2.0**-52 * abs(float(ref["t"])))
                rate = 1 / ref["t_dot"]
                want = {c: mp.mpf(self.c0) + mp.mpf(float(s[picks[i]])), c + "_dot": rate, r: ref[r],
                        r + "_dot": ref[r + "_dot"] * rate}
                for other in self.others:
                    want[other], want[other + "_dot"] = ref[other], ref[other + "_dot"] * rate
                for name, value in want.items():
                    diff = abs(float(here[name][picks[i]]) - float(value)) + 2.0**-52 * abs(float(value))
                    worst[name] = max(worst.get(name, 0.0), diff)
        # the inversion: an error δt in time is δs = δt·|ċ| in s; each column moves by what it does over δs
        delta_t = np.abs(residual) + t_error
        delta_s = delta_t * np.abs(here[c + "_dot"])
        moved = self._state(s + delta_s)
        for name in worst:
            with np.errstate(invalid="ignore"):
                shift = np.abs(moved[name] - here[name])
            worst[name] += float(np.max(shift)) if shift.size else 0.0
        worst[c] = max(worst[c], float(np.max(delta_s)) if delta_s.size else 0.0)
        chosen = [worst[n] for n in wanted if n in worst]
        return (max(chosen) if chosen else 0.0), worst

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
