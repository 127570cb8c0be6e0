"""The scene file of ``mechderive run``: a TOML description of one motion to compute.

A scene is DATA.  It is read with the standard library's :mod:`tomllib` and every
value is checked against a fixed set of names and ranges; nothing in it is ever
evaluated as code (no ``eval``, no ``sympify``), so a string such as
``"__import__('os')"`` is only ever a wrong value, refused with a message.

The format (optional keys marked)::

    name = "my top"           # optional: a printable label (1-100 characters)
    system = "heavy_top"      # a registered system: `mechderive scenes --systems` lists them
    method = "auto"           # optional: "auto" | "exact" | "integrate" (default "auto")
    rtol = 1e-10              # optional: relative accuracy in [1e-15, 1e-2] (default 1e-9)
    strict = false            # optional (default true): accept moments no rigid body has (see below)

    [parameters]              # the system's own keys, checked by the system (heavy_top: I1 I3 M g l,
                              # or I1 I3 Mgl; free_top: I1 I2 I3; falling_cat: optional, open)
    I1 = 1.0
    ...

    [initial]                 # heavy_top: theta phi psi theta_dot phi_dot psi_dot (rad, rad/s)
    ...                       # free_top: omega = [w1, w2, w3] (body frame, rad/s), optional phi theta psi

    [time]
    t_end = 10.0              # > t_start
    samples = 1001            # equally spaced on [t_start, t_end], both ends included; 2 <= samples <= 10^7,
                              # and the run at most MAX_RUN_BYTES (1 GB, below)
    t_start = 0.0             # optional: the first output time, in [0, t_end) (default 0)
    samples_per_period = 200  # instead of samples, for a system that knows its period before solving
                              # (the heavy top's nutation, the free top's polhode): samples =
                              # ceil((t_end - t_start) / period × N) + 1
    # or, instead of all of these:
    times = [0.0, 0.5, 2.0]   # explicit output times: finite, >= 0, strictly increasing, 2 to 10^7 of them

    The ``[initial]`` values are at t = 0 whatever the output times: ``t_start`` skips the start of
    the motion, it does not move the launch.  A system whose motion is defined over its own duration
    (the falling cat: :attr:`~mechderive.systems.base.System.free_times` False) takes only ``t_end`` and
    ``samples``.

    [output]
    quantities = ["theta", "phi", "psi"]   # names from QUANTITIES[system], each once
                                           # (`mechderive scenes --quantities SYSTEM` lists them)
    summary = ["nutation_period", "theta_min"]   # optional: per-motion quantities of the system,
                                           # each once (listed by the same command)

    coordinates = [...]       # a system's own top-level keys and tables (its ``extra_keys``), if any

``strict = false`` waives the rigid-body conditions — the triangle inequalities of a free
top's moments, a heavy top's I1 - M l² ≥ I3/2 (I1 ≥ I3/2 with ``Mgl``) — which published
benchmarks break (moments (3, 3, 9); a heavy top with I1 < M l²); the run's report lists
what was waived.  Positive, finite values are required all the same.  A heavy top's
``Mgl`` replaces ``M``, ``g`` and ``l`` (only their product enters the motion): give it
or all three, never both.

Numbers are finite doubles: ``nan``, ``inf`` and any number spelled beyond the largest double
(``1e400``, an integer of 400 digits — TOML integers have no size limit) are refused naming
their key; a nonzero literal below the smallest double (``1e-400``) is 0.  Integers are accepted
for floats.  The ranges of each key are those above; the systems' own checks (whose messages
are re-worded to name the scene keys) may refuse more, e.g. a motion no double can follow.

A scene's size is estimated before anything is solved (:attr:`Scene.size_estimate`): the run's
peak memory (the solver's measured working memory per sample, plus the table) and its table as
CSV must each stay within :data:`MAX_RUN_BYTES` (1 GB), else ``[time].samples`` is refused with
the estimate and the most samples these quantities allow.  Scene files must be regular files
(not a FIFO, a device or a directory) of at most :data:`MAX_SCENE_BYTES` bytes of UTF-8.

Every refusal is an :class:`~mechderive.errors.InvalidInputError` (or a subclass:
:class:`~mechderive.errors.NonFiniteValueError` for NaN/inf,
:class:`~mechderive.errors.UnphysicalInertiaError` for moments no body can have) whose
message names the key, the value and what is allowed, e.g.
``scene key [parameters].I1: expected a number > 0, got -1.0``.

>>> scene = load_scene('''
... system = "free_top"
... [parameters]
... I1 = 1
... I2 = 2
... I3 = 3
... [initial]
... omega = [1, 0.5, 1]
... [time]
... t_end = 10
... samples = 3
... [output]
... quantities = ["omega1", "energy"]
... ''')
>>> scene.parameters, scene.initial["omega"], scene.times()
({'I1': 1.0, 'I2': 2.0, 'I3': 3.0}, (1.0, 0.5, 1.0), array([ 0.,  5., 10.]))
>>> load_scene(scene_to_toml(scene)) == scene
True
"""

from __future__ import annotations

import math
import os
import re
import stat
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Iterable

import numpy as np

