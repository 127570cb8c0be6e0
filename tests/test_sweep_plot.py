"""Maps of a parameter sweep (mechderive.sweeps.plot): what is drawn, the files written, the refusals.

What a picture holds (panels, categories and their counts, colour-scale limits) is checked through
``_layout`` against the table computed independently here; the files are checked for their format
and a sensible size.
"""

from __future__ import annotations

import struct
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from mechderive.errors import InvalidInputError, MechDeriveError
from mechderive.sweeps.plot import MAX_PANELS, _layout, plot_map

CLASSES = ("monotonic precession", "looping", "cusps", "uniform precession")


def _status(rows: int, refused: list[int]) -> np.ndarray:
    status = np.array(["ok"] * rows, dtype=object)
    for i in refused:
        status[i] = "refused: energy above the separatrix"
    return status


@pytest.fixture
def grid2() -> dict[str, np.ndarray]:
    """6 × 5 grid over (theta0, spin), C order, two refused points, a categorical column with gaps."""
    theta, spin = np.linspace(0.2, 1.2, 6), np.linspace(5.0, 25.0, 5)
    T, S = np.meshgrid(theta, spin, indexing="ij")
    rows = T.size
    nutation = (np.sin(T) / S).ravel()
    nutation[7] = np.nan  # not available although the point is ok
    motion = np.array([CLASSES[i % 3] for i in range(rows)], dtype=object)
    motion[4], motion[11] = "", None
    return {"theta0": T.ravel(), "spin": S.ravel(), "status": _status(rows, [2, 17]),
            "nutation": nutation, "motion_class": motion}


@pytest.fixture
def grid3() -> dict[str, np.ndarray]:
    """20 × 4 × 3 grid: more values of the first axis than panels."""
    a, b, c = np.linspace(0.0, 1.9, 20), np.linspace(1.0, 4.0, 4), np.linspace(-1.0, 1.0, 3)
    A, B, C = np.meshgrid(a, b, c, indexing="ij")
    rows = A.size
    return {"mass": A.ravel(), "theta0": B.ravel(), "spin": C.ravel(), "status": _status(rows, [0, 5]),
            "energy": (A * B + C).ravel(),
            "motion_class": np.where(A.ravel() > 1.0, "looping", "cusps").astype(str)}


@pytest.fixture
def grid3_small(grid3) -> dict[str, np.ndarray]:
    """The first 5 masses of ``grid3``: 5 panels (a 12-panel figure takes ~2 s to draw)."""
    keep = grid3["mass"] < 0.45
    return {k: v[keep] for k, v in grid3.items()}


@pytest.fixture
def random3(rng) -> dict[str, np.ndarray]:
    rows = 150
    x, y, z = rng.uniform(0, 1, rows), rng.uniform(-2, 2, rows), rng.uniform(3, 4, rows)
    q = x * y
    q[:9] = np.nan
    return {"theta0": x, "spin": y, "mass": z, "status": _status(rows, [20, 21, 22]), "period": q,
            "motion_class": np.array([CLASSES[i % 4] for i in range(rows)], dtype=object)}


def _ok(table: dict[str, np.ndarray]) -> np.ndarray:
    return np.array([s == "ok" for s in table["status"]])


def _expected_categories(names, ok) -> tuple[list[tuple[str, int]], int]:
    counts = Counter(n for n, good in zip(names, ok) if good and isinstance(n, str) and n)
    return sorted(counts.items()), len(names) - sum(counts.values())


# --- what is drawn ------------------------------------------------------------------------------


def test_layout_2d_numeric(grid2):
    layout = _layout(grid2, ["theta0", "spin"], "nutation", True)
    ok = _ok(grid2) & np.isfinite(grid2["nutation"])
    shown = grid2["nutation"][ok]
    assert layout.panels == 1 and not layout.categorical and layout.categories == ()
    assert layout.limits == (shown.min(), shown.max())
    assert layout.missing == 3  # two refused, one NaN
    assert layout.values.shape == (6, 5)
    # C order: the last axis varies fastest, so row i*5 + j is (theta[i], spin[j])
    assert layout.values[3, 4] == grid2["nutation"][19]


def test_layout_2d_categorical(grid2):
    layout = _layout(grid2, ["theta0", "spin"], "motion_class", True)
    categories, missing = _expected_categories(grid2["motion_class"].tolist(), _ok(grid2))
    assert layout.categorical and layout.limits is None
    assert list(layout.categories) == categories
    assert [n for n, _ in layout.categories] == sorted(n for n, _ in layout.categories)
    assert layout.missing == missing == 4  # two refused, "" and None
    assert sum(c for _, c in layout.categories) + layout.missing == 30


