"""Compare LHS and RHS at one point, with digits enough that the answer means something.

A difference d = LHS − RHS computed with error bound E (:mod:`.evaluate`) says one of three
things at a given precision:

- *it differs*: |d| > 2E, so d ≠ 0 however small it is (the point is exact, so the claim is
  false there) — confirmed at a second, higher precision whose value agrees within the bounds;
- *it agrees*: |d| ≤ 2E and E ≤ 10^−K · S, S the size of the terms, K = max(base, 2·depth + 40)
  − 10 with depth the decades by which the expression attenuates some input (:mod:`.evaluate`):
  a perturbation of relative size 10^−k present anywhere — a typed 1e-100, θ·10^-100 inside a
  sine, tanh near its asymptote — changes the result by about 10^−k, or 10^−2k at second order
  (cos(10^-100 θ) = 1), so it is seen;
- *not yet*: E is too large for that (digits lost to cancellation or to an ill-conditioned
  function count against K), or the evaluator could not trust its bound.  The digits are raised
  by what is missing (at most fourfold a step) and the point evaluated again, up to
  :data:`MAX_DIGITS`; past that, or past the time budget, the point is rejected with the
  reason, never taken as agreement.

So a difference hidden below the working precision (``sin(θ) = sin(θ + 1e-100)``), a value
with no correct digit, or an overflow (``exp(exp(1000)) = 1``) never counts as agreement.

>>> import sympy as sp
>>> x = sp.Symbol("x", real=True)
>>> compare(sp.sin(x), sp.sin(x + sp.Rational(1, 10**100)), {x: sp.Rational(1, 2)}, base=60).kind
'differ'
>>> compare(sp.sin(x)**2 + sp.cos(x)**2, sp.Integer(1), {x: sp.Rational(1, 2)}, base=60).kind
'agree'
>>> compare(sp.exp(sp.exp(1000)), sp.Integer(1), {}, base=60).reason
'overflow: exp(exp(1000)) is beyond 10^10000'
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Mapping

import mpmath
import sympy as sp

from .budget import run_until
from .evaluate import PointRejected, Unresolved, evaluate_terms

__all__ = ["compare", "Comparison", "MAX_DIGITS", "SCREEN_DIGITS"]

#: The most digits an evaluation may use (a 2000-digit evaluation of the heavy top's on-shell
#: expressions takes about 0.05 s with mpmath's pure-Python backend).
MAX_DIGITS = 2500
#: The precision of the first, screening evaluation.
SCREEN_DIGITS = 30
_MARGIN = 10  # digits a resolved value may have lost to cancellation or conditioning


@dataclass(frozen=True)
class Comparison:
    """The outcome at one point: ``kind`` "agree", "differ" or "reject", at ``digits`` digits.

    For "differ": both sides' values and the difference; for "reject": the reason.
    """

    kind: str
    digits: int
    reason: str = ""
    agreed_to: int = 0  # for "agree": the digits K of the terms' size to which LHS − RHS vanished
    lhs: mpmath.mpf | None = None
    rhs: mpmath.mpf | None = None
    difference: mpmath.mpf | None = None


@dataclass(frozen=True)
class _Difference:
    digits: int
    lhs: mpmath.mpf
    rhs: mpmath.mpf
    d: mpmath.mpf
    error: mpmath.mpf
    size: mpmath.mpf
    depth: float  # decades by which some input is attenuated (:mod:`.evaluate`)

    @property
    def differs(self) -> bool:
        return abs(self.d) > 2 * self.error

    def consistent(self, other: "_Difference") -> bool:
        """Whether the two differences agree within their bounds (a check on the bounds themselves)."""
        with mpmath.workdps(max(self.digits, other.digits)):
            return abs(self.d - other.d) <= 2 * (self.error + other.error)

    def resolved_digits(self) -> float:
        """Digits to which the difference is known relative to the size of the terms: −log10(E/S)."""
        if self.error == 0:
            return math.inf
        if self.size == 0:
            return -math.inf
        with mpmath.workdps(self.digits):
            return -float(mpmath.log10(self.error / self.size))

    def digits_needed(self, base: int) -> tuple[int, str, int]:
        """The digits at which an agreement would count, and why that many.

        An agreement counts when the difference is known to K = max(base, 2·depth + 40) − 10
        digits relative to the terms.  Digits lost to cancellation or conditioning (the
        shortfall of :meth:`resolved_digits` from this precision) are lost at any precision,
        so they are added once.  Returns (digits, why, K).
        """
        by_depth = math.ceil(2 * self.depth) + 40
        wanted = max(base, by_depth) - _MARGIN
        why = f"a relative 10^-{self.depth:.0f} is in play" if by_depth > base else f"{base} digits asked"
        known = self.resolved_digits()
        if known >= wanted:
            return self.digits, why, wanted
        if known == -math.inf:
            return 10 * MAX_DIGITS, "no digit of the terms is known", wanted
        lost = self.digits - known
        return self.digits + math.ceil(wanted - known) + _MARGIN // 2, why + f"; {lost:.0f} digits are lost", wanted


def _difference(lhs: sp.Expr, rhs: sp.Expr, point: Mapping, digits: int) -> _Difference:
    left, right = (evaluate_terms(x, point, dps=digits) for x in (lhs, rhs))
    with mpmath.workdps(digits):
        d = left.value - right.value
        error = left.error + right.error + 2 * mpmath.mp.eps * abs(d)
    return _Difference(digits, left.value, right.value, d, error, left.size + right.size,
                       max(left.depth, right.depth))


class _Rejected(Exception):
    pass


def compare(lhs: sp.Expr, rhs: sp.Expr, point: Mapping[sp.Symbol, sp.Rational], *, base: int,
            cap: int = MAX_DIGITS, deadline: float | None = None) -> Comparison:
    """Decide LHS − RHS at ``point`` (exact rationals): see the module docstring.

    ``base``: the fewest digits an agreement is accepted at; ``cap``: the most digits used;
    ``deadline``: a :func:`time.monotonic` instant after which no evaluation starts (and one
    running is interrupted, in the main thread: :mod:`.budget`); the point is then rejected.
    :class:`~.evaluate.CannotEvaluate` propagates.
    """
    def once(digits: int) -> _Difference:
        if deadline is None:
            return _difference(lhs, rhs, point, digits)
        if deadline <= time.monotonic():  # (the same reason at every point, so that the reasons add up)
            raise _Rejected("needs more digits than the time budget allows (--budget)" if digits > SCREEN_DIGITS
                            else "the time budget (--budget) was spent before this point")
        done, out = run_until(lambda: _difference(lhs, rhs, point, digits), deadline, unbudgeted_ok=True)
        if not done:
            raise _Rejected("an evaluation exceeded the time budget (--budget)")
        return out

    def at(digits: int, ceiling: int = cap) -> _Difference:
        """The difference at ``digits`` digits, or at more where the evaluator asks for them."""
        for _ in range(5):
            if digits > ceiling:
                raise _Rejected(f"needs more than {ceiling} digits")
            try:
                return once(digits)
            except Unresolved as exc:
                if math.isinf(exc.short) or digits >= ceiling:
                    raise _Rejected(f"{exc} (unresolved at {digits} digits)") from None
                digits = min(ceiling, max(2 * digits, digits + math.ceil(exc.short) + 2 * _MARGIN))
        raise _Rejected(f"unresolved at {digits} digits")

    def confirm(first: _Difference) -> Comparison:
        """A difference seen at one precision, seen again at a higher one with a consistent value."""
        higher = max(base, first.digits + max(2 * _MARGIN, first.digits // 2))
        second = at(higher, ceiling=max(cap, higher))
        if not (second.differs and first.consistent(second)):
            raise _Rejected(f"the {first.digits}- and {second.digits}-digit values disagree beyond their error bounds")
        return Comparison("differ", second.digits, lhs=second.lhs, rhs=second.rhs, difference=second.d)

    try:
        current = at(SCREEN_DIGITS)
        for _ in range(10):
            if current.differs:
                return confirm(current)
            target, why, wanted = current.digits_needed(base)
            if target <= current.digits:
                return Comparison("agree", current.digits, agreed_to=wanted)
            if current.digits >= cap:  # no difference at the most digits allowed
                raise _Rejected(f"an agreement would need {target} digits ({why}), more than {cap}")
            # at most fourfold a step: a difference usually shows well before the target
            following = at(min(cap, max(current.digits + 1, min(target, max(base, 4 * current.digits)))))
            if not current.consistent(following):
                raise _Rejected(f"the {current.digits}- and {following.digits}-digit values disagree beyond "
                                "their error bounds")
            current = following
        raise _Rejected(f"not resolved at {current.digits} digits")
    except (_Rejected, PointRejected) as exc:
        return Comparison("reject", 0, reason=str(exc))
