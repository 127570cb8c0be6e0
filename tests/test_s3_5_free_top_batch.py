"""The free top's per-motion quantities of N motions at once (section 3.5; :mod:`mechderive.systems.free_top.batch`).

Reference: the single-point planner (``run_scene`` with ``[output] summary``), whose periods come from
40-digit constants (correctly rounded) and whose T, |L| and stability table are double evaluations of the
same expressions.  Justification of the tolerance: the contract of ``System.summarize_batch`` is agreement to
1e-12 relative at every point not marked ``fallback``; each batched value carries a rounding bound from its
own condition numbers, and points whose bound exceeds 1e-13 fall back, so 1e-12 is the contract, not a fit.
"""

from __future__ import annotations

import numpy as np
import pytest

from mechderive.errors import InvalidInputError
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import parse_scene
from mechderive.systems.free_top.system import FreeTop

PLAIN = ("polhode_period", "period", "flip_interval", "energy", "angular_momentum")
TOP = FreeTop()


def _single(I, w, names, strict=True):
    scene = {"system": "free_top", "strict": bool(strict),
             "parameters": {k: float(v) for k, v in zip(("I1", "I2", "I3"), I)},
             "initial": {"omega": [float(x) for x in w]},
             # a time short against the motion (the closed form refuses beyond 2^50 of its turns)
             "time": {"t_end": 1e-3 / max(float(np.max(np.abs(w))), 1e-3), "samples": 2},
             "output": {"quantities": ["omega1"], "summary": list(names)}}
    report = run_scene(parse_scene(scene)).report
    return report["summary"], report["summary_error"]


def _batch(I, w, names, strict=True):
    out = TOP.summarize_batch({"I1": I[:, 0], "I2": I[:, 1], "I3": I[:, 2]}, {"omega": w}, names, strict=strict)
    assert out is not None
    return out


def _relative(batched, single):
    """The largest relative difference of a number or a (nested) table of numbers, classes equal."""
    if isinstance(single, dict):
        assert set(batched) == set(single), (batched, single)
        return max([_relative(batched[k], single[k]) for k in single] + [0.0])
    if isinstance(single, str):
        assert batched == single
        return 0.0
    assert single is not None
    return 0.0 if batched == single else abs(batched - single) / abs(single)


def _symmetric_sample(rng, n):
    """Symmetric tops (two equal moments, either the larger or the smaller, on any axis), some spinning
    steadily (about the symmetry axis or in the plane of equal moments)."""
    I, w = _sample(rng, n, physical=True)
    for i in range(n):
        a, b = rng.choice(3, 2, replace=False)
        I[i, b] = I[i, a]
        c = 3 - a - b
        I[i, c] = min(I[i, c], 2 * I[i, a])  # a rigid body's: I_c ≤ 2 I⊥
        if rng.random() < 0.1:
            w[i, c] = 0.0
        elif rng.random() < 0.1:
            w[i, a] = w[i, b] = 0.0
    return I, w


def _near_separatrix_sample(rng, n):
    """Bodies tilted 1e-7..1e-1 (relative, in ω3) off the separatrix L² = 2T·I2, axes in any order: the points
    the conditioning bound must sort (the nearer fall back, the others must still agree)."""
    I = np.sort(10.0 ** rng.uniform(-1, 1, (n, 3)), axis=1)
    I[:, 2] = np.minimum(I[:, 2], I[:, 0] + I[:, 1])
    w1 = rng.uniform(0.1, 1.0, n)
    # I1 ω1² (I2 - I1) = I3 ω3² (I3 - I2) on the separatrix
    w3 = np.sqrt(I[:, 0] * w1**2 * (I[:, 1] - I[:, 0]) / (I[:, 2] * (I[:, 2] - I[:, 1])))
    tilt = 10.0 ** rng.uniform(-7, -1, n) * rng.choice([-1.0, 1.0], n)
    w = np.stack([w1, rng.uniform(0.1, 2.0, n), w3 * (1 + tilt)], axis=1)
    order = np.array([rng.permutation(3) for _ in range(n)])
    return np.take_along_axis(I, order, axis=1), np.take_along_axis(w, order, axis=1)


