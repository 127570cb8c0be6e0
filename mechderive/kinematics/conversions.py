"""Conversions between the chapter's R and other conventions: SciPy's ``Rotation`` and quaternions.

The chapter's R is *passive*: e_a = R_ab ẽ_b, components r̃ = Rᵀ r.  SciPy's
:class:`scipy.spatial.transform.Rotation` and unit quaternions describe *active*
rotations.  The active rotation that carries the space axes ẽ_a onto the body
axes e_a (and body components onto space components, r̃ = A r) is

    A = Rᵀ.

Euler sequences: R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ) gives
A = R3(φ)ᵀ R1(θ)ᵀ R3(ψ)ᵀ = Rz(φ) Rx(θ) Rz(ψ) with Rz, Rx SciPy's active
elementary rotations, which is SciPy's **intrinsic** "ZXZ" sequence with angles
in the order (φ, θ, ψ) — equivalently the extrinsic "zxz" sequence with angles
(ψ, θ, φ)::

    Rotation.from_euler("ZXZ", [phi, theta, psi]).as_matrix() == R(phi, theta, psi).T

Quaternions here are the unit quaternions of A, **scalar first**: q = (q0, q1, q2, q3)
= (cos(α/2), n sin(α/2)) for the active rotation A by α about the unit axis n.
SciPy's default is scalar *last*; pass ``scalar_first=True`` to SciPy, or reorder.
q and -q are the same rotation; :func:`matrix_to_quaternion` returns q0 ≥ 0.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.validate import as_finite_array, check_rotation_matrix
from ..errors import InvalidInputError

__all__ = [
    "to_scipy_rotation",
    "from_scipy_rotation",
    "matrix_to_quaternion",
    "quaternion_to_matrix",
    "euler_to_quaternion",
]


def to_scipy_rotation(R: Any):
    """The SciPy ``Rotation`` of the active rotation A = Rᵀ (see the module docstring)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.swapaxes(check_rotation_matrix(R), -1, -2))


def from_scipy_rotation(rotation: Any) -> np.ndarray:
    """The chapter's R = Aᵀ from a SciPy ``Rotation`` A; shape (3, 3) or (N, 3, 3)."""
    return np.swapaxes(rotation.as_matrix(), -1, -2)


def quaternion_to_matrix(q: Any) -> np.ndarray:
    """The chapter's R from the unit quaternion q = (q0, q1, q2, q3) of A = Rᵀ, scalar first.

    Raises if |q| differs from 1 by more than 1e-9 (a non-unit quaternion is refused, not normalised).
    """
    q = as_finite_array(q, "q")
    if q.shape[-1:] != (4,):
        from ..errors import ShapeError

        raise ShapeError(f"expected `q` to have shape (..., 4), got {q.shape}")
    norm = np.linalg.norm(q, axis=-1)
    if np.any(np.abs(norm - 1) > 1e-9):
        raise InvalidInputError(f"expected a unit quaternion (|q| = 1 within 1e-9), got |q| = {float(np.max(np.abs(norm))):.12g}")
    w, x, y, z = np.moveaxis(q, -1, 0)
    A = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )
    return np.swapaxes(A, -1, -2)


def matrix_to_quaternion(R: Any) -> np.ndarray:
    """The unit quaternion (q0 ≥ 0, scalar first) of A = Rᵀ, shape (..., 3, 3) → (..., 4).

    Uses Shepperd's method (the largest of the four diagonal combinations as pivot),
    accurate at every rotation angle including π.
    """
    A = np.swapaxes(check_rotation_matrix(R), -1, -2)
    a00, a11, a22 = A[..., 0, 0], A[..., 1, 1], A[..., 2, 2]
    tr = a00 + a11 + a22
    cand = np.stack([tr, a00, a11, a22], axis=-1)
    k = np.argmax(cand, axis=-1)
    q = np.empty(A.shape[:-2] + (4,))
    # Each branch divides by 4·(its largest component), so no branch divides by a small number.
    s0 = np.sqrt(np.maximum(1 + tr, 0)) * 2
    s1 = np.sqrt(np.maximum(1 + a00 - a11 - a22, 0)) * 2
    s2 = np.sqrt(np.maximum(1 - a00 + a11 - a22, 0)) * 2
    s3 = np.sqrt(np.maximum(1 - a00 - a11 + a22, 0)) * 2
    with np.errstate(divide="ignore", invalid="ignore"):
        b0 = np.stack([0.25 * s0, (A[..., 2, 1] - A[..., 1, 2]) / s0, (A[..., 0, 2] - A[..., 2, 0]) / s0,
                       (A[..., 1, 0] - A[..., 0, 1]) / s0], axis=-1)
        b1 = np.stack([(A[..., 2, 1] - A[..., 1, 2]) / s1, 0.25 * s1, (A[..., 0, 1] + A[..., 1, 0]) / s1,
                       (A[..., 0, 2] + A[..., 2, 0]) / s1], axis=-1)
        b2 = np.stack([(A[..., 0, 2] - A[..., 2, 0]) / s2, (A[..., 0, 1] + A[..., 1, 0]) / s2, 0.25 * s2,
                       (A[..., 1, 2] + A[..., 2, 1]) / s2], axis=-1)
        b3 = np.stack([(A[..., 1, 0] - A[..., 0, 1]) / s3, (A[..., 0, 2] + A[..., 2, 0]) / s3,
                       (A[..., 1, 2] + A[..., 2, 1]) / s3, 0.25 * s3], axis=-1)
    q = np.choose(k[..., None], [b0, b1, b2, b3])
    q = np.where(q[..., :1] < 0, -q, q)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def euler_to_quaternion(phi: Any, theta: Any, psi: Any) -> np.ndarray:
    """The unit quaternion (scalar first) of A = R(φ, θ, ψ)ᵀ, vectorised; shape (..., 4).

    A = Rz(φ) Rx(θ) Rz(ψ), so q = q_z(φ) ⊗ q_x(θ) ⊗ q_z(ψ), which in closed form is
    (cos(θ/2)cos((φ+ψ)/2), sin(θ/2)cos((φ-ψ)/2), sin(θ/2)sin((φ-ψ)/2), cos(θ/2)sin((φ+ψ)/2)).
    This is exact for every angle, with no gimbal-lock loss near θ = 0.
    """
    phi, theta, psi = (as_finite_array(v, n) for v, n in ((phi, "phi"), (theta, "theta"), (psi, "psi")))
    c, s = np.cos(theta / 2), np.sin(theta / 2)
    sp_, dp = (phi + psi) / 2, (phi - psi) / 2
    q = np.stack(np.broadcast_arrays(c * np.cos(sp_), s * np.cos(dp), s * np.sin(dp), c * np.sin(sp_)), axis=-1)
    return q
