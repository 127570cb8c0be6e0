"""The size of the terms an expression is computed from: a scale of its rounding error in floating point.

Evaluating a sum whose terms cancel leaves an absolute error of ~ε × (the sum of the terms' sizes),
not ε × |the result|.  :func:`magnitude` builds that sum of sizes as an expression: every sum becomes
the sum of its terms' magnitudes, a product the product of its factors', a sine or cosine its absolute
value (a power keeps its exponent: a denominator is taken as computed without loss).  Compiled beside
the expression, it turns a value's rounding into a measured estimate, point by point.

>>> import sympy as sp
>>> x, y = sp.symbols("x y", real=True)
>>> magnitude(x**2 - y**2)
x**2 + y**2
>>> magnitude((x - y) / (x + y))
(Abs(x) + Abs(y))/Abs(x + y)
"""

from __future__ import annotations

import sympy as sp

__all__ = ["magnitude"]


def magnitude(expr: sp.Expr) -> sp.Expr:
    """Σ of the sizes of the terms ``expr`` is computed from (see the module's docstring); ≥ |expr|."""
    if expr.is_Number:
        return abs(expr)
    if expr.is_Symbol:
        return expr if expr.is_nonnegative else sp.Abs(expr)
    if expr.is_Add:
        return sp.Add(*(magnitude(a) for a in expr.args))
    if expr.is_Mul:
        return sp.Mul(*(magnitude(a) for a in expr.args))
    if expr.is_Pow:
        base, exp = expr.args
        if exp.is_Integer and exp < 0:
            return sp.Abs(base) ** exp
        return magnitude(base) ** exp
    return sp.Abs(expr)
