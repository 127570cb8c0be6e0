"""A safe parser for formulas typed by a user: plain maths syntax, never ``eval``/``sympify``.

The text is parsed by Python's own grammar (:func:`ast.parse` in ``"eval"`` mode, which builds
a syntax tree and runs nothing) and the tree is walked with a whitelist.  A SymPy expression is
built only from these pieces:

=====================  ==================================================================
numbers                integer and decimal literals (``2``, ``0.5``, ``1.5e-3``); decimals
                       become exact rationals from their text (``0.1`` is 1/10, not a float)
names                  the chosen system's symbols (see :mod:`mechderive.formulas.systems`)
                       and the constant ``pi``; Euler's number is ``exp(1)`` (``E`` is the
                       heavy top's energy)
operators              ``+ - * / **`` and unary ``+ -``; ``^`` is read as ``**`` (the text is
                       rewritten before parsing, so ``a + b^2`` is a + b², not Python's xor)
functions              ``sin cos tan asin acos atan atan2 sinh cosh tanh exp log sqrt Abs``,
                       called by bare name with positional arguments
time derivative        ``dt(expr)``: the total time derivative (see :mod:`.check`)
claims                 ``LHS = RHS``: exactly one ``=``
=====================  ==================================================================

Everything else is refused with an :class:`~mechderive.errors.InvalidInputError` naming the
offending piece: other names, attribute access, subscripts, strings, lambdas, comprehensions,
keyword arguments, calls of anything not listed, comparisons, symbolic or large exponents
(an exponent must be a number p/q with |p|, q ≤ 100), numbers beyond 10^1000, text longer
than :data:`MAX_LENGTH` characters and nesting deeper than :data:`MAX_DEPTH`.  The limits are
checked before or while walking, so hostile input is refused in well under a millisecond per
character.  LaTeX is refused too (see :func:`parse_expression`).

The same walk serves every other piece of text a user gives, so that nothing typed ever reaches
``eval``, ``sympify`` or ``parse_expr``:

- :func:`parse_expression` with ``new_symbol``: unknown names become new symbols (``derive``'s
  pivot ``-h/2 - d``);
- :func:`parse_number`: one exact number (``9.81``, ``-1.5e-3``, ``1/3``), 0 or of magnitude
  10^-:data:`MAX_MAGNITUDE` to 10^:data:`MAX_MAGNITUDE` (``derive --set``, ``--moments``);
- :func:`as_expression`, :func:`as_matrix`: for values a *program* passes to a symbolic API
  (SymPy objects, numbers): text is refused there, since SymPy would evaluate it.

>>> import sympy as sp
>>> x = sp.Symbol("x", real=True)
>>> parse_expression("sin(x)^2 + 0.5*x", {"x": x})
x/2 + sin(x)**2
>>> parse_claim("x**2 = x*x", {"x": x})
(x**2, x**2)
>>> parse_expression("x.__class__", {"x": x})
Traceback (most recent call last):
...
mechderive.errors.InvalidInputError: expected a maths expression, got an attribute access 'x.__class__'
"""

from __future__ import annotations

import ast
import numbers
import re
from fractions import Fraction
from typing import Any, Callable, Mapping

import sympy as sp

from ..errors import InvalidInputError

__all__ = ["parse_expression", "parse_claim", "parse_number", "as_expression", "as_matrix", "dt", "FUNCTIONS",
           "MAX_LENGTH", "MAX_DEPTH", "MAX_EXPONENT", "MAX_MAGNITUDE"]

#: Longest accepted text, in characters.
MAX_LENGTH = 2000
#: Deepest accepted nesting (parentheses, function calls, powers, unary signs).
MAX_DEPTH = 40
#: Largest accepted |numerator| and denominator of an exponent.
MAX_EXPONENT = 100
#: Largest accepted size of a number, in bits (about 10^1000).
_MAX_BITS = 3400
#: A number given alone (:func:`parse_number`) is 0 or of magnitude 10^-300 … 10^300: within a
#: double's normal range, so that it survives the generated NumPy and C code.
MAX_MAGNITUDE = 300
#: Longest name accepted as a new symbol (``new_symbol`` of :func:`parse_expression`).
_MAX_NAME = 64
#: Names never made new symbols: they look like constants the parser does not offer.
_NOT_SYMBOLS = {"e": "Euler's number is exp(1)", "I": "complex numbers are not supported",
                "j": "complex numbers are not supported", "oo": "infinity is not a value",
                "nan": "not a number is not a value", "zoo": "infinity is not a value"}


