"""Numeric rotations and angular velocities in Euler angles — no SymPy at import or on a warm cache.

These evaluate R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ) (3.54) and the angular velocity (3.58)
as *derived* in :mod:`mechderive.kinematics.euler`; the derived expressions are compiled
once (lambdify with common-subexpression elimination) and the generated code is kept
in the disk cache (:mod:`mechderive.core.codecache`), so a later process evaluates
them without importing SymPy.  Conventions as in :mod:`mechderive.kinematics.euler`.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import numpy as np

from ..core.compile import compile_cached
from ..core.validate import as_finite_array, check_rotation_matrix

__all__ = ["rotation_matrix", "angular_velocity_body", "angular_velocity_space", "euler_rates",
           "euler_angles_from_matrix", "continuous_euler_angles"]

_RATES = ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")


def _build(quantity: str, names: tuple[str, ...]) -> Callable[[], tuple]:
    def build():
        from ..core.symbols import state_symbol
        from . import euler_symbolic

        expr = getattr(euler_symbolic.model(), quantity)
        return [state_symbol(n) for n in names], expr
    return build


@functools.cache
def _function(quantity: str, names: tuple[str, ...]) -> Callable[..., np.ndarray]:
    return compile_cached(f"kinematics.{quantity}", _build(quantity, names))


_ZERO, _ONE = 0, 1  # exact entries of the elementary rotations: skipped or not multiplied in a product


def _axis_rotation(axis: int, angle: np.ndarray) -> list[list[Any]]:
    """The passive rotation R_a(α) about axis 1 or 3 ((3.51), (3.52)) as nested rows of entries (arrays
    or the exact 0 and 1): the numeric form of exp(α J_a) derived in
    :func:`mechderive.kinematics.euler_symbolic.axis_rotation`."""
    c, s = np.cos(angle), np.sin(angle)
    m: list[list[Any]] = [[_ONE if i == j else _ZERO for j in range(3)] for i in range(3)]
    i, j = (1, 2) if axis == 1 else (0, 1)
    m[i][i], m[j][j], m[i][j], m[j][i] = c, c, s, -s
    return m


def _product(a: list[list[Any]], b: list[list[Any]]) -> list[list[Any]]:
    """The matrix product of nested rows, term by term on arrays, skipping exact zeros and ones."""
    out = []
    for i in range(3):
        row = []
        for j in range(3):
            terms = [x if y is _ONE else y if x is _ONE else x * y
                     for x, y in ((a[i][k], b[k][j]) for k in range(3)) if x is not _ZERO and y is not _ZERO]
            row.append(_ZERO if not terms else functools.reduce(np.add, terms))
        out.append(row)
    return out


def rotation_matrix(phi: Any, theta: Any, psi: Any) -> np.ndarray:
    """Numeric R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ) of (3.54), vectorised: arrays broadcast, result shape (..., 3, 3).

    Angles in radians.  Pure NumPy (no SymPy, no compiled code): the product of the three
    elementary rotations, agreeing with the derived R of :mod:`mechderive.kinematics.euler_symbolic`
    to an ulp or two (``tests/test_kinematics_numeric.py``).

    >>> np.allclose(rotation_matrix(0.3, 0.0, 0.4), rotation_matrix(0.7, 0.0, 0.0))
    True
    """
    phi, theta, psi = np.broadcast_arrays(as_finite_array(phi, "phi"), as_finite_array(theta, "theta"),
                                          as_finite_array(psi, "psi"))
    rows = _product(_product(_axis_rotation(3, psi), _axis_rotation(1, theta)), _axis_rotation(3, phi))
    out = np.empty(phi.shape + (3, 3))
    for i in range(3):
        for j in range(3):
            out[..., i, j] = rows[i][j]
    return out


def _rates(quantity: str, values: tuple) -> np.ndarray:
    vals = [as_finite_array(v, n) for v, n in zip(values, _RATES)]
    out = _function(quantity, _RATES)(*vals)
    return np.asarray(out).reshape(np.broadcast_shapes(*(v.shape for v in vals)) + (3,))


def angular_velocity_body(phi: Any, theta: Any, psi: Any, phi_dot: Any, theta_dot: Any, psi_dot: Any) -> np.ndarray:
    """Body components (ω1, ω2, ω3) of the angular velocity (3.58), vectorised; shape (..., 3).

    Angles in radians, rates in rad/s.
    """
    return _rates("state_angular_velocity_body", (phi, theta, psi, phi_dot, theta_dot, psi_dot))


def angular_velocity_space(phi: Any, theta: Any, psi: Any, phi_dot: Any, theta_dot: Any, psi_dot: Any) -> np.ndarray:
    """Space components (ω̃1, ω̃2, ω̃3) = Rᵀ ω of the angular velocity, vectorised; shape (..., 3)."""
    return _rates("state_angular_velocity_space", (phi, theta, psi, phi_dot, theta_dot, psi_dot))


def euler_rates(theta: Any, psi: Any, omega1: Any, omega2: Any, omega3: Any) -> np.ndarray:
    """(φ̇, θ̇, ψ̇) from the body angular velocity, (3.58) solved; shape (..., 3).

    Singular where sin θ = 0 (only φ̇ + ψ̇ is defined there): the result is then inf or NaN,
    which callers must treat as "not defined", not as a value.
    """
    names = ("theta", "psi", "omega1", "omega2", "omega3")
    vals = [as_finite_array(v, n) for v, n in zip((theta, psi, omega1, omega2, omega3), names)]
    f = _function("state_euler_rates", names)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = f(*vals)
    return np.asarray(out).reshape(np.broadcast_shapes(*(v.shape for v in vals)) + (3,))


def euler_angles_from_matrix(R: Any) -> np.ndarray:
    """Euler angles (φ, θ, ψ) with R(φ, θ, ψ) = R, shape (..., 3, 3) → (..., 3).

    θ = arccos R33 ∈ [0, π] is computed as atan2(√(R13² + R23²), R33) so it keeps
    full accuracy near 0 and π; φ = atan2(R31, -R32) and ψ = atan2(R13, R23), each
    in (-π, π].  At θ = 0 or π exactly (gimbal lock) only φ ± ψ is defined: then
    ψ = 0 is chosen and φ carries the whole angle.  Raises
    :class:`~mechderive.errors.NotARotationError` for a matrix that is not a rotation.
    """
    R = check_rotation_matrix(R)
    s = np.hypot(R[..., 0, 2], R[..., 1, 2])
    theta = np.arctan2(s, R[..., 2, 2])
    # sin θ below ~1e-15 carries no direction information: treat as gimbal lock.
    lock = s < 1e-15
    phi = np.where(lock, np.arctan2(R[..., 0, 1], R[..., 0, 0]), np.arctan2(R[..., 2, 0], -R[..., 2, 1]))
    psi = np.where(lock, 0.0, np.arctan2(R[..., 0, 2], R[..., 1, 2]))
    return np.stack([phi, theta, psi], axis=-1)


def continuous_euler_angles(angles: np.ndarray) -> np.ndarray:
    """Unwrap φ and ψ along a time series (N, 3) of (φ, θ, ψ), bridging gimbal-lock samples.

    Where sin θ = 0 only φ + ψ (θ = 0) or φ - ψ (θ = π) is defined and
    :func:`euler_angles_from_matrix` puts it all in φ; such samples
    take ψ from the nearest sample before them (or, at the start, after them), keeping
    φ ± ψ.  A run that stays at θ = 0 throughout keeps ψ = 0 and φ = φ + ψ.  The time series
    must be sampled finely enough that φ and ψ change by less than π between samples.

    >>> a = np.array([[3.0, 0.5, 0.2], [-3.0, 0.5, 0.3], [-2.9, 0.0, 0.0]])   # φ wraps, then θ = 0
    >>> np.round(continuous_euler_angles(a), 4).tolist()
    [[3.0, 0.5, 0.2], [3.2832, 0.5, 0.3], [3.0832, 0.0, 0.3]]
    """
    ang = np.array(angles, dtype=float)
    if ang.ndim != 2 or len(ang) < 2:
        return ang
    lock = np.abs(np.sin(ang[:, 1])) < 1e-12
    if lock.any() and not lock.all():
        idx = np.where(~lock, np.arange(len(ang)), -1)
        prev = np.maximum.accumulate(idx)
        src = np.where(prev >= 0, prev, int(np.argmax(~lock)))
        sign = np.where(np.cos(ang[:, 1]) > 0, 1.0, -1.0)
        total = ang[:, 0] + sign * ang[:, 2]
        psi = np.where(lock, ang[src, 2], ang[:, 2])
        ang[:, 0] = np.where(lock, total - sign * psi, ang[:, 0])
        ang[:, 2] = psi
    ang[:, 0] = np.unwrap(ang[:, 0])
    ang[:, 2] = np.unwrap(ang[:, 2])
    return ang
