"""Catalog entries for section 3.5.3: the free symmetric top in Euler angles, (3.59)–(3.61).

Derivation compared against (:meth:`FreeTopModel.symmetric_top_euler_rates`): with L = L ẽ3,
the body components are L_a = L R_a3 (column 3 of R(φ, θ, ψ), (3.54)); equating them to
(I1ω1, I1ω2, I3ω3) with ω from (3.58) (derived from ṘRᵀ) and solving gives θ̇ = 0,
φ̇ = L/I1, ψ̇ = L cos θ (I1 - I3)/(I1 I3); with L cos θ = L_3 = I3 ω3 these are ψ̇ = Ω and
(3.60).

The wobbling plate (3.61).  Two rates are compared: the *wobble* φ̇, the precession of
the plate's axis e3 about L, and the *spin* ψ̇, the plate's rotation about e3 relative to
the line of nodes.  For a disc (I3 = 2 I1) ψ̇ = -ω3 and φ̇/ψ̇ = -2/cos θ exactly, so
φ̇ ≈ -2ψ̇ holds to first order in θ (relative error 1/cos θ - 1 = θ²/2 + 5θ⁴/24 + ...):
the wobble is twice the spin, in the opposite sense — the reverse of Feynman's recollection
that the medallion went round twice as fast as the wobble.  (Seen from the space frame a
body point near e3 goes round at about φ̇ + ψ̇ = ω3(2/cos θ - 1) ≈ ω3, again half the wobble.)
For any symmetric top φ̇/ψ̇ = I3/((I1 - I3) cos θ).
"""

from __future__ import annotations

import sympy as sp

from ..core.symbols import state_symbol, t
from ..kinematics import euler
from ..systems.free_top import model as ft
from .checks import all_pass, same
from .registry import Claim, Outcome, register

SECTION = "3.5.3"
I1, I3, L = ft.I1, ft.I3, ft.L
w1, w2, w3 = ft.omega_symbols()
theta, psi = state_symbol("theta"), state_symbol("psi")
phi_dot, theta_dot, psi_dot = (state_symbol(n) for n in ("phi_dot", "theta_dot", "psi_dot"))
omega0 = sp.Symbol("omega0", positive=True)


def _m() -> ft.FreeTopModel:
    return ft.model()


def _rates() -> dict:
    return _m().symmetric_top_euler_rates_spin


def _printed_precession() -> sp.Expr:
    return w3 * (I1 - I3) / I1


def _printed_3_59() -> sp.Matrix:
    return omega0 * sp.Matrix([sp.sin(_printed_precession() * t), sp.cos(_printed_precession() * t)])


def _check_3_59(f) -> Outcome:
    m = _m()
    cand = sp.Matrix(f)
    # (a) it solves the symmetric top's equations (derived from Euler's equations with I2 = I1)
    rhs = m.symmetric_rhs[:2, :].subs({w1: cand[0], w2: cand[1]}, simultaneous=True)
    solves = same(cand.diff(t) - rhs, sp.zeros(2, 1), "residual of (3.35)")
    # (b) it is what the space-frame solution gives: ω1, ω2 of (3.58) at the derived rates, ψ = Ωt
    rates = m.symmetric_top_euler_rates
    w_ea = euler.model().state_angular_velocity_body[:2, :].subs(rates).subs(psi, rates[psi_dot] * t)
    spin_of_L = L * sp.cos(theta) / I3  # L_3 = I3 ω3
    seen = same(cand.subs({omega0: L * sp.sin(theta) / I1, w3: spin_of_L}), w_ea,
                "(ω1, ω2) from Euler angles with ψ = Ωt, ω0 = L sin θ/I1")
    return all_pass([solves, seen])


register(Claim(
    "3.59", SECTION,
    "(ω1, ω2) = ω0(sin Ωt, cos Ωt), Ω = ω3(I1 - I3)/I1; in Euler angles with L along ẽ3 this is "
    "ψ = Ωt and ω0 = L sin θ/I1",
    "symbolic",
    printed=_printed_3_59,
    check=_check_3_59,
))