class dt(sp.Function):  # noqa: N801 - printed as the user writes it
    """dt(expr): the total time derivative of ``expr``; a marker, expanded by :mod:`.check`."""

    nargs = 1

    @classmethod
    def eval(cls, arg):  # never evaluates by itself
        return None


#: The whitelisted functions: name → (SymPy function, number of arguments).
FUNCTIONS: dict[str, tuple] = {
    "sin": (sp.sin, 1), "cos": (sp.cos, 1), "tan": (sp.tan, 1),
    "asin": (sp.asin, 1), "acos": (sp.acos, 1), "atan": (sp.atan, 1), "atan2": (sp.atan2, 2),
    "sinh": (sp.sinh, 1), "cosh": (sp.cosh, 1), "tanh": (sp.tanh, 1),
    "exp": (sp.exp, 1), "log": (sp.log, 1), "sqrt": (sp.sqrt, 1), "Abs": (sp.Abs, 1),
    "dt": (dt, 1),
}
_CONSTANTS = {"pi": sp.pi}

_GENERIC_HINTS = {
    "t": "time is not a variable here; write a time derivative as dt(expr)",
    "d": "write a time derivative as dt(expr)",
    "diff": "write a time derivative as dt(expr)",
    "Derivative": "write a time derivative as dt(expr)",
    "e": "Euler's number is exp(1)",
    "I": "complex numbers are not supported",
    "j": "complex numbers are not supported",
    "oo": "infinity is not a value",
}

_NODE_NAMES = {
    ast.Attribute: "an attribute access", ast.Subscript: "a subscript", ast.Lambda: "a lambda",
    ast.ListComp: "a comprehension", ast.SetComp: "a comprehension", ast.DictComp: "a comprehension",
    ast.GeneratorExp: "a comprehension", ast.Compare: "a comparison", ast.BoolOp: "a boolean operator",
    ast.IfExp: "a conditional expression", ast.Tuple: "a tuple", ast.List: "a list", ast.Set: "a set",
    ast.Dict: "a dictionary", ast.NamedExpr: "an assignment", ast.JoinedStr: "an f-string",
    ast.Starred: "a starred argument", ast.Await: "an await", ast.Yield: "a yield",
    ast.YieldFrom: "a yield", ast.FormattedValue: "an f-string", ast.Slice: "a slice",
}
_OPERATORS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_DECIMAL = re.compile(r"^(?:\d[\d_]*)?(?:\.[\d_]*)?(?:[eE]([+-]?\d[\d_]*))?$")


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _a(what: str) -> str:
    return ("an " if what[:1] in "aeiou" else "a ") + what


def _check_text(text: object, what: str) -> str:
    """Type, length, LaTeX and nesting checks that need no parsing (all O(len))."""
    if not isinstance(text, str):
        raise InvalidInputError(f"expected the {what} as a string, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise InvalidInputError(f"expected {_a(what)} of at most {MAX_LENGTH} characters, got {len(text)}")
    if "\\" in text:
        raise InvalidInputError(
            f"expected plain maths syntax like 'I3*(psi_dot + cos(theta)*phi_dot)', got LaTeX {_short(text)!r}: "
            "LaTeX input is not supported (SymPy's parse_latex needs antlr4-python3-runtime 4.11 and "
            "misreads forms like \\sin\\theta\\dot\\phi as sin(theta*dot*phi))")
    if not text.strip():
        raise InvalidInputError(f"expected {_a(what)}, got an empty string")
    depth = deepest = 0
    for ch in text:
        if ch in "([{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in ")]}":
            depth -= 1
    if deepest > MAX_DEPTH:
        raise InvalidInputError(f"expected brackets nested at most {MAX_DEPTH} deep, got {deepest}")
    return text.replace("^", "**")


