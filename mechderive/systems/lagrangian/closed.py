"""The closed form of a ``lagrangian`` system whose reduction is elliptic (issue 16): q(t), q̇(t), each cyclic
coordinate c(t) and ċ(t), found by the toolkit rather than built by hand.

The recipe, each step derived:

1. Routh-reduce by the cyclic coordinates and find u = g(q) with u̇² = P(u), deg P ≤ 4
   (:func:`mechderive.core.quadrature.find_substitution`); ċ = R_c(u), rational
   (:func:`~mechderive.core.quadrature.cyclic_rates`).
2. The constants of this motion — E, the p_c, the parameters — enter P and R_c at 60 digits from the
   start's doubles (taken as exact; the initial values are at t = 0); u(t) = M(sn²(κ t + v_s | m))
   (:func:`mechderive.solvers.quadrature_motion.elliptic_motion`, at 40 digits or more near a steady motion).
3. q from u on the right branch of g⁻¹.  Where the motion reaches a *fold* of g (g'(q) = 0: u = cos q at
   q = 0 or π) q passes through while u turns back, so q is read from the signed distance σ = ±√|u − u_e|
   (sn or cn of the same argument), in which it is smooth: q − q_e = s·asin(σ/√2) for u = cos q
   (1 − cos q = 2 sin²(q/2)).  Through both folds (a rotation) q = q_a + s·am(v), exact for the sine-type
   substitutions (−1 + 2 sn² = cos(π + 2 am)).
4. c(t) = c0 + ∫ R_c(u) dt by partial fractions in w = sn² and Π
   (:func:`~mechderive.solvers.quadrature_motion.rate_integral`); on the motions in elementary functions of t
   (deg P ≤ 1, the quadratic with no real root: :mod:`mechderive.solvers.quadrature_open`) for R_c polynomial in
   u, as a polynomial in t or a sum of exponentials.

The unbounded motions (:mod:`~mechderive.solvers.quadrature_open`, and the cubic's branch u ≥ r3) have no period;
their root of P, where there is one, is the turning point q passes (``<q>_min`` or ``<q>_max``, the other side
unbounded).  Where u reaches ∞ in finite time (``escape_times``) times beyond are refused: the formulas continue
through ∞ there, and u̇² = P(u) — hence the energy check — would not notice.

The error estimate is measured on the run: at the last output time and five more (picked by the golden
ratio, never all on whole periods) every output is evaluated again from the Jacobi functions and Π at 30
digits (mpmath); the largest difference, and never less than the rounding of each column's size, is
reported.  The run checks itself and is refused (:class:`~mechderive.systems.base.OutOfReach`, so
``method = "auto"`` integrates instead, saying why) where its start differs from the scene's, an angle's
central difference disagrees with its rate, or a conserved quantity evaluated on it drifts by more than
1e-9 of its scale — a wrong branch, fold or sign is never a silent answer.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Sequence

import numpy as np

from ..base import OutOfReach

__all__ = ["ClosedMotion", "ExactRun", "closed_motion", "closed_orbit"]


def _mp():
    import mpmath

    return mpmath


def _per_instance(method):
    """Cache ``method(self, name)`` on the instance (an lru_cache on the method would keep every motion alive)."""
    @functools.wraps(method)
    def cached(self, name):
        store = self.__dict__.setdefault("_cached_" + method.__name__, {})
        if name not in store:
            store[name] = method(self, name)
        return store[name]

    return cached


@dataclasses.dataclass
class ExactRun:
    """The closed form's state at the output times, as a trajectory offers it: ``t``, ``y`` (q then q̇, in the
    definition's order) and the conserved quantities evaluated on it (``invariant(name)``)."""

    t: np.ndarray
    y: np.ndarray
    invariant_names: tuple
    values: Any
    component_error: Any = None
    #: the :class:`ClosedMotion` (its summaries reuse it)
    motion: Any = None

    def invariant(self, name: str) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.values[self.invariant_names.index(name)], float), self.t.shape)


