"""One chunk of a sweep: its points' per-motion quantities, batched where the system can, else one by one.

A chunk's table has, per row: the swept values; for each requested quantity its value and
``<name>_error`` (the measured estimate, in the quantity's unit); ``error_estimate``, the largest
relative estimate of the row's numbers (an estimate over |value|; the estimate itself where the value
is 0); ``status`` — ``ok`` or ``refused: <the reason>`` (an unphysical body, a motion no double can
follow: the planner's own message); ``path`` — ``batch`` where the system's NumPy batch answered,
``point`` where the planner ran the point (the batch's ill-conditioned points, or a system without a
batch); and ``notes``, the reasons of quantities that do not apply to the point (``name: why; ...``).

Values that are not numbers are text: a class as is, a table of values (``steady``, ``stability``)
as JSON.  Nothing here depends on which process runs the chunk or when: the table of chunk k is a
function of the sweep file and k.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from ..errors import MechDeriveError
from .spec import ERROR_ESTIMATE, Sweep, has_batch

__all__ = ["evaluate_chunk", "summarize_batch", "BASE_COLUMNS"]

#: the columns every sweep table has after the swept values and the quantities
BASE_COLUMNS = (ERROR_ESTIMATE, "status", "path", "notes")


def _text(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, dict):
        return json.dumps(value, sort_keys=True, default=_jsonable)
    return json.dumps(value, default=_jsonable)


def _jsonable(x: Any) -> Any:
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return repr(x)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)


def _run_point(sweep: Sweep, values: dict[str, float]) -> tuple[str, dict[str, Any], dict[str, Any]]:
    """(status, {name: value}, {name: estimate or reason}) of one point, through the planner."""
    from ..scenes.planner import run_scene
    from ..scenes.schema import parse_scene

    try:
        result = run_scene(parse_scene(sweep.point_document(values), name=sweep.name or None))
    except MechDeriveError as exc:
        return f"refused: {exc}", {}, {}
    report = result.report
    return "ok", dict(report.get("summary", {})), dict(report.get("summary_error", {}))


def _takes_scene(model: Any) -> bool:
    """Whether the system's ``summarize_batch`` takes the sweep's scene (a system registered before the
    keyword existed is called as it was written)."""
    import inspect

    params = inspect.signature(model.summarize_batch).parameters
    return "scene" in params or any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())


def summarize_batch(sweep: Sweep, parameters: dict, initial: dict) -> Any:
    """The system's :meth:`~mechderive.systems.base.System.summarize_batch` of these points, with the sweep's scene
    where it takes it."""
    model = sweep.scene.model
    return model.summarize_batch(parameters, initial, sweep.summary, strict=sweep.scene.strict,
                                 **({"scene": sweep.scene} if _takes_scene(model) else {}))


def evaluate_chunk(sweep: Sweep, k: int) -> dict[str, np.ndarray]:
    """The table (column name → array) of chunk ``k`` of ``sweep``."""
    swept = sweep.chunk_values(k)
    n = len(sweep.chunk_rows(k))
    names = sweep.summary
    # a quantity's column: float64 while every value is a number (NaN: none), object (text) otherwise
    columns: dict[str, np.ndarray] = {name: np.full(n, math.nan) for name in names}
    errors: dict[str, np.ndarray] = {name: np.full(n, math.nan) for name in names}
    status = np.full(n, "ok", dtype=object)
    path = np.full(n, "point", dtype=object)
    notes = np.full(n, "", dtype=object)
    todo: np.ndarray = np.arange(n)
    model = sweep.scene.model
    if n and has_batch(model):
        parameters, initial = sweep.batch_inputs(swept)
        batch = summarize_batch(sweep, parameters, initial)
        if batch is not None:
            fallback = np.asarray(batch.fallback, dtype=bool)
            for name in names:
                if name not in batch.values:
                    continue
                vals = np.asarray(batch.values[name])
                if vals.dtype.kind in "fiu":
                    columns[name] = np.where(fallback, math.nan, vals.astype(float))
                else:  # a class as is, a table of values (a dict) as JSON, as the one-by-one points write them
                    columns[name] = np.array(["" if f else (v if isinstance(v, str) else _text(v))
                                              for f, v in zip(fallback, vals)], dtype=object)
                errors[name] = np.where(fallback, math.nan, np.asarray(batch.errors[name], dtype=float))
            for name, why in (batch.reasons or {}).items():
                if name not in columns:
                    continue
                why = np.asarray(why, dtype=object)
                absent = ~fallback & np.array([isinstance(w, str) for w in why], dtype=bool)
                if absent.any():
                    columns[name][absent] = math.nan if columns[name].dtype == float else ""
                    errors[name][absent] = math.nan
                    for i in np.flatnonzero(absent):
                        notes[i] = f"{notes[i]}; {name}: {why[i]}" if notes[i] else f"{name}: {why[i]}"
            path[~fallback] = "batch"
            todo = np.flatnonzero(fallback)
    for i in todo:
        st, vals, errs = _run_point(sweep, {a: float(v[i]) for a, v in swept.items()})
        status[i] = st
        why = []
        for name in names:
            value, err = vals.get(name), errs.get(name)
            if value is None:
                if isinstance(err, str):
                    why.append(f"{name}: {err}")
                continue
            if _is_number(value) and columns[name].dtype == float:
                columns[name][i] = float(value)
            else:
                if columns[name].dtype == float:
                    columns[name] = np.array(["" if math.isnan(x) else repr(float(x)) for x in columns[name]],
                                             dtype=object)
                columns[name][i] = _text(value)
            if _is_number(err):
                errors[name][i] = float(err)
        notes[i] = "; ".join(why)
    table: dict[str, np.ndarray] = {a: np.asarray(v, dtype=float) for a, v in swept.items()}
    worst = np.full(n, math.nan)
    for name in names:
        col, err = columns[name], errors[name]
        if col.dtype == float:
            with np.errstate(all="ignore"):
                worst = np.fmax(worst, np.where(col != 0, err / np.abs(col), err))
        table[name] = col
        table[f"{name}_error"] = err
    table[ERROR_ESTIMATE] = worst
    table["status"], table["path"], table["notes"] = status, path, notes
    return table
