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

Text is never evaluated: a number given as text (``"9.81"``, ``"1/3"``) is read by
:func:`mechderive.formulas.parse.parse_number` — 0 or of magnitude 1e-300 to 1e300, the same
range for numbers given as such; a pivot given as text is an expression in the body's dimension
symbols (``-h/2``) read by the whitelist parser :func:`mechderive.formulas.parse.parse_expression`,
where other names become new positive symbols (``-d``).  A pivot typed as text is an algebraic expression
(arithmetic and ``sqrt``, no other function) that stays small: at most :data:`MAX_PIVOT_SYMBOLS`
symbols, total degree :data:`MAX_PIVOT_DEGREE`, and over a common denominator and expanded,
numerator terms × denominator terms at most :data:`MAX_PIVOT_TERMS`.  The parallel-axis theorem
squares it and the results are factored, whose cost grows quickly with each of these (measured on
2 shared cores: ≤ ~1.5 s at the limits, where (a+b+c+d+f+g+k+m+n+p)**2/(q+r)**2 took 30 s and
(a*b*c*d*f*g)**100 did not finish).

Errors name the option they are about (``pivot: expected …``); the command line passes
:data:`CLI_LABELS` so that they name its arguments (``--pivot: expected …``, ``--set g: …``).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Mapping, Sequence

import sympy as sp

from ..errors import InvalidInputError, MechDeriveError
from ..formulas.parse import MAX_MAGNITUDE, dt, parse_expression, parse_number

__all__ = ["Options", "as_number", "parse_assignment", "body_parameters", "API_LABELS", "CLI_LABELS",
           "MAX_PIVOT_TERMS", "MAX_PIVOT_SYMBOLS", "MAX_PIVOT_DEGREE"]

#: How errors name each option in the Python API ...
API_LABELS: Mapping[str, str] = {"pivot": "pivot", "moments": "moments", "shape": "shape",
                                 "values": "values[{name!r}]"}
#: ... and on the command line.
CLI_LABELS: Mapping[str, str] = {"pivot": "--pivot", "moments": "--moments", "shape": "--shape",
                                 "values": "--set {name}"}
#: Most terms of a pivot over a common denominator, numerator terms × denominator terms:
#: (a+b+c+d)**2 has 10, (a+b)/(c+d+f+g+k) 2 × 5.
MAX_PIVOT_TERMS = 10
#: Most symbols in a pivot.
MAX_PIVOT_SYMBOLS = 6
#: Highest total degree of a pivot (a Mul adds its factors' degrees, x**(p/q) counts |p| times).
MAX_PIVOT_DEGREE = 4
_MAX_NAME = 64


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _in_range(value: sp.Expr, label: str, shown: Any) -> sp.Expr:
    """``value`` if it is 0 or of magnitude 1e-300 … 1e300 (exact for rationals), else raise."""
    bound = sp.Integer(10) ** MAX_MAGNITUDE
    magnitude = abs(value)
    try:
        inside = magnitude == 0 or (bool(magnitude >= 1 / bound) and bool(magnitude <= bound))
    except TypeError:  # a comparison SymPy cannot decide
        inside = False
    if not inside:
        shown = repr(shown) if isinstance(shown, str) else str(shown)
        raise InvalidInputError(f"{label}: expected a number 0 or of magnitude 1e-{MAX_MAGNITUDE} to "
                                f"1e{MAX_MAGNITUDE}, got {_short(shown)}")
    return value


