"""Symbolic model of any rigid body about a fixed point in uniform gravity, in (ω, q) (sections 3.3-3.6).

Set-up (the chapter's conventions): principal moments I1, I2, I3 about the fixed point P (any
values a body can have); the centre of mass at c = c_a e_a from P (body components c1, c2, c3);
gravity -g ẽ3; e_a = R_ab ẽ_b (rows of R = body axes in space components, r = R r̃ for components,
so a vector's space components are r̃ = Rᵀ r).  A free body is the case c = 0 (3.30: its rotation
about the centre of mass is that of a body fixed there).

Derived here, in order (nothing typed in):

* **potential** V(R) = M g ẑ·(Rᵀ c) = M g Σ_a R_a3 c_a for a generic matrix R of symbols;
* **gravity torque, twice**: from the potential, by varying R → (1 + hat(δα)) R (the rotation
  Ṙ = hat(ω) R makes in dt with δα = ω dt, (3.11)), τ_a = -∂(δV)/∂δα_a; and from the force,
  τ = c × F with the body components F = R (0, 0, -M g) of the weight.  The two are checked equal;
* **R(q)**: the heavy top's :attr:`~mechderive.systems.heavy_top.rigid_model.HeavyTopRigidModel.rotation_from_quaternion`
  (the rotation of q/|q|, so nothing depends on |q|); γ = (R13, R23, R33), the body components of ẽ3;
* **equations of motion** (ω̇, q̇): Euler's equations (3.33) with torque from
  :attr:`~mechderive.systems.free_top.model.FreeTopModel.euler_rhs`, τ = τ_gravity(q) + τ_applied,
  and q̇ = ½ q ⊗ (0, ω) (:func:`mechderive.solvers.quaternion.quaternion_rate_expressions`);
* **invariants** (no applied torque): E = T + V (T of (3.18), as in (3.65)) and the vertical angular
  momentum L·ẽ3 = L_a γ_a (p_φ of (3.64) for the symmetric top); their rates along the equations are
  checked to vanish for every I, M, g, c;
* **axial momenta**: the rate of L_a = I_a ω_a along the equations,
  (I_b - I_c) ω_b ω_c + τ_a (cyclic a b c); where it vanishes identically at a body's parameter
  values, L_a is conserved — for a = 3 exactly when I1 = I2 and c1 = c2 = 0: p_ψ = I3 ω3 (3.63).

Symbols: ``I1 I2 I3`` (those of :mod:`mechderive.systems.free_top.model`), ``M`` (kg), ``g`` (m/s²),
``c1 c2 c3`` (m), ``omega1..3`` (rad/s), ``q0..q3``, ``R11..R33``, ``tau1..3`` (the applied torque, N m).

>>> m = model()
>>> m.torque_generic.T                              # M g γ × c, γ = (R13, R23, R33)
Matrix([[M*R23*c3*g - M*R33*c2*g, -M*R13*c3*g + M*R33*c1*g, M*R13*c2*g - M*R23*c1*g]])
>>> m.invariant_rates                               # d/dt of (E, L·ẽ3) along the equations, τ_applied = 0
(0, 0)
"""

from __future__ import annotations

import functools

import sympy as sp

from ...core.model import SymbolicModel, derived
from ...errors import DerivationError
from ...solvers.quaternion import quaternion_rate_expressions
from ..free_top.model import I1, I2, I3, omega_symbols, tau_symbols
from ..free_top.model import model as free_top_model
from ..heavy_top.rigid_model import _hat, quaternion_symbols, rotation_symbols, variation_symbols
from ..heavy_top.rigid_model import model as heavy_rigid_model

__all__ = ["RigidBodyModel", "model", "I1", "I2", "I3", "M", "g", "c_symbols", "parameters", "state", "names",
           "omega_symbols", "quaternion_symbols", "rotation_symbols", "tau_symbols", "time_symbol"]

M = sp.Symbol("M", nonnegative=True)
g = sp.Symbol("g", real=True)
c_symbols = tuple(sp.symbols("c1:4", real=True))
time_symbol = sp.Symbol("t", real=True)


def parameters() -> tuple[sp.Symbol, ...]:
    """(I1, I2, I3, M, g, c1, c2, c3): the calling order of every compiled function."""
    return (I1, I2, I3, M, g, *c_symbols)


def state() -> tuple[sp.Symbol, ...]:
    """(ω1, ω2, ω3, q0, q1, q2, q3): the integrated state (body ω and the quaternion of Rᵀ)."""
    return (*omega_symbols(), *quaternion_symbols())


