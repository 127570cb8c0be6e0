"""The planner: from a scene's requested quantities to the derivations, compilations and solves they need.

The planner names no system: it asks the scene's (:attr:`Scene.model`, a
:class:`~mechderive.systems.base.System` of the registry) for its methods, its units, its solve and
the drift of its conserved quantities.  Each system maps every quantity name to what computes it.
Only those are run:
a heavy-top scene asking for ``u`` evaluates sn² of the nutation phase and nothing
else — not the amplitude, not Π, not the partial fractions of φ̇ and ψ̇ (which are
not even derived).  The report lists exactly what was derived and compiled in this
run (empty on a warm disk cache: see :mod:`mechderive.core.codecache`).

Method choice (``method = "auto"``): the closed form where the system has one (its ``methods``
list ``"exact"``: the free and the heavy top) — it is more accurate than integration at every rtol, and as fast
as the compiled DOP853 at its loosest tolerances (see ``benchmarks/``); integration
otherwise (the falling cat, a user's system).  Near a pole passage φ and ψ each are ill-conditioned for any
method; the closed form's estimate says so (its conditioning), and the report says what
is well conditioned instead rather than switching methods silently.

Error estimates are measured on the run, never a constant: the closed forms' own
``error_estimate(t, quantities)`` (a residual of the derived equations at the samples,
scaled to an error in the output), the integrators' global estimate (a rerun at a tighter
tolerance).  ``rtol_met`` is ``estimate <= rtol`` (both absolute: angles in rad, R
entries), or ``None`` with ``rtol_met_reason`` when there is no estimate.

Drift of conserved quantities (:func:`mechderive.core.drift.drift`) is measured against a
scale of the motion, never the quantity's own initial value (which may be ~0, e.g.
p_φ = 0): for the heavy top E against max_t (T + |V|), p_φ and p_ψ against
max(|p_φ(0)|, |p_ψ(0)|, √(2 I1 T_max), √(I1 M g l)); for the free top T against T
and |L| against |L|; for the falling cat L (which must stay 0) against the angular
momentum its turn carries, max_t |Ĩ Ω|.  The same functions serve the closed form and
the integrator (from the trajectory's own invariants); ``drift_relative_to`` in the
report names each scale and its size.

``strict = false`` scenes run moments no rigid body has; ``waived`` in the report lists
the conditions that were waived (empty otherwise).

Extreme numbers (issue 12): a scene far from order one is solved in the units of its own motion,
exact powers of two (:mod:`.units`; the report's ``units`` says so), and what no choice of units
brings within double precision is refused before solving, naming the scene keys and the range
allowed — an output beyond the doubles (E = ½ I ω² of 1e600 J), a ``t_end`` beyond a closed form's
2^51 periods or an integration's :data:`~.units.MAX_INTEGRATED_RADIANS`.  With ``method = "auto"``
a motion the closed form cannot follow (within ~1e-75 rad of the pole or the bottom, ~1e-150 of the
separatrix) is integrated, and the note says why; ``method = "exact"`` refuses it, naming the keys.
A solver's own refusal is prefixed with the scene keys its message mentions.
"""

from __future__ import annotations

import dataclasses
import math
import re
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core import cbuild, codecache
from ..core.model import derivation_log, derivation_seconds
from ..errors import InvalidInputError, MechDeriveError
from ..systems.base import OutOfReach, Quantity, Solved
from .schema import Scene, waived
from ..systems.scaling import Scaled, check_samples, in_scene_units, scale_scene, solving_in

__all__ = ["RunResult", "run_scene", "summarize"]


@dataclass
class RunResult:
    """The table a scene asked for (``t`` then the quantities, in order) and the run's report."""

    scene: Scene
    t: np.ndarray
    columns: dict[str, np.ndarray]
    report: dict[str, Any] = field(default_factory=dict)
    solution: Any = None  # the solved object (in the solver's units where the report has ``units``)

    def output_columns(self) -> dict[str, np.ndarray]:
        """The scene's quantities as ``-o`` writes and the summary prints them: each in its ``[output].units``
        where the scene gives one (``theta`` in deg), else SI; ``columns`` itself stays SI (plots, drift)."""
        units = self.scene.output_units
        if not units:
            return {q: self.columns[q] for q in self.scene.quantities}
        from .units import factor_to

        si = {q.name: q.unit for q in self.scene.model.quantities}
        return {q: self.columns[q] / factor_to(f"scene key [output].units.{q}", units[q], si.get(q, ""))
                if q in units else self.columns[q] for q in self.scene.quantities}


