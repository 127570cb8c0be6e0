"""A ``lagrangian`` system's definition: its coordinates, its Lagrangian and its output expressions, checked.

The scene gives them as text; a program as SymPy expressions or text (:func:`from_objects`).  Text is
read by the whitelist parser :func:`mechderive.formulas.parse.parse_expression`, never evaluated.  In
the Lagrangian each name is

* a coordinate ``q`` (listed in ``coordinates``), or its velocity ``q_dot``;
* ``t``, the time (then L depends on t explicitly and the energy is not conserved);
* any other name: a parameter, whose value ``[parameters]`` must give.

What is refused, each with the scene key it is about: a coordinate name that is no plain identifier,
is a function or constant of the parser (``sin``, ``pi``), ``t``, or ends in ``_dot``; two equal
coordinates; a coordinate that appears in L neither as ``q`` nor as ``q_dot``; an acceleration
``q_ddot`` or ``dt(...)`` in L; ``x_dot`` where ``x`` is no coordinate; an output expression whose
name is already an output (``energy``, ``p_<q>``, a coordinate or velocity).  The mass matrix and
the parameters are checked by :mod:`.model` and :mod:`.system`.
"""

from __future__ import annotations

import hashlib
import keyword
from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Sequence

import sympy as sp

from ...core.symbols import state_symbol, t as TIME
from ...errors import InvalidInputError
from ...formulas.parse import FUNCTIONS, dt, parse_expression

__all__ = ["Definition", "parse_definition", "from_objects", "MAX_COORDINATES", "MAX_EXPRESSIONS", "RESERVED"]

#: Most coordinates a definition may have.  The compiled elimination grows fast with them: a chain of n
#: planar links builds (derive + generate + compile C, cold) in 2.1 s for n = 6, 3.7 s for 7, 14 s for 8
#: (measured; the C printer is cse-first, so the DAG is never walked as a tree), beyond which the C
#: compiler's time on the generated file dominates.  (A Lagrangian's text is also bounded, 2000 chars.)
MAX_COORDINATES = 8
#: Most output expressions.
MAX_EXPRESSIONS = 50
#: Names that are neither coordinates nor parameters: the parser's functions and constants, and time.
RESERVED = {**{name: "a function" for name in FUNCTIONS}, "pi": "the constant π", "t": "the time",
            "e": "Euler's number (write exp(1))", "E": "reserved (Euler's number is exp(1))",
            "I": "the imaginary unit", "j": "the imaginary unit", "oo": "infinity", "nan": "not a number",
            "zoo": "complex infinity"}
_MAX_NAME = 64


@dataclass(frozen=True)
class Definition:
    """One concrete Lagrangian system.

    ``lagrangian`` is L in the state symbols ``q, q_dot`` (:func:`~mechderive.core.symbols.state_symbol`),
    the time symbol t if ``uses_time``, and the parameter symbols (real symbols named as in
    ``parameters``, sorted by name).  ``expressions`` are (name, expression) of the extra outputs, in
    the same symbols.  ``digest`` is a short hash of all of it (the output expressions' compiled code
    carries it); ``dynamics_digest`` one of the coordinates, L and the parameters L uses
    (``dynamics_parameters``, sorted): the equations of motion's compiled code carries it, so that a
    new output expression compiles nothing else again.
    """

    coordinates: tuple[str, ...]
    lagrangian: sp.Expr
    parameters: tuple[str, ...]
    expressions: tuple[tuple[str, sp.Expr], ...]
    uses_time: bool
    digest: str
    source: str
    dynamics_parameters: tuple[str, ...] = ()
    dynamics_digest: str = ""

    @property
    def positions(self) -> tuple[sp.Symbol, ...]:
        return tuple(state_symbol(q) for q in self.coordinates)

    @property
    def velocities(self) -> tuple[sp.Symbol, ...]:
        return tuple(state_symbol(q + "_dot") for q in self.coordinates)

    @property
    def parameter_symbols(self) -> tuple[sp.Symbol, ...]:
        return tuple(parameter_symbol(p) for p in self.parameters)

    @property
    def dynamics_symbols(self) -> tuple[sp.Symbol, ...]:
        return tuple(parameter_symbol(p) for p in self.dynamics_parameters)


def parameter_symbol(name: str) -> sp.Symbol:
    """The real symbol of parameter ``name`` (the same object for the same name)."""
    return sp.Symbol(name, real=True)


def _fail(key: str, message: str) -> InvalidInputError:
    return InvalidInputError(f"scene key {key}: {message}")