def as_number(value: Any, label: str) -> sp.Expr:
    """An exact SymPy number from a real number or its text (``"9.81"`` → 981/100, never evaluated).

    Accepted: text read by :func:`~mechderive.formulas.parse.parse_number`, Python and NumPy
    integers, fractions and finite floats (a float ``x`` stands for the decimal ``repr(x)``),
    and real SymPy numbers; 0 or of magnitude 1e-300 to 1e300.  Errors start with ``label``.

    >>> as_number("9.81", "--set g"), as_number(0.1, "g"), as_number(2, "g")
    (981/100, 1/10, 2)
    """
    if isinstance(value, str):
        return parse_number(value, label)
    if isinstance(value, bool) or value is None:
        raise InvalidInputError(f"{label}: expected a real number, got {value!r}")
    if isinstance(value, sp.Basic):
        if not (isinstance(value, sp.Expr) and value.is_number and value.is_extended_real and value.is_finite):
            raise InvalidInputError(f"{label}: expected a finite real number, got {_short(str(value))}")
        return _in_range(value, label, value)
    if isinstance(value, numbers.Integral):
        return _in_range(sp.Integer(int(value)), label, value)
    if isinstance(value, numbers.Rational):
        return _in_range(sp.Rational(int(value.numerator), int(value.denominator)), label, value)
    if isinstance(value, numbers.Real):
        f = float(value)
        if not math.isfinite(f):
            raise InvalidInputError(f"{label}: expected a finite real number, got {value!r}")
        exact = Fraction(repr(f))
        return _in_range(sp.Rational(exact.numerator, exact.denominator), label, value)
    raise InvalidInputError(f"{label}: expected a real number, got {type(value).__name__} {_short(repr(value))}")


def parse_assignment(text: str) -> tuple[str, sp.Expr]:
    """``"NAME=NUMBER"`` → (name, exact number), for ``--set`` (errors name ``--set NAME``).

    >>> parse_assignment("g=9.81")
    ('g', 981/100)
    """
    name, sep, value = text.partition("=")
    name = name.strip()
    if not sep or not name.isidentifier() or not name.isascii() or len(name) > _MAX_NAME:
        raise InvalidInputError(f"--set: expected NAME=NUMBER with NAME a symbol's name, got {_short(text)!r}")
    return name, as_number(value, CLI_LABELS["values"].format(name=name))


# ------------------------------------------------------------------------------------------ pivot
def _expanded_terms(expr: sp.Expr, limit: int) -> tuple[int, int]:
    """Upper bounds of the number of terms of numerator and denominator of ``expr`` brought over a
    common denominator and expanded (functions and fractional powers count as one term each, their
    arguments are bounded on their own).  Counts beyond ``limit`` are returned as ``limit + 1``.
    """
    def cap(n: int) -> int:
        return min(n, limit + 1)

    if not expr.args:
        return 1, 1
    if isinstance(expr, sp.Add):
        parts = [_expanded_terms(a, limit) for a in expr.args]
        den = cap(math.prod(d for _, d in parts))
        num = cap(sum(n * cap(math.prod(d for j, (_, d) in enumerate(parts) if j != i))
                      for i, (n, _) in enumerate(parts)))
        return num, den
    if isinstance(expr, sp.Mul):
        parts = [_expanded_terms(a, limit) for a in expr.args]
        return cap(math.prod(n for n, _ in parts)), cap(math.prod(d for _, d in parts))
    if isinstance(expr, sp.Pow) and expr.exp.is_Integer:
        k = abs(int(expr.exp))
        n, d = _expanded_terms(expr.base, limit)
        up, down = cap(math.comb(n + k - 1, k)), cap(math.comb(d + k - 1, k))
        return (up, down) if expr.exp > 0 else (down, up)
    for a in expr.args:  # a function or a fractional power: one term, its arguments bounded too
        if max(_expanded_terms(a, limit)) > limit:
            return limit + 1, 1
    return 1, 1


def _degree(expr: sp.Expr) -> float:
    """The total degree of an algebraic ``expr`` in its symbols and radicals (inf if not algebraic)."""
    if expr.is_Symbol:
        return 1
    if expr.is_number:
        return 0
    if isinstance(expr, sp.Add):
        return max(_degree(a) for a in expr.args)
    if isinstance(expr, sp.Mul):
        return sum(_degree(a) for a in expr.args)
    if isinstance(expr, sp.Pow) and expr.exp.is_Rational:
        return abs(int(expr.exp.p)) * _degree(expr.base)
    return math.inf


