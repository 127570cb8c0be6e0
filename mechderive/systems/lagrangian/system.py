"""``system = "lagrangian"``: any holonomic system given by its Lagrangian, derived, compiled, run and checked.

A scene names the coordinates and writes L with ``<q>_dot`` for the velocities, parameters from
``[parameters]`` and, optionally, the time ``t``::

    system = "lagrangian"
    coordinates = ["theta", "phi"]
    lagrangian = "m*l**2/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + m*g*l*cos(theta)"
    [initial]            # every q and q_dot
    [output.expressions] # optional outputs: name = formula of q, q_dot, t and the parameters
    x = "l*sin(theta)*cos(phi)"

The outputs are each ``q`` and ``q_dot``, ``energy`` (the Jacobi integral h = q̇·∂L/∂q̇ − L, the
energy when L = T − V; conserved and its drift reported when L does not depend on t), ``p_<q>``
for each cyclic coordinate (conserved, drift reported), and the expressions.  The equations of
motion are derived (:mod:`.model`) and integrated by the one driver (:mod:`mechderive.solvers.driver`:
DOP853 compiled to C where a compiler exists, t carried as a state when L depends on it), rerun
tighter until the measured global error meets ``rtol``.

:data:`SYSTEM` is the registered family: its :meth:`~LagrangianFamily.configure` returns the
concrete :class:`LagrangianSystem` of a scene's definition (cached by a hash of its text; the
compiled code's names carry that hash).  From a program: :func:`from_lagrangian`.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from ...errors import InvalidInputError
from ..base import Derivation, Key, OutOfReach, Quantity, Solved, System

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from ...core.drift import Drift
    from ...scenes.schema import Scene
    from .definition import Definition
    from .model import LagrangianEquations

__all__ = ["SYSTEM", "LagrangianSystem", "LagrangianFamily", "from_lagrangian", "EXAMPLE_SCENE", "EXAMPLE_DEFINITION"]

EXAMPLE_SCENE = '''\
# The spherical pendulum from its Lagrangian (theta from the downward vertical).
system = "lagrangian"
coordinates = ["theta", "phi"]
lagrangian = "m*l**2/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + m*g*l*cos(theta)"
rtol = 1e-10
[parameters]
m = 1.0
l = 1.0
g = 9.81
[initial]
theta = 1.0
phi = 0.0
theta_dot = 0.0
phi_dot = 2.0
[time]
t_end = 10.0
samples = 1001
[output]
quantities = ["theta", "phi", "theta_dot", "phi_dot", "energy", "p_phi", "x"]
[output.expressions]
x = "l*sin(theta)*cos(phi)"
'''

#: the definition of :data:`EXAMPLE_SCENE` (its keys as :meth:`LagrangianFamily.configure` gets them)
EXAMPLE_DEFINITION = {
    "coordinates": ["theta", "phi"],
    "lagrangian": "m*l**2/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + m*g*l*cos(theta)",
    "output.expressions": {"x": "l*sin(theta)*cos(phi)"},
}

_SUMMARY = "any holonomic system from its Lagrangian L(q, q_dot, t): derived, compiled, integrated"


class LagrangianSystem(System):
    """The concrete system of one :class:`~.definition.Definition` (see the module docstring)."""

    summary = _SUMMARY
    section = ""
    extra_keys = ("output.expressions",)
    #: "exact": the closed form the toolkit finds itself (:mod:`.closed`) where L reduces to an elliptic
    #: quadrature; ``auto`` takes it when it applies to the scene's motion, else integrates and says why
    methods = ("exact", "integrate")
    #: a sweep's points per chunk: each integrated point is milliseconds of C (:mod:`.batch`)
    batch_chunk = 100

    def __init__(self, definition: "Definition", name: str = "lagrangian") -> None:
        self.name = name  # type: ignore[misc]  # an instance's own name (a program's system)
        self.definition = definition
        d = definition
        self.parameters = tuple(Key(p, "", "a parameter of the Lagrangian") for p in d.parameters)
        self.initial = (tuple(Key(q, "", f"coordinate {q} at t = 0") for q in d.coordinates)
                        + tuple(Key(q + "_dot", "", f"velocity d{q}/dt at t = 0") for q in d.coordinates))
        eq = self.equations
        self.quantities = (
            tuple(Quantity(q, "", f"coordinate {q}") for q in d.coordinates)
            + tuple(Quantity(q + "_dot", "", f"velocity d{q}/dt") for q in d.coordinates)
            + (Quantity("energy", "", "Jacobi integral h = Σ q̇ ∂L/∂q̇ − L"
                        + ("" if d.uses_time else " (conserved)")),)
            + tuple(Quantity(f"p_{q}", "", f"momentum ∂L/∂{q}_dot of the cyclic coordinate {q} (conserved)")
                    for q in eq.cyclic)
            + tuple(Quantity(n, "", f"output expression {n}") for n, _ in d.expressions))
        from ..summaries import REDUCED_PERIOD, invariant_quantities

        reduced: tuple = ()
        remaining = [q for q in d.coordinates if q not in eq.cyclic]
        if len(remaining) == 1:
            q = remaining[0]
            reduced = (Quantity(f"{q}_min", "", f"smallest {q} of the motion (closed form: a turning point, from "
                                "the roots of P(u)); none for a rotation or where L does not reduce"),
                       Quantity(f"{q}_max", "", f"largest {q} of the motion (closed form, as {q}_min)"),
                       *(Quantity(f"{c}_per_period", "", f"advance of the cyclic coordinate {c} over one period of "
                                  f"the reduced motion (closed form: complete Π integrals)") for c in eq.cyclic))
        self.summaries = (REDUCED_PERIOD,) + reduced + invariant_quantities(
            {n: ("", "Jacobi integral h" if n == "energy" else f"momentum of the cyclic coordinate {n[2:]}", "")
             for n in eq.conserved_names})

    @property
    def equations(self) -> "LagrangianEquations":
        from .model import equations

        return equations(self.definition)

    def configure(self, definition: Mapping[str, Any]) -> "LagrangianSystem":
        """Itself; with ``[output.expressions]``, the same system with those outputs added."""
        definition = dict(definition)
        table = definition.pop("output.expressions", None)
        if definition:
            raise InvalidInputError(f"scene key {sorted(definition)[0]}: system {self.name!r} takes no such key "
                                    "(its Lagrangian is fixed)")
        if not table:
            return self
        from .definition import with_expressions

        return _cached(with_expressions(self.definition, table), self.name)

    # --- the scene's values ----------------------------------------------------------------------

    def check_parameters(self, given: Mapping[str, Any], *, strict: bool = True) -> dict[str, Any]:
        """Every parameter of L and the expressions, a finite number; no other key (see the module docstring)."""
        from .definition import RESERVED

        d = self.definition
        names = set(d.coordinates) | {q + "_dot" for q in d.coordinates}
        unused = [k for k in given if k not in d.parameters]
        for p in d.parameters:
            if p not in given:
                raise InvalidInputError(self._unknown_symbol(p, unused))
        for key in given:
            where = f"scene key [parameters].{key}"
            if key in RESERVED:
                raise InvalidInputError(f"{where}: expected a parameter name that is not {RESERVED[key]}, got "
                                        f"{key!r} (name clash)")
            if key in names:
                raise InvalidInputError(f"{where}: expected a parameter, got the name of a coordinate or velocity "
                                        f"(name clash: its value goes in [initial])")
            if key not in d.parameters:
                used = ", ".join(d.parameters) or "none"
                raise InvalidInputError(f"{where}: unknown key; expected the parameters the Lagrangian and the "
                                        f"expressions use ({used})")
        return {p: _number(f"[parameters].{p}", given[p]) for p in d.parameters}

    def _unknown_symbol(self, name: str, unused: Sequence[str]) -> str:
        from .definition import parameter_symbol

        d = self.definition
        key = "lagrangian"
        if parameter_symbol(name) not in d.lagrangian.free_symbols:
            key = next((f"[output.expressions].{n}" for n, e in d.expressions if parameter_symbol(name) in
                        e.free_symbols), key)
        coords = ", ".join(d.coordinates)
        vels = ", ".join(q + "_dot" for q in d.coordinates)
        given = f"; [parameters] has {', '.join(unused)}, which nothing uses" if unused else ""
        return (f"scene key {key}: unknown symbol {name!r}: expected a coordinate ({coords}), a velocity ({vels}), "
                f"t, or a parameter given in [parameters] (add {name} = <value> there{given})")

    def check_initial(self, given: Mapping[str, Any], parameters: Mapping[str, Any]) -> dict[str, Any]:
        """Every q and q_dot, finite; the mass matrix regular at that state (else the keys it depends on)."""
        keys = [k.name for k in self.initial]
        for key in given:
            if key not in keys:
                raise InvalidInputError(f"scene key [initial].{key}: unknown key; expected {', '.join(keys)}")
        for key in keys:
            if key not in given:
                raise InvalidInputError(f"scene key [initial].{key}: missing; expected a value for every coordinate "
                                        f"and velocity: {', '.join(keys)}")
        values = {k: _number(f"[initial].{k}", given[k]) for k in keys}
        self._check_regular(dict(parameters), values)
        return values

    def _check_regular(self, parameters: dict, initial: dict) -> None:
        import numpy as np

        d, eq = self.definition, self.equations
        p = [parameters[n] for n in d.dynamics_parameters]
        q = [initial[n] for n in d.coordinates]
        v = [initial[n + "_dot"] for n in d.coordinates]
        M = eq.mass_at(p, q, v, 0.0)
        problem = None
        if not np.all(np.isfinite(M)):
            problem = "not finite"
        else:
            cond = np.linalg.cond(M)
            if not cond <= eq_limit():
                problem = f"singular (condition number {cond:.3g} > {eq_limit():.0e})"
            elif eq.solve_kind == "elimination":
                with np.errstate(all="ignore"):
                    pivots = np.abs(np.array(eq.pivot_function()(*p, *q, *v, 0.0), dtype=float))
                smallest = float(np.min(pivots)) / float(np.max(np.abs(M)))
                if not smallest >= 1.0 / eq_limit():
                    problem = (f"eliminated with too small a pivot ({smallest:.3g} of the largest entry: the compiled "
                               "elimination follows the coordinates' order; list them in another order)")
        if problem is None:
            return
        free = {s.name for s in eq.mass_matrix.free_symbols}
        keys = ([f"[parameters].{n}" for n in d.parameters if n in free]
                + [f"[initial].{n}" for n in d.coordinates if n in free]
                + [f"[initial].{n}_dot" for n in d.coordinates if n + "_dot" in free])
        where = ("scene keys " + ", ".join(keys)) if len(keys) > 1 else (f"scene key {keys[0]}" if keys
                                                                          else "scene table [initial]")
        shown = ", ".join(f"{k.split('.')[-1]} = {(parameters | initial)[k.split('.')[-1]]:g}" for k in keys)
        raise InvalidInputError(f"{where}: expected a mass matrix ∂²L/∂q̇∂q̇ that is invertible at the initial "
                                f"state, got one that is {problem} at {shown or 'this state'} (singular mass matrix)")

    # --- solving -----------------------------------------------------------------------------

    def solve(self, scene: "Scene", method: str, t: "np.ndarray") -> Solved:
        """The closed form (``method = "exact"``, :mod:`.closed`; raises
        :class:`~mechderive.systems.base.OutOfReach` with the reason where there is none), or integrate from the
        scene's initial state; only the requested expressions are evaluated."""
        if method == "exact":
            return self._exact(scene, t)
        from ...solvers.driver import integrate, integrate_to_rtol

        y0, p, p_all = self.integration_start(scene, t)
        wanted = tuple(scene.quantities)
        term = self.equations.term

        def run(tol: float) -> Any:
            return integrate(term, y0, t, p, rtol=tol)

        def estimate(tr: Any) -> float | None:
            return self._error_estimate(tr, wanted, p, p_all)

        traj, attempts = integrate_to_rtol(run, estimate, scene.rtol)
        return self.integrated(traj, attempts, wanted, p_all)

    def integration_start(self, scene: "Scene", t: "np.ndarray") -> tuple[list, list, list]:
        """(y0 = q, q̇[, t0], the dynamics' parameter values, every parameter's value) of ``scene``'s integration."""
        d = self.definition
        p = [scene.parameters[n] for n in d.dynamics_parameters]
        p_all = [scene.parameters[n] for n in d.parameters]
        y0 = ([scene.initial[q] for q in d.coordinates] + [scene.initial[q + "_dot"] for q in d.coordinates]
              + ([float(t[0])] if d.uses_time else []))
        return y0, p, p_all

    def integrated(self, traj: Any, attempts: list, wanted: tuple[str, ...], p_all: Sequence[float]) -> Solved:
        """The :class:`Solved` of an integration's last run ``traj`` (one per attempt in ``attempts``)."""
        d, eq = self.definition, self.equations
        columns = self._columns(traj, wanted, p_all)
        info = {
            "error_estimate": attempts[-1]["error_estimate"],
            "error_estimate_kind": (f"{traj.error_estimate_kind}, absolute, in the outputs' units (energy, p_<q> "
                                    "and expressions by propagating each state component's distance)"),
            "backend": traj.backend,
            "acceleration_solve": {"symbolic": "symbolic (M⁻¹b solved and simplified by SymPy)",
                                   "elimination": "compiled elimination of the numeric M and b at each step"}[
                                       eq.solve_kind],
            "cyclic_coordinates": list(eq.cyclic),
            "energy_conserved": not d.uses_time,
            "n_evaluations": traj.n_evaluations,
            "n_steps": traj.n_steps,
            "attempts": attempts,
            "definition": d.digest,
        }
        return Solved({q: columns[q] for q in wanted}, info, traj)

    def _exact(self, scene: "Scene", t: "np.ndarray") -> Solved:
        """The closed form's columns and its measured estimate (doubles against 30 digits at sampled times).

        The conserved quantities are evaluated on the closed form's state (they need q, q̇ and each ċ = R_c(u),
        not the cyclic angles, so no Π is built for them): the report's drift is the closed form's own residual.
        """
        import numpy as np

        from .closed import ExactRun, closed_motion

        d, eq = self.definition, self.equations
        motion = closed_motion(self, dict(scene.parameters), dict(scene.initial))
        wanted = tuple(scene.quantities)
        expr_names = [e for e, _ in d.expressions]
        needs_angles = any(w in expr_names for w in wanted)
        state_wanted = [*(q for q in d.coordinates if q in wanted or needs_angles or q == motion.remaining),
                        *(q + "_dot" for q in d.coordinates)]
        # the scene's initial values are at t = 0 whatever its output times (t_start, times)
        cols = motion.columns(t, state_wanted)
        try:
            estimate, per_column = motion.estimate(t, [w for w in state_wanted if w in wanted or needs_angles])
        except (ArithmeticError, ValueError) as exc:  # the 30-digit reference itself failed (a 0 or ∞ there)
            raise OutOfReach(f"the closed form's 30-digit reference could not be evaluated on this motion "
                             f"({type(exc).__name__}: {exc or 'no detail'}): its error is not measured") from None
        # never below the rounding of each column's own size (the sampled times may all sit where it is small) —
        # unless the motion bounds every sample itself (its bounds hold each sample's own rounding)
        if not getattr(motion, "bounds_every_sample", False):
            for name in per_column:
                per_column[name] = max(per_column[name], 4 * 2.0**-52 * float(np.max(np.abs(cols[name]))))
        estimate = max([per_column[n] for n in per_column if n in wanted] + [estimate])
        names = [*d.coordinates, *(q + "_dot" for q in d.coordinates)]
        # a cyclic angle nobody asked for stays at its start: the invariants do not depend on it
        y = np.column_stack([np.broadcast_to(cols[n] if n in cols else float(scene.initial[n]), t.shape)
                             for n in names] + ([t] if d.uses_time else []))
        p = [scene.parameters[n] for n in d.dynamics_parameters]
        run = ExactRun(t, y, eq.term.invariant_names, eq.term.invariant_function()(*p, *y.T), motion=motion)
        # the closed form checks itself: its start against the scene's, its angles against its rates, its
        # invariants against their start
        failed = motion.check_derivatives(t, [n for n in names if n in cols])
        start = motion.columns(np.zeros(1), [n for n in names if n in cols])
        for name, value in start.items():
            given = float(scene.initial[name])
            if not abs(value[0] - given) <= 1e-9 * max(1.0, abs(given), float(np.max(np.abs(cols[name])))):
                failed = failed or f"{name} starts at {value[0]:.12g}, not at the scene's {given:.12g}"
        for name in eq.conserved_names:
            values, scale = run.invariant(name), float(np.max(np.abs(run.invariant(f"scale_{name}"))))
            moved = float(np.max(np.abs(values - values[0])))
            if not moved <= 1e-9 * scale:
                failed = failed or f"{name} drifts by {moved:.3g} (of {scale:.3g}) on it"
        if failed:
            raise OutOfReach(f"the closed form ({motion.found.name}, {motion.kind}) failed its own check: {failed}")
        if scene.method == "auto" and not estimate <= scene.rtol * max(1.0, _largest(cols, wanted)):
            # ill-conditioned here (e.g. a rate's pole just outside the motion): integration can do better
            raise OutOfReach(f"the closed form's estimate {estimate:.2g} exceeds rtol {scene.rtol:g} (ill-conditioned "
                             f"for this motion)")
        out = {k: np.ascontiguousarray(cols[k], dtype=float) for k in wanted if k in cols}
        for q in wanted:
            if q in run.invariant_names:
                out[q] = run.invariant(q).copy()
        if needs_angles:
            vals = self._expressions([scene.parameters[n] for n in d.parameters], y, t)
            out.update({e: v for e, v in zip(expr_names, vals) if e in wanted})
        info = {
            "error_estimate": estimate,
            "error_estimate_kind": getattr(motion, "estimate_kind", (
                "absolute, in the outputs' units: the doubles against an evaluation of the same closed form at 30 "
                "digits at up to 6 of the times (the last included)")),
            "closed_form": motion.describe(),
            **({"note": motion.note} if getattr(motion, "note", None) else {}),
            "per_column_estimate": per_column,
            "cyclic_coordinates": list(eq.cyclic),
            "energy_conserved": True,
            "definition": d.digest,
        }
        return Solved({q: out[q] for q in wanted}, info, run)

    def _columns(self, traj: Any, wanted: Sequence[str], p_all: Sequence[float]) -> dict:
        import numpy as np

        d = self.definition
        n = len(d.coordinates)
        cols: dict[str, Any] = {}
        for i, q in enumerate(d.coordinates):
            cols[q], cols[q + "_dot"] = traj.y[:, i], traj.y[:, n + i]
        for name in traj.invariant_names:
            if not name.startswith("scale_"):
                cols[name] = traj.invariant(name)
        expr_names = [e for e, _ in d.expressions]
        if any(w in expr_names for w in wanted):
            vals = self._expressions(p_all, traj.y, traj.t)
            cols.update({e: v for e, v in zip(expr_names, vals)})
        return {k: np.ascontiguousarray(v, dtype=float) for k, v in cols.items() if k in wanted}

    def _expressions(self, p: Sequence[float], y: "np.ndarray", t: "np.ndarray") -> list:
        import numpy as np

        n = len(self.definition.coordinates)
        with np.errstate(all="ignore"):
            vals = self.equations.expression_function(self.definition)(*p, *y[:, :2 * n].T, t)
        return [np.broadcast_to(np.asarray(v, dtype=float), t.shape) for v in vals]

    def _error_estimate(self, traj: Any, wanted: Sequence[str], p: Sequence[float],
                        p_all: Sequence[float]) -> float | None:
        """The largest estimated error of the requested outputs: the state's distance to the tighter rerun,
        and, for a function f of the state, Σ_i |f(y + δ_i e_i) − f(y)| with δ_i component i's distance."""
        import numpy as np

        if traj.component_error is None:
            return None
        d = self.definition
        n = len(d.coordinates)
        state_names = [*d.coordinates, *(q + "_dot" for q in d.coordinates)]
        err = traj.component_error
        worst = max((float(err[i]) for i, q in enumerate(state_names) if q in wanted), default=0.0)
        invariants = [q for q in wanted if q in traj.invariant_names]
        expr_names = [e for e, _ in d.expressions]
        expressions = [q for q in wanted if q in expr_names]
        if not invariants and not expressions:
            return worst
        inv_fn = self.equations.term.invariant_function()
        t = traj.t

        def outputs(y: "np.ndarray") -> np.ndarray:
            rows = []
            if invariants:
                with np.errstate(all="ignore"):
                    vals = inv_fn(*p, *y.T)
                rows += [np.broadcast_to(np.asarray(vals[traj.invariant_names.index(q)], float), t.shape)
                         for q in invariants]
            if expressions:
                vals = self._expressions(p_all, y, t)
                rows += [vals[expr_names.index(q)] for q in expressions]
            return np.array(rows)

        base = outputs(traj.y)
        total = np.zeros_like(base)
        for i in range(2 * n):
            if err[i] > 0:
                shifted = traj.y.copy()
                shifted[:, i] += err[i]
                total += np.abs(outputs(shifted) - base)
        propagated = float(np.max(total)) if total.size else 0.0
        return max(worst, propagated) if np.isfinite(propagated) else float("nan")

    def summarize_batch(self, parameters: Mapping[str, Any], initial: Mapping[str, Any], names: tuple[str, ...], *,
                        strict: bool = True, scene: Any = None) -> Any:
        """The summaries of a sweep's points that integrate (:mod:`.batch`); None without the sweep's scene."""
        from .batch import summarize_batch

        return None if scene is None else summarize_batch(self, scene, parameters, initial, names)

    def summarize(self, scene: "Scene", solved: Solved, t: "np.ndarray",
                  names: tuple[str, ...]) -> dict[str, tuple[Any, Any]]:
        """``period`` of the reduced motion (non-cyclic q and every q̇): in closed form where L reduces to
        u̇² = P(u) with P of degree ≤ 4 (:mod:`.closed`, cross-checked against the period measured on the
        trajectory), else measured; the turning points and per-period advances (:meth:`_closed_summaries`);
        the conserved quantities' values (:mod:`..summaries`)."""
        import numpy as np

        from ..summaries import invariants_of, period_of

        drifts = self.drift(scene, solved, t)
        reduced = {q.name for q in self.summaries[1:] if q.name.endswith(("_min", "_max", "_per_period"))}
        out = invariants_of(drifts, tuple(n for n in names if n != "period" and n not in reduced),
                            "the Lagrangian depends on t")
        # every closed-form summary from one pair of motions (the run's own, where it was the closed form)
        closed_names = [n for n in names if n in reduced or n == "period" and self.has_reduction()]
        closed_out = self._closed_summaries(scene, drifts, closed_names, getattr(solved.solution, "motion", None)) \
            if closed_names else {}
        out.update({n: v for n, v in closed_out.items() if n != "period"})
        if "period" in names:
            traj, n = solved.solution, len(self.definition.coordinates)
            keep = [i for i, q in enumerate(self.definition.coordinates) if q not in self.equations.cyclic]
            columns = keep + list(range(n, 2 * n))
            errors = None if traj.component_error is None else np.asarray(traj.component_error)[columns]
            if self.definition.uses_time:
                # a time that is only a gauge (core.quadrature.without_time_gauge) leaves a repeating motion
                found, why = self.reduction()
                if found is None:
                    out["period"] = (None, f"the Lagrangian depends on t: the motion need not repeat ({why})")
                else:
                    closed = closed_out["period"]
                    measured = period_of(np.asarray(traj.t), np.asarray(traj.y)[:, columns], errors)
                    out["period"] = measured if closed[0] is None else _checked(closed, measured)
            else:
                measured = period_of(np.asarray(traj.t), np.asarray(traj.y)[:, columns], errors)
                if not self.has_reduction():
                    out["period"] = measured
                else:
                    out["period"] = _checked(closed_out["period"], measured)
        return {name: out[name] for name in names}

    def reduction(self, along: str | None = None) -> tuple[Any, str | None]:
        """(substitution, None), or (None, the reason there is none): the reduction to u̇² = P(u), or with ``along``
        (a cyclic coordinate c) to the orbit's (du/dc)² = P(u) (cached)."""
        key = "_found" if along is None else f"_found_{along}"
        if key not in self.__dict__:
            from ...core.quadrature import NoQuadrature, NoSubstitution, find_substitution, reduce_to_quadrature
            from ...errors import DerivationError

            try:
                self.__dict__[key] = (find_substitution(reduce_to_quadrature(self.reduced_model(), along)), None)
            except (NoQuadrature, NoSubstitution, DerivationError) as exc:
                self.__dict__[key] = (None, str(exc))
        return self.__dict__[key]

    def has_reduction(self) -> bool:
        """Whether a closed form may exist: the reduction in t, or an orbit along a cyclic coordinate (then t along it
        inverts, :mod:`.timed`)."""
        if self.reduction()[0] is not None:
            return True
        from ...core.quadrature import NoQuadrature
        from ...errors import DerivationError

        try:
            cyclic = self.reduced_model().cyclic_coordinates
        except (NoQuadrature, DerivationError):  # t not a gauge: no reduction at all (reduction() says why)
            return False
        return any(self.reduction(q.func.__name__)[0] is not None for q in cyclic)

    def reduced_model(self) -> Any:
        """The :class:`~mechderive.core.lagrangian.LagrangianModel` the closed form reduces: L itself, or, where L
        depends on t only through a total derivative dG(q, t)/dt (an accelerating frame's gauge), L − dG/dt
        (:func:`~mechderive.core.quadrature.without_time_gauge`; raises its reason otherwise)."""
        if "_reduced_model" not in self.__dict__:
            from ...core.quadrature import without_time_gauge

            from ...core.quadrature import one_free_coordinate

            model = self.equations.lagrangian_model
            model = without_time_gauge(model)[0] if self.definition.uses_time else model
            # every coordinate cyclic (a free rotor, a free particle): nothing would be left to Routh-reduce to, so the
            # first is the coordinate the quadrature solves (u̇² = P constant)
            self.__dict__["_reduced_model"] = one_free_coordinate(model)
        return self.__dict__["_reduced_model"]

    def cyclic_rates(self) -> dict:
        """{cyclic coordinate: (N, D) or the reason}: ċ = N(u)/D(u) (:func:`mechderive.core.quadrature.cyclic_rates`),
        u the substitution of the reduction in t.  Where that reduction has none (Kepler's problem: u = 1/r gives
        degree 6; L depending on t other than through a gauge), every cyclic coordinate's entry is the reason,
        ``"no reduction in t: …"`` — its rate is then no function of a u with u̇² = P(u) (an orbit along a cyclic
        coordinate has its own rates, in that coordinate)."""
        if "_rates" not in self.__dict__:
            from ...core.quadrature import NoQuadrature, cyclic_rates
            from ...errors import DerivationError

            found, reason = self.reduction()
            if found is None:
                try:
                    model = self.reduced_model()
                except (NoQuadrature, DerivationError):  # t no gauge: the cyclic coordinates of L itself
                    model = self.equations.lagrangian_model
                rates = {c.func.__name__: f"no reduction in t: {reason}" for c in model.cyclic_coordinates}
            else:
                rates = cyclic_rates(self.reduced_model(), found)
            self.__dict__["_rates"] = rates
        return self.__dict__["_rates"]

    def _closed_summaries(self, scene: "Scene", drifts: dict, names: list[str], base: Any = None) -> dict:
        """The period, turning points and per-period advances from the closed form (:mod:`.closed`; ``base``, the
        run's own motion where it has one), each with the change it undergoes when E moves by its evaluation's
        rounding from the start's doubles (the estimate); (None, the reason) where the motion has no closed form
        or the quantity does not apply."""
        from .closed import closed_motion

        try:
            base = base or closed_motion(self, dict(scene.parameters), dict(scene.initial))
            energy = [float(v) for k, v in base.values.items() if k.name == "E"]
            shift = 8 * 2.0**-52 * (max(float(drifts["energy"].scale), abs(float(drifts["energy"].start)))
                                    if "energy" in drifts else abs(energy[0]) if energy else 1.0)
            moved = closed_motion(self, dict(scene.parameters), dict(scene.initial), energy_shift=shift)
        except OutOfReach as exc:
            return {n: (None, str(exc)) for n in names}
        out = {}
        for n in names:
            if n == "period" and (base.kind == "steady" or base.kind.startswith("unbounded")):
                out[n] = (None, f"no period: the motion is {base.kind}")
                continue
            if n == "period" and base.motion.asymptotic:
                out[n] = (None, f"m = 1 ({base.kind}): the motion takes infinitely long and does not return")
                continue
            if base.motion.asymptotic and not n.endswith("_per_period"):
                # on a separatrix the far end is the double root, exact from the scene's numbers (a shift of E by
                # its rounding would make another kind of motion, not a nearby value): the limit q approaches
                try:
                    value = base.summary(n)
                except OutOfReach as exc:
                    out[n] = (None, str(exc))
                    continue
                out[n] = (value, 4 * 2.0**-52 * abs(value))
                continue
            try:
                value, other = ((float(base.period), float(moved.period)) if n == "period"
                                else (base.summary(n), moved.summary(n)))
            except OutOfReach as exc:
                out[n] = (None, str(exc))
                continue
            out[n] = (value, abs(other - value) + 2.0**-52 * abs(value))
        return out

    def drift(self, scene: "Scene", solved: Solved, t: "np.ndarray") -> dict[str, "Drift"]:
        """Energy (when ∂L/∂t = 0) and each p_c, each against the largest sum of the sizes of its terms."""
        import numpy as np

        from ...core.drift import drift

        traj = solved.solution
        out = {}
        for name in self.equations.conserved_names:
            scale = float(np.max(np.abs(traj.invariant(f"scale_{name}"))))
            out[name] = drift(traj.invariant(name), scale, f"max_t Σ|terms of {name}|")
        return out

    # --- derive, check ---------------------------------------------------------------------------

    def lagrangian_model(self) -> tuple:
        """(L, coordinates, velocities, parameter symbols): what :mod:`mechderive.core.linearize` reduces."""
        d = self.definition
        return d.lagrangian, d.positions, d.velocities, d.parameter_symbols

    def derivations(self) -> tuple[Derivation, ...]:
        """L, the Euler–Lagrange equations, M, b, q̈, the momenta, the energy and the conserved momenta."""
        eq = self.equations

        def conserved(_: Any) -> Any:
            import sympy as sp

            index = {q: i for i, q in enumerate(self.definition.coordinates)}
            return sp.Matrix([eq.momenta[index[q]] for q in eq.cyclic]) if eq.cyclic else sp.Matrix([])

        return (
            Derivation("lagrangian", "L(q, q_dot, t) as given", "(3.62) for the heavy top",
                       lambda _: eq.state_lagrangian),
            Derivation("euler_lagrange", "d/dt ∂L/∂q̇_i − ∂L/∂q_i = 0, in functions of t", "",
                       lambda _: eq.euler_lagrange),
            Derivation("mass_matrix", "M = ∂²L/∂q̇∂q̇ (M q̈ = b)", "", lambda _: eq.mass_matrix),
            Derivation("forcing", "b = ∂L/∂q − (∂²L/∂q̇∂q) q̇ − ∂²L/∂q̇∂t (M q̈ = b)", "", lambda _: eq.forcing),
            Derivation("accelerations", f"q̈ = M⁻¹ b ({eq.solve_kind})", "", lambda _: eq.accelerations),
            Derivation("momenta", "p = ∂L/∂q̇", "(3.63)-(3.64) for the heavy top", lambda _: eq.momenta),
            Derivation("energy", "h = Σ q̇ ∂L/∂q̇ − L (conserved when ∂L/∂t = 0)", "(3.65) for the heavy top",
                       lambda _: eq.energy),
            Derivation("conserved_momenta", "p_c of the cyclic coordinates (∂L/∂q_c ≡ 0)", "", conserved),
            Derivation("closed_form", "the reduction by the cyclic coordinates to u̇² = P(u), P a polynomial of degree "
                       "≤ 4 in the substitution u = g(q) found (elliptic functions solve it)", "(3.73) for the heavy top",
                       lambda _: self._reduction()[1], lhs=lambda: self._reduction()[0]),
            *self._solution_derivations(),
        )

    def _solution_derivations(self) -> tuple[Derivation, ...]:
        """closed_form_u, _m, _kappa, _t and closed_form_<c> (:func:`.closed.solution_formulas`): the solution as
        formulas, built on request (a system without a reduction lists them and says why when asked)."""
        names = ["u", "m", "kappa", "t", *self.equations.cyclic]
        # the formulas are the system's, not a start's: say which motion they describe
        meanings = {"u": "u(χ) along the motion between two real roots of P (χ the amplitude); the other root "
                         "configurations are closed_form_u_<configuration> (polynomial, sinh, cosh, double_root, "
                         "cn_cubic, cn_quartic, cn_quartic_outside, tan), and `run --json` reports a start's own under "
                         "details.closed_form",
                    "m": "the Jacobi parameter m, the roots' cross-ratio", "kappa": "the rate κ of the Jacobi argument",
                    "t": "t − t₀ = (F(χ|m) − F(χ₀|m))/κ"}

        def formula(name: str, part: int) -> Any:
            from .closed import solution_formulas

            try:
                found = solution_formulas(self)
            except OutOfReach as exc:
                from ...errors import DerivationError

                raise DerivationError(str(exc)) from exc
            if name not in found:
                from ...errors import DerivationError

                raise DerivationError(f"closed_form_{name}: no printable formula (a quartic's rates, a rate that is "
                                      "not simple partial fractions over its poles, or not a rational function of u; "
                                      "for deg P ≤ 1, m, κ and t(χ) do not apply)")
            return found[name][part]

        def configuration(config: str, part: int) -> Any:
            from ...errors import DerivationError
            from .configurations import CONFIGURATIONS, configuration_formulas

            found, reason = self.reduction()
            if found is None:
                raise DerivationError(f"no closed form: {reason}")
            if config not in CONFIGURATIONS[found.degree]:
                where = ", ".join(str(d) for d, names in CONFIGURATIONS.items() if config in names)
                raise DerivationError(f"closed_form_u_{config}: expected P of degree {where}, got degree "
                                      f"{found.degree} ({found.name}); its configurations: "
                                      + ", ".join(CONFIGURATIONS[found.degree]))
            return configuration_formulas(found.variable, found.polynomial.LC(), found.degree)[config][part]

        from .configurations import CONFIGURATIONS

        configs = dict.fromkeys(c for names in CONFIGURATIONS.values() for c in names)
        return tuple(Derivation(f"closed_form_{n}", meanings.get(n, f"{n} − {n}₀ by partial fractions in u and "
                                                                     "Π(n; χ|m)"), "",
                                lambda _, n=n: formula(n, 1), lhs=lambda n=n: formula(n, 0)) for n in names) + tuple(
            Derivation(f"closed_form_u_{c}", f"u for the root configuration {c} of P, in its roots and leading "
                       "coefficient ([u(χ), m, κ] for the elliptic ones; mechderive.systems.lagrangian.configurations)",
                       "", lambda _, c=c: configuration(c, 1), lhs=lambda c=c: configuration(c, 0)) for c in configs)

    def _reduction(self) -> Any:
        """((d g(q)/dt)², P(g(q))): the substitution found and its polynomial, printed as one equation (the right
        side in the plain coordinate symbol, so that code can be generated from it); raises the reason where there
        is none (:mod:`mechderive.core.quadrature`)."""
        import sympy as sp

        from ...core.symbols import t as time
        from ...errors import DerivationError

        found, reason = self.reduction()
        if found is None:
            raise DerivationError(reason)
        model = self.reduced_model()
        q = model.remaining_coordinates[0]  # q(t)
        g = found.u_of_q.subs({s: q for s in found.u_of_q.free_symbols})
        plain = model.positions[model.coordinates.index(q)]
        g_plain = found.u_of_q.subs({s: plain for s in found.u_of_q.free_symbols})
        return sp.Derivative(g, time, evaluate=False) ** 2, found.polynomial.as_expr().subs(found.variable, g_plain)


    def check_system(self) -> Any:
        """The symbols of ``mechderive check``: q, q_dot (state), q_ddot, the parameters, energy, p_<q>, Lagrangian."""
        import sympy as sp

        from ...core.symbols import state_symbol
        from ...core import check_system as fs

        d, eq = self.definition, self.equations
        qs = [fs.Quantity(q, state_symbol(q), "state", f"coordinate {q}") for q in d.coordinates]
        qs += [fs.Quantity(q + "_dot", state_symbol(q + "_dot"), "state", f"velocity of {q}") for q in d.coordinates]
        qs += [fs.Quantity(q + "_ddot", state_symbol(q + "_ddot"), "derivative",
                           f"acceleration of {q} (fixed by the equations of motion on a motion)") for q in d.coordinates]
        qs += [fs.Quantity(p, s, "parameter", "a parameter of the Lagrangian")
               for p, s in zip(d.parameters, d.parameter_symbols)]
        qs += [fs.Quantity("Lagrangian", sp.Symbol("Lagrangian", real=True), "defined", "L as given",
                           lambda s: eq.state_lagrangian),
               fs.Quantity("energy", sp.Symbol("energy", real=True), "defined", "h = Σ q̇ ∂L/∂q̇ − L",
                           lambda s: eq.energy)]
        for i, q in enumerate(d.coordinates):
            qs.append(fs.Quantity(f"p_{q}", sp.Symbol(f"p_{q}", real=True), "defined", f"p_{q} = ∂L/∂{q}_dot",
                                  lambda s, i=i: eq.momenta[i]))
        taken = {x.name for x in qs}
        qs += [fs.Quantity(n, sp.Symbol(n, real=True), "defined", f"output expression {n}", lambda s, e=e: e)
               for n, e in d.expressions if n not in taken]
        return fs.System(name=self.name, summary=_SUMMARY, coordinates=d.coordinates, order=2,
                         highest=lambda: eq.acceleration_map, quantities=qs, domain={})

    def example_scene(self) -> str:
        return EXAMPLE_SCENE


