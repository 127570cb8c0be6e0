"""Printing derived quantities: text, LaTeX, SymPy source, Python (NumPy) source, C source, JSON.

One function per format, each taking SymPy objects:

- :func:`to_text` — unicode pretty-printing, ``phi_dot`` shown as φ̇;
- :func:`to_latex` — LaTeX with the chapter's symbols (``\\dot{\\phi}``, ``I_{1}``), for amsmath;
- :func:`to_sympy_source` — Python source that rebuilds the SymPy objects *exactly*: one
  ``Symbol(name, assumptions)`` per symbol, then each object in SymPy's ``str`` form with exact
  integers (``S(1)/2``).  Chosen over ``srepr`` (which :func:`to_json` carries) because it is
  both readable and exact;
- :func:`to_python_source` — a standalone NumPy function (common subexpressions eliminated by
  :func:`sympy.cse`, printed by SymPy's ``NumPyPrinter``) whose docstring lists the argument
  order and units; it broadcasts like :func:`mechderive.core.compile.compile_expressions`:
  a result of shape S at arguments broadcasting to B has shape B + S;
- :func:`to_c_source` — a C99 function (cse'd, printed by :func:`sympy.ccode`) writing the
  row-major entries to ``double *out``, with a header comment listing the arguments and units;
- :func:`to_json` — per quantity: description, equation, text, LaTeX, ``str`` and ``srepr``.

:func:`render` puts a list of :class:`~mechderive.derive.api.Derived` together in one format.
Arguments of generated code default to :func:`argument_order`: the parameters, then the state,
then any other symbol by name (see :data:`mechderive.core.codegen.ARGUMENTS`).  The code
generators live in :mod:`mechderive.core.codegen` (below the solvers, which compile with them)
and are re-exported here.

>>> import sympy as sp
>>> x = sp.Symbol("theta_dot")
>>> to_latex(x**2 / 2, sp.Symbol("T"))
'T = \\\\frac{\\\\dot{\\\\theta}^{2}}{2}'
"""

from __future__ import annotations

import json
import keyword
from typing import Any, Mapping, Sequence

import sympy as sp

from ..core.codegen import (_checked, _flat, _identifiers, _inert, argument_order, to_c_source,  # noqa: F401
                             to_python_source)
from ..core.display import display_symbols
from ..errors import InvalidInputError

__all__ = ["FORMATS", "argument_order", "to_text", "to_latex", "to_sympy_source", "to_python_source",
           "to_c_source", "to_json", "render"]

#: The output formats.
FORMATS = ("text", "latex", "sympy", "python", "c", "json")


# ------------------------------------------------------------------------------ text and LaTeX
def _equation(expr: Any, lhs: Any) -> Any:
    expr = _checked(expr, "the expression")
    if lhs is not None and not isinstance(lhs, str):
        lhs = _checked(lhs, "the left-hand side")
    if lhs is None:
        return display_symbols(expr)
    if isinstance(lhs, str):  # "= 0"
        return sp.Eq(display_symbols(expr), sp.zeros(*expr.shape) if isinstance(expr, sp.MatrixBase) else 0,
                     evaluate=False)
    return sp.Eq(display_symbols(lhs), display_symbols(expr), evaluate=False)


def _greek_subscripts(expr: Any) -> Any:
    """Symbols ``p_psi`` renamed ``p_ψ``: unicode has no subscript ψ, and SymPy would print pₚₛᵢ."""
    from sympy.printing.pretty.pretty_symbology import greek_unicode

    subs = {}
    for s in expr.free_symbols:
        base, sep, sub = s.name.partition("_")
        if sep and sub in greek_unicode and base:
            subs[s] = sp.Symbol(f"{base}_{greek_unicode[sub]}", **s.assumptions0)
    return expr.xreplace(subs) if subs else expr


