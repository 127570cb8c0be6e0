"""Generated code from SymPy expressions: standalone NumPy (Python) and C99 functions.

Below :mod:`mechderive.solvers`, which compiles the derived right-hand sides with
:func:`to_c_source`; :mod:`mechderive.derive.formats` prints the same functions for ``derive``.

- :func:`to_python_source` — a standalone NumPy function (common subexpressions eliminated by
  :func:`sympy.cse`, printed by SymPy's ``NumPyPrinter``) whose docstring lists the argument
  order and units; it broadcasts like :func:`mechderive.core.compile.compile_expressions`:
  a result of shape S at arguments broadcasting to B has shape B + S;
- :func:`to_c_source` — a C99 function (cse'd, printed by :func:`sympy.ccode`) writing the
  row-major entries to ``double *out``, with a header comment listing the arguments and units.

Arguments default to :func:`argument_order`: the parameters, then the state, then any other
symbol by name (see :data:`ARGUMENTS`).  Text is never evaluated: every expression goes through
:func:`mechderive.formulas.parse.as_expression`.
"""

from __future__ import annotations

import keyword
from typing import Any, Mapping, Sequence

import sympy as sp
from sympy.core.function import AppliedUndef

from ..errors import InvalidInputError
from ..formulas.parse import as_expression

__all__ = ["ARGUMENTS", "argument_order", "to_python_source", "to_c_source"]


#: Argument names in the order generated functions take them, with their meaning and unit
#: (any consistent set of units; "length" etc. name the dimension).  Names not listed follow,
#: sorted.
ARGUMENTS: dict[str, tuple[str, str]] = {
    "I1": ("principal moment of inertia about e1", "mass·length²"),
    "I2": ("principal moment of inertia about e2", "mass·length²"),
    "I3": ("principal moment of inertia about e3", "mass·length²"),
    "M": ("mass", "mass"),
    "g": ("gravitational acceleration", "length/time²"),
    "l": ("distance from the pivot to the centre of mass (heavy top) or rod length", "length"),
    "R": ("radius", "length"),
    "h": ("height", "length"),
    "a": ("a = I3 ω3/I1 (3.66), or the cuboid's or ellipsoid's first dimension", "1/time or length"),
    "b": ("b = p_φ/I1 (3.66), or the second dimension", "1/time or length"),
    "c": ("the cuboid's or ellipsoid's third dimension", "length"),
    "alpha": ("α = 2E'/I1 (3.72), or a rotation angle", "1/time² or rad"),
    "beta": ("β = 2Mgl/I1 (3.72)", "1/time²"),
    "half_mass": ("mass of each half of the cat", "mass"),
    "joint_offset": ("distance from the waist joint to each half's centre", "length"),
    "radius": ("radius of each half's ring of masses", "length"),
    "half_length": ("axial half-length of each half", "length"),
    "phi": ("first Euler angle φ", "rad"),
    "theta": ("second Euler angle θ", "rad"),
    "psi": ("third Euler angle ψ", "rad"),
    "bend": ("bend angle of the cat", "rad"),
    "swivel": ("swivel angle of the cat's bending axis", "rad"),
    "phi_dot": ("φ̇", "rad/time"),
    "theta_dot": ("θ̇", "rad/time"),
    "psi_dot": ("ψ̇", "rad/time"),
    "bend_dot": ("rate of bend", "rad/time"),
    "swivel_dot": ("rate of swivel", "rad/time"),
    "omega1": ("body component ω1 of the angular velocity", "rad/time"),
    "omega2": ("body component ω2", "rad/time"),
    "omega3": ("body component ω3 (the spin)", "rad/time"),
    "tau1": ("body component τ1 of the torque", "mass·length²/time²"),
    "tau2": ("body component τ2 of the torque", "mass·length²/time²"),
    "tau3": ("body component τ3 of the torque", "mass·length²/time²"),
    "u": ("u = cos θ (3.71)", "1"),
    "u0": ("u at release or of uniform precession", "1"),
    "theta0": ("θ of uniform precession", "rad"),
    "p_phi": ("conserved momentum p_φ", "mass·length²/time"),
    "p_psi": ("conserved momentum p_ψ", "mass·length²/time"),
    "Omega": ("spin rate Ω (3.40) or precession rate Ω (3.36)", "rad/time"),
}