from ..errors import InvalidInputError
from ..systems import registry
from ..systems.base import Key, Quantity, System
from ..systems.scene_keys import NAME_PATTERN as _NAME_PATTERN
from ..systems.scene_keys import Underflowed as _Underflowed
from ..systems.scene_keys import Unrepresentable as _Unrepresentable
from ..systems.scene_keys import as_table as _as_table
from ..systems.scene_keys import check_keys as _check_keys
from ..systems.scene_keys import choice as _choice
from ..systems.scene_keys import fail as _fail
from ..systems.scene_keys import key_name as _key_name
from ..systems.scene_keys import number as _number
from ..systems.scene_keys import one_of as _one_of
from ..systems.scene_keys import show as _show

if TYPE_CHECKING:  # pragma: no cover
    from pathlib import Path

__all__ = [
    "Scene",
    "SizeEstimate",
    "METHODS",
    "QUANTITIES",
    "load_scene",
    "waived",
    "parse_scene",
    "scene_to_toml",
    "register_system_parameters",
    "register_system_quantities",
]

METHODS = ("auto", "exact", "integrate")
DEFAULT_METHOD = "auto"
DEFAULT_RTOL = 1e-9
RTOL_RANGE = (1e-15, 1e-2)
MAX_SAMPLES = 10**7
MAX_NAME_LENGTH = 100
MAX_SCENE_BYTES = 1_000_000  # a scene is a page of text; refuse anything far larger unread

#: The largest run a scene may ask for (bytes): its estimated peak memory, and its table written as CSV,
#: must each stay within it (:attr:`Scene.size_estimate`), so that a scene cannot exhaust a shared machine.
#: The solve's own memory per sample is its system's measured ``bytes_per_sample``.
MAX_RUN_BYTES = 1_000_000_000
#: Memory per value of the table (bytes): the float64 column, the arrays the quantities are taken from and
#: the CSV writer's rows (measured 11-25 per column and sample on top of the solve).
_BYTES_PER_VALUE = 30
#: The CSV file per value (bytes): ``repr`` of a double has at most 24 characters, plus the separator.
_CSV_BYTES_PER_VALUE = 25

TOP_LEVEL_KEYS = ("name", "system", "method", "rtol", "strict")
DEFAULT_STRICT = True
TABLES = ("parameters", "initial", "time", "output")
TIME_KEYS = ("t_end", "samples")
#: every key [time] may hold: ``t_end`` with ``samples`` or ``samples_per_period`` (and ``t_start``), or ``times``
TIME_ALL_KEYS = ("t_end", "samples", "t_start", "samples_per_period", "times")
OUTPUT_KEYS = ("quantities",)
#: optional keys of [output]: ``summary``, the per-motion quantities (turning angles, periods, invariants)
OUTPUT_OPTIONAL_KEYS = ("summary", "units")


class _Quantities(Mapping):
    """system name -> the quantity names a scene of it may ask for, in a fixed order (from the registry)."""

    def __getitem__(self, system: str) -> tuple[str, ...]:
        return registry.get(system).quantity_names()  # an unknown name: InvalidInputError listing the known

    def __contains__(self, system: object) -> bool:
        return system in registry.names()

    def __iter__(self):
        return iter(registry.names())

    def __len__(self) -> int:
        return len(registry.names())


#: The quantity names a scene may ask for, per system, in a fixed order (each system's ``quantities``).
QUANTITIES: Mapping[str, tuple[str, ...]] = _Quantities()


# ----------------------------------------------------------------------------- checks of the scene itself

def _system(value: Any) -> System:
    """The registered system a scene's ``system`` names (refused with the list of those known)."""
    return registry.get(_choice("system", value, registry.names()))


def _needed_tables(system: System) -> tuple[str, ...]:
    """The tables a scene of ``system`` must have: [parameters] and [initial] where it requires a key of
    them, then [time] and [output]."""
    return tuple(t for t, keys in (("parameters", system.parameters), ("initial", system.initial))
                 if any(k.required for k in keys)) + ("time", "output")


def waived(scene: "Scene") -> list[str]:
    """What ``strict = false`` let through for ``scene``: the rigid-body conditions its parameters violate.

    Empty for a strict scene (nothing was waived) and for one whose body is physical anyway.
    """
    if scene.strict:
        return []
    return list(scene.model.waived(scene.parameters))


def _name_list(key: str, what: str, system: str, value: Any, allowed: tuple[str, ...], *,
               empty: bool) -> tuple[str, ...]:
    """``[output].<key>``: a list of the system's ``what`` names (``allowed``), each once; empty if ``empty``."""
    if not isinstance(value, (list, tuple)) or (not value and not empty):
        _fail(f"[output].{key}", f"a {'' if empty else 'non-empty '}list of {what} names (for {system}: "
              f"{_one_of(allowed) if allowed else 'none'})", value)
    seen: set[str] = set()
    for i, q in enumerate(value):
        where = f"[output].{key}[{i}]"
        if not isinstance(q, str):
            _fail(where, f"a {what} name (a string)", q)
        if q not in allowed:
            expected = f"one of {_one_of(allowed)}" if allowed else f"none: this system has no {what}s"
            raise InvalidInputError(f"scene key {where}: unknown {what} {_show(q)} for system {system!r}; "
                                    f"expected {expected}")
        if q in seen:
            raise InvalidInputError(f"scene key {where}: duplicate {what} {q!r}; each may appear once")
        seen.add(q)
    return tuple(value)


