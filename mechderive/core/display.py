"""Printing derived expressions for people: plain text or LaTeX, with the chapter's symbols.

Used by the ``derivations/`` scripts.  State symbols (``phi_dot``) print as φ̇ in
text and as ``\\dot{\\phi}`` in LaTeX.
"""

from __future__ import annotations

import argparse
from typing import Any

import sympy as sp

from .symbols import to_state_symbols

__all__ = ["show", "derivation_args", "display_symbols"]


def display_symbols(expr: Any) -> Any:
    """``expr`` with q_dot, q_ddot renamed qdot, qddot, which SymPy prints as q̇, q̈ (and \\dot{q} in LaTeX)."""
    from .symbols import as_symbolic

    expr = as_symbolic(expr)
    subs = {}
    for s in expr.free_symbols:
        for suffix in ("_ddot", "_dot"):
            if s.name.endswith(suffix):
                base = s.name[: -len(suffix)]
                stem = base.rstrip("0123456789")
                index = base[len(stem):]
                # "omega1_dot" -> "omegadot_1": SymPy puts the dot on ω and keeps the subscript
                name = f"{stem}{suffix[1:]}_{index}" if index else f"{base}{suffix[1:]}"
                subs[s] = sp.Symbol(name, **s.assumptions0)
                break
    return expr.subs(subs)


def show(label: str, expr: Any, *, latex: bool = False) -> None:
    """Print ``label = expr`` in plain text (unicode pretty-printing) or as a LaTeX equation."""
    expr = display_symbols(to_state_symbols(expr))
    if latex:
        print(f"% {label}\n\\begin{{equation}}\n{sp.latex(expr)}\n\\end{{equation}}")
    else:
        pretty = sp.pretty(expr, use_unicode=True, wrap_line=False)
        if "\n" in pretty:
            print(f"{label} =\n{pretty}\n")
        else:
            print(f"{label} = {pretty}")


def derivation_args(description: str) -> argparse.Namespace:
    """The common command line of the derivations/ scripts: ``--latex``."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--latex", action="store_true", help="print equations as LaTeX")
    return parser.parse_args()