def _flat(expr: Any) -> tuple[list[sp.Expr], tuple[int, ...]]:
    if isinstance(expr, sp.MatrixBase):
        return list(expr), tuple(expr.shape)
    return [as_expression(expr, "the expression")], ()


def _check_printable(flat: Sequence[sp.Expr]) -> None:
    for e in flat:
        bad = e.atoms(AppliedUndef, sp.Derivative)
        if bad:
            raise InvalidInputError(f"expected expressions in plain symbols for code, got {sorted(map(str, bad))[0]}")


def _checked(value: Any, what: str) -> Any:
    """A matrix as it is, anything else through :func:`as_expression` (text is never evaluated)."""
    return value if isinstance(value, sp.MatrixBase) else as_expression(value, what)



def argument_order(exprs: Any) -> list[sp.Symbol]:
    """The free symbols of ``exprs`` in the order generated functions take them.

    >>> import sympy as sp
    >>> argument_order(sp.Symbol("theta") + sp.Symbol("I1") + sp.Symbol("zeta"))
    [I1, theta, zeta]
    """
    items = exprs.values() if isinstance(exprs, Mapping) else (exprs if isinstance(exprs, (list, tuple)) else [exprs])
    free: set[sp.Symbol] = set()
    for e in items:
        free |= set(_checked(e, "each expression").free_symbols)
    return _ordered(free)


def _ordered(free: set) -> list[sp.Symbol]:
    """Symbols in the order of :data:`ARGUMENTS`, then by name."""
    rank = {n: i for i, n in enumerate(ARGUMENTS)}
    return sorted(free, key=lambda s: (rank.get(s.name, len(rank)), s.name))


def _identifiers(symbols: Sequence[sp.Symbol], reserved: set[str]) -> dict[sp.Symbol, str]:
    out, used = {}, set()
    for s in sorted(symbols, key=lambda s: s.name):
        name = "".join(c if (c.isalnum() or c == "_") else "_" for c in s.name)
        if not name or name[0].isdigit():
            name = "_" + name
        while keyword.iskeyword(name) or name in reserved or name in used:
            name += "_"
        out[s] = name
        used.add(name)
    return out


def _inert(title: str) -> str:
    """``title`` made safe in a comment or docstring of every format: one line (no line break of any
    kind), no ``*/`` to close a C comment, no triple quote or backslash in a Python docstring.

    >>> _inert("a\\nimport os */ " + '"' * 3 + " x\\\\y")
    "a import os * / ''' x/y"
    """
    flat = " ".join(title.splitlines())
    flat = "".join(c if c.isprintable() else " " for c in flat)
    return flat.replace("*/", "* /").replace('"""', "'''").replace("\\", "/")


# ------------------------------------------------------------------------------ code
def _argument_lines(args: Sequence[sp.Symbol], names: Mapping[sp.Symbol, str], prefix: str) -> list[str]:
    width = max((len(names[a]) for a in args), default=0)
    out = []
    for a in args:
        meaning, unit = ARGUMENTS.get(a.name, ("", ""))
        text = f"{meaning} [{unit}]" if meaning else ""
        alias = "" if names[a] == a.name else f" (symbol {a.name})"
        out.append(f"{prefix}{names[a]:<{width}}  {text}{alias}".rstrip())
    return out


def _check_args(flat: Sequence[sp.Expr] | set, args: Sequence[Any]) -> list[sp.Symbol]:
    """``args`` checked: distinct symbols including every free symbol of ``flat`` (expressions, or their
    free symbols as a set)."""
    args = list(args)
    for a in args:
        if not isinstance(a, sp.Symbol):
            raise InvalidInputError(f"expected the arguments to be SymPy symbols, got {a!r}")
    if len(set(args)) != len(args):
        raise InvalidInputError(f"expected distinct arguments, got {[str(a) for a in args]}")
    free = flat if isinstance(flat, set) else set().union(*(e.free_symbols for e in flat)) if flat else set()
    missing = sorted(str(s) for s in free - set(args))
    if missing:
        raise InvalidInputError(f"expected the arguments to include every free symbol, got {', '.join(missing)} missing")
    return args


_PY_RESERVED = {"numpy", "_values", "_shape"}