def _bits(r: sp.Rational) -> int:
    return int(r.p).bit_length() + int(r.q).bit_length()


class _Builder:
    """Walks a Python syntax tree, building a SymPy expression from whitelisted pieces only."""

    def __init__(self, text: str, names: Mapping[str, sp.Expr], hints: Mapping[str, str],
                 new_symbol: Callable[[str], sp.Expr] | None = None) -> None:
        self.text, self.names, self.hints, self.new_symbol = text, names, hints, new_symbol

    def _segment(self, node: ast.AST) -> str:
        return _short(ast.get_source_segment(self.text, node) or type(node).__name__)

    def _refuse(self, node: ast.AST, what: str) -> InvalidInputError:
        return InvalidInputError(f"expected a maths expression, got {what} {self._segment(node)!r}")

    def build(self, node: ast.AST, depth: int = 0) -> sp.Expr:
        if depth > MAX_DEPTH:
            raise InvalidInputError(f"expected an expression nested at most {MAX_DEPTH} deep, got deeper")
        if isinstance(node, ast.Constant):
            return self._constant(node)
        if isinstance(node, ast.Name):
            return self._name(node)
        if isinstance(node, ast.BinOp):
            return self._binop(node, depth)
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.USub):
                return -self.build(node.operand, depth + 1)
            if isinstance(node.op, ast.UAdd):
                return self.build(node.operand, depth + 1)
            raise self._refuse(node, "the operator")
        if isinstance(node, ast.Call):
            return self._call(node, depth)
        raise self._refuse(node, _NODE_NAMES.get(type(node), f"a {type(node).__name__}"))

    def _constant(self, node: ast.Constant) -> sp.Expr:
        value = node.value
        if isinstance(value, bool) or value is None or value is Ellipsis:
            raise self._refuse(node, "the constant")
        if isinstance(value, int):
            if value.bit_length() > _MAX_BITS:
                raise InvalidInputError(f"expected numbers below 10^1000, got {self._segment(node)!r}")
            return sp.Integer(value)
        if isinstance(value, float):
            literal = (ast.get_source_segment(self.text, node) or "").replace("_", "")
            match = _DECIMAL.match(literal)
            if not literal or match is None:
                raise self._refuse(node, "the number")
            if match.group(1) is not None and abs(int(match.group(1))) > MAX_EXPONENT:
                raise InvalidInputError(
                    f"expected a decimal exponent of at most {MAX_EXPONENT} in size, got {_short(literal)!r}")
            f = Fraction(literal)
            return sp.Rational(f.numerator, f.denominator)
        if isinstance(value, complex):
            raise self._refuse(node, "the imaginary number")
        if isinstance(value, (str, bytes)):
            raise self._refuse(node, "the string")
        raise self._refuse(node, "the constant")

    def _name(self, node: ast.Name) -> sp.Expr:
        name = node.id
        if name in self.names:
            return self.names[name]
        if name in _CONSTANTS:
            return _CONSTANTS[name]
        if name in FUNCTIONS:
            raise InvalidInputError(f"expected {name} to be called, like {name}(x), got {name!r} alone")
        if self.new_symbol is not None:
            return self._new_symbol(name)
        hint = self.hints.get(name) or _GENERIC_HINTS.get(name)
        known = ", ".join([*sorted(self.names, key=str.lower), "pi"])
        raise InvalidInputError(
            f"expected a known symbol, got unknown symbol {_short(name, 40)!r}"
            + (f" ({hint})" if hint else "") + f" — known symbols: {known}")

    def _new_symbol(self, name: str) -> sp.Expr:
        if name.startswith("_"):
            raise InvalidInputError(f"expected a symbol name starting with a letter, got {_short(name, 40)!r}")
        if name in _NOT_SYMBOLS:
            raise InvalidInputError(f"expected a symbol, got {name!r} ({_NOT_SYMBOLS[name]})")
        if len(name) > _MAX_NAME:
            raise InvalidInputError(f"expected a symbol name of at most {_MAX_NAME} characters, got {len(name)}")
        return self.new_symbol(name)  # type: ignore[misc]

    def _binop(self, node: ast.BinOp, depth: int) -> sp.Expr:
        op = type(node.op)
        if op not in _OPERATORS:
            raise self._refuse(node, "the operator in")
        if op is ast.Pow:
            base = self.build(node.left, depth + 1)
            return self._power(node, base, self._exponent(node.right, depth + 1))
        # Left-associated chains (a + b - c + ...) are walked iteratively: no depth for a long sum.
        group = (ast.Add, ast.Sub) if op in (ast.Add, ast.Sub) else (ast.Mult, ast.Div)
        chain: list[tuple[type, ast.AST]] = []
        left: ast.AST = node
        while isinstance(left, ast.BinOp) and isinstance(left.op, group):
            chain.append((type(left.op), left.right))
            left = left.left
        parts = [self.build(left, depth + 1)]
        for kind, right in reversed(chain):
            value = self.build(right, depth + 1)
            if kind is ast.Sub:
                value = -value
            elif kind is ast.Div:
                if value == 0:
                    raise InvalidInputError(
                        f"expected a nonzero divisor, got division by zero in {self._segment(node)!r}")
                value = 1 / value
            parts.append(value)
        return sp.Add(*parts) if op in (ast.Add, ast.Sub) else sp.Mul(*parts)

    def _exponent(self, node: ast.AST, depth: int) -> sp.Rational:
        value = self.build(node, depth)
        if not isinstance(value, sp.Rational):
            raise InvalidInputError(
                f"expected a numeric exponent (p/q with |p|, q ≤ {MAX_EXPONENT}), got {self._segment(node)!r}")
        if abs(value.p) > MAX_EXPONENT or value.q > MAX_EXPONENT:
            raise InvalidInputError(
                f"expected an exponent p/q with |p|, q ≤ {MAX_EXPONENT}, got {_short(str(value), 40)}")
        return value

    def _power(self, node: ast.BinOp, base: sp.Expr, exponent: sp.Rational) -> sp.Expr:
        if isinstance(base, sp.Rational):
            if base == 0 and exponent < 0:
                raise InvalidInputError(f"expected a nonzero base for a negative power, got {self._segment(node)!r}")
            if _bits(base) * abs(exponent.p) > _MAX_BITS:
                raise InvalidInputError(f"expected numbers below 10^1000, got {self._segment(node)!r}")
        result = base ** exponent
        for p in sp.preorder_traversal(result):
            if isinstance(p, sp.Pow) and isinstance(p.exp, sp.Rational) and abs(p.exp.p) > MAX_EXPONENT:
                raise InvalidInputError(
                    f"expected exponents p/q with |p| ≤ {MAX_EXPONENT} after combining powers, got {p.exp} "
                    f"in {self._segment(node)!r}")
        return result

    def _call(self, node: ast.Call, depth: int) -> sp.Expr:
        name = node.func.id if isinstance(node.func, ast.Name) else self._segment(node.func)
        if name not in FUNCTIONS:
            allowed = ", ".join(FUNCTIONS)
            hint = self.hints.get(name) or _GENERIC_HINTS.get(name)
            raise InvalidInputError(f"expected a call of one of {allowed}, got a call of {_short(name, 40)!r}"
                                    + (f" ({hint})" if hint else ""))
        if node.keywords:
            raise self._refuse(node, "keyword arguments in")
        func, arity = FUNCTIONS[name]
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self._refuse(node, "a starred argument in")
        if len(node.args) != arity:
            raise InvalidInputError(
                f"expected {name} with {arity} argument{'s' if arity > 1 else ''}, got {len(node.args)} "
                f"in {self._segment(node)!r}")
        return func(*[self.build(a, depth + 1) for a in node.args])


