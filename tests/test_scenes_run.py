"""Scenes end to end: the planner does only what a scene asks for, and `mechderive run` reports it."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from mechderive.cli import main
from mechderive.errors import InvalidInputError
from mechderive.scenes.builtin import load_builtin
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import load_scene

from .conftest import run_python

HEAVY = """
system = "heavy_top"
rtol = 1e-10
[parameters]
I1 = 1.0
I3 = 0.5
M = 0.1
g = 10.0
l = 1.0
[initial]
theta = 0.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 5.0
[time]
t_end = 20.0
samples = 201
[output]
quantities = ["u"]
"""


def test_asking_for_u_alone_neither_derives_nor_evaluates_phi_or_psi(tmp_path):
    (tmp_path / "u.toml").write_text(HEAVY)
    code = ("import json\nfrom mechderive.scenes.schema import load_scene\n"
            "from mechderive.scenes.planner import run_scene\nfrom pathlib import Path\n"
            f"r = run_scene(load_scene(Path({str(tmp_path / 'u.toml')!r})))\n"
            "print(json.dumps({'derived': r.report['derived'], 'evaluated': r.report['details']['evaluated']}))\n")
    proc = run_python("-c", code, env={"MECHDERIVE_NO_DISK_CACHE": "1"})  # derive for real
    assert proc.returncode == 0, proc.stderr
    rep = json.loads(proc.stdout)
    # sn² of the phase, and 1 ∓ u for the measured estimate's residual u̇² − f(u): nothing of φ or ψ
    assert rep["evaluated"] == ["phase", "jacobi", "1-u,1+u"]
    assert not any("fractions" in d or "precession" in d.lower() for d in rep["derived"]), rep["derived"]
    assert "HeavyTopExactModel.nutation_constants" in rep["derived"]


# The second run of the default scene from the disk cache, never importing SymPy: tests/test_bench.py
# (test_cold_start_splits_stages_and_the_warm_run_reads_the_disk_cache), on the bench's own cold and warm runs.


def test_auto_picks_the_closed_form_and_agrees_with_integration():
    scene = load_scene(HEAVY.replace('quantities = ["u"]', 'quantities = ["theta", "phi", "psi", "energy"]'))
    exact = run_scene(scene)
    integ = run_scene(dataclasses.replace(scene, method="integrate"))
    assert exact.report["method"] == "exact" and integ.report["method"] == "integrate"
    for q in ("theta", "phi", "psi"):
        # DOP853 at rtol 1e-10 over ~6 periods: ~1e-8; the closed form ~1e-13
        np.testing.assert_allclose(integ.columns[q], exact.columns[q], atol=1e-7)
    assert exact.report["drift"]["energy"] < 1e-14
    assert exact.report["error_estimate"] < 1e-12


def test_integrated_scene_tightens_until_its_estimate_meets_rtol():
    # DOP853 bounds the error per step; over 6 nutation periods the global error outgrows rtol
    # unless the planner tightens the integrator's tolerance (reruns at a smaller one).
    scene = load_scene(HEAVY.replace('quantities = ["u"]', 'quantities = ["theta", "phi", "psi"]'))
    exact = run_scene(scene)
    integ = run_scene(dataclasses.replace(scene, method="integrate"))
    attempts = integ.report["details"]["integrator_attempts"]
    assert attempts[0]["integrator_rtol"] == 1e-10 and attempts[0]["error_estimate"] > 1e-10  # the first falls short
    assert integ.report["rtol_met"] and integ.report["error_estimate"] <= 1e-10
    # the true error (against the closed form, itself ~1e-13) is of the estimate's size: ≤ 10× it
    err = max(np.max(np.abs(integ.columns[q] - exact.columns[q])) for q in ("theta", "phi", "psi"))
    assert err <= 10 * integ.report["error_estimate"]


def test_free_top_scene_quantities_are_consistent():
    scene = load_builtin("free_top_tumbling")
    r = run_scene(dataclasses.replace(scene, quantities=("omega1", "L1", "energy", "R11", "q0", "theta")))
    assert r.report["method"] == "exact"
    I1 = scene.parameters["I1"]
    np.testing.assert_allclose(r.columns["L1"], I1 * r.columns["omega1"], rtol=1e-15)
    assert r.report["drift"]["energy"] < 1e-14 and r.report["drift"]["L_norm"] < 1e-14


def test_unattainable_rtol_is_reported_not_hidden():
    # the continuous angles reach tens of rad, whose own rounding (ulp) exceeds 1e-15: the measured
    # estimate says so (u alone, rounded to ~1e-16, does meet 1e-15)
    scene = dataclasses.replace(load_scene(HEAVY.replace('["u"]', '["theta", "phi", "psi"]')), rtol=1e-15)
    r = run_scene(scene)
    assert r.report["rtol_met"] is False and "not met" in r.report["note"]


def test_exact_method_for_a_system_without_closed_form_is_refused():
    scene = dataclasses.replace(load_builtin("falling_cat"), method="exact")
    with pytest.raises(InvalidInputError, match="has no closed form"):
        run_scene(scene)


def test_cli_run_writes_the_requested_columns_in_order(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(HEAVY.replace('quantities = ["u"]', 'quantities = ["psi", "theta", "apex_z"]'))
    out = tmp_path / "out.csv"
    assert main(["run", str(path), "-o", str(out)]) == 0
    header = out.read_text().splitlines()[0]
    assert header == "t,psi,theta,apex_z"
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    np.testing.assert_allclose(data[:, 3], np.cos(data[:, 2]), atol=1e-15)  # apex_z = cos θ


def test_cli_run_json_report(capsys):
    assert main(["run", "default", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    for key in ("system", "method", "derived", "compiled", "timings", "error_estimate", "drift"):
        assert key in report
    assert set(report["timings"]) >= {"parse", "derive", "compile", "solve", "write"}
    assert set(report["drift"]) == {"energy", "p_phi", "p_psi"}


def test_cli_scenes_lists_and_prints(capsys):
    assert main(["scenes"]) == 0
    listing = capsys.readouterr().out
    assert "default" in listing and "falling_cat" in listing
    assert main(["scenes", "default"]) == 0
    assert 'system = "heavy_top"' in capsys.readouterr().out


def test_cli_run_unknown_scene_is_an_input_error(capsys):
    assert main(["run", "nope"]) == 2
    assert "expected a .toml file or a built-in scene" in capsys.readouterr().err


def test_falling_cat_scene_reports_its_integrators_error():
    scene = dataclasses.replace(load_builtin("falling_cat"), samples=51, quantities=("flip_angle", "L1"))
    r = run_scene(scene)
    est = r.report["error_estimate"]
    assert est is not None and 0 < est <= scene.rtol and r.report["rtol_met"]
    # the flip ends at π: the estimate is at least as large as that end-point error
    assert abs(r.columns["flip_angle"][-1] - np.pi) <= 10 * est
    # L = 0 against the angular momentum the turn carries (~0.1): as accurate as R, ~rtol
    assert r.report["drift"]["L"] <= scene.rtol and r.report["drift_relative_to"]["L"].startswith("max_t |Ĩ Ω| = ")


def test_near_pole_scene_phi_is_right_to_its_measured_estimate():
    # the apex passes ~5e-7 rad from the pole (stress case pole-pass-1e-3): φ and ψ each are
    # ill-conditioned there (conditioning ~2e9); the closed form evaluates them from the distance to
    # the turning point (double-double) and its measured estimate must cover the true error, taken
    # against the independent 30-digit Taylor reference (angles compared modulo 2π)
    from mechderive.stress.reference import heavy_reference

    near = HEAVY.replace("theta = 0.5", "theta = 1e-3").replace("theta_dot = 0.0", "theta_dot = 0.5") \
                .replace("psi_dot = 5.0", "psi_dot = 10.0").replace("t_end = 20.0", "t_end = 6.0") \
                .replace("samples = 201", "samples = 13")
    scene = load_scene(near.replace('quantities = ["u"]', 'quantities = ["phi", "R11", "R23", "apex_z"]'))
    run = run_scene(scene)
    assert run.report["method"] == "exact" and run.solution.conditioning > 1e9
    ref = heavy_reference(scene.parameters, scene.initial, run.t)
    err_phi = np.max(np.abs(np.angle(np.exp(1j * (run.columns["phi"] - ref.angles[:, 0])))))
    err_R = max(np.max(np.abs(run.columns["R11"] - ref.R[:, 0, 0])),
                np.max(np.abs(run.columns["R23"] - ref.R[:, 1, 2])))
    assert max(err_phi, err_R) <= run.report["error_estimate"]
    assert run.report["rtol_met"] is (run.report["error_estimate"] <= scene.rtol)