def _sample(rng, n, *, physical):
    """Moments with ratios 1e-3..1e3 (strict = false) or a body's (triangle inequalities), ω in every
    direction with magnitudes 1e-2..1e2 — some with a zero component, some symmetric, to reach those paths."""
    if physical:
        I = np.sort(10.0 ** rng.uniform(-3, 3, (n, 1)) * rng.uniform(0.05, 1.0, (n, 3)), axis=1)
        I[:, 2] = np.minimum(I[:, 2], I[:, 0] + I[:, 1])
        I = rng.permuted(I, axis=1)
    else:
        I = 10.0 ** rng.uniform(-3, 3, (n, 3))
    w = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-2, 2, (n, 1))
    w[rng.random(n) < 0.05, rng.integers(0, 3)] = 0.0
    sym = rng.random(n) < 0.05
    I[sym, 1] = I[sym, 0]
    return I, w


@pytest.mark.parametrize("share", [0.4, pytest.param(1.0, marks=pytest.mark.slow)])
def test_every_answered_point_equals_the_single_path(share):
    # each single path costs ~10 ms: 40% of the 460 points by default, all of them with -m slow
    rng = np.random.default_rng(20261128)
    worst: dict[str, float] = {}
    answered = 0
    symmetric = ("polhode_period", "period", "energy", "angular_momentum", "precession_rate", "stability")
    cases = ((False, 300, PLAIN), (True, 60, PLAIN + ("stability",)), ("symmetric", 40, symmetric),
             ("separatrix", 60, PLAIN))
    cases = tuple((physical, round(share * n), names) for physical, n, names in cases)
    total = sum(n for _, n, _ in cases)
    for physical, n, names in cases:
        if physical == "symmetric":
            I, w = _symmetric_sample(rng, n)
        elif physical == "separatrix":
            I, w = _near_separatrix_sample(rng, n)
        else:
            I, w = _sample(rng, n, physical=physical)
        physical = bool(physical)
        out = _batch(I, w, names, strict=physical)
        for i in np.flatnonzero(~out.fallback):
            single, _ = _single(I[i], w[i], names, strict=physical)
            answered += 1
            for name in names:
                worst[name] = max(worst.get(name, 0.0), _relative(out.values[name][i], single[name]))
                assert np.isfinite(out.errors[name][i]) and out.errors[name][i] >= 0
            # the estimate is honest: it covers the difference from the correctly rounded single path
            P, P1 = out.values["polhode_period"][i], single["polhode_period"]
            assert abs(P - P1) <= out.errors["polhode_period"][i] + np.spacing(P1)
    print(f"\nanswered {answered} of {total} points; largest relative difference per quantity: {worst}")
    assert answered >= 0.74 * total  # 340 of 460 in the full sample
    assert max(worst.values()) <= 1e-12


def test_fallback_is_rare_on_a_typical_grid():
    # a body (1, 2, I3) swept over I3 and ω over a sphere of directions, |ω| = 1
    I3 = np.linspace(2.05, 2.95, 10)
    th, ph = np.meshgrid(np.linspace(0.01, np.pi - 0.01, 60), np.linspace(0.0, 2 * np.pi, 60, endpoint=False))
    dirs = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1).reshape(-1, 3)
    I = np.array([[1.0, 2.0, c] for c in I3 for _ in dirs])
    w = np.tile(dirs, (len(I3), 1))
    out = _batch(I, w, PLAIN)
    fraction = float(np.mean(out.fallback))
    print(f"\nfallback fraction on a {len(I)}-point grid: {fraction:.4f}")
    assert fraction < 0.02


