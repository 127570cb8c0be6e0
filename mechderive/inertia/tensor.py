"""The inertia tensor of point masses, kinetic energy and angular momentum (3.17)–(3.19), (3.27)–(3.28).

Convention
----------
Every vector here is in **body components** (r = r_a e_a, ω = ω_a e_a, section
3.1.1); the text's angular-velocity matrix is ω_ab = ε_abc ω_c = (Ṙ Rᵀ)_ab.
Units: any consistent set (kg, m, rad/s give kg m², J and kg m²/s).

Derivation (nothing below is typed in from the chapter)
-------------------------------------------------------
1. A body point has constant body components r and space components r̃ = Rᵀ r.
   Its velocity in space components is ṙ̃ = Ṙᵀ r, so in body components
   v = R ṙ̃ = R Ṙᵀ r = (Ṙ Rᵀ)ᵀ r = ωᵀ r, with ω = Ṙ Rᵀ (3.5)/(3.11).
   (The model checks that this is ω × r, the rigid velocity used in (3.17).)
2. T = ½ Σ m v·v is a homogeneous quadratic form in ω, so it equals ½ ωᵀ H ω
   with H its Hessian: the inertia tensor (3.18)–(3.19) *is* ∂²T/∂ω_a∂ω_b.
3. L = Σ m r × v; the model checks L = I ω = ∂T/∂ω (3.27)–(3.28).

Numerics go through :meth:`SymbolicModel.compile`: the one-mass tensor is
compiled as a function of (m, x, y, z) and summed over the masses.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import sympy as sp

from ..core.model import SymbolicModel, derived
from ..core.validate import as_finite_array
from ..errors import DerivationError, InvalidInputError, ShapeError

__all__ = [
    "PointMassModel",
    "point_mass_model",
    "point_mass_tensor",
    "inertia_tensor",
    "inertia_tensor_symbolic",
    "kinetic_energy",
    "angular_momentum",
    "omega_symbols",
    "general_inertia_symbols",
]


@functools.cache
def omega_symbols() -> sp.Matrix:
    """Body components (ω1, ω2, ω3) of the angular velocity, as a column."""
    return sp.Matrix(sp.symbols("omega1:4", real=True))


@functools.cache
def general_inertia_symbols() -> sp.Matrix:
    """A general symmetric tensor [[I11, I12, I13], [I12, I22, I23], [I13, I23, I33]] of symbols."""
    s = {(a, b): sp.Symbol(f"I{min(a, b)}{max(a, b)}", real=True) for a in (1, 2, 3) for b in (1, 2, 3)}
    return sp.Matrix(3, 3, lambda a, b: s[(a + 1, b + 1)])


def _omega_matrix(w: sp.Matrix) -> sp.Matrix:
    """The text's ω_ab = ε_abc ω_c (section 3.1.2)."""
    return sp.Matrix(3, 3, lambda a, b: sum(sp.LeviCivita(a + 1, b + 1, c + 1) * w[c] for c in range(3)))


def _require_zero(expr: Any, what: str) -> None:
    bad = sp.Matrix(expr).applyfunc(sp.expand) if isinstance(expr, sp.MatrixBase) else sp.expand(expr)
    if (bad.is_zero_matrix if isinstance(bad, sp.MatrixBase) else bad == 0) is not True:
        raise DerivationError(f"expected {what} to vanish identically, got {bad}")


