"""§3.6 generalised (issue 16): each system the issue lists, solved by the closed form the toolkit finds from its
Lagrangian, against 30-digit motions of hand-written equations over more than 100 periods.

The references (``tests/reference/quadrature_cases.json``, made by ``make_quadrature_reference.py``): mpmath's
Taylor integrator at 36-50 digits on equations of motion written by hand (Newton for the spherical pendulum,
Euler–Lagrange worked on paper for the others), samples in the first period and at 100.3 T, 137.8 T, 1000.1 T and
2024.65 T by the period symmetry.  Every sample is compared with the closed form in doubles:

* within 1e-12 relative to max(1, |q|) — the issue's target (an unwrapped angle of 10⁴ rad keeps ~16 digits);
* within the closed form's own estimate (doubles against 30 digits of the same formulas, measured on these
  samples) plus two ulp of the value: the estimate is honest.

Kepler's ellipse and hyperbola and the precessing orbit have no elliptic closed form in t (u = 1/r gives a
sextic): their orbit r(φ) along φ is compared here at the reference's φ; their motion in t — the orbit with t(φ)
inverted (:mod:`mechderive.systems.lagrangian.timed`) — at the reference's t in ``test_s3_6_closed_form_in_time.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

REFERENCE = Path(__file__).parent / "reference" / "quadrature_cases.json"
CASES = json.loads(REFERENCE.read_text(encoding="utf-8"))["cases"]
ORBITS = {"kepler_ellipse", "kepler_hyperbola", "precessing_orbit"}
KINDS = {
    "spherical_generic": "oscillation between turning points",
    "spherical_moving_start": "oscillation between turning points",
    "spherical_conical": "oscillation between turning points",
    "spherical_through_pole": "libration through a fold",
    "spherical_near_pole": "oscillation between turning points",
    "top_default": "oscillation between turning points",
    "top_looping": "oscillation between turning points",
    "top_moving_start": "oscillation between turning points",
    "pendulum_libration": "libration through a fold",
    "pendulum_rotation": "rotation",
    "pendulum_near_separatrix_libration": "libration through a fold",
    "pendulum_near_separatrix_rotation": "rotation",
    "top_accelerating_pivot": "oscillation between turning points",
}


def _system(case):
    from mechderive.systems.lagrangian import from_lagrangian

    return from_lagrangian(case["lagrangian"], case["coordinates"], list(case["parameters"]))


@pytest.mark.parametrize("case", [c for c in CASES if c["name"] not in ORBITS], ids=lambda c: c["name"])
def test_closed_form_against_30_digit_integration_over_100_periods(case):
    from mechderive.systems.lagrangian.closed import closed_motion

    motion = closed_motion(_system(case), case["parameters"], case["initial"])
    assert motion.kind == KINDS[case["name"]]
    if case["period"] is not None and case["name"] != "spherical_conical":
        assert abs(float(motion.period) - float(case["period"])) <= 1e-14 * float(case["period"])
    t = np.array([float(s["t"]) for s in case["samples"]])
    assert t[-1] > 100 * float(case["period"]) or case["name"] == "spherical_conical"
    names = [*case["coordinates"], *(q + "_dot" for q in case["coordinates"])]
    got = motion.columns(t, names)
    estimate = motion.estimate(t, names)[1]
    for i, sample in enumerate(case["samples"]):
        for name in names:
            want = float({**sample["q"], **sample["q_dot"]}[name])
            diff = abs(got[name][i] - want)
            assert diff <= 1e-12 * max(1.0, abs(want)), (name, float(sample["t"]), diff)
            assert diff <= 4 * estimate[name] + 2 * np.spacing(abs(want)) + 1e-300, (name, diff, estimate[name])


@pytest.mark.parametrize("case", [c for c in CASES if c["name"] in ORBITS], ids=lambda c: c["name"])
def test_orbit_along_phi_against_30_digit_integration(case):
    from mechderive.systems.lagrangian.closed import closed_orbit

    orbit = closed_orbit(_system(case), "phi", case["parameters"], case["initial"])
    phi = np.array([float(s["q"]["phi"]) for s in case["samples"]]) - case["initial"]["phi"]
    r = orbit.columns(phi, ["r"])["r"]
    want = np.array([float(s["q"]["r"]) for s in case["samples"]])
    # r(φ) at the reference's φ: φ's own rounding (ulp of up to ~10⁴ rad) moves r by |dr/dφ|·ulp(φ)
    slope = np.abs(orbit.columns(phi, ["r_dot"])["r_dot"])
    assert np.all(np.abs(r - want) <= 1e-12 * np.maximum(1.0, want) + 4 * slope * np.spacing(np.abs(phi) + 1))
    if case["period"] is not None:
        advance = float(case["advance"]["phi"])
        assert abs(float(orbit.period) - advance) <= 1e-14 * advance


@pytest.mark.parametrize("case", [c for c in CASES if c["name"] not in ORBITS and c["advance"]
                                  and c["name"] != "spherical_conical"], ids=lambda c: c["name"])
def test_per_period_advances_against_the_references(case):
    """``<c>_per_period`` (complete Π, 40 digits) against the reference's advance over one period (its period
    found as a root at 36+ digits); a rotating pendulum's θ advances by 2π (the fold scale times π)."""
    from mechderive.systems.lagrangian.closed import closed_motion

    motion = closed_motion(_system(case), case["parameters"], case["initial"])
    for name, advance in case["advance"].items():
        got = (motion.shape.scale * np.pi * (1 if motion.qd0 > 0 else -1) if name == motion.remaining
               else motion.summary(f"{name}_per_period"))
        assert abs(got - float(advance)) <= 1e-13 * max(1.0, abs(float(advance))), (name, got, advance)


def test_accelerating_pivot_summaries_in_a_scene():
    """The period and advances of the top on the accelerating pivot, as a scene's summaries (L depends on t: the
    closed form of its gauge-free L), against the reference."""
    from mechderive.scenes.planner import run_scene
    from mechderive.scenes.schema import parse_scene

    case = next(c for c in CASES if c["name"] == "top_accelerating_pivot")
    names = ["period", "phi_per_period", "psi_per_period"]
    scene = parse_scene({"system": "lagrangian", "coordinates": case["coordinates"], "lagrangian": case["lagrangian"],
                         "parameters": case["parameters"], "initial": case["initial"], "rtol": 1e-10,
                         "time": {"t_end": 3.0, "samples": 301}, "output": {"quantities": ["theta"], "summary": names}})
    result = run_scene(scene)
    summary, errors = result.report["summary"], result.report["summary_error"]
    want = {"period": case["period"], "phi_per_period": case["advance"]["phi"],
            "psi_per_period": case["advance"]["psi"]}
    for name in names:
        assert abs(summary[name] - float(want[name])) <= max(4 * errors[name], 1e-14 * abs(float(want[name])))
