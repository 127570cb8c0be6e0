"""Scenes report an error estimate measured on the run (issue 11): a wrong constant planted in a
closed form is caught by the run's own estimate, and `rtol_met` follows from it."""

from __future__ import annotations

import dataclasses

import numpy as np

import mechderive.systems.free_top.exact as free_exact
from mechderive.scenes.builtin import load_builtin
from mechderive.scenes.planner import run_scene
from mechderive.systems.free_top.integrate import integrate_free_top

R_NAMES = [f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]


def _tumbling(**changes):
    scene = load_builtin("free_top_tumbling")
    return dataclasses.replace(scene, method="exact", quantities=tuple(R_NAMES), **changes)


def _planted(real):
    """exact_free_top with its precession angle φ'0 off by 1e-7 rad: a wrong constant, no error raised."""
    def make(*args, **kwargs):
        sol = real(*args, **kwargs)
        wrong = dataclasses.replace(sol._orient, phi0=sol._orient.phi0 + 1e-7)
        sol.__dict__["_orient"] = wrong
        return sol
    return make


def test_a_planted_wrong_constant_is_caught_by_the_run(monkeypatch):
    scene = _tumbling()
    honest = run_scene(scene)
    assert honest.report["rtol_met"] is True and honest.report["error_estimate"] < 1e-11
    monkeypatch.setattr(free_exact, "exact_free_top", _planted(free_exact.exact_free_top))
    planted = run_scene(scene)
    # independent reference: DOP853 at rtol 1e-12 (its own estimate ~1e-11); the plant turns R by ~1e-7
    t = planted.t
    moments = tuple(scene.parameters[k] for k in ("I1", "I2", "I3"))
    ref = integrate_free_top(moments, scene.initial["omega"], t, rtol=1e-12, atol=1e-15, R0=np.eye(3))
    R = np.stack([planted.columns[k] for k in R_NAMES], axis=-1).reshape(-1, 3, 3)
    true = float(np.max(np.abs(R - ref.R)))
    assert true > 1e-8  # the plant does make the output wrong
    assert planted.report["error_estimate"] >= true
    assert planted.report["rtol_met"] is False
