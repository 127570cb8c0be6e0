"""The heavy top's closed form set up in extended precision (issue 15: a warm run without mpmath):
the same motion as the 40-digit setup over a random sample of every class, the fallbacks, and a warm
``mechderive run`` that imports neither mpmath nor SymPy.  Section 3.6 for the physics."""

from __future__ import annotations


import numpy as np
import pytest

from mechderive.systems.heavy_top import exact_extended
from mechderive.systems.heavy_top.exact import exact_heavy_top

from .conftest import warm_run_report

pytestmark = pytest.mark.skipif(not exact_extended.EXTENDED, reason="numpy.longdouble is a double here")

QUANTITIES = ["u", "theta", "theta_dot", "phi", "psi", "phi_wrapped", "psi_wrapped", "phi_dot", "psi_dot", "R",
              "apex", "omega"]
#: the agreement promised (the batched path's); the extended setup's own margin is 1e-14
RTOL = 1e-12


def _sample(rng: np.random.Generator, n: int) -> list[tuple[dict, dict, float]]:
    """Random rigid tops (I1 − M l² ≥ I3/2) and launches: moving starts (θ̇0 ≠ 0), starts at a turning point
    (θ̇0 = 0), from rest in φ (cusps: φ̇0 = 0 with θ̇0 = 0), slow and fast spins, over 1 to 40 periods."""
    cases = []
    while len(cases) < n:
        M, l = rng.uniform(0.05, 0.5), rng.uniform(0.1, 1.0)
        I3 = rng.uniform(0.1, 1.0)
        I1 = M * l * l + I3 / 2 + rng.uniform(0.05, 1.5)
        kind = len(cases) % 4
        theta_dot = 0.0 if kind in (1, 2) else rng.uniform(-2, 2)
        phi_dot = 0.0 if kind == 2 else rng.uniform(-4, 4)
        psi_dot = rng.choice([-1, 1]) * 10 ** rng.uniform(-0.5, 1.7)
        init = dict(theta=rng.uniform(0.1, 3.0), phi=rng.uniform(-3, 3), psi=rng.uniform(-3, 3),
                    theta_dot=theta_dot, phi_dot=phi_dot, psi_dot=psi_dot)
        cases.append((dict(I1=I1, I3=I3, M=M, g=9.81, l=l), init, 10 ** rng.uniform(0, 1.6)))
    return cases


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1.0))


def test_extended_setup_equals_the_40_digit_one_on_a_random_sample(rng):
    worst, classes, fallbacks = 0.0, set(), 0
    for params, init, periods in _sample(rng, 80):
        ref = exact_heavy_top(params, init)
        if ref.kind != "nutating":
            continue
        horizon = periods * ref.nutation_period
        top = exact_heavy_top(params, init, horizon=horizon)
        if "extended" not in top._mp:
            fallbacks += 1
            continue
        classes.add(top.motion_class)
        assert top.motion_class == ref.motion_class
        for name in ("nutation_period", "m", "m1", "energy", "p_phi", "p_psi", "conditioning"):
            worst = max(worst, abs(getattr(top, name) - getattr(ref, name)) / max(abs(getattr(ref, name)), 1e-300))
        worst = max(worst, _relative(np.array(top.roots), np.array(ref.roots)))
        t = np.linspace(0.0, horizon, 41)
        got, want = top.evaluate(t, QUANTITIES), ref.evaluate(t, QUANTITIES)
        for q in QUANTITIES:
            worst = max(worst, _relative(got[q], want[q]))
        assert worst <= RTOL, (params, init, horizon, worst)
        # the error estimate is measured on this motion (not a constant) and covers the 40-digit motion
        estimate = top.error_estimate(t, ["theta", "phi", "psi"])
        assert 0 < estimate < 1e-6
        for q in ("theta", "phi_wrapped", "psi_wrapped"):
            diff = np.abs(got[q] - want[q])
            if q.endswith("wrapped"):
                diff = np.minimum(diff, 2 * np.pi - diff)
            assert np.max(diff) <= estimate, (q, np.max(diff), estimate)
    print(f"worst relative difference {worst:.2e}; {fallbacks} of 80 at 40 digits; classes {sorted(classes)}")
    assert {"cusps", "looping", "monotonic precession"} <= classes
    assert fallbacks <= 20


