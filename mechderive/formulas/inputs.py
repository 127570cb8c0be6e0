"""The claim and the --given entries of ``mechderive check``, parsed within limits; errors name the input.

:mod:`.parse` limits each text (length, nesting, numbers, exponents).  Names defined by --given
are substituted as parsed, so that a few short entries can combine beyond those limits: each
using the previous name many times builds a tree of 3^k nodes, ``x*x*…`` with x = 10^999 a
number of millions of digits, or with x = θ^100 a power of exponent 10^4 and more (and SymPy
multiplies big integers without a pause for a timer).  The same limits then apply to every
parsed side and --given value, names substituted: at most :data:`MAX_INPUT_NODES` nodes,
:data:`MAX_INPUT_DEPTH` deep, numbers below 10^1000, exponents p/q with |p|, q ≤ 100.

Every error starts with the input it is about: ``claim 'E = x': …``, ``given 'I2 = x': …``
(the command line says ``--given``); an error SymPy itself raises while building an expression
(``atan2(0, log(0))``: "Invalid NaN comparison") is an input error too.
"""

from __future__ import annotations

import keyword
import math
from contextlib import contextmanager
from typing import Iterator, Sequence

import sympy as sp

from ..errors import InvalidInputError
from .parse import FUNCTIONS, MAX_EXPONENT, MAX_LENGTH, dt, parse_claim, parse_expression
from .size import brief, tree_size
from .systems import System

__all__ = ["parse_givens", "parse_claim_within_limits", "bounded_input", "specialise", "naming", "label", "shown",
           "sympy_failure", "MAX_INPUT_NODES", "MAX_INPUT_DEPTH", "MAX_GIVEN", "SYMPY_ERRORS"]

#: The largest tree a parsed side or --given value may have once the --given names are substituted.
MAX_INPUT_NODES = 20_000
#: The deepest nesting a parsed side or --given value may have once the --given names are substituted
#: (the parser allows 40 in one text; SymPy's recursive algorithms fail near 150 once dt is expanded).
MAX_INPUT_DEPTH = 60
#: The most --given entries.
MAX_GIVEN = 20
_MAX_BITS = 3400  # numbers below about 10^1000, as the parser's literals
#: What SymPy itself raises on some inputs while building or transforming an expression: atan2(0, zoo)
#: "Invalid NaN comparison" (TypeError); sinh(sinh(…(30)…)) asks mpmath for 1 << 10^k (MemoryError, at
#: once: nothing is allocated); a recursion too deep.  (InvalidInputError, a ValueError, is caught before.)
SYMPY_ERRORS = (TypeError, ValueError, ArithmeticError, RecursionError, NotImplementedError, MemoryError)


def label(what: str, text: object) -> str:
    """How an error names the input it is about: ``claim 'E = x'``, ``given 'I2 = x'``."""
    words = text if isinstance(text, str) else type(text).__name__
    return f"{what} {words[:40] + '…' if len(words) > 40 else words!r}"


def bounded_input(expr: sp.Expr, what: str) -> None:
    """Refuse what the parser's limits let through by combining (see the module docstring)."""
    if tree_size(expr, MAX_INPUT_NODES + 1) > MAX_INPUT_NODES:
        raise InvalidInputError(f"expected {what} of at most {MAX_INPUT_NODES} nodes once the --given names are "
                                f"substituted, got more")
    depth = nesting(expr)
    if depth > MAX_INPUT_DEPTH:
        raise InvalidInputError(f"expected {what} nested at most {MAX_INPUT_DEPTH} deep once the --given names are "
                                f"substituted, got {depth}")
    for r in expr.atoms(sp.Rational):
        bits = max(int(r.p).bit_length(), int(r.q).bit_length())
        if bits > _MAX_BITS:  # (its digits counted from its bits: str() refuses more than 4300 of them)
            raise InvalidInputError(f"expected numbers below 10^1000 in {what}, got one of about "
                                    f"{round(bits * math.log10(2))} digits")
    for p in expr.atoms(sp.Pow):
        if isinstance(p.exp, sp.Rational) and (abs(p.exp.p) > MAX_EXPONENT or p.exp.q > MAX_EXPONENT):
            raise InvalidInputError(f"expected exponents p/q with |p|, q ≤ {MAX_EXPONENT} in {what} once the "
                                    f"--given names are substituted, got {brief(p.exp, 40)}")


