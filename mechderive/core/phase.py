"""Phases of periodic motions in double-double arithmetic: long times cost no accuracy.

A closed-form motion is a function of a phase v = ω t + v0 that is periodic (or
quasi-periodic) with period P in v.  Evaluating it at t = 10⁶ periods in plain
floating point would lose the phase's low digits twice: in the product ω·t and in
the reduction v mod P.  Here both are done with error-free transformations
(Dekker's TwoProduct, Knuth's TwoSum, from :mod:`mechderive.special._doubledouble`),
with ω, v0 and P known to ~32 digits as :class:`DD` pairs, giving an exact integer
period count j and a remainder r accurate to a few ulp of r.  What no method can
avoid is the rounding of t itself (relative 1.1e-16).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..special._doubledouble import PI_HI, PI_LO, dd_add, two_prod

__all__ = ["DD", "reduce_phase", "mod_two_pi"]


@dataclass(frozen=True)
class DD:
    """A double-double constant hi + lo (|lo| ≤ ulp(hi)/2), ~32 significant digits."""

    hi: float
    lo: float

    @classmethod
    def of(cls, x) -> "DD":
        """The double-double nearest to an mpmath number ``x`` (computed at ≥ 32 digits)."""
        import mpmath

        hi = float(x)
        return cls(hi, float(x - mpmath.mpf(hi)))


def reduce_phase(rate: DD, offset: DD, period: DD | None, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(j, r) with rate·t + offset = j·period + r, j integer, r in [0, period); double-double throughout.

    With ``period`` None (an aperiodic motion, e.g. on a separatrix) j = 0 and r is the phase.

    >>> j, r = reduce_phase(DD(1.0, 0.0), DD(0.5, 0.0), DD(2.0, 0.0), np.array([10.0]))
    >>> int(j[0]), float(r[0])
    (5, 0.5)
    """
    hi, lo = two_prod(rate.hi, t)
    lo = lo + rate.lo * t
    hi, lo = dd_add(hi, lo, offset.hi, offset.lo)
    if period is None:
        return np.zeros_like(t), hi + lo
    j = np.floor(hi / period.hi)
    ph, pl = two_prod(j, period.hi)  # exact: j is an integer below 2**53
    pl = pl + j * period.lo
    rh, rl = dd_add(hi, lo, -ph, -pl)
    r = rh + rl
    # floor of the rounded hi part can be off by one at a period boundary: correct it
    low = r < 0
    r, j = np.where(low, r + period.hi, r), np.where(low, j - 1, j)
    high = r >= period.hi
    r, j = np.where(high, r - period.hi, r), np.where(high, j + 1, j)
    return j, r


def mod_two_pi(rate: DD | float, x: np.ndarray) -> np.ndarray:
    """(rate·x) modulo 2π, in (-π, π] up to rounding, formed in double-double.

    >>> round(float(mod_two_pi(DD(1.0, 0.0), np.array(7.0))), 15)   # 7 - 2π
    0.716814692820414
    """
    hi_r, lo_r = (rate.hi, rate.lo) if isinstance(rate, DD) else (float(rate), 0.0)
    ph, pl = two_prod(hi_r, x)
    pl = pl + lo_r * x
    k = np.round(ph / (2 * PI_HI))
    kh, kl = two_prod(k, 2 * PI_HI)
    kl = kl + k * 2 * PI_LO
    rh, rl = dd_add(ph, pl, -kh, -kl)
    return rh + rl
