"""A sweep's chunk of a system that integrates, as the planner would run each point — without the planner.

A system without a closed form answers :meth:`~.base.System.summarize_batch` by integrating its
points together (:mod:`mechderive.solvers.batch`) and measuring each point's summaries with its own
:meth:`~.base.System.summarize` on that point's trajectory — the very code a single run uses, on a
trajectory equal to the single run's bit for bit, so the batched values are the one-by-one values.
What the batch saves is the rest of a planner run: reading the point's scene document, the scene's
checks of everything the sweep does not vary, one ctypes call per run and per rerun.

This module holds what every such system needs:

* :func:`common_times` — the output times every point of the sweep shares, or None where a point's
  times depend on its motion (``samples_per_period``) or do not start at t = 0 (the planner then
  solves from 0 and drops a sample): those sweeps run one by one;
* :func:`point_scenes` — each point's scene: the sweep's checked scene with the point's
  ``[parameters]`` and ``[initial]`` checked by the system as the scene would check them (None for
  a point the system refuses, or one solved in units of its own motion: the planner says why, or
  converts);
* :func:`batch_summary` — each answered point's {name: (value, estimate)} as a
  :class:`~.base.BatchSummary`, every other point marked ``fallback``.
"""

from __future__ import annotations

import copy
from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import MechDeriveError
from .base import BatchSummary, System

__all__ = ["common_times", "point_scenes", "batch_summary"]


def common_times(scene: Any) -> np.ndarray | None:
    """The output times of every point of a sweep of ``scene``, or None where they are not one array from 0."""
    if scene.samples_per_period is not None or scene.times_given is not None or scene.t_start != 0:
        return None
    from .scaling import check_samples

    t = scene.times()
    try:
        check_samples(scene, t)
    except MechDeriveError:
        return None
    return t


def _row(values: Mapping[str, np.ndarray], i: int) -> dict:
    """Point ``i`` of a chunk's arrays: a number per key, a tuple for a vector key."""
    return {k: (float(v[i]) if np.ndim(v) == 1 else tuple(float(x) for x in v[i])) for k, v in values.items()}


def point_scenes(model: System, scene: Any, parameters: Mapping[str, np.ndarray],
                 initial: Mapping[str, np.ndarray]) -> list[Any]:
    """Each point's scene (``scene`` with the point's values, checked by ``model`` as the scene checks
    them), or None where the system refuses the point or would solve it in other units."""
    n = len(next(iter(initial.values()))) if initial else len(next(iter(parameters.values())))
    scaled_by_model = type(model).scale is not System.scale
    out: list[Any] = []
    for i in range(n):
        try:
            p = model.check_parameters(_row(parameters, i), strict=scene.strict)
            q = model.check_initial(_row(initial, i), p)
        except MechDeriveError:
            out.append(None)
            continue
        point = copy.copy(scene)  # the sweep's scene, checked once; only the point's values differ
        object.__setattr__(point, "parameters", p)
        object.__setattr__(point, "initial", q)
        if scaled_by_model:
            try:
                if not model.scale(point).identity:
                    point = None
            except MechDeriveError:
                point = None
        out.append(point)
    return out


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)


def batch_summary(names: Sequence[str], answers: Sequence[Mapping[str, tuple[Any, Any]] | None]) -> BatchSummary:
    """The :class:`~.base.BatchSummary` of ``answers``: point i's {name: (value, estimate)} from the system's
    own ``summarize``, or None (fallback).  A value that is not a number (a class, a table) is left to the
    planner too, which writes it as text."""
    n = len(answers)
    values = {name: np.full(n, np.nan) for name in names}
    errors = {name: np.full(n, np.nan) for name in names}
    reasons = {name: np.full(n, None, dtype=object) for name in names}
    fallback = np.ones(n, dtype=bool)
    for i, answer in enumerate(answers):
        if answer is None or any(answer[name][0] is not None and not _is_number(answer[name][0]) for name in names):
            continue
        fallback[i] = False
        for name in names:
            value, error = answer[name]
            if value is None:
                reasons[name][i] = error if isinstance(error, str) else None
                continue
            values[name][i] = float(value)
            if _is_number(error):
                errors[name][i] = float(error)
    return BatchSummary(values, errors, fallback, reasons)
