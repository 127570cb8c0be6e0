"""Section 3.6: the heavy symmetric top's derived model (mechderive.systems.heavy_top.model).

Independent references: SymPy's own mechanics (sympy.physics.mechanics: a RigidBody oriented
body-fixed 'ZXZ', LagrangesMethod); Euler's equations with the gravity torque (Newton–Euler,
NumPy cross products) against ω̇ by central differences of ω along the derived motion; SciPy's
solve_ivp (DOP853, rtol 1e-12) for conservation laws and the qualitative claims; numpy.roots
on the derived f(u); the gyroscope's slow precession Mgl/(I3ω3) for a fast top.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from mechderive.core.compile import compile_expressions
from mechderive.core.simplify import is_zero
from mechderive.core.symbols import coordinate, state_symbol
from mechderive.kinematics import euler
from mechderive.systems.heavy_top import model as ht
from mechderive.systems.heavy_top.model import HeavyTopModel

ARGS = [*ht.PARAMETERS, *ht.STATE]
STATE6 = [state_symbol(n) for n in ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")]
PARAMS = (1.0, 0.6, 1.0, 9.81, 0.1)  # I1, I3, M, g, l (Mgl = 0.981)


def _rhs():
    return ht.model().ode_rhs(ht.PARAMETERS)


def _integrate(y0, t_end, params=PARAMS, **kw):
    opts = dict(method="DOP853", rtol=1e-12, atol=1e-12)
    opts.update(kw)
    return solve_ivp(_rhs(), (0.0, t_end), y0, args=params, **opts)


def _random_states(rng, n):
    """Rows (φ, θ, ψ, φ̇, θ̇, ψ̇) away from sin θ = 0, and parameter rows (I1, I3, M, g, l)."""
    y = np.column_stack([rng.uniform(-3, 3, n), rng.uniform(0.2, np.pi - 0.2, n), rng.uniform(-3, 3, n),
                         rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), rng.uniform(-15, 15, n)])
    p = np.column_stack([rng.uniform(0.5, 2, n), rng.uniform(0.2, 2, n), rng.uniform(0.5, 2, n),
                         rng.uniform(1, 10, n), rng.uniform(0.1, 1, n)])
    return y, p


# --- laziness ----------------------------------------------------------------------------------

def test_f_u_derives_nothing_of_the_equations_of_motion():
    m = HeavyTopModel()
    _ = m.f_u
    for name in ("accelerations", "mass_matrix", "forcing", "euler_lagrange", "energy", "energy_function",
                 "precession_rates", "sleeping_f", "routhian"):  # the Routhian's normal form, not its readable one
        assert not m.is_derived(name), name
    assert "routhian_normal" in m.derived and "kinetic_energy" in m.derived


def test_f_u_and_rates_in_u_skip_the_readable_theta_forms():
    # f(u) and φ̇(u), ψ̇(u) are taken from what the Routhian and the momenta give, not from the readable E' (3.69)
    # and (3.67)-(3.68) brought back to u (a cold run's time): the readable forms are derived only when asked for
    m = HeavyTopModel()
    _ = m.f_u, m.precession_rate_u, m.spin_rate_u
    for name in ("reduced_energy", "precession_rate_theta", "spin_rate_theta"):
        assert not m.is_derived(name), name


def test_accelerations_derive_nothing_of_the_reduction():
    m = HeavyTopModel()
    _ = m.accelerations
    for name in ("routhian", "cyclic_coordinates", "f_u", "effective_potential"):
        assert not m.is_derived(name), name


def test_uniform_precession_needs_only_f():
    m = HeavyTopModel()
    _ = m.precession_rates
    assert not m.is_derived("accelerations") and not m.is_derived("sleeping_f")


# --- (3.62): the Lagrangian and the equations of motion against independent derivations ---------

def _sympy_mechanics_top():
    """The top built with sympy.physics.mechanics, numerically: q̈(q, q̇, params).

    Convention map: B.orient_body_fixed(N, (q1, q2, q3), 'ZXZ') turns B from N by q1 about N.z, then q2
    about the new x, then q3 about the new z; B.dcm(N)[a, b] = b_a · n_b.  With e_a = b_a and ẽ_b = n_b
    that is our R_ab = e_a · ẽ_b, so (q1, q2, q3) = (φ, θ, ψ) exactly (checked in the next test).
    """
    from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)
    from sympy.physics.vector import dot

    I1, I3, M, g, l = ht.PARAMETERS
    q = dynamicsymbols("q1 q2 q3")
    N, B = ReferenceFrame("N"), ReferenceFrame("B")
    B.orient_body_fixed(N, q, "ZXZ")
    P = Point("P")
    P.set_vel(N, 0)
    C = P.locatenew("C", l * B.z)
    C.v2pt_theory(P, N, B)
    body = RigidBody("top", C, B, M, (inertia(B, I1, I1, I3), P))  # moments about the pivot P
    body.potential_energy = M * g * dot(C.pos_from(P), N.z)
    lm = LagrangesMethod(Lagrangian(N, body), q)
    lm.form_lagranges_equations()
    qd = [x.diff(dynamicsymbols._t) for x in q]
    plain = sp.symbols("x1:7")
    subs = dict(zip(qd + list(q), plain[3:] + plain[:3]))
    mm = sp.lambdify([*plain, *ht.PARAMETERS], lm.mass_matrix.subs(subs))
    ff = sp.lambdify([*plain, *ht.PARAMETERS], lm.forcing.subs(subs))
    return (lambda y, p: np.linalg.solve(np.array(mm(*y, *p), dtype=float), np.array(ff(*y, *p), dtype=float).ravel())), B, N, q


def test_sympy_mechanics_zxz_frame_is_our_rotation():
    _, B, N, q = _sympy_mechanics_top()
    ours = euler.euler_rotation(*q)
    assert all(is_zero(e) for e in (B.dcm(N) - ours))


def test_accelerations_match_sympy_mechanics_lagranges_method(rng):
    reference, *_ = _sympy_mechanics_top()
    acc = compile_expressions(list(ht.model().accelerations), [*STATE6, *ht.PARAMETERS], name="ht_acc_test")
    ys, ps = _random_states(rng, 50)
    for y, p in zip(ys, ps):
        ref = reference(y, p)
        # two exact formulas evaluated in double precision; sin θ ≥ sin 0.2 keeps the condition modest
        np.testing.assert_allclose(acc(*y, *p), ref, rtol=1e-10, atol=1e-10 * np.max(np.abs(ref)))


def test_accelerations_satisfy_eulers_equations_with_gravity_torque(rng):
    # I ω̇ + ω × Iω = τ, τ = (l e3) × (−Mg ẽ3) in body components, ẽ3 = column 3 of R.
    # ω̇ by a central difference of ω over ±h along the derived motion: error O(h²) ≈ 1e-8 at h = 1e-4.
    ys, ps = _random_states(rng, 8)
    h = 1e-4
    for y, p in zip(ys, ps):
        I1, I3, M, g, l = p
        ends = [_integrate(y, s * h, params=tuple(p), rtol=1e-13, atol=1e-14).y[:, -1] for s in (1, -1)]
        w_plus, w_minus = (euler.angular_velocity_body(*e) for e in ends)
        w_dot = (w_plus - w_minus) / (2 * h)
        w = euler.angular_velocity_body(*y)
        inertia = np.array([I1, I1, I3])
        e3_space = euler.rotation_matrix(*y[:3])[:, 2]
        torque = np.cross([0.0, 0.0, l], -M * g * e3_space)
        residual = inertia * w_dot + np.cross(w, inertia * w) - torque
        assert np.max(np.abs(residual)) < 1e-6 * (1 + np.max(np.abs(torque)) + np.max(np.abs(inertia * w)))


def test_lagrangian_is_t_minus_v_of_the_kinematics():
    m = ht.model()
    w = euler.model().state_angular_velocity_body
    T = (w.T * sp.diag(ht.I1, ht.I1, ht.I3) * w)[0] / 2
    V = ht.M * ht.g * ht.l * sp.cos(state_symbol("theta"))
    assert is_zero(m.state_lagrangian - (T - V))
    assert m.cyclic_coordinates == (coordinate("phi"), coordinate("psi"))


# --- (3.63)-(3.65): conservation along the motion ----------------------------------------------

def test_energy_and_momenta_conserved_along_solve_ivp():
    m = ht.model()
    y0 = [0.0, 0.7, 0.0, 0.4, 1.1, 12.0]
    sol = _integrate(y0, 10.0)
    inv = m.invariants_function()(*PARAMS, sol.y[1], sol.y[4], sol.y[3], sol.y[5])  # (N, 3): E, p_φ, p_ψ
    drift = np.max(np.abs(inv - inv[0]), axis=0) / np.abs(inv[0])
    # rtol 1e-12 per step over a few thousand steps: relative drift stays below 1e-10
    assert np.all(drift < 1e-10), drift


# --- (3.66)-(3.76): the reduction to θ and f(u) -------------------------------------------------

def test_rates_from_a_b_reproduce_the_state(rng):
    m = ht.model()
    ab = compile_expressions([m.constants_from_state[ht.a], m.constants_from_state[ht.b]], ARGS, name="ab_test")
    rate_phi = compile_expressions(m.precession_rate_u, [ht.a, ht.b, ht.u], name="phi_dot_u")
    rate_psi = compile_expressions(m.spin_rate_u, [ht.I1, ht.I3, ht.a, ht.b, ht.u], name="psi_dot_u")
    ys, ps = _random_states(rng, 200)
    a, b = ab(*ps.T, ys[:, 1], ys[:, 4], ys[:, 3], ys[:, 5]).T
    u = np.cos(ys[:, 1])
    np.testing.assert_allclose(rate_phi(a, b, u), ys[:, 3], rtol=1e-9, atol=1e-9)  # (3.74); 1/sin²θ ≤ 25
    np.testing.assert_allclose(rate_psi(ps[:, 0], ps[:, 1], a, b, u), ys[:, 5], rtol=1e-9, atol=1e-9)  # (3.75)


def test_f_of_cos_theta_is_u_dot_squared(rng):
    f = ht.model().f_coefficients_function()
    ys, ps = _random_states(rng, 200)
    coeffs = f(*ps.T, ys[:, 1], ys[:, 4], ys[:, 3], ys[:, 5])
    u = np.cos(ys[:, 1])
    value = np.einsum("nk,nk->n", coeffs, np.column_stack([u**3, u**2, u, np.ones_like(u)]))
    # coefficients up to ~1e3 (ψ̇² I3²/I1²) cancel to u̇² = O(10): 1e-9 absolute is ~1e4 ulps of them
    np.testing.assert_allclose(value, np.sin(ys[:, 1]) ** 2 * ys[:, 4] ** 2, rtol=1e-9, atol=1e-9)


def test_f_is_nonnegative_and_u_stays_between_its_roots_along_the_motion():
    m = ht.model()
    y0 = [0.0, 0.8, 0.0, 1.5, 0.9, 9.0]
    coeffs = m.f_coefficients_function()(*PARAMS, y0[1], y0[4], y0[3], y0[5])
    roots = np.sort(np.roots(coeffs).real)
    u1, u2, u3 = roots
    assert -1 < u1 < np.cos(y0[1]) < u2 < 1 < u3
    sol = _integrate(y0, 10.0)
    u = np.cos(sol.y[1])
    f_along = np.polyval(coeffs, u)
    # f ≥ 0 up to rounding of a cubic with O(10) coefficients; u confined to [u1, u2] likewise
    assert np.min(f_along) > -1e-9
    assert np.min(u) > u1 - 1e-9 and np.max(u) < u2 + 1e-9
    # both turning points are reached (the motion fills [u1, u2])
    assert np.min(u) < u1 + 1e-3 and np.max(u) > u2 - 1e-3
    # and u̇² = f(u) along it (same coefficients: E', a, b are constants)
    u_dot = -np.sin(sol.y[1]) * sol.y[4]
    np.testing.assert_allclose(u_dot**2, f_along, atol=1e-8)


def test_released_top_falls_and_precesses_with_its_spin():
    m = ht.model()
    y0 = [0.0, 0.5, 0.0, 0.0, 0.0, 15.0]  # θ̇ = φ̇ = 0, spin ω3 > 0
    coeffs = m.f_coefficients_function()(*PARAMS, y0[1], y0[4], y0[3], y0[5])
    assert abs(np.polyval(coeffs, np.cos(0.5))) < 1e-12  # f(u0) = 0 (3.77)
    sol = _integrate(y0, 5.0)
    assert np.all(sol.y[1] >= 0.5 - 1e-10)  # θ only increases from θ0: u0 is the upper root u2
    assert np.all(sol.y[3][1:] >= -1e-9)  # φ̇ ≥ 0, the sense of the spin (motion of the third kind)
    assert np.max(sol.y[3]) > 0.01


# --- (3.79)-(3.81): uniform precession ---------------------------------------------------------

def _rates(params, spin, th0):
    slow, fast = ht.model().precession_rates
    f = compile_expressions([slow, fast], [*ht.PARAMETERS, ht.omega3, ht.theta0], name="precession_rates")
    return f(*params, spin, th0)


@pytest.mark.parametrize("which", [0, 1], ids=["slow", "fast"])
def test_uniform_precession_keeps_theta_constant(which):
    spin, th0 = 20.0, 0.6
    rate = _rates(PARAMS, spin, th0)[which]
    y0 = [0.0, th0, 0.0, rate, 0.0, spin - rate * np.cos(th0)]
    sol = _integrate(y0, 10.0)
    assert np.max(np.abs(sol.y[1] - th0)) < 1e-9  # integration error only
    # a rate 1 % off nutates visibly
    y_off = [0.0, th0, 0.0, 1.01 * rate, 0.0, spin - 1.01 * rate * np.cos(th0)]
    assert np.max(np.abs(_integrate(y_off, 10.0).y[1] - th0)) > 1e-5


def test_slow_precession_approaches_the_gyroscope_rate():
    # fast top: φ̇_slow = Mgl/(I3ω3) (1 + O(ε)), ε = I1 Mgl cos θ0/(I3ω3)²
    I1, I3, M, g, l = PARAMS
    for spin in (50.0, 500.0):
        slow, fast = _rates(PARAMS, spin, 0.6)
        eps = I1 * M * g * l * np.cos(0.6) / (I3 * spin) ** 2
        assert abs(slow * I3 * spin / (M * g * l) - 1) < 2 * eps
        assert abs(fast * I1 * np.cos(0.6) / (I3 * spin) - 1) < 2 * eps


def test_minimum_spin_is_where_the_rates_merge():
    m = ht.model()
    th0 = 0.6
    w_min = float(m.minimum_spin.subs(dict(zip(ht.PARAMETERS, PARAMS))).subs(ht.theta0, th0))
    disc = compile_expressions(m.precession_discriminant, [*ht.PARAMETERS, ht.omega3, ht.theta0], name="disc")
    assert abs(disc(*PARAMS, w_min, th0)) < 1e-12
    assert disc(*PARAMS, 1.001 * w_min, th0) > 0 > disc(*PARAMS, 0.999 * w_min, th0)


def test_hanging_top_precesses_uniformly_even_without_a_fast_spin():
    # θ0 > π/2: (3.81)'s root would be imaginary; the rates are real for a spin far below
    # 2√(I1 Mgl |cos θ0|)/I3, of opposite signs, and each keeps θ fixed.
    I1, I3, M, g, l = PARAMS
    th0, spin = 2.2, 0.05 * 2 * np.sqrt(I1 * M * g * l * abs(np.cos(2.2))) / I3
    slow, fast = _rates(PARAMS, spin, th0)
    assert np.isfinite(slow) and np.isfinite(fast) and slow * fast < 0
    for rate in (slow, fast):
        sol = _integrate([0.0, th0, 0.0, rate, 0.0, spin - rate * np.cos(th0)], 10.0)
        assert np.max(np.abs(sol.y[1] - th0)) < 1e-9


# --- (3.82)-(3.83): the sleeping top ------------------------------------------------------------

@pytest.mark.parametrize("factor, stays_up", [(1.05, True), (0.95, False)])
def test_sleeping_top_threshold(factor, stays_up):
    # near upright (θ = 1e-3), released: above I3ω3 = 2√(I1Mgl) θ stays small; below it the top falls
    m = ht.model()
    crit = float(m.sleeping_threshold_spin.subs(dict(zip(ht.PARAMETERS, PARAMS))))
    sol = _integrate([0.0, 1e-3, 0.0, 0.0, 0.0, factor * crit], 20.0, rtol=1e-10, max_step=0.02)
    # bounds from f: u2 − 1 ≈ ±0.1, so the far turning point is θ ≈ 0.004 (stable) or ≈ 0.45 (falls)
    assert (np.max(sol.y[1]) < 0.05) == stays_up


def test_sleeping_top_second_root_in_the_spin():
    m = ht.model()
    I1, I3, M, g, l = ht.PARAMETERS
    u2 = m.sleeping_second_root_spin
    assert sp.simplify(u2 - (I3**2 * ht.omega3**2 / (2 * I1 * M * g * l) - 1)) == 0
    assert sp.simplify(u2.subs(ht.omega3, m.sleeping_threshold_spin) - 1) == 0


def test_sleeping_constants_from_the_upright_state():
    # θ = θ̇ = 0 numerically: a = b and α = β whatever φ̇ and ψ̇
    m = ht.model()
    f = compile_expressions([m.constants_from_state[s] for s in (ht.a, ht.b, ht.alpha, ht.beta)], ARGS, name="abab")
    a, b, alpha, beta = f(*PARAMS, 0.0, 0.0, 0.7, 11.0)
    assert abs(a - b) < 1e-14 * abs(a) and abs(alpha - beta) < 1e-14 * abs(beta)


def test_partial_fractions_by_residues_are_sympys_apart():
    # the rates' partial fractions in u by residues at distinct linear poles: sympy.apart's expression (srepr)
    u, a, b, I1, I3 = ht.u, ht.a, ht.b, ht.I1, ht.I3
    cases = [(b - a * u) / (1 - u**2), (a - b * u) / (1 - u**2) + a * (I1 - I3) / I3,
             (a * u**3 + b) / ((2 * u - 1) * (u + 3) * (I1 * u - a)), (u**2 + a) / ((u - a) * (u + b)),
             (a * u + 1) / ((u - 1) ** 2 * (u + 2)), (u + b) / (u**2 + 1), a / (u - b), sp.Integer(3)]
    for rate in cases:
        rate = sp.together(rate)
        assert sp.srepr(ht._apart(rate, u)) == sp.srepr(sp.apart(rate, u)), rate
