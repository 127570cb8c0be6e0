"""Values with units in scene files: ``theta = "30 deg"``, ``psi_dot = "1000 rpm"``, ``I1 = "12 kg*cm^2"``.

A bare number in a scene is SI (radians, rad/s, kg m², m/s², ...) as each key's unit says
(:attr:`mechderive.systems.base.Key.unit`).  A string is a number followed by a unit, read by
`pint <https://pint.readthedocs.io>`_ (the optional extra ``units``: ``pip install "mechderive[units]"``),
imported only when such a string appears, and converted to the key's SI unit on reading.

No ambiguity is let through: pint counts the radian as dimensionless, so that ``"1 Hz"`` would
silently become 1 rad/s (a cycle per second is 2π rad/s) and ``"2"`` an angle.  Here a key whose
SI unit holds radians (an angle, a rate) takes only a unit that holds them too (deg, turn, rpm,
rad/s, deg/s, ...), and any other key only a unit without them; ``"1 Hz"`` for a rate is refused,
saying why.  The text is checked against a plain pattern (a decimal number, then unit names,
``*``, ``/``, ``^`` and integer powers, at most 64 characters) before pint sees it: nothing in it is
evaluated as code.

>>> to_si("[initial].theta", "30 deg", "rad")   # doctest: +SKIP
0.5235987755982988
"""

from __future__ import annotations

import math
import re
from functools import lru_cache
from typing import Any

from ..errors import InvalidInputError

__all__ = ["to_si", "factor_to", "is_unit_string", "MAX_TEXT"]

MAX_TEXT = 64
# a decimal number, then a unit expression: names, *, /, ^ or ** with a small integer power, spaces, brackets
_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d{1,3})?"
_UNIT = r"[A-Za-z_µΩ°][A-Za-z_0-9µΩ°]*(?:\s*(?:\^|\*\*)\s*-?[1-9])?"
_EXPRESSION = rf"\(?\s*{_UNIT}(?:\s*[*/ ]\s*\(?\s*{_UNIT}\s*\)?)*\s*\)?"


@lru_cache(maxsize=None)
def _pattern(which: str) -> re.Pattern:
    """The compiled pattern of a number with a unit (``value``) or of a unit alone (``unit``): compiled on the
    first text to look at, not on import (~3 ms of every run, which mostly has no text to convert)."""
    expression = rf"\s*({_NUMBER})\s*({_EXPRESSION})\s*" if which == "value" else rf"\s*({_EXPRESSION})\s*"
    return re.compile(expression)


def is_unit_string(value: Any) -> bool:
    """Whether a scene value is text shaped as a number with a unit ("30 deg"); any other text is left to the
    key's own check, which refuses it as not a number."""
    return isinstance(value, str) and len(value) <= MAX_TEXT and _pattern("value").fullmatch(value) is not None


@lru_cache(maxsize=1)
def _registry() -> Any:
    try:
        import pint
    except ImportError:  # pragma: no cover - the test extra installs pint
        raise InvalidInputError("values with units (\"30 deg\") need pint: pip install 'mechderive[units]'") from None
    return pint.UnitRegistry()


def _si_text(si: str) -> str:
    """A key's unit as pint reads it: ``"kg m^2/s"`` → ``"kg*m**2/s"``, ``"1"`` → dimensionless."""
    return "dimensionless" if si in ("", "1") else si.replace(" ", "*").replace("^", "**")


def _radians(registry: Any, unit: Any) -> float:
    """The power of radian in ``unit``'s root units (pint keeps it there, though it calls it dimensionless)."""
    _, root = registry.get_root_units(unit)
    return float(dict(root._units).get("radian", 0))


@lru_cache(maxsize=256)
def factor_to(where: str, unit_text: str, si: str) -> float:
    """The factor from ``unit_text`` to the SI unit ``si`` (a key's or a column's); refused, naming ``where``,
    when the text is not a unit, or one of another dimension, or one that differs in radians (Hz for rad/s)."""
    if not isinstance(unit_text, str) or len(unit_text) > MAX_TEXT or not _pattern("unit").fullmatch(unit_text):
        raise InvalidInputError(f"{where}: expected a unit such as \"deg\", \"rpm\", \"kg*cm^2\" (names, *, /, ^ "
                                f"and small integer powers, at most {MAX_TEXT} characters), got {unit_text!r}")
    if si == "":
        raise InvalidInputError(f"{where}: expected a number in the system's own units (the system does not say "
                                f"the unit of this key), got the unit {unit_text!r}")
    registry = _registry()
    import pint

    try:
        given = registry.parse_units(unit_text.strip())
        target = registry.parse_units(_si_text(si))
    except (pint.errors.PintError, AttributeError, TypeError, ValueError, SyntaxError) as exc:
        raise InvalidInputError(f"{where}: expected a unit pint knows (deg, rpm, rad/s, kg*cm^2, m/s^2, ...), "
                                f"got {unit_text!r} ({type(exc).__name__}: {exc})") from None
    if registry.get_dimensionality(given) != registry.get_dimensionality(target):
        raise InvalidInputError(f"{where}: expected a unit of {si} ({registry.get_dimensionality(target)}), got "
                                f"{unit_text!r}, which is {registry.get_dimensionality(given)}")
    if _radians(registry, given) != _radians(registry, target):
        hint = (" (a cycle per second is 2π rad/s: say \"rpm\", \"turn/s\" or \"rad/s\")"
                if _radians(registry, target) else "")
        raise InvalidInputError(f"{where}: expected a unit of {si}, got {unit_text!r}, which "
                                f"{'does not count' if _radians(registry, target) else 'counts'} radians{hint}")
    factor = float(registry.Quantity(1.0, given).to(target).magnitude)
    if not math.isfinite(factor) or factor == 0:
        raise InvalidInputError(f"{where}: expected a unit convertible to {si}, got {unit_text!r} "
                                f"(factor {factor!r})")
    return factor


def to_si(where: str, text: str, si: str) -> float:
    """``text`` ("30 deg") as a number in the SI unit ``si`` of the key ``where`` ("[initial].theta")."""
    match = _pattern("value").fullmatch(text) if isinstance(text, str) and len(text) <= MAX_TEXT else None
    if match is None:
        raise InvalidInputError(f"{where}: expected a number, or a number with a unit such as \"30 deg\", "
                                f"\"1000 rpm\", \"12 kg*cm^2\" (at most {MAX_TEXT} characters), got {text!r}")
    number, unit = match.groups()
    value = float(number) * factor_to(where, unit, si)
    if not math.isfinite(value):
        raise InvalidInputError(f"{where}: expected a finite value, got {text!r} = {value!r} {si}")
    return value