def test_layout_3d_chooses_panels_evenly(grid3):
    layout = _layout(grid3, ["mass", "theta0", "spin"], "energy", True)
    masses = np.unique(grid3["mass"])
    assert layout.panels == MAX_PANELS == len(layout.panel_values)
    assert layout.panel_values[0] == masses[0] and layout.panel_values[-1] == masses[-1]
    assert set(layout.panel_values) <= set(masses) and list(layout.panel_values) == sorted(set(layout.panel_values))
    steps = np.diff(np.searchsorted(masses, layout.panel_values))
    assert steps.min() >= 1 and steps.max() - steps.min() <= 1  # evenly chosen
    assert layout.values.shape == (MAX_PANELS, 4, 3)
    # one colour scale over the panels shown, refused points left out
    shown = np.isin(grid3["mass"], layout.panel_values) & _ok(grid3)
    assert layout.limits == (grid3["energy"][shown].min(), grid3["energy"][shown].max())
    assert layout.missing == int(np.sum(np.isin(grid3["mass"], layout.panel_values) & ~_ok(grid3)))


def test_layout_3d_categorical_counts_the_panels_shown(grid3):
    layout = _layout(grid3, ["mass", "theta0", "spin"], "motion_class", True)
    shown = np.isin(grid3["mass"], layout.panel_values)
    categories, missing = _expected_categories(grid3["motion_class"][shown].tolist(), _ok(grid3)[shown])
    assert list(layout.categories) == categories and layout.missing == missing


def test_layout_3d_few_values_one_panel_each(grid3_small):
    table = grid3_small
    layout = _layout(table, ["mass", "theta0", "spin"], "energy", True)
    assert layout.panels == 5 and layout.panel_values == tuple(np.unique(table["mass"]))


def test_layout_random(random3):
    layout = _layout(random3, ["theta0", "spin", "mass"], "period", False)
    ok = _ok(random3) & np.isfinite(random3["period"])
    assert layout.panels == 1 and layout.panel_values == ()
    assert layout.limits == (random3["period"][ok].min(), random3["period"][ok].max())
    assert layout.missing == int(np.sum(~ok)) == 12
    categories, missing = _expected_categories(random3["motion_class"].tolist(), _ok(random3))
    assert list(_layout(random3, ["theta0", "spin"], "motion_class", False).categories) == categories


def test_layout_one_axis_random_is_sorted(random3):
    layout = _layout(random3, ["spin"], "period", False)
    order = np.argsort(random3["spin"], kind="stable")
    assert np.all(np.diff(layout.coords[0]) >= 0)
    np.testing.assert_array_equal(layout.values, np.where(_ok(random3), random3["period"], np.nan)[order])


def test_layout_without_status_counts_every_point(grid2):
    table = {k: v for k, v in grid2.items() if k != "status"}
    assert _layout(table, ["theta0", "spin"], "nutation", True).missing == 1


# --- the files ----------------------------------------------------------------------------------


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


CASES = [
    ("grid2", ["theta0", "spin"], "nutation", True),
    ("grid2", ["theta0", "spin"], "motion_class", True),
    ("grid2", ["spin"], "nutation", False),
    ("grid2", ["theta0"], "motion_class", False),
    ("grid3_small", ["mass", "theta0", "spin"], "energy", True),
    ("grid3_small", ["mass", "theta0", "spin"], "motion_class", True),
    ("random3", ["theta0", "spin", "mass"], "period", False),
    ("random3", ["theta0", "spin"], "motion_class", False),
]


@pytest.mark.parametrize("fixture, axes, quantity, grid", CASES,
                         ids=[f"{f}-{len(a)}-{q}" for f, a, q, _ in CASES])
def test_plot_map_writes_a_png(request, tmp_path, fixture, axes, quantity, grid):
    pytest.importorskip("matplotlib")
    table = request.getfixturevalue(fixture)
    path = tmp_path / "map.png"
    assert plot_map(table, axes, quantity, path, grid=grid, units={"theta0": "rad", "spin": "rad/s"}) is None
    width, height = _png_size(path)
    assert 300 <= width <= 3000 and 150 <= height <= 2500
    assert path.stat().st_size > 5000
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left


@pytest.mark.parametrize("suffix, head", [(".pdf", b"%PDF"), (".svg", b"<?xml"), (".PNG", b"\x89PNG")])
def test_plot_map_format_from_suffix(tmp_path, grid2, suffix, head):
    pytest.importorskip("matplotlib")
    path = tmp_path / f"map{suffix}"
    plot_map(grid2, ["theta0", "spin"], "motion_class", path, title="classes")
    assert path.read_bytes().startswith(head)


