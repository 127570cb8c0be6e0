"""The scene file of ``mechderive run``: a TOML description of one motion to compute.

A scene is DATA.  It is read with the standard library's :mod:`tomllib` and every
value is checked against a fixed set of names and ranges; nothing in it is ever
evaluated as code (no ``eval``, no ``sympify``), so a string such as
``"__import__('os')"`` is only ever a wrong value, refused with a message.

The format (optional keys marked)::

    name = "my top"           # optional: a printable label (1-100 characters)
    system = "heavy_top"      # "free_top" | "heavy_top" | "falling_cat"
    method = "auto"           # optional: "auto" | "exact" | "integrate" (default "auto")
    rtol = 1e-10              # optional: relative accuracy in [1e-15, 1e-2] (default 1e-9)
    strict = false            # optional (default true): accept moments no rigid body has (see below)

    [parameters]              # heavy_top: I1 I3 M g l, or I1 I3 Mgl; free_top: I1 I2 I3;
                              # falling_cat: registered names
    I1 = 1.0
    ...

    [initial]                 # heavy_top: theta phi psi theta_dot phi_dot psi_dot (rad, rad/s)
    ...                       # free_top: omega = [w1, w2, w3] (body frame, rad/s), optional phi theta psi

    [time]
    t_end = 10.0              # > 0
    samples = 1001            # equally spaced on [0, t_end], both ends included; 2 <= samples <= 10^7,
                              # and the run at most MAX_RUN_BYTES (1 GB, below)

    [output]
    quantities = ["theta", "phi", "psi"]   # names from QUANTITIES[system], each once

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

import datetime
import math
import os
import re
import secrets
import stat
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from ..errors import InvalidInputError, NonFiniteValueError
from ..systems import registry
from ..systems.heavy_top import parameters as heavy_top_parameters

__all__ = [
    "Scene",
    "SizeEstimate",
    "SYSTEMS",
    "METHODS",
    "QUANTITIES",
    "SYSTEM_PARAMETERS",
    "FALLING_CAT_PARAMETERS",
    "load_scene",
    "waived",
    "parse_scene",
    "scene_to_toml",
    "register_system_parameters",
    "register_system_quantities",
]

SYSTEMS = ("free_top", "heavy_top", "falling_cat")
METHODS = ("auto", "exact", "integrate")
DEFAULT_METHOD = "auto"
DEFAULT_RTOL = 1e-9
RTOL_RANGE = (1e-15, 1e-2)
MAX_SAMPLES = 10**7
MAX_NAME_LENGTH = 100
MAX_SCENE_BYTES = 1_000_000  # a scene is a page of text; refuse anything far larger unread

#: The largest run a scene may ask for (bytes): its estimated peak memory, and its table written as CSV,
#: must each stay within it (:attr:`Scene.size_estimate`), so that a scene cannot exhaust a shared machine.
MAX_RUN_BYTES = 1_000_000_000
#: Peak memory of each system's solve per sample beyond the table (bytes), an upper bound of the growth of
#: the process's maxrss measured from 4·10⁴ (falling_cat) or 5·10⁵ samples, closed form and integration,
#: one quantity and all: heavy_top 360-510, free_top 225-490, falling_cat 11,250 (its L is taken by
#: differences over a 9-point stencil of rotations per sample).
_SOLVE_BYTES_PER_SAMPLE = {"free_top": 600, "heavy_top": 600, "falling_cat": 12_500}
#: Memory per value of the table (bytes): the float64 column, the arrays the quantities are taken from and
#: the CSV writer's rows (measured 11-25 per column and sample on top of the solve).
_BYTES_PER_VALUE = 30
#: The CSV file per value (bytes): ``repr`` of a double has at most 24 characters, plus the separator.
_CSV_BYTES_PER_VALUE = 25

TOP_LEVEL_KEYS = ("name", "system", "method", "rtol", "strict")
DEFAULT_STRICT = True
TABLES = ("parameters", "initial", "time", "output")
TIME_KEYS = ("t_end", "samples")
OUTPUT_KEYS = ("quantities",)

_R = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))

#: The quantity names a scene may ask for, per system, in a fixed order.
QUANTITIES: dict[str, tuple[str, ...]] = {
    "free_top": ("omega1", "omega2", "omega3", "L1", "L2", "L3", "energy", "L_norm", *_R,
                 "phi", "theta", "psi", "q0", "q1", "q2", "q3"),
    "heavy_top": ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot", "u", "energy", "p_phi", "p_psi",
                  "omega1", "omega2", "omega3", *_R, "apex_x", "apex_y", "apex_z"),
    "falling_cat": (*_R, "q0", "q1", "q2", "q3", "flip_angle", "L1", "L2", "L3", "shape_bend", "shape_swivel"),
}

#: The falling cat's parameters, all optional: lengths and a mass > 0, ``peak_bend`` in (0, π)
#: (mechderive.systems.deformable.cat.check_cat_parameters validates them, and is called here).
FALLING_CAT_PARAMETERS: tuple[str, ...] = ("half_mass", "joint_offset", "radius", "half_length", "peak_bend")
_CAT_RANGES: dict[str, tuple[str, Callable[[float], bool]]] = {
    **{k: ("a number > 0", lambda x: x > 0) for k in FALLING_CAT_PARAMETERS},
    "peak_bend": ("a number in (0, π) (rad: the halves must not fold through each other)",
                  lambda x: 0 < x < math.pi),
}

#: The [parameters] names per system.  free_top needs all of its; heavy_top all of
#: I1 I3 M g l or all of I1 I3 Mgl; falling_cat's are optional and open to
#: :func:`register_system_parameters`.
SYSTEM_PARAMETERS: dict[str, tuple[str, ...]] = {
    "free_top": ("I1", "I2", "I3"),
    "heavy_top": (*heavy_top_parameters.PARAM_KEYS, "Mgl"),
    "falling_cat": FALLING_CAT_PARAMETERS,
}
_OPEN_PARAMETERS = ("falling_cat",)
_FREE_TOP_ANGLES = ("phi", "theta", "psi")
_INITIAL_NAMES: dict[str, tuple[str, ...]] = {
    "free_top": ("omega", *_FREE_TOP_ANGLES),
    "heavy_top": heavy_top_parameters.INITIAL_NAMES,
    "falling_cat": (),
}
#: The physics checks' way out (their STRICT_HINT), as said to a scene's author.
_SCENE_STRICT_HINT = "add strict = false to the scene to accept moments no rigid body has"
_NAME_PATTERN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")  # a bare TOML key and a Python identifier


# ----------------------------------------------------------------------------- numbers

#: The largest finite double, as messages state the range of every number a scene holds.
_LARGEST = sys.float_info.max


class _Unrepresentable:
    """A number the scene's text spells but no double holds: ``1e400``, an integer of 401 digits.

    Made by the TOML reader (:func:`_parse_toml`) in place of ``inf`` or an exception, so that the
    check of the key it is found under refuses it by name.
    """

    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return _literal(self.text)


class _Underflowed(float):
    """A nonzero float literal that is 0 in double precision (``1e-400``); it is 0 wherever 0 is allowed."""

    text: str

    def __repr__(self) -> str:
        return f"{_literal(self.text)} (0 in double precision)"


def _literal(text: str) -> str:
    """A number as the scene spells it, shortened if it is long (``1e-`` and 5000 digits)."""
    return text if len(text) <= 40 else f"{text[:12]}...{text[-12:]} (a number of {len(text)} characters)"


def _digits(n: int) -> int:
    """The number of decimal digits of ``n``, without converting it to text (huge ints refuse that)."""
    n = abs(n)
    d = max(1, int(n.bit_length() * 0.30102999566398120))  # log10(2): exact or one short
    return d + (n >= 10 ** d)


# ----------------------------------------------------------------------------- messages

def _show(value: Any, depth: int = 0) -> str:
    """The value as the message shows it: short, escaped, on one line, with its TOML kind when that helps."""
    if isinstance(value, bool):
        return f"{str(value).lower()} (a boolean)"
    if isinstance(value, (int, np.integer)) and _digits(int(value)) > 40:
        return f"an integer of {_digits(int(value))} digits"
    if isinstance(value, (int, float, _Unrepresentable)):
        return repr(value)
    if isinstance(value, str):
        text = repr(value)
        return text if len(text) <= 80 else text[:70] + "...' (truncated)"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, (datetime.date, datetime.time)):
        return f"{value.isoformat()} (a date/time)"
    if isinstance(value, (list, tuple)):
        if depth > 2 or len(value) > 20:
            return f"a list of {len(value)} items"
        text = "[" + ", ".join(_show(v, depth + 1) for v in value) + "]"
        return text if len(text) <= 80 else f"a list of {len(value)} items"
    return f"a {type(value).__name__}"


def _key_name(key: Any) -> str:
    """A key as the message shows it: bare if it is a plain name, else quoted and escaped."""
    if isinstance(key, str) and _NAME_PATTERN.fullmatch(key) and len(key) <= 40:
        return key
    return _show(key)


def _at(table: str | None, key: Any) -> str:
    return f"[{table}].{_key_name(key)}" if table else _key_name(key)


def _fail(where: str, expected: str, value: Any, error: type[InvalidInputError] = InvalidInputError) -> None:
    raise error(f"scene key {where}: expected {expected}, got {_show(value)}")


def _one_of(names: Iterable[str]) -> str:
    return ", ".join(names)


# ----------------------------------------------------------------------------- value checks

def _number(where: str, value: Any, *, expected: str = "a finite number",
            valid: Callable[[float], bool] = lambda x: True) -> float:
    """``value`` as a float; bool and non-numbers are refused, ints accepted, NaN/inf refused.

    Every number of a scene is a finite double: a value spelled beyond ±1.8e308 (``1e400``, an
    integer of 400 digits) is refused as not finite, naming the key, rather than read as inf.
    """
    finite = f"{expected} (a finite double: at most {_LARGEST:.2g} in size)"
    if isinstance(value, _Unrepresentable):
        _fail(where, finite, value, NonFiniteValueError)
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        _fail(where, expected, value)
    try:
        x = float(value)
    except OverflowError:  # an int beyond the largest double
        _fail(where, finite, value, NonFiniteValueError)
    if not math.isfinite(x):
        _fail(where, expected, x, NonFiniteValueError)
    if not valid(x):
        _fail(where, expected, value)
    return x


def _choice(where: str, value: Any, allowed: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in allowed:
        _fail(where, "one of " + ", ".join(repr(a) for a in allowed), value)
    return value


def _check_keys(given: Mapping[str, Any], table: str, allowed: tuple[str, ...], required: tuple[str, ...],
                what: str) -> None:
    for key in given:
        if key not in allowed:
            allowed_text = f"expected one of {_one_of(allowed)}" if allowed else "it takes none"
            raise InvalidInputError(f"scene key {_at(table, key)}: unknown {what}; {allowed_text}")
    for key in required:
        if key not in given:
            raise InvalidInputError(f"scene key {_at(table, key)}: missing; expected all of {_one_of(required)}")


def _as_table(where: str, value: Any) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise InvalidInputError(f"scene table {where}: expected a table, got {_show(value)}")
    return value


def _rename_keys(exc: InvalidInputError, table: str, names: tuple[str, ...]) -> InvalidInputError:
    """Re-word an error of a physics check so that it names the scene keys it is about."""
    message = str(exc)
    claim = message.split(";")[0]  # the checked relation; later clauses are hints
    involved = [k for k in names if re.search(rf"(?<![A-Za-z0-9_]){re.escape(k)}(?![A-Za-z0-9_])", claim)]
    where = ("scene key" + ("s " if len(involved) > 1 else " ") + ", ".join(f"[{table}].{k}" for k in involved)
             if involved else f"scene table [{table}]")
    return type(exc)(f"{where}: {message}")


# ----------------------------------------------------------------------------- per-system checks

def _heavy_top_names(given: Mapping[str, Any]) -> tuple[str, ...]:
    """The heavy top's parameter names in the form the scene uses: I1 I3 M g l, or I1 I3 Mgl."""
    _check_keys(given, "parameters", SYSTEM_PARAMETERS["heavy_top"], (), "parameter for system 'heavy_top'")
    separate = [k for k in ("M", "g", "l") if k in given]
    if "Mgl" in given and separate:
        raise InvalidInputError("scene keys " + ", ".join(_at("parameters", k) for k in ("Mgl", *separate))
                                + ": expected either Mgl or all of M, g, l (only M g l enters the motion), got both")
    names = heavy_top_parameters.MGL_KEYS if "Mgl" in given else heavy_top_parameters.PARAM_KEYS
    for key in names:
        if key not in given:
            raise InvalidInputError(f"scene key {_at('parameters', key)}: missing; expected all of "
                                    + (f"{_one_of(names)}, or {_one_of(heavy_top_parameters.MGL_KEYS)} "
                                       "(only M g l enters the motion)" if "Mgl" not in names else _one_of(names)))
    return names