def test_refused_separatrix_steady_and_inapplicable_points_fall_back():
    I = np.array([[1.0, 1.5, 3.0],     # I1 + I2 < I3: no body has these moments
                  [1.0, 2.0, 3.0],     # near the separatrix (below)
                  [1.0, 2.0, 3.0],     # rotation about a principal axis: steady
                  [1.0, 2.0, 2.5],     # an ordinary motion
                  [-1.0, 2.0, 2.5],    # a negative moment
                  [np.nan, 2.0, 2.5]])
    # on the separatrix L² = 2T·I2: I1 ω1² (I2 - I1) = I3 ω3² (I3 - I2), here ω1 = √3 ω3; then tilted by 1e-9
    w = np.array([[1.0, 0.5, 1.0], [np.sqrt(3.0), 0.3, 1.0 + 1e-9], [0.0, 2.0, 0.0], [1.0, 0.5, 1.0],
                  [1.0, 0.5, 1.0], [1.0, 0.5, 1.0]])
    strict = _batch(I, w, PLAIN)
    assert strict.fallback.tolist() == [True, True, True, False, True, True]
    loose = _batch(I, w, PLAIN, strict=False)
    assert loose.fallback.tolist() == [False, True, True, False, True, True]
    single, _ = _single(I[0], w[0], PLAIN, strict=False)
    assert _relative(loose.values["polhode_period"][0], single["polhode_period"]) <= 1e-12
    # a symmetric top has no flip interval but a precession rate, which an asymmetric top has not; a sphere has
    # neither; an unknown name falls back
    sym = np.array([[1.0, 1.0, 1.5]]), np.array([[1.0, 0.5, 1.0]])
    assert not _batch(*sym, ("polhode_period", "precession_rate")).fallback[0]
    assert _batch(*sym, ("flip_interval",)).fallback[0]
    assert _batch(np.array([[2.0, 2.0, 2.0]]), sym[1], ("precession_rate",)).fallback[0]
    assert _batch(I[3:4], w[3:4], ("precession_rate",)).fallback[0]
    assert _batch(I[3:4], w[3:4], ("no_such_quantity",)).fallback[0]
    # a non-finite Euler angle is refused by the scene: fallback; arrays of different lengths are refused here
    angles = {"omega": w[3:4], "phi": np.array([np.inf])}
    assert TOP.summarize_batch({"I1": I[3:4, 0], "I2": I[3:4, 1], "I3": I[3:4, 2]}, angles, PLAIN).fallback[0]
    with pytest.raises(InvalidInputError):
        TOP.summarize_batch({"I1": I[:, 0], "I2": I[:, 1], "I3": I[:, 2]}, {"omega": w[:2]}, PLAIN)


def test_chunks_do_not_change_results():
    rng = np.random.default_rng(7)
    I, w = _sample(rng, 2000, physical=True)
    names = PLAIN + ("stability", "precession_rate")
    whole = _batch(I, w, names)
    cut = 777
    parts = [_batch(I[a:b], w[a:b], names) for a, b in ((0, cut), (cut, len(I)))]
    assert np.array_equal(whole.fallback, np.concatenate([p.fallback for p in parts]))
    for name in names:
        joined = np.concatenate([p.values[name] for p in parts])
        if whole.values[name].dtype == object:
            assert all(a == b for a, b in zip(whole.values[name], joined))
        else:
            assert whole.values[name].tobytes() == joined.tobytes()
        assert whole.errors[name].tobytes() == np.concatenate([p.errors[name] for p in parts]).tobytes()


@pytest.mark.parametrize("tilt", [1e-12, 1e-6])
def test_near_separatrix_is_fallback(tilt):
    I = np.array([[1.0, 2.0, 3.0]])
    w = np.array([[np.sqrt(3.0) * (1 + tilt), 0.0, 1.0]])  # ω2 = 0: on the separatrix before the tilt
    w[0, 1] = 1e-3
    assert _batch(I, w, ("polhode_period",)).fallback[0]
