"""The free top's closed form set up in extended precision (issue 15: a warm run without mpmath): the same
motion as the 40-digit setup over a random sample, what goes to 40 digits, planted wrong constants, and a
warm ``mechderive run`` of a free-top scene that imports neither mpmath nor SymPy.  Sections 3.4-3.5."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mechderive.core.phase import DD
from mechderive.systems.free_top import exact_extended
from mechderive.systems.free_top.exact import exact_free_top

from .conftest import warm_run_report

pytestmark = pytest.mark.skipif(not exact_extended.EXTENDED, reason="numpy.longdouble is a double here")

#: the agreement promised (the batched paths'); the extended setup's own margin is 1e-14
RTOL = 1e-12


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1.0))


def _sample(rng: np.random.Generator, n: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, float]]:
    """Random rigid bodies (triangle inequalities), launches of every size ratio (ω components from 1e-4 to 1
    of each other, either sign), random attitudes, over 1 to 40 polhode periods (in units of 1/|ω|)."""
    from mechderive.kinematics.rotations import rotation_matrix

    cases = []
    while len(cases) < n:
        I = rng.uniform(0.2, 2.0, 3)
        if 2 * I.max() > I.sum():
            continue
        w = rng.choice([-1, 1], 3) * 10 ** rng.uniform(-4, 0, 3) * 10 ** rng.uniform(-1, 1)
        R0 = rotation_matrix(*rng.uniform(-3, 3, 3))
        cases.append((I, w, R0, 10 ** rng.uniform(0, 1.6) * 2 * np.pi / np.linalg.norm(w)))
    return cases


def test_extended_setup_equals_the_40_digit_one_on_a_random_sample(rng):
    worst, extended = 0.0, 0
    for I, w, R0, span in _sample(rng, 16):
        ref = exact_free_top(I, w, R0=R0)
        top = exact_free_top(I, w, R0=R0, horizon=span)
        if "extended" not in top._mp:
            continue
        extended += 1
        assert (top.kind, top._q0, top._perm.tolist()) == (ref.kind, ref._q0, ref._perm.tolist())
        for name in ("m", "m1", "energy", "L_norm", "polhode_period", "precession_per_period"):
            a, b = getattr(top, name), getattr(ref, name)
            worst = max(worst, abs(a - b) / max(abs(b), 1e-300))
        t = np.linspace(-0.1 * span, span, 201)
        got = {"omega": top.omega(t), "R": top.rotation(t)}
        want = {"omega": ref.omega(t), "R": ref.rotation(t)}
        for q in got:
            worst = max(worst, _relative(got[q], want[q]))
        assert worst <= RTOL, (I, w, span, worst)
        # the orientation's constants passed their own checks (no 40-digit constants made)
        assert "constants" not in top._mp
        # the error estimate is measured on this motion (not a constant) and covers the 40-digit motion
        estimate = top.error_estimate(t, ["omega", "R"])
        assert 0 < estimate < 1e-8
        # ω's estimate is relative to |ω0| (FreeTopSolution.error_estimate), R's absolute
        assert np.max(np.abs(got["omega"] - want["omega"])) / np.linalg.norm(w) <= estimate
        assert np.max(np.abs(got["R"] - want["R"])) <= estimate
    print(f"worst relative difference {worst:.2e}; {extended} of 16 in extended precision")
    assert extended >= 12


@pytest.mark.parametrize("moments, omega, horizon", [
    ((1.0, 2.0, 3.0), (0.0, 1.0, 0.0), 10.0),          # steady: a spin about a principal axis
    ((3.0, 4.0, 6.0), (2.0, 0.5, 1.0), 10.0),          # on the separatrix: G_y = 3·2² − 12·1² = 0 exactly
    ((1.0, 2.0, 3.0), (1e-20, 1.0, 1e-20), 10.0),      # 1 − m ~ 1e-40: the piecewise-separatrix regime
    ((1.0, 2.0, 3.0), (1.0, 0.5, 1.0), 2.0**52),       # 2^49 polhode periods: K would be needed to 1e-30
    ((1.0, 2.0, 3.0), (1e-150, 1.0, 1e-150), 10.0),    # gaps of 1e-300: beyond 2^±400
])
def test_what_the_extended_setup_cannot_vouch_for_goes_to_40_digits(moments, omega, horizon):
    assert "extended" not in exact_free_top(moments, omega, horizon=horizon)._mp


def test_a_planted_wrong_constant_is_caught(monkeypatch):
    I, w = (1.0, 2.0, 3.0), (1.0, 0.5, 1.0)
    t = np.linspace(0.0, 50.0, 501)
    ref = exact_free_top(I, w)
    assert "extended" in exact_free_top(I, w, horizon=50.0)._mp
    compiled = exact_extended._compiled()
    # m off by 1e-9 in both precisions (a wrong derivation): the self-check (Euler's equations (3.33)) refuses
    wrong_m = dict(compiled, gaps=lambda *a: [*compiled["gaps"](*a)[:4], compiled["gaps"](*a)[4] * (1 + 1e-9),
                                              compiled["gaps"](*a)[5]])
    monkeypatch.setattr(exact_extended, "_compiled", lambda: wrong_m)
    assert "extended" not in exact_free_top(I, w, horizon=50.0)._mp
    # K off by 1e-12 of itself in the extended run only (a step of it done in doubles, say): the comparison
    # with the doubles sees an error far above the extended values' and refuses
    monkeypatch.setattr(exact_extended, "_compiled", lambda: compiled)
    elliptic = exact_extended._elliptic

    def planted(Im, wr, G, dtype, decided):
        out = elliptic(Im, wr, G, dtype, decided)
        return dict(out, K=out["K"] * (1 + dtype(1e-12))) if dtype is np.longdouble else out

    monkeypatch.setattr(exact_extended, "_elliptic", planted)
    assert "extended" not in exact_free_top(I, w, horizon=50.0)._mp
    monkeypatch.undo()
    # a quarter period off by 1e-12 in a motion that is evaluated: the run's estimate (the period against an
    # independent K, Euler's equations at the samples) grows to cover the error it makes
    top = exact_free_top(I, w, horizon=50.0)
    K = top._quarter.hi * (1 + 1e-12)
    bad = dataclasses.replace(top, _quarter=DD(K, 0.0), _period=DD(4 * K, 0.0), _mp={})
    err = float(np.max(np.abs(bad.omega(t) - ref.omega(t)))) / np.linalg.norm(w)  # relative to |ω0|, as estimated
    assert err > 1e-12
    assert bad.error_estimate(t, ["omega"]) >= err


def test_orientation_falls_back_lazily_to_the_40_digit_constants(monkeypatch):
    I, w = (1.0, 2.0, 3.0), (1.0, 0.5, 1.0)
    monkeypatch.setattr(exact_extended, "orientation", lambda sol: None)
    top = exact_free_top(I, w, horizon=20.0)
    t = np.linspace(0.0, 20.0, 101)
    assert _relative(top.omega(t), exact_free_top(I, w).omega(t)) <= RTOL
    assert "constants" not in top._mp  # ω alone needs no orientation
    got = top.rotation(t)
    assert "constants" in top._mp
    assert _relative(got, exact_free_top(I, w).rotation(t)) <= RTOL


def test_a_warm_run_of_a_free_top_scene_imports_no_mpmath():
    code = ("import sys, io, contextlib, json\n"
            "from mechderive.cli import main\n"
            "out = io.StringIO()\n"
            "with contextlib.redirect_stdout(out):\n"
            "    main(['run', 'free_top_tumbling', '--json'])\n"
            "report = json.loads(out.getvalue())\n"
            "print(json.dumps({m: m in sys.modules for m in ('mpmath', 'sympy', 'scipy', 'tomllib', 'hashlib')}\n"
            "                 | {'estimate': report['error_estimate']}))\n")
    report = warm_run_report(code)
    assert not report["mpmath"] and not report["sympy"] and not report["scipy"], report
    assert not report["tomllib"] and not report["hashlib"], report  # the scene's parse and SHA-256: see the heavy top's
    assert 0 < report["estimate"] < 1e-9
