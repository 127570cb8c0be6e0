"""The scene layer of per-motion quantities (issue 14 §1): ``[output].summary`` read and checked, computed
by the system's ``summarize`` in its solver's units, brought back to the scene's units, printed, in the
``--json`` report and in ``OUT.summary.json``.

The system here is the free top with two per-motion quantities of its own whose values are known
independently of the plumbing: the run's length t_end − t_start (a time) and |ω(0)| (a rate).  A scene
of extreme numbers is solved in units of its own motion (powers of two, issue 12), so getting them back
exactly tests the conversion; the systems' real quantities are tested against the physics in
``test_summary_*.py``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from mechderive.cli import main
from mechderive.errors import InvalidInputError
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import load_scene, scene_to_toml
from mechderive.systems import registry
from mechderive.systems.base import Quantity
from mechderive.systems.free_top.system import FreeTop


class _Probe(FreeTop):
    name = "probe_top"
    summaries = (Quantity("run_length", "s", "t_end − t_start of the run", scales_as="time"),
                 Quantity("spin0", "rad/s", "|ω(0)|", scales_as="rate"),
                 Quantity("kind", "1", "a word"),
                 Quantity("rates", "rad/s", "a table of rates", scales_as="rate"))

    def summarize(self, scene, solved, t, names):
        spin = math.sqrt(sum(w * w for w in scene.initial["omega"]))
        every = {"run_length": (float(t[-1] - t[0]), 0.0), "spin0": (spin, 1e-16 * spin),
                 "kind": ("tumbling", None), "rates": ({"a": spin}, None)}
        return {n: every[n] for n in names}


@pytest.fixture
def probe():
    registry.register(_Probe(), replace=True)
    yield
    registry.unregister("probe_top")


def _scene(summary: str, omega: str = "[1.0, 0.5, 1.0]", moments: str = "1, 2, 3") -> str:
    I1, I2, I3 = moments.split(",")
    return f"""system = "probe_top"
[parameters]
I1 = {I1}
I2 = {I2}
I3 = {I3}
[initial]
omega = {omega}
[time]
t_end = 2.5
samples = 11
[output]
quantities = ["omega1"]
summary = {summary}
"""


def test_summary_read_checked_and_round_tripped(probe):
    scene = load_scene(_scene('["spin0", "run_length"]'))
    assert scene.summary == ("spin0", "run_length")
    assert load_scene(scene_to_toml(scene)) == scene
    assert load_scene(_scene("[]")).summary == ()
    with pytest.raises(InvalidInputError, match=r"\[output\].summary\[1\]: unknown per-motion quantity 'nope'.*"
                                                r"expected one of run_length, spin0"):
        load_scene(_scene('["spin0", "nope"]'))
    with pytest.raises(InvalidInputError, match=r"duplicate per-motion quantity 'spin0'"):
        load_scene(_scene('["spin0", "spin0"]'))
    with pytest.raises(InvalidInputError, match=r"\[output\].summary: expected a list"):
        load_scene(_scene('"spin0"'))


def test_a_system_without_summaries_says_so():
    text = _scene('["period"]').replace("probe_top", "falling_cat")
    text = text.split("[parameters]")[0] + "[time]\nt_end = 1\nsamples = 3\n[output]\nquantities = [\"flip_angle\"]\n" \
        "summary = [\"period_x\"]\n"
    with pytest.raises(InvalidInputError, match="summary"):
        load_scene(text)


@pytest.mark.parametrize("moments, omega", [("1, 2, 3", "[1.0, 0.5, 1.0]"),
                                            # solved in units of its own motion: moments ×2^-k, rates ×2^-j
                                            ("1e-200, 2e-200, 3e-200", "[1e-150, 0.5e-150, 1e-150]")])
def test_values_come_back_in_the_scene_units(probe, moments, omega):
    scene = load_scene(_scene('["run_length", "spin0", "kind", "rates"]', omega, moments))
    result = run_scene(scene)
    spin = math.sqrt(sum(w * w for w in scene.initial["omega"]))
    summary, errors = result.report["summary"], result.report["summary_error"]
    # exact: the conversion is by powers of two
    assert summary["run_length"] == 2.5 and summary["spin0"] == spin
    assert summary["kind"] == "tumbling"
    assert errors["spin0"] == pytest.approx(1e-16 * spin, rel=1e-15)
    if "units" in result.report:  # a table cannot be brought back by one power of two: refused, not wrong
        assert summary["rates"] is None and "units of its own motion" in errors["rates"]
    else:
        assert summary["rates"] == {"a": spin}
    assert list(summary) == ["run_length", "spin0", "kind", "rates"]


def test_cli_prints_writes_and_reports(probe, tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(_scene('["spin0", "kind"]'))
    assert main(["run", str(path), "-o", str(tmp_path / "out.csv")]) == 0
    out = capsys.readouterr().out
    assert "per-motion quantities:" in out and "spin0 = 1.5 rad/s" in out and "kind  = tumbling" in out
    written = json.loads((tmp_path / "out.summary.json").read_text())
    assert written["summary"] == {"spin0": 1.5, "kind": "tumbling"}
    assert written["units"] == {"spin0": "rad/s", "kind": "1"} and written["summary_error"]["kind"] is None
    assert main(["run", str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["summary"] == written["summary"] and report["summary_error"]["spin0"] == pytest.approx(1.5e-16)
    assert "summary" in report["timings"]


def test_scene_without_summary_has_none_in_its_report(probe, tmp_path):
    scene = load_scene(_scene("[]"))
    result = run_scene(scene)
    assert "summary" not in result.report and "summary" not in result.report["timings"]
    assert np.isfinite(result.columns["omega1"]).all()


def test_scenes_quantities_lists_the_summaries(probe, capsys):
    assert main(["scenes", "--quantities", "probe_top"]) == 0
    out = capsys.readouterr().out
    assert "[output].summary" in out and "run_length" in out and "t_end − t_start of the run" in out


def test_readme_lists_every_systems_quantities_as_the_registry_has_them():
    from pathlib import Path

    from mechderive.cli.run import quantities_markdown

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    block = readme.split("<!-- quantities:begin -->\n", 1)[1].split("<!-- quantities:end -->", 1)[0]
    assert block == quantities_markdown()  # regenerate with mechderive.cli.run.quantities_markdown()
