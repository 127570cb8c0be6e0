"""Scene results: tables (CSV, NPZ), the JSON report, the progress bar and the plots."""

from __future__ import annotations

import builtins
import io
import json
import math
import re
import sys

import numpy as np
import pytest

from mechderive.errors import InvalidInputError, ShapeError
from mechderive.scenes.output import report_json, write_table
from mechderive.scenes.progress import Progress

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def table(rng):
    t = np.linspace(0.0, 10.0, 101)
    columns = {
        "theta": 0.5 + 0.1 * np.sin(t) + 1e-17 * rng.standard_normal(t.size),
        "phi": rng.standard_normal(t.size) * 10.0 ** rng.integers(-300, 300, t.size),
        "R11": np.r_[np.nan, np.inf, -np.inf, -0.0, 5e-324, rng.random(t.size - 5)],
    }
    return t, columns


# ------------------------------------------------------------------------------------ tables

def test_csv_round_trips_exactly(tmp_path, table):
    t, columns = table
    path = write_table(tmp_path / "out.csv", t, columns)
    with open(path, encoding="ascii") as f:
        assert f.readline() == "t,theta,phi,R11\n"
    back = np.loadtxt(path, delimiter=",", skiprows=1)
    assert back.shape == (101, 4)
    np.testing.assert_array_equal(back[:, 0], t)
    for k, name in enumerate(columns, start=1):
        np.testing.assert_array_equal(back[:, k], columns[name])  # NaN == NaN here
    assert math.copysign(1.0, back[3, 3]) == -1.0  # -0.0 kept


def test_csv_keeps_the_column_order_given(tmp_path):
    t = np.arange(3.0)
    write_table(tmp_path / "o.csv", t, {"psi": t, "apex_z": -t, "energy": 2 * t})
    assert (tmp_path / "o.csv").read_text().splitlines()[0] == "t,psi,apex_z,energy"


def test_npz_round_trips_exactly(tmp_path, table):
    t, columns = table
    columns = {**columns, "file": t * 3, "allow_pickle": t * 4}  # names np.savez's keywords would swallow
    write_table(tmp_path / "out.npz", t, columns)
    with np.load(tmp_path / "out.npz", allow_pickle=False) as data:
        assert data.files == ["t", *columns]
        np.testing.assert_array_equal(data["t"], t)
        for name, values in columns.items():
            np.testing.assert_array_equal(data[name], values)
            assert data[name].dtype == np.float64


def test_no_temporary_file_is_left(tmp_path):
    write_table(tmp_path / "a.csv", [0.0, 1.0], {"x": [1.0, 2.0]})
    write_table(tmp_path / "a.npz", [0.0, 1.0], {"x": [1.0, 2.0]})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "a.npz"]


@pytest.mark.parametrize("name, suffix", [("out.txt", "'.txt'"), ("out", "'none'"), ("out.csv.gz", "'.gz'")])
def test_bad_suffix_is_refused(tmp_path, name, suffix):
    with pytest.raises(InvalidInputError, match=rf"output file '.*{name}': expected a suffix \.csv or \.npz, "
                                                rf"got {suffix}"):
        write_table(tmp_path / name, [0.0], {"x": [1.0]})
    assert not (tmp_path / name).exists()


def test_table_input_errors(tmp_path):
    with pytest.raises(ShapeError, match=r"expected column 'x' to have the shape of `t`, \(3,\), got \(2,\)"):
        write_table(tmp_path / "a.csv", [0.0, 1.0, 2.0], {"x": [1.0, 2.0]})
    with pytest.raises(ShapeError, match=r"expected `t` to be a 1-D array of real numbers, got shape \(2, 2\)"):
        write_table(tmp_path / "a.csv", np.zeros((2, 2)), {})
    with pytest.raises(InvalidInputError, match=r"expected a column name matching .* other than 't', got 't'"):
        write_table(tmp_path / "a.csv", [0.0], {"t": [1.0]})
    with pytest.raises(InvalidInputError, match=r"expected a column name matching .*, got 'a,b'"):
        write_table(tmp_path / "a.csv", [0.0], {"a,b": [1.0]})
    with pytest.raises(InvalidInputError, match=r"expected column 'x' to hold real numbers, got complex128"):
        write_table(tmp_path / "a.npz", [0.0], {"x": [1j]})
    with pytest.raises(InvalidInputError, match=r"expected an existing directory, got '.*nowhere'"):
        write_table(tmp_path / "nowhere" / "a.csv", [0.0], {"x": [1.0]})