def _quantity_list(system: str, value: Any, allowed: tuple[str, ...]) -> tuple[str, ...]:
    """``[output].quantities``: a non-empty list of the system's output columns, each once."""
    return _name_list("quantities", "quantity", system, value, allowed, empty=False)


def _summary_list(system: str, value: Any, allowed: tuple[str, ...]) -> tuple[str, ...]:
    """``[output].summary``: a list (possibly empty) of the system's per-motion quantity names, each once."""
    return _name_list("summary", "per-motion quantity", system, value, allowed, empty=True)


def _in_si(table: str, values: Mapping[str, Any], keys: tuple[Key, ...], given: dict[str, str]) -> dict[str, Any]:
    """``values`` with each string ("30 deg", or in a list) converted to its key's SI unit (:mod:`.units`);
    ``given`` collects the texts as given, by "[table].key".  A table without strings is returned as is
    (and pint is not imported)."""
    from .units import is_unit_string, to_si  # light: pint itself is imported on the first conversion

    if not any(is_unit_string(v) or (isinstance(v, (list, tuple)) and any(is_unit_string(x) for x in v))
               for v in values.values()):
        return dict(values)

    units = {k.name: k.unit for k in keys}
    out = dict(values)
    for name, v in values.items():
        where = f"scene key {table}.{_key_name(name)}"
        if is_unit_string(v):
            out[name] = to_si(where, v, units.get(name, ""))
            given[f"{table}.{name}"] = v
        elif isinstance(v, (list, tuple)) and any(is_unit_string(x) for x in v):
            out[name] = [to_si(f"{where}[{i}]", x, units.get(name, "")) if is_unit_string(x) else x
                         for i, x in enumerate(v)]
            given[f"{table}.{name}"] = "[" + ", ".join(x if isinstance(x, str) else repr(x) for x in v) + "]"
    return out


def _output_units(value: Any, model: System, quantities: tuple[str, ...]) -> dict[str, str]:
    """``[output].units``: {column: unit text}, each column one of the scene's quantities, each unit of its
    dimension (checked, and its factor cached, by :func:`.units.factor_to`)."""
    value = _as_table("[output].units", value or {})
    if not value:
        return {}
    from .units import factor_to

    si = {q.name: q.unit for q in model.quantities}
    for name, unit in value.items():
        where = f"scene key [output].units.{_key_name(name)}"
        if name not in quantities:
            raise InvalidInputError(f"{where}: expected one of the scene's quantities ({_one_of(quantities)}), "
                                    f"got {_show(name)}")
        factor_to(where, unit, si.get(name, ""))
    return dict(value)


def _name(value: Any) -> str | None:
    if value is None:
        return None
    if not isinstance(value, str) or not 1 <= len(value) <= MAX_NAME_LENGTH or not value.isprintable():
        _fail("name", f"a printable string of 1 to {MAX_NAME_LENGTH} characters", value)
    return value


# ----------------------------------------------------------------------------- the size of a run

def _gigabytes(n: float) -> str:
    return f"{n / 1e9:.3g} GB" if n >= 1e8 else f"{n / 1e6:.3g} MB"


@dataclass(frozen=True)
class SizeEstimate:
    """What a scene's run will take, estimated from its system, samples and quantities before solving.

    ``columns`` counts ``t`` and the quantities; ``values = samples × columns``.  ``table_bytes``
    is the table in memory (float64; an ``.npz`` file's size), ``csv_bytes`` an upper bound of the
    ``.csv`` file, ``memory_bytes`` of the run's peak memory: the solve's working memory per sample
    (measured per system) and the table's.  :data:`MAX_RUN_BYTES` bounds the last two.
    """

    samples: int
    columns: int
    values: int
    table_bytes: int
    csv_bytes: int
    memory_bytes: int

    @classmethod
    def of(cls, system: str, samples: int, quantities: int) -> "SizeEstimate":
        """The estimate for ``samples`` samples of ``quantities`` quantities (and ``t``) of ``system``."""
        columns = quantities + 1
        values = samples * columns
        per_sample = registry.get(system).bytes_per_sample
        return cls(samples, columns, values, 8 * values, _CSV_BYTES_PER_VALUE * values,
                   samples * per_sample + _BYTES_PER_VALUE * values)

    @property
    def max_samples(self) -> int:
        """The most samples these columns may have within :data:`MAX_RUN_BYTES`."""
        per_sample = max(self.memory_bytes, self.csv_bytes) // self.samples
        return MAX_RUN_BYTES // per_sample


def _check_size(scene: "Scene") -> None:
    size = scene.size_estimate
    if max(size.memory_bytes, size.csv_bytes) <= MAX_RUN_BYTES:
        return
    raise InvalidInputError(
        f"scene key [time].samples: expected a run of at most {_gigabytes(MAX_RUN_BYTES)}, got an estimated "
        f"{_gigabytes(size.memory_bytes)} of memory ({_gigabytes(size.csv_bytes)} as CSV) for {size.samples} samples "
        f"of {size.columns} columns (t and {size.columns - 1} quantities); use at most {size.max_samples} "
        "samples, or fewer [output].quantities")


