"""The one integration driver (mechderive.solvers.driver): a term, DOP853 (C or SciPy), the splittings,
the error estimates, the tolerance controller, the refusals.

The free and heavy tops run through the driver in their own tests (test_free_top_integrate.py,
test_heavy_top_integrate.py, test_integrated_angles.py, ...); here the driver is exercised directly: on a
term of its own (the harmonic oscillator, whose exact solution is known) and on the tops' terms with
both splittings, each against an independent reference.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechderive.core import cbuild
from mechderive.errors import InvalidInputError
from mechderive.kinematics.conversions import euler_to_quaternion, quaternion_to_matrix
from mechderive.kinematics.rotations import euler_angles_from_matrix
from mechderive.solvers import driver
from mechderive.solvers.half_angles import half_angles_of_quaternion, rotation_angle_between

BACKENDS = ["scipy"] + (["c"] if cbuild.c_enabled() else [])


def _oscillator_exprs():
    import sympy as sp

    x, v, k = sp.symbols("x v k")
    return [v, -k * x], [x, v], [k]


def _oscillator_energy():
    import sympy as sp

    x, v, k = sp.symbols("x v k")
    return [v**2 / 2 + k * x**2 / 2]


#: x'' = -k x: x = cos(√k t) from (1, 0).
OSCILLATOR = driver.Term("test_driver_oscillator", _oscillator_exprs, invariants=_oscillator_energy,
                         invariant_names=("energy",))


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_term_of_its_own_within_its_error_estimate(backend):
    t = np.linspace(0.0, 20.0, 201)
    run = driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], rtol=1e-9, backend=backend)
    exact = np.stack([np.cos(2.0 * t), -2.0 * np.sin(2.0 * t)], axis=-1)
    err = np.max(np.abs(run.y - exact), axis=0)
    # the estimate is the distance to a 1000× tighter rerun (× 1.03): it must cover the true error, and
    # be of its size (a factor 10 is the measured ratio of DOP853's global errors at r = 1e-3, with margin)
    assert np.all(err <= run.component_error) and np.all(run.component_error <= 10 * err + 1e-15)
    assert run.error_estimate == pytest.approx(float(np.max(run.component_error)))
    assert run.backend == backend and run.method == "DOP853" and "distance to" in run.error_estimate_kind
    # E = 2 exactly; the drift is the integrator's error in x and v (≤ the estimate × |∇E| ≲ 2 × 2)
    assert np.max(np.abs(run.invariant("energy") - 2.0)) <= 4 * run.error_estimate
    assert run.quaternion is None and run.euler_angles is None and run.estimates is None


def test_compiled_and_scipy_take_the_same_steps():
    if "c" not in BACKENDS:
        pytest.skip("no C compiler")
    t = np.linspace(0.0, 20.0, 201)
    c, s = (driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], rtol=1e-9, backend=b, estimate_error=False)
            for b in ("c", "scipy"))
    # the same tableau, controller and dense output: the same steps; the states differ by rounding (the
    # C compiler's order of operations), which the steps carry along like the truncation error: measured
    # 2 % of the error (7e-11 against 3e-9), 10 % allowed
    truth = np.stack([np.cos(2.0 * t), -2.0 * np.sin(2.0 * t)], axis=-1)
    assert c.n_steps == s.n_steps
    assert np.max(np.abs(c.y - s.y)) <= 0.1 * np.max(np.abs(s.y - truth))


def test_the_controller_tightens_until_the_estimate_meets_rtol():
    t = np.linspace(0.0, 200.0, 201)
    traj, attempts = driver.integrate_to_rtol(
        lambda tol: driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], rtol=tol), lambda tr: tr.error_estimate, 1e-9)
    # at rtol 1e-9 a 64-period run is off by ~6e-8 (measured): one rerun, tighter, meets 1e-9
    assert len(attempts) == 2 and attempts[0]["error_estimate"] > 1e-9 >= attempts[1]["error_estimate"]
    assert np.max(np.abs(traj.y[:, 0] - np.cos(2.0 * t))) <= 1e-9


@pytest.mark.parametrize("top", ["free_top", "heavy_top"])
def test_both_splittings_within_their_estimates(top):
    # the free symmetric top (I = 1, 1, 0.5) by the Lie–Poisson splitting and the heavy top by the
    # kick–drift–kick splitting on its derived stage map, against DOP853 at rtol 1e-13 on the same term
    from mechderive.systems.free_top.integrate import TERM as FREE
    from mechderive.systems.heavy_top.integrate import TERM as HEAVY

    term, par = {"free_top": (FREE, (1.0, 1.0, 0.5, 0.0, 0.0, 0.0)),
                 "heavy_top": (HEAVY, (1.0, 0.5, 1.0, 4.0, 0.25))}[top]
    q0 = euler_to_quaternion(0.2, 0.5, 0.1)
    y0, args0 = np.array([0.3, 0.1, 5.0, *q0]), (0.15, 0.05)
    t = np.linspace(0.0, 3.0, 7)
    ref = driver.integrate(term, y0, t, par, rtol=1e-13, track=args0)
    run = driver.integrate(term, y0, t, par, method="splitting", step=0.01, order=4, track=args0)
    assert run.method == "splitting" and run.order == 4 and "Richardson" in run.error_estimate_kind
    slack = ref.error_estimate  # the reference's own error (~3e-12), far below the splitting's (~1e-9)
    assert np.max(np.abs(run.omega - ref.omega)) <= run.omega_error_estimate + slack
    assert np.max(rotation_angle_between(run.quaternion, ref.quaternion)) <= run.rotation_error_estimate + slack
    assert np.max(np.abs(run.euler_angles - ref.euler_angles)) <= run.euler_angle_error_estimate + slack
    assert run.error_estimate == max(run.estimates.values()) < 1e-7
    # R is that of the projected quaternion, |q| drifts only by rounding in the exact sub-flows
    assert np.allclose(run.R, quaternion_to_matrix(run.quaternion), rtol=0, atol=0)
    assert run.quaternion_norm_drift < 1e-13


def test_half_angles_of_a_quaternion_give_its_euler_angles(rng):
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        q_signed, (sigma, delta) = half_angles_of_quaternion(q)
        phi, theta, psi = euler_angles_from_matrix(quaternion_to_matrix(q))
        # the same rotation, with the sign of euler_to_quaternion at the angles σ ± δ (1e-15: rounding)
        assert np.allclose(q_signed, euler_to_quaternion(sigma + delta, theta, sigma - delta), rtol=0, atol=1e-15)
        assert abs(abs(float(np.dot(q_signed, q))) - 1.0) < 1e-15
        assert math.isclose(sigma + delta, phi, abs_tol=1e-15) and math.isclose(sigma - delta, psi, abs_tol=1e-15)


def test_refusals_say_what_is_allowed():
    t = [0.0, 1.0]
    with pytest.raises(InvalidInputError, match="expected method one of 'DOP853', 'splitting', got 'RK4'"):
        driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], rtol=1e-9, method="RK4")
    with pytest.raises(InvalidInputError, match="expected `rtol` > 0 with method='DOP853', got rtol=None"):
        driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0])
    with pytest.raises(InvalidInputError, match="expected a term with a splitting"):
        driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], method="splitting", step=0.1)
    with pytest.raises(InvalidInputError, match="has no quaternion to track"):
        driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], rtol=1e-9, track=(0.0, 0.0))
    with pytest.raises(InvalidInputError, match="backend='auto' or 'scipy' with `parameters_at`"):
        driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], rtol=1e-9, backend="c", parameters_at=lambda t, y: [4.0])
    with pytest.raises(InvalidInputError, match="expected `step` only with method='splitting'"):
        driver.check_method_options("DOP853", rtol=1e-9, atol=None, step=0.1, order=None)
    with pytest.raises(InvalidInputError, match="expected order one of 2, 4, 6, got 3"):
        driver.check_method_options("splitting", rtol=None, atol=None, step=0.1, order=3)


def test_parameters_computed_in_python_drive_scipy():
    # k from a Python function of (t, y): the same motion as the constant k = 4
    t = np.linspace(0.0, 5.0, 11)
    run = driver.integrate(OSCILLATOR, [1.0, 0.0], t, [4.0], rtol=1e-10, parameters_at=lambda t_, y: (4.0,))
    assert run.backend == "scipy"
    assert np.max(np.abs(run.y[:, 0] - np.cos(2.0 * t))) <= run.error_estimate
