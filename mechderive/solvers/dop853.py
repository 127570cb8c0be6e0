"""DOP853 on a derived right-hand side — compiled C or SciPy — with the error estimate both tops report.

Two backends run the same algorithm (the same tableau, controller and dense output, so the same
steps to rounding):

* ``"c"`` — :mod:`.dop853_c`: the stepper and the right-hand side compiled together by the system
  C compiler (~1 µs a step for the heavy top);
* ``"scipy"`` — SciPy's ``DOP853`` stepper (the one :func:`scipy.integrate.solve_ivp` drives), driven
  step by step on the compiled-to-Python right-hand side (~100 µs a step), also the only one for
  right-hand sides that call back into Python (a torque).

``backend="auto"`` takes C where a compiler is found (see :mod:`mechderive.core.cbuild`).  Both
backends can follow the Euler half-angles of a quaternion in the state along every accepted step
(:mod:`.half_angles`), so that continuous angles do not depend on how finely the output is sampled.

The error estimate is the distance to a second run at a tighter tolerance, scaled by the factor of
:func:`reference_tolerance`; both backends raise any rtol below 100·ε to 2.3e-14 (SciPy's rule;
:data:`SCIPY_MIN_RTOL`), so below 2.3e-13 the second run is *looser* and the distance an upper
bound — callers say so in their ``error_estimate_kind``.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from ..errors import IntegrationError, InvalidInputError, MechDeriveError
from .limits import MAX_STEPS, check_max_steps, nonfinite_start, nonfinite_state, too_many_steps

__all__ = ["SCIPY_MIN_RTOL", "BACKENDS", "Dop853Run", "run_dop853", "check_backend", "reference_tolerance",
           "reference_run"]

#: solve_ivp raises rtol below 100·ε to this value.
SCIPY_MIN_RTOL = 2.3e-14
BACKENDS = ("auto", "c", "scipy")


@dataclass(frozen=True)
class Dop853Run:
    """One DOP853 run: ``y`` of shape (n, N) (as SciPy's), right-hand-side evaluations, accepted steps;
    with tracking (``track=`` of :func:`run_dop853`) the half-angles ``args`` (N, 2) at the output
    times, ``closest`` (2,) and ``near`` (2, DECADES) (see :mod:`.half_angles`), else None."""

    y: np.ndarray
    nfev: int
    steps: int | None
    args: np.ndarray | None = None
    closest: np.ndarray | None = None
    near: np.ndarray | None = None


def check_backend(backend: str) -> str:
    """Validate ``backend`` (one of :data:`BACKENDS`)."""
    if backend not in BACKENDS:
        raise InvalidInputError(f"expected backend one of {', '.join(map(repr, BACKENDS))}, got {backend!r}")
    return backend


def reference_tolerance(rtol: float) -> tuple[float, float]:
    """(rtol of the reference run, factor to apply to the distance between the runs).

    The reference runs at rtol/1000, or at :data:`SCIPY_MIN_RTOL` when that is above it (DOP853's
    global error falls roughly like rtol^p, p ≈ 0.9 measured; the factor 1/(1 - √r), r the ratio of
    the tolerances, covers any p ≥ 1/2: ≤ 1.03 at r = 1e-3, 1.46 at r = 0.1).  Below
    10 × SCIPY_MIN_RTOL no tighter run is possible: the reference then runs *looser*, at 10·rtol,
    and the distance (≈ the looser run's error, ~10× the main run's) is reported as is — an
    upper bound, not an estimate of the same size.
    """
    if rtol >= 10 * SCIPY_MIN_RTOL:
        rt_ref = max(rtol * 1e-3, SCIPY_MIN_RTOL)
        return rt_ref, 1.0 / (1.0 - (rt_ref / rtol) ** 0.5)
    return 10 * rtol, 1.0


def _solve_scipy(fun: Callable[[float, np.ndarray], Any], t: np.ndarray, y0: np.ndarray, rtol: float, atol: float,
                 track: tuple[int, Sequence[float]] | None, max_steps: int = MAX_STEPS) -> Dop853Run:
    """SciPy's DOP853 stepper driven step by step (as ``solve_ivp`` drives it), outputs by its dense output.

    Stops with an :class:`IntegrationError` where ``solve_ivp`` would return NaN or loop without end: a
    right-hand side not finite at the start (SciPy's first step would be NaN, and its step loop never
    ends on NaN) or that cannot be evaluated (math overflow), a state no longer finite, ``max_steps``.
    """
    from scipy.integrate import DOP853

    from .half_angles import HalfAngleTracker

    label = "DOP853 (SciPy)"
    # NaN and overflow are checked here and said once, not as RuntimeWarnings of SciPy's arithmetic
    with np.errstate(all="ignore"), _arithmetic_errors(label, t):
        if not np.all(np.isfinite(y0)):
            raise nonfinite_start(label, t0=float(t[0]), what="the initial state")
        solver = DOP853(fun, t[0], y0, t[-1], rtol=rtol, atol=atol)
        if not (np.all(np.isfinite(solver.f)) and np.isfinite(solver.h_abs) and solver.h_abs > 0):
            raise nonfinite_start(label, t0=float(t[0]))
        ys = np.empty((t.size, y0.size))
        ys[0] = y0
        tracker, args = None, None
        if track is not None:
            tracker = HalfAngleTracker(y0, solver.f, track[0], track[1])
            args = np.empty((t.size, 2))
            args[0] = tracker.args_at(y0)
        k, steps = 1, 0
        while k < t.size:
            if steps >= max_steps:
                raise too_many_steps(label, t=float(solver.t), t_end=float(t[-1]), steps=steps, max_steps=max_steps)
            t_from = float(solver.t)
            solver.step()
            if solver.status == "failed":
                raise IntegrationError(f"expected {label} to reach t = {t[-1]:.6g}, got stuck at t = {solver.t:.6g}: "
                                       "the step size fell below 10 ulp of t (the solution is probably singular "
                                       "or blows up there, or the right-hand side is not finite there)")
            if not np.all(np.isfinite(solver.y)):
                raise nonfinite_state(label, t=t_from, steps=steps)
            steps += 1
            t_old, t_new = solver.t_old, solver.t
            h = t_new - t_old
            dense = []

            def at(x: float, t_old: float = t_old, h: float = h, dense: list = dense) -> np.ndarray:
                if not dense:
                    dense.append(solver.dense_output())
                return dense[0](t_old + x * h)
            first = k
            while k < t.size and t[k] <= t_new:
                ys[k] = solver.y if t[k] == t_new else at((t[k] - t_old) / h)
                k += 1
            if tracker is not None:
                inside = [i for i in range(first, k) if t[i] < t_new]
                points = [((t[i] - t_old) / h, ys[i]) for i in inside] + [(1.0, solver.y)]
                values = tracker.step(solver.y_old, h, solver.K, points, at)
                for i, v in zip(inside, values):
                    args[i] = v
                if t[k - 1] == t_new:
                    args[k - 1] = values[-1]
    if tracker is None:
        return Dop853Run(y=ys.T, nfev=int(solver.nfev), steps=steps)
    return Dop853Run(y=ys.T, nfev=int(solver.nfev), steps=steps, args=args, closest=np.array(tracker.closest),
                     near=tracker.near.copy())


@contextlib.contextmanager
def _arithmetic_errors(label: str, t: np.ndarray) -> Iterator[None]:
    """Turn the exceptions of a right-hand side evaluated in Python floats (``math``: OverflowError,
    "math domain error" on an infinite argument, division by zero) into an :class:`IntegrationError`."""
    try:
        yield
    except MechDeriveError:
        raise
    except (ArithmeticError, ValueError) as exc:
        raise IntegrationError(f"expected the right-hand side of {label} to be computable on [{t[0]:.6g}, "
                               f"{t[-1]:.6g}], got {type(exc).__name__}: {exc}: a parameter or initial value is "
                               "probably out of floating-point range, or the motion blows up") from exc


def run_dop853(fun: Callable[[float, np.ndarray], Any] | None, t: np.ndarray, y0: np.ndarray, rtol: float,
               atol: float, *, reference: bool, compiled: Any = None, params: Sequence[float] = (),
               track: tuple[int, Sequence[float]] | None = None, max_steps: int | None = None
               ) -> tuple[Dop853Run, float, Dop853Run | None, str, float]:
    """(run at ``t``, wall seconds of that run, reference run or None, how the reference was made,
    the factor to apply to the distance between the runs (:func:`reference_tolerance`)).

    With ``compiled`` (a :class:`~.dop853_c.CompiledDOP853`) the C stepper runs with ``params``;
    otherwise SciPy's DOP853 stepper on ``fun(t, y)``.  ``track = (qoff, (σ0, δ0))`` follows the
    Euler half-angles of the quaternion at ``y[qoff:qoff + 4]`` along every step on both backends
    (:mod:`.half_angles`).  ``max_steps``: accepted steps allowed per run (default
    :data:`~.limits.MAX_STEPS`).  Raises :class:`IntegrationError` when a run does not reach ``t[-1]``:
    a state or right-hand side that is not finite, a step size that collapses, ``max_steps`` reached.
    """
    max_steps = check_max_steps(max_steps)
    if compiled is not None:
        def solve(rt: float, at: float) -> Dop853Run:
            y, stats = compiled.solve(t, y0, params, rt, at, track=track, max_steps=max_steps)
            return Dop853Run(y=y.T, nfev=stats["nfev"], steps=stats["steps"], args=stats.get("args"),
                             closest=stats.get("closest"), near=stats.get("near"))
        label = "compiled DOP853"
    else:
        def solve(rt: float, at: float) -> Dop853Run:
            return _solve_scipy(fun, t, y0, max(rt, SCIPY_MIN_RTOL), at, track, max_steps)
        label = "DOP853"

    start = time.perf_counter()
    sol = solve(rtol, atol)
    wall = time.perf_counter() - start
    if not reference:
        return sol, wall, None, "not requested", 1.0
    rt_ref, at_ref, factor, how = reference_run(label, rtol, atol)
    return sol, wall, solve(rt_ref, at_ref), how, factor


def reference_run(label: str, rtol: float, atol: float) -> tuple[float, float, float, str]:
    """(rtol, atol of the reference run, the factor of :func:`reference_tolerance`, how the run is made):
    one definition for a single run (:func:`run_dop853`) and a batch (:mod:`.batch`)."""
    rt_ref, factor = reference_tolerance(rtol)
    at_ref = atol * rt_ref / rtol
    how = f"{label} at rtol={rt_ref:.2g}, atol={at_ref:.2g}"
    if rt_ref > rtol:
        how += " (looser: no tighter run is possible, so the distance is an upper bound)"
    elif factor > 1.0:
        how += f", distance × {factor:.3g} = 1/(1 - √(tolerance ratio))"
    return rt_ref, at_ref, factor, how
