"""Evaluate a SymPy expression with mpmath at a chosen precision, with a running error bound.

:func:`evaluate` walks the expression tree (only the node types that :mod:`.parse` and the
models produce: numbers, symbols, π, e, +, ×, powers and the elementary functions) and
returns the value v together with a first-order bound on its rounding error,

    e(a + b) = e(a) + e(b) + n·ε·(|a| + |b|),   e(a·b) = e(a)|b| + |a|e(b) + n·ε·|ab|,
    e(f(x)) = |f'(x)|·e(x) + ε·|f(x)|,           ε = 2^(1 − precision in bits),

so that ``e / ε`` measures the size of the terms that cancelled (a scale for a relative test of
LHS − RHS that is meaningful even when both sides are 0).  A point is *rejected*
(:class:`PointRejected`) where the expression is singular, non-real, not finite, or so
ill-conditioned that the first-order bound cannot be trusted; an unknown node type raises
:class:`CannotEvaluate`.

>>> import sympy as sp
>>> x = sp.Symbol("x", real=True)
>>> v, e = evaluate(sp.sin(x)**2 + sp.cos(x)**2, {x: sp.Rational(1, 3)}, dps=30)
>>> abs(v - 1) < 1e-29, e < 1e-28
(True, True)
>>> evaluate(sp.sqrt(x), {x: sp.Rational(-1)}, dps=30)
Traceback (most recent call last):
...
mechderive.formulas.evaluate.PointRejected: non-real value of sqrt(x)
"""

from __future__ import annotations

from typing import Mapping

import mpmath
import sympy as sp

__all__ = ["evaluate", "PointRejected", "CannotEvaluate"]


class PointRejected(ArithmeticError):
    """The expression has no trustworthy real value at this point (singular, non-real, ill-conditioned)."""


class CannotEvaluate(ValueError):
    """The expression contains a node this evaluator does not know."""


def _sec(x):
    return 1 / mpmath.cos(x)


# f, |f'| at x (given x and f(x)).
_FUNCS = {
    sp.sin: (mpmath.sin, lambda x, v: abs(mpmath.cos(x))),
    sp.cos: (mpmath.cos, lambda x, v: abs(mpmath.sin(x))),
    sp.tan: (mpmath.tan, lambda x, v: 1 + v * v),
    sp.cot: (mpmath.cot, lambda x, v: 1 + v * v),
    sp.sec: (_sec, lambda x, v: abs(v * mpmath.tan(x))),
    sp.csc: (lambda x: 1 / mpmath.sin(x), lambda x, v: abs(v * mpmath.cot(x))),
    sp.asin: (mpmath.asin, lambda x, v: 1 / mpmath.sqrt(1 - x * x)),
    sp.acos: (mpmath.acos, lambda x, v: 1 / mpmath.sqrt(1 - x * x)),
    sp.atan: (mpmath.atan, lambda x, v: 1 / (1 + x * x)),
    sp.sinh: (mpmath.sinh, lambda x, v: mpmath.cosh(x)),
    sp.cosh: (mpmath.cosh, lambda x, v: abs(mpmath.sinh(x))),
    sp.tanh: (mpmath.tanh, lambda x, v: 1 - v * v),
    sp.exp: (mpmath.exp, lambda x, v: abs(v)),
    sp.log: (mpmath.log, lambda x, v: 1 / abs(x)),
}
_ILL = mpmath.mpf("1e-8")  # relative error of an argument beyond which linear error bounds are not trusted


