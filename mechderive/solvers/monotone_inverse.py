"""The inverse of a monotone function given with its derivative: s(t) with T(s) = t, by a safeguarded Newton
iteration, vectorised over many targets (issue 16: a coordinate c(t) from the closed form t(c) of an orbit).

For each target tᵢ the caller gives a bracket [loᵢ, hiᵢ] with σ(T(lo) − t) ≤ 0 ≤ σ(T(hi) − t) (σ = +1 for an
increasing T, −1 for a decreasing one) and a first guess inside it.  Each step evaluates T and T' at the current
s (one vectorised call for all targets still moving), narrows the bracket by the sign of σ(T(s) − t) and takes the
Newton step s − (T(s) − t)/T'(s) when it stays strictly inside the bracket, else the bracket's midpoint (Newton
near a flat or steep stretch of T cannot leave it; bisection halves it, so every target converges).

A target stops when the step is at most a few ulp of s (Newton converges quadratically: the next step would be below
the rounding of s), when the bracket is that narrow, or when |T(s) − t| is within a few ulp of t or the caller's
rounding floor of T (no double s does better: T itself is evaluated to about that).  A caller that can form T(s) − t
without T's own rounding (``differences=True``: a large T whose secular part is exact in double-double) gives that
difference instead of T, and the ulp of t is no floor: the iteration can then go to the double s nearest the root
(``step_ulps=0``: a target stops when Newton's next point is s itself, or its bracket is one ulp wide — a step to a
neighbour is taken and evaluated, not assumed).  Near convergence T's rounding makes the last steps noisy, so each
target keeps the s with the smallest |T(s) − t| ever evaluated, and that residual is returned with it: the caller
turns it into the error of s (residual × ds/dt), measured, not assumed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

__all__ = ["MonotoneInverse", "invert_monotone"]

#: the stopping step, in ulp of s (and the residual floor, in ulp of t)
ULPS = 4.0


@dataclass
class MonotoneInverse:
    """``s`` with T(s) ≈ t; ``residual`` = T(s) − t as evaluated (doubles) at that very s; ``iterations``: the
    evaluations of T the slowest target took; ``bisections``: how many steps (over all targets) fell back to the
    midpoint; ``converged``: per target, whether it met a stopping rule (else it ran out of iterations, and its
    residual says how far it got)."""

    s: np.ndarray
    residual: np.ndarray
    iterations: int
    bisections: int
    converged: np.ndarray


def invert_monotone(function: Callable[..., tuple[np.ndarray, np.ndarray]], targets: np.ndarray,
                    lo: np.ndarray, hi: np.ndarray, guess: np.ndarray, *, increasing: bool, noise: Any = 0.0,
                    max_iterations: int = 120, differences: bool = False, step_ulps: float = 4.0) -> MonotoneInverse:
    """Solve T(s) = t for each target (see the module docstring).  ``function(s)`` returns (T(s), T'(s)) for an
    array s — with ``differences``, ``function(s, t)`` returns (T(s) − t, T'(s)) for the targets t of those s;
    ``lo`` < ``hi`` bracket each root; ``guess`` starts the iteration (clipped into the bracket); ``noise``: the
    absolute rounding of T's evaluation where it exceeds ulp(t) (T a difference of terms larger than t near t = 0),
    a residual below which no step is trusted (a number, or one per target); ``step_ulps``: the Newton step, in ulp
    of s, at or below which a target stops (0: only where the next point is s itself).

    >>> r = invert_monotone(lambda s: (s**3 + s, 3 * s**2 + 1), np.array([2.0, -10.0]), np.array([-3.0, -3.0]),
    ...                     np.array([3.0, 3.0]), np.array([0.0, 0.0]), increasing=True)
    >>> [float(x) for x in r.s], bool(r.converged.all())
    ([1.0, -2.0], True)
    """
    t = np.asarray(targets, dtype=float)
    noise = np.broadcast_to(np.asarray(noise, dtype=float), t.shape)
    floor_ulps = 0.0 if differences else ULPS
    lo = np.array(lo, dtype=float, copy=True)
    hi = np.array(hi, dtype=float, copy=True)
    s = np.clip(np.asarray(guess, dtype=float), lo, hi)
    sigma = 1.0 if increasing else -1.0
    best_s, best_res = s.copy(), np.full(t.shape, np.inf)  # |T − t| of the best s so far, and its sign below
    best_signed = np.full(t.shape, np.nan)
    converged = np.zeros(t.shape, bool)
    active = np.arange(t.size)
    bisections = 0
    iterations = 0
    while active.size and iterations < max_iterations:
        iterations += 1
        sa = s[active]
        if differences:
            res, slope = function(sa, t[active])
            res = np.asarray(res, float)
        else:
            value, slope = function(sa)
            res = np.asarray(value, float) - t[active]
        better = np.abs(res) < best_res[active]
        best_s[active[better]] = sa[better]
        best_res[active[better]] = np.abs(res[better])
        best_signed[active[better]] = res[better]
        # the bracket narrows by the sign of σ(T(s) − t); a zero residual is a root
        below = sigma * res < 0
        lo[active[below]] = sa[below]
        above = sigma * res > 0
        hi[active[above]] = sa[above]
        with np.errstate(all="ignore"):
            newton = sa - res / np.asarray(slope, float)
        lo_a, hi_a = lo[active], hi[active]
        inside = np.isfinite(newton) & (newton > lo_a) & (newton < hi_a)
        step_to = np.where(inside, newton, 0.5 * (lo_a + hi_a))
        ulp_s = np.spacing(np.abs(sa))
        # the Newton step itself (taken or not) at the rounding of s: T's rounding decides its last bits
        small = np.isfinite(newton) & (np.abs(newton - sa) <= step_ulps * ulp_s)
        done = ((res == 0) | small | (hi_a - lo_a <= max(step_ulps, 1.0) * ulp_s)
                | (np.abs(res) <= floor_ulps * np.spacing(np.abs(t[active])) + noise[active]))
        bisections += int(np.count_nonzero(~inside & ~done))
        s[active] = step_to
        converged[active[done]] = True
        active = active[~done]
    return MonotoneInverse(best_s, best_signed, iterations, bisections, converged)
