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

import numpy as np

from ..core.validate import every, some

__all__ = ["elliprc", "elliprd", "elliprf", "elliprj"]

_MAX_STEPS = 64  # each step quarters Q / |A|: 64 steps reach 4⁻⁶⁴ ≈ 3e-39


def _dtype(*args) -> type:
    """longdouble if any argument is, else float64."""
    return np.longdouble if any(np.asarray(a).dtype == np.longdouble for a in args) else np.float64


def _q(dtype: type) -> tuple[float, float, float]:
    """Carlson's (Q_F, Q_J, Q_C) factors for the rounding unit r of ``dtype``."""
    r = float(np.finfo(dtype).eps) / 2
    return (3 * r) ** (-1 / 6), (r / 4) ** (-1 / 6), (3 * r) ** (-1 / 8)


def _as_float(*args):
    dtype = _dtype(*args)
    return np.broadcast_arrays(*(np.asarray(a, dtype=dtype) for a in args))


def elliprf(x, y, z):
    """R_F(x, y, z) (DLMF 19.16.1) by duplication (Carlson 1995, algorithm 1)."""
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
        A = xyzA[3]
        X = (A0 - x0) * scale / A
        Y = (A0 - y0) * scale / A
        Z = -(X + Y)
        E2 = X * Y - Z * Z
        E3 = X * Y * Z
        return (1 - E2 / 10 + E3 / 14 + E2 * E2 / 24 - 3 * E2 * E3 / 44) / np.sqrt(A)


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
            sx, sy, sz, sp = np.sqrt(x), np.sqrt(y), np.sqrt(z), np.sqrt(p)
            lam = sx * sy + sx * sz + sy * sz
            d = (sp + sx) * (sp + sy) * (sp + sz)
            e = (delta * scale**3) / (d * d)
            total = total + scale * _rc_one(e) / d
            x, y, z, p, A = (x + lam) * 0.25, (y + lam) * 0.25, (z + lam) * 0.25, (p + lam) * 0.25, (A + lam) * 0.25
            scale *= 0.25
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
        result = scale * series / (A * np.sqrt(A)) + 6 * total
    return result if result.shape == shape else np.broadcast_to(result, shape).copy()


def elliprj(x, y, z, p):
    """R_J(x, y, z, p) (DLMF 19.16.2); for p < 0 the Cauchy principal value (DLMF 19.20.14)."""
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
