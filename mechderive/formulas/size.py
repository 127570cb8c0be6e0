"""The size of a SymPy expression, counted and printed without walking more of it than a bound.

An expression built by repeated differentiation shares its subexpressions: a few hundred
distinct nodes can stand for a tree of millions (``dt`` applied five times to the heavy top's
energy along the motion: about 600 distinct nodes, 800 000 in the tree).  SymPy's ``str``,
``count_ops``, ``xreplace`` and ``diff`` walk the tree, so its size is what they cost; these
helpers walk at most a given number of nodes.

>>> import sympy as sp
>>> x = sp.Symbol("x")
>>> tree_size(sp.sin(x) + x**2, cap=100), tree_size(sp.sin(x) + x**2, cap=3)
(6, 3)
>>> brief(sp.sin(x) + x**2)
'x**2 + sin(x)'
"""

from __future__ import annotations

import sympy as sp

__all__ = ["tree_size", "brief"]

_PRINTABLE = 400  # nodes: str() of a tree this small is cheap


def tree_size(expr: sp.Basic, cap: int) -> int:
    """The number of nodes of ``expr``'s tree (each use of a shared subexpression counted), at most ``cap``."""
    count, stack = 0, [expr]
    while stack and count < cap:
        node = stack.pop()
        count += 1
        stack.extend(node.args)
    return count


def brief(expr: sp.Basic, limit: int = 60) -> str:
    """``str(expr)`` cut to ``limit`` characters; a big expression is printed only as far as shown."""
    text = str(expr) if tree_size(expr, _PRINTABLE) < _PRINTABLE else _outline(expr, limit + 1)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _outline(expr: sp.Basic, room: int) -> str:
    """A printout of a big expression, at least ``room`` characters long or complete: heads first."""
    if tree_size(expr, _PRINTABLE) < _PRINTABLE:
        return str(expr)
    if expr.is_Add or expr.is_Mul:
        sep, parts = (" + " if expr.is_Add else "*"), []
        for arg in expr.args:
            part = _outline(arg, room)
            parts.append(part if expr.is_Add or not arg.is_Add else f"({part})")
            room -= len(part) + len(sep)
            if room <= 0:
                break
        return sep.join(parts) + (sep + "…" if len(parts) < len(expr.args) else "")
    if expr.is_Pow:
        base = _outline(expr.base, room)
        return f"({base})**{_outline(expr.exp, room - len(base))}"
    name = getattr(expr.func, "__name__", type(expr).__name__)
    parts = []
    for arg in expr.args:
        parts.append(_outline(arg, room))
        room -= len(parts[-1]) + 2
        if room <= 0:
            break
    return f"{name}({', '.join(parts)}{', …' if len(parts) < len(expr.args) else ''})"