def _parameters(system: str, given: Mapping[str, Any], strict: bool = True) -> dict[str, float]:
    given = _as_table("[parameters]", given)
    names = SYSTEM_PARAMETERS[system]
    if system == "heavy_top":
        names = _heavy_top_names(given)
    else:
        required = () if system in _OPEN_PARAMETERS else names
        _check_keys(given, "parameters", names, required, f"parameter for system {system!r}")
    if system == "falling_cat":
        p = {}
        for k in (k for k in names if k in given):  # registered names: any finite number
            expected, valid = _CAT_RANGES.get(k, ("a finite number", lambda x: True))
            p[k] = _number(_at("parameters", k), given[k], expected=expected, valid=valid)
        from ..systems.deformable.cat import check_cat_parameters  # no SymPy: only the checks

        try:
            check_cat_parameters({k: v for k, v in p.items() if k in FALLING_CAT_PARAMETERS})
        except InvalidInputError as exc:
            raise _rename_keys(exc, "parameters", names) from exc
        return p
    expected = "a number > 0" + ("" if strict else " (strict = false does not waive this)")
    p = {k: _number(_at("parameters", k), given[k], expected=expected, valid=lambda x: x > 0) for k in names}
    # Sums and squares of moments near the largest double overflow to ±inf, which the comparisons order
    # rightly (I1 + I2 = inf >= I3): the checks' answers stand; NumPy's RuntimeWarnings would only be noise
    # printed before the message.
    try:
        with np.errstate(all="ignore"):
            if system == "heavy_top":
                heavy_top_parameters.check_params(p, strict=strict)
            else:
                from ..inertia.validate import check_principal_moments  # imports SymPy: only when needed

                check_principal_moments(p["I1"], p["I2"], p["I3"], strict=strict)
    except InvalidInputError as exc:
        renamed = _rename_keys(exc, "parameters", names)
        raise type(renamed)(str(renamed).replace(heavy_top_parameters.STRICT_HINT, _SCENE_STRICT_HINT)) from exc
    return p


