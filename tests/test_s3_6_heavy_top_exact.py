"""Section 3.6: the heavy top's closed-form motion against 30-digit mpmath integrations.

Reference data: tests/reference/heavy_top_cases.json, from the seeded script
tests/reference/make_heavy_top_reference.py — mpmath's Taylor ODE solver at 30 digits on
the Newton–Euler equations (body ω and R, written by hand there, independent of the
toolkit's Lagrangian), angles read off R; long times by the nutation periodicity.

Accuracy target (issue "The heavy symmetric top"): θ, φ, ψ within 1e-12 rad over 100
nutation periods for each motion class and a hanging top.
"""

from __future__ import annotations

import json
from pathlib import Path

import mpmath
import numpy as np
import pytest

from mechderive.errors import InvalidInputError, UnphysicalInertiaError
from mechderive.systems.heavy_top.exact import classify, exact_heavy_top

DATA = json.loads((Path(__file__).parent / "reference" / "heavy_top_cases.json").read_text())
CASES = {c["name"]: c for c in DATA["cases"]}
BASELINE = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)

# 1e-12 rad: the target.  Constants carry 40 digits and the phase is reduced in
# double-double, so the error is the elliptic functions' few ulp times O(1) coefficients
# (measured ≤ 3e-13 at 100 periods, where the continuous ψ ≈ 2000 rad has ulp 2.3e-13).
TOL = 1e-12


def _wrap(x):
    return (np.asarray(x) + np.pi) % (2 * np.pi) - np.pi


def _wrapped_reference(text: str) -> float:
    """The 30-digit reference angle reduced to (-π, π] *before* rounding to a float."""
    with mpmath.workdps(40):
        x = mpmath.mpf(text)
        return float(x - 2 * mpmath.pi * mpmath.nint(x / (2 * mpmath.pi)))


@pytest.mark.parametrize("name", list(CASES))
def test_closed_form_matches_30_digit_integration(name):
    case = CASES[name]
    top = exact_heavy_top(case["parameters"], case["initial"])
    for p in case["points"]:
        t = np.array([p["t"]])
        ref = {k: float(p[k]) for k in ("theta", "phi", "psi")}
        assert abs(top.theta(t)[0] - ref["theta"]) < TOL, (name, p["t"], "theta")
        periods = p["t"] / top.nutation_period if np.isfinite(top.nutation_period) else 0
        if periods <= 101:
            # continuous angles, as floats: within the target up to 100 periods
            assert abs(top.phi(t)[0] - ref["phi"]) < TOL, (name, p["t"], "phi")
            assert abs(top.psi(t)[0] - ref["psi"]) < TOL, (name, p["t"], "psi")
        # reduced angles keep the accuracy at any time (10⁴ periods here)
        for k, f in (("phi", top.phi), ("psi", top.psi)):
            assert abs(_wrap(f(t, wrapped=True)[0] - _wrapped_reference(p[k]))) < TOL, (name, p["t"], k, "wrapped")


@pytest.mark.parametrize("name", [n for n, c in CASES.items() if c["period"] is not None])
def test_nutation_period_matches_the_integrated_period(name):
    case = CASES[name]
    top = exact_heavy_top(case["parameters"], case["initial"])
    assert top.nutation_period == pytest.approx(float(case["period"]), rel=1e-14)


def test_baseline_case_figures():
    # BASELINE.md: nutation between θ = 0.5 and 0.7576, period 3.5177 s
    top = exact_heavy_top(BASELINE, dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0))
    assert top.nutation_period == pytest.approx(3.5177, abs=5e-5)
    assert np.arccos(top.roots[0]) == pytest.approx(0.7576, abs=5e-5)
    assert top.roots[1] == pytest.approx(np.cos(0.5), abs=1e-15)
    assert top.motion_class == "cusps"  # (3.77)-(3.78): a released top has cusps


