"""The period of a sampled motion, measured: successive crossings of a level by one coordinate.

A motion whose reduced state (the coordinates that are not cyclic, and the velocities) returns to
itself is periodic; its period is measured on the samples without knowing any formula: the state
component that varies most is followed through its mid-level (half-way between its extremes, where
it crosses with its largest slope, never at a turning point), each upward crossing is located by the
quintic through the six samples around it (an error of order h⁶), and the period is the mean interval
between crossings.  The estimate is measured: the largest difference between the quintic's and the
cubic's crossing time (a bound of the quintic's interpolation error), plus the spread of the measured intervals
about their mean.  The motion is called periodic only if every component of the state takes the
same value at each crossing, within its own interpolation error; otherwise (a quasi-periodic
motion, or one that never comes back) there is no period, and the reason says so.

>>> import numpy as np
>>> t = np.linspace(0.0, 10.0, 2001)
>>> p = measure_period(t, np.stack([np.cos(3 * t), -3 * np.sin(3 * t)], axis=1))
>>> round(p.period, 10), p.estimate < 1e-9
(2.0943951024, True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Period", "measure_period"]


@dataclass(frozen=True)
class Period:
    """``period`` (s) and its measured ``estimate``, or None and ``reason`` (why there is none)."""

    period: float | None
    estimate: float | None
    reason: str = ""
    crossings: int = 0


def _crossing(t: np.ndarray, x: np.ndarray, k: int, level: float, points: int) -> float:
    """The time where the interpolating polynomial through ``points`` samples around [k, k + 1] crosses ``level``."""
    lo = min(max(k - (points - 2) // 2, 0), len(t) - points)
    ts, xs = t[lo:lo + points], x[lo:lo + points] - level
    scale = ts[-1] - ts[0]
    coeffs = np.polyfit((ts - t[k]) / scale, xs, points - 1)
    roots = np.roots(coeffs)
    a, b = 0.0, (t[k + 1] - t[k]) / scale
    real = [r.real for r in roots if abs(r.imag) < 1e-12 and a - 1e-9 <= r.real <= b + 1e-9]
    if not real:  # rounding: the linear crossing
        return float(t[k] + (t[k + 1] - t[k]) * (-x[k] + level) / (x[k + 1] - x[k]))
    return float(t[k] + min(real, key=lambda r: abs(r - b / 2)) * scale)


def _windows(n: int, ks: np.ndarray, points: int) -> np.ndarray:
    """Indices (m, points) of the ``points`` samples around each interval [k, k + 1], inside 0 … n − 1."""
    lo = np.clip(ks - (points - 2) // 2, 0, n - points)
    return lo[:, None] + np.arange(points)


def _crossings(t: np.ndarray, x: np.ndarray, ks: np.ndarray, level: float, points: int) -> np.ndarray:
    """:func:`_crossing` at every interval of ``ks`` at once: the interpolating polynomials are solved for in
    one batched Vandermonde system and their roots found by Newton's method from the linear crossing;
    an interval where Newton does not land inside it falls back to :func:`_crossing` (all the roots)."""
    idx = _windows(len(t), ks, points)
    ts, xs = t[idx], x[idx] - level
    scale = ts[:, -1] - ts[:, 0]
    s = (ts - t[ks][:, None]) / scale[:, None]
    powers = np.arange(points)
    coeffs = np.linalg.solve(s[:, :, None] ** powers, xs[:, :, None])[:, :, 0]  # (m, points), lowest first
    b = (t[ks + 1] - t[ks]) / scale
    root = b * (level - x[ks]) / (x[ks + 1] - x[ks])
    for _ in range(8):
        value = np.zeros_like(root)
        slope = np.zeros_like(root)
        for c in coeffs.T[::-1]:  # Horner, for the value and its derivative
            slope = slope * root + value
            value = value * root + c
        with np.errstate(divide="ignore", invalid="ignore"):
            root = root - value / slope
    out = t[ks] + root * scale
    bad = ~(np.isfinite(root) & (root >= -1e-9) & (root <= b + 1e-9))
    for i in np.nonzero(bad)[0]:
        out[i] = _crossing(t, x, int(ks[i]), level, points)
    return out


def _states_at(t: np.ndarray, y: np.ndarray, when: np.ndarray, points: int) -> np.ndarray:
    """The state (m, k) at each of the times ``when``, by the polynomial through the ``points`` samples
    around it (Lagrange's form, all times at once)."""
    ks = np.clip(np.searchsorted(t, when) - 1, 0, len(t) - 2)
    idx = _windows(len(t), ks, points)
    ts = t[idx]                                               # (m, p)
    numer = np.repeat((when[:, None] - ts)[:, None, :], points, axis=1)  # (m, i, j): when − t_j
    denom = ts[:, :, None] - ts[:, None, :]                   # t_i − t_j
    eye = np.eye(points, dtype=bool)
    numer[:, eye] = 1.0
    denom[:, eye] = 1.0
    weights = np.prod(numer / denom, axis=2)                  # (m, p)
    return np.einsum("mp,mpk->mk", weights, y[idx])


def measure_period(t: np.ndarray, state: np.ndarray, *, component_errors: np.ndarray | None = None) -> Period:
    """The period of the sampled ``state`` (N, k) at increasing times ``t`` (N,), measured (module docstring).

    ``component_errors`` (k,): the errors of the samples themselves (an integrator's estimate), added to
    the tolerance of the return test.  At least two crossings (one whole period) must lie inside the run.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(state, dtype=float).reshape(len(t), -1)
    if len(t) < 8 or not np.all(np.isfinite(y)):
        return Period(None, None, "too few samples, or a state not defined at every sample")
    ranges = np.ptp(y, axis=0)
    c = int(np.argmax(ranges))
    if ranges[c] == 0:
        return Period(None, None, "the state does not change (a steady motion): no period to measure")
    x = y[:, c]
    level = 0.5 * (np.max(x) + np.min(x))
    up = np.nonzero((x[:-1] < level) & (x[1:] >= level))[0]
    if len(up) < 2:
        return Period(None, None, f"fewer than one whole period inside the run ({len(up)} upward crossing(s) of "
                                  "the mid-level of the state's most varying component): run longer")
    up = up[(up >= 2) & (up <= len(t) - 4)]  # room for six samples around each crossing
    if len(up) < 2:
        return Period(None, None, "fewer than one whole period inside the run, away from its ends: run longer")
    cubic = _crossings(t, x, up, level, 6)  # the quintic through six samples
    quadratic = _crossings(t, x, up, level, 4)  # the cubic, to measure the first's error
    interpolation = float(np.max(np.abs(cubic - quadratic)))
    intervals = np.diff(cubic)
    period = float((cubic[-1] - cubic[0]) / (len(cubic) - 1))
    spread = float(np.max(np.abs(intervals - period)))
    # the whole state must come back at each crossing: else the motion is not periodic
    states = _states_at(t, y, cubic, 6)
    state_error = np.max(np.abs(states - _states_at(t, y, cubic, 4)), axis=0)
    h = float(np.max(np.diff(t)))
    slope = np.max(np.abs(np.diff(y, axis=0)), axis=0) / h  # a bound of each component's rate
    # the return is judged to the samples' own precision: the interpolation, a millionth of each component's
    # swing, and 1e-9 of its size (a nearly constant component, ω3 of a symmetric top, varies by its rounding)
    allowed = slope * (interpolation + 2 * spread) + 2 * state_error + 1e-6 * ranges + 1e-9 * np.max(np.abs(y), axis=0) + (
        0.0 if component_errors is None else 2 * np.asarray(component_errors, dtype=float))
    mismatch = np.max(np.abs(states - states[0]), axis=0)
    if np.any(mismatch > allowed):
        worst = int(np.argmax(mismatch / np.maximum(allowed, 1e-300)))
        return Period(None, None, f"not periodic within the run: component {worst} of the state differs by "
                                  f"{mismatch[worst]:.3g} between returns of component {c} (quasi-periodic, "
                                  "or not bounded)", len(up))
    # an error δx of the samples themselves moves a crossing by δx / slope, at each end of the run
    sample_error = 0.0
    if component_errors is not None:
        crossing_slope = float(np.min(np.abs(np.diff(x)[up]) / np.diff(t)[up]))
        sample_error = 2 * float(np.asarray(component_errors, dtype=float)[c]) / crossing_slope / (len(cubic) - 1)
    return Period(period, float(interpolation + spread + sample_error + 4 * np.spacing(period)), "", len(up))