def waived(scene: "Scene") -> list[str]:
    """What ``strict = false`` let through for ``scene``: the rigid-body conditions its parameters violate.

    Empty for a strict scene (nothing was waived) and for one whose body is physical anyway.
    """
    if scene.strict or scene.system == "falling_cat":
        return []
    if scene.system not in SYSTEMS:
        return list(scene.model.waived(scene.parameters))
    p = scene.parameters
    with np.errstate(all="ignore"):  # as in _parameters
        if scene.system == "heavy_top":
            return heavy_top_parameters.rigid_body_violations(p)
        from ..inertia.validate import rigid_body_violations

        return rigid_body_violations(p["I1"], p["I2"], p["I3"])


def _initial(system: str, given: Mapping[str, Any]) -> dict[str, Any]:
    given = _as_table("[initial]", given)
    names = _INITIAL_NAMES[system]
    if system == "heavy_top":
        _check_keys(given, "initial", names, names, "initial value for system 'heavy_top'")
        s = {k: _number(_at("initial", k), given[k]) for k in names}
        _number("[initial].theta", s["theta"], expected="a number in [0, π]", valid=lambda x: 0 <= x <= math.pi)
        try:
            heavy_top_parameters.check_initial(s)
        except InvalidInputError as exc:
            raise _rename_keys(exc, "initial", names) from exc
        return s
    if system == "free_top":
        _check_keys(given, "initial", names, ("omega",), "initial value for system 'free_top'")
        omega = given["omega"]
        if not isinstance(omega, (list, tuple)) or len(omega) != 3:
            _fail("[initial].omega", "a list of 3 finite numbers [w1, w2, w3] (rad/s)", omega)
        state: dict[str, Any] = {"omega": tuple(_number(f"[initial].omega[{i}]", w) for i, w in enumerate(omega))}
        state.update({k: _number(_at("initial", k), given.get(k, 0.0)) for k in _FREE_TOP_ANGLES})
        return state
    _check_keys(given, "initial", names, (), f"initial value for system {system!r}")
    return {}