def choose_method(scene: Scene) -> tuple[str, str | None]:
    """(method, note): the solver a scene will use and, if the request cannot be met before the run, why."""
    methods = scene.model.methods
    if scene.method == "exact" and "exact" not in methods:
        raise InvalidInputError(f"scene method 'exact': system {scene.system!r} has no closed form; "
                                "expected method 'auto' or 'integrate'")
    method = scene.method
    if method == "auto":
        method = "exact" if "exact" in methods else "integrate"
    return method, None


def _mentioned(message: str, names: tuple[str, ...]) -> list[str]:
    claim = message.split(";")[0]
    return [k for k in names if re.search(rf"(?<![A-Za-z0-9_]){re.escape(k)}(?![A-Za-z0-9_])", claim)]


def _scene_error(scene: Scene, exc: MechDeriveError) -> MechDeriveError:
    """A solver's refusal as a scene's: naming the keys its message mentions, else the tables it is about.

    The planner checks what it can before solving and names the keys itself; this is for what
    only a solver can find (it says what and why; the scene's keys are named in front).
    """
    message = str(exc)
    if message.startswith("scene "):
        return exc
    tables = [(table, names) for table, names in
              (("parameters", tuple(k.name for k in scene.model.parameters)),
               ("initial", tuple(k.name for k in scene.model.initial))) if names]
    keys = [f"[{table}].{k}" for table, names in tables for k in _mentioned(message, names)]
    where = ("scene keys " + ", ".join(keys) if len(keys) > 1 else f"scene key {keys[0]}" if keys else
             "scene tables " + ", ".join(f"[{table}]" for table, _ in tables))
    return type(exc)(f"{where}: {message}")


def _solve(scene: Scene, method: str, scaled: Scaled, t: np.ndarray) -> tuple[str, str | None, Solved]:
    """(method used, note, solved) in the solver's units; ``auto`` integrates where the closed form cannot
    follow the motion (the system raises :class:`~mechderive.systems.base.OutOfReach`), and says so."""
    model, work = scene.model, scaled.scene
    try:
        with solving_in(scaled):
            return method, None, model.solve(work, method, t)
    except OutOfReach as exc:
        why = exc.__cause__ if exc.__cause__ is not None else exc
        if scene.method != "auto":
            raise InvalidInputError(str(exc)) from exc
        try:
            with solving_in(scaled):
                result = model.solve(work, "integrate", t)
        except MechDeriveError as second:
            raise type(second)(f"{_scene_error(work, second)} (and the closed form cannot follow this motion "
                               f"either: {why})") from second
        return "integrate", f"integrated: the closed form cannot follow this motion ({why})", result


