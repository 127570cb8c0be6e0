"""Double-double arithmetic on NumPy arrays, or on Python floats for one value (private).

A double-double number is an unevaluated sum ``hi + lo`` of two float64 with
``|lo| <= ulp(hi)/2``; it carries about 106 bits.  Only what the elliptic
functions need is here: the quarter period K(m) to ~32 digits, so that the
argument reduction u - j·2K loses nothing for j up to ~1e15.  The error-free
transformations are Knuth's TwoSum and Dekker's TwoProduct (with Veltkamp
splitting, since NumPy has no fused multiply-add).

>>> hi, lo = two_sum(1.0, 1e-20)
>>> hi, lo
(1.0, 1e-20)
"""

from __future__ import annotations

import math

import numpy as np

from ..core.validate import some

__all__ = ["two_sum", "two_prod", "dd_add", "dd_mul", "dd_div", "dd_sqrt", "PI_HI", "PI_LO"]

#: π = PI_HI + PI_LO to about 32 digits.
PI_HI = 3.141592653589793
PI_LO = 1.2246467991473532e-16

_SPLITTER = 134217729.0  # 2**27 + 1
_BIG = 2.0**995  # above this, Veltkamp splitting would overflow: scale first


def two_sum(a, b):
    """Return (s, e) with s = fl(a + b) and s + e = a + b exactly (Knuth)."""
    s = a + b
    bb = s - a
    e = (a - (s - bb)) + (b - bb)
    return s, e


def _fast_two_sum(a, b):
    """(s, e) with s + e = a + b exactly, provided |a| >= |b| (Dekker)."""
    s = a + b
    return s, b - (s - a)


def _split(a):
    """Veltkamp split a = hi + lo, each with <= 26 significant bits."""
    big = abs(a) > _BIG
    if some(big):  # (not np.any's wrapper: every TwoProduct splits twice)
        a_s = np.where(big, a * 2.0**-54, a)
        hi, lo = _split(a_s)
        scale = np.where(big, 2.0**54, 1.0)
        return hi * scale, lo * scale
    t = _SPLITTER * a
    hi = t - (t - a)
    return hi, a - hi


def two_prod(a, b):
    """Return (p, e) with p = fl(a·b) and p + e = a·b exactly (Dekker), barring underflow."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    return p, e


def dd_add(ah, al, bh, bl):
    """(ah + al) + (bh + bl) in double-double."""
    s, e = two_sum(ah, bh)
    t, f = two_sum(al, bl)
    e = e + t
    s, e = _fast_two_sum(s, e)
    e = e + f
    return _fast_two_sum(s, e)


def dd_mul(ah, al, bh, bl):
    """(ah + al)·(bh + bl) in double-double."""
    p, e = two_prod(ah, bh)
    e = e + (ah * bl + al * bh)
    return _fast_two_sum(p, e)


def dd_div(ah, al, bh, bl):
    """(ah + al)/(bh + bl) in double-double (long division, two correction steps)."""
    q1 = ah / bh
    ph, pl = dd_mul(q1, 0.0, bh, bl)
    rh, rl = dd_add(ah, al, -ph, -pl)
    q2 = rh / bh
    ph, pl = dd_mul(q2, 0.0, bh, bl)
    rh, rl = dd_add(rh, rl, -ph, -pl)
    q3 = rh / bh
    q1, q2 = _fast_two_sum(q1, q2)
    return dd_add(q1, q2, q3, 0.0)


def dd_sqrt(ah, al):
    """√(ah + al) in double-double for ah >= 0 (one Newton correction; tiny inputs rescaled)."""
    if type(ah) is float and type(al) is float:
        return _dd_sqrt_float(ah, al)
    ah = np.asarray(ah, dtype=float)
    small = (ah < 2.0**-900) & (ah > 0)
    scale_in = np.where(small, 2.0**200, 1.0)
    scale_out = np.where(small, 2.0**-100, 1.0)
    ah, al = ah * scale_in, al * scale_in
    s = np.sqrt(ah)
    p, e = two_prod(s, s)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.where(s > 0, ((ah - p) - e + al) / (2.0 * s), 0.0)
    hi, lo = _fast_two_sum(s, corr)
    return hi * scale_out, lo * scale_out


def _dd_sqrt_float(ah: float, al: float) -> tuple[float, float]:
    """:func:`dd_sqrt` on Python floats, step for step (the same IEEE operations, so the same bits; NaN for ah < 0
    as np.sqrt gives): the scalar AGM of the quarter period runs on floats."""
    small = 0.0 < ah < 2.0**-900
    if small:
        ah, al = ah * 2.0**200, al * 2.0**200
    s = math.sqrt(ah) if ah >= 0 else math.nan
    p, e = two_prod(s, s)
    corr = ((ah - p) - e + al) / (2.0 * s) if s > 0 else 0.0
    hi, lo = _fast_two_sum(s, corr)
    return (hi * 2.0**-100, lo * 2.0**-100) if small else (hi, lo)