def _quantities(system: str, value: Any) -> tuple[str, ...]:
    return _quantity_list(system, value, QUANTITIES[system])


def _quantity_list(system: str, value: Any, allowed: tuple[str, ...]) -> tuple[str, ...]:
    if not isinstance(value, (list, tuple)) or not value:
        _fail("[output].quantities", f"a non-empty list of quantity names (for {system}: {_one_of(allowed)})",
              value)
    seen: set[str] = set()
    for i, q in enumerate(value):
        where = f"[output].quantities[{i}]"
        if not isinstance(q, str):
            _fail(where, "a quantity name (a string)", q)
        if q not in allowed:
            raise InvalidInputError(f"scene key {where}: unknown quantity {_show(q)} for system {system!r}; "
                                    f"expected one of {_one_of(allowed)}")
        if q in seen:
            raise InvalidInputError(f"scene key {where}: duplicate quantity {q!r}; each may appear once")
        seen.add(q)
    return tuple(value)


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
        if system in _SOLVE_BYTES_PER_SAMPLE:
            per_sample = _SOLVE_BYTES_PER_SAMPLE[system]
        else:
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

    Numbers become floats (``samples`` stays an int), ``quantities`` a tuple, a
    free top's ``initial`` holds ``omega`` as a 3-tuple and ``phi theta psi``
    (default 0); a heavy top's ``parameters`` keep the form given (``M g l`` or ``Mgl``).
    ``strict=False`` accepts moments no rigid body has (:func:`waived` lists them).
    Invalid fields raise :class:`~mechderive.errors.InvalidInputError`.
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
    #: the concrete system (:class:`~mechderive.systems.base.System`) this scene runs, set on construction
    model: Any = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "name", _name(self.name))
        if not isinstance(self.strict, bool):
            _fail("strict", "true or false (a boolean; false accepts moments no rigid body has)", self.strict)
        if self.system not in SYSTEMS:
            self._post_init_registered()
            return
        set_(self, "definition", {})
        system = _choice("system", self.system, SYSTEMS)
        set_(self, "method", _choice("method", self.method, METHODS))
        lo, hi = RTOL_RANGE
        set_(self, "rtol", _number("rtol", self.rtol, expected=f"a number in [{lo:g}, {hi:g}]",
                                   valid=lambda x: lo <= x <= hi))
        set_(self, "parameters", _parameters(system, self.parameters, self.strict))
        set_(self, "initial", _initial(system, self.initial))
        set_(self, "t_end", _number("[time].t_end", self.t_end, expected="a finite number > 0",
                                    valid=lambda x: x > 0))
        if (isinstance(self.samples, bool) or not isinstance(self.samples, (int, np.integer))
                or not 2 <= self.samples <= MAX_SAMPLES):
            _fail("[time].samples", f"an integer in [2, {MAX_SAMPLES}]", self.samples)
        set_(self, "samples", int(self.samples))
        set_(self, "quantities", _quantities(system, self.quantities))
        _check_size(self)

    def _post_init_registered(self) -> None:
        """Check the fields of a scene of a registered system through the system itself."""
        set_ = object.__setattr__
        system = registry.get(self.system) if isinstance(self.system, str) else _choice("system", self.system,
                                                                                         registry.names())
        model = system.configure(dict(self.definition or {}))
        set_(self, "model", model)
        set_(self, "definition", dict(self.definition or {}))
        set_(self, "method", _choice("method", self.method, ("auto", *model.methods)))
        lo, hi = RTOL_RANGE
        set_(self, "rtol", _number("rtol", self.rtol, expected=f"a number in [{lo:g}, {hi:g}]",
                                   valid=lambda x: lo <= x <= hi))
        set_(self, "parameters", model.check_parameters(_as_table("[parameters]", self.parameters or {}),
                                                        strict=self.strict))
        set_(self, "initial", model.check_initial(_as_table("[initial]", self.initial or {}), self.parameters))
        set_(self, "t_end", _number("[time].t_end", self.t_end, expected="a finite number > 0",
                                    valid=lambda x: x > 0))
        if (isinstance(self.samples, bool) or not isinstance(self.samples, (int, np.integer))
                or not 2 <= self.samples <= MAX_SAMPLES):
            _fail("[time].samples", f"an integer in [2, {MAX_SAMPLES}]", self.samples)
        set_(self, "samples", int(self.samples))
        set_(self, "quantities", _quantity_list(self.system, self.quantities, model.quantity_names()))
        _check_size(self)

    @property
    def size_estimate(self) -> SizeEstimate:
        """The run's size, estimated before solving (:class:`SizeEstimate`); at most :data:`MAX_RUN_BYTES`."""
        return SizeEstimate.of(self.system, self.samples, len(self.quantities))

    def times(self) -> np.ndarray:
        """The sample times: ``samples`` equally spaced on [0, t_end], both ends included."""
        return np.linspace(0.0, self.t_end, self.samples)


