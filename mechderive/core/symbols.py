"""The toolkit's named symbols, one place for every layer.

Time-dependent coordinates are SymPy functions of the time symbol ``t``
(``phi(t)``, ...), so that derivatives are taken by :func:`sympy.diff`.  Before
compilation, :func:`to_state_symbols` replaces them and their derivatives by
plain real symbols with the names used throughout the toolkit and its scene
files: ``phi, theta, psi, phi_dot, theta_dot, psi_dot, phi_ddot, ...``.
"""

from __future__ import annotations

import functools
import numbers
from typing import Any

import sympy as sp

from ..errors import InvalidInputError

__all__ = ["t", "coordinate", "euler_angles", "state_symbol", "to_state_symbols", "as_symbolic"]

#: The time symbol.
t = sp.Symbol("t", real=True)


@functools.cache
def coordinate(name: str) -> sp.Function:
    """The generalised coordinate ``name`` as a real function of time, ``name(t)``."""
    return sp.Function(name, real=True)(t)


def euler_angles() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """The Euler angles (φ(t), θ(t), ψ(t)) of (3.50)–(3.54)."""
    return coordinate("phi"), coordinate("theta"), coordinate("psi")


@functools.cache
def state_symbol(name: str) -> sp.Symbol:
    """A plain real symbol with ``name`` (e.g. ``theta_dot``)."""
    return sp.Symbol(name, real=True)


_SUFFIX = {0: "", 1: "_dot", 2: "_ddot"}


def as_symbolic(value: Any, what: str = "the expression") -> Any:
    """``value`` as a SymPy object without ever reading text as code.

    SymPy expressions and matrices pass unchanged; Python and NumPy numbers become SymPy
    numbers; lists and tuples become matrices of such entries.  Text is refused: a plain
    ``sympify`` would evaluate it as Python (``sympify("__import__('os')...")``).

    >>> as_symbolic(2) + as_symbolic(sp.Symbol("x"))
    x + 2
    >>> as_symbolic("x + 1")
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: expected the expression to be a SymPy expression or a number, got the text 'x + 1'
    """
    if isinstance(value, (sp.Basic, sp.MatrixBase)):
        return value
    if isinstance(value, (list, tuple)) and value:
        return sp.Matrix([as_symbolic(v, what) if not isinstance(v, (list, tuple)) else
                          [as_symbolic(x, what) for x in v] for v in value])
    if isinstance(value, numbers.Number) and not isinstance(value, bool):
        try:
            return sp.sympify(value, strict=True)
        except (sp.SympifyError, TypeError, ValueError):
            pass
    shown = f"the text {value!r}" if isinstance(value, str) else f"a {type(value).__name__}"
    raise InvalidInputError(f"expected {what} to be a SymPy expression or a number, got {shown[:200]}")


def to_state_symbols(expr: Any) -> Any:
    """Replace q(t), q'(t), q''(t) in ``expr`` by symbols q, q_dot, q_ddot.

    >>> phi = coordinate("phi")
    >>> to_state_symbols(sp.diff(phi**2, t))
    2*phi*phi_dot
    """
    expr = as_symbolic(expr)
    subs: dict[Any, Any] = {}
    for d in expr.atoms(sp.Derivative):
        if isinstance(d.expr, sp.core.function.AppliedUndef) and d.variables and set(d.variables) == {t}:
            order = len(d.variables)
            if order not in _SUFFIX:
                raise InvalidInputError(f"expected derivatives of order <= 2, got order {order} in {d}")
            subs[d] = state_symbol(d.expr.func.__name__ + _SUFFIX[order])
    # Derivatives first, so that q(t) inside them is not replaced first.  xreplace: each replaced node is an exact
    # subtree, so the structural replacement gives what subs would, without subs' search and re-evaluation
    expr = expr.xreplace(subs)
    funcs = {f: state_symbol(f.func.__name__) for f in expr.atoms(sp.core.function.AppliedUndef) if f.args == (t,)}
    return expr.xreplace(funcs)
