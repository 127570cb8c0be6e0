"""What ``derive`` substitutes into a system's derived equations: a body shape, numbers, a pivot.

- ``shape``: a standard body of :mod:`mechderive.inertia.bodies` (``solid_cone``, ``disc``, …),
  its inertia *derived* by integration there.  The body's own axes are principal (checked);
  axis 3 is the symmetry axis of a heavy top.  Moments are taken about the ``pivot``, a point
  (0, 0, z) on axis 3 in the body's coordinates: by default the body's frame origin for the
  heavy top (the apex of ``solid_cone``, the centre of the others) and the centre of mass for
  the free top.  For the heavy top, l = (centre of mass)₃ − z.
- ``moments``: numbers (I1, I2, I3); the heavy top needs I1 = I2.  Checked to be moments of
  a body (> 0, triangle inequalities: :func:`mechderive.inertia.check_principal_moments`).
- ``values``: {name: number} for any symbol left in the results (``g=9.81``); numbers are
  kept exact (decimal text becomes a rational).

A pivot given as text is an expression in the body's dimension symbols (``-h/2``); other
names in it become new positive symbols (``-d``).
"""

from __future__ import annotations

import keyword
import numbers
import re
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import sympy as sp

from ..errors import InvalidInputError

__all__ = ["Options", "as_number", "parse_assignment", "body_parameters"]