def check_coordinates(value: Any, key: str = "coordinates") -> tuple[str, ...]:
    """The coordinate names: a non-empty list of distinct identifiers that are no function, constant or t."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise _fail(key, f"expected a list of coordinate names like [\"theta\", \"phi\"], got {_show(value)}")
    if not value:
        raise _fail(key, "expected at least one coordinate, got an empty list")
    if len(value) > MAX_COORDINATES:
        raise _fail(key, f"expected at most {MAX_COORDINATES} coordinates (the generated code grows too fast beyond), "
                         f"got {len(value)}")
    names: list[str] = []
    for q in value:
        if not isinstance(q, str):
            raise _fail(key, f"expected each coordinate as a name (text), got {_show(q)}")
        _check_name(q, key, "coordinate")
        for suffix in ("_dot", "_ddot"):
            if q.endswith(suffix):
                raise _fail(key, f"expected coordinate names without the suffix {suffix} (q_dot is the velocity "
                                 f"of q), got {q!r}")
        if q in names:
            raise _fail(key, f"expected distinct coordinates, got {q!r} twice")
        names.append(q)
    for q in names:
        if q.startswith("p_") and q[2:] in names:
            raise _fail(key, f"expected no coordinate named like the momentum of another, got {q!r} and {q[2:]!r}")
        if q == "energy":
            raise _fail(key, "expected a coordinate name other than 'energy' (an output), got 'energy'")
    return tuple(names)


def _check_name(name: str, key: str, what: str) -> None:
    if not name.isidentifier() or keyword.iskeyword(name) or not name.isascii():
        raise _fail(key, f"expected each {what} name to be a plain identifier (letters, digits, _), got {_show(name)}")
    if name.startswith("_"):
        raise _fail(key, f"expected each {what} name to start with a letter, got {name!r}")
    if len(name) > _MAX_NAME:
        raise _fail(key, f"expected {what} names of at most {_MAX_NAME} characters, got {len(name)}")
    if name in RESERVED:
        raise _fail(key, f"expected a {what} name that is not {RESERVED[name]}, got {name!r} (name clash)")


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:59] + "…"


class _Names:
    """The names a formula may use: coordinates, velocities, t, and parameters (collected as they appear)."""

    def __init__(self, coordinates: Sequence[str], key: str, known_parameters: Iterable[str] = (),
                 open_parameters: bool = True) -> None:
        self.coordinates, self.key, self.open = tuple(coordinates), key, open_parameters
        self.names: dict[str, sp.Expr] = {"t": TIME}
        for q in coordinates:
            self.names[q] = state_symbol(q)
            self.names[q + "_dot"] = state_symbol(q + "_dot")
        for p in known_parameters:
            self.names[p] = parameter_symbol(p)
        self.new: list[str] = []
        self.hints = {q + "_ddot": "a Lagrangian depends on the coordinates and velocities only, not on accelerations"
                      for q in coordinates}

    def new_symbol(self, name: str) -> sp.Expr:
        if name.endswith("_ddot") and name[:-5] in self.coordinates:
            raise _fail(self.key, f"expected no acceleration in a Lagrangian (it depends on q and q_dot only), "
                                  f"got {name!r}")
        if name.endswith("_dot"):
            listed = ", ".join(self.coordinates)
            raise _fail(self.key, f"expected velocities of the coordinates ({listed}), got {name!r}: "
                                  f"{name[:-4]!r} is not a coordinate")
        if name in RESERVED:
            raise _fail(self.key, f"expected {name!r} as {RESERVED[name]}, got it used as a symbol")
        if not self.open:
            known = ", ".join(n for n in self.names if n != "t")
            raise _fail(self.key, f"unknown symbol {name!r}: expected a coordinate, a velocity, t or a parameter "
                                  f"({known})")
        if name not in self.new:
            self.new.append(name)
        return parameter_symbol(name)

    def parse(self, text: Any, what: str) -> sp.Expr:
        try:
            expr = parse_expression(text, self.names, hints=self.hints, what=what, new_symbol=self.new_symbol)
        except InvalidInputError as exc:
            message = str(exc)
            raise (exc if message.startswith("scene ") else _fail(self.key, message)) from None
        if expr.has(dt):
            raise _fail(self.key, f"expected no time derivative dt(...) in the {what} (write velocities as q_dot), "
                                  f"got {_show(text)}")
        return expr


def _digest(*parts: str) -> str:
    return hashlib.sha256("\x00".join(parts).encode()).hexdigest()[:12]


def _build(coordinates: tuple[str, ...], L: sp.Expr, parameters: list[str], expressions: list[tuple[str, sp.Expr]],
           key: str, source: str) -> Definition:
    positions = [state_symbol(q) for q in coordinates]
    velocities = [state_symbol(q + "_dot") for q in coordinates]
    free = L.free_symbols
    for q, x, v in zip(coordinates, positions, velocities):
        if x not in free and v not in free:
            raise _fail(key, f"expected every coordinate in the Lagrangian, got no {q} and no {q}_dot in it "
                             f"(a coordinate missing from the Lagrangian)")
    names = set(coordinates) | {q + "_dot" for q in coordinates}
    for name, _ in expressions:
        if name in names or name == "energy" or (name.startswith("p_") and name[2:] in coordinates):
            raise _fail(f"[output.expressions].{name}", f"expected a name that is not already an output "
                                                        f"(coordinates, velocities, energy, p_<q>), got {name!r}")
        if name in parameters:
            raise _fail(f"[output.expressions].{name}", f"expected a name that is not a parameter, got {name!r}")
    parameters = sorted(parameters)
    dynamics = sorted(p for p in parameters if parameter_symbol(p) in free)
    text = "\x00".join([",".join(coordinates), sp.srepr(L), ",".join(dynamics)])
    full = "\x00".join([text, ",".join(parameters), *(f"{n}={sp.srepr(e)}" for n, e in expressions)])
    return Definition(coordinates=coordinates, lagrangian=L, parameters=tuple(parameters),
                      expressions=tuple(expressions), uses_time=L.has(TIME), digest=_digest(full), source=source,
                      dynamics_parameters=tuple(dynamics), dynamics_digest=_digest(text))


def parse_definition(definition: Mapping[str, Any]) -> Definition:
    """The :class:`Definition` of a scene's keys ``coordinates``, ``lagrangian`` and ``[output.expressions]``."""
    for key in ("coordinates", "lagrangian"):
        if key not in definition:
            raise _fail(key, "missing; system 'lagrangian' needs top-level keys coordinates (a list of names) "
                             "and lagrangian (a formula of the coordinates, their velocities q_dot, t and parameters)")
    coordinates = check_coordinates(definition["coordinates"])
    text = definition["lagrangian"]
    if not isinstance(text, str):
        raise _fail("lagrangian", f"expected the Lagrangian as text like \"m*l**2/2*theta_dot**2 + m*g*l*cos(theta)\", "
                                  f"got {_show(text)}")
    names = _Names(coordinates, "lagrangian")
    L = names.parse(text, "Lagrangian")
    parameters = list(names.new)
    expressions = _parse_expressions(definition.get("output.expressions", {}), coordinates, parameters)
    exprs_text = "".join(f"\x00{k}={v}" for k, v in dict(definition.get("output.expressions", {})).items())
    return _build(coordinates, L, parameters, expressions, "lagrangian", text + exprs_text)


