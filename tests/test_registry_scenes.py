"""The scene layer asks the registry of systems and names none (issue 13, part 1).

* The code of ``mechderive/scenes/*.py``, ``mechderive/sweeps/*.py``, ``cli/run.py``, ``cli/sweep.py`` and ``cli/__init__.py`` (docstrings aside)
  holds no built-in system's name: the systems are data of the registry.
* The registry lists the built-in systems; ``mechderive scenes --systems`` and
  ``mechderive scenes --quantities SYSTEM`` print what it says (name, unit, meaning).
* A system registered in this module (a harmonic oscillator, solved in closed form) runs end to
  end through ``load_scene`` / ``run_scene`` and ``mechderive run FILE`` without editing the package.
"""

from __future__ import annotations

import ast
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from mechderive.cli import main
from mechderive.errors import InvalidInputError
from mechderive.systems import registry
from mechderive.systems.base import Key, Quantity, Solved, System

from .conftest import run_python

PACKAGE = Path(__file__).resolve().parents[1] / "mechderive"
SCANNED = sorted((PACKAGE / "scenes").glob("*.py")) + sorted((PACKAGE / "sweeps").glob("*.py")) + [
    PACKAGE / "cli" / "run.py", PACKAGE / "cli" / "sweep.py", PACKAGE / "cli" / "__init__.py"]
BUILT_IN = ("free_top", "heavy_top", "falling_cat")
FORBIDDEN = (*BUILT_IN, "deformable")


def _docstrings(tree: ast.AST) -> set[int]:
    """The ids of the docstring nodes of a module, its classes and functions."""
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                ids.add(id(first.value))
    return ids


def _names_in_code(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = _docstrings(tree)
    found = []
    for node in ast.walk(tree):
        texts: list[str] = []
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip:
            texts = [node.value]
        elif isinstance(node, ast.Name):
            texts = [node.id]
        elif isinstance(node, ast.Attribute):
            texts = [node.attr]
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef, ast.AsyncFunctionDef)):
            texts = [node.name]
        elif isinstance(node, ast.alias):
            texts = [node.name, node.asname or ""]
        elif isinstance(node, ast.ImportFrom):
            texts = [node.module or ""]
        found += [f"{path.relative_to(PACKAGE)}:{getattr(node, 'lineno', '?')}: {name}"
                  for text in texts for name in FORBIDDEN if name in text]
    return found


def test_the_scene_layer_names_no_system():
    assert len(SCANNED) >= 8
    found = [hit for path in SCANNED for hit in _names_in_code(path)]
    assert found == []


def test_the_scan_finds_a_name_in_code_but_not_in_a_docstring(tmp_path):
    # the scan can fail: a planted name in code is found, the same in a docstring is not
    planted = tmp_path / "planted.py"
    planted.write_text('"""Runs heavy_top scenes."""\nSYSTEM = "heavy_top"\n\ndef f():\n    """free_top too."""\n')
    hits = _names_in_code_at(planted)
    assert hits == ["2: heavy_top"]


def _names_in_code_at(path: Path) -> list[str]:
    global PACKAGE
    saved, PACKAGE = PACKAGE, path.parent
    try:
        return [hit.split(":", 1)[1].strip() for hit in _names_in_code(path)]
    finally:
        PACKAGE = saved


def test_the_registry_lists_the_built_in_systems():
    names = registry.names()
    assert names[:3] == BUILT_IN
    for name in BUILT_IN:
        system = registry.get(name)
        assert isinstance(system, System) and system.name == name and system.summary and system.section
        assert "integrate" in system.methods and system.quantities and system.builtin_scenes()
        assert all(q.unit and q.meaning for q in system.quantities)
        assert set(system.plot_quantities) <= set(system.quantity_names())
        assert system.example_scene() in {text for _, _, text in system.builtin_scenes()}


def test_the_built_in_scenes_are_the_same_nine():
    from mechderive.scenes.builtin import list_scenes

    assert sorted(n for n, _ in list_scenes()) == sorted(
        ["default", "heavy_top_looping", "heavy_top_hanging", "sleeping_top", "free_top_tumbling",
         "free_top_near_separatrix", "tennis_racket", "gyroscope", "falling_cat"])


@pytest.mark.parametrize("name", BUILT_IN)
def test_scenes_quantities_prints_each_with_unit_and_meaning(name, capsys):
    assert main(["scenes", "--quantities", name]) == 0
    lines = capsys.readouterr().out.splitlines()
    system = registry.get(name)
    heads = ["[output].quantities (columns, one value per sample):"] + (
        ["[output].summary (per-motion quantities, one value per run):"] if system.summaries else [])
    assert [line for line in lines if not line.startswith("  ")] == heads
    listed = [line.strip() for line in lines if line.startswith("  ")]
    described = system.quantities + system.summaries
    assert len(listed) == len(described)
    for line, q in zip(listed, described):
        assert re.fullmatch(rf"{q.name} +{re.escape(q.unit or '-')} +{re.escape(q.meaning)}", line), line


