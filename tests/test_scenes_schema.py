"""Scene files: the TOML format, every refusal's message, the built-in scenes, hostile input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechderive.errors import InvalidInputError, NonFiniteValueError, UnphysicalInertiaError
from mechderive.scenes import builtin, schema
from mechderive.scenes.schema import QUANTITIES, Scene, load_scene, parse_scene, scene_to_toml

from .conftest import run_python

HEAVY = """\
system = "heavy_top"
method = "auto"
rtol = 1e-10

[parameters]
I1 = 1.0
I3 = 0.5
M = 1.0
g = 9.81
l = 0.1

[initial]
theta = 0.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 20.0

[time]
t_end = 10.0
samples = 1001

[output]
quantities = ["theta", "phi", "psi"]
"""

FREE = """\
system = "free_top"
[parameters]
I1 = 1
I2 = 2
I3 = 3
[initial]
omega = [1, 0.5, 1]
[time]
t_end = 100
samples = 11
[output]
quantities = ["omega1", "R33"]
"""


def heavy(**tables) -> dict:
    """The HEAVY scene as a mapping, with tables/keys replaced (a value None deletes the key)."""
    import tomllib

    doc = tomllib.loads(HEAVY)
    for key, value in tables.items():
        if isinstance(value, dict) and isinstance(doc.get(key), dict):
            for k, v in value.items():
                if v is None:
                    doc[key].pop(k, None)
                else:
                    doc[key][k] = v
        elif value is None:
            doc.pop(key, None)
        else:
            doc[key] = value
    return doc


def free(**tables) -> dict:
    import tomllib

    doc = tomllib.loads(FREE)
    for key, value in tables.items():
        if value is None:
            doc.pop(key, None)
        elif isinstance(value, dict):
            doc[key].update(value)
        else:
            doc[key] = value
    return doc


# ------------------------------------------------------------------------------------ the happy path

def test_heavy_top_scene_parses_with_floats_and_defaults():
    scene = load_scene(HEAVY)
    assert scene.system == "heavy_top" and scene.method == "auto" and scene.rtol == 1e-10
    assert scene.parameters == dict(I1=1.0, I3=0.5, M=1.0, g=9.81, l=0.1)
    assert scene.initial["psi_dot"] == 20.0 and scene.quantities == ("theta", "phi", "psi")
    assert scene.name is None
    t = scene.times()
    assert t.shape == (1001,) and t[0] == 0.0 and t[-1] == 10.0
    np.testing.assert_allclose(np.diff(t), 0.01, rtol=1e-12)


def test_defaults_and_ints_accepted_for_floats():
    doc = heavy(method=None, rtol=None, parameters={"I1": 1, "M": 1})
    scene = parse_scene(doc)
    assert scene.method == "auto" and scene.rtol == 1e-9
    assert type(scene.parameters["I1"]) is float and type(scene.samples) is int


def test_free_top_initial_defaults_angles_to_zero():
    scene = load_scene(FREE)
    assert scene.initial == {"omega": (1.0, 0.5, 1.0), "phi": 0.0, "theta": 0.0, "psi": 0.0}
    scene = parse_scene(free(initial={"theta": 0.3}))
    assert scene.initial["theta"] == 0.3


def test_falling_cat_needs_no_parameters_or_initial():
    scene = parse_scene({"system": "falling_cat", "time": {"t_end": 1, "samples": 201},
                         "output": {"quantities": ["flip_angle", "L1"]}, "parameters": {}})
    assert scene.parameters == {} and scene.initial == {}


def test_load_scene_from_path_names_it_after_the_file(tmp_path):
    path = tmp_path / "spinning.toml"
    path.write_text(HEAVY, encoding="utf-8")
    assert load_scene(path).name == "spinning"
    assert load_scene(path, name="other").name == "other"
    path.write_text('name = "given"\n' + HEAVY, encoding="utf-8")
    assert load_scene(path).name == "given"


@pytest.mark.parametrize("text", [HEAVY, FREE, 'name = "quote \\" and \\\\ é"\n' + HEAVY])
def test_round_trip_scene_toml_scene(text):
    scene = load_scene(text)
    again = load_scene(scene_to_toml(scene))
    assert again == scene
    assert scene_to_toml(again) == scene_to_toml(scene)


def test_round_trip_keeps_every_float_exactly():
    doc = heavy(parameters={"g": 9.80665, "l": 0.1 + 0.2}, initial={"psi_dot": 1 / 3}, time={"t_end": 2 ** 0.5})
    scene = parse_scene(doc)
    again = load_scene(scene_to_toml(scene))
    assert again.parameters["l"] == 0.1 + 0.2 and again.initial["psi_dot"] == 1 / 3
    assert again.t_end == 2 ** 0.5


def test_quantity_lists_are_as_specified():
    r = [f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
    assert QUANTITIES["free_top"] == ("omega1", "omega2", "omega3", "L1", "L2", "L3", "energy", "L_norm", *r,
                                      "phi", "theta", "psi", "q0", "q1", "q2", "q3")
    assert QUANTITIES["heavy_top"] == ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot", "u", "energy",
                                       "p_phi", "p_psi", "omega1", "omega2", "omega3", *r,
                                       "apex_x", "apex_y", "apex_z")
    assert QUANTITIES["falling_cat"][:13] == (*r, "q0", "q1", "q2", "q3")
    assert QUANTITIES["falling_cat"][13:] == ("flip_angle", "L1", "L2", "L3", "shape_bend", "shape_swivel")


def test_scene_constructor_validates():
    with pytest.raises(InvalidInputError, match=r"scene key \[time\]\.samples: expected an integer in "
                                                r"\[2, 10000000\], got 1"):
        Scene(system="falling_cat", method="auto", rtol=1e-9, parameters={}, initial={}, t_end=1.0, samples=1,
              quantities=("flip_angle",))


def test_scene_is_frozen():
    scene = load_scene(HEAVY)
    with pytest.raises(AttributeError):
        scene.t_end = 3.0  # type: ignore[misc]


# ------------------------------------------------------------------------------------ structure

@pytest.mark.parametrize("doc, error, message", [
    (heavy(colour="red"), InvalidInputError,
     r"scene key colour: unknown key; expected top-level keys name, system, method, rtol, strict and tables "
     r"\[parameters\], \[initial\], \[time\], \[output\]"),
    (heavy(extras={"a": 1}), InvalidInputError,
     r"scene table \[extras\]: unknown table; expected one of \[parameters\], \[initial\], \[time\], \[output\]"),
    (heavy(time={"dt": 0.1}), InvalidInputError,
     r"scene key \[time\]\.dt: unknown key; expected one of t_end, samples"),
    (heavy(output={"format": "csv"}), InvalidInputError,
     r"scene key \[output\]\.format: unknown key; expected one of quantities"),
    (heavy(parameters={"I2": 1.0}), InvalidInputError,
     r"scene key \[parameters\]\.I2: unknown parameter for system 'heavy_top'; expected one of I1, I3, M, g, l"),
    (heavy(initial={"omega": [1, 2, 3]}), InvalidInputError,
     r"scene key \[initial\]\.omega: unknown initial value for system 'heavy_top'; expected one of theta, phi"),
    (heavy(system=None), InvalidInputError,
     r"scene key system: missing; expected one of 'free_top', 'heavy_top', 'falling_cat'"),
    (heavy(parameters={"M": None}), InvalidInputError,
     r"scene key \[parameters\]\.M: missing; expected all of I1, I3, M, g, l"),
    (heavy(initial={"psi_dot": None}), InvalidInputError,
     r"scene key \[initial\]\.psi_dot: missing; expected all of theta, phi, psi, theta_dot, phi_dot, psi_dot"),
    (heavy(time={"samples": None}), InvalidInputError,
     r"scene key \[time\]\.samples: missing; expected samples or samples_per_period"),
    (heavy(output={"quantities": None}), InvalidInputError,
     r"scene key \[output\]\.quantities: missing; expected all of quantities"),
    (heavy(parameters=None), InvalidInputError,
     r"scene table \[parameters\]: missing; system 'heavy_top' needs tables \[parameters\], \[initial\], "
     r"\[time\], \[output\]"),
    (heavy(time=None), InvalidInputError, r"scene table \[time\]: missing; system 'heavy_top' needs tables"),
    ({"system": "falling_cat", "time": {"t_end": 1, "samples": 2}}, InvalidInputError,
     r"scene table \[output\]: missing; system 'falling_cat' needs tables \[time\], \[output\]"),
    (heavy(parameters=3), InvalidInputError, r"scene table \[parameters\]: expected a table, got 3"),
    (heavy(time=[1, 2]), InvalidInputError, r"scene table \[time\]: expected a table, got \[1, 2\]"),
    (heavy(system="pendulum"), InvalidInputError,
     r"scene key system: expected one of 'free_top', 'heavy_top', 'falling_cat', ('\w+', )*got 'pendulum'"),
    (heavy(system={"x": 1}), InvalidInputError, r"scene key system: expected one of .*, got a table"),
    (heavy(method="fast"), InvalidInputError,
     r"scene key method: expected one of 'auto', 'exact', 'integrate', got 'fast'"),
    (heavy(name=""), InvalidInputError,
     r"scene key name: expected a printable string of 1 to 100 characters, got ''"),
    (heavy(name="a\nb"), InvalidInputError, r"scene key name: expected a printable string .*, got 'a\\nb'"),
], ids=lambda x: None)
def test_structure_errors(doc, error, message):
    with pytest.raises(error, match=message):
        parse_scene(doc)


def test_not_a_mapping():
    with pytest.raises(InvalidInputError, match=r"scene: expected a table of keys \(a mapping\), got \[1\]"):
        parse_scene([1])  # type: ignore[arg-type]


def test_unknown_key_with_odd_characters_is_shown_escaped():
    with pytest.raises(InvalidInputError, match=r"scene key '\\x1b\[31mred': unknown key"):
        load_scene('"\\u001b[31mred" = 1\n' + HEAVY)


# ------------------------------------------------------------------------------------ values

@pytest.mark.parametrize("doc, error, message", [
    (heavy(rtol=0.1), InvalidInputError, r"scene key rtol: expected a number in \[1e-15, 0.01\], got 0.1"),
    (heavy(rtol=1e-16), InvalidInputError, r"scene key rtol: expected a number in \[1e-15, 0.01\], got 1e-16"),
    (heavy(rtol="1e-9"), InvalidInputError, r"scene key rtol: expected a number in .*, got '1e-9'"),
    (heavy(rtol=True), InvalidInputError, r"scene key rtol: expected a number in .*, got true \(a boolean\)"),
    (heavy(time={"t_end": 0}), InvalidInputError, r"scene key \[time\]\.t_end: expected a finite number > 0, got 0"),
    (heavy(time={"t_end": -1.5}), InvalidInputError, r"scene key \[time\]\.t_end: expected .* > 0, got -1.5"),
    (heavy(time={"t_end": math.inf}), NonFiniteValueError,
     r"scene key \[time\]\.t_end: expected a finite number > 0, got inf"),
    (heavy(time={"samples": 1}), InvalidInputError,
     r"scene key \[time\]\.samples: expected an integer in \[2, 10000000\], got 1"),
    (heavy(time={"samples": 10 ** 7 + 1}), InvalidInputError,
     r"scene key \[time\]\.samples: expected an integer in \[2, 10000000\], got 10000001"),
    (heavy(time={"samples": 1001.0}), InvalidInputError,
     r"scene key \[time\]\.samples: expected an integer in \[2, 10000000\], got 1001.0"),
    (heavy(time={"samples": True}), InvalidInputError,
     r"scene key \[time\]\.samples: expected an integer .*, got true \(a boolean\)"),
    (heavy(parameters={"I1": -1.0}), InvalidInputError,
     r"scene key \[parameters\]\.I1: expected a number > 0, got -1.0"),
    (heavy(parameters={"g": 0}), InvalidInputError, r"scene key \[parameters\]\.g: expected a number > 0, got 0"),
    (heavy(parameters={"M": "1.0"}), InvalidInputError,
     r"scene key \[parameters\]\.M: expected a number > 0, got '1.0'"),
    (heavy(parameters={"l": False}), InvalidInputError,
     r"scene key \[parameters\]\.l: expected a number > 0, got false \(a boolean\)"),
    (heavy(parameters={"I3": math.nan}), NonFiniteValueError,
     r"scene key \[parameters\]\.I3: expected a number > 0, got nan"),
    # the relation itself is worded by mechderive.systems.heavy_top.parameters; the scene names the keys
    (heavy(parameters={"I1": 0.005}), UnphysicalInertiaError,
     r"scene keys \[parameters\]\.I1, \[parameters\]\.I3, \[parameters\]\.M, \[parameters\]\.l: "
     r"expected I1 - M l² >= I3/2 .*got I1 - M l² = -0.005"),
    (heavy(parameters={"I1": 0.2}), UnphysicalInertiaError,
     r"scene keys \[parameters\]\.I1, \[parameters\]\.I3, \[parameters\]\.M, \[parameters\]\.l: "
     r"expected I1 - M l² >= I3/2 .*got I1 - M l² = 0.19 < I3/2 = 0.25"),
    (heavy(initial={"theta": 4.0}), InvalidInputError,
     r"scene key \[initial\]\.theta: expected a number in \[0, π\], got 4.0"),
    (heavy(initial={"theta": -0.1}), InvalidInputError,
     r"scene key \[initial\]\.theta: expected a number in \[0, π\], got -0.1"),
    (heavy(initial={"psi_dot": -math.inf}), NonFiniteValueError,
     r"scene key \[initial\]\.psi_dot: expected a finite number, got -inf"),
    (heavy(initial={"phi": [0.0]}), InvalidInputError,
     r"scene key \[initial\]\.phi: expected a finite number, got \[0.0\]"),
    (free(parameters={"I2": 0}), InvalidInputError, r"scene key \[parameters\]\.I2: expected a number > 0, got 0"),
    (free(parameters={"I3": 4}), UnphysicalInertiaError,
     r"scene keys \[parameters\]\.I1, \[parameters\]\.I2, \[parameters\]\.I3: expected I1 \+ I2 >= I3 "
     r"\(triangle inequality\), got I1 \+ I2 = 3 < I3 = 4"),
    (free(parameters={"I4": 1}), InvalidInputError,
     r"scene key \[parameters\]\.I4: unknown parameter for system 'free_top'; expected one of I1, I2, I3"),
    (free(initial={"omega": [1, 2]}), InvalidInputError,
     r"scene key \[initial\]\.omega: expected a list of 3 finite numbers \[w1, w2, w3\] \(rad/s\), got \[1, 2\]"),
    (free(initial={"omega": 1.0}), InvalidInputError,
     r"scene key \[initial\]\.omega: expected a list of 3 finite numbers .*, got 1.0"),
    (free(initial={"omega": [1, math.nan, 1]}), NonFiniteValueError,
     r"scene key \[initial\]\.omega\[1\]: expected a finite number, got nan"),
    (free(initial={"omega": [1, "x", 1]}), InvalidInputError,
     r"scene key \[initial\]\.omega\[1\]: expected a finite number, got 'x'"),
    (free(initial={"psi": math.inf}), NonFiniteValueError,
     r"scene key \[initial\]\.psi: expected a finite number, got inf"),
    (free(initial={"theta_dot": 1}), InvalidInputError,
     r"scene key \[initial\]\.theta_dot: unknown initial value for system 'free_top'; "
     r"expected one of omega, phi, theta, psi"),
    (free(initial=None), InvalidInputError, r"scene table \[initial\]: missing; system 'free_top' needs"),
    ({"system": "falling_cat", "parameters": {"k": 1}, "time": {"t_end": 1, "samples": 2},
      "output": {"quantities": ["L1"]}}, InvalidInputError,
     r"scene key \[parameters\]\.k: unknown parameter for system 'falling_cat'; expected one of half_mass, "
     r"joint_offset, radius, half_length, peak_bend"),
    ({"system": "falling_cat", "initial": {"shape": 1}, "time": {"t_end": 1, "samples": 2},
      "output": {"quantities": ["L1"]}}, InvalidInputError,
     r"scene key \[initial\]\.shape: unknown initial value for system 'falling_cat'; it takes none"),
    # the cat's own checks (mechderive.systems.deformable.cat.check_cat_parameters), said of the scene keys
    ({"system": "falling_cat", "parameters": {"radius": -0.25}, "time": {"t_end": 1, "samples": 2},
      "output": {"quantities": ["L1"]}}, InvalidInputError,
     r"^scene key \[parameters\]\.radius: expected a number > 0, got -0.25$"),
    ({"system": "falling_cat", "parameters": {"peak_bend": 3.5}, "time": {"t_end": 1, "samples": 2},
      "output": {"quantities": ["L1"]}}, InvalidInputError,
     r"^scene key \[parameters\]\.peak_bend: expected a number in \(0, π\) \(rad: the halves must not fold "
     r"through each other\), got 3.5$"),
    ({"system": "falling_cat", "parameters": {"half_mass": 10 ** 400}, "time": {"t_end": 1, "samples": 2},
      "output": {"quantities": ["L1"]}}, NonFiniteValueError,
     r"^scene key \[parameters\]\.half_mass: expected a number > 0 \(a finite double: at most 1.8e\+308 in size\), "
     r"got an integer of 401 digits$"),
], ids=lambda x: None)
def test_value_errors(doc, error, message):
    with pytest.raises(error, match=message):
        parse_scene(doc)


@pytest.mark.parametrize("quantities, message", [
    ([], r"scene key \[output\]\.quantities: expected a non-empty list of quantity names "
         r"\(for heavy_top: theta, phi, psi, .*apex_z\), got \[\]"),
    ("theta", r"scene key \[output\]\.quantities: expected a non-empty list of quantity names .*, got 'theta'"),
    (["theta", 3], r"scene key \[output\]\.quantities\[1\]: expected a quantity name \(a string\), got 3"),
    (["theta", "omega"], r"scene key \[output\]\.quantities\[1\]: unknown quantity 'omega' for system 'heavy_top'; "
                         r"expected one of theta, phi, psi, theta_dot, .*, apex_x, apex_y, apex_z$"),
    (["theta", "phi", "theta"], r"scene key \[output\]\.quantities\[2\]: duplicate quantity 'theta'; "
                                r"each may appear once"),
])
def test_quantity_errors(quantities, message):
    with pytest.raises(InvalidInputError, match=message):
        parse_scene(heavy(output={"quantities": quantities}))


def test_quantities_are_checked_per_system():
    with pytest.raises(InvalidInputError, match=r"unknown quantity 'apex_x' for system 'free_top'; "
                                                r"expected one of omega1, omega2"):
        parse_scene(free(output={"quantities": ["omega1", "apex_x"]}))


# ------------------------------------------------------------------------------------ TOML text and files

@pytest.mark.parametrize("text, message", [
    ('system = "heavy_top"\nrtol = ', r"scene text: not valid TOML: Invalid value \(at end of document\)"),
    ('system = "heavy_top"\nrtol 1e-9\n', r"scene text: not valid TOML: .*\(at line 2, column 6\)"),
    ('rtol = 1e-9\nrtol = 1e-8\n', r"scene text: not valid TOML: Cannot overwrite a value"),
    ("rtol = " + "[" * 100_000, r"scene text: not valid TOML: arrays or tables nested too deeply"),
])
def test_toml_syntax_errors_are_wrapped(text, message):
    with pytest.raises(InvalidInputError, match=message):
        load_scene(text)


def test_nan_literal_in_toml_is_refused():
    with pytest.raises(NonFiniteValueError, match=r"scene key \[parameters\]\.g: expected a number > 0, got nan"):
        load_scene(HEAVY.replace("g = 9.81", "g = nan"))


@pytest.mark.parametrize("literal, error, message", [
    ("1e400", NonFiniteValueError,
     r"^scene key \[parameters\]\.g: expected a number > 0 \(a finite double: at most 1.8e\+308 in size\), got 1e400$"),
    ("-1" + "0" * 400, NonFiniteValueError, r"^scene key \[parameters\]\.g: .*, got an integer of 401 digits$"),
    ("9" * 4301, NonFiniteValueError, r"^scene key \[parameters\]\.g: .*, got an integer of 4301 digits$"),
    ("1_000" * 1200, NonFiniteValueError, r"^scene key \[parameters\]\.g: .*, got an integer of 4800 digits$"),
    # nonzero, below the smallest double: 0, said so where 0 is refused
    ("1e-400", InvalidInputError, r"^scene key \[parameters\]\.g: expected a number > 0, got 1e-400 "
                                  r"\(0 in double precision\)$"),
])
def test_numbers_no_double_holds_are_named_as_written(literal, error, message):
    with pytest.raises(error, match=message):
        load_scene(HEAVY.replace("g = 9.81", f"g = {literal}"))


def test_checks_near_the_largest_double_warn_of_nothing():
    """Sums and squares of moments overflow to inf in the physics checks: their answers stand, silently."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning would be printed before the message
        assert parse_scene(free(parameters={"I1": 1.7e308, "I2": 1.7e308, "I3": 1.7e308})).parameters["I1"] == 1.7e308
        with pytest.raises(UnphysicalInertiaError, match=r"^scene keys \[parameters\]\.I1, .*got I1 - M l² = -inf "
                                                         r"< I3/2 = 0\.25"):
            parse_scene(heavy(parameters={"I1": 1e308, "I3": 0.5, "M": 1e308, "l": 1e308}))


