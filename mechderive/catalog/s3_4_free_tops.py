"""Catalog entries for section 3.4: free tops, (3.34)–(3.49).

Every printed formula is compared with a quantity derived by
:class:`~mechderive.systems.free_top.model.FreeTopModel` from Euler's equations:
the symmetric top's equations and precession rate (3.34)–(3.37), the Earth's wobble
(3.38)–(3.39), the linearisation about a steady spin and its stability (3.40)–(3.45),
and Poinsot's conserved quantities (3.46)–(3.49).

Units for (3.39): the chapter writes ω3 = (1 day)⁻¹ and reads 1/300 day⁻¹ as "a
wobble every 300 days".  Since Ω = ω3 (I1 - I3)/I1 is linear in ω3 the ratio
|Ω|/ω3 = 1/300 holds in any unit, but the 300-day *period* 2π/|Ω| needs ω3 = 2π rad/day
(one turn per day); with ω3 = 1 rad/day it would be 600π ≈ 1885 days.  The entries
check the ratio and the period under the one-turn-per-day reading.
"""

from __future__ import annotations

import itertools

import sympy as sp

from ..core.symbols import t, to_state_symbols
from ..systems.free_top import model as ft
from .checks import all_pass, same
from .registry import Claim, Outcome, register

I1, I2, I3, Omega = ft.I1, ft.I2, ft.I3, ft.Omega
w1, w2, w3 = ft.omega_symbols()
omega0 = sp.Symbol("omega0", positive=True)
alpha = sp.Symbol("alpha", real=True)
T = sp.Symbol("T", positive=True)
eta1, eta2, eta3 = ft.eta_functions()


def _m() -> ft.FreeTopModel:
    return ft.model()


# ----------------------------------------------------------------------------- 3.4: the sphere

register(Claim(
    "3.4 sphere", "3.4",
    "for a sphere, I1 = I2 = I3, Euler's equations give ω̇ = 0: ω is constant (and parallel to L = I1 ω)",
    "symbolic",
    printed=lambda: sp.zeros(3, 1),
    check=lambda f: same(f, _m().free_rhs.subs({I2: I1, I3: I1}), "ω̇ of the sphere"),
))

# ----------------------------------------------------------------------------- 3.4.1: the symmetric top

register(Claim(
    "3.34", "3.4.1",
    "symmetric top I1 = I2: I1ω̇1 = ω2ω3(I1 - I3), I2ω̇2 = -ω1ω3(I1 - I3), I3ω̇3 = 0 (so ω3 is constant)",
    "symbolic",
    printed=lambda: sp.Matrix([w2 * w3 * (I1 - I3), -w1 * w3 * (I1 - I3), 0]),
    check=lambda f: same(f, sp.diag(I1, I1, I3) * _m().symmetric_rhs, "(I1ω̇1, I1ω̇2, I3ω̇3) at I2 = I1"),
))

register(Claim(
    "3.35", "3.4.1",
    "ω̇1 = Ωω2, ω̇2 = -Ωω1 with Ω of (3.36)",
    "symbolic",
    printed=lambda: sp.Matrix([Omega * w2, -Omega * w1]),
    check=lambda f: same(sp.Matrix(f).subs(Omega, _m().symmetric_precession_rate), _m().symmetric_rhs[:2, :],
                         "(ω̇1, ω̇2) of the symmetric top"),
))


def _check_3_36(f) -> Outcome:
    m = _m()
    return all_pass([
        same(f, m.symmetric_precession_rate, "Ω read off ω̇1 = Ωω2"),
        # Ω is a constant of the motion: it depends on ω3 only, and ω̇3 = 0 (3.34)
        same(sp.diff(m.symmetric_precession_rate, w1) ** 2 + sp.diff(m.symmetric_precession_rate, w2) ** 2
             + m.symmetric_rhs[2] ** 2, 0, "dΩ/dt"),
    ])


register(Claim(
    "3.36", "3.4.1",
    "the precession rate Ω = ω3(I1 - I3)/I1 is a constant",
    "symbolic",
    printed=lambda: w3 * (I1 - I3) / I1,
    check=_check_3_36,
))


def _printed_3_37() -> sp.Matrix:
    return omega0 * sp.Matrix([sp.sin(Omega * t), sp.cos(Omega * t)])