def _numpy_printer_class() -> type:
    """SymPy's NumPyPrinter, with Max and Min as nested numpy.maximum/minimum: SymPy prints them
    with ``functools.reduce``, which the generated module (``import numpy`` only) would not have."""
    from sympy.printing.numpy import NumPyPrinter

    class _Printer(NumPyPrinter):
        def _fold(self, expr: sp.Expr, func: str) -> str:
            args = [self._print(a) for a in expr.args]
            out = args[0]
            for a in args[1:]:
                out = f"numpy.{func}({out}, {a})"
            return out

        def _print_Max(self, expr: sp.Expr) -> str:
            return self._fold(expr, "maximum")

        def _print_Min(self, expr: sp.Expr) -> str:
            return self._fold(expr, "minimum")

        # Legendre's elliptic integrals (the closed forms' F(φ|m), E(φ|m), Π(n; φ|m)): mechderive's own,
        # vectorised and valid for every real φ (SciPy has no incomplete Π); the function imports them
        def _print_elliptic_f(self, expr: sp.Expr) -> str:
            return "mechderive.special.elliptic_f({}, {})".format(*map(self._print, expr.args))

        def _print_elliptic_e(self, expr: sp.Expr) -> str:
            if len(expr.args) == 1:
                return "mechderive.special.elliptic_e({})".format(self._print(expr.args[0]))
            return "mechderive.special.elliptic_e_incomplete({}, {})".format(*map(self._print, expr.args))

        def _print_elliptic_k(self, expr: sp.Expr) -> str:
            return "mechderive.special.ellipk_m1(1 - ({}))".format(self._print(expr.args[0]))

        def _print_elliptic_pi(self, expr: sp.Expr) -> str:
            if len(expr.args) == 2:
                return "mechderive.special.elliptic_pi({}, {})".format(*map(self._print, expr.args))
            return "mechderive.special.elliptic_pi_incomplete({}, {}, {})".format(*map(self._print, expr.args))

    return _Printer


def to_python_source(exprs: Any, args: Sequence[Any] | None = None, name: str = "f", *, doc: str = "",
                     imports: bool = True) -> str:
    """Source of a standalone NumPy function ``name(*args)`` evaluating ``exprs`` (scalar or Matrix).

    ``import numpy`` (unless ``imports=False``), then the function: its docstring starts with
    ``doc`` and lists the arguments in order (default :func:`argument_order`) with their units;
    the body is cse'd.  A Matrix of shape S at arguments broadcasting to B gives an array B + S.

    >>> import sympy as sp
    >>> x, y = sp.symbols("x y")
    >>> ns = {}; exec(to_python_source(sp.Matrix([x * y, sp.sin(x * y)]), [x, y], "g"), ns)
    >>> ns["g"](2.0, 0.25).round(6).tolist()
    [[0.5], [0.479426]]
    """
    _NumPyPrinter = _numpy_printer_class()
    flat, shape = _flat(exprs)
    _check_printable(flat)
    args = _check_args(flat, argument_order(exprs) if args is None else args)
    if not name.isidentifier() or keyword.iskeyword(name):
        raise InvalidInputError(f"expected a Python identifier for the function name, got {name!r}")
    names = _identifiers(args, _PY_RESERVED | {name})
    plain = {a: sp.Symbol(names[a]) for a in args}
    repl, reduced = sp.cse([e.xreplace(plain) for e in flat], symbols=sp.numbered_symbols("_x"))
    printer = _NumPyPrinter({"fully_qualified_modules": True, "allow_unknown_functions": False})
    body = [f"    {s} = {printer.doprint(e)}" for s, e in repl]
    if any(e.has(sp.elliptic_f, sp.elliptic_e, sp.elliptic_k, sp.elliptic_pi) for e in flat):
        body.insert(0, "    import mechderive.special")
    entries = [printer.doprint(e) for e in reduced]
    if shape:
        body.append("    _values = numpy.broadcast_arrays(" +
                    ", ".join(f"numpy.asarray({e}, dtype=float)" for e in entries) + ")")
        body.append(f"    return numpy.stack(_values, axis=-1).reshape(_values[0].shape + {shape!r})")
        returns = f"float array of shape (*broadcast, {', '.join(map(str, shape))}), entries row-major"
    else:
        body.append(f"    return numpy.asarray({entries[0]}, dtype=float)")
        returns = "float array of the arguments' broadcast shape"
    lines = (doc.rstrip().splitlines() + [""]) if doc else []
    lines += ["Arguments, in order (any consistent units):", *_argument_lines(args, names, "    "), "",
              f"Returns a {returns}.", "Generated by mechderive from its SymPy derivation (cse'd)."]
    lines = [_inert(line) for line in lines]
    docstring = ['    """' + lines[0]] + [f"    {line}" if line else "" for line in lines[1:]] + ['    """']
    head = f"def {name}({', '.join(names[a] for a in args)}):"
    return "\n".join((["import numpy", "", ""] if imports else []) + [head, *docstring, *body]) + "\n"


