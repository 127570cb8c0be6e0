"""Carlson's symmetric elliptic integrals R_C, R_D, R_F, R_J for real arguments, vectorised in NumPy.

Definitions (DLMF 19.16.1, 19.16.2, 19.16.5, 19.2.17):

    R_F(x, y, z)    = ½ ∫₀^∞ dt / √((t+x)(t+y)(t+z)),
    R_J(x, y, z, p) = 3/2 ∫₀^∞ dt / ((t+p) √((t+x)(t+y)(t+z))),
    R_D(x, y, z)    = R_J(x, y, z, z),
    R_C(x, y)       = R_F(x, y, y).

Algorithm: Carlson's duplication theorem and the fifth-order Taylor expansion about
the mean (B. C. Carlson, "Numerical computation of real or complex elliptic
integrals", Numer. Algorithms 10 (1995) 13–26, algorithms 1–4), with the stopping
rule 4⁻ⁿ Q < |Aₙ| for Q = (3r)^(-1/6) max|A₀ - x| (r = 2⁻⁵³ in R_F, and the
corresponding constants in R_J and R_C): the truncation error is then below one
ulp.  R_J with p < 0 is the Cauchy principal value, by Carlson's transformation
(DLMF 19.20.14).  Written here rather than taken from ``scipy.special`` because
importing SciPy's module costs ~0.4 s — more than a whole warm ``mechderive run``.

Precision: the arguments' own.  Doubles by default; with any argument a ``numpy.longdouble`` array
(x87 extended precision on x86-64: 64-bit significand, ε = 1.1e-19) every step runs in it, with the
stopping rule's r set to its half-ulp — the extended tier of the batched closed forms
(:mod:`mechderive.systems.heavy_top.batch`) takes its integrals from here.

Domain: x, y, z ≥ 0 with at most one zero; p ≠ 0; y > 0 for R_C.  The callers in
this package guarantee it; outside it the results are NaN or inf, not errors.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..core.validate import every, some

__all__ = ["elliprc", "elliprd", "elliprf", "elliprj"]

_MAX_STEPS = 64  # each step quarters Q / |A|: 64 steps reach 4⁻⁶⁴ ≈ 3e-39


def _dtype(*args) -> type:
    """longdouble if any argument is, else float64."""
    return np.longdouble if any(np.asarray(a).dtype == np.longdouble for a in args) else np.float64


@functools.cache
def _q(dtype: type) -> tuple[float, float, float]:
    """Carlson's (Q_F, Q_J, Q_C) factors for the rounding unit r of ``dtype``."""
    r = float(np.finfo(dtype).eps) / 2
    return (3 * r) ** (-1 / 6), (r / 4) ** (-1 / 6), (3 * r) ** (-1 / 8)


def _as_float(*args):
    dtype = _dtype(*args)
    return np.broadcast_arrays(*(np.asarray(a, dtype=dtype) for a in args))


def elliprf(x, y, z):
    """R_F(x, y, z) (DLMF 19.16.1) by duplication (Carlson 1995, algorithm 1)."""
    one = _one_point((x, y, z), zeros=1)
    if one is not None:
        try:
            return _shaped(_rf_one(*one[0]), *one[1:])
        except ZeroDivisionError:  # an underflow to 0 that the array code turns into inf: its answer
            pass
    x0, y0, z0 = _as_float(x, y, z)
    A0 = (x0 + y0 + z0) / 3
    Q = _q(x0.dtype.type)[0] * np.maximum(np.abs(A0 - x0), np.maximum(np.abs(A0 - y0), np.abs(A0 - z0)))
    # x, y, z and A stacked: one ufunc call per step for all four (the closed forms' setups call this on a
    # batch of one, where the calls, not the arithmetic, are the cost); each element's arithmetic is unchanged
    xyzA = np.stack([x0, y0, z0, A0])
    scale = 1.0  # 4⁻ⁿ, exact
    with np.errstate(all="ignore"):
        for _ in range(_MAX_STEPS):
            if every(scale * Q < xyzA[3]):  # (A > 0 in the domain: |A| is A; a NaN stops neither)
                break
            s = np.sqrt(xyzA[:3])
            sx, sy, sz = s
            lam = sx * sy + sx * sz + sy * sz
            xyzA = (xyzA + lam) / 4
            scale = scale / 4
        return _rf_series(A0, x0, y0, xyzA[3], scale, np.sqrt)


