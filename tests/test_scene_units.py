"""Values with units in scene files and output columns in chosen units (issue 14 §2).

References: the conversion factors written by hand (30 deg = π/6 rad, 1000 rpm = 1000·2π/60 rad/s,
12 kg·cm² = 12e-4 kg m²), and the same scene given in SI numbers (its columns must agree to the
rounding of the conversion: a relative ulp or two of each input).
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from mechderive.cli import main
from mechderive.errors import InvalidInputError
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import load_scene, scene_to_toml
from mechderive.scenes.units import to_si

SI = """system = "heavy_top"
[parameters]
I1 = {I1}
I3 = 0.5
M = 1.0
g = {g}
l = {l}
[initial]
theta = {theta}
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = {psi_dot}
[time]
t_end = 5.0
samples = 51
[output]
quantities = ["theta", "psi_dot"]
{output}"""


def _scene(output: str = "", **given) -> str:
    values = {"I1": 1.0, "g": 9.81, "l": 0.1, "theta": 0.5, "psi_dot": 20.0}
    values.update(given)
    return SI.format(output=output, **{k: f'"{v}"' if isinstance(v, str) else v for k, v in values.items()})


@pytest.mark.parametrize("text, si, expected", [
    ("30 deg", "rad", math.pi / 6),
    ("1000 rpm", "rad/s", 1000 * 2 * math.pi / 60),
    ("90 deg/s", "rad/s", math.pi / 2),
    ("0.5 turn", "rad", math.pi),
    ("12 kg*cm^2", "kg m^2", 12e-4),
    ("9.81 m/s^2", "m/s^2", 9.81),
    ("250 g", "kg", 0.25),
    ("1.5e2 mm", "m", 0.15),
    ("2 ms", "s", 2e-3),
])
def test_conversion_factors(text, si, expected):
    assert to_si("k", text, si) == pytest.approx(expected, rel=2.3e-16)  # one rounding of the factor


def test_a_scene_given_with_units_equals_the_si_scene():
    si = run_scene(load_scene(_scene()))
    units = load_scene(_scene(I1="1e7 g*cm^2", g="981 cm/s^2", l="10 cm", theta=f"{math.degrees(0.5)!r} deg",
                              psi_dot=f"{20 * 60 / (2 * math.pi)!r} rpm"))
    assert units.given_with_units["[initial].theta"].endswith(" deg")
    for k in ("I1", "g", "l"):
        assert units.parameters[k] == pytest.approx(load_scene(_scene()).parameters[k], rel=3e-16)
    run = run_scene(units)
    for q in ("theta", "psi_dot"):  # inputs within 2 ulp: the motion within ~1e-15 relative over 5 s
        assert np.max(np.abs(run.columns[q] - si.columns[q])) < 1e-13 * max(1.0, np.max(np.abs(si.columns[q])))
    assert load_scene(scene_to_toml(units)) == units  # written back in SI numbers


@pytest.mark.parametrize("given, message", [
    ({"psi_dot": "3 Hz"}, r"\[initial\].psi_dot: expected a unit of rad/s, got '3 Hz'|"
                          r"\[initial\].psi_dot: expected a unit of rad/s, got 'Hz', which does not count radians"),
    ({"theta": "30 kg"}, r"\[initial\].theta: expected a unit of rad"),
    ({"I1": "1 deg"}, r"\[parameters\].I1: expected a unit of kg m\^2"),
    ({"g": "nine m/s^2"}, r"\[parameters\].g: expected a number > 0, got 'nine m/s\^2'"),
    ({"g": "9.81 furlongs_per_fortnight"}, r"\[parameters\].g: expected a unit pint knows"),
    ({"g": "9.81 m/s^2; import os"}, r"\[parameters\].g: expected a number > 0, got"),
    ({"g": "1e306 km/s^2"}, r"\[parameters\].g: expected a finite value"),
])
def test_bad_units_name_the_key(given, message):
    with pytest.raises(InvalidInputError, match=message):
        load_scene(_scene(**given))


def test_output_columns_in_chosen_units(tmp_path, capsys):
    path = tmp_path / "u.toml"
    path.write_text(_scene('units = {theta = "deg", psi_dot = "rpm"}'))
    scene = load_scene(path)
    assert load_scene(scene_to_toml(scene)) == scene
    result = run_scene(scene)
    out = result.output_columns()
    assert np.allclose(out["theta"], np.degrees(result.columns["theta"]), rtol=3e-16, atol=0)
    assert np.allclose(out["psi_dot"], result.columns["psi_dot"] * 60 / (2 * math.pi), rtol=3e-16, atol=0)
    assert result.report["column_units"] == {"theta": "deg", "psi_dot": "rpm"}
    assert main(["run", str(path), "-o", str(tmp_path / "o.csv")]) == 0
    assert "theta [deg]" in capsys.readouterr().out
    table = np.loadtxt(tmp_path / "o.csv", delimiter=",", skiprows=1)
    assert table[0, 1] == pytest.approx(math.degrees(0.5), rel=1e-15)
    for output, message in [('units = {phi = "deg"}', r"\[output\].units.phi: expected one of the scene's quantities"),
                            ('units = {theta = "rpm"}', r"\[output\].units.theta: expected a unit of rad")]:
        with pytest.raises(InvalidInputError, match=message):
            load_scene(_scene(output))


def test_a_key_of_unknown_unit_takes_no_unit():
    cat = ('system = "falling_cat"\n[parameters]\nsomething = "3 m"\n[time]\nt_end = 1\nsamples = 3\n'
           '[output]\nquantities = ["flip_angle"]')
    with pytest.raises(InvalidInputError, match=r"the system does not say the unit"):
        load_scene(cat)


def test_pint_is_imported_only_for_a_unit():
    code = ("import sys; from mechderive.scenes.schema import load_scene; "
            "from mechderive.scenes.builtin import load_builtin; load_builtin('default'); "
            "print('pint' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