def eq_limit() -> float:
    from .model import CONDITION_LIMIT

    return CONDITION_LIMIT


def _number(key: str, value: Any) -> float:
    import math

    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InvalidInputError(f"scene key {key}: expected a finite number, got {type(value).__name__} {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise InvalidInputError(f"scene key {key}: expected a finite number, got {value!r}")
    return x


_CACHE: "OrderedDict[tuple[str, str], LagrangianSystem]" = OrderedDict()
_LOCK = threading.Lock()
_CACHE_SIZE = 64


def _cached(definition: "Definition", name: str) -> LagrangianSystem:
    key = (definition.digest, name)
    with _LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _CACHE.move_to_end(key)
            return hit
    system = LagrangianSystem(definition, name)
    reason = system.equations.singular_reason()
    if reason is not None:
        raise InvalidInputError(f"scene key lagrangian: expected a regular Lagrangian (an invertible mass matrix "
                                f"∂²L/∂q̇∂q̇), got a singular mass matrix: {reason}")
    with _LOCK:
        _CACHE[key] = system
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return system


class LagrangianFamily(System):
    """The registered ``lagrangian`` family: :meth:`configure` builds a scene's :class:`LagrangianSystem`."""

    name = "lagrangian"
    summary = _SUMMARY
    section = ""
    extra_keys = ("coordinates", "lagrangian", "output.expressions")
    methods = ("exact", "integrate")

    def configure(self, definition: Mapping[str, Any]) -> LagrangianSystem:
        """The concrete system of a scene's ``coordinates``, ``lagrangian`` and ``[output.expressions]``."""
        from .definition import parse_definition

        return _cached(parse_definition(definition), self.name)

    def _example(self) -> LagrangianSystem:
        return self.configure(EXAMPLE_DEFINITION)

    def derivations(self) -> tuple[Derivation, ...]:
        """None: the family has no equations until a scene (or :func:`from_lagrangian`) gives its Lagrangian;
        ``mechderive derive SCENE.toml`` derives a configured one's."""
        return ()

    def check_system(self) -> Any:
        """None, as :meth:`derivations`: ``mechderive check SCENE.toml`` checks a configured one's."""
        return None

    def example_scene(self) -> str:
        return EXAMPLE_SCENE


SYSTEM = LagrangianFamily()


def _largest(columns: dict, names: Sequence[str]) -> float:
    """The largest magnitude among the requested columns (the scale an absolute estimate is judged against)."""
    import numpy as np

    sizes = [float(np.max(np.abs(columns[n]))) for n in names if n in columns and np.size(columns[n])]
    return max(sizes, default=0.0)


def _checked(closed: tuple[Any, Any], measured: tuple[Any, Any]) -> tuple[Any, Any]:
    """The closed form's (period, estimate), cross-checked against the period measured on the trajectory where
    the run shows one: if they disagree by more than ten times their estimates together, the recipe's
    assumptions did not hold for this motion — the measured period is given instead, its estimate the
    disagreement (never a wrong number with a small estimate)."""
    (value, estimate), (seen, seen_estimate) = closed, measured
    if value is None or seen is None or not isinstance(seen_estimate, (int, float)):
        return closed
    if abs(value - seen) <= 10 * (estimate + seen_estimate):
        return closed
    return seen, abs(value - seen)


def from_lagrangian(lagrangian: Any, coordinates: Sequence[Any], parameters: Sequence[Any] = (),
                    name: str | None = None) -> LagrangianSystem:
    """The system of ``lagrangian`` in ``coordinates``, ready to register, run, derive and check.

    ``lagrangian``: a SymPy expression (coordinates as symbols ``q`` or functions ``q(t)``, velocities
    as symbols ``q_dot`` or ``q(t).diff(t)``) or text, parsed by the whitelist (never evaluated).
    ``coordinates``: names, Symbols or functions of t.  ``parameters``: names or Symbols; every other
    symbol of L must be one of them (``t`` is the time).  ``name``: the system's name for
    :func:`mechderive.systems.registry.register` and a scene's ``system = "..."`` (default
    ``"lagrangian_<hash>"``).  Raises :class:`~mechderive.errors.InvalidInputError` naming what is wrong.

    >>> pendulum = from_lagrangian("l**2*theta_dot**2/2 + g*l*cos(theta)", ["theta"], ["g", "l"], name="pendulum")
    >>> pendulum.quantity_names()
    ('theta', 'theta_dot', 'energy')
    """
    from .definition import from_objects

    definition = from_objects(lagrangian, coordinates, parameters)
    if name is None:
        name = f"lagrangian_{definition.digest}"
    if not isinstance(name, str) or not name.isidentifier():
        raise InvalidInputError(f"expected a system name that is an identifier, got {name!r}")
    return _cached(definition, name)
