"""The values of a scene, checked: numbers, lists and key sets, with messages naming the scene key.

Shared by the scene schema (:mod:`mechderive.scenes.schema`) and the systems' own checks of their
``[parameters]`` and ``[initial]`` (:meth:`mechderive.systems.base.System.check_parameters`), so
that every refusal reads the same: ``scene key [parameters].I1: expected a number > 0, got -1.0``.
Nothing here evaluates anything: a value is a number, a list, a string or a table, or it is refused.

A number that the TOML reader could not hold in a double (``1e400``, an integer of 400 digits) is
an :class:`Unrepresentable` (made by the reader), refused by :func:`number` naming its key.
"""

from __future__ import annotations

import datetime
import math
import re
import sys
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from ..errors import InvalidInputError, NonFiniteValueError

__all__ = ["Unrepresentable", "Underflowed", "show", "key_name", "at", "fail", "one_of", "number", "choice",
           "check_keys", "as_table", "rename_keys", "number_list", "SCENE_STRICT_HINT", "NAME_PATTERN"]

#: The physics checks' way out (their STRICT_HINT), as said to a scene's author.
SCENE_STRICT_HINT = "add strict = false to the scene to accept moments no rigid body has"
NAME_PATTERN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")  # a bare TOML key and a Python identifier


# ----------------------------------------------------------------------------- numbers

#: The largest finite double, as messages state the range of every number a scene holds.
LARGEST = sys.float_info.max


class Unrepresentable:
    """A number the scene's text spells but no double holds: ``1e400``, an integer of 401 digits.

    Made by the scene's TOML reader (:mod:`mechderive.scenes.schema`) in place of ``inf`` or an exception, so that the
    check of the key it is found under refuses it by name.
    """

    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return literal(self.text)


class Underflowed(float):
    """A nonzero float literal that is 0 in double precision (``1e-400``); it is 0 wherever 0 is allowed."""

    text: str

    def __repr__(self) -> str:
        return f"{literal(self.text)} (0 in double precision)"


def literal(text: str) -> str:
    """A number as the scene spells it, shortened if it is long (``1e-`` and 5000 digits)."""
    return text if len(text) <= 40 else f"{text[:12]}...{text[-12:]} (a number of {len(text)} characters)"


def digits(n: int) -> int:
    """The number of decimal digits of ``n``, without converting it to text (huge ints refuse that)."""
    n = abs(n)
    d = max(1, int(n.bit_length() * 0.30102999566398120))  # log10(2): exact or one short
    return d + (n >= 10 ** d)


# ----------------------------------------------------------------------------- messages

def show(value: Any, depth: int = 0) -> str:
    """The value as the message shows it: short, escaped, on one line, with its TOML kind when that helps."""
    if isinstance(value, bool):
        return f"{str(value).lower()} (a boolean)"
    if isinstance(value, (int, np.integer)) and digits(int(value)) > 40:
        return f"an integer of {digits(int(value))} digits"
    if isinstance(value, (int, float, Unrepresentable)):
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
        text = "[" + ", ".join(show(v, depth + 1) for v in value) + "]"
        return text if len(text) <= 80 else f"a list of {len(value)} items"
    return f"a {type(value).__name__}"


def key_name(key: Any) -> str:
    """A key as the message shows it: bare if it is a plain name, else quoted and escaped."""
    if isinstance(key, str) and NAME_PATTERN.fullmatch(key) and len(key) <= 40:
        return key
    return show(key)


def at(table: str | None, key: Any) -> str:
    return f"[{table}].{key_name(key)}" if table else key_name(key)


def fail(where: str, expected: str, value: Any, error: type[InvalidInputError] = InvalidInputError) -> None:
    raise error(f"scene key {where}: expected {expected}, got {show(value)}")


def one_of(names: Iterable[str]) -> str:
    return ", ".join(names)


# ----------------------------------------------------------------------------- value checks

def number(where: str, value: Any, *, expected: str = "a finite number",
            valid: Callable[[float], bool] = lambda x: True) -> float:
    """``value`` as a float; bool and non-numbers are refused, ints accepted, NaN/inf refused.

    Every number of a scene is a finite double: a value spelled beyond ±1.8e308 (``1e400``, an
    integer of 400 digits) is refused as not finite, naming the key, rather than read as inf.
    """
    finite = f"{expected} (a finite double: at most {LARGEST:.2g} in size)"
    if isinstance(value, Unrepresentable):
        fail(where, finite, value, NonFiniteValueError)
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        fail(where, expected, value)
    try:
        x = float(value)
    except OverflowError:  # an int beyond the largest double
        fail(where, finite, value, NonFiniteValueError)
    if not math.isfinite(x):
        fail(where, expected, x, NonFiniteValueError)
    if not valid(x):
        fail(where, expected, value)
    return x


def choice(where: str, value: Any, allowed: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in allowed:
        fail(where, "one of " + ", ".join(repr(a) for a in allowed), value)
    return value


def check_keys(given: Mapping[str, Any], table: str, allowed: tuple[str, ...], required: tuple[str, ...],
                what: str) -> None:
    for key in given:
        if key not in allowed:
            allowed_text = f"expected one of {one_of(allowed)}" if allowed else "it takes none"
            raise InvalidInputError(f"scene key {at(table, key)}: unknown {what}; {allowed_text}")
    for key in required:
        if key not in given:
            raise InvalidInputError(f"scene key {at(table, key)}: missing; expected all of {one_of(required)}")


def as_table(where: str, value: Any) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise InvalidInputError(f"scene table {where}: expected a table, got {show(value)}")
    return value


def rename_keys(exc: InvalidInputError, table: str, names: tuple[str, ...]) -> InvalidInputError:
    """Re-word an error of a physics check so that it names the scene keys it is about."""
    message = str(exc)
    claim = message.split(";")[0]  # the checked relation; later clauses are hints
    involved = [k for k in names if re.search(rf"(?<![A-Za-z0-9_]){re.escape(k)}(?![A-Za-z0-9_])", claim)]
    where = ("scene key" + ("s " if len(involved) > 1 else " ") + ", ".join(f"[{table}].{k}" for k in involved)
             if involved else f"scene table [{table}]")
    return type(exc)(f"{where}: {message}")


def number_list(where: str, value: Any, size: int, expected: str) -> tuple[float, ...]:
    """A list of ``size`` finite numbers (``expected`` says what it is, e.g. "[w1, w2, w3] (rad/s)")."""
    if not isinstance(value, (list, tuple)) or len(value) != size:
        fail(where, expected, value)
    return tuple(number(f"{where}[{i}]", w) for i, w in enumerate(value))