def _near_steady() -> dict:
    """Slow steady precession (3.80) at θ0 = 0.5, ω3 = 5, I1 = 1, I3 = 0.5, M g l = 1, φ̇0 off by 1e-12 relative:
    M g l = φ̇ (I3 ω3 − I1 φ̇ cos θ0)."""
    c, w3 = np.cos(0.5), 5.0
    slow = (0.5 * w3 - np.sqrt((0.5 * w3) ** 2 - 4 * c)) / (2 * c)
    phi_dot = slow * (1 + 1e-12)
    return dict(theta=0.5, phi_dot=phi_dot, psi_dot=w3 - phi_dot * c)


@pytest.mark.parametrize("initial", [
    dict(theta=1e-4, psi_dot=5.0),  # next to the pole: a near passage
    _near_steady(),  # next to uniform precession
    dict(theta=0.0, psi_dot=10.0),  # on the pole: sleeping
])
def test_what_the_extended_setup_cannot_vouch_for_goes_to_40_digits(initial):
    params = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
    init = dict(dict(phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0), **initial)
    assert "extended" not in exact_heavy_top(params, init, horizon=10.0)._mp


def test_a_long_span_goes_to_40_digits():
    params = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
    init = dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0)
    assert "extended" in exact_heavy_top(params, init, horizon=100.0)._mp
    # 2^40 periods: the phase's constants would have to be known to ~1e-26
    assert "extended" not in exact_heavy_top(params, init, horizon=2.0**40)._mp


def test_angles_fall_back_lazily_to_the_40_digit_constants(monkeypatch):
    params = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
    init = dict(theta=0.5, phi=0.3, psi=-0.2, theta_dot=0.4, phi_dot=0.1, psi_dot=5.0)
    monkeypatch.setattr(exact_extended, "angle_constants", lambda sol: None)
    top = exact_heavy_top(params, init, horizon=20.0)
    assert "extended" in top._mp and "precise" not in top._mp
    t = np.linspace(0.0, 20.0, 101)
    got = top.evaluate(t, ["phi", "psi", "R"])
    assert "precise" in top._mp
    want = exact_heavy_top(params, init).evaluate(t, ["phi", "psi", "R"])
    for q in got:
        assert _relative(got[q], want[q]) <= RTOL
    assert abs(got["phi"][0] - 0.3) <= 1e-15 and abs(got["psi"][0] + 0.2) <= 1e-15


def test_a_warm_run_of_the_default_scene_imports_no_mpmath():
    code = ("import sys, io, contextlib, json\n"
            "from mechderive.cli import main\n"
            "sys.argv = ['mechderive', 'run', '--json']\n"
            "out = io.StringIO()\n"
            "with contextlib.redirect_stdout(out):\n"
            "    try:\n        main()\n    except SystemExit:\n        pass\n"
            "report = json.loads(out.getvalue())\n"
            "print(json.dumps({'mpmath': 'mpmath' in sys.modules, 'sympy': 'sympy' in sys.modules,\n"
            "                  'scipy': 'scipy' in sys.modules, 'solve': report['timings']['solve'],\n"
            "                  'estimate': report['error_estimate'],\n"
            "                  'light': [m for m in ('tomllib', 'hashlib', 'secrets') if m in sys.modules]}))\n")
    report = warm_run_report(code)
    assert not report["mpmath"] and not report["sympy"] and not report["scipy"], report
    # nor the TOML parser (the scene's parse is read from the disk cache), OpenSSL's hashlib (the cache's SHA-256
    # is CPython's own), secrets: ~10 ms of a 0.2 s run together
    assert report["light"] == [], report
    assert 0 < report["estimate"] < 1e-9


def test_a_start_at_theta_pi_over_2_given_by_mgl_is_set_up_in_extended_precision():
    # the built-in gyroscope: u0 = cos(π/2) = 6e-17 in doubles is a root; its relative error is no measure
    params = dict(I1=0.010625, I3=0.00125, Mgl=0.981)
    init = dict(theta=np.pi / 2, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=300.0)
    top = exact_heavy_top(params, init, horizon=1.75)
    assert "extended" in top._mp
    ref = exact_heavy_top(params, init)
    t = np.linspace(0.0, 1.75, 201)
    got, want = top.evaluate(t, QUANTITIES), ref.evaluate(t, QUANTITIES)
    assert max(_relative(got[q], want[q]) for q in QUANTITIES) <= RTOL