def names() -> dict[str, sp.Symbol]:
    """Every name a user formula (the applied torque) may use, with its symbol: t, ω, R generic, parameters."""
    R = rotation_symbols()
    table = {"t": time_symbol, **{f"omega{a + 1}": w for a, w in enumerate(omega_symbols())},
             **{f"R{i + 1}{j + 1}": R[i, j] for i in range(3) for j in range(3)}}
    table.update({str(s): s for s in parameters()})
    return table


def _expect_zero(exprs, what: str) -> None:
    for e in (exprs if isinstance(exprs, (list, tuple, sp.MatrixBase)) else [exprs]):
        if sp.cancel(sp.expand(e)) != 0 and sp.simplify(e) != 0:
            raise DerivationError(f"expected {what} to vanish, got {e}")


class RigidBodyModel(SymbolicModel):
    """Lazily derived equations of a rigid body about a fixed point in uniform gravity, in (ω, q)."""

    # --- gravity ---------------------------------------------------------------------------

    @derived
    def potential_generic(self) -> sp.Expr:
        """V = M g ẑ·(Rᵀ c) = M g Σ_a R_a3 c_a: the height of the centre of mass, space components Rᵀ c."""
        R = rotation_symbols()
        c_space = R.T * sp.Matrix(c_symbols)
        return M * g * c_space[2]

    @derived
    def torque_from_potential(self) -> sp.Matrix:
        """τ_a = -∂(δV)/∂δα_a with δV the first-order change of V under R → R + hat(δα) R."""
        R = rotation_symbols()
        da = variation_symbols()
        varied = self.potential_generic.subs({R[i, j]: (R + _hat(da) * R)[i, j] for i in range(3) for j in range(3)},
                                             simultaneous=True)
        dV = sp.expand(varied - self.potential_generic)
        return sp.Matrix([sp.factor(-dV.diff(d)) for d in da])

    @derived
    def torque_from_force(self) -> sp.Matrix:
        """τ = c × F, body components; the weight -M g ẽ3 has body components F = R (0, 0, -M g)."""
        R = rotation_symbols()
        F = R * sp.Matrix([0, 0, -M * g])
        return sp.Matrix(c_symbols).cross(F)

    @derived
    def torque_generic(self) -> sp.Matrix:
        """The gravity torque for a generic R, after checking that both derivations agree."""
        _expect_zero(self.torque_from_potential - self.torque_from_force, "τ(potential) - τ(force)")
        return self.torque_from_force.applyfunc(sp.expand)

    # --- orientation from the quaternion -----------------------------------------------------

    @derived
    def rotation_from_quaternion(self) -> sp.Matrix:
        """R(q): the rotation of q/|q| (the heavy top's derivation, shared)."""
        return heavy_rigid_model().rotation_from_quaternion

    @derived
    def vertical_body(self) -> sp.Matrix:
        """γ = (R13, R23, R33): body components of ẽ3 (r = R r̃), in q."""
        return self.rotation_from_quaternion[:, 2]

    def in_quaternion(self, expr):
        """``expr`` with every generic R_ab replaced by R(q)_ab."""
        R = rotation_symbols()
        Rq = self.rotation_from_quaternion
        return expr.subs({R[i, j]: Rq[i, j] for i in range(3) for j in range(3)}, simultaneous=True)

    @derived
    def torque(self) -> sp.Matrix:
        """Body components of the gravity torque in q: τ_generic with R = R(q)."""
        return self.in_quaternion(self.torque_generic)

    @derived
    def vertical_rate_generic(self) -> sp.Matrix:
        """γ̇ for γ = (R13, R23, R33), the body components of ẽ3: γ̇ = γ × ω (Poisson's equation).

        Derived, not assumed: the rate of R(q)'s third column along q̇ = ½ q ⊗ (0, ω) is compared with
        γ × ω in q, and the derivation raises unless they agree identically.
        """
        R = rotation_symbols()
        gamma = sp.Matrix([R[a, 2] for a in range(3)])
        candidate = gamma.cross(sp.Matrix(omega_symbols()))
        q, rate = quaternion_symbols(), self.quaternion_rhs
        from_q = sp.Matrix([sum(self.vertical_body[a].diff(s) * r for s, r in zip(q, rate)) for a in range(3)])
        _expect_zero([sp.cancel(e) for e in from_q - self.in_quaternion(candidate)], "dγ/dt(q) − γ × ω")
        return candidate

    # --- equations of motion -----------------------------------------------------------------

    @derived
    def euler_rhs_generic(self) -> sp.Matrix:
        """ω̇ from Euler's equations (3.33) with τ = τ_gravity(R) + τ_applied (symbols tau1..3), R generic."""
        total = {tau: self.torque_generic[a] + tau for a, tau in enumerate(tau_symbols)}
        return free_top_model().euler_rhs.subs(total, simultaneous=True).applyfunc(sp.expand)

    @derived
    def euler_equations_generic(self) -> sp.Matrix:
        """Euler's equations with the gravity torque, as I_a ω̇_a - (I_b - I_c) ω_b ω_c - τ_a (each = 0)."""
        wdot = sp.Matrix(sp.symbols("omega1_dot omega2_dot omega3_dot", real=True))
        I = sp.Matrix([I1, I2, I3])
        rows = [sp.expand(I[a] * (wdot[a] - self.euler_rhs_generic[a])) for a in range(3)]
        return sp.Matrix(rows)

    @derived
    def euler_rhs(self) -> sp.Matrix:
        """ω̇ in (ω, q): :attr:`euler_rhs_generic` with R = R(q)."""
        return self.in_quaternion(self.euler_rhs_generic)

    @derived
    def quaternion_rhs(self) -> sp.Matrix:
        """q̇ = ½ q ⊗ (0, ω) (:mod:`mechderive.solvers.quaternion`)."""
        return quaternion_rate_expressions(quaternion_symbols(), omega_symbols())

    @derived
    def rhs(self) -> sp.Matrix:
        """(ω̇1, ω̇2, ω̇3, q̇0, …, q̇3) of (ω, q), the parameters and the applied torque tau1..3."""
        return sp.Matrix([*self.euler_rhs, *self.quaternion_rhs])

    # --- invariants ----------------------------------------------------------------------------

    @derived
    def angular_momentum_body(self) -> sp.Matrix:
        """L_a = I_a ω_a (3.28)."""
        return sp.Matrix([I1, I2, I3]).multiply_elementwise(sp.Matrix(omega_symbols()))

    @derived
    def energy_generic(self) -> sp.Expr:
        """E = T + V: T = ½ Σ I_a ω_a² (3.18), V = :attr:`potential_generic` (R generic)."""
        return free_top_model().energy + self.potential_generic

    @derived
    def vertical_momentum_generic(self) -> sp.Expr:
        """L·ẽ3 = L_a (e_a·ẽ3) = Σ_a L_a R_a3 (R generic): p_φ of (3.64) for the symmetric top."""
        R = rotation_symbols()
        return sum(self.angular_momentum_body[a] * R[a, 2] for a in range(3))

    @derived
    def energy(self) -> sp.Expr:
        """E in (ω, q)."""
        return self.in_quaternion(self.energy_generic)

    @derived
    def vertical_momentum(self) -> sp.Expr:
        """L·ẽ3 in (ω, q)."""
        return self.in_quaternion(self.vertical_momentum_generic)

    def _rate(self, F: sp.Expr) -> sp.Expr:
        """dF/dt along (ω̇, q̇) with no applied torque, cancelled to a normal form."""
        free = {tau: 0 for tau in tau_symbols}
        rhs = self.rhs.subs(free)
        return sp.cancel(sp.expand(sum(F.diff(s) * r for s, r in zip(state(), rhs))))

    @derived
    def invariant_rates(self) -> tuple[sp.Expr, sp.Expr]:
        """d/dt of (E, L·ẽ3) along the equations with τ_applied = 0; raises unless each vanishes."""
        rates = (self._rate(self.energy), self._rate(self.vertical_momentum))
        _expect_zero(list(rates), "the rates of E and L·ẽ3")
        return rates

    @derived
    def axial_momentum_rates(self) -> sp.Matrix:
        """d/dt of L_a = I_a ω_a along the equations (τ_applied = 0, R generic): (I_b - I_c) ω_b ω_c + τ_a.

        L_a is conserved for a body whose parameter values make its rate vanish for every state
        (:func:`conserved_axial_momenta`); the derivation finds p_ψ = I3 ω3 for I1 = I2, c1 = c2 = 0.
        """
        free = {tau: 0 for tau in tau_symbols}
        I = (I1, I2, I3)
        return sp.Matrix([sp.expand(I[a] * self.euler_rhs_generic[a].subs(free)) for a in range(3)])


@functools.cache
def model() -> RigidBodyModel:
    """The process-wide rigid-body (ω, q) model."""
    return RigidBodyModel()