def to_text(expr: Any, lhs: Any = None) -> str:
    """``lhs = expr`` (or ``expr``) pretty-printed in unicode, rates shown with dots.

    >>> import sympy as sp
    >>> print(to_text(sp.Symbol("phi_dot") * sp.cos(sp.Symbol("theta")), sp.Symbol("p_psi")))
    p_ψ = φ̇⋅cos(θ)
    """
    return sp.pretty(_greek_subscripts(_equation(expr, lhs)), use_unicode=True, wrap_line=False)


def to_latex(expr: Any, lhs: Any = None) -> str:
    """``lhs = expr`` (or ``expr``) in LaTeX: ``\\dot{q}`` for q_dot, ``I_{1}`` for I1; matrices need amsmath."""
    return sp.latex(_equation(expr, lhs))


def _cse(exprs: list[sp.Expr]) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    return sp.cse(exprs, symbols=sp.numbered_symbols("x"), optimizations="basic")


def _text_block(d: Any, cse: bool, latex: bool) -> str:
    fmt = to_latex if latex else to_text
    lhs = d.lhs
    if not cse:
        return fmt(d.value, lhs)
    flat, shape = _flat(d.value)
    repl, reduced = _cse(flat)
    value = sp.Matrix(*shape, reduced) if shape else reduced[0]
    lines = [fmt(e, s) for s, e in repl] + [fmt(value, lhs)]
    if latex:
        return "\\begin{aligned}\n" + " \\\\\n".join(l.replace(" = ", " &= ", 1) for l in lines) + "\n\\end{aligned}"
    return "\n".join(lines)


# ------------------------------------------------------------------------------ SymPy source
def to_sympy_source(exprs: Mapping[str, Any], *, comments: Mapping[str, str] | None = None) -> str:
    """Python source that rebuilds ``{name: SymPy object}`` exactly (symbols with their assumptions).

    >>> import sympy as sp
    >>> src = to_sympy_source({"T": sp.Symbol("I1", positive=True) * sp.Symbol("w")**2 / 2})
    >>> print(src.splitlines()[-1])
    T = I1*w**S(2)/S(2)
    >>> ns = {}; exec(src, ns); ns["T"].free_symbols == {sp.Symbol("I1", positive=True), sp.Symbol("w")}
    True
    """
    import sympy

    from sympy.printing.str import StrPrinter

    for name in exprs:
        if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
            raise InvalidInputError(f"expected each name to be a Python identifier, got {name!r}")
    exprs = {name: _checked(e, f"the value of {name}") for name, e in exprs.items()}
    symbols = set()
    for e in exprs.values():
        symbols |= set(e.free_symbols)
    reserved = set(getattr(sympy, "__all__", ())) | set(exprs)
    ident = _identifiers(list(symbols), reserved)

    class _Printer(StrPrinter):
        def _print_Symbol(self, expr: sp.Symbol) -> str:
            return ident.get(expr, expr.name)

    printer = _Printer({"sympy_integers": True})
    lines = ["from sympy import *", ""]
    lines += [f"{ident[s]} = {sp.srepr(s)}" for s in sorted(symbols, key=lambda s: ident[s])]
    lines.append("")
    for name, e in exprs.items():
        if comments and name in comments:
            lines.append(f"# {_inert(str(comments[name]))}")
        lines.append(f"{name} = {printer.doprint(e)}")
    return "\n".join(lines)


# ------------------------------------------------------------------------------ JSON and documents
def to_json(entries: Sequence[Any], *, header: Mapping[str, Any] | None = None) -> str:
    """JSON: ``header`` and, per quantity, its description, equation, text, LaTeX, ``str`` and ``srepr``."""
    out = dict(header or {})
    out["quantities"] = [{
        "name": d.name, "description": d.description, "equation": d.equation,
        "lhs": "0" if d.is_zero_form else sp.sstr(d.lhs),
        "text": to_text(d.value, d.lhs), "latex": to_latex(d.value, d.lhs),
        "str": sp.sstr(d.value), "srepr": sp.srepr(d.value),
    } for d in entries]
    return json.dumps(out, indent=1, ensure_ascii=False)