def test_motion_classes_of_figure_44():
    start = dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, psi_dot=5.0)
    assert exact_heavy_top(BASELINE, {**start, "phi_dot": 0.3}).motion_class == "monotonic precession"
    assert exact_heavy_top(BASELINE, {**start, "phi_dot": -0.5}).motion_class == "looping"
    assert exact_heavy_top(BASELINE, {**start, "phi_dot": 0.0}).motion_class == "cusps"
    assert classify(0.5, 0.5, 1.0, 0.2) == "uniform precession"


def test_conserved_quantities_and_rates_along_the_motion():
    top = exact_heavy_top(BASELINE, dict(theta=0.5, phi=0.2, psi=0.1, theta_dot=0.2, phi_dot=0.4, psi_dot=5.0))
    t = np.linspace(0, 20, 401)
    th, thd, phd, psd = top.theta(t), top.theta_dot(t), top.phi_dot(t), top.psi_dot(t)
    I1, I3, mgl = 1.0, 0.5, 1.0
    E = 0.5 * I1 * (thd**2 + phd**2 * np.sin(th) ** 2) + 0.5 * I3 * (psd + phd * np.cos(th)) ** 2 + mgl * np.cos(th)
    p_phi = I1 * np.sin(th) ** 2 * phd + I3 * np.cos(th) * (psd + phd * np.cos(th))
    np.testing.assert_allclose(E, top.energy, rtol=1e-14)
    np.testing.assert_allclose(p_phi, top.p_phi, rtol=1e-13)
    # the rates are the derivatives of the angles (centred differences, h = 1e-5: error ~h² φ''' ~ 1e-9)
    h = 1e-5
    np.testing.assert_allclose((top.phi(t + h) - top.phi(t - h)) / (2 * h), phd, atol=1e-8)
    np.testing.assert_allclose((top.theta(t + h) - top.theta(t - h)) / (2 * h), thd, atol=1e-8)


def test_uniform_precession_and_sleeping_top_are_steady():
    # the slow uniform-precession rate from (3.80), as a float: a double root up to rounding
    I1, I3, mgl, th0, w3 = 1.0, 0.5, 1.0, 0.5, 5.0
    c = np.cos(th0)
    slow = (I3 * w3 - np.sqrt((I3 * w3) ** 2 - 4 * I1 * mgl * c)) / (2 * I1 * c)
    top = exact_heavy_top(BASELINE, dict(theta=th0, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=slow,
                                         psi_dot=w3 - slow * c))
    t = np.linspace(0, 100, 11)
    assert np.max(np.abs(top.theta(t) - th0)) < 1e-7  # the float rate leaves a ~1e-8 nutation
    sleeping = exact_heavy_top(BASELINE, dict(theta=0.0, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0,
                                              psi_dot=10.0))
    assert sleeping.kind == "steady" and np.all(sleeping.theta(t) == 0.0)
    assert np.all(np.isfinite(sleeping.rotation(t)))


def test_long_runs_cost_and_err_as_one_period():
    top = exact_heavy_top(BASELINE, dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0))
    T = top.nutation_period
    assert abs(top.theta(1e6 * T + 0.7) - top.theta(0.7)) < 1e-9  # rounding of t = 3.5e6 s: ulp 4.7e-10
    R = top.rotation(np.array([1e6 * T, 1e7 * T]))
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-14)


def test_bad_input():
    good_init = dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0)
    with pytest.raises(InvalidInputError, match=r"expected `params` keys among I1, I3, M, g, l, got unknown key\(s\) 'I2'"):
        exact_heavy_top({**BASELINE, "I2": 1.0}, good_init)
    with pytest.raises(InvalidInputError, match=r"expected params\['l'\] > 0 for the heavy top's closed form"):
        exact_heavy_top({**BASELINE, "l": 0.0}, good_init)
    with pytest.raises(UnphysicalInertiaError, match="triangle inequality"):
        exact_heavy_top({**BASELINE, "I3": 1.9}, good_init)
    with pytest.raises(UnphysicalInertiaError, match=r"got I1 - M l² = 0 < I3/2 = 0.25"):
        exact_heavy_top(dict(I1=1.0, I3=0.5, M=1.0, g=1.0, l=1.0), good_init)
    with pytest.raises(InvalidInputError, match=r"expected 0 <= initial\['theta'\] <= pi, got 4"):
        exact_heavy_top(BASELINE, {**good_init, "theta": 4.0})
    with pytest.raises(InvalidInputError, match=r"expected `initial\['psi_dot'\]` to be finite, got nan"):
        exact_heavy_top(BASELINE, {**good_init, "psi_dot": float("nan")})
    with pytest.raises(InvalidInputError, match="expected scalar parameters"):
        exact_heavy_top({**BASELINE, "M": np.array([0.1, 0.2])}, good_init)