# ----------------------------------------------------------------------------- the scene

@dataclass(frozen=True)
class Scene:
    """One checked scene.  Constructing it validates and normalises every field.

    The system (:mod:`mechderive.systems.registry`) checks its own ``parameters`` and ``initial``
    (:meth:`~mechderive.systems.base.System.check_parameters`, ``check_initial``): numbers become
    floats (``samples`` stays an int), ``quantities`` a tuple; e.g. a free top's ``initial`` holds
    ``omega`` as a 3-tuple and ``phi theta psi`` (default 0), a heavy top's ``parameters`` keep the
    form given (``M g l`` or ``Mgl``).  ``strict=False`` accepts moments no rigid body has
    (:func:`waived` lists them).  Invalid fields raise :class:`~mechderive.errors.InvalidInputError`.
    """

    system: str
    method: str
    rtol: float
    parameters: dict
    initial: dict
    t_end: float
    samples: int
    quantities: tuple
    name: str | None = None
    strict: bool = DEFAULT_STRICT
    #: the system's own top-level keys and tables (its ``extra_keys``: a ``lagrangian``'s ``coordinates``, ...)
    definition: Mapping[str, Any] = field(default_factory=dict)
    #: the per-motion quantities asked for (``[output].summary``), each one of the system's ``summaries``
    summary: tuple = ()
    #: {output column: unit text} of ``[output].units``: the columns written and printed in those units
    output_units: Mapping[str, str] = field(default_factory=dict)
    #: {"[table].key": text} of the values given with units (``"30 deg"``), as given; the scene holds them in SI
    given_with_units: Mapping[str, str] = field(default_factory=dict, compare=False)
    #: the first output time (``[time].t_start``); the initial values are at t = 0 all the same
    t_start: float = 0.0
    #: explicit output times (``[time].times``), or None for ``samples`` equally spaced on [t_start, t_end]
    times_given: tuple | None = None
    #: ``[time].samples_per_period`` as given (``samples`` then follows from the system's period), or None
    samples_per_period: int | None = None
    #: the concrete system (:class:`~mechderive.systems.base.System`) this scene runs, set on construction
    model: Any = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "name", _name(self.name))
        if not isinstance(self.strict, bool):
            _fail("strict", "true or false (a boolean; false accepts moments no rigid body has)", self.strict)
        system = _system(self.system)
        model = system.configure(dict(self.definition or {}))
        set_(self, "model", model)
        set_(self, "definition", dict(self.definition or {}))
        set_(self, "method", _choice("method", self.method, METHODS + tuple(m for m in model.methods
                                                                              if m not in METHODS)))
        lo, hi = RTOL_RANGE
        set_(self, "rtol", _number("rtol", self.rtol, expected=f"a number in [{lo:g}, {hi:g}]",
                                   valid=lambda x: lo <= x <= hi))
        given = dict(self.given_with_units or {})
        parameters = _in_si("[parameters]", _as_table("[parameters]", self.parameters or {}), model.parameters, given)
        set_(self, "parameters", model.check_parameters(parameters, strict=self.strict))
        initial = _in_si("[initial]", _as_table("[initial]", self.initial or {}), model.initial, given)
        set_(self, "initial", model.check_initial(initial, self.parameters))
        set_(self, "given_with_units", given)
        set_(self, "quantities", _quantity_list(self.system, self.quantities, model.quantity_names()))
        set_(self, "summary", _summary_list(self.system, self.summary, model.summary_names()))
        set_(self, "output_units", _output_units(self.output_units, model, self.quantities))
        self._check_times(model)
        _check_size(self)

    def _check_times(self, model: System) -> None:
        """``t_end``, ``samples`` (or ``samples_per_period``), ``t_start`` or ``times``: checked and normalised."""
        set_ = object.__setattr__
        if not model.free_times and (self.times_given is not None or self.t_start != 0):
            key = "[time].times" if self.times_given is not None else "[time].t_start"
            raise InvalidInputError(f"scene key {key}: system {self.system!r} takes only t_end and samples (its "
                                    f"motion is defined over [0, t_end]); got {key.split('.')[1]}")
        if self.times_given is not None:
            times = _times_list(self.times_given)
            set_(self, "times_given", times)
            set_(self, "t_start", times[0])
            set_(self, "t_end", times[-1])
            set_(self, "samples", len(times))
            if self.samples_per_period is not None:
                raise InvalidInputError("scene key [time].samples_per_period: expected either times or "
                                        "samples_per_period, got both")
            return
        set_(self, "t_start", _number("[time].t_start", self.t_start, expected="a finite number >= 0",
                                      valid=lambda x: x >= 0))
        set_(self, "t_end", _number("[time].t_end", self.t_end, expected=f"a finite number > t_start "
                                    f"({self.t_start!r})" if self.t_start else "a finite number > 0",
                                    valid=lambda x: x > self.t_start))
        if self.samples_per_period is not None:
            n = self.samples_per_period
            if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 2 <= n <= MAX_SAMPLES:
                _fail("[time].samples_per_period", f"an integer in [2, {MAX_SAMPLES}]", n)
            set_(self, "samples_per_period", int(n))
            set_(self, "samples", _samples_from_period(self, model))
        if (isinstance(self.samples, bool) or not isinstance(self.samples, (int, np.integer))
                or not 2 <= self.samples <= MAX_SAMPLES):
            _fail("[time].samples", f"an integer in [2, {MAX_SAMPLES}]", self.samples)
        set_(self, "samples", int(self.samples))

    @property
    def size_estimate(self) -> SizeEstimate:
        """The run's size, estimated before solving (:class:`SizeEstimate`); at most :data:`MAX_RUN_BYTES`."""
        return SizeEstimate.of(self.system, self.samples, len(self.quantities))

    def times(self) -> np.ndarray:
        """The output times: ``times`` as given, else ``samples`` equally spaced on [t_start, t_end], both ends
        included."""
        if self.times_given is not None:
            return np.array(self.times_given, dtype=float)
        return np.linspace(self.t_start, self.t_end, self.samples)