def _residual_of_symmetric_top(f) -> sp.Matrix:
    """d/dt (ω1, ω2) minus the symmetric top's (ω̇1, ω̇2) evaluated on the candidate, with Ω of (3.36) substituted."""
    m = _m()
    cand = sp.Matrix(f).subs(Omega, m.symmetric_precession_rate)
    rhs = m.symmetric_rhs[:2, :].subs({w1: cand[0], w2: cand[1]}, simultaneous=True)
    return cand.diff(t) - rhs


register(Claim(
    "3.37", "3.4.1",
    "(ω1, ω2) = ω0(sin Ωt, cos Ωt) solves the symmetric top's equations for any constant ω0",
    "symbolic",
    printed=_printed_3_37,
    check=lambda f: same(_residual_of_symmetric_top(f), sp.zeros(2, 1), "residual of (3.35)"),
))


def _check_3_37_general(f) -> Outcome:
    # Every initial value is (ω1, ω2)(0) = ω0(sin α, cos α) (polar coordinates, ω0 >= 0): the derived
    # general solution from it must equal the printed one shifted in time by α/Ω.
    general = _m().symmetric_general_solution.subs(
        dict(zip(ft.initial_omega, (omega0 * sp.sin(alpha), omega0 * sp.cos(alpha)))), simultaneous=True)
    shifted = sp.expand(sp.Matrix(f).subs(t, t + alpha / Omega))  # sin(Ω(t + α/Ω)) → sin(Ωt + α)
    return same(shifted, general, "exp(tM)·ω0(sin α, cos α) vs (3.37) at t + α/Ω")


register(Claim(
    "3.37 general", "3.4.1",
    "(3.37) is the general solution up to a phase: exp(tM)·(ω1, ω2)(0) = ω0(sin(Ωt + α), cos(Ωt + α))",
    "symbolic",
    printed=_printed_3_37,
    check=_check_3_37_general,
))

# ----------------------------------------------------------------------------- 3.4.2: the Earth's wobble


def _earth_precession(spin: sp.Expr) -> sp.Expr:
    """(3.36)'s derived Ω with (I1 - I3)/I1 = -1/300 (3.38), i.e. I3 = (301/300) I1, and ω3 = ``spin``."""
    return _m().symmetric_precession_rate.subs({I3: I1 * sp.Rational(301, 300), w3: spin})


register(Claim(
    "3.39", "3.4.2",
    "with (I1 - I3)/I1 = -1/300 (3.38) and ω3 = (1 day)⁻¹, |Ω_earth| = 1/300 day⁻¹ "
    "(Ω itself is -ω3/300: in the body frame the wobble turns against the spin)",
    "symbolic",
    printed=lambda: sp.Rational(1, 300),
    check=lambda f: same(f, sp.Abs(_earth_precession(sp.Integer(1))), "|Ω| in day⁻¹ at ω3 = 1 day⁻¹"),
))

register(Claim(
    "3.39 period", "3.4.2",
    "\"a wobble every 300 days\": the period 2π/|Ω| is 300 days when ω3 is one turn per day (2π rad/day); "
    "with ω3 = 1 rad/day it would be 600π ≈ 1885 days",
    "symbolic",
    printed=lambda: sp.Integer(300),
    check=lambda f: same(f, 2 * sp.pi / sp.Abs(_earth_precession(2 * sp.pi)), "2π/|Ω| in days at ω3 = 2π/day"),
))

# ----------------------------------------------------------------------------- 3.4.3: stability


register(Claim(
    "3.40", "3.4.3",
    "ω = (Ω, 0, 0), spin about a principal axis, solves Euler's equations",
    "symbolic",
    printed=lambda: sp.Matrix([Omega, 0, 0]),
    check=lambda f: same(_m().free_rhs.subs(dict(zip((w1, w2, w3), f)), simultaneous=True), sp.zeros(3, 1),
                         "ω̇ at the candidate"),
    perturbed=lambda: sp.Matrix([Omega, Omega / 7, 0]),  # any (Ω', 0, 0) is steady: tilt it instead
))

register(Claim(
    "3.42 and 3.43", "3.4.3",
    "to first order in η: I1η̇1 = 0, I2η̇2 = Ωη3(I3 - I1), I3η̇3 = Ωη2(I1 - I2)",
    "symbolic",
    printed=lambda: sp.Matrix([0, Omega * eta3 * (I3 - I1), Omega * eta2 * (I1 - I2)]),
    check=lambda f: same(f, _m().linearised_axis1, "(I1η̇1, I2η̇2, I3η̇3) at order ε"),
))


