"""`mechderive bench`: it runs, and its tables have the structure the README describes.

These are not timed tests: nothing here asserts a speed.  They check that each section is
measured, that every row carries a time, an error and a speed-up where one is defined, that
the targets are evaluated, and that the 30-digit values copied into the package match the
committed reference files.
"""

from __future__ import annotations

import json
import math

import pytest

from mechderive.bench import check_targets, format_report, plot_work_precision, run_benchmarks
from mechderive.bench.work_precision import FREE_REFERENCE, HEAVY_REFERENCE
from mechderive.cli import main

from .conftest import ROOT, run_python


# session scope: a worker runs other files' tests between this file's, and a module fixture would be torn
# down and built again (measured: twice per session, 12 s each)
@pytest.fixture(scope="session")
def quick() -> dict:
    proc = run_python("-m", "mechderive.cli", "bench", "--quick", "--json", timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def _check_rows(rows: list[dict], families: set[str]) -> None:
    assert {r["family"] for r in rows} == families
    assert rows[0]["family"] == "closed form"
    for r in rows:
        assert r["seconds"] > 0 and math.isfinite(r["seconds"]), r
        assert r["max_error"] > 0 and math.isfinite(r["max_error"]), r
        assert r["runs"] >= 1


def test_quick_run_measures_the_four_quick_sections(quick):
    assert quick["meta"]["quick"] is True
    assert {"heavy_top", "free_top", "ensemble", "cold_start"} <= quick.keys()
    assert "laziness" not in quick  # left out of --quick unless named
    assert quick["heavy_top"]["case"]["periods"] == quick["free_top"]["case"]["periods"] == 10


def test_heavy_top_table_has_every_family_and_speedups_against_the_baseline(quick):
    heavy = quick["heavy_top"]
    _check_rows(heavy["rows"], {"closed form", "DOP853 (C)", "DOP853 (SciPy)", "splitting order 4",
                                "splitting order 6", "baseline", "baseline (cold)"})
    assert [r["setting"] for r in heavy["rows"] if r["family"] == "baseline"] == ["rtol 1e-08", "rtol 1e-13"]
    for r in heavy["rows"]:
        if r["family"].startswith("baseline"):
            assert r["speedup"] is None
        else:
            assert r["speedup"] > 0 and r["speedup_vs"].lstrip("> ").startswith("baseline rtol")
    cold = heavy["baseline_cold"]
    assert cold["derive_s"] > 0 and cold["lambdify_s"] > 0
    assert heavy["reference_error"] < 1e-9  # measured against 30 digits: the closed form is that good at least


def test_free_top_table_compares_with_dop853(quick):
    rows = quick["free_top"]["rows"]
    _check_rows(rows, {"closed form", "DOP853 (C)", "DOP853 (SciPy)", "splitting order 4", "splitting order 6"})
    assert all(r["speedup_vs"].lstrip("> ").startswith("DOP853 (SciPy)") for r in rows
               if r["family"] != "DOP853 (SciPy)")


def test_ensemble_rows_cover_both_systems_up_to_100_bodies(quick):
    rows = quick["ensemble"]["rows"]
    for system in ("heavy top", "free top"):
        assert [r["M"] for r in rows if r["system"] == system] == [1, 100, "1 (scalar path)"]
    assert all(r["body_steps_per_second"] > 0 for r in rows)


def test_cold_start_splits_stages_and_the_warm_run_reads_the_disk_cache(quick):
    cold, warm = quick["cold_start"]["cold"], quick["cold_start"]["warm"]
    for run in (cold, warm):
        assert {"parse", "derive", "compile", "solve", "total"} <= run["timings"].keys()
        assert run["wall"] >= run["timings"]["total"]
    assert cold["derived"] > 0 and "sympy" in cold["imported"]
    # the second run of the default scene reads everything from the disk cache and never imports SymPy
    assert warm["derived"] == 0 and set(warm["compiled"]) == {"disk"}
    assert isinstance(warm["imported"], list) and "sympy" not in warm["imported"]
    # the cold run's stages are net of what they derived: solving 2001 samples takes measurable time
    stages = cold["timings"]
    assert stages["derive"] > 0 and stages["solve"] > 0
    assert stages["derive"] + stages["compile"] + stages["solve"] <= stages["total"] + 1e-6


def test_targets_and_the_printed_report(quick, tmp_path):
    targets = quick["targets"]
    assert len(targets) == 6 and all(isinstance(t["met"], bool) and t["figures"] for t in targets)
    assert check_targets(quick) == targets
    text = format_report(quick)
    for heading in ("## 1. Heavy top", "## 2. Free top", "## 3. Ensemble", "## 4. `mechderive run --json`", "## Targets",
                    "| method | setting | time | max error (rad) | evals | speed-up vs baseline |",
                    "Not run: laziness"):
        assert heading in text
    assert "shared machine" in text  # the noise caveat
    pytest.importorskip("matplotlib")
    out = tmp_path / "wp.png"
    plot_work_precision(quick, str(out))
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_laziness_scenes_and_their_report():
    # the section itself runs cold derivations of every quantity (5-50 s on a busy machine): the full
    # `mechderive bench` runs it; here its scenes and its part of the report
    from mechderive.bench.startup import ALL_HEAVY_QUANTITIES, _scene_text
    from mechderive.scenes.schema import QUANTITIES, load_scene

    assert ALL_HEAVY_QUANTITIES == QUANTITIES["heavy_top"]
    for names in (("u",), ALL_HEAVY_QUANTITIES):
        scene = load_scene(_scene_text(names))
        assert scene.quantities == names and scene.t_end == pytest.approx(35.177) and scene.samples == 2001
    run = dict(wall=0.4, timings=dict(parse=0.001, derive=0.0, compile=0.02, solve=0.1, total=0.15), derived=0,
               compiled=["disk"], evaluated=["phase", "jacobi"], imported=["mpmath"], walls=[0.4], wall_median=0.4)
    result = dict(meta=dict(quick=False, date="d", machine="m", load_before="1", load_after="1", python="3",
                            versions={}),
                  laziness=dict(u_warm=run, all_warm={**run, "wall": 0.6, "walls": [0.6], "wall_median": 0.6},
                                n_quantities_all=25))
    text = format_report(result)
    assert "## 5. Laziness: default scene asking for u only vs all 25 quantities" in text
    assert "u only, cache disabled (derives): skipped" in text
    assert "saved by asking for u only (warm): 0.20 s of 0.60 s (whole process, medians)" in text


def test_unknown_sections_are_refused(capsys):
    assert main(["bench", "--only", "heavy_top,nope"]) == 2
    assert "expected names among heavy_top" in capsys.readouterr().err
    with pytest.raises(ValueError, match="expected sections among .*, got 'nope'"):
        run_benchmarks(sections=("nope",))


def test_reference_values_copied_into_the_package_match_the_committed_files():
    heavy = {c["name"]: c for c in json.loads((ROOT / "tests/reference/heavy_top_cases.json").read_text())["cases"]}
    case = heavy["cusps_released"]
    assert case["parameters"] == dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
    assert case["initial"] == dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0)
    assert [(p["t"], p["phi"], p["theta"], p["psi"]) for p in case["points"]] == list(HEAVY_REFERENCE)
    free = {c["name"]: c for c in json.loads((ROOT / "tests/reference/free_top_cases.json").read_text())["cases"]}
    case = free["generic"]
    assert (case["moments"], case["omega0"]) == ([1.0, 2.0, 3.0], [1.0, 0.5, 1.0])
    assert [(p["t"], *p["omega"]) for p in case["points"]] == list(FREE_REFERENCE)


def test_interactive_section_is_left_out_of_quick_and_reports_a_table(quick):
    from mechderive.bench.interactive import BASELINES, report_lines

    assert "interactive" not in quick  # a minute of fresh processes: named with --only
    for job, script in BASELINES.items():
        compile(script, f"<baseline {job}>", "exec")  # the usual path's scripts are whole programs
    lines = report_lines({"rows": {"run": {"command": "mechderive run", "cold": 2.5, "warm": 0.2,
                                           "baseline": 1.6, "warm_runs": [0.2]}}, "repeats": 1})
    assert "| `mechderive run` | 2.50 s | 0.20 s | 1.60 s | 8× |" in lines


@pytest.mark.slow
def test_interactive_section_measures_every_job():
    from mechderive.bench.interactive import interactive

    rows = interactive(quick=True)["rows"]
    assert set(rows) == {"derive", "check", "run"}
    for r in rows.values():
        assert 0 < r["warm"] <= r["cold"] * 1.5 and r["baseline"] > 0