def _times_list(value: Any) -> tuple[float, ...]:
    """``[time].times``: 2 to MAX_SAMPLES finite numbers >= 0, strictly increasing."""
    if not isinstance(value, (list, tuple)) or not 2 <= len(value) <= MAX_SAMPLES:
        _fail("[time].times", f"a list of 2 to {MAX_SAMPLES} times (s), strictly increasing", value)
    times = tuple(_number(f"[time].times[{i}]", x, expected="a finite number >= 0", valid=lambda x: x >= 0)
                  for i, x in enumerate(value))
    for i in range(1, len(times)):
        if not times[i] > times[i - 1]:
            raise InvalidInputError(f"scene key [time].times[{i}]: expected times strictly increasing, got "
                                    f"{times[i]!r} after {times[i - 1]!r}")
    return times


def _samples_from_period(scene: "Scene", model: System) -> int:
    """``samples`` for ``samples_per_period`` N: ceil((t_end - t_start) / period × N) + 1, from the system's
    period of this motion (:meth:`~mechderive.systems.base.System.period`)."""
    period = model.period(scene)
    if period is None or not math.isfinite(period) or period <= 0:
        knows = [n for n in registry.names() if type(registry.get(n)).period is not System.period]
        raise InvalidInputError(
            f"scene key [time].samples_per_period: system {scene.system!r} does not know the period of this motion "
            f"before solving (a steady or non-periodic motion, or a system without a known period: those that "
            f"know theirs are {_one_of(knows) if knows else 'none'}); give samples instead")
    periods = (scene.t_end - scene.t_start) / period
    count = math.ceil(periods * scene.samples_per_period) + 1 if periods < MAX_SAMPLES else MAX_SAMPLES + 1
    if count > MAX_SAMPLES:
        raise InvalidInputError(
            f"scene key [time].samples_per_period: expected at most {MAX_SAMPLES} samples in all, got "
            f"{periods:.6g} periods of {period:.6g} s × {scene.samples_per_period} = {count} samples; give fewer "
            "samples per period or a shorter run")
    return count


def parse_scene(mapping: Mapping[str, Any], *, name: str | None = None) -> Scene:
    """Check a parsed TOML document (a mapping) and return its :class:`Scene`.

    ``name`` overrides the document's optional ``name`` key.  Besides the keys and tables of every
    scene, a system may read its own (its ``extra_keys``: a top-level key, a table, or
    ``output.expressions`` for an ``[output.expressions]`` table).

    >>> parse_scene({"system": "falling_cat", "time": {"t_end": 1, "samples": 2},
    ...              "output": {"quantities": ["flip_angle"]}}).initial
    {}
    >>> parse_scene({"system": "heavy_top", "colour": "red"})
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: scene key colour: unknown key; expected top-level keys name, system, \
method, rtol, strict and tables [parameters], [initial], [time], [output]
    """
    if not isinstance(mapping, Mapping):
        raise InvalidInputError(f"scene: expected a table of keys (a mapping), got {_show(mapping)}")
    given = mapping.get("system")
    system = registry.get(given) if isinstance(given, str) and given in registry.names() else None
    extra = tuple(system.extra_keys) if system is not None else ()
    tables = ", ".join(f"[{t}]" for t in TABLES)
    for key, value in mapping.items():
        if key in TABLES:
            _as_table(f"[{key}]", value)
        elif key not in TOP_LEVEL_KEYS and key not in extra:
            if isinstance(value, Mapping) and not extra:
                raise InvalidInputError(f"scene table [{_key_name(key)}]: unknown table; expected one of {tables}")
            raise InvalidInputError(f"scene key {_key_name(key)}: unknown key; expected top-level keys "
                                    f"{_one_of(TOP_LEVEL_KEYS + extra)} and tables {tables}")
    if "system" not in mapping:
        raise InvalidInputError("scene key system: missing; expected one of "
                                + ", ".join(repr(s) for s in registry.names()))
    system = _system(given)
    needed = _needed_tables(system)
    missing = [t for t in needed if t not in mapping]
    if missing:
        raise InvalidInputError(f"scene table [{missing[0]}]: missing; system {system.name!r} needs tables "
                                + ", ".join(f"[{t}]" for t in needed))
    time, output = mapping["time"], mapping["output"]
    _check_keys(time, "time", TIME_ALL_KEYS, (), "key")
    _check_time_keys(time)
    out_keys = OUTPUT_KEYS + (("expressions",) if "output.expressions" in extra else ())
    _check_keys(output, "output", out_keys + OUTPUT_OPTIONAL_KEYS, OUTPUT_KEYS, "key")
    definition = {k: mapping[k] for k in extra if k in mapping and not k.startswith("output.")}
    if "output.expressions" in extra and "expressions" in output:
        definition["output.expressions"] = output["expressions"]
    return Scene(system=system.name, method=mapping.get("method", DEFAULT_METHOD),
                 rtol=mapping.get("rtol", DEFAULT_RTOL), parameters=mapping.get("parameters", {}),
                 initial=mapping.get("initial", {}), t_end=time.get("t_end"), samples=time.get("samples"),
                 t_start=time.get("t_start", 0.0), times_given=time.get("times"),
                 samples_per_period=time.get("samples_per_period"),
                 quantities=output["quantities"], summary=output.get("summary", ()),
                 output_units=output.get("units", {}), name=name if name is not None else mapping.get("name"),
                 strict=mapping.get("strict", DEFAULT_STRICT), definition=definition)