class ClosedMotion:
    """The closed form of one motion of a ``lagrangian`` system (see the module docstring)."""

    def __init__(self, system: Any, parameters: dict, initial: dict, energy_shift: float = 0.0,
                 along: str | None = None) -> None:
        import sympy as sp

        from ...core.quadrature import SHAPES
        from ...solvers.quadrature_motion import DPS, EllipticMotionCn, NotElliptic, elliptic_motion

        self.system = system
        found, reason = system.reduction(along)
        if found is None:
            raise OutOfReach(f"no closed form: {reason}")
        #: the independent variable: "t", or the cyclic coordinate an orbit is measured along (then the times
        #: given to :meth:`columns` are that coordinate's advance from its start, and q_dot is dq/dc)
        self.along = along
        self.found = found
        model = system.reduced_model()
        d = system.definition
        self.names = tuple(d.coordinates)
        self.remaining = model.remaining_coordinates[0].func.__name__
        self.cyclic = tuple(c.func.__name__ for c in model.cyclic_coordinates if c.func.__name__ != along)
        if along is not None:
            # along an orbit the time itself is a coordinate of the same kind: dt/dc = 1/ċ(u), rational in u
            self.cyclic = (*self.cyclic, "t")
        self.parameters = dict(parameters)
        self.initial = dict(initial)
        self.shape = SHAPES[found.name]
        mp = _mp()
        # the constants to 20 digits beyond the working precision: near a steady motion the roots of P are close
        # and their distance (the amplitude) needs them (elliptic_motion raises its precision then)
        with mp.workdps(DPS + 20):
            values = self._constants(model, parameters, initial)
            if energy_shift:
                # the period's and turning points' sensitivity to E's rounding (an estimate, not the motion)
                for sym in values:
                    if sym.name == "E":
                        values[sym] = values[sym] + sp.Float(energy_shift, 60)
            self.values = values
            coeffs = [self._number(c) for c in found.polynomial.all_coeffs()]
            q0, qd0 = float(initial[self.remaining]), float(initial[self.remaining + "_dot"])
            g = found.u_of_q
            qsym = next(iter(g.free_symbols))
            u0 = self._number(g.subs(qsym, sp.Float(q0, 60)))
            slope = float(self._number(sp.diff(g, qsym).subs(qsym, sp.Float(q0, 60))))
        if along is not None:
            along_rate = float(initial[along + "_dot"])
            if along_rate == 0:
                raise OutOfReach(f"no orbit along {along}: d{along}/dt = 0 at the start")
            qd0 = qd0 / along_rate  # dq/dc
        direction = int(np.sign(qd0 * slope))
        try:
            motion = elliptic_motion(coeffs, u0, direction)
        except NotElliptic as exc:
            raise OutOfReach(f"the reduction {found.name}, degree {found.degree}, has no closed form here: {exc}") \
                from exc
        self.q0, self.qd0 = q0, qd0
        a, b = motion.interval
        ends = []
        for end, value in (("a", a), ("b", b)):
            if end == "b" and (motion.asymptotic or motion.escape_times is not None):
                # approached, never reached (or beyond ∞, past the escape): not a fold q passes through
                ends.append(None)
                continue
            fold = None if mp.isinf(value) else self.shape.fold_point(float(value), q0)
            with mp.workdps(DPS):  # a root 1e-17 from a fold is a turning point, not the fold
                exact_fold = fold is not None and any(abs(value - mp.mpf(u_e)) <= mp.mpf(10) ** -25
                                                      for u_e, _, _ in self.shape.folds)
            ends.append(end if exact_fold else None)
        folds = [e for e in ends if e]
        if motion.steady:
            folds = []
        elementary = getattr(motion, "elementary", False)
        if folds and (isinstance(motion, EllipticMotionCn) or elementary):
            raise OutOfReach(f"the reduction {found.name} reaches a fold of the substitution on a motion in cn or in "
                             "elementary functions (complex roots of P, or degree ≤ 2 unbounded): not covered")
        if len(folds) == 2:
            if motion.mobius[3] != 0:
                raise OutOfReach(f"a rotation through both folds of {found.name} with a quartic P: not covered")
            self.kind = "rotation"
            self.S = 1.0 if qd0 > 0 else -1.0
            q_a = self.shape.fold_point(float(a), q0)
            with mp.workdps(DPS):
                am_start = self.S * (mp.mpf(q0) - mp.mpf(q_a)) / mp.mpf(self.shape.scale)
                motion = dataclasses.replace(motion, v_start=mp.ellipf(am_start, motion.m), _f={})
            self.q_fold = q_a
        elif len(folds) == 1:
            self.kind = "libration through a fold"
            self.end = folds[0]
            value = float(a if self.end == "a" else b)
            self.q_fold = self.shape.fold_point(value, q0)
        elif motion.steady:
            self.kind = "steady"
        elif motion.asymptotic and np.isfinite(float(b)):
            self.kind = "separatrix: towards an unstable equilibrium"
        elif motion.escape_times is not None:
            self.kind = "unbounded: reaches infinity in finite time"
        elif np.isfinite(float(b)):
            self.kind = "oscillation between turning points"
        elif elementary and motion.asymptotic:
            towards = float(motion.constants[1]) == 0.0  # u − r ∝ e^{−κt}
            self.kind = ("unbounded: from infinity towards an unstable equilibrium, never reached" if towards else
                         "unbounded: away from an unstable equilibrium, to infinity")
        elif elementary:
            self.kind = {"polynomial": "unbounded: uniformly accelerated" if motion.degree == 1 else
                         "unbounded: uniform motion", "exponential": "unbounded: no turning point"}[motion.form]
        else:
            self.kind = "unbounded"
        if found.name == "u = 1/q" and float(min(a, b)) <= 0 <= float(max(a, b)):
            # u = 1/q passes 0: q escapes to ±∞ there (Kepler's hyperbola along φ); past it u has no meaning
            self.kind = "unbounded: q → ∞ where u = 1/q reaches 0"
        self.motion = motion
        #: the value of u at the substitution's other fold (u_e ∓ 2 for the sine-type shapes), if it has one
        self.other_fold = None
        if self.kind == "libration through a fold":
            u_e = float(a if self.end == "a" else b)
            others = [v for v, _, _ in self.shape.folds if abs(v - u_e) > 1e-9 * (1 + abs(v))]
            if self.shape.local == "asin" and others:
                self.other_fold = others[0]
            sigma, sigma_dot = motion.signed_root(self.end, np.zeros(1))
            if abs(sigma[0]) > 1e-150:
                self.eps = float(np.sign((q0 - self.q_fold) * sigma[0]))
            else:
                self.eps = float(np.sign(qd0 * sigma_dot[0])) or 1.0
        # the period of q: twice u's through one fold (q returns after u's second turn), u's otherwise;
        # infinite at m = 1 (a separatrix, a hyperbolic escape)
        self.period = motion.u_period * (2 if self.kind == "libration through a fold" else 1)
        if motion.escape_times is not None:
            # the cubic's branch u ≥ r3 has 2K/κ as the period of its formula, which passes through ∞: no motion repeats
            self.period = _mp().inf
        #: the motion's time scale: its period, or 1/κ where there is none
        self.time_scale = float(self.period) if np.isfinite(float(self.period)) else 1.0 / float(motion.kappa)

    # --- constants --------------------------------------------------------------------------------

    def _number(self, expr: Any) -> Any:
        import sympy as sp

        mp = _mp()
        value = sp.N(expr.xreplace(self.values), mp.mp.dps + 10) if hasattr(expr, "subs") else expr
        return mp.mpf(str(sp.re(value))) if not isinstance(value, (int, float)) else mp.mpf(value)

    def _constants(self, model: Any, parameters: dict, initial: dict) -> dict:
        """{symbol: exact sympy Float}: the parameters, E and each p_c at the start (the doubles taken as exact)."""
        import sympy as sp

        found = self.found
        state = {}
        for q, s, v in zip(model.coordinates, model.positions, model.velocities):
            name = q.func.__name__
            state[s] = sp.Float(float(initial[name]), 60)
            state[v] = sp.Float(float(initial[name + "_dot"]), 60)
        values = {}
        symbols = found.polynomial.free_symbols - {found.variable}
        for q in model.cyclic_coordinates:
            symbols |= {model.momentum_symbols[q]}
        for sym in symbols:
            if sym.name == "E":
                values[sym] = sp.N(model.energy_function.xreplace(state).xreplace(self._par(parameters)), 75)
        for q in model.cyclic_coordinates:
            values[model.momentum_symbols[q]] = sp.N(model.conserved_momenta[q].xreplace(state)
                                                     .xreplace(self._par(parameters)), 75)
        values.update(self._par(parameters))
        return values

    def _par(self, parameters: dict) -> dict:
        import sympy as sp

        syms = self.system.definition.parameter_symbols
        return {s: sp.Float(float(parameters[s.name]), 60) for s in syms if s.name in parameters}

    @_per_instance
    def rate_coefficients(self, name: str) -> tuple[list, list]:
        """ċ = N(u)/D(u) of the cyclic coordinate ``name``: N's and D's coefficients (highest first, 40 digits)."""
        from ...solvers.quadrature_motion import DPS

        entry = self._rates()[name]
        if isinstance(entry, str):
            raise OutOfReach(f"no closed form for {name}: {entry}")
        N, D = entry
        mp = _mp()
        with mp.workdps(DPS):
            return [self._number(c) for c in N.all_coeffs()], [self._number(c) for c in D.all_coeffs()]

    def _rates(self) -> dict:
        """{name: (N, D) or the reason}: ċ = N(u)/D(u) for each cyclic coordinate; along an orbit measured by a cyclic
        coordinate a (Binet's φ), the rates in a instead — dt/da = 1/ȧ = D_a/N_a, dc/da = ċ/ȧ = N_c D_a/(D_c N_a) —
        with the orbit's substitution."""
        if self.along is None:
            return self.system.cyclic_rates()
        if "_orbit_rates" not in self.__dict__:
            from ...core.quadrature import cyclic_rates

            rates = cyclic_rates(self.system.reduced_model(), self.found)
            base = rates[self.along]
            out: dict = {}
            for name, entry in rates.items():
                if name == self.along:
                    continue
                out[name] = base if isinstance(base, str) else entry if isinstance(entry, str) else \
                    (entry[0] * base[1], entry[1] * base[0])
            out["t"] = base if isinstance(base, str) else (base[1], base[0])
            self.__dict__["_orbit_rates"] = out
        return self.__dict__["_orbit_rates"]

    def _start_value(self, name: str) -> float:
        """c(0) of a cyclic output: the scene's initial value, 0 for the time along an orbit (t = 0 at the start)."""
        return 0.0 if name == "t" and self.along is not None else float(self.initial[name])

    @_per_instance
    def rate_poles(self, name: str) -> tuple:
        """(N's coefficients as doubles, D's leading coefficient, D's real roots (working precision), D's other
        factor's coefficients): ċ = N(u) / (lead·Π(u − p_j)·rest(u)), so that u − p_j near a pole is taken from the
        nearer end of the motion (:meth:`~mechderive.solvers.quadrature_motion.EllipticMotion.minus`)."""
        from ...solvers.quadrature_motion import DPS

        num, den = self.rate_coefficients(name)
        mp = _mp()
        with mp.workdps(DPS):
            if len(den) == 1:
                return [float(x) for x in num], float(den[0]), (), [1.0]
            roots = mp.polyroots(den, maxsteps=400, extraprec=6 * DPS)
            tiny = mp.mpf(10) ** (-DPS // 2)
            real = [mp.re(r) for r in roots if abs(mp.im(r)) <= tiny * (1 + abs(r))]
            rest = [mp.mpf(1)]
            for r in roots:
                if abs(mp.im(r)) > tiny * (1 + abs(r)):
                    rest = [x - r * y for x, y in zip(rest + [0], [0] + rest)]
            return ([float(x) for x in num], float(den[0]), tuple(real), [float(mp.re(x)) for x in rest])

    def _rate_values(self, name: str, t: np.ndarray, jac: tuple) -> np.ndarray:
        num, lead, poles, rest = self.rate_poles(name)
        u = self.motion.u(t, jac)
        den = lead * np.polyval(rest, u)
        for p in poles:
            den = den * self.motion.minus(p, t, jac)
        with np.errstate(all="ignore"):
            return np.polyval(num, u) / den

    @_per_instance
    def rate(self, name: str) -> tuple:
        """(∫ ċ dt as a :class:`~mechderive.solvers.quadrature_motion.RateIntegral`, N, D as doubles), built on
        first request: a scene asking for θ alone never builds φ's partial fractions."""
        from ...solvers.quadrature_motion import NotElliptic, rate_integral

        num, den = self.rate_coefficients(name)
        try:
            integral = rate_integral(self.motion, num, den)
        except NotElliptic as exc:
            raise OutOfReach(f"no closed form for {name}: {exc}") from exc
        return integral, [float(x) for x in num], [float(x) for x in den]

    def describe(self) -> dict:
        """The closed form's constants for the report: substitution, degree, the motion's kind, m, κ, the period."""
        mo = self.motion
        kind = self.kind if not mo.asymptotic or self.kind.startswith(("separatrix", "unbounded")) else \
            f"{self.kind}, on the separatrix (m = 1)"
        elementary = getattr(mo, "elementary", False)
        out = {"substitution": self.found.name, "degree": self.found.degree, "motion": kind,
               "interval": [float(x) for x in mo.interval], "m": None if elementary else float(mo.m),
               "kappa": None if elementary and mo.form == "polynomial" else float(mo.kappa),
               "period": float(self.period) if np.isfinite(float(self.period)) else None}
        if mo.escape_times is not None:
            out["escape_times"] = list(mo.escape_times)
        return out

    def summary(self, name: str) -> float:
        """``<q>_min``, ``<q>_max`` (the turning points of q; the fold's mirror image for a libration through a
        fold) or ``<c>_per_period`` (c's advance over one period of q)."""
        if name.endswith("_per_period"):
            if getattr(self.motion, "elementary", False) or self.motion.escape_times is not None or \
                    self.kind.startswith("unbounded"):
                raise OutOfReach(f"{name}: no period ({self.kind})")
            integral, _, _ = self.rate(name[: -len("_per_period")])
            return float(integral.advance * (2 if self.kind == "libration through a fold" else 1))
        if self.kind == "rotation" or self.kind.startswith("unbounded: q"):
            raise OutOfReach(f"{name}: q is not bounded on this motion ({self.kind})")
        a, b = (float(x) for x in self.motion.interval)
        if self.kind.startswith("unbounded"):
            return self._unbounded_summary(name, a, b)
        if self.kind == "libration through a fold":
            other = a if self.end == "b" else b
            reach = abs(float(self.shape.inverse(np.array(other), self.q0)) - self.q_fold)
            if self.shape.folds and self.shape.fold_point(other, self.q0) is not None:
                reach = float(self.shape.scale * np.pi / 2)  # both ends folds: handled as a rotation
            ends = (self.q_fold - reach, self.q_fold + reach)
        else:
            ends = tuple(sorted(float(self.shape.inverse(np.array(x), self.q0)) for x in (a, b)))
        return ends[0] if name.endswith("_min") else ends[1]

    def _unbounded_summary(self, name: str, a: float, b: float) -> float:
        """``<q>_min`` / ``<q>_max`` of a motion from the turning point a (a root of P; none where a = −∞) out to
        u = ±∞: the turning point's q is the bound on its side (reached in the motion's past or future, at
        u̇ = 0), and the other side has none."""
        if not np.isfinite(a) or a == b:
            raise OutOfReach(f"{name}: q is not bounded on this motion ({self.kind}; u has no turning point)")
        q_turn = float(self.shape.inverse(np.array(a), self.q0))
        # the side of a the motion lies on: u0's, or from a start on a itself where P > 0, the sign of P'(a) (a simple
        # root) — not (b − a)'s: the hyperbolic quadratic's u ≤ r1 branch is listed (r1, ∞), ∞ being reached via −∞
        u0 = float(self.motion.u(np.zeros(1))[0])
        if u0 != a:
            u_side = np.sign(u0 - a)
        else:
            c = [float(x) for x in self.motion.coefficients]
            u_side = np.sign(np.polyval(np.polyder(c), a))
        # q moves away from q_turn on the side where u does, through g'(q)
        with np.errstate(all="ignore"):
            side = u_side * np.sign(float(self.shape.dg(np.array(q_turn))))
        bounded = "_min" if side > 0 else "_max"
        if not name.endswith(bounded):
            bound = "the equilibrium" if self.motion.asymptotic else "its turning point"  # approached, not reached
            raise OutOfReach(f"{name}: q is not bounded on this side ({self.kind}, from {bound} "
                             f"{self.remaining} = {q_turn:.12g})")
        return q_turn

    # --- evaluation ---------------------------------------------------------------------------------

    def _q(self, t: np.ndarray, jac: tuple) -> tuple[np.ndarray, np.ndarray]:
        """(q, q̇) in doubles."""
        mo, shape = self.motion, self.shape
        if self.kind == "steady":
            return np.full(t.shape, self.q0), np.zeros(t.shape)
        if self.kind == "rotation":
            am = mo.amplitude(t)
            return (self.q_fold + self.S * shape.scale * am,
                    self.S * shape.scale * float(mo.kappa) * jac[2])
        if self.kind == "libration through a fold":
            sigma, sigma_dot = mo.signed_root(self.end, t, jac)
            _, f, df = self._fold_local(sigma, t, jac)
            # on a separatrix, far along, u − u_o and σ̇ both underflow (e^{-2κt}, κt ≳ 350): q̇ is below the
            # smallest double there, not ∞ · 0
            with np.errstate(invalid="ignore"):
                rate = np.where(sigma_dot == 0.0, 0.0, df * sigma_dot)
            return (self.q_fold + self.eps * shape.scale * f, self.eps * shape.scale * rate / np.sqrt(2.0))
        u = mo.u(t, jac)
        if self.kind.startswith("unbounded") and not self.kind.startswith("unbounded: q"):
            # an unbounded motion crossing a fold value of g that is not its turning point: there g'(q) = 0 while
            # u̇ ≠ 0, so q̇ = u̇/g'(q) is infinite — a collapse (u = x² reaching 0 under V = −k/x²); past it g⁻¹
            # has no branch to follow (q = √u would stick at 0)
            u_start = float(mo.u(np.zeros(1))[0])
            for u_e, _, _ in shape.folds:
                past = np.sign(u - u_e) == -np.sign(u_start - u_e)
                if u_start != u_e and np.any(past):
                    raise OutOfReach(f"{self.remaining} reaches the fold of {self.found.name} at u = {u_e:g} with u̇ ≠ 0 "
                                     f"(d{self.remaining}/dt infinite: a collapse) before "
                                     f"{'t' if self.along is None else self.along} = {float(np.asarray(t)[past][0]):.6g}")
        if self.kind.startswith("unbounded: q"):
            past = np.sign(u) != np.sign(float(self.motion.u_mp(0.0)))
            if np.any(past):
                raise OutOfReach(f"{self.remaining} escapes to infinity (u = 1/{self.remaining} reaches 0) before "
                                 f"{'t' if self.along is None else self.along} = {float(np.asarray(t)[past][0]):.6g}")
        q = shape.inverse(u, self.q0)
        with np.errstate(all="ignore"):
            qd = mo.u_dot(t, jac) / shape.dg(q)
        return q, qd

    def _fold_local(self, sigma: np.ndarray, t: np.ndarray, jac: tuple) -> tuple:
        """(x, f(x), f'(x)) at x = σ/√2 for a motion through a fold (see the module docstring, step 3)."""
        mo, shape = self.motion, self.shape
        x = sigma / np.sqrt(2.0)
        if shape.local == "asin":
            with np.errstate(divide="ignore"):  # x = ±1 at the other fold: replaced below
                f, df = np.arcsin(np.clip(x, -1.0, 1.0)), 1.0 / np.sqrt(np.maximum(1.0 - x * x, 0.0))
            if self.other_fold is not None:
                # near the other fold (|u − u_o| = 2(1 − x²), |u_e − u_o| = 2) take 1 − x² from u − u_o at the
                # nearer end of the motion: a separatrix approaches it exponentially, where 1 − x² from x would
                # round to 0 (θ = π exactly, θ̇ = NaN)
                with np.errstate(all="ignore"):
                    rest = np.abs(mo.minus(self.other_fold, t, jac)) / 2.0
                    far = x * x > 0.5
                    f = np.where(far, np.sign(x) * (np.pi / 2 - np.arcsin(np.sqrt(rest))), f)
                    df = np.where(far, 1.0 / np.sqrt(rest), df)
        elif shape.local == "asinh":
            f, df = np.arcsinh(x), 1.0 / np.sqrt(1.0 + x * x)
        else:
            f, df = x, np.ones_like(x)
        return x, f, df

    def _q_ddot(self, t: np.ndarray, jac: tuple, q: np.ndarray, q_dot: np.ndarray) -> np.ndarray:
        """q̈ = d²q/dτ² (τ = t, or c − c(0) along an orbit) in doubles, from q and q̇ at the same τ (:meth:`_q`).  From
        u̇² = P(u), ü = P'(u)/2 on every motion; then per kind:

        - on g⁻¹'s branch, u = g(q): ü = g''(q) q̇² + g'(q) q̈, so q̈ = (P'(u)/2 − g''(q) q̇²)/g'(q) (g'' from the
          substitution itself; g' ≠ 0 there: a motion reaching a fold is read from σ below, or refused);
        - a rotation, q = q_a + S·scale·am(v), q̇ = S·scale·κ dn: q̈ = −S·scale·κ² m sn cn (dn' = −m sn cn);
        - through a fold e, q = q_e + ε·scale·f(x), x = σ/√2, σ² = |u − e|: with P(u) = (u − e) P₁(u), σ̇² = ±P₁(u)/4,
          so σ̈ = P₁'(u) σ/4 (finite at the fold, where the first form is 0/0), and
          q̈ = ε·scale·(f''(x) σ̇²/2 + f'(x) σ̈/√2), f'' = x f'³ (asin), −x f'³ (asinh), 0 (identity);
        - steady: 0."""
        mo, shape = self.motion, self.shape
        if self.kind == "steady":
            return np.zeros(np.shape(t))
        if self.kind == "rotation":
            sn, cn, _, _, _ = jac
            return -self.S * shape.scale * float(mo.kappa) ** 2 * float(mo.m) * sn * cn
        if self.kind == "libration through a fold":
            sigma, sigma_dot = mo.signed_root(self.end, t, jac)
            u = mo.u(t, jac)
            sigma_ddot = np.polyval(self._p1_slope, u) * sigma / 4.0
            x, _, df = self._fold_local(sigma, t, jac)
            with np.errstate(all="ignore"):
                ddf = {"asin": x * df**3, "asinh": -x * df**3}.get(shape.local, np.zeros_like(x))
                return self.eps * shape.scale * (ddf * sigma_dot**2 / 2.0 + df * sigma_ddot / np.sqrt(2.0))
        u = mo.u(t, jac)
        p_slope = np.polyder([float(c) for c in mo.coefficients])
        with np.errstate(all="ignore"):
            return (np.polyval(p_slope, u) / 2.0 - self._d2g(q) * q_dot**2) / shape.dg(q)

    @functools.cached_property
    def _d2g(self) -> Any:
        """g''(q) in doubles (NumPy), from the substitution's g by SymPy."""
        import sympy as sp

        g = self.found.u_of_q
        qs = next(iter(g.free_symbols))
        return sp.lambdify(qs, sp.diff(g, qs, 2), "numpy")  # a constant (u = q²) broadcasts as a scalar

    @functools.cached_property
    def _p1_slope(self) -> np.ndarray:
        """P₁' in doubles, P(u) = (u − e) P₁(u) at the fold's end e (synthetic division at the working precision)."""
        from ...solvers.quadrature_motion import DPS

        mp = _mp()
        with mp.workdps(DPS):
            e = self.motion.interval[0 if self.end == "a" else 1]
            quotient = [mp.mpf(0)]
            for c in self.motion.coefficients[:-1]:
                quotient.append(mp.mpf(c) + e * quotient[-1])
            p1 = quotient[1:]
            return np.polyder([float(c) for c in p1]) if len(p1) > 1 else np.zeros(1)

    def _rate_slope(self, name: str, t: np.ndarray, jac: tuple, value: np.ndarray) -> np.ndarray:
        """d/dτ of the cyclic rate ``name``, R = N(u)/D(u) (``value`` = R at τ, :meth:`_rate_values`):
        Ṙ = u̇·(N'(u)/D(u) − R·D'(u)/D(u)), D'/D = rest'/rest + Σ 1/(u − p_j) with u − p_j from the nearer end of the
        motion as in R itself (Kepler's dt/dφ = 1/(ℓu²) near the asymptote u → 0 keeps its digits)."""
        num, lead, poles, rest = self.rate_poles(name)
        mo = self.motion
        u, u_dot = mo.u(t, jac), mo.u_dot(t, jac)
        log_slope = np.polyval(np.polyder(rest), u) / np.polyval(rest, u) if len(rest) > 1 else np.zeros(u.shape)
        distance = {}
        for p in poles:
            if p not in distance:
                distance[p] = mo.minus(p, t, jac)
            log_slope = log_slope + 1.0 / distance[p]
        with np.errstate(all="ignore"):
            plain = value * 0.0
            if len(num) > 1:
                den = lead * np.polyval(rest, u)
                for p in poles:
                    den = den * distance[p]
                plain = np.polyval(np.polyder(num), u) / den
            return u_dot * (plain - value * log_slope)

    def columns(self, t: np.ndarray, wanted: Sequence[str], jac: tuple | None = None) -> dict:
        """The requested state columns (q, q_dot of every coordinate) at the times ``t`` (``jac``: the motion's Jacobi
        functions there, if the caller has them)."""
        t = np.asarray(t, dtype=float)
        escape = self.motion.escape_times
        if escape is not None and t.size and not (escape[0] < np.min(t) and np.max(t) < escape[1]):
            # u = ±∞ at the escape: past it the formula continues through ∞ (u̇² = P(u) still holds, the sign of u̇
            # turned), which is no motion — refused, as a blow-up is for integration
            raise OutOfReach(f"{self.remaining} reaches infinity at t = {escape[1]:.12g} (and, backwards, at "
                             f"{escape[0]:.12g}): u̇² = P(u) blows up in finite time, the closed form stops there")
        jac = self.motion.jacobi(t) if jac is None else jac
        out: dict = {}
        r = self.remaining
        if r in wanted or r + "_dot" in wanted or any(c + "_dot" in wanted for c in self.cyclic):
            out[r], out[r + "_dot"] = self._q(t, jac)
        for c in self.cyclic:
            if c in wanted:
                integral, _, _ = self.rate(c)
                self._within_singular_times(c, integral, t)
                out[c] = self._start_value(c) + integral(t, jac)
            if c + "_dot" in wanted:
                out[c + "_dot"] = self._rate_values(c, t, jac)
        return out

    def _within_singular_times(self, name: str, integral: Any, t: np.ndarray) -> None:
        """Refuse times at or past a pole of the rate that the motion reaches (the integral diverges there: dt/dφ =
        m/(ℓu²) of Kepler's hyperbola where u = 1/r reaches 0)."""
        bounds = getattr(integral, "singular_times", None)
        if bounds is None or not t.size:
            return
        lo, hi = bounds
        if not (lo < np.min(t) and np.max(t) < hi):
            var = "t" if self.along is None else self.along
            raise OutOfReach(f"{name}: its rate has a pole the motion reaches at {var} = {hi:.12g} (and, backwards, at "
                             f"{lo:.12g}): the integral diverges there, the closed form stops before it")

    def check_derivatives(self, t: np.ndarray, names: Sequence[str]) -> str | None:
        """None, or what failed: at up to 5 of the times, each requested angle's central difference over
        ±h (h = 10⁻⁴ of the period) against its rate from the closed form (q̇ from the Jacobi functions'
        derivatives, ċ = R_c(u)).  A wrong branch, fold or sign is an O(1) mismatch; the difference's own
        truncation, h²/6 times the third derivative, is ~10⁻⁸ of the rate, far below the tolerance 10⁻⁴."""
        t = np.asarray(t, dtype=float)
        picks = t[np.unique(np.linspace(0, len(t) - 1, min(len(t), 5)).astype(int))]
        h = 1e-4 * self.time_scale
        if getattr(self.motion, "form", None) == "polynomial" and np.ptp(t) > 0:
            # u = u0 + u̇0 t + (c1/4) t² has no time scale of its own (its κ = 1 is a unit): resolve the outputs' span
            # (x = √u of an inverse-square repulsion over 1 ms has its curvature there, not over seconds)
            h = min(h, 1e-4 * float(np.ptp(t)))
        singular = [getattr(self.rate(c)[0], "singular_times", None) for c in self.cyclic if c in names]
        for lo, hi in (x for x in singular if x is not None):
            # near a pole of a rate the motion reaches (Kepler's hyperbola along φ: dt/dφ ~ (φ∞ − φ)⁻²), as near an
            # escape below: the step a thousandth of the distance to it
            h = min(h, 1e-3 * min(hi - float(np.max(picks)), float(np.min(picks)) - lo))
        escape = self.motion.escape_times
        if escape is not None:
            # near a blow-up u ~ (t₊ − t)⁻²: the truncation is ~ (h/(t₊ − t))² of the rate, kept at ~10⁻⁶ (the
            # rounding, ulp(u)/h, stays ~10⁻¹³ of it)
            h = min(h, 1e-3 * min(escape[1] - float(np.max(picks)), float(np.min(picks)) - escape[0]))
        angles = [n for n in names if n in (self.remaining, *self.cyclic)]
        if not angles:
            return None
        wanted = [*angles, *(n + "_dot" for n in angles)]
        plus, minus, here = (self.columns(picks + s, wanted) for s in (h, -h, 0.0))
        for n in angles:
            diff = (plus[n] - minus[n]) / (2 * h)
            rate = here[n + "_dot"]
            scale = np.max(np.abs(rate)) + abs(float(self.q0)) / self.time_scale + 1e-300
            bad = np.abs(diff - rate) > 1e-4 * scale
            if np.any(bad):
                i = int(np.argmax(bad))
                var = "t" if self.along is None else self.along
                return (f"d{n}/d{var} from the closed form ({rate[i]:.6g}) disagrees with the difference of {n} "
                        f"({diff[i]:.6g}) at {var} = {picks[i]:.6g}")
        return None

    # --- the estimate ----------------------------------------------------------------------------

    def estimate(self, t: np.ndarray, wanted: Sequence[str]) -> tuple[float, dict]:
        """The largest difference between the doubles and a 30-digit evaluation of the same formulas at up to 6
        of the times (the last included), over the requested coordinates; and each one's."""
        t = np.asarray(t, dtype=float)
        ts = t[golden_picks(len(t))]
        got = self.columns(ts, wanted)
        worst: dict = {}
        for i, ref in enumerate(self.reference_values(ts, got)):
            for name, value in ref.items():
                diff = abs(float(got[name][i]) - float(value)) + 2.0**-52 * abs(float(value))
                worst[name] = max(worst.get(name, 0.0), diff)
        chosen = [worst[n] for n in wanted if n in worst]
        return (max(chosen) if chosen else 0.0), worst

    def reference_values(self, ts: np.ndarray, got: dict) -> list[dict]:
        """For each time of ``ts``, {name: 30-digit value (mpmath)} of the columns in ``got`` (this motion's doubles
        at ``ts``, which pick the branch of q the Newton steps refine): the Jacobi functions and Π at 30 digits."""
        mp = _mp()
        from ...solvers.quadrature_motion import REFERENCE_DPS as DPS

        mo = self.motion
        out = []
        with mp.workdps(DPS):
            for i, ti in enumerate(ts):
                if getattr(mo, "elementary", False):  # polynomial or exponential in t: no Jacobi functions
                    v = sn = cn = dn = None
                    u, u_dot = mo.mp_state(float(ti))
                else:
                    v = mo.kappa * mp.mpf(float(ti)) + mo.v_start
                    sn, cn, dn = (mp.ellipfun(f, v, m=mo.m) for f in ("sn", "cn", "dn"))
                    u, u_dot = mo.mp_u(sn, cn, dn), None
                ref: dict = {}
                r = self.remaining
                if r in got:
                    ref[r], ref[r + "_dot"] = self._q_mp(v, sn, cn, dn, u, float(got[r][i]), u_dot)
                for c in self.cyclic:
                    if c in got:
                        integral, _, _ = self.rate(c)
                        ref[c] = mp.mpf(self._start_value(c)) + integral.value_mp(float(ti))
                    if c + "_dot" in got:
                        num, den = self.rate_coefficients(c)
                        ref[c + "_dot"] = mp.polyval(num, u) / mp.polyval(den, u)
                out.append({name: value for name, value in ref.items() if name in got})
        return out

    @functools.cached_property
    def _g_mp(self) -> tuple:
        """g and g' as mpmath functions."""
        import sympy as sp

        g = self.found.u_of_q
        qs = next(iter(g.free_symbols))
        return sp.lambdify(qs, g, "mpmath"), sp.lambdify(qs, sp.diff(g, qs), "mpmath")

    def _q_mp(self, v, sn, cn, dn, u, q_double: float, u_dot: Any = None) -> tuple:
        mp = _mp()
        from ...solvers.quadrature_motion import _am_mp

        mo, shape = self.motion, self.shape
        kap = mo.kappa
        if self.kind == "steady":
            return mp.mpf(self.q0), mp.mpf(0)
        if self.kind == "rotation":
            return (mp.mpf(self.q_fold) + self.S * shape.scale * _am_mp(v, mo.m),
                    self.S * shape.scale * kap * dn)
        if self.kind == "libration through a fold":
            A, B, C, D = mo.mobius
            det = B * C - A * D
            den = mo.mp_den(sn, cn)
            if self.end == "a":
                rho = mp.sqrt(abs(det / C) / abs(den))
                sig = sn * rho
                sig_dot = kap * cn * dn * rho + sn * (-rho * D / (2 * den)) * 2 * kap * sn * cn * dn
            else:
                rho = mp.sqrt(abs(det / (C + D)) / abs(den))
                sig = cn * rho
                sig_dot = -kap * sn * dn * rho + cn * (-rho * D / (2 * den)) * 2 * kap * sn * cn * dn
            x = sig / mp.sqrt(2)
            if shape.local == "asin":
                if self.other_fold is not None and x * x > mp.mpf(1) / 2:
                    # 1 − x² = |u − u_o|/2 from the nearer end, as in the doubles (at 30 digits it too rounds to 0
                    # on a separatrix late enough)
                    b = mo.interval[1]
                    near_b = not mp.isinf(b) and abs(mp.mpf(self.other_fold) - b) <= mp.mpf(10) ** -25
                    rest = abs(det * cn * cn / ((C + D) * den) if near_b else u - mp.mpf(self.other_fold)) / 2
                    f, df = mp.sign(x) * (mp.pi / 2 - mp.asin(mp.sqrt(rest))), 1 / mp.sqrt(rest)
                else:
                    f, df = mp.asin(x), 1 / mp.sqrt(1 - x * x)
            elif shape.local == "asinh":
                f, df = mp.asinh(x), 1 / mp.sqrt(1 + x * x)
            else:
                f, df = x, mp.mpf(1)
            return (mp.mpf(self.q_fold) + self.eps * shape.scale * f,
                    self.eps * shape.scale * df * sig_dot / mp.sqrt(2))
        # away from folds g' ≠ 0: Newton steps from the double q on its branch, to the working precision (not two
        # steps: where u = 1/q nears 0, Kepler's hyperbola at r ~ 1e12, the double q is off by 1e-3 and two steps
        # leave 1e-12 — a reference error the estimate would take for the doubles')
        gl, dgl = self._g_mp
        q = mp.mpf(q_double)
        for _ in range(40):
            step = (gl(q) - u) / dgl(q)
            q = q - step
            if abs(step) <= mp.eps * 16 * abs(q):
                break
        return q, (mo.mp_u_dot(sn, cn, dn) if u_dot is None else u_dot) / dgl(q)


def golden_picks(n: int) -> np.ndarray:
    """The indices of up to 6 of n samples an estimate re-evaluates: the last and five by the golden ratio's multiples
    (equally spaced picks can all fall on whole periods, where a libration started at its fold is ~0 and its rounding
    invisible)."""
    golden = (np.arange(1, 6) * 0.6180339887498949) % 1.0
    return np.unique(np.concatenate([(golden * (n - 1)).astype(int), [n - 1]]))


def closed_orbit(system: Any, along: str, parameters: dict, initial: dict) -> ClosedMotion:
    """The orbit q(c) along the cyclic coordinate ``along`` (Binet's u = 1/r for a central force, where the motion
    in t has no elliptic closed form): a :class:`ClosedMotion` whose :meth:`~ClosedMotion.columns` take c − c(0)
    in place of t."""
    return ClosedMotion(system, parameters, initial, along=along)


def closed_motion(system: Any, parameters: dict, initial: dict, energy_shift: float = 0.0) -> Any:
    """The :class:`ClosedMotion` of ``system`` from this start (E moved by ``energy_shift`` for a sensitivity); where
    the reduction in t has no closed form, the motion in t from an orbit along a cyclic coordinate
    (:class:`~.timed.TimedOrbit`: Kepler's problem); raises :class:`OutOfReach` with the reasons where neither
    applies."""
    found, reason = system.reduction()
    if found is None and system.has_reduction():
        from .timed import timed_motion

        return timed_motion(system, parameters, initial, energy_shift, in_t=reason)
    return ClosedMotion(system, parameters, initial, energy_shift)


# --- the solution as formulas (``mechderive derive SCENE closed_form_…``) --------------------------------

def solution_formulas(system: Any) -> dict:
    """{name: (lhs, value, meaning)}: the closed form as formulas in the roots of P (symbols u_a, u_b, u_c, …),
    the amplitude χ (sin²χ = sn²(κ(t − t₀)|m)) and the constants — ``u`` (u(χ)), ``m``, ``kappa``, ``t`` (t − t₀
    as F(χ|m)/κ) and, for each cyclic coordinate c, ``c`` (c − c₀ by partial fractions and Π).

    The labels: u moves between the adjacent roots u_a and u_b (χ = 0 at u_a), u_c is the next root of P past
    u_b (and u_d the one after, for a quartic) — any such labelling of a motion's roots gives the same motion.
    Raises :class:`OutOfReach` with the reason where the system has no reduction.
    """
    import sympy as sp

    found, reason = system.reduction()
    if found is None:
        raise OutOfReach(f"no closed form: {reason}")
    u = found.variable
    P = found.polynomial
    deg = found.degree
    if deg <= 1:
        return _polynomial_formulas(system, found)
    chi, chi0 = sp.Symbol("chi", real=True), sp.Symbol("chi_0", real=True)
    ua, ub, uc, ud = sp.symbols("u_a u_b u_c u_d", real=True)
    lead = P.LC()
    w = sp.sin(chi) ** 2
    where = ("u_a, u_b: the roots of P(u) the motion lies between (χ = 0 at u_a); u_c: the next root past u_b"
             + (", u_d the one after" if deg == 4 else ""))
    if deg == 2:
        m, kappa2, u_of = sp.Integer(0), -lead / 4, ua + (ub - ua) * w
    elif deg == 3:
        m, kappa2, u_of = (ub - ua) / (uc - ua), lead * (uc - ua) / 4, ua + (ub - ua) * w
    else:
        m = (ub - ua) * (ud - uc) / ((ud - ub) * (uc - ua))
        kappa2 = -lead * (uc - ua) * (ud - ub) / 4
        u_of = (ua * (ud - ub) + ud * (ub - ua) * w) / ((ud - ub) + (ub - ua) * w)
    kappa = sp.sqrt(kappa2)
    out = {
        "u": (sp.Symbol(str(u)), u_of, f"u = {found.name[4:]} along the motion, as a function of the amplitude χ; "
              + where),
        "m": (sp.Symbol("k") ** 2, m, "the parameter m = k² of the Jacobi functions: the cross-ratio of the roots"),
        "kappa": (sp.Symbol("kappa"), kappa, "the rate κ of the Jacobi argument v = κ (t − t₀)"),
        "t": (sp.Symbol("t") - sp.Symbol("t_0"), (sp.elliptic_f(chi, m) - sp.elliptic_f(chi0, m)) / kappa,
              "the time from the amplitude χ₀ to χ (v = F(χ|m), sin χ = sn v)"),
    }
    if deg == 4:
        return out
    for name, entry in system.cyclic_rates().items():
        if isinstance(entry, str):
            continue
        N, D = entry
        quotient, rest = sp.div(N, D)
        if quotient.degree() > 0:
            continue
        poles = sp.roots(D.as_expr(), u)
        if sum(poles.values()) != D.degree() or any(k > 1 for k in poles.values()):
            continue
        dD = D.as_expr().diff(u)
        total = quotient.as_expr() * (sp.elliptic_f(chi, m) - sp.elliptic_f(chi0, m))
        for p in poles:
            residue = sp.factor(sp.cancel((rest.as_expr() / dD).subs(u, p)))
            n = (ub - ua) / (p - ua)
            total += residue / (ua - p) * (sp.elliptic_pi(n, chi, m) - sp.elliptic_pi(n, chi0, m))
        c = sp.Symbol(name)
        out[name] = (c - sp.Symbol(f"{name}_0"), total / kappa,
                     f"d{name}/dt = {sp.sstr(sp.factor(N.as_expr() / D.as_expr()))} in partial fractions over its "
                     f"poles in u, integrated with Π(n; χ|m), n = (u_b − u_a)/(u_pole − u_a)")
    return out


def _polynomial_formulas(system: Any, found: Any) -> dict:
    """{name: (lhs, value, meaning)} for deg P ≤ 1: u = u₀ + u̇₀ (t − t₀) + (c₁/4)(t − t₀)² (ü = P'(u)/2 = c₁/2), and
    each cyclic coordinate whose rate is a polynomial in u, c − c₀ = ∫ R(u) dt in t; no Jacobi functions (``m``,
    ``kappa`` and ``t`` do not apply)."""
    import sympy as sp

    u, P = found.variable, found.polynomial
    tau = sp.Symbol("t") - sp.Symbol("t_0")
    s = sp.Symbol("s", real=True)
    u0, v0 = sp.Symbol("u_0", real=True), sp.Symbol("udot_0", real=True)
    c1 = P.as_expr().diff(u)  # a constant: P is linear
    u_of_t = u0 + v0 * tau + c1 / 4 * tau**2
    out = {"u": (sp.Symbol(str(u)), u_of_t,
                 f"u = {found.name[4:]} in uniform (deg P = 0) or uniformly accelerated (deg P = 1) motion: ü = P'(u)/2; "
                 "u_0 and udot_0 = ±√P(u_0) at t_0 (no Jacobi functions: m, κ do not apply)")}
    for name, entry in system.cyclic_rates().items():
        if isinstance(entry, str) or entry[1].degree() > 0:
            continue
        N, D = entry
        rate = (N.as_expr() / D.as_expr()).subs(u, u_of_t.subs(tau, s))
        c = sp.Symbol(name)
        out[name] = (c - sp.Symbol(f"{name}_0"), sp.expand(sp.integrate(rate, (s, 0, tau))),
                     f"d{name}/dt = {sp.sstr(N.as_expr() / D.as_expr())}, a polynomial in u, integrated in t")
    return out

