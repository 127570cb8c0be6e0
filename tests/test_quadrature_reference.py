"""Self-checks of the 30-digit reference motions for the generic Lagrangian reduction (issue 16).

The file tests/reference/quadrature_cases.json is written by tests/reference/make_quadrature_reference.py
(hand-written equations of motion, mpmath.odefun).  Here, cheaply: every stored sample conserves the
Jacobi integral of the case's Lagrangian text (for the accelerating pivot, whose L depends on t, the
energy of the equivalent top with g + a) and the momenta of its cyclic coordinates, to 1e-25 relative;
and one short stretch of one case is regenerated from scratch.
"""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import mpmath
import pytest

REF = Path(__file__).resolve().parent / "reference"
DATA = json.loads((REF / "quadrature_cases.json").read_text())
CASES = {case["name"]: case for case in DATA["cases"]}
TOL = mpmath.mpf("1e-25")


def _script():
    spec = importlib.util.spec_from_file_location("make_quadrature_reference", REF / "make_quadrature_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _lagrangian(case):
    code = compile(case["lagrangian"], "<lagrangian>", "eval")
    params = {k: mpmath.mpf(v) for k, v in case["parameters"].items()}
    names = {"sin": mpmath.sin, "cos": mpmath.cos, "sqrt": mpmath.sqrt, "__builtins__": {}}

    def L(t, values):
        return eval(code, names, {**params, **values, "t": t})
    return L, params


def _cyclic(case):
    return [c for c in case["coordinates"] if not re.search(rf"\b{c}\b(?!_dot)", case["lagrangian"])]


def _integrals(case, t, q, q_dot):
    """(energy, {cyclic coordinate: momentum}) from the Lagrangian text, by numerical differentiation."""
    L, p = _lagrangian(case)
    values = {**q, **q_dot}

    def dL(v):
        return mpmath.diff(lambda x: L(t, {**values, v: x}), values[v])
    momenta = {c: dL(c + "_dot") for c in case["coordinates"]}
    h = sum(q_dot[c + "_dot"] * momenta[c] for c in case["coordinates"]) - L(t, values)
    if re.search(r"\bt\b", case["lagrangian"]):
        # accelerating pivot: h = T_rot - M (a t)²/2 + M g a t²/2 + M g l cosθ; the conserved energy is that
        # of the top with g + a, T_rot + M (g + a) l cosθ
        M, a, g, l = p["M"], p["a"], p["g"], p["l"]
        h += M * (a * t) ** 2 / 2 - M * g * a * t ** 2 / 2 + M * a * l * mpmath.cos(q["theta"])
    return h, {c: momenta[c] for c in _cyclic(case)}


def _mp(d):
    return {k: mpmath.mpf(v) for k, v in d.items()}


@pytest.mark.parametrize("name", sorted(CASES))
def test_samples_conserve_energy_and_momenta(name):
    case = CASES[name]
    mpmath.mp.dps = 40
    init = {k: mpmath.mpf(v) for k, v in case["initial"].items()}
    q0 = {c: init[c] for c in case["coordinates"]}
    qd0 = {c + "_dot": init[c + "_dot"] for c in case["coordinates"]}
    E0, P0 = _integrals(case, mpmath.mpf(0), q0, qd0)
    assert case["samples"]
    for s in case["samples"]:
        E, P = _integrals(case, mpmath.mpf(s["t"]), _mp(s["q"]), _mp(s["q_dot"]))
        assert abs(E - E0) <= TOL * max(abs(E0), 1), (s["t"], E - E0)
        for c in P:
            assert abs(P[c] - P0[c]) <= TOL * max(abs(P0[c]), 1), (s["t"], c, P[c] - P0[c])


def test_cases_and_format():
    mpmath.mp.dps = 40
    assert DATA["dps"] == 30
    assert len(CASES) == 16
    for case in DATA["cases"]:
        for s in case["samples"]:
            assert float(s["t"]) == mpmath.mpf(s["t"])  # times are exact doubles
            assert set(s["q"]) == set(case["coordinates"])
            assert set(s["q_dot"]) == {c + "_dot" for c in case["coordinates"]}
        assert set(case["advance"]) <= set(_cyclic(case)) | {"theta"}
        if case["period"] is not None:
            T = mpmath.mpf(case["period"])
            assert sum(mpmath.mpf(s["t"]) < T for s in case["samples"]) >= 6
            late = sum(mpmath.mpf(s["t"]) > 100 * T for s in case["samples"])
            assert late >= 3 or case["name"] == "spherical_conical"  # the conical one runs to t < 100
    assert CASES["pendulum_rotation"]["advance"]["theta"] == mpmath.nstr(2 * mpmath.pi, 30)


def test_regenerated_from_scratch():
    """The first two samples of the libration pendulum, integrated anew (30 digits), equal the file's."""
    script = _script()
    case = next(c for c in script.CASES if c["name"] == "pendulum_libration")
    stored = [s for s in CASES["pendulum_libration"]["samples"] if float(s["t"]) < 0.7]
    assert len(stored) == 2
    with mpmath.workdps(30):
        entry, _ = script.generate(case, report=lambda s: None, only_times=[float(s["t"]) for s in stored])
    mpmath.mp.dps = 40
    for new, old in zip(entry["samples"], stored):
        assert new["t"] == old["t"]
        for key in ("q", "q_dot"):
            for c in old[key]:
                value = mpmath.mpf(old[key][c])
                assert abs(mpmath.mpf(new[key][c]) - value) <= TOL * max(abs(value), 1)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["spherical_near_pole", "top_looping"])
def test_regenerated_whole_case(name):
    """A whole case (period, advances, every sample) regenerated at the working precision (~15 s each)."""
    script = _script()
    case = next(c for c in script.CASES if c["name"] == name)
    with mpmath.workdps(case.get("dps", script.WORK_DPS)):
        entry, _ = script.generate(case, report=lambda s: None)
    assert entry == CASES[name]