def _rf_series(A0, x0, y0, A, scale, sqrt):
    """R_F from the last duplication step: Carlson's fifth-order series about the mean A (arrays or scalars)."""
    X = (A0 - x0) * scale / A
    Y = (A0 - y0) * scale / A
    Z = -(X + Y)
    E2 = X * Y - Z * Z
    E3 = X * Y * Z
    return (1 - E2 / 10 + E3 / 14 + E2 * E2 / 24 - 3 * E2 * E3 / 44) / sqrt(A)


def elliprc(x, y):
    """R_C(x, y) (DLMF 19.2.17), y > 0, by duplication (Carlson 1995, algorithm 2)."""
    x, y = (a.copy() for a in _as_float(x, y))
    A0 = (x + 2 * y) / 3
    Q = _q(x.dtype.type)[2] * np.abs(A0 - x)
    y0 = y.copy()
    A = A0.copy()
    scale = np.ones_like(A)
    with np.errstate(all="ignore"):
        for _ in range(_MAX_STEPS):
            if every(scale * Q < np.abs(A)):
                break
            lam = 2 * np.sqrt(x) * np.sqrt(y) + y
            x, y, A = (x + lam) / 4, (y + lam) / 4, (A + lam) / 4
            scale = scale / 4
        s = (y0 - A0) * scale / A
        poly = 1 + s * s * (3 / 10 + s * (1 / 7 + s * (3 / 8 + s * (9 / 22 + s * (159 / 208 + s * 9 / 8)))))
        return poly / np.sqrt(A)


def _rc_one(e):
    """R_C(1, 1 + e) = atan(√e)/√e (e > 0), atanh(√-e)/√-e (-1 < e < 0) — the terms of R_J's sum.

    For |e| < 1e-3 the Maclaurin series Σ (-e)ᵏ/(2k + 1) (DLMF 19.2.19 expanded) to k = 6
    (1e-3⁷/15 < 1e-22) avoids the 0/0; the closed forms elsewhere are accurate to a few ulp.
    Only the branches some point needs are evaluated (this is R_J's inner loop).
    """
    e = np.asarray(e)
    if e.dtype != np.longdouble and e.dtype != np.float64:
        e = e.astype(float)
    small = np.abs(e) < 1e-3
    if every(small):
        return _rc_one_series(e)
    # (the series only where some point needs it: R_J's first steps have every |e| large)
    series = _rc_one_series(e) if some(small) else None
    with np.errstate(all="ignore"):
        r = np.sqrt(np.abs(e))
        positive = e > 0
        if every(positive | small):
            closed = np.arctan(r) / r
        elif every(~positive | small):
            closed = np.arctanh(r) / r
        else:
            closed = np.where(positive, np.arctan(r), np.arctanh(r)) / r
    return closed if series is None else np.where(small, series, closed)


def _rc_one_series(e):
    """R_C(1, 1 + e) = Σ (-e)ᵏ/(2k + 1) to k = 6, for |e| < 1e-3 (see :func:`_rc_one`)."""
    return 1 - e * (1 / 3 - e * (1 / 5 - e * (1 / 7 - e * (1 / 9 - e * (1 / 11 - e / 13)))))


def _rj_positive(x, y, z, p):
    """R_J for p > 0 (Carlson 1995, algorithm 3).

    x, y, z are not broadcast against p: several p (an array of characteristics) for one
    (x, y, z) share the duplication of x, y, z.
    """
    dtype = _dtype(x, y, z, p)
    x, y, z, p = (np.asarray(a, dtype=dtype) for a in (x, y, z, p))
    shape = np.broadcast(x, y, z, p).shape
    A0 = (x + y + z + 2 * p) / 5
    delta = (p - x) * (p - y) * (p - z)
    Q = _q(dtype)[1] * np.maximum(np.maximum(np.abs(A0 - x), np.abs(A0 - y)), np.maximum(np.abs(A0 - z), np.abs(A0 - p)))
    x0, y0, z0 = x, y, z
    A = A0
    scale = 1.0  # 4⁻ᵐ
    total = 0.0
    with np.errstate(all="ignore"):
        for _ in range(_MAX_STEPS):
            if every(scale * Q < A):  # (A > 0 for p > 0: |A| is A)
                break
            x, y, z, p, A, total = _rj_step(x, y, z, p, A, delta, scale, total, np.sqrt, _rc_one)
            scale *= 0.25
        result = _rj_series(A0, x0, y0, z0, A, scale, total, np.sqrt)
    return result if result.shape == shape else np.broadcast_to(result, shape).copy()