def run_scene(scene: Scene) -> RunResult:
    """Solve ``scene``: derive, compile and evaluate only what its quantities need.

    A scene whose numbers are far from order one is solved in the units of its own motion and
    converted back exactly (:mod:`.units`); what cannot be computed in double precision is refused
    with the scene keys it depends on and the range allowed.  With ``method = "auto"`` a motion the
    closed form cannot follow (within ~1e-75 rad of the pole, ~1e-150 of the separatrix) is
    integrated instead, and the report's note says so.
    """
    start = time.perf_counter()
    derived0, compiled0, seconds0 = len(derivation_log()), len(codecache.compile_log()), derivation_seconds()
    built0 = len(cbuild.build_log())
    t = scene.times()
    check_samples(scene, t)
    method, note = choose_method(scene)
    # The solvers start from the initial values at t = 0: output times from t_start > 0 (or an explicit
    # list) are solved from 0 with the first sample dropped afterwards; the system sees a plain scene
    # whose t_end is the last output time.
    start_at_zero = t[0] != 0
    t_solve = np.concatenate(([0.0], t)) if start_at_zero else t
    plain = scene if scene.times_given is None and not scene.t_start and scene.samples_per_period is None else \
        dataclasses.replace(scene, times_given=None, t_start=0.0, samples_per_period=None,
                            t_end=float(t_solve[-1]), samples=len(t_solve))
    scaled = scale_scene(plain)  # the system refuses here what no choice of units brings within the doubles
    work = scaled.scene
    if plain is scene and scaled.identity:
        t_work = t
    elif scaled.identity:
        t_work = t_solve
    else:  # exact: a power of two
        t_work = np.ldexp(t_solve, scaled.time) if plain is not scene else np.linspace(0.0, work.t_end, work.samples)

    def compiled_since() -> list[tuple[str, str, float]]:
        # generated Python (lambdify) and generated C (the compiled steppers), each from memory, disk or new
        return codecache.compile_log()[compiled0:] + [(f"{name} (C)", "compiled" if how == "built" else how, s)
                                                      for name, how, s in cbuild.build_log()[built0:]]

    try:
        method, fallback, solved = _solve(scene, method, scaled, t_work)
    except MechDeriveError as exc:
        raise _scene_error(scene, exc) from exc
    if fallback:
        note = fallback
    solve_end = time.perf_counter()
    # what the solve stage itself derived and compiled (the drift check may derive more afterwards)
    solve_derive_s = derivation_seconds() - seconds0
    solve_compile_s = sum(s for _, _, s in compiled_since())
    cols, info, solution = dict(solved.columns), dict(solved.info), solved.solution
    # the solver's own word on the method and why (Kepler's problem: exact in t through its orbit along φ) leads
    method_note = info.pop("note", None)
    if method_note:
        note = method_note + ("; " + note if note else "")
    if start_at_zero:  # the launch at t = 0 was solved only to start from it
        cols = {k: v[1:] for k, v in cols.items()}
        solved = Solved(cols, info, solution)
        t_work = t_work[1:]
    drifts = scene.model.drift(work, Solved(solved.columns, info, solution), t_work)
    summary_start = time.perf_counter()
    summary, summary_error = summarize(scene, scaled, Solved(solved.columns, info, solution), t_work)
    summary_s = time.perf_counter() - summary_start
    cols = in_scene_units(scaled, cols)
    if info.get("error_estimate") is not None:
        for q in scaled.offsets:
            if q in cols:
                # the turns added back: the rounding of φ0 itself and of each output, a few ulp of the larger
                with np.errstate(over="ignore"):  # spacing of the largest double is inf: so is the estimate
                    info["error_estimate"] = max(info["error_estimate"], 4 * float(np.spacing(max(
                        float(np.max(np.abs(cols[q]))), abs(scaled.original.initial[q])))))
    derived = derivation_log()[derived0:]
    compiled = compiled_since()
    derive_s = derivation_seconds() - seconds0
    compile_s = sum(s for _, how, s in compiled)
    total = time.perf_counter() - start
    estimate = info.get("error_estimate")
    rtol_met, rtol_reason = None, None
    if estimate is None:
        rtol_reason = "no error estimate: rtol not verified"
        note = (note + "; " if note else "") + rtol_reason
    else:
        # The estimates are absolute (angles in rad, R entries): compared with rtol as is,
        # since a relative error of a growing angle would mean nothing.
        rtol_met = bool(estimate <= scene.rtol)
        if not rtol_met:
            if info.get("error_estimate_kind") == "near-pole conditioning of φ, ψ":
                why = (f"error estimate {estimate:.2g} (near-pole conditioning of φ, ψ) exceeds the requested rtol "
                       f"{scene.rtol:g}: not met; R, the apex and ω are well conditioned (ask for those), or method "
                       "'integrate' estimates its own error at the samples")
            else:
                why = f"error estimate {estimate:.2g} exceeds the requested rtol {scene.rtol:g}: not met"
            note = (note + "; " if note else "") + why
    for k, v in list(cols.items()):
        if not np.all(np.isfinite(v)):
            bad = int(np.sum(~np.isfinite(v)))
            note = (note + "; " if note else "") + f"{k}: {bad} sample(s) not defined (e.g. φ̇, ψ̇ at θ = 0)"
    let_through = waived(scene)
    if let_through:
        note = (note + "; " if note else "") + ("strict = false: waived " + "; ".join(let_through)
                                                + " (no rigid body has these moments)")
    report = {
        "system": scene.system,
        "method": method,
        "derived": [name for name, _ in derived],
        "compiled": [f"{name} ({how})" for name, how, _ in compiled],
        "timings": {"derive": round(derive_s, 6), "compile": round(compile_s, 6),
                    "solve": round(max(solve_end - start - solve_derive_s - solve_compile_s, 0.0), 6),
                    "drift_check": round(max(total - (solve_end - start) - (derive_s - solve_derive_s)
                                             - (compile_s - solve_compile_s) - summary_s, 0.0), 6),
                    **({"summary": round(summary_s, 6)} if scene.summary else {})},
        "error_estimate": info.pop("error_estimate", None),
        "drift": {k: d.value for k, d in drifts.items()},
        "drift_relative_to": {k: d.relative_to for k, d in drifts.items()},
        "rtol": scene.rtol,
        "rtol_met": rtol_met,
        "note": note,
        "waived": let_through,
        "details": info,
    }
    if scene.output_units:
        report["column_units"] = dict(scene.output_units)  # -o and the printed table; estimates stay SI
    if scene.given_with_units:
        report["given_with_units"] = dict(scene.given_with_units)
    if scene.summary:
        report["summary"] = summary
        report["summary_error"] = summary_error
    if not scaled.identity:
        report["units"] = _units_note(scaled)
    if rtol_reason is not None:
        report["rtol_met_reason"] = rtol_reason
    return RunResult(scene=scene, t=t, columns=cols, report=report, solution=solution)


