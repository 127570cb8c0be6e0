"""Magnus steps on SO(3): one step of the path-ordered exponential (3.15), exactly a rotation.

The equation (3.11), Ṙ = ω(t) R, with ω_ab = ε_abc ω_c built from the BODY
components ω_c (see :func:`mechderive.kinematics.so3.hat`), has the solution

    R(t_n + h) = exp(Ω_n) R(t_n),

where Ω_n ∈ so(3) is the Magnus series of ω over the step: Ω = ∫ω + ½∫∫_{t2<t1}[ω(t1), ω(t2)] + …
(later times on the LEFT of each commutator, as in the path ordering P of (3.15)).
Truncating the series and evaluating its integrals by Gauss–Legendre quadrature
gives the classical Lie-group integrators, with A_i = ω(t_n + c_i h):

order 4 (2 Gauss nodes c = ½ ∓ √3/6)::

    Ω = h/2 (A1 + A2) + (√3/12) h² [A2, A1]

order 6 (3 Gauss nodes c = ½ − √15/10, ½, ½ + √15/10; Blanes, Casas & Ros 2000)::

    α1 = h A2,   α2 = (√15/3) h (A3 − A1),   α3 = (10/3) h (A3 − 2 A2 + A1)
    C1 = [α1, α2],   C2 = −(1/60) [α1, 2 α3 + C1]
    Ω  = α1 + α3/12 + (1/240) [−20 α1 − α3 + C1, α2 + C2]

The sign of the order-4 commutator is *derived* in the test-suite from the
Dyson series of (3.16) with non-commuting symbols (``[b, a] h³/12`` for
ω = a + b τ), and both schemes are checked by their measured order of convergence.

Because Ω is antisymmetric and exp is evaluated exactly (Rodrigues,
:func:`~mechderive.kinematics.so3.expm_so3`), every step is a rotation to rounding.

Opposite ordering (section 3.7, (3.98)): for Ṙ = R Ω(t) — the convective
angular velocity Ω = R⁻¹Ṙ of (3.10)/(3.86), later times on the RIGHT — the inverse
Y = R⁻¹ obeys Ẏ = −Ω Y, a left-ordered problem; hence

    R(t_n + h) = R(t_n) exp(Ω_right),   Ω_right[A] = −Ω_left[−A],

which for order 4 is h/2 (A1 + A2) − (√3/12) h² [A2, A1]: the commutator flips sign.

Units: times in s, angular velocities in rad/s, Ω dimensionless (radians).
"""

from __future__ import annotations

from typing import Any, Callable, Literal

import numpy as np

from ..errors import InvalidInputError
from .so3 import expm_so3, hat, vee

__all__ = ["gauss_nodes", "magnus_exponent", "magnus_exponent_from_nodes", "magnus_step"]

Ordering = Literal["left", "right"]

_SQRT3 = np.sqrt(3.0)
_SQRT15 = np.sqrt(15.0)
#: Gauss–Legendre nodes on [0, 1] for each supported order (s nodes give order 2s).
_NODES = {
    4: np.array([0.5 - _SQRT3 / 6, 0.5 + _SQRT3 / 6]),
    6: np.array([0.5 - _SQRT15 / 10, 0.5, 0.5 + _SQRT15 / 10]),
}


def check_order(order: Any) -> int:
    """Return ``order`` if it is a supported Magnus order (4 or 6), else raise."""
    if isinstance(order, bool) or order not in _NODES:
        raise InvalidInputError(f"expected `order` 4 or 6, got {order!r}")
    return int(order)


def check_ordering(ordering: Any) -> str:
    """Return ``ordering`` if it is "left" (Ṙ = ωR, (3.15)) or "right" (Ṙ = RΩ, (3.98)), else raise."""
    if ordering not in ("left", "right"):
        raise InvalidInputError(f"expected `ordering` 'left' (Ṙ = ωR) or 'right' (Ṙ = RΩ), got {ordering!r}")
    return str(ordering)


def gauss_nodes(order: int) -> np.ndarray:
    """The Gauss–Legendre nodes c_i ∈ (0, 1) at which a Magnus step of ``order`` samples ω.

    >>> gauss_nodes(4).round(6)
    array([0.211325, 0.788675])
    """
    return _NODES[check_order(order)].copy()


