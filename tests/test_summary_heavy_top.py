"""The heavy top's per-motion quantities (issue 14 §1) against independent references.

* the roots of the cubic f(u) (3.73), written out here by hand, by mpmath.polyroots at 30 digits;
* the nutation period 2∫ du/√f and the advance Δφ = 2∫ φ̇(u)/√f du (φ̇ = (b − a u)/(1 − u²), (3.74))
  by mpmath.quad (with u = u1 + (u2 − u1) sin²x, which takes the 1/√ end-point singularities away);
* θ's extremes, the period and Δφ by solve_ivp DOP853 (rtol 1e-12) of the reduced equation of θ
  written here by hand, with events at θ̇ = 0;
* the uniform precession's rates (3.80) and the sleeping top's threshold (3.83) by hand;
* figure 44's three classes, a sleeping top (minimum_spin applies) and a top that is not.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mechderive.scenes.schema import load_scene
from mechderive.systems.heavy_top import summary as heavy_summary

I1, I3, MGL = 1.0, 0.5, 1.0  # the chapter's examples' top: M = 0.1, g = 10, l = 1


def _scene(theta: float, phi_dot: float, psi_dot: float, theta_dot: float = 0.0, *, method: str = "auto",
           t_end: float = 4.0, samples: int = 5) -> str:
    return f"""system = "heavy_top"
