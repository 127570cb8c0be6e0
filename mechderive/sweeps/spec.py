"""The sweep file: a scene plus a ``[sweep]`` table of the values to vary.

A sweep file is a scene (:mod:`mechderive.scenes.schema`) with one more table::

    [sweep]
    grid = { theta = [0.05, 3.09, 200], psi_dot = [0.5, 40.0, 200] }   # start, stop, count (linspace)
    # or: random = { samples = 1000000, seed = 1, theta = [0.05, 3.09], psi_dot = [0.5, 40.0] }
    summary = ["motion_class", "nutation_period", "theta_min", "error_estimate"]
    chunk = 10000          # optional: points per chunk (default 10000 for a system with a batched
                           # closed form, 100 for a batched integration, 10 otherwise; a small sweep in
                           # ~64 chunks, at least 10 points each)

Each swept key is a key of the scene's ``[parameters]`` or ``[initial]`` (``"parameters.I1"`` where
the name is in both; ``"omega[1]"`` for an entry of a vector key).  Start and stop may carry units
("5 deg"), converted to the key's SI unit as a scene's values are.  ``summary`` names the system's
per-motion quantities (``mechderive scenes --quantities SYSTEM``) and optionally ``error_estimate``
(each point's largest relative estimate, always written).  ``[time]`` and ``[output]`` may be left out
for a system with a closed form (the summaries do not depend on them; defaults: ``t_end = 1``,
``samples = 2``, the system's first quantity); a system that integrates measures its summaries on the
trajectory ``[time]`` asks for, so it needs the table.

The points are a pure function of the file: a grid's rows in C order over the axes (the last varies
fastest), a random sweep's chunk k drawn from ``numpy.random.default_rng([seed, k])``.  Chunking is
fixed by the file too, so the table is the same, bit for bit, whatever runs the chunks.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InvalidInputError
from ..scenes.schema import Scene, _parse_toml, _read_file, parse_scene

__all__ = ["Axis", "Sweep", "load_sweep", "parse_sweep", "has_batch", "MAX_POINTS"]

#: the most points one sweep file may ask for (a table of 10^9 rows is a cluster's job, chunk by chunk)
MAX_POINTS = 10**10
#: points per chunk where the system answers a batch in NumPy, and where each point is a planner run
BATCH_CHUNK, POINT_CHUNK = 10_000, 10
_SWEEP_KEYS = ("grid", "random", "summary", "chunk")
#: the sweep-level column a summary list may name besides the system's quantities
ERROR_ESTIMATE = "error_estimate"
_VECTOR = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\[(\d+)\]$")


@dataclass(frozen=True)
class Axis:
    """One swept key: its column name, where it lives in the scene, and its range in SI units."""

    name: str            # the column's name, as the sweep file spells the key
    table: str           # "parameters" or "initial"
    key: str             # the key in that table
    index: int | None    # the entry of a vector key, else None
    unit: str            # the key's SI unit ("rad", "rad/s", "kg m^2", ...)
    start: float
    stop: float
    count: int = 0       # grid: the number of values (linspace, both ends); random: 0

    def values(self) -> np.ndarray:
        """The grid's values along this axis."""
        return np.linspace(self.start, self.stop, self.count)