def _rj_step(x, y, z, p, A, delta, scale, total, sqrt, rc_one):
    """One duplication step of R_J (arrays or scalars): the arguments and the mean moved, the step's R_C term added."""
    sx, sy, sz, sp = sqrt(x), sqrt(y), sqrt(z), sqrt(p)
    lam = sx * sy + sx * sz + sy * sz
    d = (sp + sx) * (sp + sy) * (sp + sz)
    e = (delta * scale**3) / (d * d)
    total = total + scale * rc_one(e) / d
    return (x + lam) * 0.25, (y + lam) * 0.25, (z + lam) * 0.25, (p + lam) * 0.25, (A + lam) * 0.25, total


def _rj_series(A0, x0, y0, z0, A, scale, total, sqrt):
    """R_J from the last duplication step: Carlson's fifth-order series about the mean A plus the R_C terms'
    ``total`` (arrays or scalars)."""
    X = (A0 - x0) * scale / A
    Y = (A0 - y0) * scale / A
    Z = (A0 - z0) * scale / A
    P = -(X + Y + Z) / 2
    XYZ = X * Y * Z
    P2 = P * P
    E2 = X * Y + X * Z + Y * Z - 3 * P2
    E3 = XYZ + 2 * E2 * P + 4 * P2 * P
    E4 = (2 * XYZ + E2 * P + 3 * P2 * P) * P
    E5 = XYZ * P2
    series = (1 - 3 * E2 / 14 + E3 / 6 + 9 * E2 * E2 / 88 - 3 * E4 / 22 - 9 * E2 * E3 / 52 + 3 * E5 / 26)
    return scale * series / (A * sqrt(A)) + 6 * total


def elliprj(x, y, z, p):
    """R_J(x, y, z, p) (DLMF 19.16.2); for p < 0 the Cauchy principal value (DLMF 19.20.14)."""
    one = _one_point((x, y, z, p), zeros=1, positive_last=True)
    if one is not None:
        try:
            return _shaped(_rj_one(*one[0]), *one[1:])
        except ZeroDivisionError:  # an underflow to 0 that the array code turns into inf: its answer
            pass
    if not some(np.asarray(p) < 0):
        return _rj_positive(x, y, z, p)
    x, y, z, p = _as_float(x, y, z, p)
    neg = p < 0
    out = np.empty(p.shape, dtype=p.dtype)
    pos = ~neg
    if np.any(pos):
        out[pos] = _rj_positive(x[pos], y[pos], z[pos], p[pos])
    # DLMF 19.20.14 with x ≤ y ≤ z ordered (R_J is symmetric in x, y, z):
    # (y - p) R_J(x,y,z,p) = (q - y) R_J(x,y,z,q) - 3 R_F(x,y,z) + 3 √(xyz/(xz + pq)) R_C(xz + pq, pq),
    # q = y + (z - y)(y - x)/(y - p) > 0.
    xs, ys, zs = np.sort(np.stack([x[neg], y[neg], z[neg]]), axis=0)
    pn = p[neg]
    q = ys + (zs - ys) * (ys - xs) / (ys - pn)
    with np.errstate(all="ignore"):
        pv = ((q - ys) * _rj_positive(xs, ys, zs, q) - 3 * elliprf(xs, ys, zs)
              + 3 * np.sqrt(xs * ys * zs / (xs * zs + pn * q)) * elliprc(xs * zs + pn * q, pn * q)) / (ys - pn)
    out[neg] = pv
    return out


def elliprd(x, y, z):
    """R_D(x, y, z) = R_J(x, y, z, z) (DLMF 19.16.5)."""
    x, y, z = _as_float(x, y, z)
    return _rj_positive(x, y, z, z)