def test_huge_integers_elsewhere_in_the_text_are_left_alone():
    """Only integer values are marked: digits in strings, comments, floats and dates stay as written."""
    scene = load_scene(HEAVY.replace("g = 9.81", f"g = {'1' * 5000}.5e-4990  # {'2' * 5000}")
                       .replace('system = "heavy_top"', f'system = "heavy_top"\nname = "x{"3" * 4400}"'), name="n")
    assert scene.parameters["g"] == float(f"{'1' * 5000}.5e-4990")
    with pytest.raises(InvalidInputError, match=r"^scene key name: expected a printable string of 1 to 100 "
                                                r"characters, got 'x3333.*\(truncated\)$"):
        load_scene(HEAVY.replace('system = "heavy_top"', f'system = "heavy_top"\nname = "x{"3" * 4400}"')
                   .replace("samples = 1001", f"samples = {'4' * 4400}"))
    with pytest.raises(InvalidInputError, match=r"^scene key \[time\]\.samples: .*got an integer of 4400 digits$"):
        load_scene(HEAVY.replace('system = "heavy_top"', f'system = "heavy_top"\nname = "x{"3" * 50}"')
                   .replace("samples = 1001", f"samples = {'4' * 4400}"))


def test_datetime_value_is_named():
    with pytest.raises(InvalidInputError, match=r"scene key \[time\]\.t_end: expected a finite number > 0, "
                                                r"got 1979-05-27T07:32:00 \(a date/time\)"):
        load_scene(HEAVY.replace("t_end = 10.0", "t_end = 1979-05-27T07:32:00"))