def summarize(scene: Scene, scaled: Scaled, solved: Solved, t: np.ndarray) -> tuple[dict, dict]:
    """({name: value}, {name: error estimate}) of the scene's ``[output].summary``, in the scene's units.

    The system computes each in its solver's units (:meth:`~mechderive.systems.base.System.summarize`);
    a scene solved in units of its own motion gets each number back by the power of two its quantity
    scales with (a column's own exponent where the name is a column's, else by ``scales_as``: a time,
    a rate, an angle).  A value that is not a plain number (a class, a table of rates) cannot be brought
    back by one power of two: there it is None, and its estimate says why — never a value in the wrong units.
    A quantity that does not apply to this motion is None with the reason as its "estimate".
    """
    if not scene.summary:
        return {}, {}
    model = scene.model
    try:
        computed = model.summarize(scaled.scene, solved, t, tuple(scene.summary))
    except MechDeriveError as exc:
        raise _scene_error(scene, exc) from exc
    missing = [n for n in scene.summary if n not in computed]
    if missing:
        raise InvalidInputError(f"system {scene.system!r} did not compute the per-motion quantities "
                                f"{', '.join(missing)} it lists")
    kinds = {q.name: q for q in model.summaries}
    values, errors = {}, {}
    for name in scene.summary:
        value, error = computed[name]
        if not scaled.identity and value is not None and not isinstance(value, (str, bool)):
            e = _summary_exponent(scaled, name, kinds.get(name))
            if e is None or not isinstance(value, (int, float)):
                value, error = None, (f"not available for a scene solved in units of its own motion "
                                      f"({_units_note(scaled)}): {name} is not a number scaled by a power of two")
            else:
                try:
                    value = math.ldexp(float(value), e)
                    if isinstance(error, (int, float)):
                        error = math.ldexp(float(error), e)
                except OverflowError:  # beyond the largest double in the scene's units
                    value, error = None, (f"{name} in the scene's units is beyond the largest double "
                                          f"({float(value):.6g} × 2^{e})")
        values[name], errors[name] = value, error
    return values, errors


def _summary_exponent(scaled: Scaled, name: str, quantity: Quantity | None) -> int | None:
    """e with value (scene units) = value (solver units)·2^e, or None where it is not one power of two."""
    if name in scaled.columns:
        return scaled.columns[name]
    if quantity is None:
        return None
    if quantity.scales_as == "" and quantity.unit in ("rad", "1"):
        return 0  # an angle or a pure number (u = cos θ) does not change with the units of time and mass
    return {"time": -scaled.time, "rate": scaled.rate, "angle": 0}.get(quantity.scales_as)


def _units_note(scaled: Scaled) -> str:
    """What the report's ``units`` says: the scene was solved in units of its own motion (powers of two)."""
    if scaled.note:
        return scaled.note
    return (f"solved in units where the moments and the fastest rate are of order one (exact powers of two: "
            f"rates ×2^{-scaled.rate}, t ×2^{scaled.time}); outputs converted back")