def as_number(value: Any, what: str) -> sp.Expr:
    """An exact SymPy number from a real number or its decimal text (``"9.81"`` → 981/100)."""
    if isinstance(value, bool):
        raise InvalidInputError(f"expected {what} to be a real number, got {value!r}")
    if isinstance(value, sp.Basic) and value.is_number and value.is_real:
        return value  # type: ignore[return-value]
    if isinstance(value, numbers.Real):
        return sp.Rational(str(value)) if isinstance(value, float) else sp.Integer(int(value))
    if isinstance(value, str) and re.fullmatch(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?(/\d+)?", value.strip()):
        return sp.Rational(value.strip())
    raise InvalidInputError(f"expected {what} to be a real number, got {value!r}")


def parse_assignment(text: str) -> tuple[str, sp.Expr]:
    """``"NAME=NUMBER"`` → (name, exact number), for ``--set``.

    >>> parse_assignment("g=9.81")
    ('g', 981/100)
    """
    name, sep, value = text.partition("=")
    if not sep or not name.strip().isidentifier():
        raise InvalidInputError(f"expected NAME=NUMBER, got {text!r}")
    return name.strip(), as_number(value, f"the value of {name.strip()}")


def _parse_pivot(value: Any, dimensions: Mapping[str, sp.Symbol]) -> sp.Expr:
    if value is None:
        return None  # type: ignore[return-value]
    if isinstance(value, sp.Basic):
        return value  # type: ignore[return-value]
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return as_number(value, "the pivot")
    if not isinstance(value, str):
        raise InvalidInputError(f"expected the pivot as a number, an expression or its text, got {value!r}")
    from sympy.parsing.sympy_parser import parse_expr, standard_transformations

    names = set(re.findall(r"[A-Za-z_]\w*", value))
    bad = [n for n in names if keyword.iskeyword(n) or n.startswith("_")]
    if bad:
        raise InvalidInputError(f"expected the pivot as an arithmetic expression, got {value!r}")
    local = {n: dimensions.get(n, sp.Symbol(n, positive=True)) for n in names}
    allowed = {"Integer": sp.Integer, "Float": sp.Float, "Rational": sp.Rational, "Symbol": sp.Symbol}
    try:
        expr = parse_expr(value, local_dict=local, global_dict=allowed, transformations=standard_transformations)
    except Exception as exc:  # SymPy raises many kinds here
        raise InvalidInputError(f"expected the pivot as an arithmetic expression, got {value!r}") from exc
    if not isinstance(expr, sp.Expr) or expr.has(sp.I):
        raise InvalidInputError(f"expected the pivot as a real expression, got {value!r}")
    return expr


@dataclass(frozen=True)
class Options:
    """The options of one ``derive`` request (see the module docstring)."""

    sequence: str = "ZXZ"
    frame: str | None = None
    shape: str | None = None
    pivot: Any = None
    moments: Sequence[Any] | None = None
    values: Mapping[Any, Any] = field(default_factory=dict)
    simplify: bool = False

    def __post_init__(self) -> None:
        from .sequences import check_sequence

        seq, fr = check_sequence(self.sequence, self.frame)
        object.__setattr__(self, "sequence", seq)
        object.__setattr__(self, "frame", fr)
        if self.shape is not None and self.moments is not None:
            raise InvalidInputError("expected a body shape or numeric moments, got both")
        if self.shape is not None:
            from ..inertia.bodies import BODIES

            if self.shape not in BODIES:
                raise InvalidInputError(f"expected a shape among {', '.join(BODIES)}, got {self.shape!r}")
        if self.pivot is not None and self.shape is None:
            raise InvalidInputError(f"expected a shape with the pivot, got pivot {self.pivot!r} and no shape")
        if self.moments is not None:
            ms = list(self.moments)
            if len(ms) != 3:
                raise InvalidInputError(f"expected three moments I1 I2 I3, got {len(ms)}")
            nums = tuple(as_number(m, f"I{k}") for k, m in enumerate(ms, start=1))
            from ..inertia.validate import check_principal_moments

            check_principal_moments(*(float(m) for m in nums))
            object.__setattr__(self, "moments", nums)
        if not isinstance(self.values, Mapping):
            raise InvalidInputError(f"expected values as a mapping name -> number, got {type(self.values).__name__}")
        vals = {}
        for k, v in self.values.items():
            name = k.name if isinstance(k, sp.Symbol) else k
            if not isinstance(name, str):
                raise InvalidInputError(f"expected each value's name to be a string or a Symbol, got {k!r}")
            vals[name] = as_number(v, f"the value of {name}")
        object.__setattr__(self, "values", vals)

    @property
    def is_default_sequence(self) -> bool:
        """Whether the chapter's body-fixed ZXZ (3.54) is asked for."""
        return self.sequence == "ZXZ" and self.frame == "body"

    def pivot_expr(self) -> sp.Expr | None:
        """The pivot's coordinate z on axis 3 as a SymPy expression (None if not given)."""
        from ..inertia.bodies import body_model

        dims = {s.name: s for s in body_model(self.shape).spec.symbols} if self.shape else {}
        dims["M"] = sp.Symbol("M", positive=True)
        return _parse_pivot(self.pivot, dims)


def body_parameters(options: Options, *, default_pivot: str) -> dict[str, sp.Expr]:
    """{"I1", "I2", "I3", "l", "pivot"} of the shape about its pivot (``default_pivot`` "origin" or "centre").

    Raises unless the body's axes are principal about the pivot and the pivot lies on axis 3
    with the centre of mass.
    """
    from ..inertia.bodies import body_inertia_symbolic

    body = body_inertia_symbolic(options.shape)
    com = body.centre_of_mass
    if any(sp.simplify(c) != 0 for c in com[:2]):
        raise InvalidInputError(f"expected the centre of mass on axis 3, got {list(com)} for {options.shape!r}")
    z = options.pivot_expr()
    if z is None:
        z = sp.Integer(0) if default_pivot == "origin" else com[2]
    I = body.inertia_about(sp.Matrix([0, 0, z])).applyfunc(sp.factor)
    off = [I[i, j] for i in range(3) for j in range(3) if i != j]
    if any(sp.simplify(e) != 0 for e in off):
        raise InvalidInputError(f"expected the body's axes to be principal about the pivot, got products of "
                                f"inertia {off} for {options.shape!r}")
    return {"I1": I[0, 0], "I2": I[1, 1], "I3": I[2, 2], "l": sp.factor(com[2] - z), "pivot": z}