def test_file_errors(tmp_path):
    with pytest.raises(InvalidInputError, match=r"scene file '.*missing\.toml': expected an existing file, "
                                                r"got no such file"):
        load_scene(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text('system = "heavy_top"\n[time\n', encoding="utf-8")
    with pytest.raises(InvalidInputError, match=r"scene file '.*bad\.toml': not valid TOML: .*\(at line 2, "
                                                r"column \d+\): '\[time'$"):
        load_scene(bad)
    latin = tmp_path / "latin.toml"
    latin.write_bytes(b'name = "caf\xe9"\n')
    with pytest.raises(InvalidInputError, match=r"scene file '.*latin\.toml': expected UTF-8 text, got byte 0xe9, "
                                                r"which is not UTF-8, at line 1, column 12$"):
        load_scene(latin)
    big = tmp_path / "big.toml"
    big.write_text("#" * (schema.MAX_SCENE_BYTES + 1), encoding="utf-8")
    with pytest.raises(InvalidInputError, match=r"scene file '.*big\.toml': expected at most 1000000 bytes, "
                                                r"got 1000001"):
        load_scene(big)


def test_a_path_given_as_str_gets_a_hint():
    with pytest.raises(InvalidInputError, match=r"scene text: expected TOML, got 'scenes/top\.toml', which looks "
                                                r"like a file name; pass pathlib\.Path\('scenes/top\.toml'\)"):
        load_scene("scenes/top.toml")


def test_wrong_argument_type():
    with pytest.raises(InvalidInputError, match=r"scene: expected a pathlib\.Path or TOML text \(a str\), "
                                                r"got a bytes"):
        load_scene(HEAVY.encode())  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------ hostile input

PAYLOAD = "__import__('pathlib').Path({marker!r}).touch() or __import__('os').system('echo hi')"


def test_scene_files_are_data_nothing_in_them_is_evaluated(tmp_path, monkeypatch):
    """Scene files are data: nothing in them is evaluated as code."""
    import builtins
    import os

    marker = tmp_path / "pwned"
    payload = PAYLOAD.format(marker=str(marker))
    calls = []
    monkeypatch.setattr(os, "system", lambda *a: calls.append(a) or 0)
    monkeypatch.setattr(builtins, "eval", lambda *a, **k: calls.append(a))
    monkeypatch.setattr(builtins, "exec", lambda *a, **k: calls.append(a))
    as_parameter = HEAVY.replace("I1 = 1.0", f"I1 = {schema._toml_string(payload)}")
    with pytest.raises(InvalidInputError, match=r"scene key \[parameters\]\.I1: expected a number > 0, "
                                                r"got \"__import__\('pathlib'\).*\(truncated\)"):
        load_scene(as_parameter)
    as_quantity = HEAVY.replace('quantities = ["theta"', f'quantities = [{schema._toml_string(payload)}')
    with pytest.raises(InvalidInputError, match=r"scene key \[output\]\.quantities\[0\]: unknown quantity "
                                                r"\"__import__.*\(truncated\) for system 'heavy_top'"):
        load_scene(as_quantity)
    as_system = HEAVY.replace('system = "heavy_top"', f"system = {schema._toml_string(payload)}")
    with pytest.raises(InvalidInputError, match=r"scene key system: expected one of 'free_top', 'heavy_top', "
                                                r"'falling_cat', ('\w+', )*got \"__import__"):
        load_scene(as_system)
    as_key = HEAVY.replace("I1 = 1.0", f"{schema._toml_string(payload)} = 1.0")
    with pytest.raises(InvalidInputError, match=r"scene key \[parameters\]\.\"__import__.*: unknown parameter"):
        load_scene(as_key)
    assert not marker.exists() and calls == []


def test_loading_scenes_imports_no_sympy():
    proc = run_python("-c", "import sys; from mechderive.scenes.builtin import load_builtin; "
                            "load_builtin('default'); print('sympy' in sys.modules)")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "False"


# ------------------------------------------------------------------------------------ registration hooks

def test_register_falling_cat_parameters_and_quantities(monkeypatch):
    from mechderive.systems import registry

    cat = registry.get("falling_cat")
    monkeypatch.setattr(cat, "parameters", cat.parameters)  # restored after the test
    monkeypatch.setattr(cat, "quantities", cat.quantities)
    schema.register_system_parameters("falling_cat", ["twist", "bend"])
    schema.register_system_parameters("falling_cat", ["twist"])  # twice: harmless
    schema.register_system_quantities("falling_cat", ("shape_twist", "shape_bend"))
    assert tuple(k.name for k in cat.parameters)[-2:] == ("twist", "bend")
    assert QUANTITIES["falling_cat"][-2:] == ("shape_swivel", "shape_twist")  # shape_bend was already known
    scene = parse_scene({"system": "falling_cat", "parameters": {"twist": 0.5},
                         "time": {"t_end": 1, "samples": 3}, "output": {"quantities": ["shape_bend"]}})
    assert scene.parameters == {"twist": 0.5}
    assert load_scene(scene_to_toml(scene)) == scene
    with pytest.raises(InvalidInputError, match=r"scene key \[parameters\]\.twist: expected a finite number, "
                                                r"got 'a lot'"):
        parse_scene({"system": "falling_cat", "parameters": {"twist": "a lot"},
                     "time": {"t_end": 1, "samples": 3}, "output": {"quantities": ["L1"]}})


def test_registration_refusals():
    with pytest.raises(InvalidInputError, match=r"expected a system whose parameters are open \(falling_cat\), "
                                                r"got 'heavy_top', whose parameters are fixed: I1, I3, M, g, l"):
        schema.register_system_parameters("heavy_top", ["k"])
    with pytest.raises(InvalidInputError, match=r"expected quantity names matching \[A-Za-z_\]\[A-Za-z0-9_\]\*, "
                                                r"got 'shape-x'"):
        schema.register_system_quantities("falling_cat", ["shape-x"])
    with pytest.raises(InvalidInputError, match=r"expected a sequence of parameter names, got the single string "
                                                r"'twist'"):
        schema.register_system_parameters("falling_cat", "twist")
    with pytest.raises(InvalidInputError, match=r"expected a system, one of free_top, heavy_top, falling_cat, "
                                                r"(\w+, )*got 'dog'"):
        schema.register_system_quantities("dog", ["x"])


# ------------------------------------------------------------------------------------ built-in scenes

@pytest.mark.parametrize("name", [n for n, _ in builtin.list_scenes()])
def test_every_builtin_parses_and_round_trips(name):
    scene = load_scene(builtin.scene_text(name), name=name)
    assert scene == builtin.load_builtin(name)
    assert scene.name == name
    assert load_scene(scene_to_toml(scene)) == scene


def test_size_estimate_of_every_builtin_is_within_the_limit():
    for name, _ in builtin.list_scenes():
        size = builtin.load_builtin(name).size_estimate
        assert size.values == size.samples * size.columns and size.memory_bytes <= schema.MAX_RUN_BYTES


def test_builtin_list_and_descriptions():
    names = [n for n, _ in builtin.list_scenes()]
    # each system's own, the default's system first (the default leading), then in the registry's order
    assert names == ["default", "heavy_top_looping", "heavy_top_hanging", "sleeping_top", "gyroscope",
                     "free_top_tumbling", "free_top_near_separatrix", "tennis_racket", "falling_cat"]
    for _, description in builtin.list_scenes():
        assert description and "\n" not in description


def test_unknown_builtin_lists_names():
    with pytest.raises(InvalidInputError, match=r"unknown built-in scene 'nope': expected one of default, "
                                                r"heavy_top_looping, .*, falling_cat$"):
        builtin.load_builtin("nope")


def test_builtin_default_is_the_baseline_top():
    scene = builtin.load_builtin("default")
    assert scene.parameters == dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
    assert scene.initial == dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0)
    assert (scene.t_end, scene.samples, scene.quantities) == (35.177, 2001, ("theta", "phi", "psi"))