def _parse_tree(text: str) -> ast.Expression:
    try:
        return ast.parse(text, mode="eval")
    except SyntaxError as exc:
        where = f" at column {exc.offset}" if exc.offset else ""
        raise InvalidInputError(
            f"expected a formula in plain maths syntax (like 'I3*(psi_dot + cos(theta)*phi_dot)'), "
            f"got a syntax error{where} in {_short(text)!r}") from None
    except (ValueError, MemoryError, RecursionError):
        raise InvalidInputError(f"expected a formula in plain maths syntax, got {_short(text)!r}") from None


def parse_expression(text: str, names: Mapping[str, sp.Expr], *, hints: Mapping[str, str] | None = None,
                     what: str = "expression", new_symbol: Callable[[str], sp.Expr] | None = None) -> sp.Expr:
    """The SymPy expression for ``text``, built from whitelisted pieces only (see the module docstring).

    ``names`` maps each allowed name to what it stands for (usually a symbol); ``hints`` adds a
    suggestion to the error for a known-wrong name.  ``new_symbol``, if given, is called with
    each other name (a letter first, at most 64 characters, not ``e``, ``I``, ``j``, ``oo``) and
    returns what it stands for; without it such names are refused.  Raises
    :class:`~mechderive.errors.InvalidInputError` naming the offending piece.

    >>> import sympy as sp
    >>> parse_expression("__import__('os')", {})
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: expected a call of one of sin, cos, ..., dt, got a call of '__import__'
    >>> h = sp.Symbol("h", positive=True)
    >>> parse_expression("-h/2 - d", {"h": h}, new_symbol=lambda n: sp.Symbol(n, positive=True))
    -d - h/2
    """
    source = _check_text(text, what)
    tree = _parse_tree(source.strip())
    expr = _Builder(source.strip(), names, hints or {}, new_symbol).build(tree.body)
    if expr.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise InvalidInputError(f"expected a finite expression, got {expr} from {_short(text)!r}")
    return expr