def _comm(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return x @ y - y @ x


def _omega_left(a: np.ndarray, h: np.ndarray, order: int) -> np.ndarray:
    """Magnus exponent for Ṙ = A R from A at the Gauss nodes; a: (..., s, 3, 3), h: (...)."""
    h = h[..., None, None]
    if order == 4:
        a1, a2 = a[..., 0, :, :], a[..., 1, :, :]
        return 0.5 * h * (a1 + a2) + (_SQRT3 / 12) * h**2 * _comm(a2, a1)
    a1, a2, a3 = a[..., 0, :, :], a[..., 1, :, :], a[..., 2, :, :]
    al1 = h * a2
    al2 = (_SQRT15 / 3) * h * (a3 - a1)
    al3 = (10.0 / 3.0) * h * (a3 - 2 * a2 + a1)
    c1 = _comm(al1, al2)
    c2 = -_comm(al1, 2 * al3 + c1) / 60
    return al1 + al3 / 12 + _comm(-20 * al1 - al3 + c1, al2 + c2) / 240


def magnus_exponent_from_nodes(omega_nodes: Any, h: Any, *, order: int = 4, ordering: Ordering = "left") -> np.ndarray:
    """The Magnus exponent of one step, as a vector (body components), from ω at the Gauss nodes.

    ``omega_nodes`` has shape (..., s, 3): the body angular velocity at t_n + c_i h for
    the s = order/2 nodes of :func:`gauss_nodes`; ``h`` broadcasts against (...).
    Returns the vector Ω with hat(Ω) = Ω_n, shape (..., 3); the step is exp(hat(Ω)).
    """
    order, ordering = check_order(order), check_ordering(ordering)
    a = hat(np.asarray(omega_nodes, dtype=float))
    h = np.asarray(h, dtype=float)
    if ordering == "left":
        return vee(_omega_left(a, h, order))
    return -vee(_omega_left(-a, h, order))


def _nodes_times(t: np.ndarray, h: np.ndarray, order: int) -> np.ndarray:
    return t[..., None] + _NODES[order] * h[..., None]


def _evaluate(omega: Callable[[np.ndarray], np.ndarray], times: np.ndarray) -> np.ndarray:
    flat = np.asarray(omega(times.reshape(-1)), dtype=float)
    return flat.reshape(times.shape + (3,))


def magnus_exponent(omega: Callable[[np.ndarray], np.ndarray], t: Any, h: Any, *, order: int = 4,
                    ordering: Ordering = "left") -> np.ndarray:
    """The Magnus exponent (body-component vector) of the step [t, t + h], vectorised over t and h.

    ``omega`` maps times of shape (N,) to body angular velocities of shape (N, 3).

    >>> w = lambda s: np.tile([0.0, 0.0, 2.0], (len(s), 1))   # fixed axis: Ω = ∫ω exactly
    >>> magnus_exponent(w, 0.0, 0.5)
    array([0., 0., 1.])
    """
    order = check_order(order)
    t, h = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(h, dtype=float))
    nodes = _evaluate(omega, _nodes_times(t, h, order))
    return magnus_exponent_from_nodes(nodes, h, order=order, ordering=ordering)


def magnus_step(omega: Callable[[np.ndarray], np.ndarray], t: float, h: float, R: Any, *, order: int = 4,
                ordering: Ordering = "left") -> np.ndarray:
    """Advance R(t) to R(t + h): exp(Ω_n) R for ordering "left" (3.11), R exp(Ω_n) for "right" (3.98).

    ``omega`` maps times of shape (N,) to shape (N, 3) (body components, rad/s); h in s.
    R (shape (..., 3, 3)) is not validated here — :func:`path_ordered_exponential` does that.

    >>> w = lambda s: np.tile([0.0, 0.0, 1.0], (len(s), 1))
    >>> from mechderive.kinematics.euler import rotation_matrix
    >>> np.allclose(magnus_step(w, 0.0, 0.3, np.eye(3)), rotation_matrix(0.3, 0.0, 0.0))
    True
    """
    step = expm_so3(magnus_exponent(omega, t, h, order=order, ordering=ordering))
    R = np.asarray(R, dtype=float)
    return step @ R if ordering == "left" else R @ step
