"""Dataclasses whose methods are written once, not generated at every import (private helper).

``@dataclass(frozen=True)`` writes the source of ``__init__``, ``__repr__``, ``__eq__``, ``__hash__``,
``__setattr__`` and ``__delattr__`` and compiles each with ``exec`` when the class is defined: ~1–2 ms
per class (Python 3.11), ~20 ms of a warm ``mechderive run`` over the ~16 classes it loads, a tenth
of the whole process.  A class here is a dataclass all the same — :func:`dataclasses.fields`,
:func:`~dataclasses.replace`, :func:`~dataclasses.asdict` and :func:`~dataclasses.is_dataclass` see its
fields — declared with :func:`record` (``@dataclass(init=False, repr=False, eq=False)``: field
bookkeeping only, ~0.15 ms), whose ``__init__`` is written out in the class (a ``field(default_factory=f)``
is given the default None there and gets ``f()``), and whose other methods are inherited: from
:class:`Frozen` (``frozen=True``) or :class:`Record` (a plain ``@dataclass``), generic over the fields and
behaving as the generated ones: the same ``repr``, ``==`` on the same class over the compared fields
(``NotImplemented`` otherwise), the hash of those fields (frozen) or none, and
:class:`dataclasses.FrozenInstanceError` on assignment (frozen).  tests/test_records.py holds every
such class to its fields (``__init__``'s parameters, their order and defaults) and to what
``@dataclass`` generates.
"""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar

from ..errors import ArgumentError

__all__ = ["Frozen", "Record", "record", "CLASSES"]

T = TypeVar("T", bound=type)

#: every class declared with :func:`record` so far in this process (the test checks them)
CLASSES: list[type] = []


def record(cls: T) -> T:
    """Declare ``cls`` (a subclass of :class:`Frozen` or :class:`Record` with its own ``__init__``) a dataclass of
    its annotated fields, without generating any method."""
    if not issubclass(cls, Record) or "__init__" not in cls.__dict__:
        raise ArgumentError(f"{cls.__qualname__}: expected a subclass of Frozen or Record with its own __init__")
    cls = dataclasses.dataclass(init=False, repr=False, eq=False)(cls)
    fields = dataclasses.fields(cls)
    cls._repr_fields = tuple(f.name for f in fields if f.repr)
    cls._compared_fields = tuple(f.name for f in fields if f.compare)
    cls._hashed_fields = tuple(f.name for f in fields if (f.compare if f.hash is None else f.hash))
    CLASSES.append(cls)
    return cls


class Record:
    """The methods ``@dataclass`` (eq=True, not frozen) generates, over the fields :func:`record` found."""

    __slots__ = ()
    _repr_fields: tuple[str, ...] = ()
    _compared_fields: tuple[str, ...] = ()
    _hashed_fields: tuple[str, ...] = ()

    __hash__ = None  # type: ignore[assignment] - mutable and compared by value: unhashable, as @dataclass makes it

    def __repr__(self) -> str:
        values = self.__dict__
        return f"{type(self).__qualname__}(" + ", ".join(f"{k}={values[k]!r}" for k in self._repr_fields) + ")"

    def __eq__(self, other: object) -> Any:
        if other.__class__ is self.__class__:
            mine, theirs = self.__dict__, other.__dict__
            return tuple(mine[k] for k in self._compared_fields) == tuple(theirs[k] for k in self._compared_fields)
        return NotImplemented


class Frozen(Record):
    """The methods ``@dataclass(frozen=True)`` generates: :class:`Record`'s, a hash, and no assignment.

    ``__init__`` sets the fields with ``self.__dict__.update(...)`` (``__post_init__`` work with
    ``object.__setattr__``, as in a frozen dataclass); ``functools.cached_property`` works as there.
    """

    __slots__ = ()

    def __hash__(self) -> int:
        values = self.__dict__
        return hash(tuple(values[k] for k in self._hashed_fields))

    def __setattr__(self, name: str, value: Any) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot delete field {name!r}")
