"""Symbolic model of the heavy symmetric top on a non-singular state: body ω and the quaternion q (section 3.6).

The Euler-angle Lagrangian (3.62) is singular at θ = 0 (the sleeping top, 3.6.3); this model
derives the same motion in variables that are not: the body components ω_a of the angular
velocity and the unit quaternion q of A = Rᵀ (scalar first, :mod:`mechderive.solvers.quaternion`).

Set-up (the chapter's conventions): a symmetric body, principal moments I1 = I2 and I3 about
the *pivot* P; the centre of mass on the body's e3 axis at distance l from P; gravity
-g ẽ3; e_a = R_ab ẽ_b (rows of R = body axes in space components, r = R r̃ for components).

Derived here, in order (nothing typed in):

* **potential** V(R) = M g l R33 (= M g l cos θ of (3.62), since R33 = e3·ẽ3);
* **gravity torque, twice** (generic R, no Euler angles): from the potential, by varying
  R → (1 + hat(δα)) R (the rotation Ṙ = hat(ω) R produces in dt with δα = ω dt, (3.11)),
  τ_a = -∂(δV)/∂δα_a; and from the force, τ = l e3 × F with the body components
  F = R (0, 0, -M g) of the weight (r = R r̃).  The two are checked equal; both give
  τ = M g l (R23, -R13, 0);
* **R(q)**: A_ij = (q ⊗ (0, ẽ_j) ⊗ q̄)_i / |q|² with SymPy's quaternion product, R = Aᵀ (the
  rotation of q/|q|, so nothing depends on |q|); the body components of the vertical
  γ = (R13, R23, R33) follow;
* **equations of motion** (ω̇, q̇): Euler's equations with torque from
  :attr:`FreeTopModel.euler_rhs` with I2 = I1 and τ = τ(q) substituted, and q̇ = ½ q ⊗ (0, ω)
  from :func:`mechderive.solvers.quaternion.quaternion_rate_expressions`;
* **invariants**: E = T + V (3.65), p_φ = L·ẽ3 = L_a γ_a (3.64: the space-vertical angular
  momentum) and p_ψ = I3 ω3 (3.63); their rates along the equations are checked to vanish;
* **initial state** from the scene-file Euler angles and rates: q(φ, θ, ψ) as a product of axis–angle
  quaternions and ω = 2 vec(q̄ ⊗ q̇), regular at θ = 0;
* **the splitting** H = T + V used by :mod:`mechderive.solvers.splitting_heavy_top`:
  for I1 = I2, T = |L|²/(2 I1) + c L3²/2 with c = 1/I3 - 1/I1, two commuting pieces whose flows
  are exact rotations (derived below, :attr:`free_flow`); V generates a kick L → L + h τ(q) with
  q fixed (:attr:`kick`).

Symbols: ``I1 I3`` (those of :mod:`mechderive.systems.free_top.model`), ``M`` (kg), ``g``
(m/s², ≥ 0), ``l`` (m, ≥ 0), ``omega1..3`` (rad/s), ``q0..q3``, ``L1..L3`` (body angular
momentum, kg m²/s), ``h_free``, ``h_kick`` (sub-step durations, s).

>>> m = model()
>>> m.torque_generic.T                              # body components, R generic: M g l (R23, -R13, 0)
Matrix([[M*R23*g*l, -M*R13*g*l, 0]])
>>> m.torque[0]                                     # in the quaternion of Rᵀ, independent of |q|
2*M*g*l*(q0*q1 + q2*q3)/(q0**2 + q1**2 + q2**2 + q3**2)
>>> m.invariant_rates                               # d/dt of (E, p_φ, p_ψ) along the equations
(0, 0, 0)
"""

from __future__ import annotations

import functools

import sympy as sp
from sympy.algebras.quaternion import Quaternion

from ...core.model import SymbolicModel, derived
from ...core.symbols import state_symbol
from ...errors import DerivationError
from ...kinematics.euler import generator
from ...solvers.quaternion import quaternion_rate_expressions
from ..free_top.model import I1, I2, I3, omega_symbols, tau_symbols
from ..free_top.model import model as free_top_model

__all__ = ["HeavyTopRigidModel", "model", "I1", "I3", "M", "g", "l", "quaternion_symbols", "momentum_symbols",
           "h_free", "h_kick", "rotation_symbols", "variation_symbols", "parameters"]