class _Evaluator:
    def __init__(self, point: Mapping[sp.Symbol, sp.Rational]) -> None:
        self.point = point
        self.eps = mpmath.mp.eps * 2
        self.memo: dict = {}

    def __call__(self, node: sp.Basic) -> tuple:
        if node in self.memo:
            return self.memo[node]
        try:
            v, e = self._eval(node)
        except ZeroDivisionError:
            raise PointRejected(f"division by zero in {_short(node)}") from None
        if isinstance(v, mpmath.mpc):
            raise PointRejected(f"non-real value of {_short(node)}")
        if not mpmath.isfinite(v) or not mpmath.isfinite(e):
            raise PointRejected(f"non-finite value of {_short(node)}")
        self.memo[node] = (v, e)
        return v, e

    def _number(self, v) -> tuple:
        return v, self.eps * abs(v)

    def _eval(self, node: sp.Basic) -> tuple:
        eps = self.eps
        if node.is_Symbol:
            if node not in self.point:
                raise CannotEvaluate(f"no value for the symbol {node}")
            r = self.point[node]
            return self._number(mpmath.mpf(int(r.p)) / int(r.q))
        if node.is_Rational:
            return self._number(mpmath.mpf(int(node.p)) / int(node.q))
        if node is sp.pi:
            return self._number(+mpmath.pi)
        if node is sp.E:
            return self._number(+mpmath.e)
        if node.is_Float:
            return self._number(mpmath.mpf(node))
        if node.is_Add:
            parts = [self(a) for a in node.args]
            v = mpmath.fsum(p[0] for p in parts)
            return v, sum(p[1] for p in parts) + len(parts) * eps * sum(abs(p[0]) for p in parts)
        if node.is_Mul:
            parts = [self(a) for a in node.args]
            v = mpmath.fprod(p[0] for p in parts)
            e = mpmath.mpf(0)
            for i, (_, ei) in enumerate(parts):
                if ei:
                    e += ei * mpmath.fprod(abs(p[0]) for j, p in enumerate(parts) if j != i)
            return v, e + len(parts) * eps * abs(v)
        if node.is_Pow:
            return self._pow(node)
        if isinstance(node, sp.Abs):
            v, e = self(node.args[0])
            return abs(v), e
        if isinstance(node, sp.sign):
            v, e = self(node.args[0])
            if abs(v) <= e:
                raise PointRejected(f"sign of a value indistinguishable from 0 in {_short(node)}")
            return mpmath.sign(v), mpmath.mpf(0)
        if isinstance(node, sp.atan2):
            (y, ey), (x, ex) = self(node.args[0]), self(node.args[1])
            r2 = x * x + y * y
            if r2 == 0 or (ex + ey) ** 2 > _ILL * r2:
                raise PointRejected(f"atan2 at (0, 0) in {_short(node)}")
            v = mpmath.atan2(y, x)
            return v, (abs(x) * ey + abs(y) * ex) / r2 + eps * abs(v)
        if node.func in _FUNCS:
            f, slope = _FUNCS[node.func]
            x, ex = self(node.args[0])
            if node.func is sp.log and (x <= 0 or ex > _ILL * abs(x)):
                raise PointRejected(f"log of a non-positive or uncertain value in {_short(node)}")
            v = f(x)
            if isinstance(v, mpmath.mpc):
                raise PointRejected(f"non-real value of {_short(node)}")
            return v, slope(x, v) * ex + eps * abs(v)
        raise CannotEvaluate(f"cannot evaluate {type(node).__name__} numerically")

    def _pow(self, node: sp.Pow) -> tuple:
        eps = self.eps
        b, eb = self(node.base)
        if node.exp.is_Rational:
            n = node.exp
            if n.is_Integer and n >= 0:
                k = int(n)
                v = b ** k
                return v, (k * abs(b) ** (k - 1) * eb if k else 0) + eps * abs(v) * (1 + k.bit_length())
            if b == 0 or eb > _ILL * abs(b):
                raise PointRejected(f"a power with a zero or uncertain base in {_short(node)}")
            if n.is_Integer:
                v = b ** int(n)
                return v, abs(n) * abs(v / b) * eb + eps * abs(v) * (1 + int(abs(n)).bit_length())
            if b < 0:
                raise PointRejected(f"non-real value of {_short(node)}")
            v = mpmath.root(b, int(n.q)) ** int(n.p) if n.p > 0 else 1 / mpmath.root(b, int(n.q)) ** int(-n.p)
            return v, abs(n) * abs(v / b) * eb + eps * abs(v) * (2 + int(abs(n.p)).bit_length())
        x, ex = self(node.exp)
        if b <= 0 or eb > _ILL * abs(b):
            raise PointRejected(f"a non-positive or uncertain base of a symbolic power in {_short(node)}")
        lb = mpmath.log(b)
        v = mpmath.exp(x * lb)
        return v, abs(v) * (abs(x / b) * eb + abs(lb) * ex) + eps * abs(v) * (2 + abs(x * lb))


def _short(node: sp.Basic, limit: int = 60) -> str:
    text = str(node)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def evaluate(expr: sp.Basic, point: Mapping[sp.Symbol, sp.Rational], *, dps: int) -> tuple:
    """(value, error bound) of ``expr`` at ``point`` (exact rationals) with ``dps`` significant digits.

    Raises :class:`PointRejected` where no trustworthy real value exists, :class:`CannotEvaluate`
    for an unknown node type.  The mpmath precision is restored afterwards.
    """
    with mpmath.workdps(dps):
        return _Evaluator(point)(sp.sympify(expr))