_C_RESERVED = {
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum", "extern",
    "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return", "short", "signed",
    "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void", "volatile", "while", "out",
    # <math.h> (C99 and POSIX) names an argument must not shadow
    "acos", "asin", "atan", "atan2", "cos", "sin", "tan", "cosh", "sinh", "tanh", "exp", "log", "log10", "pow",
    "sqrt", "ceil", "floor", "fabs", "fmod", "gamma", "lgamma", "tgamma", "erf", "erfc", "j0", "j1", "jn", "y0",
    "y1", "yn", "hypot", "cbrt", "round", "trunc", "signbit", "isnan", "isinf", "nan", "remainder", "scalb",
}


def to_c_source(exprs: Any, args: Sequence[Any] | None = None, name: str = "f", *, doc: str = "",
                include: bool = True) -> str:
    """Source of a C99 function ``void name(double arg, ..., double *out)`` writing the entries of ``exprs``.

    ``out`` receives the entries row-major (one for a scalar, 9 for a 3×3 matrix); the body is
    cse'd; a header comment (starting with ``doc``) lists the arguments in order and their units.
    Needs ``<math.h>`` (included unless ``include=False``) and ``-lm``.
    """
    flat, shape = _flat(exprs)
    if not name.isidentifier() or name in _C_RESERVED:
        raise InvalidInputError(f"expected a C identifier for the function name, got {name!r}")
    # cse first: a derived expression may be a DAG whose tree is exponentially larger (the eliminated
    # accelerations of a many-coordinate Lagrangian); cse visits each distinct node once, and every
    # later check and renaming walks only its small pieces.
    temporaries = sp.numbered_symbols("cse_", cls=sp.Dummy)
    repl, reduced = sp.cse(flat, symbols=temporaries)
    pieces = [e for _, e in repl] + list(reduced)
    _check_printable(pieces)
    made = {s for s, _ in repl}
    free = set().union(*(e.free_symbols for e in pieces)) - made if pieces else set()
    args = _check_args(free, _ordered(free) if args is None else args)
    names = _identifiers(args, _C_RESERVED | {name})
    plain = {a: sp.Symbol(names[a]) for a in args}
    taken = set(names.values())
    cse_names = {}
    for k, (s, _) in enumerate(repl):
        label = f"cse_{k}"
        while label in taken:
            label += "_"
        cse_names[s] = sp.Symbol(label)
    plain.update(cse_names)
    repl = [(cse_names[s], e.xreplace(plain)) for s, e in repl]
    reduced = [e.xreplace(plain) for e in reduced]
    layout = " x ".join(map(str, shape)) if shape else "scalar"
    comment = ["/*"]
    comment += [f" * {_inert(line)}".rstrip() for line in doc.strip().splitlines()] if doc else []
    comment += [" *", " * Arguments, in order (any consistent units):",
                *(_inert(line) for line in _argument_lines(args, names, " *   ")),
                f" * Output: out[0 .. {len(flat) - 1}], the {layout} result"
                + (f" row-major: entry (i, j) at out[{shape[1]}*i + j]." if len(shape) == 2 else "."),
                " * Generated by mechderive from its SymPy derivation (cse'd).", " */"]
    params = ", ".join([f"double {names[a]}" for a in args] + ["double *out"])
    body = [f"    const double {s} = {sp.ccode(e, standard='C99')};" for s, e in repl]
    body += [f"    out[{i}] = {sp.ccode(e, standard='C99')};" for i, e in enumerate(reduced)]
    return "\n".join(comment + (["#include <math.h>", ""] if include else []) +
                     [f"void {name}({params})", "{", *body, "}"]) + "\n"