def test_scenes_systems_lists_the_registry(capsys):
    assert main(["scenes", "--systems"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in out] == list(registry.names())
    assert main(["scenes", "--quantities", "dog"]) == 2
    assert "expected a system one of 'free_top', 'heavy_top', 'falling_cat'" in capsys.readouterr().err


def test_loading_the_default_scene_imports_only_the_systems_before_it():
    proc = run_python("-c", "import sys; from mechderive.scenes.builtin import load_builtin; load_builtin('default'); "
                            "print(sorted(m for m in sys.modules if m.startswith('mechderive.systems.') "
                            "and m.endswith('.system')))")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "['mechderive.systems.free_top.system', 'mechderive.systems.heavy_top.system']"


def test_the_command_line_loads_a_builtin_scene_importing_only_the_systems_before_it():
    # `mechderive run tennis_racket` looked the name up in the list of every scene, importing every system
    # (the falling cat's, the Lagrangian's: ~20 ms of a 0.3 s warm run)
    proc = run_python("-c", "import sys; from mechderive.cli.run import _load; s = _load('tennis_racket'); "
                            "print(s.name, sorted(m for m in sys.modules if m.startswith('mechderive.systems.') "
                            "and m.endswith('.system')))")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "tennis_racket ['mechderive.systems.free_top.system']"


# --------------------------------------------------------------------------- a system of a test module

class Oscillator(System):
    """x'' = -k x, solved in closed form: x = x0 cos ωt + (v0/ω) sin ωt, ω = √k."""

    name = "test_oscillator"
    summary = "harmonic oscillator (test)"
    parameters = (Key("k", "1/s^2", "stiffness per mass"),)
    initial = (Key("x", "m", "position at t = 0"), Key("v", "m/s", "velocity at t = 0"))
    quantities = (Quantity("x", "m", "position"), Quantity("energy", "J/kg", "energy per mass"))
    methods = ("exact", "integrate")

    def check_parameters(self, given, *, strict=True):
        from mechderive.systems.scene_keys import at, check_keys, number

        check_keys(given, "parameters", ("k",), ("k",), "parameter for system 'test_oscillator'")
        return {"k": number(at("parameters", "k"), given["k"], expected="a number > 0", valid=lambda x: x > 0)}

    def check_initial(self, given, parameters):
        from mechderive.systems.scene_keys import at, check_keys, number

        check_keys(given, "initial", ("x", "v"), ("x", "v"), "initial value for system 'test_oscillator'")
        return {k: number(at("initial", k), given[k]) for k in ("x", "v")}

    def solve(self, scene, method, t):
        w = math.sqrt(scene.parameters["k"])
        x0, v0 = scene.initial["x"], scene.initial["v"]
        x, v = x0 * np.cos(w * t) + v0 / w * np.sin(w * t), -x0 * w * np.sin(w * t) + v0 * np.cos(w * t)
        cols = {"x": x, "energy": 0.5 * (v * v + w * w * x * x)}
        return Solved({q: cols[q] for q in scene.quantities}, {"error_estimate": 1e-15}, (x, v))

    def drift(self, scene, solved, t):
        from mechderive.core.drift import drift

        x, v = solved.solution
        E = 0.5 * (v * v + scene.parameters["k"] * x * x)
        return {"energy": drift(E, float(np.max(E)), "max_t E")}


SCENE = """\
system = "test_oscillator"
[parameters]
k = 4.0
[initial]
x = 1.0
v = 0.0
[time]
t_end = 3.0
samples = 7
[output]
quantities = ["x", "energy"]
"""


@pytest.fixture
def oscillator():
    registry.register(Oscillator(), replace=True)
    yield
    registry.unregister("test_oscillator")


def test_a_registered_system_runs_end_to_end(oscillator, tmp_path, capsys):
    from mechderive.scenes.planner import run_scene
    from mechderive.scenes.schema import QUANTITIES, load_scene, scene_to_toml

    scene = load_scene(SCENE)
    assert QUANTITIES["test_oscillator"] == ("x", "energy") and load_scene(scene_to_toml(scene)) == scene
    result = run_scene(scene)
    # x = cos 2t exactly; the closed form's rounding is a few ulp of 1
    assert np.max(np.abs(result.columns["x"] - np.cos(2.0 * result.t))) < 1e-15
    assert result.report["method"] == "exact" and result.report["drift"]["energy"] < 1e-15
    path = tmp_path / "osc.toml"
    path.write_text(SCENE)
    assert main(["run", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["system"] == "test_oscillator"
    assert main(["scenes", "--quantities", "test_oscillator"]) == 0
    assert capsys.readouterr().out.splitlines()[1].split()[:2] == ["x", "m"]
    assert main(["scenes", "--quantities", str(path)]) == 0  # a scene file: its system as it defines it
    assert capsys.readouterr().out.splitlines()[2].split()[:2] == ["energy", "J/kg"]
    with pytest.raises(InvalidInputError, match=r"scene key \[parameters\]\.k: expected a number > 0, got -1"):
        load_scene(SCENE.replace("k = 4.0", "k = -1"))
    with pytest.raises(InvalidInputError, match=r"scene table \[initial\]: missing; system 'test_oscillator' "
                                                r"needs tables \[parameters\], \[initial\], \[time\], \[output\]"):
        load_scene(SCENE.replace("[initial]\nx = 1.0\nv = 0.0\n", ""))


def test_a_registered_system_without_a_picture_is_drawn_column_by_column(oscillator, tmp_path):
    pytest.importorskip("matplotlib")
    path = tmp_path / "osc.toml"
    path.write_text(SCENE)
    assert main(["run", str(path), "--plot", str(tmp_path / "osc.png")]) == 0
    assert (tmp_path / "osc.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
