"""system = "rigid_body": any rigid body about a fixed point in uniform gravity, end to end through scenes.

References are independent of the package: closed forms of other solvers agree with the integration;
Kovalevskaya's invariant and the hand-written Euler–Poisson equations are written here; the torque
cases have elementary exact solutions.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from mechderive.errors import InvalidInputError, MechDeriveError, UnphysicalInertiaError
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import load_scene, parse_scene
from mechderive.systems import registry
from mechderive.systems.rigid_body.system import rigid_body

ALL = ["omega1", "omega2", "omega3", "L1", "R11", "R13", "R23", "R33", "q0", "q3", "apex_x", "apex_z", "phi",
       "theta", "psi", "energy", "L_vertical"]


def _run(body, initial, *, t_end=5.0, samples=101, quantities=ALL, method="auto", rtol=1e-10, strict=True):
    return run_scene(parse_scene(body.scene_mapping(initial, t_end=t_end, samples=samples, quantities=quantities,
                                                    method=method, rtol=rtol, strict=strict)))


def _agree(a, b, tol):
    for k in a.columns:
        assert np.max(np.abs(a.columns[k] - b.columns[k])) <= tol, k


def test_free_body_closed_form_agrees_with_integration():
    body = rigid_body(1.0, 2.0, 3.0)  # c = 0: gravity exerts no torque
    init = {"omega": [1.0, 0.5, 1.0], "phi": 0.3, "theta": 0.4, "psi": -0.2}
    exact, num = _run(body, init), _run(body, init, method="integrate")
    assert exact.report["method"] == "exact" and "free top" in exact.report["details"]["solver"]
    assert num.report["method"] == "integrate" and num.report["details"]["why"] == "method = 'integrate'"
    # both estimates are ≤ rtol = 1e-10 (asserted): their difference is within their sum
    assert exact.report["rtol_met"] and num.report["rtol_met"]
    _agree(exact, num, exact.report["error_estimate"] + num.report["error_estimate"])


def test_heavy_symmetric_top_closed_form_agrees_with_integration():
    body = rigid_body(1.0, 1.0, 0.5, M=0.1, g=10.0, center_of_mass=(0.0, 0.0, 1.0))
    init = {"omega": [0.3, -0.2, 5.0], "phi": 0.1, "theta": 0.5, "psi": 0.2}
    q = [*ALL, "p_psi"]
    exact, num = _run(body, init, quantities=q), _run(body, init, quantities=q, method="integrate")
    assert exact.report["method"] == "exact" and "heavy symmetric top" in exact.report["details"]["solver"]
    assert exact.report["rtol_met"] and num.report["rtol_met"]
    # energy, L_vertical are sums of terms ~ T + M g l ≈ 7 (J): their errors are ω's and R's times that
    _agree(exact, num, 10 * (exact.report["error_estimate"] + num.report["error_estimate"]))
    # p_ψ = I3 ω3 is found conserved by the derivation, and the gyroscopic form keeps ω3 exactly
    assert set(num.report["drift"]) == {"energy", "L_vertical", "p_psi"} and num.report["drift"]["p_psi"] == 0.0


@pytest.mark.parametrize("theta", [math.pi, 1e-9])
def test_heavy_top_at_the_poles_closed_form_agrees_with_integration(theta):
    # at θ = π exactly (hanging) the Euler rates of (3.58) divide by sin(fl(π)) ~ 1e-16: the closed form must
    # still agree with the integration of (ω, q), which has no singularity there
    body = rigid_body(1.0, 1.0, 0.5, M=0.1, g=10.0, center_of_mass=(0.0, 0.0, 1.0))
    q = ["omega1", "omega2", "omega3", "R13", "R23", "R33", "theta", "energy", "L_vertical"]
    init = {"omega": [0.1, 0.0, 3.0], "theta": theta}
    exact, num = _run(body, init, quantities=q), _run(body, init, quantities=q, method="integrate")
    assert exact.report["method"] == "exact" and exact.report["rtol_met"] and num.report["rtol_met"]
    _agree(exact, num, 10 * (exact.report["error_estimate"] + num.report["error_estimate"]))


def test_symmetric_top_with_centre_of_mass_below_pivot_is_integrated_and_says_why():
    body = rigid_body(1.0, 1.0, 0.5, M=0.1, g=10.0, center_of_mass=(0.0, 0.0, -1.0))
    r = _run(body, {"omega": [0.0, 0.0, 5.0], "theta": 0.5}, quantities=["theta"])
    assert r.report["method"] == "integrate" and "l = c3 > 0" in r.report["note"]
    assert "no closed form applies" in r.report["details"]["why"]


def _kovalevskaya_K(w, gamma, nu):
    """Kovalevskaya's integral for I = (2C, 2C, C), c = (x0, 0, 0): |(ω1 + i ω2)² - ν (γ1 + i γ2)|², ν = M g x0 / C
    (the time derivative of this form vanishes along τ = M g γ × c, γ̇ = γ × ω: checked by hand with SymPy)."""
    p, q = w[..., 0], w[..., 1]
    A, B = p * p - q * q - nu * gamma[..., 0], 2 * p * q - nu * gamma[..., 1]
    return A * A + B * B, (A, B)


def test_kovalevskaya_top_conserves_its_invariant():
    C, M, g, x0 = 1.0, 1.0, 9.81, 0.5  # I_cm = (2, 1.75, 0.75): a real body
    body = rigid_body(2 * C, 2 * C, C, M=M, g=g, center_of_mass=(x0, 0.0, 0.0))
    r = _run(body, {"omega": [1.0, -2.0, 3.0], "theta": 1.0, "phi": 0.2, "psi": 0.7}, t_end=20.0, samples=401,
             quantities=["omega1", "omega2", "R13", "R23"], rtol=1e-11)
    assert r.report["method"] == "integrate"  # I1 = I2 but c off the axis: no closed form
    c = r.columns
    w = np.stack([c["omega1"], c["omega2"]], axis=-1)
    gamma = np.stack([c["R13"], c["R23"]], axis=-1)
    nu = M * g * x0 / C
    K, (A, B) = _kovalevskaya_K(w, gamma, nu)
    # tolerance: the run's own estimate e (ω in rad/s, R entries) propagated to first order into K
    e = r.report["error_estimate"]
    dK = 2 * (np.abs(A) + np.abs(B)) * (2 * (np.abs(w[:, 0]) + np.abs(w[:, 1])) * e + abs(nu) * e)
    assert np.all(np.abs(K - K[0]) <= 2 * np.max(dK))
    assert np.ptp(c["omega1"]) > 0.5


def _euler_poisson_reference(I, M, g, c, w0, gamma0, t_end, dps=30):
    """Hand-written Euler equations with the gravity torque τ = M g γ × c (the weight -M g γ at c) and
    Poisson's γ̇ = γ × ω for the body components γ of the space vertical, by mpmath's Taylor integrator."""
    with mpmath.workdps(dps):
        I = [mpmath.mpf(x) for x in I]
        c = [mpmath.mpf(x) for x in c]
        mg = mpmath.mpf(M) * mpmath.mpf(g)

        def f(_t, y):
            w1, w2, w3, g1, g2, g3 = y
            tau = (mg * (g2 * c[2] - g3 * c[1]), mg * (g3 * c[0] - g1 * c[2]), mg * (g1 * c[1] - g2 * c[0]))
            return [((I[1] - I[2]) * w2 * w3 + tau[0]) / I[0], ((I[2] - I[0]) * w3 * w1 + tau[1]) / I[1],
                    ((I[0] - I[1]) * w1 * w2 + tau[2]) / I[2],
                    g2 * w3 - g3 * w2, g3 * w1 - g1 * w3, g1 * w2 - g2 * w1]
        sol = mpmath.odefun(f, 0, [mpmath.mpf(x) for x in (*w0, *gamma0)], tol=mpmath.mpf(10) ** (-dps + 2))
        return np.array([[float(x) for x in sol(mpmath.mpf(t_end))]])


def test_asymmetric_top_at_theta_zero_exactly_against_30_digit_reference():
    I, M, g, cm = (2.0, 3.0, 4.0), 1.0, 9.81, (0.1, 0.05, 0.5)
    w0 = (0.7, -0.4, 6.0)
    body = rigid_body(*I, M=M, g=g, center_of_mass=cm)
    r = _run(body, {"omega": list(w0), "theta": 0.0, "phi": 0.3, "psi": -0.1}, t_end=1.5, samples=4,
             quantities=["omega1", "omega2", "omega3", "R13", "R23", "R33", "phi", "theta", "psi", "R11", "R12",
                         "R21"], rtol=1e-12)
    c = r.columns
    assert c["theta"][0] == 0.0 and np.all(np.isfinite(c["phi"])) and np.all(np.isfinite(c["psi"]))
    # γ(0) = (sin θ sin ψ, sin θ cos ψ, cos θ) (3.57) = ẽ3 at θ = 0
    ref = _euler_poisson_reference(I, M, g, cm, w0, (0.0, 0.0, 1.0), 1.5)[0]
    got = np.array([c[k][-1] for k in ("omega1", "omega2", "omega3", "R13", "R23", "R33")])
    e = r.report["error_estimate"]
    # the estimate (ω rad/s, R entries) must bound the true error; the reference's own error is ~1e-28
    assert e <= 1e-12 and np.max(np.abs(got - ref)) <= e
    # the continuous Euler angles output reproduce R (3.54) at every sample to the angles' estimate
    from mechderive.kinematics.rotations import rotation_matrix
    R = rotation_matrix(c["phi"], c["theta"], c["psi"])
    for k in ("R11", "R12", "R21", "R13", "R33"):
        assert np.max(np.abs(R[:, int(k[1]) - 1, int(k[2]) - 1] - c[k])) <= 4 * e + 1e-14


def _long_run(periods: int):
    body = rigid_body(2.0, 3.0, 4.0, M=1.0, g=9.81, center_of_mass=(0.1, 0.0, 0.5))
    w = 20.0  # natural period 2π/ω0: the spin
    return _run(body, {"omega": [0.0, 0.0, w], "theta": 0.3}, t_end=periods * 2 * math.pi / w, samples=2001,
                quantities=["omega1", "R33", "energy", "L_vertical"])


def _check_long_run(r, bound):
    d = r.report["drift"]
    assert set(d) == {"energy", "L_vertical"} and all(math.isfinite(v) for v in d.values())
    # DOP853 at rtol ≤ 1e-10 with the quaternion renormalised at output: the invariants' drift is rounding
    # and truncation accumulated over the steps, a few hundred ulp per 10⁴ steps measured (1e-13 at 10⁴ periods)
    assert max(d.values()) <= bound
    assert "max_t (T + |V|)" in r.report["drift_relative_to"]["energy"]


def test_long_run_bounded_drift():
    _check_long_run(_long_run(1000), 1e-11)


@pytest.mark.slow
def test_long_run_ten_thousand_periods():
    _check_long_run(_long_run(10_000), 1e-11)


def test_motor_torque_depending_on_t_matches_the_exact_spin_up():
    # a symmetric free body (I1 = I2, c = 0): ω̇3 = τ3 / I3 exactly, so ω3 = ω3(0) + 0.1 t² / I3 for τ3 = 0.2 t
    body = rigid_body(1.0, 1.0, 1.5, torque=["0", "0", "0.2*t"])
    assert body.methods == ("integrate",)
    r = _run(body, {"omega": [0.5, 0.0, 1.0], "theta": 0.2}, t_end=3.0, samples=31,
             quantities=["omega3", "energy", "L_vertical", "L3"])
    t = r.t
    assert np.max(np.abs(r.columns["omega3"] - (1.0 + 0.1 * t**2 / 1.5))) <= max(r.report["error_estimate"], 1e-14)
    assert r.report["drift"] == {}  # with a torque, E and L·ẽ3 are outputs only
    # the energy the motor put in: ΔE = ½ I3 (ω3² - ω3(0)²) (ω1² + ω2² is constant for I1 = I2, τ1 = τ2 = 0)
    dE = r.columns["energy"] - r.columns["energy"][0]
    assert np.max(np.abs(dE - 0.75 * (r.columns["omega3"] ** 2 - 1.0))) <= 1e-8


def test_damper_torque_decays_spin():
    body = rigid_body(1.0, 1.0, 1.5, torque=["0", "0", "-0.3*omega3"])  # ω3 = ω3(0) exp(-0.2 t)
    r = _run(body, {"omega": [0.0, 0.0, 2.0]}, t_end=2.0, samples=11, quantities=["omega3"])
    assert np.max(np.abs(r.columns["omega3"] - 2.0 * np.exp(-0.2 * r.t))) <= max(r.report["error_estimate"], 1e-14)


def test_scene_file_through_cli(tmp_path):
    from mechderive.cli import main

    path = tmp_path / "top.toml"
    path.write_text(registry.get("rigid_body").example_scene().replace("t_end = 20.0", "t_end = 1.0")
                    .replace("samples = 2001", "samples = 11"))
    out = tmp_path / "out.csv"
    assert main(["run", str(path), "-o", str(out)]) in (0, None)
    lines = out.read_text().splitlines()
    assert lines[0].split(",")[:2] == ["t", "omega1"] and len(lines) >= 12
    r = run_scene(load_scene(path.read_text()))
    assert r.report["rtol_met"] and r.report["method"] == "integrate"


@pytest.mark.parametrize("change, message", [
    ({"torque": {"components": ["__import__('os')", "0", "0"]}}, "scene key \\[torque\\].components"),
    ({"torque": {"components": ["0", "0"]}}, "expected a list of 3 formula strings"),
    ({"torque": {"components": ["x", "0", "0"]}}, "may use t, omega1"),
    ({"torque": {"comps": []}}, "scene key \\[torque\\].comps: unknown key"),
    ({"parameters": {"I1": 1.0, "I2": 1.0, "I3": 3.0}}, "triangle inequality"),
    ({"parameters": {"I1": 1.0, "I2": 2.0, "I3": 3.0, "M": 1.0, "center_of_mass": [0.1, 0.0, 0.5]}},
     "centre of mass"),
    ({"parameters": {"I1": 1.0, "I2": 1.0, "I3": 1.0, "g": -1.0}}, "scene key \\[parameters\\].g"),
    ({"parameters": {"I1": 1.0, "I2": 1.0, "I3": 1.0, "l": 1.0}}, "scene key \\[parameters\\].l: unknown key"),
    ({"initial": {"omega": [1.0, 2.0]}}, "scene key \\[initial\\].omega: expected a list of 3"),
    ({"initial": {"omega": [1.0, 2.0, 3.0], "theta": 4.0}}, "scene key \\[initial\\].theta: expected a number in"),
])
def test_refusals_name_the_key(change, message):
    scene = {"system": "rigid_body", "parameters": {"I1": 1.0, "I2": 1.0, "I3": 1.5},
             "initial": {"omega": [0.0, 0.0, 1.0]}, "time": {"t_end": 1.0, "samples": 3},
             "output": {"quantities": ["omega1"]}}
    scene.update(change)
    with pytest.raises(InvalidInputError, match=message):
        run_scene(parse_scene(scene))


def test_strict_false_runs_and_reports_what_was_waived():
    body = rigid_body(1.0, 2.0, 3.0, M=1.0, center_of_mass=(0.1, 0.0, 0.5), strict=False)  # the example
    r = _run(body, {"omega": [0.0, 0.0, 20.0], "theta": 0.3}, t_end=0.5, quantities=["omega1"], strict=False)
    assert any("centre of mass" in w for w in r.report["waived"])
    with pytest.raises(UnphysicalInertiaError, match="I_cm"):
        rigid_body(1.0, 2.0, 3.0, M=1.0, center_of_mass=(0.1, 0.0, 0.5))


def test_p_psi_and_exact_refused_where_they_do_not_apply():
    body = rigid_body(2.0, 3.0, 4.0, M=1.0, center_of_mass=(0.1, 0.0, 0.5))
    with pytest.raises(InvalidInputError, match="p_psi only for a body symmetric"):
        _run(body, {"omega": [0.0, 0.0, 1.0]}, quantities=["p_psi"])
    with pytest.raises(MechDeriveError, match="no closed form for this body"):
        _run(body, {"omega": [0.0, 0.0, 1.0]}, quantities=["omega1"], method="exact")


def test_derived_equations_match_hand_written_euler_equations():
    import sympy as sp

    from mechderive.systems.rigid_body import model as rm

    eqs = {d.name: d for d in registry.get("rigid_body").derivations()}["euler_equations"].build(None)
    I, (w1, w2, w3), (c1, c2, c3) = (rm.I1, rm.I2, rm.I3), rm.omega_symbols(), rm.c_symbols
    R = rm.rotation_symbols()
    g1, g2, g3 = R[0, 2], R[1, 2], R[2, 2]
    wd = sp.symbols("omega1_dot omega2_dot omega3_dot", real=True)
    mg = rm.M * rm.g
    hand = [I[0] * wd[0] - (I[1] - I[2]) * w2 * w3 - mg * (g2 * c3 - g3 * c2),
            I[1] * wd[1] - (I[2] - I[0]) * w3 * w1 - mg * (g3 * c1 - g1 * c3),
            I[2] * wd[2] - (I[0] - I[1]) * w1 * w2 - mg * (g1 * c2 - g2 * c1)]
    assert all(sp.expand(a - b) == 0 for a, b in zip(eqs, hand))


@pytest.mark.slow
def test_bench_row_baseline_is_the_same_body():
    # the bench's hand-written sympy.physics.mechanics body (an independent derivation: Lagrange's equations
    # in Euler angles) and the scene agree, each within its tolerance (both run at rtol 1e-10: 1e-8 is the
    # global error their error-controlled steps allow over 2 s of a 20 rad/s spin, with margin)
    from mechderive.bench.rigid_body import rigid_body_work_precision

    result = rigid_body_work_precision(quick=True, repeat=1)
    rows = {(r["family"], r["setting"]): r for r in result["rows"]}
    assert rows[("baseline", "rtol 1e-08")]["max_error"] <= 1e-6
    assert rows[("rigid_body scene", "rtol 1e-10")]["max_error"] <= 1e-9