def _printed_A() -> sp.Expr:
    return Omega**2 / I3 * (I3 - I1) * (I1 - I2)


register(Claim(
    "3.44", "3.4.3",
    "eliminating η3: I2η̈2 = A η2 with A = (Ω²/I3)(I3 - I1)(I1 - I2)",
    "symbolic",
    printed=_printed_A,
    check=lambda f: all_pass([same(f, _m().stability_coefficient, "A by elimination of η3"),
                              same(f, _m().axis_stability_coefficients[0], "A = I2·(-c2) of det(λ - J)")]),
))


def _check_eigenvalues(f) -> Outcome:
    lam = ft.lam
    w = ft.omega_symbols()
    derived = _m().characteristic_polynomial.as_expr().subs({w[0]: Omega, w[1]: 0, w[2]: 0})
    candidate = sp.Mul(*[lam - r for r in f])
    return same(sp.expand(candidate), sp.expand(derived), "Π(λ - λ_i) vs det(λ - J) at ω = Ωe1")


register(Claim(
    "3.44 fate", "3.4.3",
    "the linearised motion about (3.40) has exponents 0, ±√(A/I2): oscillation if A < 0, exponential growth if A > 0",
    "symbolic",
    printed=lambda: (sp.Integer(0), sp.sqrt(_printed_A() / I2), -sp.sqrt(_printed_A() / I2)),
    check=_check_eigenvalues,
    parts=("0", "+√(A/I2)", "−√(A/I2)"),
))


def _check_3_45(f) -> Outcome:
    # Every assignment of the values 1, 2, 3 to (I1, I2, I3), repeats allowed (27 cases, all orderings
    # including equal moments): the printed condition must hold exactly when A > 0.
    A = _m().stability_coefficient.subs(Omega, 1)
    for values in itertools.product((1, 2, 3), repeat=3):
        point = dict(zip((I1, I2, I3), values))
        want = bool(A.subs(point) > 0)
        got = bool(f.subs(point))
        if got != want:
            return Outcome(False, f"at (I1, I2, I3) = {values}: condition says {got}, A = {A.subs(point)}")
    return Outcome(True, "matches A > 0 for all 27 assignments of 1, 2, 3 to (I1, I2, I3)")


register(Claim(
    "3.45", "3.4.3",
    "spin about e1 is unstable (A > 0) iff I2 < I1 < I3 or I3 < I1 < I2",
    "symbolic",
    printed=lambda: sp.Or(sp.And(I2 < I1, I1 < I3), sp.And(I3 < I1, I1 < I2)),
    check=_check_3_45,
    perturbed=lambda: sp.And(I2 < I1, I1 < I3),  # half the condition
))


def _check_3_45_generic(f) -> Outcome:
    # The generic linearization (mechderive.core.linearize) of Euler's equations about ω = (Ω, 0, 0):
    # det(λ − J) = λ(λ² + ω²); the printed condition must hold exactly where ω² < 0 (a growing mode),
    # on all 27 assignments of 1, 2, 3 (ω² = 0, equal moments, is marginal: neither).
    from ..core.linearize import linearize_first_order

    lin = linearize_first_order(_m().free_rhs, (w1, w2, w3), {w1: Omega, w2: 0, w3: 0})
    if len(lin.squared_frequencies) != 1:
        return Outcome(False, f"expected one oscillation pair, got ω² = {lin.squared_frequencies}")
    (w_sq,) = lin.squared_frequencies
    for values in itertools.product((1, 2, 3), repeat=3):
        point = dict(zip((I1, I2, I3), values))
        grows = bool(w_sq.subs(point).subs(Omega, 1) < 0)
        if grows != bool(f.subs(point)):
            return Outcome(False, f"at (I1, I2, I3) = {values}: ω² = {w_sq.subs(point)} Ω², the condition says "
                                  f"{bool(f.subs(point))}")
    return Outcome(True, f"ω² = {w_sq} from the generic linearization: negative exactly where the condition "
                         "holds, on all 27 assignments of 1, 2, 3")


register(Claim(
    "3.45 generic", "3.4.3",
    "spin about e1 is unstable iff I2 < I1 < I3 or I3 < I1 < I2 — from the generic linearization of (3.33)",
    "symbolic",
    printed=lambda: sp.Or(sp.And(I2 < I1, I1 < I3), sp.And(I3 < I1, I1 < I2)),
    check=_check_3_45_generic,
    perturbed=lambda: sp.And(I2 < I1, I1 < I3),
))