def nesting(expr: sp.Basic) -> int:
    """The depth of ``expr``'s tree (a leaf is 1), walked without recursion."""
    deepest, stack = 0, [(expr, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        stack.extend((a, depth + 1) for a in node.args)
    return deepest


def parse_givens(given: Sequence[str], system: System, rename: dict | None = None) -> tuple[dict, list, list]:
    """(names for parsing, [(symbol, value)] specialisations, [new names]) from ``name = expression`` texts.

    A specialisation's value has the earlier specialisations substituted (``I2 = I1`` then
    ``I3 = I2`` makes I3 = I1).  ``rename`` maps symbols to stand-ins used throughout (the
    assumption-free parameters of :func:`_positivity_used`).  An error names the entry.
    """
    rename = rename or {}
    if isinstance(given, str) or not isinstance(given, Sequence):
        raise InvalidInputError(f"given: expected a list of 'name = expression' strings, got {shown(given)}")
    if len(given) > MAX_GIVEN:
        raise InvalidInputError(f"given: expected at most {MAX_GIVEN} entries, got {len(given)}")
    names: dict[str, sp.Expr] = {n: rename.get(s, s) for n, s in system.names.items()}
    specs: list[tuple[sp.Symbol, sp.Expr]] = []
    new: list[str] = []
    for text in given:
        with naming(label("given", text)):
            _parse_given(text, system, rename, names, specs, new)
    return names, specs, new


@contextmanager
def naming(label: str) -> Iterator[None]:
    """An input error inside, prefixed with ``label``; so is an error SymPy raises while building the
    expression (``atan2(0, log(0))``: "Invalid NaN comparison"), which is the input's, not a bug."""
    try:
        yield
    except InvalidInputError as exc:
        raise InvalidInputError(f"{label}: {exc}") from None
    except SYMPY_ERRORS as exc:
        raise InvalidInputError(f"{label}: expected an expression SymPy can build, got {sympy_failure(exc)}") from None


def sympy_failure(exc: BaseException) -> str:
    """One line saying what SymPy raised (a MemoryError has no message: a number too large to hold)."""
    text = str(exc).strip().splitlines()[0][:80] if str(exc).strip() else ""
    if isinstance(exc, MemoryError):
        text = text or "a number too large to hold (a constant like sinh(sinh(…(30)…)) that SymPy evaluates)"
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _parse_given(text: object, system: System, rename: dict, names: dict, specs: list, new: list) -> None:
    """One --given entry into ``names`` (a new name) or ``specs`` (a specialisation)."""
    if not isinstance(text, str) or len(text) > MAX_LENGTH or text.count("=") != 1 or "==" in text:
        raise InvalidInputError("expected 'name = expression' with one '=' and at most "
                                f"{MAX_LENGTH} characters, got {shown(text)}")
    left, right = (s.strip() for s in text.split("="))
    if not left.isidentifier() or keyword.iskeyword(left) or not left.isascii():
        raise InvalidInputError(f"expected 'name = expression' with a plain name on the left, got {left[:60]!r}")
    if left in FUNCTIONS or left == "pi":
        raise InvalidInputError(f"expected a name that is not a function or constant, got {left!r}")
    value = parse_expression(right, names, hints=system.hints, what=f"value of {left}")
    bounded_input(value, f"the value of {left}")
    if left in new:
        raise InvalidInputError(f"expected each new name defined once, got {left!r} twice")
    if left not in system.names:
        names[left] = value
        new.append(left)
        return
    sym = system.names[left]
    kind = system.kind(sym)
    if kind not in ("state", "parameter"):
        what = {"defined": "the defined quantity", "derivative": "the time derivative"}.get(kind, "the symbol")
        raise InvalidInputError(
            f"expected a new name or a state variable or parameter to specialise, got {what} "
            f"{left!r} (fixed by {'its definition' if kind == 'defined' else 'the equations of motion'})")
    if value.has(dt):
        raise InvalidInputError(f"expected a value without dt() for {left}, got {right.strip()[:60]!r}")
    value = specialise(system.expand_definitions(value).xreplace(rename), specs)
    bounded_input(value, f"the value of {left}")
    sym = rename.get(sym, sym)
    if value.has(sym):
        raise InvalidInputError(f"expected the value of {left} not to depend on {left}, got {brief(value)}")
    if sym.is_positive and value.is_positive is False:
        raise InvalidInputError(f"expected a positive value for {left}, got {brief(value)}")
    beyond = sorted(s.name for s in value.free_symbols if system.kind(s) == "derivative")
    if beyond:
        raise InvalidInputError(f"expected the value of {left} in the state and the parameters, got {beyond[0]}")
    specs.append((sym, value))


def parse_claim_within_limits(claim: object, names: dict, system: System) -> tuple[sp.Expr, sp.Expr]:
    """(LHS, RHS) of the claim, within the input limits; an error names the claim."""
    with naming(label("claim", claim)):
        sides = parse_claim(claim, names, hints=system.hints)
        for side, x in zip(("left", "right"), sides):
            bounded_input(x, f"the {side}-hand side")
    return sides


def specialise(expr: sp.Expr, specs: list) -> sp.Expr:
    for sym, value in specs:
        expr = expr.xreplace({sym: value})
    return expr


def shown(value: object) -> str:
    """A short repr of something that is not an expression (for an error message)."""
    text = repr(value)
    return text if len(text) <= 60 else text[:59] + "…"
