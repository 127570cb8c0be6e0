"""The parameter pair (m, m1 = 1 - m), the quarter period K to ~32 digits, argument reduction (private).

Exactness convention
--------------------
Callers may pass the complementary parameter m1 = 1 - m explicitly (near the
separatrix it is known without cancellation, e.g. m1 = 1e-14, while m = 1 - 1e-14
is already rounded).  Of the two numbers, the *smaller* is taken as exact and the
other is formed from it in double-double: m1 = 1 - m exactly when m <= 1/2, and
m = 1 - m1 exactly when m1 < 1/2.  The larger one, when given, is only checked:
|m + m1 - 1| <= 1e-15.

Quarter period
--------------
K(m) = π / (2 M(1, k')),  k' = √m1,  M = arithmetic-geometric mean   (DLMF 19.8.5)

evaluated in double-double (about 32 significant digits), so that reducing u by
j·2K costs ~|u|·1e-32 instead of j·ulp(2K).

>>> p = parameter(0.0)
>>> float(p.K_hi), float(p.K_lo)
(1.5707963267948966, 6.123233995736766e-17)
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from ..core.validate import as_finite_array, every
from ..errors import InvalidInputError
from ._doubledouble import PI_HI, PI_LO, dd_add, dd_div, dd_mul, dd_sqrt, two_prod, two_sum

__all__ = [
    "Parameter",
    "parameter",
    "check_unit_interval",
    "check_periods",
    "quarter_period",
    "reduce_by_half_periods",
    "as_output",
]

#: Largest allowed |m + m1 - 1| when both are given.
CONSISTENCY_TOL = 1e-15


class Parameter:
    """A validated parameter array: m, m1 = 1 - m (m1_hi + m1_lo exactly), K = K_hi + K_lo.

    A plain record (a frozen dataclass's generated methods took ~1 ms of every warm run's imports; its
    ``==`` and hash were of no use on arrays)."""

    __slots__ = ("m", "m1", "m1_lo", "K_hi", "K_lo")

    def __init__(self, m: np.ndarray, m1: np.ndarray, m1_lo: np.ndarray, K_hi: np.ndarray, K_lo: np.ndarray) -> None:
        self.m, self.m1, self.m1_lo, self.K_hi, self.K_lo = m, m1, m1_lo, K_hi, K_lo

    @property
    def kc(self) -> np.ndarray:
        """The complementary modulus k' = √m1."""
        return np.sqrt(self.m1 + self.m1_lo)


def check_unit_interval(arr: np.ndarray, name: str) -> None:
    """Raise unless every element of ``arr`` lies in [0, 1]."""
    bad = (arr < 0) | (arr > 1)
    if np.any(bad):
        raise InvalidInputError(f"expected `{name}` in [0, 1], got {float(arr[bad].ravel()[0])!r}")


def parameter(m: Any, m1: Any = None) -> Parameter:
    """Validate (m, m1) and return the :class:`Parameter` with K in double-double."""
    m_arr = as_finite_array(m, "m")
    check_unit_interval(m_arr, "m")
    if m1 is None:
        m1_hi, m1_lo = two_sum(1.0, -m_arr)  # exact: 1 - m is exact for m >= 1/2 anyway
        m_use = m_arr
    else:
        m1_arr = as_finite_array(m1, "m1")
        check_unit_interval(m1_arr, "m1")
        m_arr, m1_arr = np.broadcast_arrays(m_arr, m1_arr)
        gap = np.abs((m_arr + m1_arr) - 1.0)
        bad = gap > CONSISTENCY_TOL
        if np.any(bad):
            i = np.flatnonzero(bad.ravel())[0]
            raise InvalidInputError(
                f"expected `m1` = 1 - `m` (|m + m1 - 1| <= {CONSISTENCY_TOL:g}), got m = "
                f"{float(m_arr.ravel()[i])!r}, m1 = {float(m1_arr.ravel()[i])!r} (m + m1 - 1 = {gap.ravel()[i]:.3g})"
            )
        use_m1 = m1_arr < 0.5
        from_m = two_sum(1.0, -m_arr)
        m1_hi = np.where(use_m1, m1_arr, from_m[0])
        m1_lo = np.where(use_m1, 0.0, from_m[1])
        m_use = np.where(use_m1, 1.0 - m1_arr, m_arr)
    K_hi, K_lo = quarter_period(m1_hi, m1_lo)
    return Parameter(m=np.asarray(m_use, dtype=float), m1=np.asarray(m1_hi, dtype=float),
                     m1_lo=np.asarray(m1_lo, dtype=float), K_hi=K_hi, K_lo=K_lo)