M = sp.Symbol("M", positive=True)
g = sp.Symbol("g", nonnegative=True)
l = sp.Symbol("l", nonnegative=True)  # noqa: E741 - the chapter's name
h_free, h_kick = sp.symbols("h_free h_kick", real=True)


def quaternion_symbols() -> tuple[sp.Symbol, sp.Symbol, sp.Symbol, sp.Symbol]:
    """(q0, q1, q2, q3): the quaternion of A = Rᵀ, scalar first."""
    return tuple(sp.symbols("q0:4", real=True))  # type: ignore[return-value]


def momentum_symbols() -> tuple[sp.Symbol, sp.Symbol, sp.Symbol]:
    """(L1, L2, L3): body components of the angular momentum about the pivot, L_a = I_a ω_a (3.28)."""
    return tuple(sp.symbols("L1:4", real=True))  # type: ignore[return-value]


def rotation_symbols() -> sp.Matrix:
    """A generic matrix of symbols R11 … R33 (no Euler angles, no orthogonality used)."""
    return sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"R{i + 1}{j + 1}", real=True))


def variation_symbols() -> tuple[sp.Symbol, sp.Symbol, sp.Symbol]:
    """(δα1, δα2, δα3): body components of an infinitesimal rotation, δR = hat(δα) R."""
    return tuple(sp.symbols("delta_alpha1:4", real=True))  # type: ignore[return-value]


def parameters() -> tuple[sp.Symbol, ...]:
    """The parameter symbols (I1, I3, M, g, l), in the calling order of every compiled function."""
    return (I1, I3, M, g, l)


def _hat(v) -> sp.Matrix:
    """hat(v)_ab = ε_abc v_c, built from the generators J_c (so3 convention of the toolkit)."""
    return sum((v[c] * generator(c + 1) for c in range(3)), sp.zeros(3, 3))


def _expect_zero(exprs, what: str) -> None:
    for e in (exprs if isinstance(exprs, (list, tuple, sp.MatrixBase)) else [exprs]):
        if sp.cancel(sp.expand(e)) != 0 and sp.simplify(e) != 0:
            raise DerivationError(f"expected {what} to vanish, got {e}")


def _quat_column(qt: Quaternion) -> sp.Matrix:
    return sp.Matrix([qt.a, qt.b, qt.c, qt.d])


