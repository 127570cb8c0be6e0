"""Extreme but schema-valid numbers in scenes (issue 12, findings 5 and 7): solved right or refused by key.

Every outcome of ``mechderive run`` on a scene of valid numbers must be a correct answer (within
its reported estimate; checked here against references independent of the run: exact solutions,
scaling laws of the equations of motion, the same motion in ordinary units) or exit status 2 with
one line naming the scene key and what is allowed — never a traceback, a RuntimeWarning, a hang
or a NaN.  The reproductions of the issue run in-process; a deterministic sample of the sweep of
:mod:`.numeric_sweep` runs by default (in forked children: a hang cannot stop the suite) and the
whole sweep under ``-m slow``.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

from mechderive.cli import main

from .numeric_sweep import BASE, GOOD, _toml, _with, all_cases, sweep

DOUBLE_MAX = 1.7976931348623157e308


def _run(tmp_path, capsys, doc: dict, method: str = "auto", quantities: list[str] | None = None):
    """``mechderive run scene -o out.npz --json`` in-process: (status, report, columns, stderr lines).

    Every warning is recorded and must be none (a RuntimeWarning printed before a result or a
    refusal is a finding of the issue)."""
    doc = dict(doc, method=method)
    if quantities is not None:
        doc["output"] = {"quantities": quantities}
    path, out = tmp_path / "scene.toml", tmp_path / "out.npz"
    path.write_text(_toml(doc))
    out.unlink(missing_ok=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status = main(["run", str(path), "-o", str(out), "--json"])
    captured = capsys.readouterr()
    assert not caught, [str(w.message) for w in caught]
    err = [line for line in captured.err.splitlines() if line.strip()]
    if status != 0:
        assert not out.exists()
        return status, None, None, err
    assert not err, err
    with np.load(out) as data:
        columns = {k: data[k] for k in data.files}
    for name, col in columns.items():
        assert np.all(np.isfinite(col)), name
    return status, json.loads(captured.out), columns, err


def _refused(status: int, err: list[str], *keys: str) -> str:
    """The one line of a refusal, which names ``keys`` and says what is expected."""
    assert status == 2, err
    assert len(err) == 1 and err[0].startswith("mechderive: error: scene key"), err
    assert "expected" in err[0]
    for key in keys:
        assert key in err[0], (key, err[0])
    return err[0]


# ------------------------------------------------------------------------- the reproductions

def test_free_top_moments_of_1e300_are_solved_as_a_sphere(tmp_path, capsys):
    # was: OverflowError (L² = Σ (I ω)² = 2.25e600).  Reference: with I1 = I2 = I3 Euler's equations
    # (3.33) give ω̇ = 0, so ω(t) = ω0, E = ½ I |ω0|², |L| = I |ω0|; R(t) is the unit sphere's.
    doc = dict(BASE["free_top"], parameters={"I1": 1e300, "I2": 1e300, "I3": 1e300})
    names = ["omega1", "omega2", "omega3", "energy", "L_norm", "R11", "R23", "q0"]
    status, report, cols, _ = _run(tmp_path, capsys, doc, quantities=names)
    assert status == 0
    w0 = np.array(BASE["free_top"]["initial"]["omega"])
    assert np.array_equal(np.stack([cols["omega1"], cols["omega2"], cols["omega3"]], axis=-1),
                          np.broadcast_to(w0, (len(cols["t"]), 3)))
    # 4 ulp: ½ I |ω|² and I |ω| formed in the solver's units, converted back by a power of two
    assert cols["energy"] == pytest.approx(0.5e300 * float(w0 @ w0), rel=1e-15)
    assert cols["L_norm"] == pytest.approx(1e300 * float(np.linalg.norm(w0)), rel=1e-15)
    status, _, unit, _ = _run(tmp_path, capsys, dict(doc, parameters={"I1": 1.0, "I2": 1.0, "I3": 1.0}),
                              quantities=names)
    for q in ("R11", "R23", "q0"):  # the same motion (I → c I): to the rounding of R (1e-15, × the 50 samples)
        assert np.max(np.abs(cols[q] - unit[q])) <= 1e-14


def test_heavy_top_theta_dot_1e300(tmp_path, capsys):
    # was: LinAlgError.  E = ½ I1 θ̇² = 5e599 J is no double: refused naming the keys, with the rate allowed
    doc = _with(BASE["heavy_top"], "initial", "theta_dot", None, 1e300)
    status, _, _, err = _run(tmp_path, capsys, doc, quantities=["theta", "energy"])
    line = _refused(status, err, "[initial].theta_dot", "[parameters].I1", "energy")
    allowed = float(line.rsplit("below ~", 1)[1].split()[0])
    assert 1e153 < allowed <= math.sqrt(2 * DOUBLE_MAX / 1.0)  # ½ I1 θ̇² ≤ DOUBLE_MAX, I1 = 1
    # without the energy the motion is computable, but 10 s of it are ~10^300 turns: t_end is named
    status, _, _, err = _run(tmp_path, capsys, doc, quantities=["theta", "R11"])
    line = _refused(status, err, "[time].t_end")
    assert float(line.split("at most ")[1].split()[0]) < 1e-290
    # and a t_end within reach is solved.  Reference: gravity (M g l = 1 against I1 θ̇² = 1e600) is
    # nothing, and ω = (θ̇, 0, 0) lies along a principal axis: a steady turn about the line of
    # nodes, θ(t) = 0.5 + θ̇ t reflected into [0, π] at the pole and the bottom.
    doc["time"] = {"t_end": 2e-298, "samples": 51}
    status, report, cols, _ = _run(tmp_path, capsys, doc, quantities=["theta", "theta_dot"])
    assert status == 0
    turned = (0.5 + 1e300 * cols["t"]) % (2 * np.pi)
    reference = np.where(turned <= np.pi, turned, 2 * np.pi - turned)
    # the angle 1e300·t carries the rounding of t (1.1e-16 relative of up to 200 rad) besides the estimate
    assert np.max(np.abs(cols["theta"] - reference)) <= report["error_estimate"] + 1e-13
    assert np.max(np.abs(np.abs(cols["theta_dot"]) / 1e300 - 1)) < 1e-12


def test_moment_1e308_names_the_violated_triangle_inequality(tmp_path, capsys):
    # was: "scene key [parameters].I2: expected principal moments > 0 (3.22), got I2 = 2" — I2 = 2 is
    # positive; what no body has is I2 + I3 = 5 < I1 = 1e308
    status, _, _, err = _run(tmp_path, capsys, _with(BASE["free_top"], "parameters", "I1", None, 1e308))
    line = _refused(status, err, "[parameters].I1", "[parameters].I2", "[parameters].I3", "triangle")
    assert "> 0" not in line


def test_heavy_top_i1_1e308_barely_moves(tmp_path, capsys):
    # A valid top (I1 - M l² ≥ I3/2) that gravity (M g l / I1 = 1e-308 s⁻²) cannot tip in 10 s: the
    # closed form refuses the bottom passage it would make after ~1e154 s, auto integrates.
    # Reference: θ = θ0, φ = φ0 and ψ = ψ0 + ψ̇ t to ~1e-300 rad (ω3 = ψ̇ is constant, ω1, ω2 ~ 1e-308 t).
    doc = _with(BASE["heavy_top"], "parameters", "I1", None, 1e308)
    status, report, cols, _ = _run(tmp_path, capsys, doc, quantities=["theta", "phi", "psi"])
    assert status == 0 and report["method"] == "integrate" and "closed form cannot follow" in report["note"]
    assert np.max(np.abs(cols["theta"] - 0.5)) <= report["error_estimate"] + 1e-15
    assert np.max(np.abs(cols["psi"] - 5.0 * cols["t"])) <= report["error_estimate"] + 1e-14


def test_heavy_top_psi_dot_1e_300_is_the_planar_pendulum(tmp_path, capsys):
    # The issue saw "expected `n` to be finite"; here the closed form refuses the passage 5e-301 rad from
    # the bottom and auto integrates.  Reference: ψ̇ = 0 exactly is the planar pendulum through the bottom,
    # which the closed form follows (an exact passage); θ differs by ~1e-300.
    status, report, cols, _ = _run(tmp_path, capsys, _with(BASE["heavy_top"], "initial", "psi_dot", None, 1e-300),
                                   quantities=["theta", "apex_x", "apex_z"])
    assert status == 0 and report["method"] == "integrate"
    _, ref_report, ref, _ = _run(tmp_path, capsys, _with(BASE["heavy_top"], "initial", "psi_dot", None, 0.0),
                                 method="exact", quantities=["theta", "apex_x", "apex_z"])
    for q in ("theta", "apex_x", "apex_z"):
        assert np.max(np.abs(cols[q] - ref[q])) <= report["error_estimate"] + ref_report["error_estimate"]


@pytest.mark.parametrize("system, method, limit", [
    ("heavy_top", "auto", 2.0**51 * 3.5177),   # 2^51 nutation periods of the chapter's top (3.5177 s)
    ("free_top", "exact", None),
    ("heavy_top", "integrate", None),
])
def test_t_end_beyond_reach_names_t_end(tmp_path, capsys, system, method, limit):
    # was: "expected |u| <= 2**52·K(m) = 7.24275e+15 (...), got u = 1.1e280" (no key), or a hang (integrate)
    status, _, _, err = _run(tmp_path, capsys, _with(BASE[system], "time", "t_end", None, 1e300), method=method)
    line = _refused(status, err, "[time].t_end")
    at_most = float(line.split("at most ")[1].split()[0])
    assert 0 < at_most < 1e300
    if limit is not None:
        assert at_most == pytest.approx(limit, rel=1e-4)


def test_falling_cat_at_the_loosest_rtol(tmp_path, capsys):
    # was: an internal "R orthogonal" error (DOP853 at 1e-4 leaves RᵀR - 1 ~ 3e-7).  Reference: the
    # flip turns the cat by π (its bend is root-found for it), to the reported estimate of R
    status, report, cols, _ = _run(tmp_path, capsys, dict(BASE["falling_cat"], rtol=1e-2),
                                   quantities=["flip_angle", "R22", "q0"])
    assert status == 0 and report["rtol_met"]
    assert abs(cols["flip_angle"][-1] - np.pi) <= 2 * report["error_estimate"]  # an angle vs entries of R: ×2
    assert abs(cols["R22"][-1] + 1) <= report["error_estimate"]


def test_falling_cat_of_1e300_kg_turns_as_any_cat(tmp_path, capsys):
    # was: a compiled DOP853 looping on NaN.  The connection (3.87) depends on mass ratios only: R(t) is
    # the default cat's; L = Σ m r × ṙ scales with the mass (and stays 0)
    names = ["R11", "R23", "q0", "flip_angle", "L1"]
    status, report, cols, _ = _run(tmp_path, capsys, _with(BASE["falling_cat"], "parameters", "half_mass",
                                                           None, 1e300), quantities=names)
    assert status == 0 and report["rtol_met"]
    _, ref_report, ref, _ = _run(tmp_path, capsys, BASE["falling_cat"], quantities=names)
    for q in ("R11", "R23", "q0", "flip_angle"):
        assert np.max(np.abs(cols[q] - ref[q])) <= report["error_estimate"] + ref_report["error_estimate"]
    assert np.max(np.abs(cols["L1"])) <= 1e300 * 1e-12  # |L| ~ 1e-15 of the default cat's |Ĩ Ω| ~ 0.1


def test_falling_cat_parameters_are_refused_by_key(tmp_path, capsys):
    # was: "expected `joint_offset` finite and > 0" (no scene key), a NaN loop for radius = 1e-300
    for key, value, expected in (("joint_offset", -1.0, "> 0"), ("radius", 1e-300, "invertible"),
                                 ("half_length", 1e-300, "turn")):
        status, _, _, err = _run(tmp_path, capsys, _with(BASE["falling_cat"], "parameters", key, None, value))
        line = _refused(status, err, f"[parameters].{key}")
        assert expected in line


def test_heavy_top_moments_and_rates_scaled_give_the_same_motion(tmp_path, capsys):
    # The scaling laws of (3.62): I1, I3, M g l → c·(I1, I3, M g l) leaves the motion unchanged; rates → c·rates,
    # M g l → c²·M g l, t → t/c gives the same angles at c·t.  Reference: the chapter's top in SI units.
    names = ["theta", "phi", "psi", "apex_x"]
    _, ref_report, ref, _ = _run(tmp_path, capsys, BASE["heavy_top_mgl"], quantities=names + ["psi_dot"])
    c = 1e150
    doc = dict(BASE["heavy_top_mgl"], parameters={"I1": c, "I3": 0.5 * c, "Mgl": c},
               initial={**BASE["heavy_top_mgl"]["initial"], "psi_dot": 5.0 / c},
               time={"t_end": 10.0 * c, "samples": 51})
    doc["parameters"]["Mgl"] = c / (c * c)  # M g l / I1 = 1/c² s⁻²
    status, report, cols, _ = _run(tmp_path, capsys, doc, quantities=names + ["energy", "psi_dot"])
    assert status == 0 and "units" in report
    for q in names:  # the inputs' scalings round at 1e-16: a few ulp of the angles' 50 rad
        assert np.max(np.abs(cols[q] - ref[q])) <= report["error_estimate"] + ref_report["error_estimate"] + 1e-13
    # ψ̇ at c·t is ψ̇/c of the reference (its estimate is in the scene's rad/s, the reference's in its own)
    assert np.max(np.abs(cols["psi_dot"] * c - ref["psi_dot"])) <= \
        report["error_estimate"] * c + ref_report["error_estimate"] + 1e-13


# ------------------------------------------------------------------------- the sweep

def _sample(cases, every: int):
    return cases[::every]


def test_a_sample_of_the_sweep(capsys):
    # about 10 of the sweep's cases, every 120th (deterministic), each in a forked child
    cases = [c for c in all_cases() if c.backend == "c"]
    results = sweep(_sample(cases, 120), timeout=60.0, verbose=False)
    bad = [r for r in results if r["kind"] not in GOOD]
    assert not bad, bad


@pytest.mark.slow
def test_the_whole_sweep():
    results = sweep(all_cases(), timeout=60.0, verbose=False)
    bad = [r for r in results if r["kind"] not in GOOD]
    assert not bad, bad


# ------------------------------------------------------------------------- scaling laws as references

_FREE_NAMES = ["omega1", "omega2", "omega3", "energy", "L_norm", "R11", "R23", "q0", "phi", "theta", "psi"]
_HEAVY_NAMES = ["theta", "phi", "psi", "theta_dot", "phi_dot", "energy", "p_phi", "omega1", "R11", "apex_z"]
_PER_UNIT = {  # how each output scales with the moments (I → a I) and the rates (ω → b ω, t → t/b)
    "omega1": (0, 1), "omega2": (0, 1), "omega3": (0, 1), "theta_dot": (0, 1), "phi_dot": (0, 1),
    "psi_dot": (0, 1), "energy": (1, 2), "L_norm": (1, 1), "p_phi": (1, 1), "p_psi": (1, 1),
}


def _compare_scaled(cols, report, ref, ref_report, a: float, b: float) -> None:
    """Each column against the reference's, converted by the scaling law; rate-like estimates scale by b."""
    for q, col in cols.items():
        if q == "t":
            continue
        pa, pb = _PER_UNIT.get(q, (0, 0))
        factor = a**pa * b**pb
        if pa:  # E, |L|, p: the estimates bound no invariant; their drift is relative: compare relatively
            assert np.max(np.abs(col / factor - ref[q])) <= 1e-12 * np.max(np.abs(ref[q])), q
            continue
        # angles, R, q in rad or 1; rates in rad/s (each run's estimate in its own units); + the inputs'
        # rounding (a, b are no powers of two: the scaled moments and rates round at 1e-16, × the 10 s run)
        tol = report["error_estimate"] / (b**pb) + ref_report["error_estimate"] + 1e-12 * max(1.0, np.max(np.abs(ref[q])))
        assert np.max(np.abs(col / factor - ref[q])) <= tol, q