def test_asking_for_theta_evaluates_no_angle_and_derives_no_fractions():
    from .conftest import run_python

    code = ("from mechderive.systems.heavy_top.exact import exact_heavy_top\n"
            "from mechderive.systems.heavy_top import exact_model\n"
            "top = exact_heavy_top(dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0), dict(theta=0.5, phi=0.0, psi=0.0,"
            " theta_dot=0.0, phi_dot=0.0, psi_dot=5.0))\n"
            "out, ps = top._evaluate(top.nutation_period * 0.3 + __import__('numpy').zeros(3), ['theta'])\n"
            "print(ps.computed, exact_model.model().derived, '_angles' in top.__dict__)\n"
            "out, ps = top._evaluate(top.nutation_period * 0.3 + __import__('numpy').zeros(3), ['theta', 'phi'])\n"
            "print(ps.computed, exact_model.model().derived, '_angles' in top.__dict__)\n")
    proc = run_python("-c", code, env={"MECHDERIVE_NO_DISK_CACHE": "1"})  # so that derivations happen
    assert proc.returncode == 0, proc.stderr
    first, second = proc.stdout.strip().splitlines()
    assert first.startswith("['phase', 'jacobi', '1-u,1+u']") and "fractions" not in first
    assert first.endswith("False")
    assert "pi(" in second and "precession_fractions" in second and second.endswith("True")