def parse_scene(mapping: Mapping[str, Any], *, name: str | None = None) -> Scene:
    """Check a parsed TOML document (a mapping) and return its :class:`Scene`.

    ``name`` overrides the document's optional ``name`` key.

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
    if isinstance(mapping.get("system"), str) and mapping["system"] not in SYSTEMS:
        return _parse_registered(mapping, name)
    tables = ", ".join(f"[{t}]" for t in TABLES)
    for key, value in mapping.items():
        if key in TABLES:
            _as_table(f"[{key}]", value)
        elif key not in TOP_LEVEL_KEYS:
            if isinstance(value, Mapping):
                raise InvalidInputError(f"scene table [{_key_name(key)}]: unknown table; expected one of {tables}")
            raise InvalidInputError(f"scene key {_key_name(key)}: unknown key; expected top-level keys "
                                    f"{_one_of(TOP_LEVEL_KEYS)} and tables {tables}")
    if "system" not in mapping:
        raise InvalidInputError("scene key system: missing; expected one of "
                                + ", ".join(repr(s) for s in SYSTEMS))
    system = _choice("system", mapping["system"], SYSTEMS)
    needed = [t for t in ("time", "output") if t not in mapping]
    if system != "falling_cat":
        needed = [t for t in ("parameters", "initial") if t not in mapping] + needed
    if needed:
        raise InvalidInputError(f"scene table [{needed[0]}]: missing; system {system!r} needs tables "
                                + (", ".join(f"[{t}]" for t in TABLES) if system != "falling_cat"
                                   else "[time], [output]"))
    time, output = mapping["time"], mapping["output"]
    _check_keys(time, "time", TIME_KEYS, TIME_KEYS, "key")
    _check_keys(output, "output", OUTPUT_KEYS, OUTPUT_KEYS, "key")
    return Scene(system=system, method=mapping.get("method", DEFAULT_METHOD), rtol=mapping.get("rtol", DEFAULT_RTOL),
                 parameters=mapping.get("parameters", {}), initial=mapping.get("initial", {}),
                 t_end=time["t_end"], samples=time["samples"], quantities=output["quantities"],
                 name=name if name is not None else mapping.get("name"),
                 strict=mapping.get("strict", DEFAULT_STRICT))


def _parse_registered(mapping: Mapping[str, Any], name: str | None) -> Scene:
    system = registry.get(mapping["system"]) if mapping["system"] in registry.names() else _choice(
        "system", mapping["system"], registry.names())
    extra = tuple(system.extra_keys)
    tables = ", ".join(f"[{t}]" for t in TABLES)
    for key, value in mapping.items():
        if key in TABLES:
            _as_table(f"[{key}]", value)
        elif key not in TOP_LEVEL_KEYS and key not in extra:
            allowed = _one_of(TOP_LEVEL_KEYS + extra)
            raise InvalidInputError(f"scene key {_key_name(key)}: unknown key; expected top-level keys "
                                    f"{allowed} and tables {tables}")
    needed = [t for t in ("time", "output") if t not in mapping]
    if needed:
        raise InvalidInputError(f"scene table [{needed[0]}]: missing; system {system.name!r} needs tables "
                                "[time], [output]")
    time, output = mapping["time"], mapping["output"]
    _check_keys(time, "time", TIME_KEYS, TIME_KEYS, "key")
    out_keys = ("quantities", *(k for k in ("expressions",) if "output.expressions" in extra))
    _check_keys(output, "output", out_keys, OUTPUT_KEYS, "key")
    definition = {k: mapping[k] for k in extra if k in mapping and not k.startswith("output.")}
    if "output.expressions" in extra and "expressions" in output:
        definition["output.expressions"] = output["expressions"]
    return Scene(system=system.name, method=mapping.get("method", DEFAULT_METHOD),
                 rtol=mapping.get("rtol", DEFAULT_RTOL), parameters=mapping.get("parameters", {}),
                 initial=mapping.get("initial", {}), t_end=time["t_end"], samples=time["samples"],
                 quantities=output["quantities"], name=name if name is not None else mapping.get("name"),
                 strict=mapping.get("strict", DEFAULT_STRICT), definition=definition)


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


def _parse_toml(text: str, source: str) -> dict[str, Any]:
    """``tomllib.loads`` with every failure an :class:`InvalidInputError` saying where it is.

    Python refuses to convert an integer of more than ``sys.get_int_max_str_digits()`` (4300)
    digits to an int; those (which no double holds either) are read as :class:`_Unrepresentable`
    so that the check of their key refuses them by name.
    """
    try:
        try:
            return tomllib.loads(text, parse_float=_parse_float)
        except tomllib.TOMLDecodeError:
            raise
        except ValueError:
            limit = sys.get_int_max_str_digits()
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


def load_scene(path_or_text: os.PathLike | str, *, name: str | None = None) -> Scene:
    """Read a scene from a file (a :class:`pathlib.Path`) or from TOML text (a ``str``).

    A file's scene is named after the file's stem (if that is a valid name) unless it has a
    ``name`` key or ``name`` is given.  The file must be a regular file (not a FIFO, a device or a
    directory) of at most :data:`MAX_SCENE_BYTES` bytes of UTF-8 text.  TOML syntax errors, files
    that cannot be read and numbers no double holds become
    :class:`~mechderive.errors.InvalidInputError` naming the file, the line or the key.

    >>> load_scene('system = "heavy_top"\\nsamples = 5')
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: scene key samples: unknown key; expected top-level keys name, system, \
method, rtol, strict and tables [parameters], [initial], [time], [output]
    """
    default_name = None
    if isinstance(path_or_text, os.PathLike):
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
    document = _parse_toml(text, source)
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
    for table, content in (("parameters", scene.parameters), ("initial", scene.initial),
                           ("time", {"t_end": scene.t_end, "samples": scene.samples}),
                           ("output", {"quantities": scene.quantities})):
        if content:
            lines += ["", f"[{table}]"] + [f"{k} = {_toml_value(v)}" for k, v in content.items()]
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- registration hooks

def _check_new_names(system: str, names: Iterable[str], what: str) -> tuple[str, ...]:
    if system not in SYSTEMS:
        raise InvalidInputError(f"expected a system, one of {_one_of(SYSTEMS)}, got {_show(system)}")
    if isinstance(names, str):
        raise InvalidInputError(f"expected a sequence of {what} names, got the single string {names!r}")
    names = tuple(names)
    for n in names:
        if not isinstance(n, str) or not _NAME_PATTERN.fullmatch(n):
            raise InvalidInputError(f"expected {what} names matching [A-Za-z_][A-Za-z0-9_]*, got {_show(n)}")
    return names


def register_system_parameters(system: str, names: Iterable[str]) -> None:
    """Allow more (optional) [parameters] names for ``system``; only falling_cat's set is open.

    Registering a name twice is harmless, so a module may register at import.
    """
    names = _check_new_names(system, names, "parameter")
    if system not in _OPEN_PARAMETERS:
        raise InvalidInputError(f"expected a system whose parameters are open ({_one_of(_OPEN_PARAMETERS)}), "
                                f"got {system!r}, whose parameters are fixed: {_one_of(SYSTEM_PARAMETERS[system])}")
    current = SYSTEM_PARAMETERS[system]
    SYSTEM_PARAMETERS[system] = current + tuple(n for n in dict.fromkeys(names) if n not in current)


def register_system_quantities(system: str, names: Iterable[str]) -> None:
    """Allow more [output] quantity names for ``system`` (e.g. the falling cat's ``shape_*``).

    Registering a name twice is harmless, so a module may register at import.
    """
    names = _check_new_names(system, names, "quantity")
    current = QUANTITIES[system]
    QUANTITIES[system] = current + tuple(n for n in dict.fromkeys(names) if n not in current)