_SCIPY_EXAMPLE = '''Convention: e_a = R_ab ẽ_b (3.54), R passive; SciPy's Rotation is active and equals Rᵀ.
Sequence {seq} {frame}-fixed is SciPy's "{scipy}" with the angles in the same order:

>>> import numpy
>>> from scipy.spatial.transform import Rotation
>>> angles = [0.3, 0.5, 0.7]                      # (phi, theta, psi) in rad
>>> {var} = {fname}(*angles)
>>> bool(numpy.allclose({var}, Rotation.from_euler("{scipy}", angles).as_matrix(){T}))
True
>>> bool(numpy.allclose(Rotation.from_matrix({var}{T}).as_euler("{scipy}"), angles))   # and back
True
'''


def _doc(d: Any, system: str, fname: str) -> str:
    eq = f" ({d.equation})" if d.equation else ""
    text = f"{d.description}{eq}: {system}, quantity {d.name!r}."
    if system == "rotation" and d.name in ("R", "A"):
        from .sequences import scipy_sequence

        text += "\n\n" + _SCIPY_EXAMPLE.format(seq=d.sequence, frame=d.frame, scipy=scipy_sequence(d.sequence, d.frame),
                                                fname=fname, var=d.name, T=".T" if d.name == "R" else "")
    return text


def render(entries: Sequence[Any], fmt: str = "text", *, system: str = "", summary: str = "",
           options: Mapping[str, Any] | None = None, cse: bool = False) -> str:
    """``entries`` (:class:`~mechderive.derive.api.Derived`) as one document in format ``fmt``.

    ``options`` (sequence, frame, …) go into headers; ``cse`` prints text and LaTeX with common
    subexpressions pulled out (code is always cse'd).
    """
    if fmt not in FORMATS:
        raise InvalidInputError(f"expected a format among {', '.join(FORMATS)}, got {fmt!r}")
    opts = {k: v for k, v in (options or {}).items() if v not in (None, {}, False)}
    where = ", ".join(f"{k}={v}" for k, v in opts.items())
    title = _inert(f"{system}: {summary}" + (f" [{where}]" if where else ""))
    if fmt == "json":
        return to_json(entries, header={"system": system, "summary": summary, "options": {k: str(v) for k, v in opts.items()}})
    if fmt == "sympy":
        src = to_sympy_source({d.name: d.value for d in entries},
                              comments={d.name: f"{d.description} ({d.equation})" for d in entries})
        return f"# {title}\n# SymPy objects derived by mechderive; exec() this to rebuild them exactly.\n{src}\n"
    if fmt == "python":
        parts = [f'"""{title}.\n\nGenerated by mechderive from its SymPy derivations."""\n\nimport numpy\n']
        for d in entries:
            fname = f"{system}_{d.name}"
            parts.append("\n" + to_python_source(d.value, None, fname, doc=_doc(d, system, fname), imports=False))
        return "\n".join(parts)
    if fmt == "c":
        parts = [f"/* {title}.  Generated by mechderive from its SymPy derivations. */\n\n#include <math.h>\n"]
        for d in entries:
            fname = f"{system}_{d.name}"
            parts.append(to_c_source(d.value, None, fname, doc=_doc(d, system, fname), include=False))
        return "\n".join(parts)
    latex = fmt == "latex"
    mark = "%" if latex else "#"
    blocks = [f"{mark} {title}" + ("\n% Generated by mechderive; needs \\usepackage{amsmath}." if latex else "")]
    for d in entries:
        eq = f" ({d.equation})" if d.equation else ""
        body = _text_block(d, cse, latex)
        if latex:
            body = f"\\begin{{equation}}\n{body}\n\\end{{equation}}"
        blocks.append(f"{mark} {d.name}: {d.description}{eq}\n{body}")
    return "\n\n".join(blocks) + "\n"