#: (a, b) with every output and M g l (∝ a b²) a normal double
_SCALES = [(1e300, 1.0), (1.0, 1e100), pytest.param(1e-300, 1e100, marks=pytest.mark.slow),
           pytest.param(1e-100, 1e-100, marks=pytest.mark.slow), pytest.param(1e-150, 1e150, marks=pytest.mark.slow),
           pytest.param(1e150, 1e-100, marks=pytest.mark.slow), pytest.param(1e-5, 1e-150, marks=pytest.mark.slow)]


@pytest.mark.parametrize("a, b", _SCALES)
def test_free_top_scaling_law(tmp_path, capsys, a, b):
    # (3.33) is homogeneous: I → a I leaves ω(t), R(t) unchanged; ω → b ω with t → t/b gives ω(t) → b ω(b t)
    base = dict(BASE["free_top"], initial={**BASE["free_top"]["initial"], "theta": 0.5})
    doc = dict(base, parameters={k: a * v for k, v in base["parameters"].items()},
               initial={**base["initial"], "omega": [b * w for w in base["initial"]["omega"]]},
               time={**base["time"], "t_end": base["time"]["t_end"] / b})
    status, report, cols, _ = _run(tmp_path, capsys, doc, quantities=_FREE_NAMES)
    assert status == 0
    _, ref_report, ref, _ = _run(tmp_path, capsys, base, quantities=_FREE_NAMES)
    _compare_scaled(cols, report, ref, ref_report, a, b)


@pytest.mark.parametrize("a, b", _SCALES)
def test_heavy_top_scaling_law(tmp_path, capsys, a, b):
    # (3.62): I1, I3, M g l → a·(...) leaves the motion unchanged; rates → b·rates with M g l → b² M g l,
    # t → t/b gives the same angles at b·t
    base = dict(BASE["heavy_top_mgl"], initial={**BASE["heavy_top_mgl"]["initial"], "phi_dot": -0.5})
    doc = dict(base, parameters={"I1": a * 1.0, "I3": a * 0.5, "Mgl": a * b * b},
               initial={**base["initial"], **{k: b * base["initial"][k] for k in ("phi_dot", "psi_dot")}},
               time={**base["time"], "t_end": base["time"]["t_end"] / b})
    status, report, cols, _ = _run(tmp_path, capsys, doc, quantities=_HEAVY_NAMES)
    assert status == 0
    _, ref_report, ref, _ = _run(tmp_path, capsys, base, quantities=_HEAVY_NAMES)
    _compare_scaled(cols, report, ref, ref_report, a, b)