def _check_axes(f) -> Outcome:
    from ..systems.free_top.stability import principal_axis_stability

    for moments in itertools.permutations((2.0, 3.0, 4.0)):
        got = principal_axis_stability(*moments)
        order = sorted(range(3), key=lambda k: moments[k])
        roles = {"smallest": order[0] + 1, "intermediate": order[1] + 1, "largest": order[2] + 1}
        for role, axis in roles.items():
            if f[role] != got[axis]:
                return Outcome(False, f"I = {moments}: the {role} axis {axis} is {got[axis]}, claimed {f[role]}")
    return Outcome(True, "all 6 orderings of (2, 3, 4): signs of s_a = (I_a - I_b)(I_c - I_a)/(I_b I_c)")


register(Claim(
    "3.45 axes", "3.4.3",
    "a body rotates stably about the axes of largest and smallest moment, unstably about the intermediate one",
    "numeric",
    printed=lambda: {"largest": "stable", "intermediate": "unstable", "smallest": "stable"},
    check=_check_axes,
    perturbed=lambda: {"largest": "unstable", "intermediate": "stable", "smallest": "unstable"},  # each flipped
    parts=("largest", "intermediate", "smallest"),
))

# ----------------------------------------------------------------------------- 3.4.4: Poinsot


def _two_T() -> sp.Expr:
    return I1 * w1**2 + I2 * w2**2 + I3 * w3**2


register(Claim(
    "3.46", "3.4.4",
    "2T = I1ω1² + I2ω2² + I3ω3²",
    "symbolic",
    printed=_two_T,
    check=lambda f: same(f, 2 * _m().energy, "2T = ω_a I_ab ω_b"),
))

register(Claim(
    "3.47", "3.4.4",
    "L² = I1²ω1² + I2²ω2² + I3²ω3²",
    "symbolic",
    printed=lambda: I1**2 * w1**2 + I2**2 * w2**2 + I3**2 * w3**2,
    check=lambda f: same(f, _m().angular_momentum_squared, "L_a L_a"),
))

register(Claim(
    "3.46 and 3.47 conserved", "3.4.4",
    "T and L² are constants of motion: dT/dt = 0 and dL²/dt = 0 along Euler's equations",
    "symbolic",
    printed=lambda: sp.Matrix([0, 0]),
    check=lambda f: same(f, sp.Matrix([_m().energy_rate, _m().angular_momentum_squared_rate]),
                         "(dT/dt, dL²/dt) on Euler's equations"),
))

register(Claim(
    "3.48", "3.4.4",
    "the inertia ellipsoid: (I1/2T)ω1² + (I2/2T)ω2² + (I3/2T)ω3² = 1",
    "symbolic",
    printed=lambda: sp.Eq(I1 / (2 * T) * w1**2 + I2 / (2 * T) * w2**2 + I3 / (2 * T) * w3**2, 1, evaluate=False),
    check=lambda f: same(f.lhs.subs(T, _m().energy), f.rhs, "LHS at T = ½ω_aI_abω_b"),
))

register(Claim(
    "3.49", "3.4.4",
    "L = ∇_ω T (so L is normal to the inertia ellipsoid, a level surface of T)",
    "symbolic",
    printed=lambda: sp.Matrix([sp.diff(_two_T() / 2, wa) for wa in (w1, w2, w3)]),
    check=lambda f: same(f, to_state_symbols(_m().angular_momentum_body), "L_a = I_ab ω_b"),
))


def _check_invariable_plane(f) -> Outcome:
    m = _m()
    projection = m.omega_dot_angular_momentum / sp.sqrt(m.angular_momentum_squared)
    rate = sum(sp.diff(projection, wa) * m.free_rhs[a] for a, wa in enumerate((w1, w2, w3)))
    return all_pass([same(f, projection, "ω·L/|L|"), same(sp.simplify(rate), 0, "d(ω·L/|L|)/dt on Euler's equations")])


register(Claim(
    "3.49 invariable plane", "3.4.4",
    "2T = L·ω, so ω's projection on the fixed L, 2T/|L|, is constant: ω moves in a plane ⟂ L "
    "(the centre of the inertia ellipsoid stays at distance 2T/|L| from it)",
    "symbolic",
    printed=lambda: _two_T() / sp.sqrt(I1**2 * w1**2 + I2**2 * w2**2 + I3**2 * w3**2),
    check=_check_invariable_plane,
))
