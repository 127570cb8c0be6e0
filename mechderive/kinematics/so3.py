"""The Lie algebra so(3) in the chapter's convention, and its exponential map.

The chapter turns an angular velocity vector into an antisymmetric matrix by
(3.6) inverted, ω_ab = ε_abc ω_c (section 3.1.2)::

    hat(ω) = [[  0,   ω3, -ω2],
              [-ω3,   0,   ω1],
              [ ω2, -ω1,   0 ]]

This is *minus* the usual cross-product matrix [ω]×, because the chapter's R
acts on basis vectors (e_a = R_ab ẽ_b, a passive rotation).  Consequently
``exp(θ hat(n))`` is the passive rotation by θ about the unit axis n; for
n = e3 it is R3(θ) of (3.51) and for n = e1 it is R1(θ) of (3.52).

Numeric functions here take arrays with trailing dimension 3 (vectors) or
(3, 3) (matrices) and broadcast over leading dimensions.
"""

from __future__ import annotations

import numpy as np

__all__ = ["hat", "vee", "expm_so3", "logm_so3"]


def hat(omega: np.ndarray) -> np.ndarray:
    """The antisymmetric matrix ω_ab = ε_abc ω_c of a vector (shape (..., 3) → (..., 3, 3)).

    >>> hat([0.0, 0.0, 1.0]).tolist()
    [[0.0, 1.0, -0.0], [-1.0, 0.0, 0.0], [0.0, -0.0, 0.0]]
    """
    w = np.asarray(omega, dtype=float)
    out = np.zeros(w.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = w[..., 2], -w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = -w[..., 2], w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = w[..., 1], -w[..., 0]
    return out


def vee(matrix: np.ndarray) -> np.ndarray:
    """The vector ω_a = ½ ε_abc ω_bc of an antisymmetric matrix (3.6); inverse of :func:`hat`."""
    m = np.asarray(matrix, dtype=float)
    return 0.5 * np.stack(
        [m[..., 1, 2] - m[..., 2, 1], m[..., 2, 0] - m[..., 0, 2], m[..., 0, 1] - m[..., 1, 0]], axis=-1
    )


def expm_so3(omega: np.ndarray) -> np.ndarray:
    """exp(hat(ω)) by Rodrigues' formula, accurate to rounding for all |ω| (shape (..., 3) → (..., 3, 3)).

    With θ = |ω| and K = hat(ω)/θ: exp(θK) = 1 + sin θ K + (1 - cos θ) K².  The
    coefficients sin θ/θ and (1 - cos θ)/θ² are evaluated stably for small θ
    (the latter as ½ sinc²(θ/2)), so there is no cancellation near θ = 0.
    """
    w = np.asarray(omega, dtype=float)
    theta = np.linalg.norm(w, axis=-1)[..., None, None]
    a = np.sinc(theta / np.pi)  # sin θ / θ
    b = 0.5 * np.sinc(theta / (2 * np.pi)) ** 2  # (1 - cos θ) / θ²
    K = hat(w)
    return np.eye(3) + a * K + b * (K @ K)


def logm_so3(matrix: np.ndarray) -> np.ndarray:
    """The vector ω with exp(hat(ω)) = R and |ω| ≤ π (shape (..., 3, 3) → (..., 3)).

    Uses the quaternion of R (robust at every angle, including near π).
    """
    from .conversions import matrix_to_quaternion

    q = matrix_to_quaternion(np.asarray(matrix, dtype=float))  # scalar first, of the active rotation Rᵀ
    q = np.where(q[..., :1] < 0, -q, q)  # the same rotation with angle in [0, π]
    w, v = q[..., 0], q[..., 1:]
    s = np.linalg.norm(v, axis=-1)
    angle = 2 * np.arctan2(s, w)
    # exp(hat(ω))ᵀ = exp(-hat(ω)) = exp([ω]×) is the *active* rotation by |ω| about ω/|ω|;
    # so ω is the rotation vector of the active rotation Rᵀ, whose quaternion we have.
    # angle / s -> 2 / w as s -> 0 (w ≥ 1/√2 there), avoiding 0/0.
    scale = np.where(s > 1e-8, angle / np.where(s > 1e-8, s, 1.0), 2.0 / w)
    return scale[..., None] * v
