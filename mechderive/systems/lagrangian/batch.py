"""A sweep's chunk of a Lagrangian system that integrates: its runs batched, its summaries measured as one run's.

:func:`summarize_batch` answers the points a single run integrates — every point with ``method =
"integrate"``; with ``method = "auto"``, every point of a system whose Lagrangian has no reduction to a
quadrature (else the closed form answers, point by point through the planner) — by integrating them
together (:func:`mechderive.solvers.batch.integrate_batch`, each trajectory equal to the single run's
bit for bit, rerun tighter point by point as :func:`~mechderive.solvers.driver.integrate_to_rtol` does)
and measuring each point's summaries with :meth:`.system.LagrangianSystem.summarize`.  Points the
system's checks refuse, and runs that stop, are left to the planner (``fallback``), which words why.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ...errors import MechDeriveError
from ..base import BatchSummary
from ..batch_points import batch_summary, common_times, point_scenes

__all__ = ["summarize_batch"]


def summarize_batch(system: Any, scene: Any, parameters: Mapping[str, np.ndarray], initial: Mapping[str, np.ndarray],
                    names: tuple[str, ...]) -> BatchSummary | None:
    """The per-motion quantities ``names`` of the chunk's points (:meth:`~..base.System.summarize_batch`), each
    from its batched run; None where the points do not integrate, or their times depend on the point, or
    there is no C compiler."""
    from ...solvers.batch import integrate_batch, integrate_to_rtol_batch

    t = common_times(scene)
    if t is None or scene.method == "exact" or (scene.method == "auto" and system.reduction()[0] is not None):
        return None
    scenes = point_scenes(system, scene, parameters, initial)
    todo = [i for i, point in enumerate(scenes) if point is not None]
    answers: list[Any] = [None] * len(scenes)
    if todo:
        starts = [system.integration_start(scenes[i], t) for i in todo]
        y0 = np.array([s[0] for s in starts], dtype=float)
        par = np.array([s[1] for s in starts], dtype=float).reshape(len(todo), -1)
        wanted = tuple(scene.quantities)
        term = system.equations.term

        def run(tols: np.ndarray, points: np.ndarray) -> list | None:
            return integrate_batch(term, y0[points], t, par[points], rtol=tols)

        def estimate(traj: Any, k: int) -> float | None:
            return system._error_estimate(traj, wanted, starts[k][1], starts[k][2])

        done = integrate_to_rtol_batch(run, estimate, scene.rtol, len(todo))
        if done is None:
            return None
        for k, (i, result) in enumerate(zip(todo, done)):
            if isinstance(result, MechDeriveError):
                continue
            try:
                solved = system.integrated(result[0], result[1], wanted, starts[k][2])
                answers[i] = system.summarize(scenes[i], solved, t, names)
            except MechDeriveError:
                continue
    return batch_summary(names, answers)
