"""Numerical integration of the heavy symmetric top (3.62)–(3.83), checked from independent angles.

References: a 30-digit mpmath Taylor integration (mpmath.odefun) of Euler's equations with the gravity
torque and q̇ = ½ q ⊗ (0, ω), typed in here from the chapter; the Euler-angle equations derived
independently with sympy.physics.mechanics (LagrangesMethod, body-fixed 'ZXZ'); the nutation range and
period from the cubic f(u) of (3.73) by mpmath root-finding and quadrature; the sleeping-top criterion
(3.83); the free top's integrator (g = 0); measured orders of convergence.

The BASELINE case (I1 = 1, I3 = 0.5 about the pivot, M g l = 1) is realised by M = 1, g = 4, l = 0.25:
with M = g = l = 1 the moments about the centre of mass would be I1_cm = 0 < I3/2 (no body has them),
which :func:`check_params` refuses; the motion depends on M g l only (checked below).
"""

from __future__ import annotations

import functools
import math

import mpmath
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from mechderive.core.simplify import is_zero
from mechderive.errors import InvalidInputError, NonFiniteValueError, ShapeError, UnphysicalInertiaError
from mechderive.kinematics.euler import angular_velocity_body, euler_rotation, model as kinematics_model
from mechderive.kinematics.conversions import euler_to_quaternion
from mechderive.solvers import kick_drift
from mechderive.solvers.composition import suzuki_fractal
from mechderive.systems.free_top.integrate import integrate_free_top
from mechderive.systems.free_top.model import omega_symbols
from mechderive.systems.heavy_top import rigid_model
from mechderive.systems.heavy_top.integrate import (INITIAL_KEYS, PARAM_KEYS, _evaluate_invariants, _rhs,
                                                    check_initial, check_params, initial_state, integrate_heavy_top,
                                                    integrate_heavy_top_ensemble)

PARAMS = dict(I1=1.0, I3=0.5, M=1.0, g=4.0, l=0.25)  # M g l = 1
BASE = dict(theta=0.5, psi_dot=5.0)  # BASELINE.md: let go at θ0 = 0.5 with θ̇ = φ̇ = 0, ψ̇ = ω3 = 5
MP_TIMES = (1.0, 2.0, 3.0)


# --- the independent references ----------------------------------------------------------------

@pytest.fixture(scope="session")
def mp_reference() -> np.ndarray:
    """(ω, q) of the BASELINE case at MP_TIMES from mpmath.odefun at 30 digits; shape (3, 7)."""
    with mpmath.workdps(30):
        I1, I3, MGL = mpmath.mpf(1), mpmath.mpf("0.5"), mpmath.mpf(1)

        def F(_t, y):
            w1, w2, w3, q0, q1, q2, q3 = y
            # body components of ẽ3 = third column of R = Aᵀ, A the rotation matrix of the unit quaternion q
            gam = [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), 1 - 2 * (q1**2 + q2**2)]
            # τ = l e3 × F with F = -M g γ (weight, body components)
            tau = [MGL * gam[1], -MGL * gam[0], 0]
            # Euler's equations (3.33) with torque, I2 = I1
            dw = [((I1 - I3) * w2 * w3 + tau[0]) / I1, ((I3 - I1) * w3 * w1 + tau[1]) / I1, tau[2] / I3]
            dq = [-(q1 * w1 + q2 * w2 + q3 * w3) / 2, (q0 * w1 + q2 * w3 - q3 * w2) / 2,
                  (q0 * w2 + q3 * w1 - q1 * w3) / 2, (q0 * w3 + q1 * w2 - q2 * w1) / 2]
            return dw + dq

        # θ0 = 0.5, φ0 = ψ0 = 0: A = Rx(0.5), q = (cos 0.25, sin 0.25, 0, 0); ω = (0, 0, ψ̇) by (3.58)
        y0 = [0, 0, mpmath.mpf(5), mpmath.cos(mpmath.mpf("0.25")), mpmath.sin(mpmath.mpf("0.25")), 0, 0]
        sol = mpmath.odefun(F, 0, y0)
        return np.array([[float(v) for v in sol(mpmath.mpf(t))] for t in MP_TIMES])