def parse_claim(text: str, names: Mapping[str, sp.Expr], *, hints: Mapping[str, str] | None = None,
                what: str = "claim") -> tuple[sp.Expr, sp.Expr]:
    """(LHS, RHS) of a claim ``LHS = RHS`` (exactly one ``=``), each parsed by :func:`parse_expression`."""
    _check_text(text, what)
    for op in ("==", "<=", ">=", "!="):
        if op in text:
            raise InvalidInputError(f"expected one '=' between the two sides of the {what}, got {op!r}")
    if text.count("=") != 1:
        raise InvalidInputError(
            f"expected {_a(what)} 'LHS = RHS' with exactly one '=', got {text.count('=')} in {_short(text)!r}")
    left, right = text.split("=")
    return (parse_expression(left, names, hints=hints, what=f"left-hand side of the {what}"),
            parse_expression(right, names, hints=hints, what=f"right-hand side of the {what}"))



# ------------------------------------------------------------------------------------ numbers
_PLAIN_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE]([+-]?[0-9]+))?")


def _in_range(value: sp.Rational, label: str, text: str) -> sp.Rational:
    bound = sp.Integer(10) ** MAX_MAGNITUDE
    if value != 0 and not (1 / bound <= abs(value) <= bound):
        raise InvalidInputError(f"{label}: expected a number 0 or of magnitude 1e-{MAX_MAGNITUDE} to "
                                f"1e{MAX_MAGNITUDE}, got {_short(text)!r}")
    return value


