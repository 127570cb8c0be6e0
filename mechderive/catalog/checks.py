"""Ways a claim is decided: exact identity, or high-precision evaluation at random points.

:func:`same` proves equality of (matrices of) trigonometric rational expressions
exactly via :func:`mechderive.core.simplify.is_zero`, falling back to SymPy's
``simplify`` for anything else.  :func:`same_numerically` evaluates both sides
with mpmath at 30 significant digits at seeded random points; with a relative
tolerance of 1e-20 a wrong formula can only pass if it agrees with the right one
to 20 digits at every point.
"""

from __future__ import annotations

import random
from typing import Any, Iterable, Sequence

import mpmath
import sympy as sp

from ..core.simplify import is_zero
from ..core.symbols import to_state_symbols
from .registry import Outcome

__all__ = ["same", "same_numerically", "as_matrix"]


def as_matrix(obj: Any) -> sp.Matrix:
    """``obj`` (a matrix, a list or tuple, an expression) as a Matrix; text inside is refused, never evaluated."""
    from ..formulas.parse import as_matrix as checked_matrix

    return checked_matrix(obj, "the formula")


def _is_zero(e: sp.Expr) -> bool:
    e = to_state_symbols(e)
    if e == 0:
        return True
    decided = is_zero(e)
    if decided is not None:
        return decided
    return sp.simplify(e) == 0


def _short(e: sp.Expr, limit: int = 120) -> str:
    text = str(to_state_symbols(e))
    return text if len(text) <= limit else text[: limit - 1] + "…"


def same(formula: Any, derived: Any, what: str = "") -> Outcome:
    """Exact test that ``formula`` equals ``derived`` entry by entry (shapes must match)."""
    a, b = as_matrix(formula), as_matrix(derived)
    if a.shape != b.shape:
        return Outcome(False, f"shape {a.shape} differs from derived {b.shape}")
    for i in range(a.rows):
        for j in range(a.cols):
            if not _is_zero(a[i, j] - b[i, j]):
                where = f"[{i + 1},{j + 1}]" if len(a) > 1 else ""
                return Outcome(False, f"{what}{where}: printed {_short(a[i, j])} ≠ derived {_short(b[i, j])}")
    return Outcome(True, f"{what} identical after exact simplification".strip())


def same_numerically(
    formula: Any,
    derived: Any,
    symbols: Sequence[sp.Symbol] | None = None,
    *,
    points: int = 12,
    dps: int = 30,
    rtol: float = 1e-20,
    ranges: dict[sp.Symbol, tuple[float, float]] | None = None,
    seed: int = 20261121,
) -> Outcome:
    """Compare ``formula`` and ``derived`` at seeded random points with mpmath at ``dps`` digits.

    Symbols not listed in ``ranges`` are drawn uniformly from (0.1, 1.4) — positive,
    away from 0 and from the Euler-angle singularity at θ = π.
    """
    a, b = to_state_symbols(as_matrix(formula)), to_state_symbols(as_matrix(derived))
    if a.shape != b.shape:
        return Outcome(False, f"shape {a.shape} differs from derived {b.shape}")
    syms = list(symbols) if symbols is not None else sorted(a.free_symbols | b.free_symbols, key=sp.default_sort_key)
    fa = sp.lambdify(syms, list(a), "mpmath")
    fb = sp.lambdify(syms, list(b), "mpmath")
    rng = random.Random(seed)
    ranges = ranges or {}
    worst = mpmath.mpf(0)
    with mpmath.workdps(dps):
        for _ in range(points):
            vals = [mpmath.mpf(rng.uniform(*ranges.get(s, (0.1, 1.4)))) for s in syms]
            va, vb = fa(*vals), fb(*vals)
            for x, y in zip(va, vb):
                err = abs(x - y) / (1 + abs(y))
                worst = max(worst, err)
                if err > rtol:
                    pt = ", ".join(f"{s}={mpmath.nstr(v, 6)}" for s, v in zip(syms, vals))
                    return Outcome(False, f"differs by {mpmath.nstr(err, 3)} (relative) at {pt}")
    return Outcome(True, f"agrees at {points} random points to {mpmath.nstr(worst, 2)} ({dps} digits)")


def all_pass(outcomes: Iterable[Outcome]) -> Outcome:
    """Combine outcomes: the first failure, or a pass listing the details."""
    outs = list(outcomes)
    for o in outs:
        if not o.passed:
            return o
    return Outcome(True, "; ".join(o.detail for o in outs if o.detail))