def test_closed_form_agrees_with_the_euler_lagrange_equations_integrated():
    from scipy.integrate import solve_ivp

    from mechderive.core.compile import compile_scalar
    from mechderive.systems.heavy_top import model as hm

    init = dict(theta=0.5, phi=0.1, psi=-0.3, theta_dot=0.2, phi_dot=0.4, psi_dot=5.0)
    top = exact_heavy_top(BASELINE, init)
    m = hm.model()
    acc = compile_scalar(m.accelerations, [*m.positions, *m.velocities, *hm.PARAMETERS])
    p = tuple(BASELINE[k] for k in ("I1", "I3", "M", "g", "l"))
    y0 = [init[k] for k in ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")]
    t = np.linspace(0, 30, 301)
    sol = solve_ivp(lambda _t, y: [y[3], y[4], y[5], *acc(*y, *p)], (0, 30), y0, method="DOP853",
                    rtol=1e-12, atol=1e-14, t_eval=t)
    # DOP853 at rtol 1e-12 over ~9 nutation periods: error ~1e-10 (benchmarks/bench_heavy_top_exact.py)
    np.testing.assert_allclose(sol.y[1], top.theta(t), atol=1e-9)
    np.testing.assert_allclose(sol.y[0], top.phi(t), atol=1e-9)
    np.testing.assert_allclose(sol.y[2], top.psi(t), atol=1e-9)


def test_omega_at_the_start_next_to_the_bottom_is_the_initial_state():
    # Regression: ω was formed with θ̇ = -u̇/sin θ and sin θ from a θ rounded next to π, which loses
    # ulp(π)/(π - θ) relative: ω1(0) came out 1.2e-9 off at θ0 = π - 1e-8.  The reference is (3.58)
    # at the initial state, by hand: ω = (φ̇ sin θ sin ψ + θ̇ cos ψ, φ̇ sin θ cos ψ - θ̇ sin ψ, φ̇ cos θ + ψ̇).
    init = dict(theta=np.pi - 1e-8, phi=0.2, psi=-0.4, theta_dot=0.3, phi_dot=0.0, psi_dot=3.0)
    top = exact_heavy_top(BASELINE, init)
    with mpmath.workdps(30):
        th, ps = mpmath.mpf(init["theta"]), mpmath.mpf(init["psi"])
        phd, thd, psd = (mpmath.mpf(init[k]) for k in ("phi_dot", "theta_dot", "psi_dot"))
        want = [float(phd * mpmath.sin(th) * mpmath.sin(ps) + thd * mpmath.cos(ps)),
                float(phd * mpmath.sin(th) * mpmath.cos(ps) - thd * mpmath.sin(ps)), float(phd * mpmath.cos(th) + psd)]
    # 1e-13 relative to |ω|: the closed form's claimed accuracy at one point
    np.testing.assert_allclose(top.evaluate([0.0], ["omega"])["omega"][0], want, rtol=0, atol=1e-13 * 3.1)


# --- passages near the pole and the bottom --------------------------------------------------------------

# θ0 next to the pole (bottom), moving away: the apex comes back within 5e-6 .. 5e-14 rad of the pole
# (~1e-14 .. 1e-16 of the bottom) once per nutation period, where φ and ψ each turn by ~π in a time
# ~(1 - n₊)^(1/2) (resp. (-n₋)^(-1/2)); R, the apex and ω stay smooth there.
NEAR_PASSAGES = {
    "pole-1e-3": dict(theta=1e-3, theta_dot=0.5, psi_dot=10.0),
    "pole-1e-7": dict(theta=1e-7, theta_dot=0.5, psi_dot=10.0),  # n₊ = 1 - 5e-26 rounds to 1
    "bottom-1e-7": dict(theta=np.pi - 1e-7, theta_dot=0.3, psi_dot=3.0),
    "bottom-1e-8": dict(theta=np.pi - 1e-8, theta_dot=0.3, psi_dot=3.0),
}


def _hand_roots(init: dict, dps: int = 120) -> list:
    """The roots u1 ≤ u2 ≤ u3 of f(u) (3.73) for BASELINE, typed in by hand from (3.65)–(3.72), (3.78)."""
    with mpmath.workdps(dps):
        I1, I3, mgl = mpmath.mpf(1), mpmath.mpf("0.5"), mpmath.mpf(BASELINE["M"]) * 10 * 1
        th, thd = mpmath.mpf(init["theta"]), mpmath.mpf(init["theta_dot"])
        phd, psd = mpmath.mpf(init.get("phi_dot", 0.0)), mpmath.mpf(init["psi_dot"])
        w3 = psd + phd * mpmath.cos(th)
        a = I3 * w3 / I1
        b = (I1 * phd * mpmath.sin(th) ** 2 + I3 * w3 * mpmath.cos(th)) / I1
        alpha = thd**2 + phd**2 * mpmath.sin(th) ** 2 + 2 * mgl * mpmath.cos(th) / I1
        beta = 2 * mgl / I1
        # f(u) = β u³ - (α + a²) u² + (2ab - β) u + (α - b²)
        roots = mpmath.polyroots([beta, -(alpha + a * a), 2 * a * b - beta, alpha - b * b], maxsteps=400,
                                 extraprec=4 * dps)
        return sorted(mpmath.re(r) for r in roots)


@pytest.mark.parametrize("name", list(NEAR_PASSAGES))
def test_conditioning_near_a_passage_has_full_relative_accuracy(name):
    # Regression: at 40 digits 1 + u1 = 3e-32 came out 2e-9 off relative (R 7e-9 off); the setup now
    # adds the digits 1 ∓ u has lost.  conditioning = max((1 - u1)/(1 - u2), (1 + u2)/(1 + u1)).
    top = exact_heavy_top(BASELINE, NEAR_PASSAGES[name])
    with mpmath.workdps(120):
        u1, u2, _ = _hand_roots(NEAR_PASSAGES[name])
        want = float(max((1 - u1) / (1 - u2), (1 + u2) / (1 + u1)))
    assert top.conditioning > 1e9  # the case is what it says: a near passage
    # 1e-13: both are correctly rounded 30+-digit values, up to the float inputs' own rounding
    assert top.conditioning == pytest.approx(want, rel=1e-13)


def _passage_time(top, t_lo: float, t_hi: float) -> float:
    """The time of the extremum of u in [t_lo, t_hi] (a sign change of u̇), by bisection: the window only."""
    f = lambda t: float(top.evaluate([t], ["u_dot"])["u_dot"][0])  # noqa: E731
    lo, hi = t_lo, t_hi
    assert f(lo) * f(hi) < 0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) * f(lo) > 0 else (lo, mid)
    return lo