def test_builtin_physics_claims():
    p = builtin.load_builtin("sleeping_top").parameters
    s = builtin.load_builtin("sleeping_top").initial
    threshold = 2 * math.sqrt(p["I1"] * p["M"] * p["g"] * p["l"]) / p["I3"]
    assert s["theta"] == 0.0 and s["psi_dot"] > threshold
    assert builtin.load_builtin("heavy_top_hanging").initial["theta"] == 2.5
    # near separatrix: L² - 2 T I2 ≈ 1e-10 L²
    scene = builtin.load_builtin("free_top_near_separatrix")
    moments = np.array([scene.parameters[k] for k in ("I1", "I2", "I3")])
    w = np.array(scene.initial["omega"])
    l2, two_t = np.sum(moments ** 2 * w ** 2), np.sum(moments * w ** 2)
    excess = np.sum(moments * (moments - moments[1]) * w ** 2)  # = L² - 2 T I2 without cancellation
    assert excess / l2 == pytest.approx(1e-10, rel=1e-5)
    assert (l2 - two_t * moments[1]) / l2 == pytest.approx(1e-10, rel=1e-3)
    # tennis racket: spin about the intermediate axis, perturbed by 1e-6
    scene = builtin.load_builtin("tennis_racket")
    assert scene.initial["omega"] == (1e-6, 1.0, 1e-6)
    cat = builtin.load_builtin("falling_cat")
    assert (cat.t_end, cat.samples, cat.quantities) == (1.0, 201, ("flip_angle", "L1", "L2", "L3"))