def _check_pivot_text(expr: sp.Expr, label: str) -> None:
    """Refuse a pivot typed as text beyond the limits of the module docstring (its cost grows with them)."""
    functions = sorted({type(f).__name__ for f in expr.atoms(sp.Function)})
    if functions:
        raise InvalidInputError(f"{label}: expected an algebraic pivot (arithmetic and sqrt) like -h/2 or h/4 - d, "
                                f"got {functions[0]} in {_short(str(expr))}")
    for number in expr.atoms(sp.Rational):
        _in_range(number, f"{label}: each number", number)
    num, den = _expanded_terms(expr, MAX_PIVOT_TERMS)
    if (num * den > MAX_PIVOT_TERMS or len(expr.free_symbols) > MAX_PIVOT_SYMBOLS
            or _degree(expr) > MAX_PIVOT_DEGREE):
        raise InvalidInputError(f"{label}: expected a pivot like -h/2 or h/4 - d, with at most {MAX_PIVOT_SYMBOLS} "
                                f"symbols, degree {MAX_PIVOT_DEGREE} and {MAX_PIVOT_TERMS} terms (numerator × "
                                f"denominator) when expanded, got {_short(str(expr))}")


def _parse_pivot(value: Any, dimensions: Mapping[str, sp.Symbol], label: str) -> sp.Expr | None:
    """The pivot's z: text is parsed and held to the limits; a SymPy expression (from a program) is taken
    as it is; either must be real and free of dt."""
    if value is None:
        return None
    if isinstance(value, str):
        try:
            expr = parse_expression(value, dimensions, what="pivot",
                                    new_symbol=lambda name: sp.Symbol(name, positive=True))
        except InvalidInputError as exc:
            raise InvalidInputError(f"{label}: {exc}") from None
    elif isinstance(value, sp.Basic):
        if not isinstance(value, sp.Expr):
            raise InvalidInputError(f"{label}: expected an expression, got {type(value).__name__} "
                                    f"{_short(str(value))}")
        expr = value
    elif isinstance(value, numbers.Real) and not isinstance(value, bool):
        return as_number(value, label)
    else:
        raise InvalidInputError(f"{label}: expected the pivot as a number, an expression or its text, got "
                                f"{type(value).__name__} {_short(repr(value))}")
    if expr.has(dt):
        raise InvalidInputError(f"{label}: expected a point on axis 3, got a time derivative in {_short(str(expr))}")
    if expr.has(sp.I) or expr.is_extended_real is False:
        raise InvalidInputError(f"{label}: expected a real expression, got {_short(str(expr))}")
    if expr.is_number:
        return _in_range(expr, label, value)
    if isinstance(value, str):
        _check_pivot_text(expr, label)
    return expr


