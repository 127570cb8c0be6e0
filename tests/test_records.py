"""The dataclasses whose methods are written once (:mod:`mechderive.core.records`) against ``@dataclass``.

Each class declared with ``@record`` writes its ``__init__`` out and inherits ``repr``, ``==``, ``hash`` and
the refusal to assign; here each is held to its own fields (``__init__``'s parameters, order, defaults:
a field added without its parameter fails) and to what ``@dataclass`` generates from the same fields.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import math
import re
from pathlib import Path

import pytest

from mechderive.core import records
from mechderive.core.records import Frozen, Record, record

PACKAGE = Path(__file__).resolve().parent.parent / "mechderive"


def _modules_with_records() -> list[str]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name != "records.py" and re.search(r"^@record$", path.read_text(encoding="utf-8"), re.M):
            parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
            out.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return out


MODULES = _modules_with_records()
for _module in MODULES:
    importlib.import_module(_module)
CLASSES = [c for c in records.CLASSES if c.__module__ in MODULES]


def test_every_module_with_records_is_checked():
    assert len(MODULES) >= 10 and len(CLASSES) >= len(MODULES)
    assert {c.__module__ for c in CLASSES} == set(MODULES)


def _same(a, b) -> bool:
    return a is b or a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: f"{c.__module__}.{c.__qualname__}")
def test_init_takes_the_fields_in_order_with_their_defaults(cls):
    fields = [f for f in dataclasses.fields(cls) if f.init]
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    assert [p.name for p in params] == [f.name for f in fields]
    for p, f in zip(params, fields):
        assert p.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD, p
        if f.default is not dataclasses.MISSING:
            assert _same(p.default, f.default), (p, f.default)
        elif f.default_factory is not dataclasses.MISSING:
            assert p.default is None, p  # None given: the factory's value
        else:
            assert p.default is inspect.Parameter.empty, p


def _reference(cls):
    """The dataclass ``@dataclass`` makes of ``cls``'s fields (no methods of its own)."""
    spec = [(f.name, f.type, dataclasses.field(default=f.default, default_factory=f.default_factory, repr=f.repr,
                                               compare=f.compare, hash=f.hash)) for f in dataclasses.fields(cls)]
    return dataclasses.make_dataclass(cls.__name__, spec, frozen=issubclass(cls, Frozen))


def _values(cls, shift: int = 0) -> dict:
    return {f.name: (i + shift, f"v{i}") for i, f in enumerate(dataclasses.fields(cls))}


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: f"{c.__module__}.{c.__qualname__}")
def test_the_methods_behave_as_the_generated_ones(cls):
    ref = _reference(cls)
    values = _values(cls)

    def ours(**changes):
        obj = object.__new__(cls)
        obj.__dict__.update({**values, **changes})
        return obj

    mine, theirs = ours(), ref(**values)
    assert repr(mine) == repr(theirs)
    assert mine == ours() and not mine != ours()
    assert (mine == values) is False and mine.__eq__(values) is NotImplemented
    for f in dataclasses.fields(cls):
        changed = ours(**{f.name: "other"})
        assert (mine == changed) == (theirs == ref(**{**values, f.name: "other"})) == (not f.compare), f.name
    if issubclass(cls, Frozen):
        assert hash(mine) == hash(theirs)
        name = dataclasses.fields(cls)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError, match=f"cannot assign to field '{name}'"):
            setattr(mine, name, 1)
        with pytest.raises(dataclasses.FrozenInstanceError):
            delattr(mine, name)
    else:
        assert cls.__hash__ is None and ref.__hash__ is None
    if not hasattr(cls, "__post_init__"):  # what __init__ sets, given every field and given only the required
        assert cls(**values).__dict__ == values
        required = {f.name: values[f.name] for f in dataclasses.fields(cls)
                    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
        assert cls(**required).__dict__.keys() == ref(**required).__dict__.keys()
        for k, v in ref(**required).__dict__.items():
            assert _same(cls(**required).__dict__[k], v), k
        first = dataclasses.fields(cls)[0].name
        assert dataclasses.replace(mine, **{first: "other"}).__dict__ == {**values, first: "other"}


def test_record_refuses_a_class_without_its_own_init():
    with pytest.raises(TypeError, match="own __init__"):
        @record
        class Bare(Frozen):
            """no __init__"""

            x: int

    with pytest.raises(TypeError, match="subclass of Frozen or Record"):
        @record
        class Plain:
            """not a Record"""

            x: int

            def __init__(self, x):
                self.x = x


def test_a_record_is_mutable_and_unhashable():
    @record
    class Point(Record):
        """x, y"""

        x: float
        y: float = 0.0

        def __init__(self, x: float, y: float = 0.0) -> None:
            self.__dict__.update(x=x, y=y)

    p = Point(1.0)
    p.y = 2.0
    assert p == Point(1.0, 2.0) and repr(p) == f"{Point.__qualname__}(x=1.0, y=2.0)"
    with pytest.raises(TypeError):
        hash(p)
    assert dataclasses.replace(p, x=3.0) == Point(3.0, 2.0) and dataclasses.asdict(p) == {"x": 1.0, "y": 2.0}