# --- one point: the same steps on scalars ------------------------------------------------------------------
# A closed form's setup evaluates these at single points, where NumPy's per-call cost (~3k instructions on an
# array of one, ~1k on a NumPy scalar, against ~60 for a Python float) is all of the time.  One point in the
# domain runs the very operations of the array code, in the same order, on Python floats (doubles) or NumPy
# longdouble scalars — the same IEEE arithmetic, so the same bits (tests/test_special_elliptic.py compares them
# bit for bit); anything else (arrays, points outside the domain, where the array code's NaN and inf are the
# answer) takes the array code.


def _one_point(args: tuple, *, zeros: int, positive_last: bool = False) -> tuple | None:
    """(values, longdouble, ndim) for arguments that are one point inside the domain — finite, ≥ 0, at most
    ``zeros`` of them 0, the last > 0 with ``positive_last`` — as Python floats or longdouble scalars; else None."""
    values, ndim, extended = [], 0, False
    for a in args:
        if type(a) is float:
            values.append(a)
            continue
        arr = np.asarray(a)
        if arr.size != 1 or arr.dtype.kind not in "fiu":
            return None
        ndim = max(ndim, arr.ndim)
        extended = extended or arr.dtype == np.longdouble
        values.append(arr.reshape(-1)[0])
    values = [np.longdouble(v) for v in values] if extended else [float(v) for v in values]
    if not all(0 <= v < math.inf for v in values) or sum(v == 0 for v in values) > zeros \
            or (positive_last and not values[-1] > 0):
        return None
    return values, extended, ndim


def _shaped(value, extended: bool, ndim: int):
    """``value`` as the array code returns it: a NumPy scalar for scalar arguments, else an array of one."""
    dtype = np.longdouble if extended else np.float64
    return dtype(value) if ndim == 0 else np.full((1,) * ndim, value, dtype=dtype)


def _sqrt_of(x):
    """√ for the kind of ``x``: math.sqrt on floats (correctly rounded, as np.sqrt), np.sqrt on longdouble."""
    return math.sqrt if type(x) is float else np.sqrt


def _rf_one(x0, y0, z0):
    """:func:`elliprf`'s steps on one point (see above)."""
    sqrt = _sqrt_of(x0)
    A0 = (x0 + y0 + z0) / 3
    Q = _q(np.longdouble if type(x0) is not float else np.float64)[0] * max(abs(A0 - x0), abs(A0 - y0), abs(A0 - z0))
    x, y, z, A = x0, y0, z0, A0
    scale = 1.0
    for _ in range(_MAX_STEPS):
        if scale * Q < A:
            break
        sx, sy, sz = sqrt(x), sqrt(y), sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        x, y, z, A = (x + lam) / 4, (y + lam) / 4, (z + lam) / 4, (A + lam) / 4
        scale = scale / 4
    return _rf_series(A0, x0, y0, A, scale, sqrt)


def _rc_one_scalar(e):
    """:func:`_rc_one` for one value (e > -1)."""
    if abs(e) < 1e-3:
        return _rc_one_series(e)
    r = _sqrt_of(e)(abs(e))
    if type(e) is float:  # NumPy's arctan, arctanh (as the array code): libm's may differ in the last bit
        return float(np.arctan(r) if e > 0 else np.arctanh(r)) / r
    return (np.arctan(r) if e > 0 else np.arctanh(r)) / r


def _rj_one(x, y, z, p):
    """:func:`_rj_positive`'s steps on one point, p > 0 (see above)."""
    sqrt = _sqrt_of(x)
    A0 = (x + y + z + 2 * p) / 5
    delta = (p - x) * (p - y) * (p - z)
    Q = _q(np.longdouble if type(x) is not float else np.float64)[1] * max(
        max(abs(A0 - x), abs(A0 - y)), max(abs(A0 - z), abs(A0 - p)))
    x0, y0, z0 = x, y, z
    A = A0
    scale = 1.0
    total = 0.0
    for _ in range(_MAX_STEPS):
        if scale * Q < A:
            break
        x, y, z, p, A, total = _rj_step(x, y, z, p, A, delta, scale, total, sqrt, _rc_one_scalar)
        scale *= 0.25
    return _rj_series(A0, x0, y0, z0, A, scale, total, sqrt)