# --------------------------------------------------------------------------- the parsed TOML kept in the disk cache

def _parsed_entries(root) -> list:
    return sorted(root.rglob("scene-*.marshal"))


def test_the_command_line_s_parse_is_kept_and_read_back_as_tomllib_gave_it(tmp_path, monkeypatch):
    import tomllib

    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    text = HEAVY
    first = load_scene(text, cached=True)
    (entry,) = _parsed_entries(tmp_path)
    monkeypatch.setattr(schema, "_read_toml", lambda *a: pytest.fail("parsed again"))
    second = load_scene(text, cached=True)
    assert second == first and second.parameters == first.parameters and second.quantities == first.quantities
    document = schema._parse_toml(text, "text", True)
    want = tomllib.loads(text)
    assert document == want and list(document) == list(want)
    assert [type(v) for v in document["initial"].values()] == [type(v) for v in want["initial"].values()]
    # without cached (the library's default), nothing is read or written
    monkeypatch.undo()
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path / "other"))
    load_scene(text)
    assert not _parsed_entries(tmp_path / "other")


def test_a_document_that_is_not_plain_data_is_never_kept(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    underflowed = HEAVY.replace("theta_dot = 0.0", "theta_dot = 1e-400")  # 0 in doubles: kept with its text
    assert type(schema._parse_toml(underflowed, "text", True)["initial"]["theta_dot"]) is schema._Underflowed
    assert load_scene(underflowed, cached=True).initial["theta_dot"] == 0.0
    with pytest.raises(InvalidInputError, match="not valid TOML"):
        load_scene(HEAVY + "[time\n", cached=True)
    assert schema._parse_toml('when = 1979-05-27\n', "text", True) == {"when": __import__("datetime").date(1979, 5, 27)}
    assert not _parsed_entries(tmp_path)


def test_an_entry_that_does_not_verify_is_parsed_anew_and_replaced(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    load_scene(HEAVY, cached=True)
    (entry,) = _parsed_entries(tmp_path)
    import marshal

    forged = marshal.dumps({"system": "heavy_top", "rtol": 0.5})  # another document, its hash not recomputed
    data = entry.read_bytes()
    entry.write_bytes(data.split(b"\n", 1)[0] + b"\n" + forged)
    scene = load_scene(HEAVY, cached=True)
    assert scene.rtol == 1e-10 and scene.parameters["I1"] == 1.0
    assert entry.read_bytes() == data