def _check_time_keys(time: Mapping[str, Any]) -> None:
    """[time] holds ``times`` alone, or ``t_end`` with one of ``samples``, ``samples_per_period`` (and ``t_start``)."""
    if "times" in time:
        others = [k for k in time if k != "times"]
        if others:
            raise InvalidInputError(f"scene key [time].{others[0]}: expected either times or t_end, samples "
                                    f"(samples_per_period, t_start), got both")
        return
    if "t_end" not in time:
        raise InvalidInputError("scene key [time].t_end: missing; expected t_end with samples (or "
                                "samples_per_period), or a list times")
    given = [k for k in ("samples", "samples_per_period") if k in time]
    if len(given) != 1:
        raise InvalidInputError("scene key [time].samples: " + (
            "missing; expected samples or samples_per_period" if not given else
            "expected samples or samples_per_period, got both"))


# ----------------------------------------------------------------------------- reading

_FILE_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
               (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
               (stat.S_ISSOCK, "a socket"))
# O_NONBLOCK: opening a FIFO that appeared after the check must not wait for a writer.
_OPEN_FLAGS = (os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
               | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0))


def _not_regular(source: str, mode: int) -> InvalidInputError:
    kind = next((name for is_kind, name in _FILE_KINDS if is_kind(mode)), "not a regular file")
    return InvalidInputError(f"scene {source}: expected a regular file, got {kind}")


def _os_error(source: str, exc: OSError | ValueError) -> InvalidInputError:
    if isinstance(exc, FileNotFoundError):
        return InvalidInputError(f"scene {source}: expected an existing file, got no such file")
    reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
    return InvalidInputError(f"scene {source}: cannot read it: {reason}")


def _read_file(path: Path, source: str) -> str:
    """The text of the scene file ``path``: a regular file of at most :data:`MAX_SCENE_BYTES` bytes of UTF-8.

    A FIFO, a device (``/dev/zero``), a directory or a socket — directly or through a link — is
    refused before it is read, and checked again on the descriptor opened (it may have been
    replaced in between); at most ``MAX_SCENE_BYTES + 1`` bytes are ever read, whatever the size
    the file claims.  A leading UTF-8 byte-order mark is dropped.
    """
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError) as exc:  # ValueError: a NUL in the name
        raise _os_error(source, exc) from None
    if not stat.S_ISREG(mode):
        raise _not_regular(source, mode)
    try:
        fd = os.open(path, _OPEN_FLAGS)
    except OSError as exc:
        raise _os_error(source, exc) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise _not_regular(source, info.st_mode)
        if info.st_size > MAX_SCENE_BYTES:
            raise InvalidInputError(f"scene {source}: expected at most {MAX_SCENE_BYTES} bytes, got {info.st_size}")
        chunks, size = [], 0
        while size <= MAX_SCENE_BYTES and (chunk := os.read(fd, MAX_SCENE_BYTES + 1 - size)):
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise _os_error(source, exc) from None
    finally:
        os.close(fd)
    if size > MAX_SCENE_BYTES:  # a file claiming less than it holds (/proc), or growing as it is read
        raise InvalidInputError(f"scene {source}: expected at most {MAX_SCENE_BYTES} bytes, got more")
    data = b"".join(chunks).removeprefix(b"\xef\xbb\xbf")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise InvalidInputError(f"scene {source}: expected UTF-8 text, got byte 0x{data[exc.start]:02x}, "
                                f"which is not UTF-8, at line {line}, column {column}") from None


# A decimal integer as TOML spells it, standing alone (not in a float, a date or a bare key's digits).
_INTEGER = re.compile(r"(?<![\w.+-])[+-]?[0-9](?:_?[0-9])*(?![\w.:+-])")


def _parse_float(text: str) -> Any:
    """TOML's floats as doubles; one spelled beyond the largest double, or nonzero and below the
    smallest, is kept with its text (:class:`_Unrepresentable`, :class:`_Underflowed`) for the message."""
    x = float(text)
    if math.isinf(x) and "inf" not in text:
        return _Unrepresentable(text)
    if x == 0.0 and re.search(r"[1-9]", text.split("e")[0].split("E")[0]):
        zero = _Underflowed(x)
        zero.text = text
        return zero
    return x


