"""Symbolic model of a free (or torqued) rigid body in principal axes: sections 3.3–3.4.

Everything here is derived, lazily, from two inputs: the body-frame angular
momentum L_a = I_ab ω_b (3.28) with I = diag(I1, I2, I3) (principal axes, 3.21),
and the rate of change of the body axes ė_a = ω_ac e_c with ω_ac = ε_acb ω_b
(3.5)–(3.6), taken from :func:`mechderive.kinematics.so3`'s convention via the
generators of :mod:`mechderive.kinematics.euler`.

Symbols: ``I1 I2 I3`` (positive), ``omega1 omega2 omega3`` (body components of
ω, functions of t in the derivation, plain symbols in the ``state_*`` forms),
``tau1 tau2 tau3`` (body components of an applied torque).
"""

from __future__ import annotations

import functools

import sympy as sp

from ...core.model import SymbolicModel, derived
from ...core.symbols import coordinate, state_symbol, t, to_state_symbols
from ...kinematics.euler import generator

__all__ = ["FreeTopModel", "model", "I1", "I2", "I3", "omega_symbols", "tau_symbols"]

I1, I2, I3 = sp.symbols("I1 I2 I3", positive=True)
tau_symbols = sp.symbols("tau1 tau2 tau3", real=True)


def omega_symbols() -> tuple[sp.Symbol, sp.Symbol, sp.Symbol]:
    """The plain symbols (omega1, omega2, omega3) used in compiled functions."""
    return tuple(state_symbol(f"omega{a}") for a in (1, 2, 3))  # type: ignore[return-value]


class FreeTopModel(SymbolicModel):
    """Lazily derived quantities of a rigid body rotating about a fixed point (or its centre of mass)."""

    @derived
    def omega(self) -> sp.Matrix:
        """Body components (ω1(t), ω2(t), ω3(t))."""
        return sp.Matrix([coordinate(f"omega{a}") for a in (1, 2, 3)])

    @derived
    def inertia(self) -> sp.Matrix:
        """The inertia tensor in principal axes, diag(I1, I2, I3) (3.21)."""
        return sp.diag(I1, I2, I3)

    @derived
    def angular_momentum_body(self) -> sp.Matrix:
        """L_a = I_ab ω_b (3.28)."""
        return self.inertia * self.omega

    @derived
    def angular_velocity_matrix(self) -> sp.Matrix:
        """ω_ac = ε_acb ω_b = Σ_b ω_b (J_b)_ac, built from the so(3) generators (3.6)."""
        return sum((self.omega[b] * generator(b + 1) for b in range(3)), sp.zeros(3, 3))

    @derived
    def rate_of_angular_momentum(self) -> sp.Matrix:
        """Body components of dL/dt = d(L_a e_a)/dt = L̇_a e_a + L_a ω_ac e_c (3.32), using ė_a = ω_ac e_c (3.5)."""
        L = self.angular_momentum_body
        W = self.angular_velocity_matrix
        return sp.Matrix([L[c].diff(t) + sum(L[a] * W[a, c] for a in range(3)) for c in range(3)])

    @derived
    def euler_equations(self) -> sp.Matrix:
        """Euler's equations (3.33) with torque: the body components of dL/dt - τ, each = 0."""
        return sp.expand(self.rate_of_angular_momentum - sp.Matrix(tau_symbols))

    @derived
    def euler_rhs(self) -> sp.Matrix:
        """ω̇ solved from Euler's equations, in the plain symbols omega1..3, I1..3, tau1..3."""
        wdot = [self.omega[a].diff(t) for a in range(3)]
        sol = sp.solve(list(self.euler_equations), wdot, dict=True)[0]
        return to_state_symbols(sp.Matrix([sp.expand(sol[w]) for w in wdot]))

    @derived
    def energy(self) -> sp.Expr:
        """Kinetic energy T = ½ ω_a I_ab ω_b (3.18), in the plain symbols."""
        return to_state_symbols(sp.expand((self.omega.T * self.inertia * self.omega)[0] / 2))

    @derived
    def angular_momentum_squared(self) -> sp.Expr:
        """L² = L_a L_a (3.47), in the plain symbols."""
        L = self.angular_momentum_body
        return to_state_symbols(sp.expand((L.T * L)[0]))


@functools.cache
def model() -> FreeTopModel:
    """The process-wide free-top model."""
    return FreeTopModel()
