"""The free top's per-motion quantities (issue 14 §1; section 3.4-3.5 of the chapter).

References: SciPy's DOP853 at rtol 1e-13 on Euler's equations (3.33) written out here, with events at
the zeros of ω along the intermediate axis (the flips) and of ω's return (the polhode period); the
chapter's (3.36), (3.44) and (3.60) written by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import load_scene

NAMES = '["polhode_period", "period", "flip_interval", "precession_rate", "stability", "energy", "angular_momentum"]'


def _scene(moments, omega, method="exact", t_end=60.0):
    I1, I2, I3 = moments
    return load_scene(f"""system = "free_top"
method = "{method}"
rtol = 1e-10
[parameters]
I1 = {I1}
I2 = {I2}
I3 = {I3}
[initial]
omega = {list(omega)}
[time]
t_end = {t_end}
samples = 2001
[output]
quantities = ["omega2"]
summary = {NAMES}
""")


def _flips(moments, omega, t_end):
    """Times where ω2 (the intermediate axis here) changes sign, by DOP853 of (3.33) with events."""
    I = np.array(moments, dtype=float)

    def rhs(_, w):
        return np.cross(I * w, w) / I

    def zero(_, w):
        return w[1]

    sol = solve_ivp(rhs, (0.0, t_end), omega, method="DOP853", rtol=1e-13, atol=1e-15, events=zero)
    return sol.t_events[0]


@pytest.mark.parametrize("method", ["exact", "integrate"])
def test_tennis_racket_flip_interval_and_polhode_period(method):
    moments, omega = (1.0, 2.0, 3.0), (1e-3, 1.0, 1e-3)
    result = run_scene(_scene(moments, omega, method))
    s, e = result.report["summary"], result.report["summary_error"]
    flips = _flips(moments, omega, 60.0)
    assert len(flips) >= 2
    measured = float(np.mean(np.diff(flips)))
    # DOP853 at rtol 1e-13 locates each flip to ~1e-11 s over 60 s: the flip interval agrees to 1e-9 relative
    assert s["flip_interval"] == pytest.approx(measured, rel=1e-9)
    assert s["polhode_period"] == pytest.approx(2 * measured, rel=1e-9) and s["period"] == s["polhode_period"]
    assert 0 < e["polhode_period"] < 1e-9 * s["polhode_period"]
    T, L = 0.5 * sum(i * w * w for i, w in zip(moments, omega)), math.sqrt(sum((i * w) ** 2 for i, w in
                                                                               zip(moments, omega)))
    assert s["energy"] == pytest.approx(T, rel=1e-15) and s["angular_momentum"] == pytest.approx(L, rel=1e-15)
    # the estimates of the invariants are their variation along the run: the integrator's, not zero
    assert e["energy"] <= 1e-9 * T


def test_stability_of_each_axis_is_3_44_and_3_45():
    moments, omega = (1.0, 2.0, 3.0), (0.0, 0.0, 2.0)
    s = run_scene(_scene(moments, omega)).report["summary"]["stability"]
    Omega = 2.0
    for axis, (a, b, c) in {1: (1.0, 2.0, 3.0), 2: (2.0, 3.0, 1.0), 3: (3.0, 1.0, 2.0)}.items():
        A = Omega ** 2 / c * (c - a) * (a - b)  # (3.44) for a spin about the axis of moment a
        rate = math.sqrt(abs(A) / b)
        kind = "unstable" if A > 0 else "stable"  # (3.45): unstable iff the intermediate axis
        assert s[f"axis{axis}"]["kind"] == kind
        key = "growth_rate" if kind == "unstable" else "frequency"
        assert s[f"axis{axis}"][key] == pytest.approx(rate, rel=1e-14)
    assert s["axis2"]["kind"] == "unstable"


def test_symmetric_top_precession_rates_3_36_and_3_60():
    moments, omega = (1.0, 1.0, 2.0), (0.3, 0.2, 1.0)
    result = run_scene(_scene(moments, omega, t_end=20.0))
    s, e = result.report["summary"], result.report["summary_error"]
    I1, I3, w3 = 1.0, 2.0, 1.0
    Omega = w3 * (I1 - I3) / I1  # (3.36)
    L = math.sqrt(0.3 ** 2 + 0.2 ** 2 + (I3 * w3) ** 2)
    cos_theta = I3 * w3 / L
    phi_dot = I3 * w3 / (I1 * cos_theta)  # (3.60)
    rate = s["precession_rate"]
    assert rate["axis"] == 3
    assert rate["body"] == pytest.approx(Omega, rel=1e-15) and rate["space"] == pytest.approx(phi_dot, rel=1e-15)
    assert e["precession_rate"] < 1e-14
    # independent: ω⊥ turns in the body at Ω, measured on the closed form's own columns would be circular; use
    # DOP853: the angle of (ω1, ω2) after 20 s
    I = np.array(moments)
    sol = solve_ivp(lambda _, w: np.cross(I * w, w) / I, (0, 20.0), omega, method="DOP853", rtol=1e-12,
                    atol=1e-14, dense_output=True)
    t = np.linspace(0, 20.0, 401)
    w = sol.sol(t)
    angle = np.unwrap(np.arctan2(w[1], w[0]))
    assert (angle[-1] - angle[0]) / 20.0 == pytest.approx(-Omega, rel=1e-9)  # (ω1, ω2) = ω0(sin Ωt, cos Ωt)
    assert s["flip_interval"] is None and "no intermediate axis" in e["flip_interval"]


def test_steady_rotation_has_no_polhode_period():
    result = run_scene(_scene((1.0, 2.0, 3.0), (0.0, 0.0, 1.0), t_end=5.0))
    s, e = result.report["summary"], result.report["summary_error"]
    assert s["polhode_period"] is None and "steady" in e["polhode_period"]


def test_samples_per_period_uses_the_polhode_period():
    scene = _scene((1.0, 2.0, 3.0), (1e-3, 1.0, 1e-3))
    P = run_scene(scene).report["summary"]["polhode_period"]
    text = f"""system = "free_top"
[parameters]
I1 = 1.0
I2 = 2.0
I3 = 3.0
[initial]
omega = [1e-3, 1.0, 1e-3]
[time]
t_end = 60.0
samples_per_period = 50
[output]
quantities = ["omega2"]
"""
    assert load_scene(text).samples == math.ceil(60.0 / P * 50) + 1