@dataclass(frozen=True)
class Sweep:
    """A checked sweep: the base scene, the axes, the summaries and the chunking."""

    document: dict            # the scene's TOML document without [sweep], with [time]/[output] filled in
    scene: Scene              # the base scene, checked
    axes: tuple[Axis, ...]
    kind: str                 # "grid" or "random"
    points: int
    seed: int | None
    summary: tuple[str, ...]  # the system's quantities (error_estimate is written always)
    chunk: int
    name: str = ""
    source: dict = field(default_factory=dict, compare=False)  # the file's whole document, [sweep] included
    fingerprint: str = field(default="", compare=False)

    @property
    def chunks(self) -> int:
        return -(-self.points // self.chunk)

    def chunk_rows(self, k: int) -> range:
        if not 0 <= k < self.chunks:
            raise InvalidInputError(f"expected a chunk index in [0, {self.chunks}), got {k}")
        return range(k * self.chunk, min((k + 1) * self.chunk, self.points))

    def chunk_values(self, k: int) -> dict[str, np.ndarray]:
        """{axis name: its values at the rows of chunk ``k``} — the same whoever asks, whenever."""
        rows = self.chunk_rows(k)
        if self.kind == "grid":
            index = np.unravel_index(np.arange(rows.start, rows.stop), tuple(a.count for a in self.axes))
            return {a.name: a.values()[i] for a, i in zip(self.axes, index)}
        rng = np.random.default_rng([int(self.seed or 0), k])
        n = len(rows)
        return {a.name: a.start + (a.stop - a.start) * rng.random(n) for a in self.axes}

    def point_document(self, values: Mapping[str, float]) -> dict:
        """The scene document of one point: the base with the swept keys set to ``values`` (SI)."""
        doc = copy.deepcopy(self.document)
        for a in self.axes:
            table = doc.setdefault(a.table, {})
            if a.index is None:
                table[a.key] = float(values[a.name])
            else:
                vec = list(self.scene_value(a))
                vec[a.index] = float(values[a.name])
                table[a.key] = vec
        return doc

    def scene_value(self, axis: Axis) -> Any:
        table = self.scene.parameters if axis.table == "parameters" else self.scene.initial
        value = table[axis.key]
        return [float(x) for x in np.ravel(value)] if axis.index is not None else float(value)

    def batch_inputs(self, values: Mapping[str, np.ndarray]) -> tuple[dict, dict]:
        """(parameters, initial) of the checked base scene with the swept keys as arrays of the chunk's values."""
        n = len(next(iter(values.values())))
        out = []
        for which, base in (("parameters", self.scene.parameters), ("initial", self.scene.initial)):
            table = {}
            for k, v in base.items():
                arr = np.asarray(v, dtype=float)
                table[k] = np.broadcast_to(arr, (n, *arr.shape)).copy()
            for a in self.axes:
                if a.table == which:
                    if a.index is None:
                        table[a.key] = np.asarray(values[a.name], dtype=float)
                    else:
                        table[a.key][:, a.index] = values[a.name]
            out.append(table)
        return out[0], out[1]


def _fail(where: str, expected: str, got: Any) -> InvalidInputError:
    return InvalidInputError(f"sweep {where}: expected {expected}, got {got!r}")


def _number(where: str, value: Any, unit: str) -> float:
    from ..scenes.units import is_unit_string, to_si

    if is_unit_string(value):
        return to_si(f"sweep {where}", value, unit)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)):
        raise _fail(where, "a finite number (or a string with a unit, e.g. \"5 deg\")", value)
    return float(value)