@pytest.mark.parametrize("name", list(NEAR_PASSAGES))
def test_rotation_apex_omega_through_a_near_passage_against_30_digit_reference(name):
    # Regressions: R, apex, ω erred 5e-8 (pole-1e-3: Π(n₊|m) per period from float(n₊)), raised
    # "expected n != 1" (pole-1e-7), erred 7e-9 in R and up to 0.14 in ω right at the bottom passage
    # (1 + u1 at 40 digits; φ̇ cos θ + ψ̇ cancelling and sin θ of a θ rounded next to π in ω).
    from mechderive.stress.reference import heavy_reference

    init = NEAR_PASSAGES[name]
    top = exact_heavy_top(BASELINE, init)
    T = top.nutation_period
    bottom = init["theta"] > 1
    # the second passage: u has its extremum there (u1 at the bottom, u2 at the pole)
    grid = np.linspace(0.5 * T, 2.0 * T, 301)
    u = top.u(grid)
    k = int(np.argmin(u) if bottom else np.argmax(u))
    tp = _passage_time(top, grid[k - 1], grid[k + 1])
    t = np.concatenate([[0.0], tp + np.array([-1e-6, -1e-9, -1e-12, 0.0, 1e-12, 1e-9, 1e-6]), [tp + 0.5 * T]])
    ref = heavy_reference(BASELINE, init, t)  # Taylor series of the hand-written Newton–Euler equations, 30 digits
    out = top.evaluate(t, ["R", "apex", "omega"])
    # 1e-12: the closed form's ~1e-13 ×10 (R, apex, ω are well conditioned through the passage)
    np.testing.assert_allclose(out["R"], ref.R, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out["apex"], ref.R[:, 2, :], rtol=0, atol=1e-12)
    np.testing.assert_allclose(out["omega"], ref.omega, rtol=0, atol=1e-12 * np.linalg.norm(ref.omega[0]))


def test_angles_by_fourier_series_equal_angles_by_carlson(monkeypatch):
    # (3.74), (3.75): φ, ψ take Π(n±; am u | m); the usual path sums its Fourier series, the
    # fallback Carlson's R_J.  Over 100 nutation periods they agree to rounding of the angles.
    import mechderive.special.pi_series as pi_series
    from mechderive.systems.heavy_top.exact import exact_heavy_top

    params = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
    initial = dict(theta=0.5, psi_dot=5.0)
    top = exact_heavy_top(params, initial)
    t = np.linspace(0.0, 100 * top.nutation_period, 2001)
    fast = top.evaluate(t, ["phi", "psi", "R"])
    assert top._mp["pi_series"] is not None, "the series path was not taken"
    monkeypatch.setattr(pi_series, "fit_pi_series", lambda *a, **k: None)
    slow = exact_heavy_top(params, initial)
    carlson = slow.evaluate(t, ["phi", "psi", "R"])
    assert slow._mp["pi_series"] is None
    # ψ reaches ~1600 rad: its own ulp is 2e-13
    for q in ("phi", "psi"):
        np.testing.assert_allclose(fast[q], carlson[q], rtol=0, atol=5e-13)
    np.testing.assert_allclose(fast["R"], carlson["R"], rtol=0, atol=1e-14)
