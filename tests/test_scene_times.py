"""``[time]``'s output times (issue 14 §3): ``t_start``, an explicit ``times`` list, ``samples_per_period``.

The references are independent runs: the same motion sampled on the plain grid [0, t_end] (the closed
form is a function of t alone, so the values at the same times must agree to rounding), and the period
computed by 30-digit mpmath quadrature of the heavy top's nutation, 2∫du/√f(u) between the turning
points, written out here from (3.73).
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from mechderive.cli import main
from mechderive.errors import InvalidInputError
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import load_scene, scene_to_toml

TOP = """system = "heavy_top"
method = "{method}"
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
{time}
[output]
quantities = ["theta", "phi"]
"""


def _run(time: str, method: str = "exact"):
    return run_scene(load_scene(TOP.format(time=time, method=method)))


@pytest.fixture(scope="session")
def plain():
    return _run("t_end = 10.0\nsamples = 1001")


@pytest.mark.parametrize("method, tol", [("exact", 1e-15),  # the same closed form; linspace(5, 10) and linspace(0, 10)
                                         # differ by an ulp of t (2e-15 × rates ≤ 0.2 rad/s) plus rounding
                                         ("integrate", 1e-9)])  # two runs, each within rtol 1e-10 (estimate)
def test_t_start_gives_the_tail_of_the_plain_run(plain, method, tol):
    tail = _run("t_start = 5.0\nt_end = 10.0\nsamples = 501", method)
    assert tail.t[0] == 5.0 and tail.t[-1] == 10.0 and len(tail.t) == 501
    np.testing.assert_allclose(tail.t, plain.t[500:], rtol=0, atol=4e-15)  # an ulp or two of t ~ 10
    for q in ("theta", "phi"):  # the launch stays at t = 0: the tail is the same motion, not a relaunch
        assert np.max(np.abs(tail.columns[q] - plain.columns[q][500:])) < tol


def test_explicit_times(plain):
    times = [0.5, 1.25, 7.0, 9.99]
    run = _run(f"times = {times}")
    assert list(run.t) == times
    at = [int(round(x * 100)) for x in times]  # the plain grid's samples at those times (0.01 s apart)
    assert np.max(np.abs(run.columns["theta"] - plain.columns["theta"][at])) < 4e-16


def test_samples_per_period_from_the_nutation_period():
    scene = load_scene(TOP.format(time="t_end = 10.0\nsamples_per_period = 20", method="exact"))
    # the period by 30-digit quadrature: f(u) = (α - βu)(1 - u²) - (b - au)² of (3.73)
    mpmath.mp.dps = 30
    I1, I3, Mgl, th, w3 = 1, mpmath.mpf("0.5"), mpmath.mpf(1) * mpmath.mpf("9.81") * mpmath.mpf("0.1"), \
        mpmath.mpf("0.5"), mpmath.mpf(20)
    u0 = mpmath.cos(th)
    a, b = I3 * w3 / I1, I3 * w3 * u0 / I1
    beta = 2 * Mgl / I1
    alpha = beta * u0
    f = lambda u: (alpha - beta * u) * (1 - u * u) - (b - a * u) ** 2  # noqa: E731
    roots = sorted(mpmath.re(r) for r in mpmath.polyroots([beta, -alpha - a * a, 2 * a * b - beta, alpha - b * b]))
    u1, u2 = roots[0], roots[1]
    period = 2 * mpmath.quad(lambda u: 1 / mpmath.sqrt(abs(f(u))), [u1, u2])  # abs: f ~ -1e-30 at the rounded roots
    assert scene.samples == math.ceil(10.0 / float(period) * 20) + 1
    assert load_scene(scene_to_toml(scene)) == scene
    assert "samples_per_period = 20" in scene_to_toml(scene)


@pytest.mark.parametrize("time, message", [
    ("times = [0.0, 1.0, 1.0]", r"\[time\].times\[2\]: expected times strictly increasing, got 1.0 after 1.0"),
    ("times = [-1.0, 1.0]", r"\[time\].times\[0\]: expected a finite number >= 0"),
    ("times = [1.0]", r"\[time\].times: expected a list of 2 to"),
    ("times = [0.0, 1.0]\nt_end = 3.0", r"expected either times or t_end"),
    ("t_start = 5.0\nt_end = 4.0\nsamples = 3", r"\[time\].t_end: expected a finite number > t_start \(5.0\)"),
    ("t_end = 4.0", r"\[time\].samples: missing; expected samples or samples_per_period"),
    ("t_end = 4.0\nsamples = 3\nsamples_per_period = 9", r"got both"),
    ("t_end = 1e6\nsamples_per_period = 100000", r"expected at most 10000000 samples in all"),
])
def test_bad_times_name_the_key(time, message):
    with pytest.raises(InvalidInputError, match=message):
        load_scene(TOP.format(time=time, method="exact"))


def test_a_system_that_cannot_know_its_period_or_take_any_times_says_so():
    steady = TOP.replace("phi_dot = 0.0", "phi_dot = 0.0").replace("theta = 0.5", "theta = 0.0")
    with pytest.raises(InvalidInputError, match=r"samples_per_period: system 'heavy_top' does not know the period"):
        load_scene(steady.format(time="t_end = 1.0\nsamples_per_period = 10", method="exact"))
    cat = 'system = "falling_cat"\n[time]\nt_start = 0.5\nt_end = 1\nsamples = 3\n[output]\nquantities = ["flip_angle"]'
    with pytest.raises(InvalidInputError, match=r"\[time\].t_start: system 'falling_cat' takes only t_end and samples"):
        load_scene(cat)


def test_cli_header_shows_the_output_interval(tmp_path, capsys):
    path = tmp_path / "tail.toml"
    path.write_text(TOP.format(time="t_start = 2.0\nt_end = 3.0\nsamples = 5", method="exact"))
    assert main(["run", str(path)]) == 0
    assert "5 samples on [2, 3] s" in capsys.readouterr().out