def _parse_toml(text: str, source: str, cached: bool = False) -> dict[str, Any]:
    """:func:`_read_toml` of ``text``; with ``cached``, what it gave for the very same text in an earlier process.

    A document of plain values (tables, arrays, strings, integers, floats, booleans) is kept in the disk cache
    (:mod:`mechderive.core.textcache`, under the fingerprint of the package and the Python version, so of
    this tomllib), named by the SHA-256 of the text, as :mod:`marshal` data: reading it back skips importing
    tomllib (its regular expressions: ~3 ms of a warm run) and parsing.  Anything else (a date, a number no
    double holds, an error) is read anew each time.
    """
    if not cached:
        return _read_toml(text, source)
    import marshal

    from ..core import cachefs, textcache

    name = f"scene-{cachefs.sha256(text.encode('utf-8', 'surrogatepass')).hexdigest()[:40]}.marshal"
    stored = textcache.get(name)
    if stored is not None:
        try:
            document = marshal.loads(stored)
        except (EOFError, ValueError, TypeError):  # pragma: no cover - sealed, so written by us
            document = None
        if type(document) is dict and _plain(document):
            return document
    document = _read_toml(text, source)
    if _plain(document):
        textcache.put(name, marshal.dumps(document))
    return document


def _plain(value: Any) -> bool:
    """Whether ``value`` is made of dicts with str keys, lists, str, int, float and bool only (what marshal
    gives back as it was: not a float subclass such as :class:`_Underflowed`, nor a date)."""
    kind = type(value)
    if kind is dict:
        return all(type(k) is str and _plain(v) for k, v in value.items())
    if kind is list:
        return all(_plain(v) for v in value)
    return kind in (str, int, float, bool)


def _read_toml(text: str, source: str) -> dict[str, Any]:
    """``tomllib.loads`` with every failure an :class:`InvalidInputError` saying where it is.

    Python refuses to convert an integer of more than ``sys.get_int_max_str_digits()`` (4300)
    digits to an int; those (which no double holds either) are read as :class:`_Unrepresentable`
    so that the check of their key refuses them by name.
    """
    import tomllib

    try:
        try:
            return tomllib.loads(text, parse_float=_parse_float)
        except tomllib.TOMLDecodeError:
            raise
        except ValueError:
            limit = sys.get_int_max_str_digits()
            import secrets  # (with pathlib, ~10 ms of a warm run when imported at the top)

            nonce = "".join(secrets.choice("0123456789") for _ in range(18))
            huge: dict[str, str] = {}

            def mark(match: re.Match) -> str:
                digits = len(match.group().lstrip("+-").replace("_", ""))
                if not limit or digits <= limit:
                    return match.group()
                marker = f"0.{nonce}{len(huge)}"
                huge[marker] = f"an integer of {digits} digits"
                return marker

            marked = _INTEGER.sub(mark, text)
            return tomllib.loads(marked, parse_float=lambda t: _Unrepresentable(huge[t]) if t in huge
                                 else _parse_float(t))
    except tomllib.TOMLDecodeError as exc:
        where = re.search(r"at line (\d+)", str(exc))
        lines = text.splitlines()
        shown = ""
        if where and 1 <= int(where.group(1)) <= len(lines):
            shown = f": {_show(lines[int(where.group(1)) - 1].strip())}"
        raise InvalidInputError(f"scene {source}: not valid TOML: {exc}{shown}") from None
    except RecursionError:
        raise InvalidInputError(f"scene {source}: not valid TOML: arrays or tables nested too deeply") from None
    except ValueError as exc:
        raise InvalidInputError(f"scene {source}: not valid TOML: {str(exc).splitlines()[0]}") from None


def load_scene(path_or_text: os.PathLike | str, *, name: str | None = None, cached: bool = False) -> Scene:
    """Read a scene from a file (a :class:`pathlib.Path`) or from TOML text (a ``str``).

    A file's scene is named after the file's stem (if that is a valid name) unless it has a
    ``name`` key or ``name`` is given.  The file must be a regular file (not a FIFO, a device or a
    directory) of at most :data:`MAX_SCENE_BYTES` bytes of UTF-8 text.  TOML syntax errors, files
    that cannot be read and numbers no double holds become
    :class:`~mechderive.errors.InvalidInputError` naming the file, the line or the key.
    ``cached``: the parsed TOML is kept in the disk cache, by the text's hash, and read back from it
    (the command line's runs: a warm one imports no TOML parser; see :func:`_parse_toml`); the scene is
    checked all the same.

    >>> load_scene('system = "heavy_top"\\nsamples = 5')
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: scene key samples: unknown key; expected top-level keys name, system, \
method, rtol, strict and tables [parameters], [initial], [time], [output]
    """
    default_name = None
    if isinstance(path_or_text, os.PathLike):
        from pathlib import Path

        path = Path(path_or_text)
        source = f"file {str(path)!r}"
        text = _read_file(path, source)
        stem = path.stem
        default_name = stem if 1 <= len(stem) <= MAX_NAME_LENGTH and stem.isprintable() else None
    elif isinstance(path_or_text, str):
        text, source = path_or_text, "text"
        if "\n" not in text and "=" not in text and text.strip().endswith(".toml"):
            raise InvalidInputError(f"scene text: expected TOML, got {_show(text)}, which looks like a file "
                                    f"name; pass pathlib.Path({text.strip()!r}) to read the file")
        if len(text) > MAX_SCENE_BYTES:
            raise InvalidInputError(f"scene text: expected at most {MAX_SCENE_BYTES} characters, got {len(text)}")
    else:
        raise InvalidInputError(f"scene: expected a pathlib.Path or TOML text (a str), got {_show(path_or_text)}")
    document = _parse_toml(text, source, cached)
    if name is None and "name" not in document:
        name = default_name
    return parse_scene(document, name=name)