class PointMassModel(SymbolicModel):
    """Kinetic energy, inertia tensor and angular momentum of ``n`` point masses, derived.

    Symbols: masses ``m1..mn`` (positive), body components ``x_i, y_i, z_i`` of
    the positions (about the point P held fixed), ω1..ω3.  For ``n == 1`` the
    names are ``m, x, y, z``.

    >>> pm = point_mass_model(1)
    >>> pm.inertia_tensor[0, 0]
    m*(y**2 + z**2)
    """

    def __init__(self, n: int) -> None:
        super().__init__()
        if not (isinstance(n, int) and n >= 1):
            raise InvalidInputError(f"expected a number of masses n >= 1, got {n!r}")
        self.n = n
        if n == 1:
            self.masses = [sp.Symbol("m", positive=True)]
            self.positions = [sp.Matrix(sp.symbols("x y z", real=True))]
        else:
            self.masses = list(sp.symbols(f"m1:{n + 1}", positive=True))
            self.positions = [sp.Matrix(sp.symbols(f"x{i} y{i} z{i}", real=True)) for i in range(1, n + 1)]
        self.omega = omega_symbols()

    @derived
    def velocities(self) -> list[sp.Matrix]:
        """Body components v_i = ωᵀ r_i of ṙ_i (from ṙ̃ = Ṙᵀ r and Ṙ = ω R, (3.11))."""
        wT = _omega_matrix(self.omega).T
        vs = [wT * r for r in self.positions]
        for v, r in zip(vs, self.positions):  # the rigid velocity is ω × r, as (3.17) uses
            _require_zero(v - self.omega.cross(r), "ωᵀ r - ω × r")
        return vs

    @derived
    def kinetic_energy(self) -> sp.Expr:
        """T = ½ Σ m_i ṙ_i², the first line of (3.17), in ω and body components."""
        return sp.expand(sum(m * v.dot(v) for m, v in zip(self.masses, self.velocities)) / 2)

    @derived
    def inertia_tensor(self) -> sp.Matrix:
        """I_ab = ∂²T/∂ω_a∂ω_b: the inertia tensor of (3.18)–(3.19) about the origin."""
        T = self.kinetic_energy
        I = sp.hessian(T, list(self.omega)).applyfunc(sp.factor)
        # T is a homogeneous quadratic in ω, so it is reproduced exactly by its Hessian (3.18):
        _require_zero(T - (self.omega.T * I * self.omega)[0] / 2, "T - ½ ωᵀ I ω")
        return I

    @derived
    def angular_momentum(self) -> sp.Matrix:
        """L = Σ m_i r_i × ṙ_i (3.27), body components; checked equal to I ω and to ∂T/∂ω (3.28)."""
        L = sum((m * r.cross(v) for m, r, v in zip(self.masses, self.positions, self.velocities)),
                sp.zeros(3, 1))
        _require_zero(L - self.inertia_tensor * self.omega, "L - I ω")
        _require_zero(L - sp.Matrix([self.kinetic_energy.diff(w) for w in self.omega]), "L - ∂T/∂ω")
        return L.applyfunc(sp.expand)

    @derived
    def total_mass(self) -> sp.Expr:
        """M = Σ m_i."""
        return sum(self.masses)


@functools.cache
def point_mass_model(n: int) -> PointMassModel:
    """The process-wide :class:`PointMassModel` for ``n`` masses."""
    return PointMassModel(n)


def point_mass_tensor(mass: Any, position: Any) -> sp.Matrix:
    """The inertia tensor (3.19) of one point mass at ``position`` about the origin (SymPy).

    >>> import sympy as sp
    >>> M, c = sp.symbols("M c", positive=True)
    >>> point_mass_tensor(M, (c, 0, 0))
    Matrix([
    [0,      0,      0],
    [0, M*c**2,      0],
    [0,      0, M*c**2]])
    """
    from ..formulas.parse import as_expression, as_matrix

    pm = point_mass_model(1)
    pos = as_matrix(position, "`position`")
    if pos.shape != (3, 1) and pos.shape != (1, 3):
        raise ShapeError(f"expected `position` with 3 components, got shape {pos.shape}")
    subs = {pm.masses[0]: as_expression(mass, "`mass`"), **{s: v for s, v in zip(pm.positions[0], pos)}}
    # the keys are the model's own symbols, atoms of a polynomial: xreplace is the simultaneous substitution,
    # without subs' per-element pattern matching (~4x faster; the bodies' inertia calls this per term)
    return pm.inertia_tensor.xreplace(subs)


def inertia_tensor_symbolic(masses: Any, positions: Any) -> sp.Matrix:
    """Σ_i of :func:`point_mass_tensor` — (3.19) for SymPy masses and positions."""
    from ..formulas.parse import as_matrix

    masses = list(masses)
    positions = [as_matrix(p, "each position") for p in positions]
    if len(masses) != len(positions):
        raise ShapeError(f"expected as many positions as masses ({len(masses)}), got {len(positions)}")
    return sum((point_mass_tensor(m, p) for m, p in zip(masses, positions)), sp.zeros(3, 3))