# ------------------------------------------------------------------------------------ report

def test_report_json_is_stable_and_writes_non_finite_as_strings():
    report = {"z": 1, "a": {"y": np.float64(np.nan), "b": [np.inf, -np.inf, 0.1]},
              "m": np.array([1.5, 2.5]), "n": np.int64(3), "ok": np.bool_(True), "none": None}
    text = report_json(report)
    assert text == report_json(dict(reversed(list(report.items()))))
    back = json.loads(text)
    assert list(back) == ["a", "m", "n", "none", "ok", "z"]
    assert back["a"] == {"b": ["Infinity", "-Infinity", 0.1], "y": "NaN"}
    assert [float(x) for x in back["a"]["b"]][:2] == [math.inf, -math.inf]
    assert math.isnan(float(back["a"]["y"]))
    assert back["m"] == [1.5, 2.5] and back["n"] == 3 and back["ok"] is True and back["none"] is None
    assert "NaN," not in text and "Infinity," not in text.replace('"Infinity",', "")


def test_report_json_refusals():
    with pytest.raises(InvalidInputError, match=r"report value at a\.b\[1\]: expected a number, string, boolean, "
                                                r"None, list or mapping, got object"):
        report_json({"a": {"b": [1, object()]}})
    with pytest.raises(InvalidInputError, match=r"report key at a: expected a string, got 1"):
        report_json({"a": {1: 2}})
    with pytest.raises(InvalidInputError, match=r"expected the report to be a mapping, got list"):
        report_json([1])  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------ progress

