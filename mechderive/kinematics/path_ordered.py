"""Path-ordered exponentials: the rotation R(t) from the angular velocity ω(t), section 3.1.2.

Given the body components ω_c(t) of the angular velocity, the rotation solves (3.11)

    Ṙ = ω R,   ω_ab = ε_abc ω_c,   R(t0) = R0,

whose solution is the path-ordered exponential R(t) = P exp(∫ω dt') R0 (3.15), with
later times on the LEFT.  :func:`path_ordered_exponential` computes it with Magnus
steps (:mod:`mechderive.kinematics.magnus`) — fixed-step, or error-controlled by step
doubling — so that every R it returns is a rotation to rounding, with no projection.

``ordering="right"`` solves instead Ṙ = R Ω, Ω = R⁻¹Ṙ the convective angular velocity
of (3.10)/(3.86), whose solution R = P̃ exp(∫Ω dt) puts later times on the RIGHT (3.98).

:func:`naive_exponential` is the scalar guess (3.12), exp(∫ω dt'), kept to show
that it is right for a fixed axis and wrong otherwise.

Conventions: R is the chapter's passive rotation (rows = body axes in space
components, e_a = R_ab ẽ_b); ω is given by its BODY components; times in s,
angular velocities in rad/s.  ω may be a callable (times (N,) → (N, 3), or a scalar
t → (3,)) or a pair ``(times, values)`` of samples, interpolated by a cubic spline
(then the accuracy is limited by the O(Δt⁴) interpolation, not by the integrator).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..core.validate import as_finite_array, check_positive, check_rotation_matrix
from ..errors import InvalidInputError, ShapeError
from .magnus import Ordering, _evaluate, _nodes_times, check_order, check_ordering, magnus_exponent_from_nodes
from .so3 import expm_so3

__all__ = ["PathOrderedResult", "path_ordered_exponential", "naive_exponential", "sampled_angular_velocity"]

#: Below this the error control asks for accuracy that double rounding cannot deliver.
_SMALLEST_RTOL = 1e-13


@dataclass(frozen=True)
class PathOrderedResult:
    """The rotations R(t) of a path-ordered exponential.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Output times (s): the step grid, or ``t_eval`` when given.
    R : ndarray, shape (N, 3, 3)
        R(t) at those times (passive, e_a = R_ab ẽ_b).
    error_estimate : float or None
        For the adaptive integrator: the estimated global error of R at the last time,
        as a rotation angle (rad) — the sum of the step-doubling local estimates, a
        first-order bound because steps are isometries.  ``None`` for fixed steps.
    steps : int
        Accepted Magnus steps.
    order, ordering
        The method used.
    """

    t: np.ndarray
    R: np.ndarray
    error_estimate: float | None
    steps: int
    order: int
    ordering: str

    def __post_init__(self) -> None:
        if self.R.shape != self.t.shape + (3, 3):
            raise ShapeError(f"expected R of shape {self.t.shape + (3, 3)}, got {self.R.shape}")


# --------------------------------------------------------------------------- ω as a function

def sampled_angular_velocity(times: Any, values: Any) -> Callable[[np.ndarray], np.ndarray]:
    """ω(t) from samples: a not-a-knot cubic spline through (times (N,), values (N, 3)).

    Needs N ≥ 4 strictly increasing times; the spline is never extrapolated.

    >>> w = sampled_angular_velocity([0, 1, 2, 3], [[0, 0, 1]] * 4)
    >>> w(np.array([0.5, 2.5]))
    array([[0., 0., 1.],
           [0., 0., 1.]])
    """
    from scipy.interpolate import CubicSpline

    ts = as_finite_array(times, "times", shape=(None,))
    vs = as_finite_array(values, "values", shape=(None, 3))
    if len(ts) != len(vs):
        raise ShapeError(f"expected `values` of shape ({len(ts)}, 3) to match `times`, got {vs.shape}")
    if len(ts) < 4:
        raise InvalidInputError(f"expected at least 4 samples for a cubic spline, got {len(ts)}")
    if not np.all(np.diff(ts) > 0):
        raise InvalidInputError("expected strictly increasing `times`, got a non-increasing step")
    spline = CubicSpline(ts, vs, axis=0, extrapolate=False)

    def omega(s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        if np.any((s < ts[0]) | (s > ts[-1])):
            raise InvalidInputError(f"expected times within the samples [{ts[0]}, {ts[-1]}], "
                                    f"got {s[(s < ts[0]) | (s > ts[-1])].ravel()[0]}")
        return spline(s)

    omega.span = (float(ts[0]), float(ts[-1]))  # type: ignore[attr-defined]
    return omega


def _vectorised(omega: Any, probe: tuple[float, float]) -> Callable[[np.ndarray], np.ndarray]:
    """Wrap ω as f(times (N,)) -> finite (N, 3), probing once whether it accepts arrays."""
    if isinstance(omega, tuple) and len(omega) == 2:
        omega = sampled_angular_velocity(*omega)
        lo, hi = omega.span
        if probe[0] < lo or probe[1] > hi:
            raise InvalidInputError(f"expected the time span within the samples [{lo}, {hi}], got {probe}")
    if not callable(omega):
        raise InvalidInputError(f"expected `omega` to be a callable ω(t) or a (times, values) pair, "
                                f"got {type(omega).__name__}")
    trial = np.array(probe, dtype=float)
    try:
        out = np.asarray(omega(trial), dtype=float)
    except Exception:  # noqa: BLE001 - a scalar-only callable; its own errors resurface below
        out = None
    if out is not None and out.shape == (2, 3):
        def f(s: np.ndarray) -> np.ndarray:
            s = np.asarray(s, dtype=float)
            w = np.asarray(omega(s), dtype=float)
            if w.shape != s.shape + (3,):
                raise ShapeError(f"expected omega(t) of shape {s.shape + (3,)} for times of shape {s.shape}, "
                                 f"got {w.shape}")
            return as_finite_array(w, "omega(t)")
        return f
    if out is not None and out.shape == (3, 2):
        raise ShapeError("expected omega(t) of shape (N, 3) for times of shape (N,), got (3, N) "
                         "(components first; stack them on the last axis)")

    def f_scalar(s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        rows = [as_finite_array(omega(float(x)), "omega(t)", shape=(3,)) for x in s.ravel()]
        return np.array(rows).reshape(s.shape + (3,))
    return f_scalar


# --------------------------------------------------------------------------- argument checks

def _check_span(t_span: Any) -> tuple[float, float]:
    span = as_finite_array(t_span, "t_span", shape=(2,))
    t0, t1 = float(span[0]), float(span[1])
    if not t1 > t0:
        raise InvalidInputError(f"expected t_end > t0 in `t_span`, got t0={t0}, t_end={t1}")
    return t0, t1


def _check_steps(steps: Any) -> int:
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
        raise InvalidInputError(f"expected `steps` to be an integer >= 1, got {steps!r}")
    return int(steps)


def _check_t_eval(t_eval: Any, t0: float, t1: float) -> np.ndarray | None:
    if t_eval is None:
        return None
    te = as_finite_array(t_eval, "t_eval", shape=(None,))
    if te.size and (te.min() < t0 or te.max() > t1):
        raise InvalidInputError(f"expected `t_eval` within t_span [{t0}, {t1}], got values in [{te.min()}, {te.max()}]")
    if np.any(np.diff(te) <= 0):
        raise InvalidInputError("expected strictly increasing `t_eval`, got a non-increasing step")
    return te


def _apply(step: np.ndarray, R: np.ndarray, ordering: str) -> np.ndarray:
    return step @ R if ordering == "left" else R @ step


# --------------------------------------------------------------------------- integrators

def path_ordered_exponential(omega: Any, t_span: Any, *, steps: int | None = None, rtol: float | None = None,
                             order: int = 4, ordering: Ordering = "left", R0: Any = None, t_eval: Any = None,
                             max_steps: int = 1_000_000) -> PathOrderedResult:
    """R(t) = P exp(∫_{t0}^t ω dt') R0, the solution of Ṙ = ωR (3.11), (3.15), by Magnus steps.

    Parameters
    ----------
    omega
        Body angular velocity (rad/s): callable ω(t) (times (N,) → (N, 3), or scalar → (3,)),
        or samples ``(times, values)`` (cubic spline).
    t_span
        (t0, t_end) in s, t_end > t0.
    steps, rtol
        Exactly one: ``steps`` uniform Magnus steps, or adaptive steps (step doubling) aiming at a
        global error ≤ ``rtol`` in R, measured as a rotation angle (R has unit norm, so relative and
        absolute error coincide); rtol ≥ 1e-13.
    order
        4 (2 Gauss nodes per step) or 6 (3 nodes).
    ordering
        Keyword-only: "left" solves Ṙ = ωR (3.11), later times on the left (3.15); "right" solves
        Ṙ = RΩ with Ω = R⁻¹Ṙ the convective angular velocity, later times on the right (3.98).
    R0
        R(t0), a rotation matrix (default the identity).
    t_eval
        Strictly increasing output times in [t0, t_end]; default every step.  Fixed steps reach an
        off-grid time by a partial Magnus step from the grid point before it (same order).
    max_steps
        The adaptive integrator gives up (raises) beyond this many steps.

    Returns
    -------
    PathOrderedResult
        ``t`` (N,), ``R`` (N, 3, 3), ``error_estimate``, ``steps``.

    >>> res = path_ordered_exponential(lambda s: np.tile([0, 0, 1.0], (len(s), 1)), (0, 1), steps=4)
    >>> from mechderive.kinematics.euler import rotation_matrix
    >>> np.allclose(res.R[-1], rotation_matrix(1.0, 0, 0))   # fixed axis: R3(∫ω dt)
    True
    """
    order, ordering = check_order(order), check_ordering(ordering)
    t0, t1 = _check_span(t_span)
    if (steps is None) == (rtol is None):
        raise InvalidInputError("expected exactly one of `steps` (fixed steps) or `rtol` (adaptive), "
                                f"got steps={steps!r}, rtol={rtol!r}")
    if steps is not None:
        steps = _check_steps(steps)
    else:
        rtol = check_positive(rtol, "rtol")
        if rtol < _SMALLEST_RTOL:
            raise InvalidInputError(f"expected `rtol` >= {_SMALLEST_RTOL:g} (double rounding), got {rtol:g}")
    R0 = np.eye(3) if R0 is None else check_rotation_matrix(R0, "R0")
    if R0.shape != (3, 3):
        raise ShapeError(f"expected `R0` to have shape (3, 3), got {R0.shape}")
    te = _check_t_eval(t_eval, t0, t1)
    w = _vectorised(omega, (t0, t1))
    if steps is not None:
        return _fixed(w, t0, t1, steps, order, ordering, R0, te)
    return _adaptive(w, t0, t1, rtol, order, ordering, R0, te, max_steps)


def _steps_exp(w: Callable, t: np.ndarray, h: np.ndarray, order: int, ordering: str) -> np.ndarray:
    """exp(Ω) of the steps [t, t + h], vectorised: shape (..., 3, 3)."""
    nodes = _evaluate(w, _nodes_times(t, h, order))
    return expm_so3(magnus_exponent_from_nodes(nodes, h, order=order, ordering=ordering))


def _accumulate(E: np.ndarray, R0: np.ndarray, ordering: str) -> np.ndarray:
    """R_{n+1} = E_n R_n (left) or R_n E_n (right): the one sequential part."""
    out = np.empty((len(E) + 1, 3, 3))
    out[0] = R = R0
    for n, step in enumerate(E):
        R = step @ R if ordering == "left" else R @ step
        out[n + 1] = R
    return out


def _fixed(w: Callable, t0: float, t1: float, n: int, order: int, ordering: str, R0: np.ndarray,
           te: np.ndarray | None) -> PathOrderedResult:
    h = (t1 - t0) / n
    grid = t0 + h * np.arange(n + 1)
    grid[-1] = t1
    E = _steps_exp(w, grid[:-1], np.diff(grid), order, ordering)
    Rs = _accumulate(E, R0, ordering)
    if te is None:
        return PathOrderedResult(grid, Rs, None, n, order, ordering)
    k = np.clip(np.searchsorted(grid, te, side="right") - 1, 0, n - 1)
    partial = _steps_exp(w, grid[k], te - grid[k], order, ordering)
    return PathOrderedResult(te, _apply(partial, Rs[k], ordering), None, n, order, ordering)


def _adaptive(w: Callable, t0: float, t1: float, rtol: float, order: int, ordering: str, R0: np.ndarray,
              te: np.ndarray | None, max_steps: int) -> PathOrderedResult:
    """Step doubling: one step h against two of h/2; the local error of the pair ≈ diff / (2^p − 1).

    The pair (the more accurate result) is kept, so R stays a product of exact rotations.
    Each step must satisfy err ≤ rtol h / T (error per unit time), so the sum — the global
    estimate, steps being isometries — stays ≤ rtol.
    """
    span = t1 - t0
    stops = np.unique(np.append(te if te is not None else [], t1))
    w0 = np.linalg.norm(w(np.array([t0]))[0])
    h = min(span, rtol ** (1 / order) / max(w0, 1 / span))
    t, R, total, n = t0, R0.copy(), 0.0, 0
    ts, Rs, at_stops = [t0], [R0.copy()], []
    for stop in stops:
        while stop - t > 1e-14 * max(1.0, abs(stop)):
            h_try = min(h, stop - t)
            starts = np.array([t, t, t + h_try / 2])
            lengths = np.array([h_try, h_try / 2, h_try / 2])
            big, half1, half2 = _steps_exp(w, starts, lengths, order, ordering)
            fine = half2 @ half1 if ordering == "left" else half1 @ half2
            # ‖A − B‖_F / √2 = 2 sin(θ/2) ≈ θ, the angle of the rotation AᵀB.
            err = np.linalg.norm(fine - big) / np.sqrt(2) / (2**order - 1)
            allowed = rtol * h_try / span
            accepted = err <= allowed
            if accepted:
                R = _apply(fine, R, ordering)
                t = stop if h_try == stop - t else t + h_try
                total += err
                n += 1
                ts.append(t)
                Rs.append(R)
                if n > max_steps:
                    raise InvalidInputError(f"expected at most max_steps={max_steps} steps for rtol={rtol:g}, "
                                            f"got more (t = {t:g} of {t1:g})")
            factor = 4.0 if err == 0 else min(4.0, max(0.2, 0.9 * (allowed / err) ** (1 / order)))
            # A step shortened only to land on a stop says little about the next one: keep h then.
            if not (accepted and h_try < h):
                h = h_try * factor
        at_stops.append(R)  # steps land on every stop exactly (or within 1e-14 of it)
    if te is not None:
        return PathOrderedResult(te, np.array(at_stops[:len(te)]), float(total), n, order, ordering)
    return PathOrderedResult(np.array(ts), np.array(Rs), float(total), n, order, ordering)


def naive_exponential(omega: Any, t: Any, *, t0: float = 0.0) -> np.ndarray:
    """The scalar guess (3.12): exp(∫_{t0}^t ω dt') — exact only if ω(t) keeps a fixed axis.

    ∫ω is computed component-wise by adaptive quadrature (scipy ``quad_vec``, 1e-13);
    the exponential by Rodrigues.  ``t`` scalar or array; result shape t.shape + (3, 3).
    For ω with a changing axis this is NOT the solution of (3.11) — see
    :func:`path_ordered_exponential`.

    >>> w = lambda s: np.array([0.0, 0.0, 2.0 * s])          # fixed axis, ∫ω = (0, 0, t²)
    >>> from mechderive.kinematics.euler import rotation_matrix
    >>> np.allclose(naive_exponential(w, 1.5), rotation_matrix(1.5**2, 0, 0))
    True
    """
    from scipy.integrate import quad_vec

    ts = as_finite_array(t, "t")
    t0 = float(as_finite_array(t0, "t0", shape=()))
    lo, hi = (min(t0, ts.min()), max(t0, ts.max())) if ts.size else (t0, t0)
    w = _vectorised(omega, (lo, hi))

    def integrand(s: float) -> np.ndarray:
        return w(np.array([s]))[0]

    M = np.array([quad_vec(integrand, t0, float(x), epsabs=1e-13, epsrel=1e-13)[0] for x in ts.ravel()])
    return expm_so3(M.reshape(ts.shape + (3,)))