def _single_tensor_function():
    pm = point_mass_model(1)
    return pm.compile("point_mass_tensor", pm.inertia_tensor, [pm.masses[0], *pm.positions[0]])


def inertia_tensor(masses: Any, positions: Any) -> np.ndarray:
    """The inertia tensor (3.19) of point masses about the origin, numerically.

    Parameters
    ----------
    masses : array_like, shape (..., N)
        Masses m_i >= 0.
    positions : array_like, shape (..., N, 3)
        Body components of r_i, measured from the point P held fixed.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    >>> inertia_tensor([1.0, 1.0], [[1.0, 0, 0], [-1.0, 0, 0]])   # a dumbbell along axis 1
    array([[0., 0., 0.],
           [0., 2., 0.],
           [0., 0., 2.]])
    """
    m = as_finite_array(masses, "masses")
    r = as_finite_array(positions, "positions")
    if m.ndim < 1 or r.ndim < 2 or r.shape[-1] != 3 or r.shape[-2] != m.shape[-1]:
        raise ShapeError(f"expected `masses` of shape (..., N) and `positions` of shape (..., N, 3), "
                         f"got {m.shape} and {r.shape}")
    if np.any(m < 0):
        raise InvalidInputError(f"expected masses >= 0, got {float(m[m < 0].ravel()[0])!r}")
    per_mass = _single_tensor_function()(m, r[..., 0], r[..., 1], r[..., 2])  # (..., N, 3, 3)
    return per_mass.sum(axis=-3)


def _quadratic_form_functions():
    """½ ωᵀ I ω for a general symmetric I, and its gradient ∂T/∂ω, compiled once."""
    pm = point_mass_model(1)
    I, w = general_inertia_symbols(), pm.omega
    T = sp.expand((w.T * I * w)[0] / 2)  # the quadratic form with Hessian I, as (3.18) states T is
    grad = sp.Matrix([T.diff(wa) for wa in w])  # L = ∂T/∂ω, checked against Σ m r × v in PointMassModel
    args = [I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2], *w]
    return pm.compile("kinetic_energy", T, args), pm.compile("angular_momentum", grad, args)


def _tensor_and_omega(inertia: Any, omega: Any) -> tuple[list[np.ndarray], np.ndarray]:
    from .validate import check_inertia_tensor

    I = check_inertia_tensor(inertia, line_body=True)
    w = as_finite_array(omega, "omega")
    if w.ndim < 1 or w.shape[-1] != 3:
        raise ShapeError(f"expected `omega` to have shape (..., 3), got {w.shape}")
    comps = [I[..., 0, 0], I[..., 0, 1], I[..., 0, 2], I[..., 1, 1], I[..., 1, 2], I[..., 2, 2]]
    return comps, w


def kinetic_energy(inertia: Any, omega: Any) -> np.ndarray | float:
    """Rotational kinetic energy T = ½ ω_a I_ab ω_b (3.18), numerically.

    ``inertia`` (..., 3, 3) and ``omega`` (..., 3) are in the same (body) components
    and broadcast together; the tensor is validated by :func:`check_inertia_tensor`
    (a line body's zero moment is accepted).

    >>> kinetic_energy(np.diag([1.0, 2.0, 3.0]), [1.0, 1.0, 1.0])
    3.0
    """
    comps, w = _tensor_and_omega(inertia, omega)
    T, _ = _quadratic_form_functions()
    return T(*comps, w[..., 0], w[..., 1], w[..., 2])


def angular_momentum(inertia: Any, omega: Any) -> np.ndarray:
    """Angular momentum L_a = I_ab ω_b (3.28), body components, shape (..., 3).

    >>> angular_momentum(np.diag([1.0, 2.0, 3.0]), [1.0, 1.0, 1.0])
    array([1., 2., 3.])
    """
    comps, w = _tensor_and_omega(inertia, omega)
    _, L = _quadratic_form_functions()
    out = L(*comps, w[..., 0], w[..., 1], w[..., 2])  # (..., 3, 1)
    return out[..., 0]