def test_labels_units_and_title_in_the_picture(tmp_path, grid3):
    """The one 12-panel figure drawn: the first and last panels are the ends of the first axis."""
    pytest.importorskip("matplotlib")
    path = tmp_path / "map.svg"
    plot_map(grid3, ["mass", "theta0", "spin"], "energy", path, units={"mass": "kg", "energy": "J"})
    svg = path.read_text(encoding="utf-8")
    # text is drawn as glyphs; the SVG keeps each string in a comment
    for text in ("energy over mass × theta0 × spin", "energy [J]", "mass = 0 kg", "mass = 1.9 kg", "theta0"):
        assert f"<!-- {text} -->" in svg, text


def test_missing_points_named_in_the_legend(tmp_path, grid2):
    pytest.importorskip("matplotlib")
    path = tmp_path / "map.svg"
    plot_map(grid2, ["theta0", "spin"], "motion_class", path)
    svg = path.read_text(encoding="utf-8")
    assert "<!-- refused / n/a -->" in svg and all(f"<!-- {c} -->" in svg for c in CLASSES[:3])
    assert "<!-- uniform precession -->" not in svg  # only the categories present


# --- refusals -----------------------------------------------------------------------------------


def test_unknown_quantity(tmp_path, grid2):
    with pytest.raises(InvalidInputError, match=r"unknown quantity 'energy'.*one of nutation, motion_class"):
        plot_map(grid2, ["theta0", "spin"], "energy", tmp_path / "map.png")


def test_unknown_axis(tmp_path, grid2):
    with pytest.raises(InvalidInputError, match=r"unknown axis 'mass'.*one of theta0, spin, nutation"):
        plot_map(grid2, ["mass", "spin"], "nutation", tmp_path / "map.png")


def test_quantity_that_is_an_axis(tmp_path, grid2):
    with pytest.raises(InvalidInputError, match=r"an axis, not a quantity 'spin'"):
        _layout(grid2, ["theta0", "spin"], "spin", True)


def test_four_axes(tmp_path, grid2):
    table = dict(grid2, mass=grid2["spin"], g=grid2["spin"])
    with pytest.raises(InvalidInputError, match=r"expected 1 to 3 axes, got 4 \(theta0, spin, mass, g\)"):
        plot_map(table, ["theta0", "spin", "mass", "g"], "nutation", tmp_path / "map.png")


def test_bad_suffix(tmp_path, grid2):
    pytest.importorskip("matplotlib")
    with pytest.raises(InvalidInputError, match=r"expected a suffix \.png, \.pdf, \.svg, got '\.jpg'"):
        plot_map(grid2, ["theta0", "spin"], "nutation", tmp_path / "map.jpg")
    assert list(tmp_path.iterdir()) == []


def test_not_a_grid(tmp_path, grid2, random3):
    shuffled = {k: v[::-1] for k, v in grid2.items()}
    with pytest.raises(InvalidInputError, match=r"expected the rows in C order over theta0, spin.*grid=False"):
        _layout(shuffled, ["theta0", "spin"], "nutation", True)
    with pytest.raises(InvalidInputError, match=r"expected a full grid, 150 theta0 × 150 spin = 22500 rows, got 150"):
        _layout(random3, ["theta0", "spin"], "period", True)


def test_bad_columns(grid2):
    with pytest.raises(InvalidInputError, match=r"one entry per row \(30\), got shape \(29,\)"):
        _layout(dict(grid2, nutation=grid2["nutation"][:-1]), ["theta0", "spin"], "nutation", True)
    with pytest.raises(InvalidInputError, match=r"names mixed with 3"):
        _layout(dict(grid2, motion_class=np.array(["a", 3] * 15, dtype=object)), ["theta0", "spin"],
                "motion_class", True)
    with pytest.raises(InvalidInputError, match=r"axis 'spin' to hold finite real numbers"):
        _layout(dict(grid2, spin=np.where(grid2["spin"] > 10, np.nan, grid2["spin"])), ["theta0", "spin"],
                "nutation", True)


def test_without_matplotlib(tmp_path, grid2, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib now raises ImportError
    with pytest.raises(InvalidInputError, match=r"pip install 'mechderive\[plot\]'"):
        plot_map(grid2, ["theta0", "spin"], "nutation", tmp_path / "map.png")


def test_every_refusal_is_a_mechderive_error(tmp_path, grid2):
    for args in ((grid2, "theta0", "nutation"), ([1, 2], ["theta0"], "nutation"), (grid2, [], "nutation")):
        with pytest.raises(MechDeriveError):
            plot_map(*args, tmp_path / "map.png")
    with pytest.raises(MechDeriveError, match="units"):
        plot_map(grid2, ["theta0", "spin"], "nutation", tmp_path / "map.png", units={"spin": 3})
