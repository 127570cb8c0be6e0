"""Per-motion quantities of every system (issue 14 §1): the period of a periodic motion, measured on the
solution (:mod:`mechderive.core.periodic`), and the invariants' values.

References: the simple pendulum's period 4K(k²)/ω0 with k = sin(θ0/2), by mpmath at 30 digits; the
heavy symmetric top's nutation period as 2∫du/√f(u) by mpmath quadrature of (3.73) written here; a
quasi-periodic sum of incommensurate cosines, which has no period.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from mechderive.core.periodic import measure_period
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import load_scene
from mechderive.systems import registry

PENDULUM = """system = "lagrangian"
coordinates = ["theta"]
lagrangian = "m*l**2*theta_dot**2/2 + m*g*l*cos(theta)"
rtol = 1e-11
[parameters]
m = 1.0
l = 1.0
g = 9.81
[initial]
theta = {theta0}
theta_dot = 0.0
[time]
t_end = 12.0
samples = 2401
[output]
quantities = ["theta"]
summary = ["period", "energy"]
"""


@pytest.mark.parametrize("theta0", [0.3, 2.5])
def test_pendulum_period_against_the_elliptic_integral(theta0):
    result = run_scene(load_scene(PENDULUM.format(theta0=theta0)))
    s, e = result.report["summary"], result.report["summary_error"]
    mpmath.mp.dps = 30
    exact = 4 * mpmath.ellipk(mpmath.sin(mpmath.mpf(theta0) / 2) ** 2) / mpmath.sqrt(mpmath.mpf("9.81"))
    # the measured period is right to its own estimate, and the estimate is small
    assert abs(s["period"] - float(exact)) <= e["period"]
    assert e["period"] < 1e-6 * float(exact)
    # the Jacobi integral h = T + V = -m g l cos θ0 at rest; its estimate is its variation along the run
    assert s["energy"] == pytest.approx(-9.81 * math.cos(theta0), rel=1e-15)
    assert 0 <= e["energy"] < 1e-9 * 9.81


def test_symmetric_rigid_body_period_is_the_nutation_period():
    text = registry.get("rigid_body").example_scene().replace("I1 = 2.0", "I1 = 3.0").replace(
        "center_of_mass = [0.1, 0.0, 0.5]", "center_of_mass = [0.0, 0.0, 0.5]").replace(
        "quantities = [", 'summary = ["period", "energy", "L_vertical", "p_psi"]\nquantities = [')
    result = run_scene(load_scene(text.replace('method = "auto"', 'method = "integrate"')))
    s, e = result.report["summary"], result.report["summary_error"]
    # (3.73) with I1 = 3, I3 = 4, M g l = 9.81·0.5, θ0 = 0.3, ω3 = 20 (about the pivot): 2∫du/√f
    mpmath.mp.dps = 30
    I1, I3, Mgl, w3 = 3, 4, mpmath.mpf("9.81") * mpmath.mpf("0.5"), 20
    u0 = mpmath.cos(mpmath.mpf("0.3"))
    a, b, beta = I3 * w3 / mpmath.mpf(I1), I3 * w3 * u0 / I1, 2 * Mgl / I1
    alpha = beta * u0
    roots = sorted(mpmath.re(r) for r in mpmath.polyroots([beta, -alpha - a * a, 2 * a * b - beta, alpha - b * b]))
    f = lambda u: (alpha - beta * u) * (1 - u * u) - (b - a * u) ** 2  # noqa: E731
    period = float(2 * mpmath.quad(lambda u: 1 / mpmath.sqrt(abs(f(u))), [roots[0], roots[1]]))
    assert abs(s["period"] - period) <= e["period"] < 1e-5 * period
    assert s["p_psi"] == 80.0 and e["p_psi"] < 1e-9 * 80  # I3 ω3, conserved: symmetric, c on the axis


def test_asymmetric_heavy_body_is_not_periodic_and_says_so():
    text = registry.get("rigid_body").example_scene().replace(
        "quantities = [", 'summary = ["period", "p_psi"]\nquantities = [')
    result = run_scene(load_scene(text))
    s, e = result.report["summary"], result.report["summary_error"]
    assert s["period"] is None and "not periodic" in e["period"]
    assert s["p_psi"] is None and "not conserved" in e["p_psi"]


def test_measure_period_refuses_quasi_periodic_and_short_runs():
    t = np.linspace(0.0, 40.0, 4001)
    quasi = np.stack([np.cos(t), np.cos(math.sqrt(2) * t)], axis=1)
    assert measure_period(t, quasi).period is None
    short = np.linspace(0.0, 1.0, 101)
    found = measure_period(short, np.cos(short)[:, None])
    assert found.period is None and "fewer than one whole period" in found.reason
    periodic = measure_period(t, np.stack([np.cos(t) + 0.3 * np.cos(2 * t), -np.sin(t)], axis=1))
    assert abs(periodic.period - 2 * math.pi) <= periodic.estimate < 1e-9


def test_batched_crossings_and_states_equal_the_one_by_one_polynomials(rng):
    # the batched path (one Vandermonde solve, Newton from the linear crossing; Lagrange weights for all
    # times at once) against the per-crossing reference: NumPy's polyfit + every root of the polynomial,
    # and the Lagrange form written out term by term.  Both interpolate the same samples, so they agree to
    # rounding: 1e-12 of the interval (the quintic's coefficients are solved from six samples).
    from mechderive.core.periodic import _crossing, _crossings, _states_at

    t = np.sort(rng.uniform(0.0, 30.0, 1500))
    x = np.cos(1.7 * t + 0.3) + 0.4 * np.cos(3.1 * t) + 0.05 * np.sin(11.0 * t)
    level = 0.1
    up = np.nonzero((x[:-1] < level) & (x[1:] >= level))[0]
    up = up[(up >= 2) & (up <= len(t) - 4)]
    assert len(up) >= 5
    for points in (4, 6):
        want = np.array([_crossing(t, x, int(k), level, points) for k in up])
        got = _crossings(t, x, up, level, points)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.max(np.diff(t)[up]))
        y = np.stack([x, np.sin(t)], axis=1)
        when = got
        states = _states_at(t, y, when, points)
        for w, s in zip(when, states):
            k = int(np.clip(np.searchsorted(t, w) - 1, 0, len(t) - 2))
            lo = min(max(k - (points - 2) // 2, 0), len(t) - points)
            ts = t[lo:lo + points]
            weights = [np.prod([(w - ts[j]) / (ts[i] - ts[j]) for j in range(points) if j != i]) for i in range(points)]
            np.testing.assert_allclose(s, np.array(weights) @ y[lo:lo + points], rtol=0, atol=1e-12)