def quarter_period(m1_hi: np.ndarray, m1_lo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """K = π/(2 AGM(1, √m1)) in double-double; K = inf where m1 = 0.

    A scalar parameter (the usual case: one motion, many times) is computed once per value, and as a scalar: the
    same arithmetic on NumPy scalars, half the time of an array of one point (a batched closed form's batch of
    one).
    """
    if np.size(m1_hi) == 1 and np.size(m1_lo) == 1:
        shape = np.broadcast(m1_hi, m1_lo).shape
        K_hi, K_lo = _quarter_period_scalar(float(np.ravel(m1_hi)[0]), float(np.ravel(m1_lo)[0]))
        return np.full(shape, K_hi), np.full(shape, K_lo)
    return _quarter_period(m1_hi, m1_lo)


@functools.lru_cache(maxsize=256)
def _quarter_period_scalar(m1_hi: float, m1_lo: float) -> tuple[float, float]:
    # in Python floats: the same IEEE double operations as on NumPy values (so the same bits), without the
    # ~3 µs of NumPy's dispatch each of the AGM's ~400 operations costs on a 0-d array
    if m1_hi == 0.0:
        return math.inf, 0.0
    return _agm_quarter_period(m1_hi, m1_lo, 1.0, 0.0)


def _quarter_period(m1_hi: np.ndarray, m1_lo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    m1_hi = np.asarray(m1_hi, dtype=float)
    zero = m1_hi == 0.0
    safe_hi = np.where(zero, 1.0, m1_hi)
    safe_lo = np.where(zero, 0.0, m1_lo)
    K_hi, K_lo = _agm_quarter_period(safe_hi, safe_lo, np.ones_like(safe_hi), np.zeros_like(safe_hi))
    return np.where(zero, np.inf, K_hi), np.where(zero, 0.0, K_lo)


def _agm_quarter_period(m1_hi: Any, m1_lo: Any, one: Any, zero: Any) -> tuple[Any, Any]:
    """π/(2 M(1, √m1)) in double-double for m1 > 0, on arrays or on Python floats (``one``, ``zero``: 1 and 0
    in the same kind)."""
    bh, bl = dd_sqrt(m1_hi, m1_lo)
    ah, al = one, zero
    for _ in range(64):
        dh, dl = dd_add(ah, al, -bh, -bl)
        if every(abs(dh) <= 1e-17 * ah):
            break
        nh, nl = dd_add(ah, al, bh, bl)
        ph, pl = dd_mul(ah, al, bh, bl)
        bh, bl = dd_sqrt(ph, pl)
        ah, al = 0.5 * nh, 0.5 * nl
    # |a - b| <= 1e-17 a: the AGM is (a + b)/2 to relative (1e-17)²/16.
    nh, nl = dd_add(ah, al, bh, bl)
    return dd_div(PI_HI, PI_LO, nh, nl)  # π/(2M) with 2M = a + b


def reduce_by_half_periods(u: np.ndarray, K_hi: np.ndarray, K_lo: np.ndarray):
    """Split u = j·2K + r with integer j and |r| <~ K; return (j, r_hi, r_lo), r in double-double.

    u - p_hi is exact (Sterbenz) because u and p_hi = fl(j·2K) agree to a factor 2, and
    j·2K = p_hi + p_lo + j·2K_lo is formed error-free up to j·2K_lo's rounding, so r is the
    exact reduction of the double u to about |u|·1e-32 + ulp(r).  Where K = inf, j = 0 and r = u.
    """
    finite = np.isfinite(K_hi)
    K2_hi = np.where(finite, 2.0 * K_hi, 1.0)
    K2_lo = np.where(finite, 2.0 * K_lo, 0.0)
    j = np.where(finite, np.rint(u / K2_hi), 0.0)
    p_hi, p_lo = two_prod(j, K2_hi)
    t = u - p_hi
    e = -p_lo - j * K2_lo
    r_hi, r_lo = two_sum(t, e)
    return j, r_hi, r_lo


def check_periods(periods: Any) -> np.ndarray:
    """Return ``periods`` as a float array of integers, raising otherwise."""
    arr = as_finite_array(periods, "periods")
    bad = arr != np.rint(arr)
    if np.any(bad):
        raise InvalidInputError(f"expected `periods` to be integers, got {float(arr[bad].ravel()[0])!r}")
    return arr


def as_output(x: np.ndarray):
    """0-d arrays become NumPy scalars, like a ufunc."""
    return x[()] if x.ndim == 0 else x
