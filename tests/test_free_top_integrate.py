"""Numerical integration of the free (and torqued) rigid body, checked from independent angles.

References: a 30-digit mpmath Taylor integration (mpmath.odefun) of Euler's equations (3.33), typed in from
the chapter, and of q̇ = ½ q ⊗ (0, ω); a direct 9-component integration of Ṙ = hat(ω) R (3.11); the
symmetric top's closed-form motion derived below; the space angular momentum Rᵀ L, constant for a free
body and growing as τ t under a constant space torque; measured orders of convergence.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from mechderive.errors import (InvalidInputError, NonFiniteValueError, NotARotationError, ShapeError,
                               UnphysicalInertiaError)
from mechderive.kinematics.conversions import quaternion_to_matrix
from mechderive.kinematics.so3 import hat
from mechderive.solvers import lie_poisson
from mechderive.solvers.composition import merged_sequence, suzuki_fractal, triple_jump, yoshida6
from mechderive.solvers.quaternion import quaternion_multiply, quaternion_rate, quaternion_rate_expressions
from mechderive.systems.free_top.integrate import (SPLITTING_ORDERS, _state_rhs, integrate_free_top,
                                                   integrate_free_top_ensemble)

I_REF = (1.0, 2.0, 3.0)
W_REF = (1.0, 0.5, 1.0)
T_REF = 4.0
T_SAMPLES = (1.0, 2.0, 3.0, 4.0)


# --- the independent 30-digit reference ------------------------------------------------------

@pytest.fixture(scope="session")
def mp_reference() -> np.ndarray:
    """(ω, q) at T_SAMPLES from mpmath.odefun (Taylor series) at 30 digits; shape (4, 7)."""
    with mpmath.workdps(30):
        I1, I2, I3 = (mpmath.mpf(x) for x in I_REF)

        def F(_t, y):
            w1, w2, w3, q0, q1, q2, q3 = y
            # Euler's equations (3.33), free body, as printed in the chapter
            dw = [(I2 - I3) * w2 * w3 / I1, (I3 - I1) * w3 * w1 / I2, (I1 - I2) * w1 * w2 / I3]
            # q̇ = ½ q ⊗ (0, ω), Hamilton product written out
            dq = [-(q1 * w1 + q2 * w2 + q3 * w3) / 2, (q0 * w1 + q2 * w3 - q3 * w2) / 2,
                  (q0 * w2 + q3 * w1 - q1 * w3) / 2, (q0 * w3 + q1 * w2 - q2 * w1) / 2]
            return dw + dq

        y0 = [mpmath.mpf(x) for x in W_REF] + [mpmath.mpf(1), 0, 0, 0]
        sol = mpmath.odefun(F, 0, y0)
        return np.array([[float(v) for v in sol(mpmath.mpf(t))] for t in T_SAMPLES])


def t_grid() -> np.ndarray:
    return np.array((0.0,) + T_SAMPLES)


def test_dop853_matches_mpmath(mp_reference):
    run = integrate_free_top(I_REF, W_REF, t_grid(), rtol=1e-12, atol=1e-14)
    # rtol 1e-12 over 4 s of smooth motion: global error ~1e-13; 1e-10 leaves room for machines/SciPy versions.
    assert np.max(np.abs(run.omega[1:] - mp_reference[:, :3])) < 1e-10
    assert np.max(np.abs(run.quaternion[1:] - mp_reference[:, 3:])) < 1e-10


def test_splitting_order6_matches_mpmath(mp_reference):
    run = integrate_free_top(I_REF, W_REF, t_grid(), method="splitting", order=6, step=0.01)
    # order 6 at h = 0.01: error ~ 1e-14 here (measured); 1e-11 also bounds rounding over 400 steps.
    assert np.max(np.abs(run.omega[1:] - mp_reference[:, :3])) < 1e-11
    assert np.max(np.abs(run.quaternion[1:] - mp_reference[:, 3:])) < 1e-11


@pytest.mark.parametrize("order", [2, 4, 6])
def test_splitting_order_of_convergence(order, mp_reference):
    steps = {2: [0.1, 0.05, 0.025, 0.0125], 4: [0.2, 0.1, 0.05, 0.025], 6: [0.2, 0.1, 0.05, 0.025]}[order]
    errors = []
    for h in steps:
        run = integrate_free_top(I_REF, W_REF, [0.0, T_REF], method="splitting", order=order, step=h,
                                 estimate_error=False)
        errors.append(np.max(np.abs(run.omega[-1] - mp_reference[-1, :3])))
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    # all errors above 1e-12 (far from rounding), so the fitted slope is the asymptotic order ± 0.3
    assert min(errors) > 1e-12
    assert abs(slope - order) < 0.3, (slope, errors)


def test_error_estimates_track_true_errors(mp_reference):
    from mechderive.solvers.half_angles import rotation_angle_between

    truth, q_truth = mp_reference[:, :3], mp_reference[:, 3:]
    split = integrate_free_top(I_REF, W_REF, t_grid(), method="splitting", order=4, step=0.1)
    true_split = np.max(np.abs(split.omega[1:] - truth))
    # Richardson with the known order: exact up to O(h^{p+1}) relative corrections (~h = 10%), then
    # widened by RICHARDSON_MARGIN = 1.25 to cover them
    assert true_split <= split.omega_error_estimate < 1.25 * 1.1 * true_split
    dop = integrate_free_top(I_REF, W_REF, t_grid(), rtol=1e-8, atol=1e-10)
    true_dop = np.max(np.abs(dop.omega[1:] - truth))
    # the rerun at rtol/1000 is ~1000× more accurate, so the difference (× 1.03) is the error to ~10%
    assert abs(dop.omega_error_estimate - true_dop) < 0.1 * true_dop
    assert "rtol" in dop.error_estimate_kind and "Richardson" in split.error_estimate_kind
    for run in (split, dop):
        # the one reported estimate covers the orientation as well (q from the same mpmath run) ...
        true_rot = np.max(rotation_angle_between(run.quaternion[1:], q_truth))
        assert true_rot <= run.rotation_error_estimate <= 1.5 * true_rot, (run.method, true_rot)
        assert run.error_estimate == max(run.omega_error_estimate, run.rotation_error_estimate,
                                         run.euler_angle_error_estimate)


# --- kinematics: q̇ = ½ q ⊗ (0, ω) is Ṙ = hat(ω) R -----------------------------------------

def test_quaternion_rate_reproduces_Rdot_numerically(rng):
    for _ in range(10):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        w = rng.normal(size=3)
        eps = 1e-6
        qdot = quaternion_rate(q, w)
        dR = (quaternion_to_matrix(_unit(q + eps * qdot)) - quaternion_to_matrix(_unit(q - eps * qdot))) / (2 * eps)
        R = quaternion_to_matrix(q)
        # central difference: truncation ~eps² |q⃛| ~ 1e-12, rounding ~1e-16/eps = 1e-10
        assert np.max(np.abs(dR - hat(w) @ R)) < 1e-8
        # the other ordering, q̇ = ½ (0, ω) ⊗ q, is the space-frame ω: it must fail here
        wrong = 0.5 * quaternion_multiply(np.concatenate([[0.0], w]), q)
        dR_wrong = (quaternion_to_matrix(_unit(q + eps * wrong)) - quaternion_to_matrix(_unit(q - eps * wrong))) / (2 * eps)
        assert np.max(np.abs(dR_wrong - hat(w) @ R)) > 1e-3


def _unit(q: np.ndarray) -> np.ndarray:
    return q / np.linalg.norm(q)


def test_quaternion_rate_symbolically_with_sympys_own_matrix():
    from sympy.algebras.quaternion import Quaternion

    q = sp.symbols("q0:4", real=True)
    w = sp.symbols("w1:4", real=True)
    R = Quaternion(*q).to_rotation_matrix().T  # SymPy's matrix is the active A; the chapter's R = Aᵀ
    qdot = quaternion_rate_expressions(q, w)
    Rdot = sum((R.diff(q[i]) * qdot[i] for i in range(4)), sp.zeros(3, 3))
    hat_w = sp.Matrix([[0, w[2], -w[1]], [-w[2], 0, w[0]], [w[1], -w[0], 0]])  # ω_ab = ε_abc ω_c
    assert (Rdot - hat_w * R).applyfunc(sp.cancel) == sp.zeros(3, 3)


def test_compiled_rhs_is_eulers_equations_with_torque(rng):
    rhs = _state_rhs()
    for _ in range(5):
        w, q, I, tau = rng.normal(size=3), rng.normal(size=4), 1 + rng.random(3), rng.normal(size=3)
        out = np.array(rhs(*w, *q, *I, *tau))
        I1, I2, I3 = I
        expected = [((I2 - I3) * w[1] * w[2] + tau[0]) / I1, ((I3 - I1) * w[2] * w[0] + tau[1]) / I2,
                    ((I1 - I2) * w[0] * w[1] + tau[2]) / I3]
        np.testing.assert_allclose(out[:3], expected, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(out[3:], quaternion_rate(q, w), rtol=1e-13, atol=1e-14)


def test_quaternion_path_matches_direct_integration_of_Rdot(rng):
    R0 = Rotation.random(random_state=7).as_matrix().T
    t = np.linspace(0.0, 5.0, 11)
    run = integrate_free_top(I_REF, W_REF, t, R0=R0, rtol=1e-12, atol=1e-14)
    I = np.array(I_REF)

    def f(_t, y):  # ω and the 9 entries of R: Euler (3.33) and Ṙ = hat(ω) R
        w, R = y[:3], y[3:].reshape(3, 3)
        wdot = np.cross(I * w, w) / I
        return np.concatenate([wdot, (hat(w) @ R).ravel()])

    direct = solve_ivp(f, (0.0, 5.0), np.concatenate([W_REF, R0.ravel()]), method="DOP853", t_eval=t,
                       rtol=1e-12, atol=1e-14)
    # two rtol-1e-12 integrations of the same motion: they agree to ~1e-12; 1e-10 as in the mpmath test
    assert np.max(np.abs(direct.y[3:].T.reshape(-1, 3, 3) - run.R)) < 1e-10
    split = integrate_free_top(I_REF, W_REF, t, R0=R0, method="splitting", order=6, step=0.01)
    assert np.max(np.abs(direct.y[3:].T.reshape(-1, 3, 3) - split.R)) < 1e-10


def test_symmetric_top_orientation_closed_form():
    """I1 = I2: with L = A I ω fixed in space, ω_body = L_body/I1 + Ω e3 where Ω = ω3 (I1 - I3)/I1 (3.36).

    So Ȧ = A[ω]× is solved by A(t) = exp(t (|L|/I1) [L̂]×) A0 exp(t Ω [e3]×): differentiating gives
    [|L|/I1 L̂]× A + A Ω[e3]× = A [Aᵀ L/I1 + Ω e3]× = A [ω]× (Aᵀ L = L_body(t), (Aᵀv)× = Aᵀ v× A).
    """
    I = np.array([2.0, 2.0, 3.0])
    w0 = np.array([0.3, -0.4, 1.5])
    R0 = Rotation.from_euler("ZXZ", [0.4, 1.1, -0.7]).as_matrix().T
    A0 = R0.T
    L_space = A0 @ (I * w0)
    Omega = w0[2] * (I[0] - I[2]) / I[0]
    t = np.linspace(0.0, 20.0, 41)
    A = np.array([Rotation.from_rotvec(tk * L_space / I[0]).as_matrix() @ A0
                  @ Rotation.from_rotvec([0.0, 0.0, Omega * tk]).as_matrix() for tk in t])
    # ω precesses about e3 at -Ω in the body: (3.37) up to phase
    w_exact = np.array([Rotation.from_rotvec([0.0, 0.0, -Omega * tk]).as_matrix() @ w0 for tk in t])
    for run, tol in ((integrate_free_top(I, w0, t, R0=R0, rtol=1e-12, atol=1e-14), 1e-10),
                     (integrate_free_top(I, w0, t, R0=R0, method="splitting", order=6, step=0.02), 1e-10)):
        # tolerance: rtol 1e-12 resp. order 6 at h = 0.02 (error ~1e-13 per unit time) over 20 s
        assert np.max(np.abs(run.omega - w_exact)) < tol
        assert np.max(np.abs(run.R - np.swapaxes(A, 1, 2))) < tol


# --- conservation ----------------------------------------------------------------------------

@pytest.mark.parametrize("method, kwargs", [("DOP853", {"rtol": 1e-12, "atol": 1e-14}),
                                            ("splitting", {"order": 4, "step": 0.05})])
def test_invariants_and_orthogonality(method, kwargs):
    R0 = Rotation.from_euler("ZXZ", [0.2, 0.9, 2.0]).as_matrix().T
    t = np.linspace(0.0, 50.0, 201)
    run = integrate_free_top(I_REF, W_REF, t, R0=R0, method=method, **kwargs)
    # R orthonormal with det +1 to rounding
    gram = np.einsum("nki,nkj->nij", run.R, run.R)
    assert np.max(np.abs(gram - np.eye(3))) < 1e-14
    assert np.max(np.abs(np.linalg.det(run.R) - 1)) < 1e-14
    # the space components of L, Rᵀ (I ω) (3.31), are constant
    L_space = np.einsum("nab,na->nb", run.R, np.array(I_REF) * run.omega)
    tol = 1e-9 if method == "DOP853" else 1e-13  # rtol 1e-12 over 50 s; the splitting keeps it to rounding
    assert np.max(np.abs(L_space - L_space[0])) < tol
    assert run.angular_momentum_drift < (1e-11 if method == "DOP853" else 1e-14)
    assert run.energy_drift < (1e-11 if method == "DOP853" else 1e-6)
    assert run.quaternion_norm_drift < 1e-11


def _energy_errors(order: int, step: float, n_steps: int, samples: int):
    t = np.linspace(0.0, step * n_steps, samples)
    run = integrate_free_top(I_REF, W_REF, t, method="splitting", order=order, step=step, estimate_error=False)
    assert run.n_steps == n_steps
    E = 0.5 * np.sum(np.array(I_REF) * run.omega**2, axis=1)
    return t, (E - E[0]) / E[0], run


def _bounded(t: np.ndarray, dE: np.ndarray) -> bool:
    """No drift: the last tenth of the run is no worse than the first tenth (which already spans
    ≳ 70 polhode periods, the envelope of the oscillation), and a linear trend explains < 1% of the range."""
    tenth = len(t) // 10
    first, last = np.max(np.abs(dE[:tenth])), np.max(np.abs(dE[-tenth:]))
    slope = np.polyfit(t, dE, 1)[0]
    return bool(last < 1.05 * first and abs(slope) * t[-1] < 0.01 * np.ptp(dE))


def _assert_bounded_energy(t, dE, run):
    assert run.angular_momentum_drift < 5e-13  # |L| kept to rounding: ~sqrt(#sub-flows) ulps
    assert _bounded(t, dE)


def test_bounded_energy_check_detects_drift():
    """The same check fails for DOP853, whose energy error grows linearly (it is not geometric)."""
    t = np.linspace(0.0, 5000.0, 2001)
    run = integrate_free_top(I_REF, W_REF, t, rtol=1e-5, atol=1e-7, estimate_error=False)
    E = 0.5 * np.sum(np.array(I_REF) * run.omega**2, axis=1)
    assert not _bounded(t, (E - E[0]) / E[0])


def test_splitting_energy_error_bounded_1e5_steps():
    t, dE, run = _energy_errors(order=2, step=0.05, n_steps=100_000, samples=2001)
    assert np.max(np.abs(dE)) < 1e-4  # order 2 at h = 0.05: ~7e-6 (bounded, from the 4 s runs above)
    _assert_bounded_energy(t, dE, run)


@pytest.mark.slow
def test_splitting_energy_error_bounded_1e6_steps():
    t, dE, run = _energy_errors(order=2, step=0.05, n_steps=1_000_000, samples=4001)
    assert np.max(np.abs(dE)) < 1e-4
    _assert_bounded_energy(t, dE, run)


# --- torque ----------------------------------------------------------------------------------

def test_constant_space_torque_makes_L_grow_linearly():
    tau_space = np.array([0.3, -0.2, 0.5])
    R0 = Rotation.from_euler("ZXZ", [1.0, 0.5, 0.2]).as_matrix().T

    def torque(_t, _w, R):  # body components of a space-fixed vector: τ_a = R_ab τ̃_b (3.3)
        return R @ tau_space

    t = np.linspace(0.0, 10.0, 21)
    run = integrate_free_top(I_REF, W_REF, t, R0=R0, torque=torque, rtol=1e-12, atol=1e-14)
    L_space = np.einsum("nab,na->nb", run.R, np.array(I_REF) * run.omega)
    # dL/dt = τ (3.31 with torque): L̃(t) = L̃(0) + τ̃ t; rtol 1e-12 over 10 s
    assert np.max(np.abs(L_space - (L_space[0] + np.outer(t, tau_space)))) < 1e-9


def test_body_torque_along_omega_on_a_sphere_is_exponential():
    k, I = 0.3, 2.0
    t = np.linspace(0.0, 3.0, 7)
    run = integrate_free_top([I, I, I], [0.1, 0.2, -0.3], t, torque=lambda _t, w, _R: k * w,
                             rtol=1e-12, atol=1e-14)
    # I ω̇ = k ω  ⇒  ω = ω0 exp(k t / I)
    exact = np.outer(np.exp(k * t / I), [0.1, 0.2, -0.3])
    np.testing.assert_allclose(run.omega, exact, rtol=1e-10)


def test_bad_torque_output_raises():
    with pytest.raises(ShapeError, match=r"expected `torque\(t, omega, R\)` to return shape \(3,\), got \(2,\)"):
        integrate_free_top(I_REF, W_REF, [0.0, 1.0], torque=lambda t, w, R: w[:2])
    with pytest.raises(InvalidInputError, match=r"expected `torque` to be callable"):
        integrate_free_top(I_REF, W_REF, [0.0, 1.0], torque=[0.0, 0.0, 1.0])


# --- the ensemble ----------------------------------------------------------------------------

def test_ensemble_matches_single_runs(rng):
    M = 5
    w0 = rng.normal(size=(M, 3))
    I = np.array([[1.0, 2.0, 3.0], [1.0, 1.0, 1.5], [2.0, 2.5, 3.0], [1.0, 1.2, 2.0], [3.0, 2.0, 1.5]])
    R0 = Rotation.random(M, random_state=3).as_matrix().transpose(0, 2, 1)
    t = np.linspace(0.0, 3.0, 7)
    ens = integrate_free_top_ensemble(I, w0, t, step=0.05, order=4, R0=R0)
    assert ens.omega.shape == (7, M, 3) and ens.quaternion.shape == (7, M, 4) and ens.R.shape == (7, M, 3, 3)
    for m in range(M):
        one = integrate_free_top(I[m], w0[m], t, R0=R0[m], method="splitting", order=4, step=0.05,
                                 estimate_error=False)
        # same arithmetic in NumPy and in Python floats, up to operation order: rounding only
        assert np.max(np.abs(ens.omega[:, m] - one.omega)) < 1e-13
        assert np.max(np.abs(ens.quaternion[:, m] - one.quaternion)) < 1e-13
        assert ens.energy_drift[m] == pytest.approx(one.energy_drift, rel=1e-6, abs=1e-15)
    assert ens.n_steps == 60 and ens.body_steps_per_second > 0


def test_ensemble_of_one_with_default_orientation():
    t = np.linspace(0.0, 2.0, 5)
    ens = integrate_free_top_ensemble(I_REF, [W_REF], t, step=0.05, order=6)
    one = integrate_free_top(I_REF, W_REF, t, method="splitting", order=6, step=0.05, estimate_error=False)
    assert np.max(np.abs(ens.omega[:, 0] - one.omega)) < 1e-14  # rounding only
    assert np.max(np.abs(ens.R[:, 0] - one.R)) < 1e-14


def test_ensemble_chunks_do_not_change_results(rng):
    L = rng.normal(size=(3, 10))
    q = np.tile([[1.0], [0.0], [0.0], [0.0]], (1, 10))
    L2, q2 = L.copy(), q.copy()
    lie_poisson.propagate_ensemble(L, q, np.array([1.0, 2.0, 3.0]), 0.1, 20, yoshida6())
    lie_poisson.propagate_ensemble(L2, q2, np.array([1.0, 2.0, 3.0]), 0.1, 20, yoshida6(), chunk=3)
    assert np.array_equal(L, L2) and np.array_equal(q, q2)


# --- composition weights ---------------------------------------------------------------------

@pytest.mark.parametrize("weights, order", [(triple_jump(4), 4), (suzuki_fractal(4), 4), (triple_jump(6), 6),
                                            (suzuki_fractal(6), 6), (yoshida6(), 6)])
def test_composition_order_conditions(weights, order):
    w = np.array(weights)
    assert np.array_equal(w, w[::-1])  # palindromic, so the composition is symmetric (even order)
    assert abs(w.sum() - 1) < 1e-14
    assert abs(np.sum(w**3)) < 1e-13
    if order == 6:
        assert abs(np.sum(w**5)) < 1e-12  # Yoshida's 15-digit weights: residual ~1e-14


def test_merged_sequence_counts():
    assert len(merged_sequence(yoshida6(), 3)) == 7 * 4 + 1
    assert lie_poisson.subflows_per_step(SPLITTING_ORDERS[4]) == 5 * 4
    assert sum(c for a, c in merged_sequence(suzuki_fractal(4), 3) if a == 2) == pytest.approx(1.0, abs=1e-15)


# --- bad input -------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, error, message", [
    ({"I": [1.0, 0.5, 3.0]}, UnphysicalInertiaError,
     r"expected I1 \+ I2 >= I3 \(triangle inequality\), got I1 \+ I2 = 1.5 < I3 = 3"),
    ({"I": [3.0, 1.0, 1.5]}, UnphysicalInertiaError,
     r"expected I2 \+ I3 >= I1 \(triangle inequality\), got I2 \+ I3 = 2.5 < I1 = 3"),
    ({"I": [-1.0, 2.0, 3.0]}, UnphysicalInertiaError, r"expected principal moments > 0 \(3.22\), got I1 = -1"),
    ({"I": [0.0, 2.0, 2.0]}, UnphysicalInertiaError, r"expected principal moments > 0 \(3.22\), got I1 = 0"),
    ({"I": [1.0, float("nan"), 2.0]}, NonFiniteValueError, r"expected `I` to be finite, got nan"),
    ({"I": [1.0, 2.0]}, ShapeError, r"expected `I` to have shape \(3,\), got \(2,\)"),
    ({"omega0": [1.0, 2.0]}, ShapeError, r"expected `omega0` to have shape \(3,\), got \(2,\)"),
    ({"omega0": [1.0, float("inf"), 2.0]}, NonFiniteValueError, r"expected `omega0` to be finite, got inf"),
    ({"t_eval": [0.0, 2.0, 1.0]}, InvalidInputError,
     r"expected `t_eval` strictly increasing, got t_eval\[2\] = 1 <= t_eval\[1\] = 2"),
    ({"t_eval": [0.0]}, InvalidInputError, r"expected `t_eval` to hold at least 2 times, got 1"),
    ({"t_eval": [[0.0, 1.0]]}, ShapeError, r"expected `t_eval` to have shape \(N,\), got \(1, 2\)"),
    ({"method": "RK4"}, InvalidInputError, r"expected method one of 'DOP853', 'splitting', got 'RK4'"),
    ({"method": "splitting", "step": 0.1, "order": 3}, InvalidInputError,
     r"expected order one of 2, 4, 6, got 3"),
    ({"method": "splitting"}, InvalidInputError, r"expected a step size `step` > 0 .* got step=None"),
    ({"method": "splitting", "step": -0.1}, InvalidInputError, r"expected `step` > 0, got -0.1"),
    ({"method": "splitting", "step": 0.1, "rtol": 1e-8}, InvalidInputError,
     r"expected `rtol` only with method='DOP853', got rtol=1e-08"),
    ({"method": "splitting", "step": 0.1, "torque": lambda t, w, R: w}, InvalidInputError,
     r"expected torque=None with method='splitting'"),
    ({"step": 0.1}, InvalidInputError, r"expected `step` only with method='splitting', got step=0.1"),
    ({"rtol": 0.0}, InvalidInputError, r"expected `rtol` > 0, got 0.0"),
    ({"R0": np.diag([1.0, 1.0, -1.0])}, NotARotationError, r"expected `R0` to have det \+1"),
    ({"R0": np.eye(2)}, ShapeError, r"expected `R0` to have shape \(3, 3\), got \(2, 2\)"),
])
def test_bad_input_raises(kwargs, error, message):
    args = {"I": I_REF, "omega0": W_REF, "t_eval": [0.0, 1.0]}
    args.update(kwargs)
    I, w0, t = args.pop("I"), args.pop("omega0"), args.pop("t_eval")
    with pytest.raises(error, match=message):
        integrate_free_top(I, w0, t, **args)


def test_ensemble_bad_input_raises():
    with pytest.raises(ShapeError, match=r"expected `omega0` to have shape \(N, 3\), got \(3,\)"):
        integrate_free_top_ensemble(I_REF, W_REF, [0.0, 1.0], step=0.1)
    with pytest.raises(UnphysicalInertiaError, match=r"expected I1 \+ I2 >= I3 \(triangle inequality\)"):
        integrate_free_top_ensemble([[1.0, 2.0, 3.0], [1.0, 0.5, 3.0]], np.ones((2, 3)), [0.0, 1.0], step=0.1)
    with pytest.raises(ShapeError, match=r"expected `I` to have shape \(2, 3\), got \(3, 3\)"):
        integrate_free_top_ensemble(np.ones((3, 3)), np.ones((2, 3)), [0.0, 1.0], step=0.1)
    with pytest.raises(ShapeError, match=r"expected `R0` to have shape \(3, 3\) or \(2, 3, 3\), got \(3, 3, 3\)"):
        integrate_free_top_ensemble(I_REF, np.ones((2, 3)), [0.0, 1.0], step=0.1, R0=np.tile(np.eye(3), (3, 1, 1)))