def _count(where: str, value: Any, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise _fail(where, f"an integer in [{lo}, {hi}]", value)
    return value


def _axis(scene: Scene, name: str, spec: Any, kind: str) -> Axis:
    model = scene.model
    keys = {"parameters": {k.name: k for k in model.parameters}, "initial": {k.name: k for k in model.initial}}
    table, key = None, name
    if "." in name:
        table, _, key = name.partition(".")
        if table not in keys:
            raise _fail(f"key {name!r}", "a table prefix 'parameters.' or 'initial.'", table)
    match = _VECTOR.match(key)
    index = None
    if match:
        key, index = match.group(1), int(match.group(2))
    found = [t for t in keys if key in keys[t] and (table is None or t == table)]
    allowed = sorted({*keys["parameters"], *keys["initial"]})
    if not found:
        raise InvalidInputError(f"sweep key {name!r}: expected a key of [parameters] or [initial] of system "
                                f"{scene.system!r} ({', '.join(allowed)}), got {key!r}")
    if len(found) > 1:
        raise InvalidInputError(f"sweep key {name!r}: in both [parameters] and [initial]; write "
                                f"'parameters.{key}' or 'initial.{key}'")
    table = found[0]
    k = keys[table][key]
    current = (scene.parameters if table == "parameters" else scene.initial).get(key)
    size = int(np.size(current)) if current is not None else int(getattr(k, "size", 0) or 0)
    vector = current is not None and np.ndim(current) > 0
    if vector and index is None:
        raise InvalidInputError(f"sweep key {name!r}: {key} is a vector of {size}; sweep one entry, "
                                f"e.g. '{key}[0]'")
    if index is not None and (not vector or index >= size):
        raise InvalidInputError(f"sweep key {name!r}: expected an entry index of a vector key below {size}, "
                                f"got {key}[{index}]")
    if kind == "grid":
        if not isinstance(spec, list) or len(spec) != 3:
            raise _fail(f"grid.{name}", "[start, stop, count]", spec)
        start, stop = (_number(f"grid.{name}", v, k.unit) for v in spec[:2])
        count = _count(f"grid.{name} count", spec[2], 1, 10**7)
        if count > 1 and not start < stop:
            raise _fail(f"grid.{name}", "start < stop", spec)
        return Axis(name, table, key, index, k.unit, start, stop, count)
    if not isinstance(spec, list) or len(spec) != 2:
        raise _fail(f"random.{name}", "[low, high]", spec)
    low, high = (_number(f"random.{name}", v, k.unit) for v in spec)
    if not low < high:
        raise _fail(f"random.{name}", "low < high", spec)
    return Axis(name, table, key, index, k.unit, low, high)


def parse_sweep(document: Mapping[str, Any], *, name: str = "") -> Sweep:
    """Check a parsed sweep document (a scene's mapping with a ``[sweep]`` table) and return its :class:`Sweep`."""
    from ..systems import registry

    if not isinstance(document, Mapping) or "sweep" not in document:
        raise InvalidInputError("sweep: expected a scene with a [sweep] table (grid = {...} or random = {...})")
    doc = {k: copy.deepcopy(v) for k, v in document.items() if k != "sweep"}
    table = document["sweep"]
    if not isinstance(table, Mapping):
        raise _fail("[sweep]", "a table", table)
    unknown = [k for k in table if k not in _SWEEP_KEYS]
    if unknown:
        raise InvalidInputError(f"sweep key {unknown[0]!r}: unknown; expected {', '.join(_SWEEP_KEYS)}")
    if ("grid" in table) == ("random" in table):
        raise InvalidInputError("sweep: expected exactly one of grid = {...} or random = {...}")
    system = registry.get(doc["system"]) if isinstance(doc.get("system"), str) and \
        doc["system"] in registry.names() else None
    closed = system is not None and "exact" in system.methods
    if "time" not in doc and closed:
        doc["time"] = {"t_end": 1.0, "samples": 2}
    output = dict(doc.get("output") or {})
    if "output" not in doc and system is not None and system.quantities:
        output = {"quantities": [system.quantities[0].name]}
    summary = table.get("summary", [])
    if not isinstance(summary, list) or not all(isinstance(s, str) for s in summary):
        raise _fail("summary", "a list of per-motion quantity names", summary)
    if len(set(summary)) != len(summary):
        raise _fail("summary", "each name once", summary)
    quantities = [s for s in summary if s != ERROR_ESTIMATE]
    if not quantities:
        raise InvalidInputError("sweep summary: expected at least one per-motion quantity of the system "
                                "(`mechderive scenes --quantities SYSTEM` lists them)")
    output["summary"] = quantities
    doc["output"] = output
    try:
        scene = parse_scene(doc, name=name or None)
    except InvalidInputError as exc:  # the summary list is the sweep's, wherever the scene checks it
        raise InvalidInputError(str(exc).replace("scene key [output].summary", "sweep key summary")) from None
    kind = "grid" if "grid" in table else "random"
    spec = table[kind]
    if not isinstance(spec, Mapping):
        raise _fail(kind, "a table of swept keys", spec)
    seed = None
    if kind == "random":
        spec = dict(spec)
        samples = _count("random.samples", spec.pop("samples", None), 1, MAX_POINTS)
        seed = _count("random.seed", spec.pop("seed", 0), 0, 2**63 - 1)
    if not spec:
        raise _fail(kind, "at least one swept key", dict(spec))
    axes = tuple(_axis(scene, k, v, kind) for k, v in spec.items())
    if len({(a.table, a.key, a.index) for a in axes}) != len(axes):
        raise InvalidInputError("sweep: a key is swept twice")
    points = math.prod(a.count for a in axes) if kind == "grid" else samples  # Python ints: no overflow
    if points > MAX_POINTS:
        raise InvalidInputError(f"sweep: expected at most {MAX_POINTS:.0e} points, got {points}")
    # a small sweep is still cut into ~64 chunks so that every worker has some (a function of the file alone)
    default_chunk = min(batch_chunk(scene.model), max(10, -(-points // 64)))
    chunk = _count("chunk", table.get("chunk", default_chunk), 1, 10**7)
    sweep = Sweep(doc, scene, axes, kind, points, seed, tuple(quantities), chunk, name=scene.name or "",
                  source=copy.deepcopy(dict(document)))
    return _with_fingerprint(sweep)


def has_batch(model: Any) -> bool:
    """Whether the system ``model`` answers chunks in NumPy (overrides :meth:`System.summarize_batch`)."""
    from ..systems.base import System

    return type(model).summarize_batch is not System.summarize_batch


def batch_chunk(model: Any) -> int:
    """Points per chunk by default: the system's ``batch_chunk`` where it answers a batch (a closed form's
    :data:`BATCH_CHUNK`; fewer for a system that integrates), else :data:`POINT_CHUNK`."""
    return int(getattr(model, "batch_chunk", BATCH_CHUNK)) if has_batch(model) else POINT_CHUNK


def _with_fingerprint(sweep: Sweep) -> Sweep:
    """The sweep with a hash of everything the table depends on (the resume check)."""
    from .. import __version__

    payload = json.dumps({"document": sweep.document, "axes": [a.__dict__ for a in sweep.axes], "kind": sweep.kind,
                          "points": sweep.points, "seed": sweep.seed, "summary": sweep.summary,
                          "chunk": sweep.chunk, "version": __version__}, sort_keys=True, default=repr)
    object.__setattr__(sweep, "fingerprint", hashlib.sha256(payload.encode()).hexdigest()[:16])
    return sweep


def load_sweep(path: os.PathLike | str) -> Sweep:
    """Read and check a sweep file (TOML): a scene with a ``[sweep]`` table."""
    path = Path(path)
    source = f"file {str(path)!r}"
    document = _parse_toml(_read_file(path, source), source)
    stem = path.stem
    return parse_sweep(document, name=document.get("name") or (stem if 0 < len(stem) <= 100 else ""))