class HeavyTopRigidModel(SymbolicModel):
    """Lazily derived equations of the heavy symmetric top in (ω, q), and its splitting H = T + V."""

    # --- gravity ---------------------------------------------------------------------------

    @derived
    def potential_generic(self) -> sp.Expr:
        """V = M g l R33 for a generic R: the centre of mass at l e3, V = M g (l e3)·ẽ3 = M g l R33."""
        R = rotation_symbols()
        return M * g * l * R[2, 2]

    @derived
    def torque_from_potential(self) -> sp.Matrix:
        """τ_a = -∂(δV)/∂δα_a with δV the first-order change of V under R → R + hat(δα) R."""
        R = rotation_symbols()
        da = variation_symbols()
        varied = self.potential_generic.subs({R[i, j]: (R + _hat(da) * R)[i, j] for i in range(3) for j in range(3)},
                                             simultaneous=True)
        dV = sp.expand(varied - self.potential_generic)
        return sp.Matrix([-dV.diff(d) for d in da])

    @derived
    def torque_from_force(self) -> sp.Matrix:
        """τ = l e3 × F, body components; the weight -M g ẽ3 has body components F = R (0, 0, -M g)."""
        R = rotation_symbols()
        F = R * sp.Matrix([0, 0, -M * g])
        return sp.Matrix([0, 0, l]).cross(F)

    @derived
    def torque_generic(self) -> sp.Matrix:
        """The gravity torque for a generic R, after checking that both derivations agree."""
        _expect_zero(self.torque_from_potential - self.torque_from_force, "τ(potential) - τ(force)")
        return self.torque_from_force

    # --- orientation from the quaternion -----------------------------------------------------

    @derived
    def rotation_from_quaternion(self) -> sp.Matrix:
        """R(q) = Aᵀ with A_ij = (q ⊗ (0, ẽ_j) ⊗ q̄)_i / |q|²: the rotation of q/|q|, for every q ≠ 0.

        Dividing by |q|² makes R — and so the torque and V — independent of |q|: a rounding drift
        of |q| over millions of steps then cannot feed back into the motion (without it, the drift
        acts like a slowly changing M g l and the energy error creeps at the 1e-11 level).
        """
        q0, q1, q2, q3 = quaternion_symbols()
        q, qbar = Quaternion(q0, q1, q2, q3), Quaternion(q0, -q1, -q2, -q3)
        cols = []
        for j in range(3):
            e = [0, 0, 0]
            e[j] = 1
            cols.append(_quat_column(q * Quaternion(0, *e) * qbar)[1:, 0])
        A = sp.Matrix.hstack(*cols).applyfunc(sp.expand) / (q0**2 + q1**2 + q2**2 + q3**2)
        return A.T

    @derived
    def vertical_body(self) -> sp.Matrix:
        """γ = (R13, R23, R33): body components of ẽ3 (r = R r̃), in q."""
        return self.rotation_from_quaternion[:, 2]

    @derived
    def torque(self) -> sp.Matrix:
        """Body components of the gravity torque in q: τ_generic with R = R(q)."""
        R = rotation_symbols()
        Rq = self.rotation_from_quaternion
        return self.torque_generic.subs({R[i, j]: Rq[i, j] for i in range(3) for j in range(3)}).applyfunc(sp.factor)

    # --- equations of motion -----------------------------------------------------------------

    @derived
    def euler_rhs(self) -> sp.Matrix:
        """ω̇ of the heavy symmetric top: FreeTopModel.euler_rhs with I2 = I1 and τ = τ(q)."""
        rhs = free_top_model().euler_rhs.subs(I2, I1)
        return sp.expand(rhs.subs(dict(zip(tau_symbols, self.torque))))

    @derived
    def quaternion_rhs(self) -> sp.Matrix:
        """q̇ = ½ q ⊗ (0, ω) (:mod:`mechderive.solvers.quaternion`)."""
        return quaternion_rate_expressions(quaternion_symbols(), omega_symbols())

    @derived
    def rhs(self) -> sp.Matrix:
        """(ω̇1, ω̇2, ω̇3, q̇0, …, q̇3) as functions of (ω, q) and the parameters (I1, I3, M, g, l)."""
        return sp.Matrix([*self.euler_rhs, *self.quaternion_rhs])

    # --- invariants ----------------------------------------------------------------------------

    @derived
    def energy(self) -> sp.Expr:
        """E = T + V (3.65): T = ½ I1 (ω1² + ω2²) + ½ I3 ω3² (3.18, I2 = I1) plus V = M g l γ3."""
        return free_top_model().energy.subs(I2, I1) + M * g * l * self.vertical_body[2]

    @derived
    def angular_momentum_body(self) -> sp.Matrix:
        """L_a = I_a ω_a (3.28) with I2 = I1."""
        return sp.Matrix([I1, I1, I3]).multiply_elementwise(sp.Matrix(omega_symbols()))

    @derived
    def p_phi(self) -> sp.Expr:
        """p_φ = L·ẽ3 = L_a γ_a (3.64): the angular momentum about the space vertical."""
        return sp.expand((self.angular_momentum_body.T * self.vertical_body)[0])

    @derived
    def p_psi(self) -> sp.Expr:
        """p_ψ = L·e3 = I3 ω3 (3.63): the angular momentum about the symmetry axis."""
        return self.angular_momentum_body[2]

    @derived
    def invariant_rates(self) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
        """d/dt of (E, p_φ, p_ψ) along (ω̇, q̇), cancelled to a normal form; raises unless each vanishes."""
        state = [*omega_symbols(), *quaternion_symbols()]
        rates = tuple(sp.cancel(sp.expand(sum(F.diff(s) * r for s, r in zip(state, self.rhs))))
                      for F in (self.energy, self.p_phi, self.p_psi))
        _expect_zero(list(rates), "the rates of E, p_φ, p_ψ")
        return rates

    # --- initial conditions from Euler angles ------------------------------------------------

    @derived
    def euler_quaternion(self) -> sp.Matrix:
        """q(φ, θ, ψ) of A = R(φ, θ, ψ)ᵀ = R3(φ)ᵀ R1(θ)ᵀ R3(ψ)ᵀ (3.54): SymPy's axis–angle quaternions, z ⊗ x ⊗ z.

        R_a(α)ᵀ is the *active* rotation by α about axis a, whose quaternion is (cos α/2, sin α/2 e_a).
        """
        phi, theta, psi = (state_symbol(n) for n in ("phi", "theta", "psi"))
        q = (Quaternion.from_axis_angle((0, 0, 1), phi) * Quaternion.from_axis_angle((1, 0, 0), theta)
             * Quaternion.from_axis_angle((0, 0, 1), psi))
        return _quat_column(q)

    @derived
    def angular_velocity_from_euler_rates(self) -> sp.Matrix:
        """Body ω from (φ, θ, ψ, φ̇, θ̇, ψ̇) by inverting (Q): (0, ω) = 2 q̄ ⊗ q̇ (|q| = 1, q = :attr:`euler_quaternion`).

        The products of half-angle functions are reduced to whole angles (sin²(x/2) = (1 - cos x)/2,
        cos²(x/2) = (1 + cos x)/2, sin(x/2) cos(x/2) = sin(x)/2; every term is quadratic in each
        angle's half-angle functions), which yields (3.58) — checked in the tests against
        :func:`mechderive.kinematics.euler.angular_velocity_body`, derived from ṘRᵀ.  This route costs
        ~0.1 s instead of seconds in a fresh process.
        """
        names = ("phi", "theta", "psi")
        phi, theta, psi = (state_symbol(n) for n in names)
        a, b, c = (Quaternion.from_axis_angle(axis, angle) for axis, angle in
                   (((0, 0, 1), phi), ((1, 0, 0), theta), ((0, 0, 1), psi)))

        def bar(x: Quaternion) -> Quaternion:
            return Quaternion(x.a, -x.b, -x.c, -x.d)

        def d(x: Quaternion, v: sp.Symbol) -> Quaternion:
            return Quaternion(*[sp.diff(comp, v) for comp in (x.a, x.b, x.c, x.d)])

        # q = a ⊗ b ⊗ c (= euler_quaternion): by the product rule and x̄ ⊗ x = 1 for unit x,
        # q̄ ⊗ q̇ = φ̇ c̄ b̄ (ā ȧ) b c + θ̇ c̄ (b̄ ḃ) c + ψ̇ c̄ ċ
        w = (bar(c) * bar(b) * (bar(a) * d(a, phi)) * b * c * state_symbol("phi_dot")
             + bar(c) * (bar(b) * d(b, theta)) * c * state_symbol("theta_dot")
             + bar(c) * d(c, psi) * state_symbol("psi_dot"))

        def whole_angles(e: sp.Expr) -> sp.Expr:
            e = sp.expand(e)
            for x in (state_symbol(n) for n in names):
                half = {sp.sin(x / 2) ** 2: (1 - sp.cos(x)) / 2, sp.cos(x / 2) ** 2: (1 + sp.cos(x)) / 2}
                e = sp.expand(e.subs(half))
                e = sp.expand(e.subs(sp.sin(x / 2) * sp.cos(x / 2), sp.sin(x) / 2))
                if e.has(sp.sin(x / 2), sp.cos(x / 2)):
                    raise DerivationError(f"expected only squares and products of half angles of {x}, got {e}")
            return e

        if whole_angles(w.a) != 0:
            raise DerivationError(f"expected Re(q̄ ⊗ q̇) = ½ d|q|²/dt = 0, got {whole_angles(w.a)}")
        return sp.Matrix([whole_angles(2 * c) for c in (w.b, w.c, w.d)])

    # --- the splitting H = T + V ---------------------------------------------------------------

    @derived
    def kinetic_energy_momentum(self) -> sp.Expr:
        """T(L) = Σ L_a²/(2 I_a) with I2 = I1: the free top's T (3.46) at ω_a = L_a / I_a."""
        L = momentum_symbols()
        return free_top_model().energy.subs(I2, I1).subs(
            {w: La / Ia for w, La, Ia in zip(omega_symbols(), L, (I1, I1, I3))})

    @derived
    def kinetic_split(self) -> tuple[sp.Expr, sp.Expr]:
        """T = T_L + T_3 with T_L = |L|²/(2 I1) and T_3 = T - T_L, checked to be c L3²/2 (c = 1/I3 - 1/I1).

        Both pieces are in involution under the Lie–Poisson bracket {F, G} = -L·(∇F × ∇G)
        (|L|² is a Casimir), so their flows commute; this is checked too.
        """
        L = sp.Matrix(momentum_symbols())
        TL = (L.T * L)[0] / (2 * I1)
        T3 = sp.factor(self.kinetic_energy_momentum - TL)
        _expect_zero(T3 - (1 / I3 - 1 / I1) * L[2] ** 2 / 2, "T - |L|²/(2 I1) - c L3²/2")
        grad = [sp.Matrix([F.diff(La) for La in L]) for F in (TL, T3)]
        _expect_zero(L.dot(grad[0].cross(grad[1])), "{T_L, T_3}")
        return TL, T3

    @derived
    def free_flow(self) -> sp.Matrix:
        """The exact flow of T over a time ``h_free``: (L, q) → (L', q'), as a column of 7.

        The flow of a piece F(L) is L̇ = L × ∇F, q̇ = ½ q ⊗ (0, ∇F) (Euler's equations and (Q) with
        ω = ∇F).  For T_L: ∇T_L = L/I1, so L̇ = 0 and q' = q ⊗ exp((0, h L/(2 I1))).  For T_3:
        ∇T_3 = c L3 e3, so L3 is constant and (L1, L2)' = exp(h K) (L1, L2) with K = ∂(L̇1, L̇2)/∂(L1, L2)
        constant; and
        q' = q ⊗ exp((0, 0, 0, h c L3/2)).  The quaternion exponentials are SymPy's, with
        sin(x)/x written as sinc(x) so that L = 0 is regular.  T_L's flow is applied first
        (the two commute, :attr:`kinetic_split`).
        """
        L = sp.Matrix(momentum_symbols())
        q = Quaternion(*quaternion_symbols())
        TL, T3 = self.kinetic_split
        gradL = sp.Matrix([TL.diff(La) for La in L])
        grad3 = sp.Matrix([T3.diff(La) for La in L])
        if any(grad3[:2]) or (L.cross(gradL)).applyfunc(sp.simplify) != sp.zeros(3, 1):
            raise DerivationError(f"expected ∇T_3 along e3 and L × ∇T_L = 0, got {grad3.T}, {L.cross(gradL).T}")
        rate = L.cross(grad3)
        K = rate[:2, :].jacobian(L[:2, :])
        _expect_zero([rate[2], *(rate[:2, :] - K * L[:2, :])], "L̇3 and L̇_(1,2) - K L_(1,2) under T_3")
        if K.has(L[0], L[1]):
            raise DerivationError(f"expected a linear flow for T_3 (K free of L1, L2), got {K}")
        # K = κ J with J constant and J² = -1, so exp(h K) = Σ (hκ)ⁿ Jⁿ/n! = cos(hκ) + J sin(hκ)
        # (even and odd powers of the series); faster than Matrix.exp's Jordan form, same result.
        kappa = K[0, 1]
        J = (K / kappa).applyfunc(sp.cancel)
        if J.free_symbols or J * J != -sp.eye(2):
            raise DerivationError(f"expected K = κ J with a constant J, J² = -1, got {K}")
        L12 = (sp.cos(h_free * kappa) * sp.eye(2) + sp.sin(h_free * kappa) * J) * L[:2, :]
        L_new = sp.Matrix([*L12, L[2]])

        def qexp(v: sp.Matrix) -> Quaternion:
            e = Quaternion(0, *v).exp()
            n = sp.sqrt(sum(x**2 for x in v))
            parts = [c.subs(sp.sin(n), n * sp.sinc(n)) for c in (e.a, e.b, e.c, e.d)]
            # cos and sinc are even: |x| inside them may be replaced by x (SymPy writes |z| for n = √(z²))
            even = lambda f: f.func(f.args[0].replace(sp.Abs, lambda a: a))  # noqa: E731
            return Quaternion(*[c.replace(lambda f: isinstance(f, (sp.cos, sp.sinc)), even) for c in parts])

        q_new = q * qexp(h_free * gradL / 2) * qexp(h_free * grad3 / 2)
        return sp.Matrix([*L_new, *_quat_column(q_new)])

    @derived
    def kick(self) -> sp.Matrix:
        """The exact flow of V over a time ``h_kick``: q̇ = ½ q ⊗ (0, ∇_L V) = 0, L̇ = τ(q): L' = L + h τ(q)."""
        L = sp.Matrix(momentum_symbols())
        return sp.Matrix([*(L + h_kick * self.torque), *quaternion_symbols()])

    @derived
    def stage_map(self) -> sp.Matrix:
        """kick(h_kick) ∘ free_flow(h_free): one drift–kick stage of the splitting, (L, q) → (L', q')."""
        state = [*momentum_symbols(), *quaternion_symbols()]
        after = self.free_flow
        return self.kick.subs(dict(zip(state, after)), simultaneous=True)


@functools.cache
def model() -> HeavyTopRigidModel:
    """The process-wide heavy-top (ω, q) model."""
    return HeavyTopRigidModel()
