"""A sweep's chunk of rigid bodies that integrate: their runs batched, their summaries measured as one run's.

:func:`summarize_batch` answers the points that a single run integrates — every point of a scene with
``method = "integrate"``; with ``method = "auto"``, those no closed form applies to
(:func:`.motion.closed_form_plan`) — by :func:`.motion.integrate_bodies` (each motion equal to
:func:`.motion.integrate_body`'s bit for bit) and :meth:`.system.RigidBody.summarize` on each: the
period measured on the trajectory, E, L·ẽ3 and p_ψ with their variation along the run.  The points
a closed form answers, the points the body's checks refuse, and those whose run stops (an error the
planner words with the scene's keys) are left to the planner (``fallback``).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ...errors import MechDeriveError
from ..base import BatchSummary, OutOfReach
from ..batch_points import batch_summary, common_times, point_scenes

__all__ = ["summarize_batch"]


def summarize_batch(system: Any, scene: Any, parameters: Mapping[str, np.ndarray], initial: Mapping[str, np.ndarray],
                    names: tuple[str, ...]) -> BatchSummary | None:
    """The per-motion quantities ``names`` of the chunk's points (:meth:`~..base.System.summarize_batch`), each
    from its batched run; None where no point can be batched (method "exact", times that depend on the
    point, no C compiler)."""
    from . import motion as mo

    t = common_times(scene)
    if t is None or scene.method == "exact":
        return None
    scenes = point_scenes(system, scene, parameters, initial)
    quantities = tuple(scene.quantities)
    need = tuple(k for k in mo.families(quantities) if k != "quaternion")
    todo, bodies = [], []
    for i, point in enumerate(scenes):
        if point is None:
            continue
        body = system.body(point.parameters)
        if "p_psi" in quantities and not mo.conserved_axial(body)[2]:
            continue  # refused by solve: the planner says why
        if scene.method == "auto":
            try:
                mo.closed_form_plan(body, point.initial)
                continue  # a closed form answers this point: the planner runs it
            except OutOfReach:
                pass
        todo.append(i)
        bodies.append(body)
    answers: list[Any] = [None] * len(scenes)
    if todo:
        motions = mo.integrate_bodies(bodies, [scenes[i].initial for i in todo], t, scene.rtol, need=need)
        if motions is None:
            return None
        for i, body, motion in zip(todo, bodies, motions):
            if isinstance(motion, MechDeriveError):
                continue
            try:
                answers[i] = system.summarize(scenes[i], system.solved(quantities, motion, body), t, names)
            except MechDeriveError:
                continue
    return batch_summary(names, answers)
