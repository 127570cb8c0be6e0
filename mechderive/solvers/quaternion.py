"""Orientation as a unit quaternion: the product and the kinematic equation q̇ = ½ q ⊗ (0, ω).

Convention (see :mod:`mechderive.kinematics.conversions`): q = (q0, q1, q2, q3),
scalar first, is the unit quaternion of the *active* rotation A = Rᵀ that
carries the space axes onto the body axes (r̃ = A r for body components r).

Kinematics, derived from the chapter's Ṙ = ω R (3.11) with ω_ab = ε_abc ω_c,
i.e. Ṙ = hat(ω) R where hat(ω) = -[ω]× (the cross-product matrix with a minus
sign, :mod:`mechderive.kinematics.so3`), ω in body components:

    Ȧ = Ṙᵀ = Rᵀ hat(ω)ᵀ = A [ω]×,

so over dt the body turns by the *active* rotation exp(dt [ω]×) about the body
axis ω applied on the right, A(t + dt) = A(t) exp(dt [ω]×) + O(dt²).  Quaternion
products compose active rotations in the same order, and the quaternion of
exp(dt [ω]×) is (1, ½ ω dt) + O(dt²), hence

    q̇ = ½ q ⊗ (0, ω).                                              (Q)

Right multiplication by a pure quaternion is an antisymmetric 4×4 map, so
q · q̇ = 0 and |q| is a first integral of (Q): a numerical drift of |q| is
integrator error only.  The tests check (Q) against Ṙ = hat(ω) R both
numerically and symbolically (with SymPy's own quaternion-to-matrix map).

>>> q = np.array([1.0, 0.0, 0.0, 0.0])
>>> quaternion_rate(q, [0.0, 0.0, 2.0]).tolist()
[0.0, 0.0, 0.0, 1.0]
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["quaternion_multiply", "quaternion_rate", "quaternion_rate_expressions", "axis_quaternion"]


def quaternion_multiply(p: Any, q: Any) -> np.ndarray:
    """Hamilton product p ⊗ q of scalar-first quaternions, shape (..., 4), broadcasting.

    (p0, p) ⊗ (q0, q) = (p0 q0 - p·q, p0 q + q0 p + p × q); the quaternion of the
    active rotation A_p A_q (first A_q, then A_p).

    >>> i, j = np.array([0, 1.0, 0, 0]), np.array([0, 0, 1.0, 0])
    >>> quaternion_multiply(i, j).tolist()     # i j = k
    [0.0, 0.0, 0.0, 1.0]
    """
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    p0, pv = p[..., :1], p[..., 1:]
    q0, qv = q[..., :1], q[..., 1:]
    scalar = p0 * q0 - np.sum(pv * qv, axis=-1, keepdims=True)
    vector = p0 * qv + q0 * pv + np.cross(pv, qv)
    lead = np.broadcast_shapes(p.shape[:-1], q.shape[:-1])
    return np.concatenate([np.broadcast_to(scalar, lead + (1,)), np.broadcast_to(vector, lead + (3,))], axis=-1)


def quaternion_rate(q: Any, omega: Any) -> np.ndarray:
    """q̇ = ½ q ⊗ (0, ω) of (Q), ω in body components (rad/s); shape (..., 4)."""
    w = np.asarray(omega, dtype=float)
    pure = np.concatenate([np.zeros(w.shape[:-1] + (1,)), w], axis=-1)
    return 0.5 * quaternion_multiply(q, pure)


def axis_quaternion(axis: int, angle: Any) -> np.ndarray:
    """The quaternion (cos(α/2), sin(α/2) e_axis) of the active rotation by α about body axis 0, 1 or 2.

    >>> np.round(axis_quaternion(2, np.pi), 12).tolist()
    [0.0, 0.0, 0.0, 1.0]
    """
    half = 0.5 * np.asarray(angle, dtype=float)
    out = np.zeros(half.shape + (4,))
    out[..., 0] = np.cos(half)
    out[..., 1 + axis] = np.sin(half)
    return out


def quaternion_rate_expressions(q: Any, omega: Any) -> Any:
    """Symbolic (Q): the SymPy column of ½ q ⊗ (0, ω) for symbols q = (q0..q3), ω = (ω1..ω3).

    Built with :class:`sympy.algebras.Quaternion`'s product, not typed in by hand.

    >>> import sympy as sp
    >>> q = sp.symbols("q0:4"); w = sp.symbols("w1:4")
    >>> quaternion_rate_expressions(q, w)[0]
    -q1*w1/2 - q2*w2/2 - q3*w3/2
    """
    import sympy as sp
    from sympy.algebras.quaternion import Quaternion

    prod = Quaternion(*q) * Quaternion(0, *omega)
    return sp.Matrix([sp.expand(c / 2) for c in (prod.a, prod.b, prod.c, prod.d)])