@dataclass(frozen=True)
class Options:
    """The options of one ``derive`` request (see the module docstring).

    ``labels`` says how errors name the options (:data:`API_LABELS` by default, the command
    line passes :data:`CLI_LABELS`).
    """

    sequence: str = "ZXZ"
    frame: str | None = None
    shape: str | None = None
    pivot: Any = None
    moments: Sequence[Any] | None = None
    values: Mapping[Any, Any] = field(default_factory=dict)
    simplify: bool = False
    labels: Mapping[str, str] = field(default_factory=lambda: API_LABELS, repr=False, compare=False)

    def label(self, option: str, name: str = "") -> str:
        """How errors name ``option`` (and, for ``values``, the symbol ``name``)."""
        return self.labels.get(option, API_LABELS[option]).format(name=name)

    def __post_init__(self) -> None:
        from .sequences import check_sequence

        seq, fr = check_sequence(self.sequence, self.frame)
        object.__setattr__(self, "sequence", seq)
        object.__setattr__(self, "frame", fr)
        if self.shape is not None and self.moments is not None:
            raise InvalidInputError(f"{self.label('shape')}, {self.label('moments')}: expected a body shape or "
                                    "numeric moments, got both")
        if self.shape is not None:
            from ..inertia.bodies import BODIES

            if self.shape not in BODIES:
                raise InvalidInputError(f"{self.label('shape')}: expected a shape among {', '.join(BODIES)}, "
                                        f"got {_short(repr(self.shape))}")
        if self.pivot is not None:
            if self.shape is None:
                raise InvalidInputError(f"{self.label('pivot')}: expected a shape with the pivot, got pivot "
                                        f"{_short(repr(self.pivot))} and no shape")
            object.__setattr__(self, "pivot", _parse_pivot(self.pivot, self._dimensions(), self.label("pivot")))
        if self.moments is not None:
            object.__setattr__(self, "moments", self._checked_moments())
        if not isinstance(self.values, Mapping):
            raise InvalidInputError(f"{self.label('values', '…')}: expected values as a mapping name -> number, "
                                    f"got {type(self.values).__name__}")
        vals = {}
        for k, v in self.values.items():
            name = k.name if isinstance(k, sp.Symbol) else k
            if not isinstance(name, str) or not name.isidentifier():
                raise InvalidInputError(f"expected each value's name to be a symbol's name or a Symbol, got "
                                        f"{_short(repr(k))}")
            vals[name] = as_number(v, self.label("values", name))
        object.__setattr__(self, "values", vals)

    def _dimensions(self) -> dict[str, sp.Symbol]:
        from ..inertia.bodies import body_model

        dims = {s.name: s for s in body_model(self.shape).spec.symbols}
        dims["M"] = sp.Symbol("M", positive=True)
        return dims

    def _checked_moments(self) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
        label = self.label("moments")
        try:
            ms = None if isinstance(self.moments, (str, bytes, Mapping)) else list(self.moments)
        except TypeError:
            ms = None
        if ms is None:
            raise InvalidInputError(f"{label}: expected three moments I1 I2 I3, got {_short(repr(self.moments))}")
        if len(ms) != 3:
            raise InvalidInputError(f"{label}: expected three moments I1 I2 I3, got {len(ms)}")
        nums = tuple(as_number(m, f"{label} I{k}") for k, m in enumerate(ms, start=1))
        from ..inertia.validate import check_principal_moments

        try:
            check_principal_moments(*(float(m) for m in nums))
        except MechDeriveError as exc:
            raise type(exc)(f"{label}: {exc}") from None
        return nums  # type: ignore[return-value]

    @property
    def is_default_sequence(self) -> bool:
        """Whether the chapter's body-fixed ZXZ (3.54) is asked for."""
        return self.sequence == "ZXZ" and self.frame == "body"

    def pivot_expr(self) -> sp.Expr | None:
        """The pivot's coordinate z on axis 3 as a SymPy expression (None if not given)."""
        return self.pivot

    def body_parameters(self, *, default_pivot: str) -> dict[str, sp.Expr]:
        """:func:`body_parameters` of these options: what a system's ``Derivation.substitute`` calls."""
        return body_parameters(self, default_pivot=default_pivot)


def body_parameters(options: Options, *, default_pivot: str) -> dict[str, sp.Expr]:
    """{"I1", "I2", "I3", "l", "pivot"} of the shape about its pivot (``default_pivot`` "origin" or "centre").

    Raises unless the body's axes are principal about the pivot and the pivot lies on axis 3
    with the centre of mass.
    """
    from ..inertia.bodies import body_inertia_symbolic

    body = body_inertia_symbolic(options.shape)
    com = body.centre_of_mass
    if any(sp.simplify(c) != 0 for c in com[:2]):
        raise InvalidInputError(f"{options.label('shape')}: expected the centre of mass on axis 3, got {list(com)} "
                                f"for {options.shape!r}")
    z = options.pivot_expr()
    if z is None:
        z = sp.Integer(0) if default_pivot == "origin" else com[2]
    I = body.inertia_about(sp.Matrix([0, 0, z])).applyfunc(sp.factor)
    off = [I[i, j] for i in range(3) for j in range(3) if i != j]
    if any(sp.simplify(e) != 0 for e in off):
        raise InvalidInputError(f"{options.label('shape')}: expected the body's axes to be principal about the "
                                f"pivot, got products of inertia {off} for {options.shape!r}")
    return {"I1": I[0, 0], "I2": I[1, 1], "I3": I[2, 2], "l": sp.factor(com[2] - z), "pivot": z}