def parse_number(text: str, label: str = "number") -> sp.Rational:
    """The exact rational number written in ``text``: a decimal (``9.81``, ``-1.5e-3``, ``0.1`` is 1/10),
    or arithmetic of numbers (``1/3``, ``2**-10``) parsed like :func:`parse_expression`.

    The number must be 0 or of magnitude 10^-:data:`MAX_MAGNITUDE` … 10^:data:`MAX_MAGNITUDE`; the
    size is checked on the text's exponent before any arithmetic, so ``1e999999999`` is refused at
    once.  Errors start with ``label`` (e.g. ``--set g``), the argument the text came from.

    >>> parse_number("9.81"), parse_number("-1/3"), parse_number("2.5e-3")
    (981/100, -1/3, 1/400)
    >>> parse_number("1e999999999", "--set g")
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: --set g: expected a number 0 or of magnitude 1e-300 to 1e300, got '1e999999999'
    """
    try:
        source = _check_text(text, "number").strip()
    except InvalidInputError as exc:
        raise InvalidInputError(f"{label}: {exc}") from None
    plain = _PLAIN_NUMBER.fullmatch(source)
    if plain is not None:
        # The mantissa has at most MAX_LENGTH digits, so a larger written exponent is out of range
        # whatever the digits; below that, Fraction's exact arithmetic takes microseconds.
        if plain.group(1) is not None and abs(int(plain.group(1))) > MAX_MAGNITUDE + MAX_LENGTH:
            return _in_range(sp.Integer(10) ** (MAX_MAGNITUDE + 1), label, source)
        f = Fraction(source)
        return _in_range(sp.Rational(f.numerator, f.denominator), label, source)
    try:
        value = parse_expression(source, {}, what="number")
    except InvalidInputError as exc:
        raise InvalidInputError(f"{label}: expected a number like 9.81, -1.5e-3 or 1/3, got {_short(source)!r}: "
                                f"{exc}") from None
    if not isinstance(value, sp.Rational):
        raise InvalidInputError(f"{label}: expected a rational number like 9.81, -1.5e-3 or 1/3, got "
                                f"{_short(source)!r} = {_short(str(value))}")
    return _in_range(value, label, source)


# ----------------------------------------------------------------------- values from a program
def _describe(value: Any) -> str:
    if isinstance(value, (str, bytes)):
        return (f"the text {_short(repr(value))} (text is never evaluated: build the expression from SymPy "
                f"symbols, or parse it with mechderive.formulas.parse_expression)")
    return f"{type(value).__name__} {_short(repr(value))}"


def as_expression(value: Any, what: str = "the value") -> sp.Expr:
    """``value`` as a SymPy expression, for symbolic APIs called by a program.

    SymPy expressions pass unchanged, Python and NumPy numbers become SymPy numbers; anything
    else — text above all, which ``sympify`` would evaluate as Python, and containers, whose
    strings it would evaluate too — is refused with an
    :class:`~mechderive.errors.InvalidInputError` naming ``what``.

    >>> as_expression(2.5), as_expression(sp.Symbol("x") + 1)
    (2.50000000000000, x + 1)
    >>> as_expression("__import__('os')", "`angle`")
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: expected `angle` to be a SymPy expression or a number, got the text ...
    """
    if isinstance(value, sp.Expr):
        return value
    if isinstance(value, numbers.Number) and not isinstance(value, bool):
        try:
            converted = sp.sympify(value, strict=True)
        except (sp.SympifyError, TypeError, ValueError):
            converted = None
        if isinstance(converted, sp.Expr):
            return converted
    raise InvalidInputError(f"expected {what} to be a SymPy expression or a number, got {_describe(value)}")


def as_matrix(value: Any, what: str = "the value") -> sp.Matrix:
    """``value`` (a SymPy matrix, or a list, tuple or array of rows or of entries) as a SymPy Matrix,
    each entry checked by :func:`as_expression` (so no text inside is ever evaluated).

    >>> as_matrix([1, sp.Symbol("x"), 0.5]).T
    Matrix([[1, x, 0.5]])
    """
    if isinstance(value, sp.MatrixBase):
        return sp.Matrix(value)
    if hasattr(value, "tolist") and not isinstance(value, sp.Basic):  # a NumPy array
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        rows = [[as_expression(e, f"each entry of {what}") for e in row] if isinstance(row, (list, tuple))
                else as_expression(row, f"each entry of {what}") for row in value]
        try:
            return sp.Matrix(rows)
        except (ValueError, TypeError) as exc:
            raise InvalidInputError(f"expected {what} to be a vector or a matrix with rows of equal length, "
                                    f"got {_short(repr(value))}") from exc
    return sp.Matrix([as_expression(value, what)])