def nutation_from_cubic(I1: float, I3: float, mgl: float, theta0: float, theta_dot0: float, phi_dot0: float,
                        psi_dot0: float) -> tuple[float, float, float]:
    """(θ_min, θ_max, period) from f(u) = (1 - u²)(α - βu) - (b - au)² (3.73), 30 digits."""
    with mpmath.workdps(30):
        th, td, pd, sd = (mpmath.mpf(x) for x in (theta0, theta_dot0, phi_dot0, psi_dot0))
        I1, I3, mgl = mpmath.mpf(I1), mpmath.mpf(I3), mpmath.mpf(mgl)
        w3 = sd + pd * mpmath.cos(th)                                            # (3.63)
        p_phi = I1 * mpmath.sin(th) ** 2 * pd + I3 * mpmath.cos(th) * w3          # (3.64)
        E = I1 * (td**2 + pd**2 * mpmath.sin(th) ** 2) / 2 + I3 * w3**2 / 2 + mgl * mpmath.cos(th)  # (3.65)
        a, b = I3 * w3 / I1, p_phi / I1                                          # (3.66)
        alpha, beta = 2 * (E - I3 * w3**2 / 2) / I1, 2 * mgl / I1                # (3.72)
        coeffs = [beta, -(alpha + a * a), 2 * a * b - beta, alpha - b * b]       # f(u) expanded, u³ first
        roots = sorted(mpmath.re(r) for r in mpmath.polyroots(coeffs, extraprec=60))
        u1, u2, u3 = roots  # u1 <= u2 in [-1, 1], u3 > 1 (f(±1) <= 0, f → +∞)
        assert -1 - 1e-25 <= u1 <= u2 <= 1 + 1e-25 < u3
        u1, u2 = max(u1, -1), min(u2, 1)
        # f = β (u - u1)(u2 - u)(u3 - u); with u = u1 + (u2 - u1) sin² s the integral of du/√f is regular:
        # T = 2 ∫_0^{π/2} 2 ds / √(β (u3 - u(s)))
        period = 2 * mpmath.quad(lambda s: 2 / mpmath.sqrt(beta * (u3 - u1 - (u2 - u1) * mpmath.sin(s) ** 2)),
                                 [0, mpmath.pi / 2])
        return float(mpmath.acos(u2)), float(mpmath.acos(u1)), float(period)


@pytest.fixture(scope="session")
def euler_angle_rhs():
    """θ̈, φ̈, ψ̈ from sympy.physics.mechanics (LagrangesMethod), lambdified; and the 'ZXZ' dcm."""
    from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)

    phi, theta, psi = dynamicsymbols("phi theta psi")
    I1, I3, M, g, l = sp.symbols("I1 I3 M g l", positive=True)
    N, B = ReferenceFrame("N"), ReferenceFrame("B")
    B.orient_body_fixed(N, (phi, theta, psi), "ZXZ")
    P = Point("P")
    P.set_vel(N, 0)
    G = P.locatenew("G", l * B.z)
    G.v2pt_theory(P, N, B)
    # inertia about the centre of mass: I1_cm = I1 - M l² (parallel axes), I3_cm = I3
    top = RigidBody("top", G, B, M, (inertia(B, I1 - M * l**2, I1 - M * l**2, I3), G))
    top.potential_energy = M * g * G.pos_from(P).dot(N.z)
    LM = LagrangesMethod(Lagrangian(N, top), [phi, theta, psi])
    LM.form_lagranges_equations()
    qs = [phi, theta, psi]
    us = [q.diff() for q in qs]
    f = sp.lambdify([*qs, *us, I1, I3, M, g, l], list(LM.rhs()), cse=True)
    subs = {phi: sp.Symbol("phi"), theta: sp.Symbol("theta"), psi: sp.Symbol("psi")}
    return f, B.dcm(N).subs(subs)