class FakeTTY(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_is_silent_off_a_terminal():
    stream = io.StringIO()
    with Progress(100, label="integrating", stream=stream, min_seconds=0) as bar:
        for _ in range(100):
            bar.update(1)
    assert stream.getvalue() == ""


def test_progress_draws_on_a_terminal_and_ends_the_line():
    stream = FakeTTY()
    with Progress(10, label="integrating", stream=stream, min_seconds=0) as bar:
        for _ in range(10):
            bar.update()
    out = stream.getvalue()
    assert out.startswith("\rintegrating [") and out.endswith("\n") and out.count("\n") == 1
    last = out.rstrip("\n").split("\r")[-1]
    assert re.fullmatch(r"integrating \[#{30}\] 100% \(10/10\) \d+\.\d s *", last)


def test_progress_waits_for_min_seconds():
    now = [0.0]
    stream = FakeTTY()
    with Progress(4, label="x", stream=stream, min_seconds=1.0, clock=lambda: now[0]) as bar:
        bar.update(1)
        assert stream.getvalue() == ""
        now[0] = 2.0
        bar.update(1)
        assert "50% (2/4) 2.0 s" in stream.getvalue()
    assert stream.getvalue().endswith("\n")
    quick = FakeTTY()
    with Progress(4, label="x", stream=quick, min_seconds=1.0, clock=lambda: 0.0) as bar:
        bar.update(4)
    assert quick.getvalue() == ""


def test_progress_ends_the_line_when_the_block_raises():
    stream = FakeTTY()
    with pytest.raises(KeyError):
        with Progress(4, label="x", stream=stream, min_seconds=0) as bar:
            bar.update(1)
            raise KeyError("boom")
    assert stream.getvalue().endswith("\n")


def test_progress_defaults_to_current_stderr(monkeypatch):
    fake = FakeTTY()
    monkeypatch.setattr(sys, "stderr", fake)
    with Progress(1, label="y", min_seconds=0) as bar:
        bar.update(1)
    assert fake.getvalue().endswith("\n")


def test_progress_input_errors():
    with pytest.raises(InvalidInputError, match=r"expected `total` to be an integer >= 0, got -1"):
        Progress(-1, label="x")
    with pytest.raises(InvalidInputError, match=r"expected `min_seconds` to be a number >= 0, got -0.5"):
        Progress(1, label="x", min_seconds=-0.5)
    with pytest.raises(InvalidInputError, match=r"expected `n` to be an integer >= 0, got 1.5"):
        Progress(1, label="x").update(1.5)  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------ plots

def _heavy_top_data() -> dict[str, np.ndarray]:
    t = np.linspace(0.0, 35.0, 701)
    theta = 0.6 - 0.1 * np.cos(2 * np.pi * t / 3.5)
    phi = 0.3 * t - 0.05 * np.sin(2 * np.pi * t / 3.5)
    return {"t": t, "theta": theta, "apex_x": np.sin(theta) * np.sin(phi),
            "apex_y": -np.sin(theta) * np.cos(phi), "apex_z": np.cos(theta)}


def _free_top_data() -> dict[str, np.ndarray]:
    t = np.linspace(0.0, 30.0, 601)  # a symmetric-top-like polhode: any samples will do for a picture
    return {"t": t, "omega1": np.cos(t), "omega2": 0.5 * np.sin(t), "omega3": np.ones_like(t)}


@pytest.mark.parametrize("system, data, extra", [
    ("heavy_top", _heavy_top_data(), None),
    ("free_top", _free_top_data(), {"moments": (1.0, 2.0, 3.0)}),
    ("falling_cat", {"t": np.linspace(0, 1, 201), "flip_angle": np.linspace(0, np.pi, 201)}, {"title": "cat"}),
])
def test_plot_each_kind_to_png(tmp_path, system, data, extra):
    pytest.importorskip("matplotlib")
    from mechderive.scenes.plot import plot_scene

    path = plot_scene(system, data, tmp_path / f"{system}.png", extra=extra)
    content = path.read_bytes()
    assert content[:8] == PNG_SIGNATURE
    assert 10_000 < len(content) < 2_000_000


def test_plot_input_errors(tmp_path):
    pytest.importorskip("matplotlib")
    from mechderive.scenes.plot import plot_scene

    data = _heavy_top_data()
    with pytest.raises(InvalidInputError, match=r"plot of heavy_top: expected data t, theta, apex_x, apex_y, "
                                                r"apex_z, got no 'apex_x'"):
        plot_scene("heavy_top", {k: v for k, v in data.items() if k != "apex_x"}, tmp_path / "a.png")
    with pytest.raises(ShapeError, match=r"plot of heavy_top: expected data 'theta' to be 1-D with the shape "
                                         r"of t, \(701,\), got \(3,\)"):
        plot_scene("heavy_top", {**data, "theta": np.zeros(3)}, tmp_path / "a.png")
    with pytest.raises(InvalidInputError, match=r"plot file '.*a\.jpg': expected a suffix \.png, \.pdf, \.svg, "
                                                r"got '\.jpg'"):
        plot_scene("heavy_top", data, tmp_path / "a.jpg")
    # the systems of the registry: the built-in ones first, then any registered
    with pytest.raises(InvalidInputError, match=r"expected a system, one of free_top, heavy_top, falling_cat, "
                                                r"(\w+, )*got 'dog'"):
        plot_scene("dog", data, tmp_path / "a.png")
    with pytest.raises(InvalidInputError, match=r"plot of free_top: expected extra\['moments'\] = \(I1, I2, I3\), "
                                                r"three numbers > 0, got None"):
        plot_scene("free_top", _free_top_data(), tmp_path / "a.png")
    with pytest.raises(InvalidInputError, match=r"expected `extra` to be a mapping with keys among moments, "
                                                r"title, got \{'colour': 'red'\}"):
        plot_scene("falling_cat", {"t": [0, 1], "flip_angle": [0, 1]}, tmp_path / "a.png",
                   extra={"colour": "red"})
    assert not any(tmp_path.iterdir())


def test_plot_without_matplotlib_says_how_to_install(tmp_path, monkeypatch):
    from mechderive.scenes.plot import plot_scene

    real_import = builtins.__import__

    def no_matplotlib(name, *args, **kwargs):
        if name == "matplotlib" or name.startswith(("matplotlib.", "mpl_toolkits")):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    with pytest.raises(InvalidInputError, match=r"^plotting needs matplotlib: pip install 'mechderive\[plot\]'$"):
        plot_scene("falling_cat", {"t": [0.0, 1.0], "flip_angle": [0.0, 1.0]}, tmp_path / "cat.png")
    assert not (tmp_path / "cat.png").exists()


def test_importing_the_scene_modules_imports_no_matplotlib():
    from .conftest import run_python

    proc = run_python("-c", "import sys, mechderive.scenes.plot, mechderive.scenes.output, "
                            "mechderive.scenes.progress, mechderive.scenes.builtin; "
                            "print('matplotlib' in sys.modules)")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "False"


def test_progress_with_a_rate_unit_shows_the_rate_and_the_time_left():
    now = [0.0]
    stream = FakeTTY()
    with Progress(1000, label="sweep", stream=stream, min_seconds=0, clock=lambda: now[0], rate_unit="points") as bar:
        now[0] = 2.0
        bar.update(250)  # 125 points/s; 750 left take 6 s at that rate
        assert stream.getvalue().endswith("25% (250/1000) 2.0 s, 125 points/s, 6 s left")
