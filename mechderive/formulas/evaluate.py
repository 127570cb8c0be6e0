"""Evaluate a SymPy expression with mpmath at a chosen precision, with a running error bound.

:func:`evaluate` walks the expression tree (only the node types that :mod:`.parse` and the
models produce: numbers, symbols, π, e, +, ×, powers and the elementary functions) and
returns the value v together with a first-order bound on its rounding error,

    e(a + b) = e(a) + e(b) + n·ε·(|a| + |b|),   e(a·b) = e(a)|b| + |a|e(b) + n·ε·|ab|,
    e(f(x)) = |f'(x)|·e(x) + ε·|f(x)|,           ε = 2^(1 − precision in bits),

and the *size of the terms* s, the value the expression would have if every sum were a sum of
absolute values (s(a + b) = s(a) + s(b), s(a·b) = s(a)s(b), s(aᵏ) = s(a)ᵏ; a function's value
starts afresh, s(f(x)) = |f(x)|).  e / s is the relative accuracy the evaluation kept: digits
lost to cancellation or to an ill-conditioned function make it large, however large the terms.

:func:`evaluate_terms` also reports the *depth*: the most decades by which some input of an
operation is attenuated in its result, so that a relative change of 10^−depth somewhere may
change the value by as little as 10^−depth relative (10^−2·depth at second order).  It is the
largest of: for a sum, log10(Σ|terms| / smallest |term|) (θ + 10^-100 hides 10^-100); for a
number p/q, the decades of p and q (1 + 10^-100 is a single rational); for a function,
log10(1/κ) with κ = |x f′(x) / f(x)| its relative condition number (tanh(200) hides
e^-400), and log10(1/|x|) at a small argument |x| < 1 of a function analytic at 0 (sin(x) = x
up to a relative x²/6).  Products do not hide anything.

A first-order bound is trusted only while every argument's error is small on the scale on
which the function's slope changes (1 for sin, exp, …; |x| for log; 1 − |x| for asin).  Beyond
that the point raises :class:`Unresolved` (a subclass of :class:`PointRejected`) with the
digits it is short of, so that a caller can retry with more digits.  A point is *rejected*
(:class:`PointRejected`) where the expression is singular, non-real, or leaves the range
10^±10000 (overflow or underflow: exp(exp(1000)) is refused, not computed); an unknown node
type raises :class:`CannotEvaluate`.

>>> import sympy as sp
>>> x = sp.Symbol("x", real=True)
>>> v, e = evaluate(sp.sin(x)**2 + sp.cos(x)**2, {x: sp.Rational(1, 3)}, dps=30)
>>> abs(v - 1) < 1e-29, e < 1e-28
(True, True)
>>> evaluate(sp.sqrt(x), {x: sp.Rational(-1)}, dps=30)
Traceback (most recent call last):
...
mechderive.formulas.evaluate.PointRejected: non-real value of sqrt(x)
>>> evaluate(sp.exp(sp.exp(1000)), {}, dps=30)
Traceback (most recent call last):
...
mechderive.formulas.evaluate.PointRejected: overflow: exp(exp(1000)) is beyond 10^10000
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import mpmath
import sympy as sp

from ..core.symbols import as_symbolic
from .size import brief

__all__ = ["evaluate", "evaluate_terms", "Terms", "PointRejected", "Unresolved", "CannotEvaluate",
           "MAX_DECADES"]

#: Values beyond 10^±MAX_DECADES are refused (mpmath never overflows, but exp(exp(1000)) is not computable).
MAX_DECADES = 10_000
_MAX_BITS = int(MAX_DECADES * math.log2(10))
_MAX_EXP_ARG = mpmath.mpf(MAX_DECADES) * mpmath.log(10)  # a double-precision constant is enough here
_LOG10_2 = math.log10(2)
_ILL = mpmath.mpf("1e-8")  # an argument's error, on its function's scale, beyond which linear bounds are not trusted


class PointRejected(ArithmeticError):
    """The expression has no trustworthy real value at this point (singular, non-real, out of range)."""


class Unresolved(PointRejected):
    """Not enough digits at this precision to trust the error bound; ``short`` more digits may do."""

    def __init__(self, message: str, short: float) -> None:
        super().__init__(message)
        self.short = short


class CannotEvaluate(ValueError):
    """The expression contains a node this evaluator does not know."""


@dataclass(frozen=True)
class Terms:
    """The value of an expression, a bound on its error, the size of its terms, and its depth (decades)."""

    value: mpmath.mpf
    error: mpmath.mpf
    size: mpmath.mpf
    depth: float


def _sec(x):
    return 1 / mpmath.cos(x)


# f, |f'| at x (given x and f(x)), and the scale of x on which |f'| changes (for the trust check;
# near a pole of tan, cot, sec, csc the scale is also at most 1/(1 + |f|), checked after evaluating).
_FUNCS = {
    sp.sin: (mpmath.sin, lambda x, v: abs(mpmath.cos(x)), lambda x: 1),
    sp.cos: (mpmath.cos, lambda x, v: abs(mpmath.sin(x)), lambda x: 1),
    sp.tan: (mpmath.tan, lambda x, v: 1 + v * v, lambda x: 1),
    sp.cot: (mpmath.cot, lambda x, v: 1 + v * v, lambda x: 1),
    sp.sec: (_sec, lambda x, v: abs(v * mpmath.tan(x)), lambda x: 1),
    sp.csc: (lambda x: 1 / mpmath.sin(x), lambda x, v: abs(v * mpmath.cot(x)), lambda x: 1),
    sp.asin: (mpmath.asin, lambda x, v: 1 / mpmath.sqrt(1 - x * x), lambda x: 1 - abs(x)),
    sp.acos: (mpmath.acos, lambda x, v: 1 / mpmath.sqrt(1 - x * x), lambda x: 1 - abs(x)),
    sp.atan: (mpmath.atan, lambda x, v: 1 / (1 + x * x), lambda x: 1),
    sp.sinh: (mpmath.sinh, lambda x, v: mpmath.cosh(x), lambda x: 1),
    sp.cosh: (mpmath.cosh, lambda x, v: abs(mpmath.sinh(x)), lambda x: 1),
    sp.tanh: (mpmath.tanh, lambda x, v: 1 / mpmath.cosh(x) ** 2, lambda x: 1),  # not 1 − v²: v may round to 1
    sp.exp: (mpmath.exp, lambda x, v: abs(v), lambda x: 1),
    sp.log: (mpmath.log, lambda x, v: 1 / abs(x), lambda x: abs(x)),
}
_GROWING = (sp.exp, sp.sinh, sp.cosh)
_POLES = (sp.tan, sp.cot, sp.sec, sp.csc)
_ANALYTIC_AT_0 = (sp.sin, sp.cos, sp.tan, sp.sinh, sp.cosh, sp.tanh, sp.exp, sp.atan, sp.asin, sp.acos,
                  sp.cot, sp.csc, sp.sec)  # (cot, csc: x·f(x) is)


def _digits_short(error, scale) -> float:
    """Decimal digits by which ``error`` exceeds ``_ILL * scale`` (what the precision is short of)."""
    if not scale > 0:
        return math.inf
    return max(0.0, float(mpmath.log10(error / (_ILL * scale))))


class _Evaluator:
    def __init__(self, point: Mapping[sp.Symbol, sp.Rational]) -> None:
        self.point = point
        self.eps = mpmath.mp.eps * 2
        self.memo: dict = {}
        self.depth = 0.0

    def _deeper(self, ratio) -> None:
        """Record an attenuation by ``ratio`` (< 1): its decades, if more than so far."""
        if 0 < ratio < 1:
            self.depth = max(self.depth, -float(mpmath.log10(ratio)))

    def __call__(self, node: sp.Basic) -> tuple:
        if node in self.memo:
            return self.memo[node]
        try:
            v, e, s = self._eval(node)
        except ZeroDivisionError:
            raise PointRejected(f"division by zero in {_short(node)}") from None
        if isinstance(v, mpmath.mpc):
            raise PointRejected(f"non-real value of {_short(node)}")
        if not mpmath.isfinite(v) or not mpmath.isfinite(e):
            raise PointRejected(f"non-finite value of {_short(node)}")
        if v:
            m = mpmath.mag(v)
            if abs(m) > _MAX_BITS:
                what = "overflow" if m > 0 else "underflow"
                raise PointRejected(f"{what}: {_short(node)} is beyond 10^{'' if m > 0 else '-'}{MAX_DECADES}")
        self.memo[node] = (v, e, s)
        return v, e, s

    def _number(self, v) -> tuple:
        return v, self.eps * abs(v), abs(v)

    def _eval(self, node: sp.Basic) -> tuple:
        eps = self.eps
        if node.is_Symbol:
            if node not in self.point:
                raise CannotEvaluate(f"no value for the symbol {node}")
            r = self.point[node]
            return self._number(mpmath.mpf(int(r.p)) / int(r.q))
        if node.is_Rational:
            if node.p:  # the digits a number carries: 1 + 10^-100 is one rational
                self.depth = max(self.depth, (abs(int(node.p)).bit_length() + int(node.q).bit_length() - 2) * _LOG10_2)
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
            resolved = [abs(p[0]) for p in parts if abs(p[0]) > p[1]]
            if len(resolved) > 1:
                self._deeper(min(resolved) / sum(resolved))
            return (v, sum(p[1] for p in parts) + len(parts) * eps * sum(abs(p[0]) for p in parts),
                    sum(p[2] for p in parts))
        if node.is_Mul:
            parts = [self(a) for a in node.args]
            v = mpmath.fprod(p[0] for p in parts)
            e = mpmath.mpf(0)
            for i, (_, ei, _) in enumerate(parts):
                if ei:
                    e += ei * mpmath.fprod(abs(p[0]) for j, p in enumerate(parts) if j != i)
            return v, e + len(parts) * eps * abs(v), mpmath.fprod(p[2] for p in parts)
        if node.is_Pow:
            return self._pow(node)
        if isinstance(node, sp.Abs):
            v, e, s = self(node.args[0])
            return abs(v), e, s
        if isinstance(node, sp.sign):
            v, e, _ = self(node.args[0])
            if v == 0 and e == 0:
                return mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)
            if abs(v) <= e:
                raise Unresolved(f"sign of a value indistinguishable from 0 in {_short(node)}",
                                 _digits_short(e, abs(v)))
            return mpmath.sign(v), mpmath.mpf(0), mpmath.mpf(1)
        if isinstance(node, sp.atan2):
            (y, ey, _), (x, ex, _) = self(node.args[0]), self(node.args[1])
            r2 = x * x + y * y
            if r2 == 0:
                raise PointRejected(f"atan2 at (0, 0) in {_short(node)}")
            if (ex + ey) ** 2 > _ILL * r2:
                raise Unresolved(f"atan2 near (0, 0) in {_short(node)}", _digits_short((ex + ey) ** 2, r2) / 2)
            v = mpmath.atan2(y, x)
            return v, (abs(x) * ey + abs(y) * ex) / r2 + eps * abs(v), abs(v)
        if node.func in _FUNCS:
            return self._function(node)
        raise CannotEvaluate(f"cannot evaluate {type(node).__name__} numerically")

    def _function(self, node: sp.Basic) -> tuple:
        f, slope, scale = _FUNCS[node.func]
        x, ex, _ = self(node.args[0])
        if node.func in _GROWING and abs(x) > _MAX_EXP_ARG:
            over = x > 0 or node.func is not sp.exp
            raise PointRejected(f"{'overflow' if over else 'underflow'}: {_short(node)} is beyond "
                                f"10^{'' if over else '-'}{MAX_DECADES}")
        if node.func is sp.log and x <= ex:
            if -x > ex:
                raise PointRejected(f"log of a non-positive value in {_short(node)}")
            raise Unresolved(f"log of a value indistinguishable from 0 in {_short(node)}", _digits_short(ex, abs(x)))
        if node.func in (sp.asin, sp.acos) and abs(x) >= 1 - ex:
            if abs(x) - 1 > ex:
                raise PointRejected(f"non-real value of {_short(node)}")
            raise Unresolved(f"{node.func.__name__} of a value indistinguishable from ±1 in {_short(node)}", math.inf)
        if ex > _ILL * scale(x):
            raise Unresolved(f"an argument known to too few digits in {_short(node)}", _digits_short(ex, scale(x)))
        v = f(x)
        if isinstance(v, mpmath.mpc):
            raise PointRejected(f"non-real value of {_short(node)}")
        if node.func in _POLES and ex * (1 + abs(v)) > _ILL:
            raise Unresolved(f"{node.func.__name__} too near a pole for the digits in {_short(node)}",
                             _digits_short(ex * (1 + abs(v)), 1))
        df = slope(x, v)
        if x and v and abs(x) > ex:
            self._deeper(abs(x) * df / abs(v))  # κ < 1: the function attenuates relative changes of x
            if node.func in _ANALYTIC_AT_0:
                self._deeper(abs(x))
        return v, df * ex + self.eps * abs(v), abs(v)

    def _pow(self, node: sp.Pow) -> tuple:
        eps = self.eps
        b, eb, sb = self(node.base)
        if node.exp.is_Rational:
            n = node.exp
            if n.is_Integer and n >= 0:
                k = int(n)  # b^k by repeated squaring: cheap for any k (the result's size is checked after)
                v = b ** k
                return v, (k * abs(b) ** (k - 1) * eb if k else 0) + eps * abs(v) * (1 + k.bit_length()), sb ** k
            if b == 0:
                raise PointRejected(f"a power with a zero base in {_short(node)}")
            if eb > _ILL * abs(b):
                raise Unresolved(f"a power with an uncertain base in {_short(node)}", _digits_short(eb, abs(b)))
            if n.is_Integer:
                v = b ** int(n)
                return v, abs(n) * abs(v / b) * eb + eps * abs(v) * (1 + int(abs(n)).bit_length()), abs(v)
            if b < 0:
                raise PointRejected(f"non-real value of {_short(node)}")
            v = mpmath.root(b, int(n.q)) ** int(n.p) if n.p > 0 else 1 / mpmath.root(b, int(n.q)) ** int(-n.p)
            return v, abs(n) * abs(v / b) * eb + eps * abs(v) * (2 + int(abs(n.p)).bit_length()), abs(v)
        x, ex, _ = self(node.exp)
        if b <= 0 and -b > eb:
            raise PointRejected(f"a non-positive base of a symbolic power in {_short(node)}")
        if eb > _ILL * abs(b) or b <= 0:
            raise Unresolved(f"an uncertain base of a symbolic power in {_short(node)}", _digits_short(eb, abs(b)))
        lb = mpmath.log(b)
        if abs(x * lb) > _MAX_EXP_ARG:
            raise PointRejected(f"{'overflow' if x * lb > 0 else 'underflow'}: {_short(node)} is beyond "
                                f"10^±{MAX_DECADES}")
        xe = abs(x / b) * eb + abs(lb) * ex
        if x and abs(x) > ex:
            self._deeper(abs(x * lb))  # b^x = exp(x log b) attenuates changes of x by |x log b|
        if xe > _ILL:
            raise Unresolved(f"an exponent known to too few digits in {_short(node)}", _digits_short(xe, 1))
        v = mpmath.exp(x * lb)
        return v, abs(v) * xe + eps * abs(v) * (2 + abs(x * lb)), abs(v)


def _short(node: sp.Basic, limit: int = 60) -> str:
    return brief(node, limit)  # not str(): an expanded dt(...) may be a tree of 10^5 nodes


def evaluate_terms(expr: sp.Basic, point: Mapping[sp.Symbol, sp.Rational], *, dps: int) -> Terms:
    """:class:`Terms` of ``expr`` at ``point`` (exact rationals) with ``dps`` significant digits.

    Raises :class:`PointRejected` where no trustworthy real value exists (:class:`Unresolved` when
    more digits may give one), :class:`CannotEvaluate` for an unknown node type.  The mpmath
    precision is restored afterwards.
    """
    with mpmath.workdps(dps):
        ev = _Evaluator(point)
        v, e, s = ev(as_symbolic(expr))
        return Terms(v, e, s, ev.depth)


def evaluate(expr: sp.Basic, point: Mapping[sp.Symbol, sp.Rational], *, dps: int) -> tuple:
    """(value, error bound) of ``expr`` at ``point``: :func:`evaluate_terms` without the sizes."""
    t = evaluate_terms(expr, point, dps=dps)
    return t.value, t.error
