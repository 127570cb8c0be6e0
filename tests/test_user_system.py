"""A system of one's own, registered from this test module without editing the package: run, derive, check.

The planar pendulum below is the README's worked example ("Your own system"), line for line: its
equation of motion is derived from L = ½ l² θ̇² + g l cos θ (per unit mass) with SymPy, compiled by
the integration driver, and registered.  The references are independent: the pendulum's exact
motion from rest, sin(θ/2) = k sn(K − t √(g/l) | k²) with k = sin(θ0/2) (Jacobi's elliptic
functions, mpmath at 30 digits), and its textbook equation θ̈ = −(g/l) sin θ.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechderive.cli import main

# --- the README's worked example -------------------------------------------------------------------
from mechderive.core.drift import drift
from mechderive.core.symbols import state_symbol
from mechderive.errors import InvalidInputError
from mechderive.solvers.driver import Term, integrate, integrate_to_rtol
from mechderive.systems import registry
from mechderive.systems.base import Derivation, Key, Quantity, Solved, System

theta, theta_dot, theta_ddot = (state_symbol(n) for n in ("theta", "theta_dot", "theta_ddot"))
g, l = sp.symbols("g l", positive=True)
L = l**2 * theta_dot**2 / 2 + g * l * sp.cos(theta)                 # per unit mass
p = sp.diff(L, theta_dot)                                              # Euler–Lagrange: d/dt ∂L/∂θ̇ = ∂L/∂θ
ACCELERATION = sp.solve(sp.diff(p, theta) * theta_dot + sp.diff(p, theta_dot) * theta_ddot - sp.diff(L, theta),
                        theta_ddot)[0]
ENERGY = sp.expand(p * theta_dot - L)
TERM = Term("planar_pendulum", lambda: ([theta_dot, ACCELERATION], [theta, theta_dot], [g, l]),
            invariants=lambda: [ENERGY], invariant_names=("energy",))


class PlanarPendulum(System):
    name = "planar_pendulum"
    summary = "a point mass on a massless rod of length l, swinging in a vertical plane"
    parameters = (Key("g", "m/s^2", "gravitational acceleration"), Key("l", "m", "length of the rod"))
    initial = (Key("theta", "rad", "angle from the downward vertical"), Key("theta_dot", "rad/s", "its rate"))
    quantities = (Quantity("theta", "rad", "angle from the downward vertical"),
                  Quantity("theta_dot", "rad/s", "angular velocity"),
                  Quantity("energy", "J/kg", "energy per unit mass, conserved"))

    def check_parameters(self, given, *, strict=True):
        for key in ("g", "l"):
            if not isinstance(given.get(key), (int, float)) or not given[key] > 0:
                raise InvalidInputError(f"scene key [parameters].{key}: expected a number > 0, got {given.get(key)!r}")
        return {"g": float(given["g"]), "l": float(given["l"])}

    def solve(self, scene, method, t):
        args = (scene.parameters["g"], scene.parameters["l"])
        y0 = (scene.initial["theta"], scene.initial["theta_dot"])
        traj, attempts = integrate_to_rtol(lambda tol: integrate(TERM, y0, t, args, rtol=tol),
                                           lambda tr: tr.error_estimate, scene.rtol)
        columns = {"theta": traj.y[:, 0], "theta_dot": traj.y[:, 1], "energy": traj.invariant("energy")}
        return Solved({q: columns[q] for q in scene.quantities},
                      {"error_estimate": traj.error_estimate, "integrator_attempts": attempts}, traj)

    def drift(self, scene, solved, t):
        E = solved.solution.invariant("energy")
        return {"energy": drift(E, scene.parameters["g"] * scene.parameters["l"], "g l")}

    def lagrangian_model(self):  # gives `check` its symbols and `derive … linearization` its equations
        return L, (theta,), (theta_dot,), (g, l)

    def derivations(self):
        return (Derivation("acceleration", "θ̈ from the Euler–Lagrange equation", "", lambda o: ACCELERATION,
                           lhs=lambda: theta_ddot, default=True),
                Derivation("energy", "E = θ̇ ∂L/∂θ̇ − L per unit mass", "", lambda o: ENERGY, default=True))


SCENE = """\
system = "planar_pendulum"
rtol = 1e-10
[parameters]
g = 9.81
l = 1.0
[initial]
theta = 2.0
theta_dot = 0.0
[time]
t_end = 10.0
samples = 101
[output]
quantities = ["theta", "energy"]
"""
# --- end of the README's example -------------------------------------------------------------------


@pytest.fixture
def pendulum(tmp_path):
    registry.register(PlanarPendulum(), replace=True)
    path = tmp_path / "pendulum.toml"
    path.write_text(SCENE)
    yield path
    registry.unregister("planar_pendulum")


def _exact_theta(t: np.ndarray, theta0: float, g_: float, l_: float) -> np.ndarray:
    """θ(t) from rest at θ0: sin(θ/2) = k sn(K − ω0 t | k²), k = sin(θ0/2), ω0 = √(g/l); 30 digits."""
    with mpmath.workdps(30):
        k = mpmath.sin(mpmath.mpf(theta0) / 2)
        m = k**2
        K = mpmath.ellipk(m)
        w0 = mpmath.sqrt(mpmath.mpf(g_) / mpmath.mpf(l_))
        return np.array([float(2 * mpmath.asin(k * mpmath.ellipfun("sn", K - w0 * mpmath.mpf(float(x)), m=m)))
                         for x in t])


def test_run_through_the_cli_and_the_planner(pendulum, tmp_path, capsys):
    out = tmp_path / "out.csv"
    assert main(["run", str(pendulum), "-o", str(out)]) == 0
    capsys.readouterr()
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    t, th, E = data.T
    # the scene asks rtol 1e-10; the run's own estimate is checked below: 1e-9 leaves ×10 for the
    # growth of the global error the estimate measures, over ~16 periods
    assert np.max(np.abs(th - _exact_theta(t, 2.0, 9.81, 1.0))) < 1e-9
    assert np.ptp(E) < 1e-9 * 9.81

    from mechderive.scenes.planner import run_scene
    from mechderive.scenes.schema import load_scene

    result = run_scene(load_scene(pendulum))
    assert result.report["system"] == "planar_pendulum" and result.report["method"] == "integrate"
    assert result.report["rtol_met"] is True and result.report["error_estimate"] <= 1e-10
    assert result.report["drift"]["energy"] < 1e-10


def test_derive_and_check_by_name_and_scene(pendulum, capsys):
    assert main(["derive", "planar_pendulum", "acceleration", "--format", "sympy"]) == 0
    capsys.readouterr()
    from mechderive.derive import derive

    acc = derive(str(pendulum), ["acceleration"], scene_parameters=True)["acceleration"]
    # exact rationals put in for g = 9.81, l = 1: the textbook equation holds exactly
    assert sp.simplify(acc + sp.Rational(981, 100) * sp.sin(theta)) == 0
    # check: the energy is conserved on every motion (on-shell), and the textbook equation holds
    assert main(["check", "planar_pendulum", "dt(energy) = 0"]) == 0
    assert "on-shell" in capsys.readouterr().out
    assert main(["check", str(pendulum), "theta_ddot = -g/l*sin(theta)"]) == 0
    assert main(["check", "planar_pendulum", "theta_ddot = -g*sin(theta)"]) == 1   # false: l is missing
    capsys.readouterr()
    # small oscillations about the bottom: ω = √(g/l) = √9.81, the textbook value
    assert main(["derive", str(pendulum), "linearization", "--at", "theta=0", "--parameters", "--format",
                 "json"]) == 0
    import json

    assert json.loads(capsys.readouterr().out)["frequencies"] == [pytest.approx(9.81**0.5, rel=1e-14)]


def test_a_bad_parameter_names_its_key(pendulum, tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.replace("l = 1.0", "l = -1.0"))
    assert main(["run", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err == "mechderive: error: scene key [parameters].l: expected a number > 0, got -1.0\n"
