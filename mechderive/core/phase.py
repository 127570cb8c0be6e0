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

import numpy as np

from ..special._doubledouble import PI_HI, PI_LO, dd_add, two_prod

__all__ = ["DD", "reduce_phase", "reduce_phase_nearest", "mod_two_pi", "EXTENDED", "EPS_EXTENDED", "EXTENDED_TO_DOUBLE",
           "EXTENDED_SAFETY", "EXTENDED_TOLERANCE"]


class DD:
    """A double-double constant (hi + lo)·2^exp (|lo| ≤ ulp(hi)/2), ~32 significant digits.

    ``exp`` is 0 except for rates built by :meth:`scaled`, whose size may lie outside the range
    where hi and lo are both normal floats (a rate of 1e-310 rad/s has no low word at all).

    Immutable, with the ``__init__``, repr, ``==`` and hash a frozen dataclass would have: written out, because
    generating them (one ``exec`` each) took ~1 ms of every warm ``mechderive run``.  Not a tuple: a DD
    multiplied by an integer must fail, not repeat.

    >>> DD(1.0, 2.0**-60) == DD(1.0, 2.0**-60, 0), DD(0.5, 0.0, -3)
    (True, DD(hi=0.5, lo=0.0, exp=-3))
    """

    __slots__ = ("hi", "lo", "exp")
    hi: float
    lo: float
    exp: int

    def __init__(self, hi: float, lo: float, exp: int = 0) -> None:
        object.__setattr__(self, "hi", hi)
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "exp", exp)

    def __setattr__(self, name: str, value: object) -> None:
        from dataclasses import FrozenInstanceError

        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        from dataclasses import FrozenInstanceError

        raise FrozenInstanceError(f"cannot delete field {name!r}")

    def __repr__(self) -> str:
        return f"DD(hi={self.hi!r}, lo={self.lo!r}, exp={self.exp!r})"

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return (self.hi, self.lo, self.exp) == (other.hi, other.lo, other.exp)  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash((self.hi, self.lo, self.exp))

    def __reduce__(self) -> tuple:  # copy and pickle through __init__ (the slots cannot be set afterwards)
        return DD, (self.hi, self.lo, self.exp)

    @classmethod
    def of(cls, x) -> "DD":
        """The double-double nearest to an mpmath number ``x`` (computed at ≥ 32 digits), or the double-double
        holding a ``numpy.longdouble`` exactly (its 11 extra bits in the low word; no mpmath imported)."""
        hi = float(x)
        if isinstance(x, np.floating):
            return cls(hi, float(x - type(x)(hi)))
        import mpmath

        return cls(hi, float(x - mpmath.mpf(hi)))

    @classmethod
    def scaled(cls, x) -> "DD":
        """``x`` as (hi + lo)·2^exp: exp = 0 in the double range's comfortable middle, 2^-500 ≤ |x| ≤ 2^500
        (so hi + lo is the value, as for :meth:`of`), else chosen so that 1/2 ≤ |hi| < 1.

        >>> import mpmath
        >>> d = DD.scaled(mpmath.mpf("1e-310"))
        >>> d.exp, 0.5 <= abs(d.hi) < 1, DD.scaled(mpmath.mpf(3)).exp
        (-1029, True, 0)

        A ``numpy.longdouble`` is split the same way without mpmath (its frexp and ldexp are exact).
        """
        if isinstance(x, np.floating):
            if x == 0 or 2.0**-500 <= abs(x) <= 2.0**500:
                return cls.of(x)
            y, e = np.frexp(x)
            hi = float(y)
            return cls(hi, float(y - type(y)(hi)), int(e))
        import mpmath

        if x == 0 or mpmath.mpf(2) ** -500 <= abs(x) <= mpmath.mpf(2) ** 500:
            return cls.of(x)
        _, e = mpmath.frexp(x)
        y = mpmath.ldexp(x, -int(e))
        hi = float(y)
        return cls(hi, float(y - mpmath.mpf(hi)), int(e))


