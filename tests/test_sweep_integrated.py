"""Sweeps of systems that integrate: a chunk's points integrated together, each answered as its single run.

The batched path (:mod:`mechderive.solvers.batch`, the systems' ``summarize_batch``) must give the table
the planner gives point by point — the same trajectories bit for bit, so the same summaries bit for bit —
and a point whose run fails must be that point's refusal, not the chunk's.  The reference is the one-by-one
path itself (``evaluate_chunk`` with the batch switched off): the planner, a scene parsed per point, one
run per point.
"""

from __future__ import annotations

import numpy as np
import pytest

from mechderive.core import cbuild
from mechderive.sweeps import evaluate
from mechderive.sweeps.spec import parse_sweep

pytestmark = pytest.mark.skipif(not cbuild.c_enabled(), reason="no C compiler on this machine")

#: the rigid_body system's example (an asymmetric heavy top: integrated, its period measured on the run)
RIGID = {"system": "rigid_body", "method": "auto", "rtol": 1e-10,
         "parameters": {"I1": 2.0, "I2": 3.0, "I3": 4.0, "M": 1.0, "g": 9.81, "center_of_mass": [0.1, 0.0, 0.5]},
         "initial": {"theta": 0.3, "omega": [0.0, 0.0, 20.0]},
         "time": {"t_end": 4.0, "samples": 401}, "output": {"quantities": ["omega1"]}}


def _one_by_one(sweep, k, monkeypatch):
    """Chunk ``k`` of ``sweep`` with every point through the planner (the batch switched off)."""
    with monkeypatch.context() as m:
        m.setattr(evaluate, "has_batch", lambda model: False)
        return evaluate.evaluate_chunk(sweep, k)


def _same(batched, single):
    """Every column equal, bit for bit (numbers) or exactly (text), but ``path``."""
    assert batched.keys() == single.keys()
    for name in batched:
        if name == "path":
            continue
        b, s = batched[name], single[name]
        if b.dtype.kind == "f":
            assert b.tobytes() == s.tobytes(), name
        else:
            assert list(b) == list(s), name


@pytest.mark.parametrize("samples", [6, pytest.param(60, marks=pytest.mark.slow)])
def test_a_batched_rigid_body_chunk_is_the_one_by_one_chunk_bit_for_bit(samples, monkeypatch):
    # tilt, spin and a moment vary; I1 = I2 = 3 with c off axis 3 has no closed form either
    sweep = parse_sweep({**RIGID, "sweep": {"random": {"samples": samples, "seed": 3, "theta": [0.1, 1.5],
                                                       "omega[2]": [5.0, 30.0], "I1": [2.0, 3.0]},
                                            "summary": ["period", "energy", "L_vertical"], "chunk": samples}})
    batched = evaluate.evaluate_chunk(sweep, 0)
    assert list(batched["path"]) == ["batch"] * samples and set(batched["status"]) == {"ok"}
    # the runs measured something: E and L·ẽ3 with estimates far below their values, the period or why not
    assert np.all(batched["energy_error"] < 1e-8 * np.abs(batched["energy"]))
    assert all(np.isfinite(p) or "period:" in n for p, n in zip(batched["period"], batched["notes"]))
    _same(batched, _one_by_one(sweep, 0, monkeypatch))


def test_a_point_that_blows_up_is_refused_alone_and_the_others_are_batched(monkeypatch):
    # ẍ = x³ from x0 > 0 at rest leaves every bound at t* = ∫ dx/√((x⁴ − x0⁴)/2) = 1.854/x0: within the run
    # (t ≤ 2) for x0 ≥ 0.93, after it for the smaller starts
    sweep = parse_sweep({"system": "lagrangian", "coordinates": ["x"], "lagrangian": "x_dot**2/2 + x**4/4",
                         "method": "integrate", "rtol": 1e-9, "initial": {"x": 0.1, "x_dot": 0.0},
                         "time": {"t_end": 2.0, "samples": 201}, "output": {"quantities": ["x"]},
                         "sweep": {"grid": {"x": [0.2, 1.2, 6]}, "summary": ["energy"]}})
    batched = evaluate.evaluate_chunk(sweep, 0)
    x = batched["x"]
    escaped = x >= 0.93
    assert escaped.any() and (~escaped).any()
    assert list(batched["path"]) == ["point" if e else "batch" for e in escaped]
    for e, status, energy in zip(escaped, batched["status"], batched["energy"]):
        if e:  # the planner's own refusal of that point
            assert status.startswith("refused: ") and "DOP853" in status and np.isnan(energy)
        else:
            assert status == "ok"
    # E = −x0⁴/4 at rest, to its estimate
    answered = ~escaped
    assert np.all(np.abs(batched["energy"][answered] + x[answered] ** 4 / 4)
                  <= batched["energy_error"][answered] + 4e-16)
    _same(batched, _one_by_one(sweep, 0, monkeypatch))