def _parse_expressions(table: Any, coordinates: tuple[str, ...], parameters: list[str]) -> list[tuple[str, sp.Expr]]:
    if not isinstance(table, Mapping):
        raise InvalidInputError(f"scene table [output.expressions]: expected a table of name = \"formula\", "
                                f"got {_show(table)}")
    if len(table) > MAX_EXPRESSIONS:
        raise InvalidInputError(f"scene table [output.expressions]: expected at most {MAX_EXPRESSIONS} expressions, "
                                f"got {len(table)}")
    out = []
    for name, text in table.items():
        key = f"[output.expressions].{name}"
        if not isinstance(name, str):
            raise InvalidInputError(f"scene table [output.expressions]: expected names as text, got {_show(name)}")
        _check_name(name, key, "output")
        if not isinstance(text, str):
            raise _fail(key, f"expected a formula as text like \"l*sin(theta)\", got {_show(text)}")
        names = _Names(coordinates, key, parameters)
        expr = names.parse(text, "output expression")
        parameters.extend(n for n in names.new if n not in parameters)
        out.append((name, expr))
    return out


def _is_time(args: tuple) -> bool:
    """Whether ``args`` is (t,): the time symbol of any assumptions (``dynamicsymbols`` use a plain t)."""
    return len(args) == 1 and isinstance(args[0], sp.Symbol) and args[0].name == "t"


