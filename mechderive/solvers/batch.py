"""A batch of runs of one derived term: M initial states (and parameter values) through the compiled DOP853.

A sweep of a system that integrates solves many motions of the same equations.  One by one, each
costs a Python-level run (the planner, the scene, a ctypes call per run and per rerun); here the M
runs go to the C stepper in one call (:meth:`~.dop853_c.CompiledDOP853.solve_batch`), each with its
own adaptive steps — the steps it takes alone, so each point's :class:`~.driver.Trajectory` equals the
one :func:`~.driver.integrate` returns for it, bit for bit — and its own status: a point that blows up
or stalls is an :class:`~mechderive.errors.IntegrationError` in its place (the one the single run
raises), never the batch's failure.

* :func:`integrate_batch` is :func:`~.driver.integrate` with ``method="DOP853"`` on the compiled
  backend for M points: the main runs, then (``estimate_error``) the reference runs of the points
  that reached the end, each at its own tolerances (:func:`~.dop853.reference_run`), and each
  point's trajectory built by the driver's own code.
* :func:`integrate_to_rtol_batch` is :func:`~.driver.integrate_to_rtol` for M points: each point's
  tolerance follows its own measured estimates (:func:`~.driver.next_tolerance`), and only the
  points that must rerun are run again, together.

Only the compiled stepper runs batches (SciPy's would gain nothing: its time is Python's per step);
without a C compiler :func:`integrate_batch` returns None and the caller runs its points one by one.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from ..errors import IntegrationError, MechDeriveError
from .dop853 import reference_run
from .driver import Term, Trajectory, _compiled, _Run, _trajectory, next_tolerance

__all__ = ["integrate_batch", "integrate_to_rtol_batch"]


def integrate_batch(term: Term, y0: Any, t: Sequence[float], params: Any, *, rtol: Any, atol: Any = None,
                    estimate_error: bool = True, track: Any = None, max_steps: int | None = None,
                    euler_rates: Sequence[tuple[float, float] | None] | None = None
                    ) -> list[Trajectory | IntegrationError] | None:
    """[the trajectory of point i, or the error its run stops with] for the M points ``y0`` (M, n) with
    parameter values ``params`` (M, n_par), at the common output times ``t``; None without a C compiler.

    ``rtol`` and ``atol`` (default ``rtol * 1e-3``, point by point) are scalars or (M,); ``track``:
    the half-angles (σ0, δ0) of each point (M, 2) to follow (the term must have a quaternion);
    ``euler_rates``: each point's (φ̇0, ψ̇0) or None, as :func:`~.driver.integrate` takes them.  Point i's
    result equals ``integrate(term, y0[i], t, params[i], rtol=rtol[i], atol=atol[i], backend="c", ...)``
    bit for bit, its ``wall`` excepted (the batch's wall time shared equally).
    """
    compiled = _compiled(term)
    if compiled is None:
        return None
    t = np.asarray(t, dtype=float)
    y0 = np.asarray(y0, dtype=float)
    m = len(y0)
    par = np.asarray(params, dtype=float).reshape(m, -1)
    rt = np.broadcast_to(np.asarray(rtol, dtype=float), (m,))
    at = rt * 1e-3 if atol is None else np.broadcast_to(np.asarray(atol, dtype=float), (m,))
    tracking = None
    if track is not None:
        if term.quaternion is None:
            raise IntegrationError(f"expected a term with a quaternion to track, got term {term.name!r} without one")
        tracking = (term.quaternion, np.asarray(track, dtype=float).reshape(m, 2))
    with np.errstate(all="ignore"):  # a state out of range is said by the checks, not as RuntimeWarnings
        main = compiled.solve_batch(t, y0, par, rt, at, max_steps=max_steps, track=tracking)
        out: list[Any] = list(main.errors)
        ok = [i for i in range(m) if out[i] is None]
        ref, refs = None, {}
        if estimate_error and ok:
            # each point's reference at its own tolerances, as run_dop853 makes it
            refs = {i: reference_run("compiled DOP853", float(rt[i]), float(at[i])) for i in ok}
            ref = compiled.solve_batch(t, y0[ok], par[ok], [refs[i][0] for i in ok], [refs[i][1] for i in ok],
                                       max_steps=max_steps,
                                       track=None if tracking is None else (tracking[0], tracking[1][ok]))
        wall = main.wall / max(m, 1)
        for j, i in enumerate(ok):
            info = main.info(i)
            reference, kind, factor = None, "not requested", 1.0
            if ref is not None:
                if ref.errors[j] is not None:
                    out[i] = ref.errors[j]
                    continue
                r = ref.info(j)
                reference, kind, factor = (ref.y[j], r.get("args"), r.get("near")), f"distance to {refs[i][3]}", \
                    refs[i][2]
            run = _Run(y=main.y[i], args=info.get("args"), closest=info.get("closest"), near=info.get("near"),
                       nfev=info["nfev"], steps=info["steps"], wall=wall, backend="c", ref=reference, factor=factor,
                       kind=kind)
            rates = None if euler_rates is None else euler_rates[i]
            out[i] = _trajectory(term, t, tuple(float(x) for x in par[i]), run, "DOP853", None, rates)
    return out


def integrate_to_rtol_batch(run: Callable[[np.ndarray, np.ndarray], list | None],
                            estimate: Callable[[Any, int], float | None], rtol: float,
                            m: int) -> list[tuple[Any, list[dict]] | MechDeriveError] | None:
    """[(the last run of point i, one record per attempt), or the error that stopped it] for M points.

    ``run(tolerances, points)`` runs the points (indices into 0 … M − 1) each at its tolerance and
    returns their results in that order (a result, or a :class:`~mechderive.errors.MechDeriveError` in
    its place), or None where the batch cannot run (no C compiler: then so does this);
    ``estimate(result, point)`` measures a point's run.  Each point
    follows :func:`~.driver.integrate_to_rtol`'s rule on its own estimates: the same tolerances, the
    same runs, the same last run.
    """
    tol = np.full(m, float(rtol))
    attempts: list[list[dict]] = [[] for _ in range(m)]
    done: list[Any] = [None] * m
    pending = np.arange(m)
    while pending.size:
        results = run(tol[pending], pending)
        if results is None:
            return None
        again = []
        for i, result in zip(pending, results):
            if isinstance(result, MechDeriveError):
                done[i] = result
                continue
            try:
                est = estimate(result, int(i))
            except MechDeriveError as exc:
                done[i] = exc
                continue
            attempts[i].append({"integrator_rtol": float(tol[i]), "error_estimate": est})
            following = next_tolerance(float(tol[i]), est, rtol, len(attempts[i]))
            if following is None:
                done[i] = (result, attempts[i])
            else:
                tol[i] = following
                again.append(i)
        pending = np.array(again, dtype=int)
    return done
