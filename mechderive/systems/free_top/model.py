"""Symbolic model of a free (or torqued) rigid body in principal axes: sections 3.3–3.4.

Everything here is derived, lazily, from two inputs: the body-frame angular
momentum L_a = I_ab ω_b (3.28) with I = diag(I1, I2, I3) (principal axes, 3.21),
and the rate of change of the body axes ė_a = ω_ac e_c with ω_ac = ε_acb ω_b
(3.5)–(3.6), taken from :func:`mechderive.kinematics.so3`'s convention via the
generators of :mod:`mechderive.kinematics.euler`.

Symbols: ``I1 I2 I3`` (positive), ``omega1 omega2 omega3`` (body components of
ω, functions of t in the derivation, plain symbols in the ``state_*`` forms),
``tau1 tau2 tau3`` (body components of an applied torque).

Further quantities, each derived from the ones above (never typed in):

- (3.31): the space components L̃ = Rᵀ L of the angular momentum change at the rate
  Rᵀ τ on Euler's equations — zero for a free body — for a *generic* R(t) with Ṙ = ωR;
- (3.34)–(3.37): the symmetric top I2 = I1: its equations, the precession rate Ω and the
  general solution exp(t ∂ω̇/∂ω)·ω(0) of the linear (ω1, ω2) system;
- (3.40)–(3.45): Euler's equations linearised about the steady spin ω = Ω e1 by
  expanding to first order in ε with ω = (Ω + εη1, εη2, εη3), the elimination of η3
  giving A of (3.44), and, for any axis, the Jacobian J = ∂ω̇/∂ω, its characteristic
  polynomial and the eigenvalues about ω = Ω e_a (used by :mod:`.stability`);
- (3.46)–(3.49): the rates of T and L² along Euler's equations, ∇_ω T, and ω·L;
- (3.59)–(3.60): the Euler-angle rates of the free symmetric top with L along ẽ3,
  solved from I ω = L·(column 3 of R) with ω from (3.58).

More symbols: ``Omega`` (the spin Ω of (3.40), or the precession rate Ω of (3.35) — the
chapter's double use, each docstring says which), ``eta1 eta2 eta3`` (perturbations,
functions of t), ``epsilon`` (the order-counting parameter), ``L`` (|L| > 0),
``omega1_0 omega2_0`` (initial values), ``lambda`` (eigenvalue).  Units: any consistent
set (rates in rad per unit time, moments in mass × length²).

>>> m = model()
>>> m.symmetric_precession_rate          # Ω of (3.36), read off the derived I2 = I1 equations
omega3*(I1 - I3)/I1
>>> m.stability_coefficient              # A of (3.44), by eliminating η3 from the linearised equations
-Omega**2*(I1 - I2)*(I1 - I3)/I3
"""

from __future__ import annotations

import functools

import sympy as sp

from ...core.model import SymbolicModel, derived
from ...core.simplify import simplify_trig
from ...core.symbols import coordinate, state_symbol, t, to_state_symbols
from ...errors import DerivationError
from ...kinematics import euler as _euler
from ...kinematics.euler import generator

__all__ = ["FreeTopModel", "model", "I1", "I2", "I3", "omega_symbols", "tau_symbols", "Omega", "epsilon",
           "L", "lam", "initial_omega", "eta_functions", "cyclic_axes"]

I1, I2, I3 = sp.symbols("I1 I2 I3", positive=True)
tau_symbols = sp.symbols("tau1 tau2 tau3", real=True)
Omega = sp.Symbol("Omega", real=True)
epsilon = sp.Symbol("epsilon", positive=True)
L = sp.Symbol("L", positive=True)
lam = sp.Symbol("lambda")
initial_omega = sp.symbols("omega1_0 omega2_0", real=True)
_MOMENTS = (I1, I2, I3)


def eta_functions() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """The perturbations (η1(t), η2(t), η3(t)) of (3.41)."""
    return tuple(coordinate(f"eta{a}") for a in (1, 2, 3))  # type: ignore[return-value]