def integrate_euler_angles(f, params: dict, init: dict, t: np.ndarray) -> np.ndarray:
    y0 = [init.get(k, 0.0) for k in ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")]
    args = [params[k] for k in PARAM_KEYS]
    sol = solve_ivp(lambda _t, y: f(*y, *args), (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=1e-12,
                    atol=1e-14)
    assert sol.success
    return sol.y[:3].T  # (φ, θ, ψ)


# --- the symbolic model ----------------------------------------------------------------------

def test_gravity_torque_from_potential_equals_torque_from_force():
    m = rigid_model.model()
    assert (m.torque_from_potential - m.torque_from_force).applyfunc(sp.simplify) == sp.zeros(3, 1)
    R = rigid_model.rotation_symbols()
    M, g, l = rigid_model.M, rigid_model.g, rigid_model.l
    assert sp.simplify(m.torque_generic - sp.Matrix([M * g * l * R[1, 2], -M * g * l * R[0, 2], 0])) == sp.zeros(3, 1)


def test_torque_does_the_work_of_the_potential_in_euler_angles():
    """Independent of the variation: τ·ω = -dV/dt for V = M g l cos θ (3.62) and ω from (3.58), all rates."""
    m = rigid_model.model()
    km = kinematics_model()
    R = rigid_model.rotation_symbols()
    Rs = km.state_rotation
    tau = m.torque_generic.subs({R[i, j]: Rs[i, j] for i in range(3) for j in range(3)})
    w = km.state_angular_velocity_body
    theta, theta_dot = sp.Symbol("theta", real=True), sp.Symbol("theta_dot", real=True)
    V = rigid_model.M * rigid_model.g * rigid_model.l * sp.cos(theta)
    power = (tau.T * w)[0] + V.diff(theta) * theta_dot
    assert is_zero(power)


def test_quaternion_rotation_matrix_matches_euler_rotation():
    m = rigid_model.model()
    rng = np.random.default_rng(3)
    for phi, theta, psi in rng.uniform(-3, 3, (5, 3)):
        q = euler_to_quaternion(phi, theta, psi)
        Rq = np.array(m.rotation_from_quaternion.subs(dict(zip(rigid_model.quaternion_symbols(), q))), dtype=float)
        Re = np.array(euler_rotation(phi, theta, psi).evalf(), dtype=float)
        np.testing.assert_allclose(Rq, Re, atol=2e-15)  # rounding of ~10 products of O(1) numbers


def test_initial_state_conversion_is_358_and_the_conversions_quaternion(rng):
    """ω from 2 q̄ ⊗ q̇ equals (3.58) as derived from ṘRᵀ (kinematics.euler); q equals euler_to_quaternion."""
    m = rigid_model.model()
    from mechderive.core.symbols import state_symbol
    names = ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")
    states = rng.uniform(-3, 3, (6, 6))
    states[0, 1] = 0.0  # θ = 0 exactly
    states[1, 1] = math.pi
    for st in states:
        subs = {state_symbol(n): v for n, v in zip(names, st)}
        w = np.array(m.angular_velocity_from_euler_rates.subs(subs).evalf(), dtype=float).ravel()
        np.testing.assert_allclose(w, angular_velocity_body(*st), atol=1e-14)  # rounding of O(3) sums
        q = np.array(m.euler_quaternion.subs(subs).evalf(), dtype=float).ravel()
        np.testing.assert_allclose(q, euler_to_quaternion(*st[:3]), atol=1e-15)
    st = np.abs(states[2])  # θ in [0, π]
    w0, q0 = initial_state(check_initial(dict(zip(names, st))))
    np.testing.assert_allclose(w0, angular_velocity_body(*st), atol=1e-14)
    v = kinematics_model().state_angular_velocity_body
    assert (m.angular_velocity_from_euler_rates - v).applyfunc(sp.simplify) == sp.zeros(3, 1)


def test_invariants_are_the_chapters_and_conserved_symbolically():
    m = rigid_model.model()
    assert m.invariant_rates == (0, 0, 0)
    # E (3.65), p_φ (3.64), p_ψ (3.63) in Euler angles at random states equal the model's in (ω, q)
    rng = np.random.default_rng(4)
    for phi, theta, psi, pd, td, sd in rng.uniform(-2, 2, (5, 6)):
        w = angular_velocity_body(phi, theta, psi, pd, td, sd)
        q = euler_to_quaternion(phi, theta, psi)
        E, p_phi, p_psi = _evaluate_invariants(w, q, PARAMS)
        I1, I3, mgl = 1.0, 0.5, 1.0
        w3 = sd + pd * math.cos(theta)
        assert E == pytest.approx(I1 * (td**2 + pd**2 * math.sin(theta) ** 2) / 2 + I3 * w3**2 / 2
                                  + mgl * math.cos(theta), abs=1e-14)
        assert p_phi == pytest.approx(I1 * math.sin(theta) ** 2 * pd + I3 * math.cos(theta) * w3, abs=1e-14)
        assert p_psi == pytest.approx(I3 * w3, abs=1e-14)


@functools.cache
def _mp_stage():
    """The derived stage map (free drift h_free, then kick h_kick) as an mpmath function, lambdified once."""
    m = rigid_model.model()
    args = [*rigid_model.momentum_symbols(), *rigid_model.quaternion_symbols(), rigid_model.h_free,
            rigid_model.h_kick, *rigid_model.parameters()]
    return sp.lambdify(args, list(m.stage_map), modules="mpmath", cse=True)


def _mp_field(y, I1, I3, mgl):
    """(L̇, q̇) of the heavy top, typed in: L̇ = L × ω + τ, q̇ = ½ q ⊗ (0, ω), ω = (L1/I1, L2/I1, L3/I3)."""
    L1, L2, L3, q0, q1, q2, q3 = y
    w1, w2, w3 = L1 / I1, L2 / I1, L3 / I3
    gam = [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1)]
    return [L2 * w3 - L3 * w2 + mgl * gam[1], L3 * w1 - L1 * w3 - mgl * gam[0], L1 * w2 - L2 * w1,
            -(q1 * w1 + q2 * w2 + q3 * w3) / 2, (q0 * w1 + q2 * w3 - q3 * w2) / 2,
            (q0 * w2 + q3 * w1 - q1 * w3) / 2, (q0 * w3 + q1 * w2 - q2 * w1) / 2]


def test_free_flow_is_the_exact_flow_of_the_free_symmetric_top():
    """d/dh of the derived free flow equals the free top's vector field at the flowed point (40 digits)."""
    stage = _mp_stage()
    rng = np.random.default_rng(5)
    with mpmath.workdps(40):
        for _ in range(4):
            L = [mpmath.mpf(float(x)) for x in rng.normal(size=3)]
            q = [mpmath.mpf(float(x)) for x in rng.normal(size=4)]
            nq = mpmath.sqrt(sum(x * x for x in q))
            q = [x / nq for x in q]
            I1, I3 = mpmath.mpf("1.3"), mpmath.mpf("0.7")
            h, eps = mpmath.mpf(float(rng.uniform(0.1, 2.0))), mpmath.mpf("1e-12")
            y = stage(*L, *q, h, 0, I1, I3, 1, 0, 0)  # g = 0: a pure drift
            yp = stage(*L, *q, h + eps, 0, I1, I3, 1, 0, 0)
            ym = stage(*L, *q, h - eps, 0, I1, I3, 1, 0, 0)
            deriv = [(a - b) / (2 * eps) for a, b in zip(yp, ym)]  # central difference: error ~ eps² = 1e-24
            field = _mp_field(y, I1, I3, 0)
            assert max(abs(a - b) for a, b in zip(deriv, field)) < 1e-20
        # the flow at h = 0 is the identity, also at L = 0 (sinc is regular)
        y = stage(0, 0, 0, *q, 0, 0, I1, I3, 1, 0, 0)
        assert max(abs(a - b) for a, b in zip(y, [0, 0, 0, *q])) == 0


def test_drift_plus_kick_generate_the_full_vector_field():
    """∂/∂h_free + ∂/∂h_kick of the stage map at 0 is the heavy top's (L̇, q̇): the splitting splits H = T + V."""
    stage = _mp_stage()
    rng = np.random.default_rng(6)
    with mpmath.workdps(40):
        L = [mpmath.mpf(float(x)) for x in rng.normal(size=3)]
        q = [mpmath.mpf(float(x)) for x in rng.normal(size=4)]
        nq = mpmath.sqrt(sum(x * x for x in q))
        q = [x / nq for x in q]
        I1, I3, M, g, l = (mpmath.mpf(x) for x in ("1.3", "0.7", "2", "3", "0.25"))
        eps = mpmath.mpf("1e-15")
        d_free = [(a - b) / (2 * eps) for a, b in zip(stage(*L, *q, eps, 0, I1, I3, M, g, l),
                                                      stage(*L, *q, -eps, 0, I1, I3, M, g, l))]
        d_kick = [(a - b) / (2 * eps) for a, b in zip(stage(*L, *q, 0, eps, I1, I3, M, g, l),
                                                      stage(*L, *q, 0, -eps, I1, I3, M, g, l))]
        field = _mp_field([*L, *q], I1, I3, M * g * l)
        assert max(abs(a + b - c) for a, b, c in zip(d_free, d_kick, field)) < 1e-20


def test_free_flow_matches_the_free_top_integrator():
    """g = 0: the splitting is the exact free flow, at any step (here 0.7 s), against integrate_free_top."""
    params = dict(PARAMS, g=0.0)
    init = dict(theta=0.9, phi=0.3, psi=-0.2, theta_dot=0.4, phi_dot=1.1, psi_dot=3.0)
    t = np.linspace(0.0, 7.0, 11)
    split = integrate_heavy_top(params, init, t, method="splitting", step=0.7, order=2, estimate_error=False)
    R0 = euler_rotation(init["phi"], init["theta"], init["psi"]).evalf()
    w0 = angular_velocity_body(init["phi"], init["theta"], init["psi"], init["phi_dot"], init["theta_dot"],
                               init["psi_dot"])
    free = integrate_free_top((1.0, 1.0, 0.5), w0, t, R0=np.array(R0, dtype=float), rtol=1e-13, atol=1e-15,
                              estimate_error=False)
    # DOP853 at rtol 1e-13 over ~20 rad of rotation: ~1e-12
    np.testing.assert_allclose(split.omega, free.omega, atol=1e-11)
    np.testing.assert_allclose(split.R, free.R, atol=1e-11)


# --- accuracy against independent references ----------------------------------------------------

def test_dop853_matches_30_digit_mpmath(mp_reference):
    run = integrate_heavy_top(PARAMS, BASE, np.array((0.0,) + MP_TIMES), rtol=1e-12)
    got = np.hstack([run.omega, run.quaternion])[1:]
    # q and -q are the same rotation; the run starts at q0 > 0 and is continuous, as is the reference
    assert np.max(np.abs(got - mp_reference)) < 1e-10  # rtol 1e-12 over ~15 rad of spin: ≲ 1e-11 expected


def test_splitting_matches_30_digit_mpmath(mp_reference):
    run = integrate_heavy_top(PARAMS, BASE, np.array((0.0,) + MP_TIMES), method="splitting", order=6, step=0.01)
    got = np.hstack([run.omega, run.quaternion])[1:]
    assert np.max(np.abs(got - mp_reference)) < 1e-10  # order 6 at h = 0.01: ~1e-12 (measured orders below)


def test_splitting_orders_4_and_2_match_mpmath_to_their_accuracy(mp_reference):
    t = np.array((0.0,) + MP_TIMES)
    for order, step, tol in ((4, 0.01, 1e-8), (2, 0.001, 1e-5)):  # errors ~ C h^p with C ~ 10-100
        run = integrate_heavy_top(PARAMS, BASE, t, method="splitting", order=order, step=step, estimate_error=False)
        assert np.max(np.abs(np.hstack([run.omega, run.quaternion])[1:] - mp_reference)) < tol


@pytest.mark.parametrize("init", [BASE, dict(theta=2.5, psi_dot=5.0),
                                  dict(theta=1.2, phi=0.4, psi=-1.0, theta_dot=0.3, phi_dot=-0.8, psi_dot=2.0)],
                         ids=["baseline", "hanging", "general"])
def test_agrees_with_euler_angle_lagrangian(euler_angle_rhs, init):
    """Against θ, φ, ψ integrated from sympy.physics.mechanics' equations (away from θ = 0)."""
    f, _ = euler_angle_rhs
    t = np.linspace(0.0, 10.0, 201)
    ref = integrate_euler_angles(f, PARAMS, init, t)
    for kw in (dict(rtol=1e-12), dict(method="splitting", order=6, step=0.01)):
        run = integrate_heavy_top(PARAMS, init, t, estimate_error=False, **kw)
        # both at ~1e-11 per unit time over 10 s; φ, ψ amplified by 1/sin θ ≤ 4
        np.testing.assert_allclose(run.euler_angles, ref, atol=1e-8)


def test_mechanics_dcm_is_the_chapters_rotation(euler_angle_rhs):
    _, dcm = euler_angle_rhs
    phi, theta, psi = sp.symbols("phi theta psi")
    assert (dcm - euler_rotation(phi, theta, psi)).applyfunc(sp.simplify) == sp.zeros(3, 3)


def test_euler_angle_rhs_is_nan_at_theta_zero_but_ours_is_finite(euler_angle_rhs):
    f, _ = euler_angle_rhs
    with np.errstate(all="ignore"):
        acc = f(0.0, 0.0, 0.0, 0.0, 0.0, 5.0, *PARAMS.values())
    assert not np.all(np.isfinite(acc))  # BASELINE.md: NaN at θ = 0
    assert np.all(np.isfinite(_rhs()(0.0, 0.0, 5.0, 1.0, 0.0, 0.0, 0.0, *PARAMS.values())))


def test_nutation_range_and_period_of_the_baseline_case():
    """θ between 0.5 and 0.7576 with period 3.5177 s (BASELINE.md), to 1e-9 against the cubic (3.73)."""
    th_min, th_max, period = nutation_from_cubic(1.0, 0.5, 1.0, 0.5, 0.0, 0.0, 5.0)
    assert (round(th_min, 4), round(th_max, 4), round(period, 4)) == (0.5, 0.7576, 3.5177)
    t = np.array([0.0, period / 2, period, 5 * period + period / 2, 10 * period])
    for kw in (dict(rtol=1e-12), dict(method="splitting", order=6, step=0.01)):
        theta = integrate_heavy_top(PARAMS, BASE, t, estimate_error=False, **kw).euler_angles[:, 1]
        # turning points: θ(t) - θ_max is quadratic in the time error, so θ agrees to ~1e-10 there
        np.testing.assert_allclose(theta, [th_min, th_max, th_min, th_max, th_min], atol=1e-9)


# --- the sleeping, falling and hanging top ------------------------------------------------------

def test_sleeping_top_at_theta_zero_stays_upright_without_nan():
    t = np.linspace(0.0, 20.0, 201)
    for spin in (10.0, 2.0):  # stable and unstable (3.83): ω3² vs 4 I1 M g l / I3² = 16
        for kw in (dict(rtol=1e-10), dict(method="splitting", step=0.05)):
            run = integrate_heavy_top(PARAMS, dict(theta=0.0, phi=0.3, psi=0.4, psi_dot=spin), t, **kw)
            ang = run.euler_angles
            assert np.all(np.isfinite(ang)) and np.all(np.isfinite(run.omega))
            assert np.max(ang[:, 1]) == 0.0  # the upright top is an exact equilibrium: γ = e3, τ = 0
            # only φ + ψ is defined: it starts at 0.7 and turns at ω3 (ψ kept at 0, φ carries it)
            np.testing.assert_allclose(ang[:, 0] + ang[:, 2], 0.7 + spin * t, atol=1e-9 * spin * t[-1])


def test_stable_sleeping_top_stays_near_upright_after_a_kick():
    """ω3 = 10 > 4: a nudge θ̇0 = 1e-3 gives a small nutation whose amplitude is the root of (3.73)."""
    _, th_max, _ = nutation_from_cubic(1.0, 0.5, 1.0, 0.0, 1e-3, 0.0, 10.0)
    t = np.linspace(0.0, 10.0, 4001)
    for kw in (dict(rtol=1e-12), dict(method="splitting", order=4, step=0.01)):
        theta = integrate_heavy_top(PARAMS, dict(theta=0.0, theta_dot=1e-3, psi_dot=10.0), t, **kw).euler_angles[:, 1]
        assert th_max < 1e-3
        # sampled maximum: below the turning point, and within the sampling's reach of it
        assert th_max * 0.999 < np.max(theta) <= th_max * (1 + 1e-8)


def test_unstable_sleeping_top_falls_to_the_predicted_angle():
    """ω3 = 2 < 4: after θ̇0 = 1e-6 the top falls to θ = arccos(I3² ω3²/(2 I1 M g l) - 1) = 2π/3 (3.83)."""
    _, th_max, _ = nutation_from_cubic(1.0, 0.5, 1.0, 0.0, 1e-6, 0.0, 2.0)
    assert th_max == pytest.approx(2 * math.pi / 3, abs=1e-5)  # u2 = a²/α - 1 = -1/2, moved by the nudge
    t = np.linspace(0.0, 25.0, 5001)
    for kw in (dict(rtol=1e-12), dict(method="splitting", order=4, step=0.01)):
        theta = integrate_heavy_top(PARAMS, dict(theta=0.0, theta_dot=1e-6, psi_dot=2.0), t, **kw).euler_angles[:, 1]
        assert np.max(theta) == pytest.approx(th_max, abs=1e-5)  # sampling at 5 ms near a turning point


def test_hanging_top_nutates_between_the_roots_of_the_cubic():
    th_min, th_max, period = nutation_from_cubic(1.0, 0.5, 1.0, 2.5, 0.0, 0.0, 5.0)
    assert th_min == pytest.approx(2.5, abs=1e-12) and th_max > math.pi / 2
    t = np.array([0.0, period / 2, period])
    for kw in (dict(rtol=1e-12), dict(method="splitting", order=6, step=0.01)):
        run = integrate_heavy_top(PARAMS, dict(theta=2.5, psi_dot=5.0), t, **kw)
        np.testing.assert_allclose(run.euler_angles[:, 1], [2.5, th_max, 2.5], atol=1e-9)
        assert run.energy_drift < 1e-10


def test_motion_depends_on_M_g_l_only_through_their_product():
    t = np.linspace(0.0, 5.0, 6)
    runs = [integrate_heavy_top(dict(I1=1.0, I3=0.5, M=M, g=g, l=l), BASE, t, method="splitting", step=0.05,
                                estimate_error=False)
            for M, g, l in ((1.0, 4.0, 0.25), (0.5, 8.0, 0.25), (2.0, 1.0, 0.5))]
    for r in runs[1:]:
        np.testing.assert_allclose(r.omega, runs[0].omega, atol=1e-13)  # M g l = 1 exactly in binary in each


# --- structure preservation and orders -----------------------------------------------------------

def _max_split_error(order: int, n: int, ref) -> float:
    t = ref.t
    run = integrate_heavy_top(PARAMS, BASE, t, method="splitting", order=order, step=t[-1] / n, estimate_error=False)
    return max(np.max(np.abs(run.omega - ref.omega)), np.max(np.abs(run.quaternion - ref.quaternion)))


@pytest.mark.parametrize("order, steps", [(2, (25, 50, 100, 200)), (4, (10, 20, 40, 80)), (6, (10, 14, 20, 28))])
def test_measured_order_of_the_splitting(order, steps):
    """Slope of log(error) against log(h) at t = 3.5 s, against DOP853 at rtol 1e-13 (errors ≥ 4e-9 ≫ its 1e-12)."""
    ref = integrate_heavy_top(PARAMS, BASE, np.array([0.0, 3.5]), rtol=1e-13, atol=1e-16, estimate_error=False)
    errors = [_max_split_error(order, n, ref) for n in steps]
    slope = np.polyfit(np.log(3.5 / np.array(steps)), np.log(errors), 1)[0]
    assert abs(slope - order) < 0.3, (slope, errors)


def _energy_halves(run) -> tuple[float, float]:
    dE = np.abs(run.invariants[:, 0] - run.invariants[0, 0])
    half = len(dE) // 2
    return float(np.max(dE[:half])), float(np.max(dE[half:]))


def test_splitting_keeps_energy_bounded_and_momenta_to_rounding_1e5_steps():
    """10⁵ Strang steps of 0.05 s (5000 s, 1400 nutation periods): E oscillates, no drift; p_φ, p_ψ to rounding."""
    t = np.linspace(0.0, 5000.0, 2001)
    run = integrate_heavy_top(PARAMS, BASE, t, method="splitting", order=2, step=0.05, estimate_error=False)
    assert run.n_steps == 100_000
    first, second = _energy_halves(run)
    assert second < 1.1 * first  # bounded: the same envelope in both halves (DOP853 doubles, below)
    assert run.energy_drift < 1e-4  # O(h²) oscillation
    assert run.p_psi_drift == 0.0  # L3 is never changed by either sub-flow
    assert run.p_phi_drift < 1e-12  # exact for each sub-flow; rounding ~ 1e-16 per step, partly cancelling
    assert run.quaternion_norm_drift < 1e-10


def test_energy_check_detects_the_drift_of_dop853():
    """The bounded-energy criterion above is not vacuous: DOP853 at rtol 1e-5 drifts linearly."""
    t = np.linspace(0.0, 1000.0, 1001)
    run = integrate_heavy_top(PARAMS, BASE, t, rtol=1e-5, estimate_error=False)
    first, second = _energy_halves(run)
    assert second > 1.5 * first


_NO_C = pytest.mark.skipif(not __import__("mechderive.core.cbuild", fromlist=["c_enabled"]).c_enabled(),
                           reason="no C compiler on this machine")


@pytest.mark.parametrize("backend", [pytest.param("c", marks=_NO_C),  # ~0.3 s each compiled
                                     pytest.param("python", marks=pytest.mark.slow)])  # ~1 min each
@pytest.mark.parametrize("order, step", [(2, 0.05), (4, 0.05), (6, 0.1)])
def test_splitting_keeps_energy_bounded_1e6_steps(order, step, backend):
    """10⁶ steps (50 000 – 100 000 s, 14 000 – 28 000 nutation periods) at each order.

    Steps are chosen so that the O(h^p) energy oscillation (≳ 1e-9) dominates the rounding walk
    (~1e-12 over 10⁶ steps); the bound on p_φ is rounding: ~1e-18 per stage over ≤ 7·10⁶ stages.
    """
    t = np.linspace(0.0, 1e6 * step, 2001)
    run = integrate_heavy_top(PARAMS, BASE, t, method="splitting", order=order, step=step, estimate_error=False,
                              backend=backend)
    assert run.n_steps == 1_000_000 and run.backend == backend
    first, second = _energy_halves(run)
    assert second < 1.1 * first, (first, second)
    assert run.p_psi_drift == 0.0
    assert run.p_phi_drift < 5e-11


def test_error_estimates_bracket_the_true_error(mp_reference):
    t = np.array((0.0,) + MP_TIMES)
    for kw in (dict(rtol=1e-8), dict(method="splitting", order=4, step=0.05)):
        run = integrate_heavy_top(PARAMS, BASE, t, **kw)
        true = np.max(np.abs(run.omega[1:] - mp_reference[:, :3]))
        # same order of magnitude: the rerun (DOP853) and Richardson (splitting) estimate the leading error
        assert true / 5 < run.omega_error_estimate < 5 * true, (kw, true, run.omega_error_estimate)
        assert run.angle_error_estimate > 0 and run.error_estimate_kind


def test_euler_angles_are_continuous_over_many_periods():
    t = np.linspace(0.0, 100 * 3.5177, 2001)
    ang = integrate_heavy_top(PARAMS, BASE, t, method="splitting", order=4, step=0.05,
                              estimate_error=False).euler_angles
    assert np.all(np.abs(np.diff(ang, axis=0)) < 1.5)  # |ψ̇| ≤ 5.1 rad/s, Δt = 0.176 s: steps < 0.9 rad
    assert ang[-1, 2] > 100  # ψ keeps growing, no wrap to (-π, π]


# --- the ensemble ---------------------------------------------------------------------------

def test_ensemble_matches_single_runs(rng):
    M = 12
    theta = rng.uniform(0.0, math.pi, M)
    theta[:3] = (0.0, math.pi / 2, 2.5)
    init = dict(theta=theta, phi=rng.uniform(-1, 1, M), psi_dot=rng.uniform(-8, 8, M), theta_dot=rng.uniform(-1, 1, M))
    t = np.linspace(0.0, 3.0, 4)
    ens = integrate_heavy_top_ensemble(PARAMS, init, t, step=0.02, order=4)
    assert ens.omega.shape == (4, M, 3) and ens.quaternion.shape == (4, M, 4) and ens.energy_drift.shape == (M,)
    for k in (0, 1, 2, M - 1):
        single = integrate_heavy_top(PARAMS, {key: v[k] for key, v in init.items()}, t, method="splitting", order=4,
                                     step=0.02, estimate_error=False)
        np.testing.assert_allclose(ens.omega[:, k], single.omega, atol=1e-12)  # NumPy vs math: rounding only
        np.testing.assert_allclose(ens.theta[:, k], single.euler_angles[:, 1], atol=1e-12)
    assert np.all(ens.p_psi_drift == 0.0) and np.all(ens.p_phi_drift < 1e-13)
    assert ens.body_steps_per_second > 0


def test_ensemble_accepts_per_member_parameters():
    init = dict(theta=np.array([0.5, 0.5]), psi_dot=5.0)
    params = dict(PARAMS, g=np.array([4.0, 0.0]))
    ens = integrate_heavy_top_ensemble(params, init, [0.0, 2.0], step=0.01, order=6)
    free = integrate_heavy_top(dict(PARAMS, g=0.0), dict(theta=0.5, psi_dot=5.0), [0.0, 2.0], method="splitting",
                               step=0.01, order=6, estimate_error=False)
    np.testing.assert_allclose(ens.omega[:, 1], free.omega, atol=1e-12)
    assert ens.theta[-1, 1] == pytest.approx(0.5, abs=1e-12)  # free symmetric top: θ constant (3.5.3)


def test_kick_drift_schedule_sums_to_one_step():
    w = suzuki_fractal(4)
    head, stages = kick_drift.kdk_schedule(w)
    assert sum(d for d, _ in stages) == pytest.approx(1.0, abs=1e-15)
    assert head + sum(k for _, k in stages) == pytest.approx(1.0, abs=1e-15)  # one step kicks for h in total
    assert stages[-1][1] == pytest.approx(head, abs=1e-15)
    assert kick_drift.stages_per_step(w) == 5


# --- bad input -------------------------------------------------------------------------------

T2 = [0.0, 1.0]


@pytest.mark.parametrize("params, error, match", [
    (dict(I1=1.0, I3=0.5, M=1.0, g=1.0, l=1.0), UnphysicalInertiaError,
     r"expected I1 - M l² >= I3/2 \(the triangle inequality .* centre of mass.*got I1 - M l² = 0 < I3/2 = 0.25"),
    (dict(PARAMS, I1=0.0), UnphysicalInertiaError, r"expected params\['I1'\] > 0 .*got 0"),
    (dict(PARAMS, I3=-1.0), UnphysicalInertiaError, r"expected params\['I3'\] > 0 .*got -1"),
    (dict(PARAMS, M=0.0), InvalidInputError, r"expected params\['M'\] > 0, got 0"),
    (dict(PARAMS, g=-9.8), InvalidInputError, r"expected params\['g'\] >= 0, got -9.8"),
    (dict(PARAMS, l=-0.1), InvalidInputError, r"expected params\['l'\] >= 0, got -0.1"),
    (dict(PARAMS, I1=float("nan")), NonFiniteValueError, r"expected `params\['I1'\]` to be finite, got nan"),
    (dict(PARAMS, L=1.0), InvalidInputError, r"expected `params` keys among I1, I3, M, g, l, got unknown key\(s\) 'L'"),
    ({k: v for k, v in PARAMS.items() if k != "M"}, InvalidInputError,
     r"expected `params` to have key\(s\) I1, I3, M, g, l, got none for 'M'"),
    ([1.0, 0.5, 1.0, 4.0, 0.25], InvalidInputError, r"expected `params` to be a dict with keys .*got list"),
])
def test_bad_params_raise(params, error, match):
    with pytest.raises(error, match=match):
        integrate_heavy_top(params, BASE, T2)


def test_plane_body_on_the_triangle_boundary_is_accepted():
    # a disc (I3_cm = 2 I1_cm) on a stick: I1_cm = 0.25, I3 = 0.5, I1 = 0.25 + M l² with rounding
    assert check_params(dict(I1=0.25 + 0.1 * 0.3**2, I3=0.5, M=0.1, g=9.81, l=0.3))["I3"] == 0.5


@pytest.mark.parametrize("initial, error, match", [
    (dict(theta=-0.1), InvalidInputError, r"expected 0 <= initial\['theta'\] <= pi, got -0.1"),
    (dict(theta=3.2), InvalidInputError, r"expected 0 <= initial\['theta'\] <= pi, got 3.2"),
    (dict(theta=0.5, psi_dot=float("inf")), NonFiniteValueError,
     r"expected `initial\['psi_dot'\]` to be finite, got inf"),
    (dict(theta=0.5, omega3=5.0), InvalidInputError,
     r"expected `initial` keys among theta, phi, psi, theta_dot, phi_dot, psi_dot, got unknown key\(s\) 'omega3'"),
    (dict(psi_dot=5.0), InvalidInputError, r"expected `initial` to have key\(s\) theta, got none for 'theta'"),
    (dict(theta=np.array([0.1, 0.2])), ShapeError, r"expected scalar `initial` values .*got arrays"),
])
def test_bad_initial_raise(initial, error, match):
    with pytest.raises(error, match=match):
        integrate_heavy_top(PARAMS, initial, T2)


@pytest.mark.parametrize("kwargs, match", [
    (dict(method="RK45"), r"expected method one of 'DOP853', 'splitting', got 'RK45'"),
    (dict(method="splitting"), r"expected a step size `step` > 0 with method='splitting', got step=None"),
    (dict(method="splitting", step=0.1, rtol=1e-8), r"expected `rtol` only with method='DOP853', got rtol=1e-08"),
    (dict(step=0.1), r"expected `step` only with method='splitting', got step=0.1 with method='DOP853'"),
    (dict(method="splitting", step=0.1, order=3), r"expected order one of 2, 4, 6, got 3"),
    (dict(method="splitting", step=-0.1), r"expected `step` > 0, got -0.1"),
    (dict(rtol=0.0), r"expected `rtol` > 0, got 0.0"),
])
def test_bad_method_options_raise(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        integrate_heavy_top(PARAMS, BASE, T2, **kwargs)


def test_bad_times_and_ensemble_shapes_raise():
    with pytest.raises(InvalidInputError, match=r"expected `t_eval` strictly increasing, got t_eval\[1\] = 0"):
        integrate_heavy_top(PARAMS, BASE, [0.0, 0.0])
    with pytest.raises(ShapeError, match=r"expected scalar `params` values .*got arrays"):
        integrate_heavy_top(dict(PARAMS, g=np.array([1.0, 2.0])), BASE, T2)
    with pytest.raises(ShapeError, match=r"expected `params` and `initial` values of shape \(\) or \(M,\)"):
        integrate_heavy_top_ensemble(PARAMS, dict(theta=np.zeros(3), psi_dot=np.zeros(2)), T2, step=0.1)
    with pytest.raises(ShapeError, match=r"got broadcast shape \(2, 2\)"):
        integrate_heavy_top_ensemble(PARAMS, dict(theta=np.zeros((2, 2))), T2, step=0.1)


def test_keys_are_documented():
    assert PARAM_KEYS == ("I1", "I3", "M", "g", "l")
    assert INITIAL_KEYS == ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")
    assert omega_symbols()[2].name == "omega3"


@pytest.mark.skipif(not __import__("mechderive.core.cbuild", fromlist=["c_enabled"]).c_enabled(),
                    reason="no C compiler on this machine")
@pytest.mark.parametrize("order", [2, 4, 6])
def test_compiled_splitting_is_the_python_splitting(order):
    # The same stage maps in the same order (kick_drift.propagate's schedule): equal to rounding, which
    # over 4000 steps walks to ~1e-14 (a different schedule would differ by the method's own error, far above 1e-12).
    t = np.linspace(0.0, 20.0, 41)
    c = integrate_heavy_top(PARAMS, BASE, t, method="splitting", order=order, step=0.005, backend="c")
    py = integrate_heavy_top(PARAMS, BASE, t, method="splitting", order=order, step=0.005, backend="python")
    assert (c.backend, py.backend) == ("c", "python") and c.n_steps == py.n_steps
    np.testing.assert_allclose(c.omega, py.omega, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.quaternion, py.quaternion, rtol=0, atol=1e-12)
    assert c.omega_error_estimate == pytest.approx(py.omega_error_estimate, rel=1e-3)