# ----------------------------------------------------------------------------- writing

def _toml_string(s: str) -> str:
    out = []
    for ch in s:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_value(v: Any) -> str:
    if isinstance(v, str):
        return _toml_string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, int):
        return str(v)
    return repr(float(v))  # shortest round-trip repr; finite by construction, so valid TOML


def scene_to_toml(scene: Scene) -> str:
    """The scene as TOML text; :func:`load_scene` of it gives back an equal scene.

    >>> print(scene_to_toml(load_scene('''system = "falling_cat"
    ... [time]
    ... t_end = 1
    ... samples = 201
    ... [output]
    ... quantities = ["flip_angle"]''')), end="")
    system = "falling_cat"
    method = "auto"
    rtol = 1e-09
    <BLANKLINE>
    [time]
    t_end = 1.0
    samples = 201
    <BLANKLINE>
    [output]
    quantities = ["flip_angle"]
    """
    lines = [f"name = {_toml_string(scene.name)}"] if scene.name is not None else []
    lines += [f"system = {_toml_string(scene.system)}", f"method = {_toml_string(scene.method)}",
              f"rtol = {_toml_value(scene.rtol)}"] + (["strict = false"] if not scene.strict else [])
    own = {k: v for k, v in scene.definition.items() if isinstance(v, Mapping)}  # the system's own tables
    lines += [f"{k} = {_toml_value(v)}" for k, v in scene.definition.items() if k not in own]
    if scene.times_given is not None:
        time = {"times": list(scene.times_given)}
    else:
        time = {**({"t_start": scene.t_start} if scene.t_start else {}), "t_end": scene.t_end,
                **({"samples_per_period": scene.samples_per_period} if scene.samples_per_period is not None
                   else {"samples": scene.samples})}
    for table, content in (("parameters", scene.parameters), ("initial", scene.initial), ("time", time),
                           ("output", {"quantities": scene.quantities,
                                       **({"summary": scene.summary} if scene.summary else {})}),
                           *((("output.units", scene.output_units),) if scene.output_units else ()),
                           *own.items()):
        if content:
            lines += ["", f"[{table}]"] + [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in content.items()]
    return "\n".join(lines) + "\n"


def _toml_key(key: str) -> str:
    return key if _NAME_PATTERN.fullmatch(key) else _toml_string(key)


# ----------------------------------------------------------------------------- registration hooks

def _check_new_names(system: str, names: Iterable[str], what: str) -> tuple[System, tuple[str, ...]]:
    if not isinstance(system, str) or system not in registry.names():
        raise InvalidInputError(f"expected a system, one of {_one_of(registry.names())}, got {_show(system)}")
    if isinstance(names, str):
        raise InvalidInputError(f"expected a sequence of {what} names, got the single string {names!r}")
    names = tuple(names)
    for n in names:
        if not isinstance(n, str) or not _NAME_PATTERN.fullmatch(n):
            raise InvalidInputError(f"expected {what} names matching [A-Za-z_][A-Za-z0-9_]*, got {_show(n)}")
    return registry.get(system), names


def register_system_parameters(system: str, names: Iterable[str]) -> None:
    """Allow more (optional) [parameters] names for ``system``, one whose parameters are open
    (:attr:`~mechderive.systems.base.System.open_parameters`: the falling cat's); each takes any finite number.

    Registering a name twice is harmless, so a module may register at import.
    """
    model, names = _check_new_names(system, names, "parameter")
    if not model.open_parameters:
        open_ = [n for n in registry.names() if registry.get(n).open_parameters]
        raise InvalidInputError(f"expected a system whose parameters are open ({_one_of(open_)}), "
                                f"got {system!r}, whose parameters are fixed: "
                                f"{_one_of(k.name for k in model.parameters)}")
    current = tuple(k.name for k in model.parameters)
    model.parameters = model.parameters + tuple(Key(n, "", "a registered parameter", required=False)
                                                for n in dict.fromkeys(names) if n not in current)


def register_system_quantities(system: str, names: Iterable[str]) -> None:
    """Allow more [output] quantity names for ``system`` (e.g. the falling cat's ``shape_*``); its solver
    must compute them.

    Registering a name twice is harmless, so a module may register at import.
    """
    model, names = _check_new_names(system, names, "quantity")
    current = model.quantity_names()
    model.quantities = model.quantities + tuple(Quantity(n, "", "a registered quantity")
                                                for n in dict.fromkeys(names) if n not in current)