def _check_theta_dot(f) -> Outcome:
    m = _m()
    # the angle between L and e3: cos∠ = L_3/L = R33 = cos θ, constant because L_3 = I3ω3 is
    return all_pass([same(f, _rates()[theta_dot], "θ̇ solved from I ω = L·(column 3 of R)"),
                     same(m.fixed_L_body_components[2] / L, sp.cos(theta), "L̂·e3 = cos θ")])


register(Claim(
    "3.59 theta", SECTION,
    "with L along ẽ3, θ is the angle between L and e3 and θ̇ = 0",
    "symbolic",
    printed=lambda: sp.Integer(0),
    check=_check_theta_dot,
))

register(Claim(
    "3.59 psi", SECTION,
    "ψ̇ = Ω = ω3(I1 - I3)/I1",
    "symbolic",
    printed=_printed_precession,
    check=lambda f: same(f, _rates()[psi_dot], "ψ̇ solved from I ω = L·(column 3 of R)"),
))

register(Claim(
    "3.60", SECTION,
    "the precession rate φ̇ = I3ω3/(I1 cos θ) (= L/I1)",
    "symbolic",
    printed=lambda: I3 * w3 / (I1 * sp.cos(theta)),
    check=lambda f: all_pass([same(f, _rates()[phi_dot], "φ̇ solved from I ω = L·(column 3 of R)"),
                              same(_m().symmetric_top_euler_rates[phi_dot], L / I1, "φ̇ = L/I1")]),
))


def _ratio() -> sp.Expr:
    r = _rates()
    return sp.simplify(r[phi_dot] / r[psi_dot])


register(Claim(
    "3.60 ratio", SECTION,
    "from (3.60) and ψ̇ = Ω: φ̇/ψ̇ = I3/((I1 - I3) cos θ) for any symmetric top",
    "symbolic",
    printed=lambda: (I3 * w3 / (I1 * sp.cos(theta))) / _printed_precession(),
    check=lambda f: same(f, _ratio(), "φ̇/ψ̇ of the derived rates"),
))

register(Claim(
    "3.61 disc spin", SECTION,
    "for a disc (I3 = 2I1) ψ̇ = -ω3",
    "symbolic",
    printed=lambda: -w3,
    check=lambda f: same(f, _rates()[psi_dot].subs(I3, 2 * I1), "ψ̇ at I3 = 2I1"),
))


def _check_3_61(f) -> Outcome:
    exact = sp.simplify(_ratio().subs(I3, 2 * I1))  # -2/cos θ
    excess = sp.series(exact / f - 1, theta, 0, 5).removeO()
    limit = same(sp.limit(exact, theta, 0), f, "lim θ→0 of φ̇/ψ̇ at I3 = 2I1")
    if not limit.passed:
        return limit
    # the approximation's error must be second order in θ (no linear term)
    if sp.simplify(excess.coeff(theta, 1)) != 0 or sp.simplify(excess.coeff(theta, 0)) != 0:
        return Outcome(False, f"relative error {excess} is not O(θ²)")
    at = {d: float(exact.subs(theta, sp.pi * d / 180) / f - 1) for d in (10, 30)}
    return Outcome(True, f"exact ratio {exact}; relative excess {excess} + O(θ⁶) "
                         f"({at[10]:.2%} at 10°, {at[30]:.1%} at 30°)")


register(Claim(
    "3.61", SECTION,
    "wobbling plate: φ̇ ≈ -2ψ̇ for slight θ — the wobble φ̇ (precession of e3 about L) is twice the spin "
    "|ψ̇| = ω3 (rotation about e3 relative to the line of nodes), opposite in sense, contrary to Feynman's story",
    "symbolic",
    printed=lambda: sp.Integer(-2),
    check=_check_3_61,
))