def _as_name(value: Any, what: str) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, sp.Symbol):
        return value.name
    if isinstance(value, sp.core.function.AppliedUndef) and _is_time(value.args):
        return value.func.__name__
    raise InvalidInputError(f"expected each {what} as a name, a SymPy Symbol or a function of t like q(t), "
                            f"got {_show(value)}")


def from_objects(lagrangian: Any, coordinates: Sequence[Any], parameters: Sequence[Any] = ()) -> Definition:
    """The :class:`Definition` of a Lagrangian given by a program: SymPy or text (parsed by the whitelist).

    ``coordinates``: names, Symbols or functions of t (``coordinate("theta")``); in a SymPy Lagrangian
    q may be a symbol ``q`` or a function ``q(t)``, its velocity a symbol ``q_dot`` or ``q(t).diff(t)``.
    ``parameters``: names or Symbols; every other symbol of L must be among them (t is the time).
    """
    if isinstance(coordinates, (str, sp.Basic)) or not hasattr(coordinates, "__iter__"):
        raise _fail("coordinates", f"expected a sequence of coordinates, got {_show(coordinates)}")
    coords = check_coordinates([_as_name(q, "coordinate") for q in coordinates])
    if isinstance(parameters, (str, sp.Basic)) or not hasattr(parameters, "__iter__"):
        raise _fail("[parameters]", f"expected a sequence of parameter names or Symbols, got {_show(parameters)}")
    params = [_as_name(p, "parameter") for p in parameters]
    for p in params:
        _check_name(p, f"[parameters].{p}", "parameter")
        if p in coords or (p.endswith("_dot") and p[:-4] in coords):
            raise _fail(f"[parameters].{p}", f"expected a parameter name that is no coordinate or velocity, "
                                             f"got {p!r} (name clash)")
    if len(set(params)) != len(params):
        raise _fail("[parameters]", f"expected distinct parameter names, got {params}")
    if isinstance(lagrangian, str):
        names = _Names(coords, "lagrangian", params, open_parameters=False)
        L = names.parse(lagrangian, "Lagrangian")
        return _build(coords, L, params, [], "lagrangian", lagrangian)
    from ...formulas.parse import as_expression

    L = as_expression(lagrangian, "the Lagrangian")
    # functions of t and their derivatives → state symbols; given symbols → the canonical real symbols
    subs: dict[Any, Any] = {}
    for d in L.atoms(sp.Derivative):
        name = _as_name(d.expr, "coordinate") if isinstance(d.expr, sp.core.function.AppliedUndef) else None
        if name in coords and _is_time(d.variables):
            subs[d] = state_symbol(name + "_dot")
        else:
            raise _fail("lagrangian", f"expected at most first time derivatives of the coordinates, got {d}")
    L = L.xreplace(subs)
    for f in L.atoms(sp.core.function.AppliedUndef):
        name = f.func.__name__
        if name in coords and _is_time(f.args):
            subs[f] = state_symbol(name)
        else:
            raise _fail("lagrangian", f"expected functions of t only for the coordinates ({', '.join(coords)}), "
                                      f"got {f}")
    L = L.xreplace(subs)
    allowed = {**{q: state_symbol(q) for q in coords}, **{q + "_dot": state_symbol(q + "_dot") for q in coords},
               "t": TIME, **{p: parameter_symbol(p) for p in params}}
    ren = {}
    for s in L.free_symbols:
        if s.name not in allowed:
            known = ", ".join(allowed)
            raise _fail("lagrangian", f"unknown symbol {s.name!r}: expected a coordinate, a velocity, t or a "
                                      f"parameter ({known})")
        ren[s] = allowed[s.name]
    L = L.xreplace(ren)
    if L.has(dt) or L.atoms(sp.Derivative):
        raise _fail("lagrangian", f"expected no derivative in the Lagrangian beyond the velocities, got {L}")
    if L.has(sp.zoo, sp.nan, sp.oo, -sp.oo, sp.I):
        raise _fail("lagrangian", f"expected a finite real Lagrangian, got {L}")
    return _build(coords, L, params, [], "lagrangian", sp.srepr(L))


def with_expressions(definition: Definition, table: Mapping[str, Any]) -> Definition:
    """``definition`` with the output expressions of a scene's ``[output.expressions]`` table added."""
    parameters = list(definition.parameters)
    expressions = [*definition.expressions,
                   *_parse_expressions(table, definition.coordinates, parameters)]
    source = definition.source + "".join(f"\x00{k}={v}" for k, v in dict(table).items())
    return _build(definition.coordinates, definition.lagrangian, parameters, expressions, "lagrangian", source)