def _times(rate: DD, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """rate·t in double-double (TwoProduct), rescaled by 2^exp: exact but for the low word's rounding."""
    hi, lo = two_prod(rate.hi, t)
    lo = lo + rate.lo * t
    if rate.exp:
        hi, lo = np.ldexp(hi, rate.exp), np.ldexp(lo, rate.exp)
    return hi, lo


def reduce_phase(rate: DD, offset: DD, period: DD | None, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(j, r) with rate·t + offset = j·period + r, j integer, r in [0, period); double-double throughout.

    With ``period`` None (an aperiodic motion, e.g. on a separatrix) j = 0 and r is the phase.

    >>> j, r = reduce_phase(DD(1.0, 0.0), DD(0.5, 0.0), DD(2.0, 0.0), np.array([10.0]))
    >>> int(j[0]), float(r[0])
    (5, 0.5)
    """
    hi, lo = _times(rate, t)
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


def reduce_phase_nearest(rate: DD, offset: DD, quarter: DD | None,
                         t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, v, v_lo) with rate·t + offset = q·quarter + v + v_lo, q integer, |v| ≤ quarter/2 (to rounding).

    The remainder is formed in double-double and returned as such (|v_lo| ≤ ulp(v)/2), so v
    keeps its *relative* accuracy however close the phase is to a multiple of the quarter
    period: the point of reducing to the nearest multiple is that a Jacobi function vanishing
    there (sn at 0 and 2K, cn at K and 3K) is then evaluated from a small, accurate argument;
    v_lo lets functions like e^v be corrected for the rounding of a large v.  With ``quarter``
    None (an aperiodic motion) q = 0 and v + v_lo is the phase.

    >>> q, v, v_lo = reduce_phase_nearest(DD(1.0, 0.0), DD(0.5, 0.0), DD(2.0, 0.0), np.array([10.0]))
    >>> int(q[0]), float(v[0]), float(v_lo[0])
    (5, 0.5, 0.0)
    """
    hi, lo = _times(rate, t)
    hi, lo = dd_add(hi, lo, offset.hi, offset.lo)
    if quarter is None:
        return np.zeros_like(hi), hi, lo
    q = np.rint(hi / quarter.hi)
    ph, pl = two_prod(q, quarter.hi)  # exact: q is an integer below 2**53
    pl = pl + q * quarter.lo
    rh, rl = dd_add(hi, lo, -ph, -pl)
    return q, rh, rl


def mod_two_pi(rate: DD | float, x: np.ndarray) -> np.ndarray:
    """(rate·x) modulo 2π, in (-π, π] up to rounding, formed in double-double.

    >>> round(float(mod_two_pi(DD(1.0, 0.0), np.array(7.0))), 15)   # 7 - 2π
    0.716814692820414
    """
    ph, pl = _times(rate if isinstance(rate, DD) else DD(float(rate), 0.0), x)
    k = np.round(ph / (2 * PI_HI))
    kh, kl = two_prod(k, 2 * PI_HI)
    kl = kl + k * 2 * PI_LO
    rh, rl = dd_add(ph, pl, -kh, -kl)
    return rh + rl

# --- the extended-precision setups (the heavy and free tops' exact_extended): their error accounting ------------

#: whether numpy.longdouble is wider than a double here (x87 extended precision on x86-64)
EXTENDED = bool(np.finfo(np.longdouble).eps < 1e-18)
#: the longdouble's ε
EPS_EXTENDED = float(np.finfo(np.longdouble).eps)
#: ε_ext / ε_double: a constant computed in doubles and in longdouble by the same code differs by about the
#: doubles' error; scaled by this ratio it estimates the extended value's
EXTENDED_TO_DOUBLE = EPS_EXTENDED / float(np.finfo(np.float64).eps)
#: the factor on that scaled difference (the two roundings are not proportional value by value)
EXTENDED_SAFETY = 16.0
#: the largest estimated error a constant may carry (relative; the phase in units of K, the angles
#: accumulated over the span in rad): 1e-14, a hundredth of the 1e-12 the batched paths promise
EXTENDED_TOLERANCE = 1e-14