method = "{method}"
[parameters]
I1 = {I1!r}
I3 = {I3!r}
M = 0.1
g = 10.0
l = 1.0
[initial]
theta = {theta!r}
phi = 0.0
psi = 0.0
theta_dot = {theta_dot!r}
phi_dot = {phi_dot!r}
psi_dot = {psi_dot!r}
[time]
t_end = {t_end!r}
samples = {samples}
[output]
quantities = ["theta"]
"""


def _summary(text: str, method: str = "exact") -> dict:
    scene = load_scene(text)
    model = scene.model
    t = scene.times()
    solved = model.solve(scene, method, t)
    return model.summarize(scene, solved, t, model.summary_names())


# (θ0, φ̇0, ψ̇0): figure 44's three classes, each let go at its upper turning point θ0 = 0.5
CLASSES = {"monotonic precession": (0.5, 0.2, 5.0), "looping": (0.5, -0.5, 5.0), "cusps": (0.5, 0.0, 5.0)}


def _reference(theta0: float, phi_dot0: float, psi_dot0: float, theta_dot0: float = 0.0) -> dict:
    """At 30 digits, by hand from (3.63)-(3.74): roots, period, Δφ per period, E, p_φ, p_ψ."""
    with mpmath.workdps(30):
        mp = mpmath.mpf
        th, thd, phd, psd = mp(theta0), mp(theta_dot0), mp(phi_dot0), mp(psi_dot0)
        mgl = mp(0.1) * 10 * 1  # the scene's M g l: the double 0.1 is 0.1 + 5.6e-18, so M g l = 1 + 5.6e-17
        w3 = psd + phd * mpmath.cos(th)
        p_psi = I3 * w3
        p_phi = I1 * mpmath.sin(th) ** 2 * phd + I3 * w3 * mpmath.cos(th)
        E = (I1 * (thd**2 + phd**2 * mpmath.sin(th) ** 2) + I3 * w3**2) / 2 + mgl * mpmath.cos(th)
        a, b = p_psi / I1, p_phi / I1
        alpha, beta = 2 * (E - I3 * w3**2 / 2) / I1, 2 * mgl / I1
        # f(u) = (1 − u²)(α − βu) − (b − au)² = βu³ − (α + a²)u² + (2ab − β)u + α − b²   (3.73)
        roots = sorted(mpmath.re(r) for r in mpmath.polyroots([beta, -(alpha + a * a), 2 * a * b - beta,
                                                               alpha - b * b], maxsteps=200, extraprec=200))
        u1, u2, u3 = roots

        def u_of(x):
            return u1 + (u2 - u1) * mpmath.sin(x) ** 2

        # du/√f = 2 dx/√(β(u3 − u)) with f = β(u − u1)(u − u2)(u − u3)
        period = 2 * mpmath.quad(lambda x: 2 / mpmath.sqrt(beta * (u3 - u_of(x))), [0, mpmath.pi / 2])
        advance = 2 * mpmath.quad(lambda x: 2 * (b - a * u_of(x)) / (1 - u_of(x) ** 2)
                                  / mpmath.sqrt(beta * (u3 - u_of(x))), [0, mpmath.pi / 2])
        return dict(u1=u1, u2=u2, u3=u3, nutation_period=period, precession_per_nutation=advance,
                    mean_precession_rate=advance / period, theta_min=mpmath.acos(u2), theta_max=mpmath.acos(u1),
                    energy=E, p_phi=p_phi, p_psi=p_psi)


def _integrated(theta0: float, phi_dot0: float, psi_dot0: float) -> dict:
    """θ's extremes, the period and Δφ from DOP853 of I1 θ̈ = I1 φ̇² sin θ cos θ − I3 ω3 φ̇ sin θ + M g l sin θ,
    φ̇ = (b − a cos θ)/sin²θ (3.67), from θ's two first maxima (θ̇ = 0 going down)."""
    w3 = psi_dot0 + phi_dot0 * math.cos(theta0)
    a = I3 * w3 / I1
    b = (I1 * math.sin(theta0) ** 2 * phi_dot0 + I3 * w3 * math.cos(theta0)) / I1

    def rhs(t, y):
        th, thd, _ = y
        phd = (b - a * math.cos(th)) / math.sin(th) ** 2
        return [thd, phd**2 * math.sin(th) * math.cos(th) - I3 * w3 * phd * math.sin(th) / I1
                + MGL * math.sin(th) / I1, phd]

    def top(t, y):
        return y[1]
    top.direction = -1.0  # θ̇ from + to −: θ's maximum

    def bottom(t, y):
        return y[1]
    bottom.direction = 1.0

    sol = solve_ivp(rhs, (0.0, 8.0), [theta0, 0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    events=(top, bottom))
    (t_top, y_top), (t_bottom, y_bottom) = (sol.t_events[0], sol.y_events[0]), (sol.t_events[1], sol.y_events[1])
    # let go at a turning point: the next maxima of θ are the period apart
    return dict(theta_max=float(y_top[0, 0]), theta_min=float(y_bottom[0, 0]),
                nutation_period=float(t_top[1] - t_top[0]),
                precession_per_nutation=float(y_top[1, 2] - y_top[0, 2]))


@pytest.mark.parametrize("kind", sorted(CLASSES))
def test_against_mpmath_and_integration(kind):
    state = CLASSES[kind]
    got = _summary(_scene(*state))
    ref = _reference(*state)
    assert got["motion_class"] == (kind, None)
    for name in ("u1", "u2", "u3", "nutation_period", "precession_per_nutation", "mean_precession_rate",
                 "theta_min", "theta_max", "energy", "p_phi", "p_psi"):
        value, estimate = got[name]
        # the estimate is measured (never 0 where rounding happened); the 30-digit reference adds ~1e-29
        assert abs(value - float(ref[name])) <= estimate + 1e-28 * (1 + abs(float(ref[name]))), (name, value, estimate)
        assert estimate < 1e-15 * (1 + abs(value)), (name, estimate)  # and it is no wider than the double's rounding
    assert got["period"] == got["nutation_period"]
    assert got["theta_min"][0] == 0.5  # let go at the upper turning point
    assert got["steady"][0] == {"kind": "none"}
    assert got["minimum_spin"][0] is None and "sleeping top" in got["minimum_spin"][1]
    # the integration: DOP853 at rtol 1e-12 over ~2 periods, events located to ~1e-12: 1e-9 is ample
    num = _integrated(*state)
    for name in ("theta_max", "theta_min", "nutation_period", "precession_per_nutation"):
        assert got[name][0] == pytest.approx(num[name], abs=1e-9), name


def test_classes_at_the_turning_points():
    """Figure 44 by the sign of φ̇ = (b − a u)/(1 − u²) (3.74) at u1 and u2, computed here from the roots."""
    for kind, state in CLASSES.items():
        got = _summary(_scene(*state))
        u1, u2 = got["u1"][0], got["u2"][0]
        w3 = state[2] + state[1] * math.cos(state[0])
        a = I3 * w3 / I1
        b = (I1 * math.sin(state[0]) ** 2 * state[1] + I3 * w3 * math.cos(state[0])) / I1
        g1, g2 = b - a * u1, b - a * u2
        expect = "cusps" if min(abs(g1), abs(g2)) < 1e-12 else "looping" if g1 * g2 < 0 else "monotonic precession"
        assert got["motion_class"][0] == expect == kind


def test_uniform_precession_rates_3_80():
    """Let go with the slow precession of (3.80) at θ0 = 0.5, ω3 = 10: steady, its rates by hand."""
    theta0, w3 = 0.5, 10.0
    c = I1 * math.cos(theta0)
    disc = math.sqrt((I3 * w3) ** 2 - 4 * c * MGL)  # real: ω3 > (2/I3)√(M g l I1 cos θ0) (3.81) = 3.75
    slow, fast = (I3 * w3 - disc) / (2 * c), (I3 * w3 + disc) / (2 * c)
    got = _summary(_scene(theta0, slow, w3 - slow * math.cos(theta0)))
    steady, err = got["steady"]
    assert steady["kind"] == "uniform precession" and steady["branch"] == "slow"
    assert got["motion_class"][0] == "uniform precession"
    # the hand formula for slow cancels (I3 ω3 − √D): ~1e-15 relative; the summary's measured estimate below 1e-14
    assert steady["slow_precession"] == pytest.approx(slow, rel=1e-14)
    assert steady["fast_precession"] == pytest.approx(fast, rel=1e-14)
    assert steady["omega3"] == pytest.approx(w3, rel=1e-15)
    assert 0 < err < 1e-14
    # φ̇ constant: its mean is itself; θ stays at 0.5 to the nutation the doubles leave (~1e-15)
    assert got["mean_precession_rate"][0] == pytest.approx(slow, rel=1e-12)
    assert got["theta_max"][0] - got["theta_min"][0] < 1e-12


def test_sleeping_top_minimum_spin_3_83():
    """θ = θ̇ = 0: minimum_spin = 2√(I1 M g l)/I3 = 4 rad/s (3.83); stable above it, not below."""
    by_hand = 2 * math.sqrt(I1 * MGL) / I3
    for w3, stable in ((6.0, True), (3.0, False)):
        got = _summary(_scene(0.0, 0.0, w3))
        value, err = got["minimum_spin"]
        assert value == pytest.approx(by_hand, rel=1e-15) and err <= 1e-15 * by_hand
        steady = got["steady"][0]
        assert steady["kind"] == "sleeping" and steady["stable"] is stable and steady["omega3"] == w3
        assert got["theta_min"] == (0.0, 0.0) and got["theta_max"] == (0.0, 0.0)
        assert got["nutation_period"][0] is None and isinstance(got["nutation_period"][1], str)
        assert got["precession_per_nutation"][0] is None
        # (3.83): f(u) = (1 − u)²(α(1 + u) − a²), the other root a²/α − 1 (α = β here: E' = M g l)
        other = (I3 * w3 / I1) ** 2 / (2 * MGL / I1) - 1
        roots = sorted([1.0, 1.0, other])
        for k, name in enumerate(("u1", "u2", "u3")):
            assert abs(got[name][0] - roots[k]) <= got[name][1] + 1e-15, name
    # a top that is not sleeping: minimum_spin does not apply
    value, reason = _summary(_scene(1e-3, 0.0, 6.0))["minimum_spin"]
    assert value is None and "sleeping top" in reason


def test_integrated_scene_uses_the_closed_form_and_the_period():
    state = CLASSES["cusps"]
    exact = _summary(_scene(*state))
    integrated = _summary(_scene(*state, method="integrate", t_end=0.5, samples=3), method="integrate")
    for name in ("nutation_period", "theta_max", "u1", "precession_per_nutation"):
        assert integrated[name] == exact[name]
    scene = load_scene(_scene(*state))
    assert scene.model.period(scene) == exact["nutation_period"][0]
    assert scene.model.period(load_scene(_scene(0.0, 0.0, 6.0))) is None  # sleeping: steady


def test_measured_on_the_trajectory(monkeypatch):
    """Where the closed form cannot follow a motion, θ's extremes and the period are measured on the samples."""
    state = CLASSES["monotonic precession"]
    exact = _summary(_scene(*state))
    monkeypatch.setattr(heavy_summary, "_closed_form", lambda scene, solved: (None, "out of reach (forced)"))
    got = _summary(_scene(*state, method="integrate", t_end=8.0, samples=801), method="integrate")
    for name in ("theta_max", "nutation_period"):
        value, err = got[name]
        # parabolic refinement at 0.01 s steps: error ~ h³ θ''' ~ 1e-6; the estimate must cover the true error
        assert abs(value - exact[name][0]) <= err + 1e-9 and err < 1e-4, (name, value, err)
    assert got["u1"][0] is None and "forced" in got["u1"][1]
    assert got["energy"][0] == pytest.approx(exact["energy"][0], rel=1e-9)