def cyclic_axes(axis: int) -> tuple[int, int, int]:
    """(a, b, c): ``axis`` and the next two axes in cyclic order, 0-based (axis 1 → (0, 1, 2))."""
    a = axis - 1
    return a, (a + 1) % 3, (a + 2) % 3


def _expect_zero(exprs, what: str) -> None:
    for e in (exprs if isinstance(exprs, (list, tuple, sp.MatrixBase)) else [exprs]):
        if sp.simplify(e) != 0:
            raise DerivationError(f"expected {what} to vanish, got {e}")


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

    # --- (3.31): L fixed in space ------------------------------------------------------------

    @derived
    def omega_dot(self) -> dict:
        """ω̇_a(t) solved from Euler's equations (torque τ), as a substitution {Derivative(ω_a(t), t): ...}."""
        back = {state_symbol(f"omega{a}"): self.omega[a - 1] for a in (1, 2, 3)}
        return {self.omega[a].diff(t): self.euler_rhs[a].subs(back) for a in range(3)}

    @derived
    def space_rate_of_angular_momentum(self) -> sp.Matrix:
        """d/dt of the space components L̃ = Rᵀ L (r̃ = Rᵀ r) on Euler's equations: = Rᵀ τ, so 0 when free (3.31).

        R(t) is a generic matrix of functions R11(t) ... R33(t) obeying Ṙ = ω R
        ((3.5) with ω_ac = ε_acb ω_b); nothing about Euler angles is assumed.
        """
        R = sp.Matrix(3, 3, lambda i, j: sp.Function(f"R{i + 1}{j + 1}", real=True)(t))
        rate = (R.T * self.angular_momentum_body).diff(t)
        Rdot = self.angular_velocity_matrix * R
        rate = rate.subs({R[i, j].diff(t): Rdot[i, j] for i in range(3) for j in range(3)})
        return to_state_symbols(sp.expand(rate.subs(self.omega_dot)))

    # --- (3.34)-(3.37): the symmetric top ----------------------------------------------------

    @derived
    def free_rhs(self) -> sp.Matrix:
        """ω̇ of the free body (τ = 0), in the plain symbols omega1..3 and I1..3."""
        return self.euler_rhs.subs({tau: 0 for tau in tau_symbols})

    @derived
    def symmetric_rhs(self) -> sp.Matrix:
        """ω̇ of the free symmetric top, I2 = I1 (3.34)."""
        return sp.expand(self.free_rhs.subs(I2, I1))

    @derived
    def symmetric_precession_rate(self) -> sp.Expr:
        """Ω of (3.35)–(3.36): ω̇1 = Ω ω2 read off the symmetric top's equations, then ω̇2 = -Ω ω1, ω̇3 = 0 confirmed."""
        w1, w2, w3 = omega_symbols()
        rhs = self.symmetric_rhs
        rate = sp.factor(rhs[0].diff(w2))
        _expect_zero([rhs[0] - rate * w2, rhs[1] + rate * w1, rhs[2]],
                     "the symmetric top's equations minus (Ω ω2, -Ω ω1, 0)")
        return rate

    @derived
    def symmetric_general_solution(self) -> sp.Matrix:
        """(ω1(t), ω2(t)) = exp(t M) (ω1(0), ω2(0)), M = ∂(ω̇1, ω̇2)/∂(ω1, ω2) written with ``Omega`` for (3.36)'s Ω.

        Every solution of (3.35) (the system is linear with constant M).  Initial values
        are the symbols ``omega1_0, omega2_0``.
        """
        w1, w2, _ = omega_symbols()
        M = self.symmetric_rhs[:2, :].jacobian([w1, w2])
        M = (M / self.symmetric_precession_rate).applyfunc(sp.simplify) * Omega
        if any(e.free_symbols - {Omega} for e in M):
            raise DerivationError(f"expected M to depend on Ω only, got {M}")
        flow = (t * M).exp().applyfunc(lambda e: sp.simplify(e.rewrite(sp.cos)))
        return flow * sp.Matrix(initial_omega)

    # --- (3.40)-(3.45): stability of steady spins --------------------------------------------

    @derived
    def linearised_axis1(self) -> sp.Matrix:
        """Right-hand sides of I_a η̇_a = ... (3.42)–(3.43): Euler's equations (τ = 0) at ω = (Ω + εη1, εη2, εη3), order ε.

        The order-ε⁰ part, Euler's equations at the steady spin (3.40), is checked to vanish.
        """
        eta = eta_functions()
        point = {self.omega[0]: Omega + epsilon * eta[0], self.omega[1]: epsilon * eta[1],
                 self.omega[2]: epsilon * eta[2]}
        eqs = self.euler_equations.subs({tau: 0 for tau in tau_symbols}).subs(point).doit().expand()
        _expect_zero(eqs.subs(epsilon, 0), "Euler's equations at the steady spin (3.40)")
        first = eqs.diff(epsilon).subs(epsilon, 0)
        # first_a = I_a η̇_a - rhs_a
        return sp.expand(sp.Matrix([_MOMENTS[a] * eta[a].diff(t) for a in range(3)]) - first)

    @derived
    def stability_coefficient(self) -> sp.Expr:
        """A of (3.44): I2 η̈2 = A η2, by differentiating (3.42)'s η2 equation and substituting (3.43)'s η̇3."""
        eta = eta_functions()
        rhs = self.linearised_axis1
        second = rhs[1].diff(t).subs(eta[2].diff(t), rhs[2] / I3)  # = I2 η̈2
        A = sp.factor(sp.simplify(second / eta[1]))
        if A.has(*eta):
            raise DerivationError(f"expected I2 η̈2 proportional to η2, got {second}")
        return A

    @derived
    def jacobian(self) -> sp.Matrix:
        """J = ∂ω̇/∂ω of the free Euler equations: η̇ = J(ω) η linearises them about ω."""
        return self.free_rhs.jacobian(list(omega_symbols()))

    @derived
    def characteristic_polynomial(self) -> sp.Poly:
        """det(λ - J(ω)) as a polynomial in λ (the symbol ``lambda``)."""
        return (lam * sp.eye(3) - self.jacobian).det(method="berkowitz").as_poly(lam)

    @derived
    def growth_squared(self) -> sp.Expr:
        """s(ω) with det(λ - J) = λ³ - s λ at a steady ω: the eigenvalues are 0 and ±√s.

        Derived facts, checked here: trace J = 0 (ω̇_a does not involve ω_a), and J ω = 2 ω̇
        (ω̇ is quadratic and homogeneous in ω), so det J = 0 when ω̇ = 0.  s is returned as
        Σ_a ω_a² s_a with each s_a factored, s_a = (I_a - I_b)(I_c - I_a)/(I_b I_c) (a, b, c cyclic).
        """
        w = omega_symbols()
        coeffs = self.characteristic_polynomial.all_coeffs()  # [1, -trace, c2, -det]
        _expect_zero(coeffs[1], "trace J")
        _expect_zero(self.jacobian * sp.Matrix(w) - 2 * self.free_rhs, "J ω - 2 ω̇")
        s = sp.expand(-coeffs[2])
        parts = sp.collect(s, [wa**2 for wa in w], evaluate=False)
        if set(parts) != {wa**2 for wa in w}:
            raise DerivationError(f"expected s to be a combination of ω_a², got {s}")
        return sum(w[a] ** 2 * sp.factor(parts[w[a] ** 2]) for a in range(3))

    @derived
    def axis_growth_squared(self) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
        """s_a = s(Ω e_a) for a steady spin Ω about principal axis a = 1, 2, 3 (factored)."""
        w = omega_symbols()
        return tuple(sp.factor(self.growth_squared.subs({w[b]: (Omega if b == a else 0) for b in range(3)}))
                     for a in range(3))

    @derived
    def axis_eigenvalues(self) -> tuple[dict, dict, dict]:
        """The roots {λ: multiplicity} of det(λ - J) at ω = Ω e_a, a = 1, 2, 3, by :func:`sympy.roots`."""
        w = omega_symbols()
        out = []
        for a in range(3):
            poly = self.characteristic_polynomial.as_expr().subs({w[b]: (Omega if b == a else 0) for b in range(3)})
            out.append(sp.roots(sp.Poly(poly, lam)))
        return tuple(out)

    @derived
    def axis_stability_coefficients(self) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
        """A_a = I_b s_a (b the next axis cyclically), so that I_b η̈_b = A_a η_b; A_1 is (3.44)'s A."""
        return tuple(sp.factor(_MOMENTS[cyclic_axes(a + 1)[1]] * self.axis_growth_squared[a]) for a in range(3))

    # --- (3.46)-(3.49): Poinsot ------------------------------------------------------------

    @derived
    def energy_rate(self) -> sp.Expr:
        """dT/dt = ∇_ω T · ω̇ along the free Euler equations (should vanish: (3.46) is conserved)."""
        w = omega_symbols()
        return sp.simplify(sum(self.energy.diff(w[a]) * self.free_rhs[a] for a in range(3)))

    @derived
    def angular_momentum_squared_rate(self) -> sp.Expr:
        """d(L²)/dt along the free Euler equations (should vanish: (3.47) is conserved)."""
        w = omega_symbols()
        return sp.simplify(sum(self.angular_momentum_squared.diff(w[a]) * self.free_rhs[a] for a in range(3)))

    @derived
    def energy_gradient(self) -> sp.Matrix:
        """∇_ω T = (∂T/∂ω1, ∂T/∂ω2, ∂T/∂ω3) (3.49)."""
        return sp.Matrix([self.energy.diff(wa) for wa in omega_symbols()])

    @derived
    def omega_dot_angular_momentum(self) -> sp.Expr:
        """ω·L = ω_a L_a in the plain symbols (the invariable plane: = 2T)."""
        return sp.expand((sp.Matrix(omega_symbols()).T * to_state_symbols(self.angular_momentum_body))[0])

    # --- (3.59)-(3.60): the free symmetric top in Euler angles --------------------------------

    @derived
    def fixed_L_body_components(self) -> sp.Matrix:
        """Body components of L = L ẽ3: r = R r̃, so L_a = L R_a3 (column 3 of R(φ, θ, ψ), (3.54))."""
        return L * _euler.model().state_rotation[:, 2]

    @derived
    def symmetric_top_euler_rates(self) -> dict:
        """{φ̇, θ̇, ψ̇} of the free symmetric top (I2 = I1) with L = L ẽ3.

        Solves I1 ω1 = L_1, I1 ω2 = L_2, I3 ω3 = L_3 with ω from (3.58) (derived from ṘRᵀ),
        linear in the rates (determinant ∝ sin θ: valid for sin θ ≠ 0).
        """
        w = _euler.model().state_angular_velocity_body
        Lb = self.fixed_L_body_components
        rates = [state_symbol(n) for n in ("phi_dot", "theta_dot", "psi_dot")]
        eqs = [I1 * w[0] - Lb[0], I1 * w[1] - Lb[1], I3 * w[2] - Lb[2]]
        sol = sp.solve(eqs, rates, dict=True)
        if len(sol) != 1:
            raise DerivationError(f"expected one solution for the Euler-angle rates, got {sol}")
        return {r: sp.factor(simplify_trig(sol[0][r])) for r in rates}

    @derived
    def symmetric_top_euler_rates_spin(self) -> dict:
        """The rates of :attr:`symmetric_top_euler_rates` in terms of ω3, using L_3 = L cos θ = I3 ω3."""
        L_of_spin = sp.solve(sp.Eq(self.fixed_L_body_components[2], I3 * state_symbol("omega3")), L)
        if len(L_of_spin) != 1:
            raise DerivationError(f"expected one L from L cos θ = I3 ω3, got {L_of_spin}")
        return {r: sp.factor(sp.simplify(v.subs(L, L_of_spin[0]))) for r, v in self.symmetric_top_euler_rates.items()}


@functools.cache
def model() -> FreeTopModel:
    """The process-wide free-top model."""
    return FreeTopModel()
