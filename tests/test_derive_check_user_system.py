"""``derive`` and ``check`` on a system registered by a program, by name and through a scene file.

A planar pendulum (θ̈ = −(g/l) sin θ) is registered here, without editing the package: its
``derivations()`` derive the Euler–Lagrange equation from L = ½ l² θ̇² + g l cos θ (per unit
mass) with SymPy, and its ``check_system()`` names θ, θ̇, θ̈, g, l and the energy E.  The
references are written by hand in this file (the pendulum's textbook equation and energy) and
evaluated with mpmath at 30 digits; nothing compares the package with itself.
"""

from __future__ import annotations

import functools
import math
import tomllib

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechderive.cli import main
from mechderive.core.check_system import Quantity as CheckQuantity
from mechderive.core.check_system import System as CheckSystem
from mechderive.core.symbols import state_symbol
from mechderive.derive import derive, derive_entries, listing, render
from mechderive.errors import InvalidInputError
from mechderive.formulas import check
from mechderive.systems import registry
from mechderive.systems.base import Derivation, Key, Quantity, System

NAME = "toy_pendulum_dc"
th, th_d, th_dd = (state_symbol(n) for n in ("theta", "theta_dot", "theta_ddot"))
g, l = sp.symbols("g l", positive=True)
_LAGRANGIAN = l**2 * th_d**2 / 2 + g * l * sp.cos(th)


def _acceleration(o) -> sp.Expr:
    """θ̈ from the Euler–Lagrange equation d/dt ∂L/∂θ̇ = ∂L/∂θ, derived (not typed)."""
    p = sp.diff(_LAGRANGIAN, th_d)
    dt_p = sp.diff(p, th) * th_d + sp.diff(p, th_d) * th_dd
    return sp.solve(sp.Eq(dt_p, sp.diff(_LAGRANGIAN, th)), th_dd)[0]


def _energy(o) -> sp.Expr:
    return sp.expand(sp.diff(_LAGRANGIAN, th_d) * th_d - _LAGRANGIAN) / l**2


@functools.cache
def _table() -> CheckSystem:
    return CheckSystem(
        name=NAME, summary="planar pendulum", coordinates=("theta",), order=2,
        highest=lambda: {th_dd: _acceleration(None)},
        quantities=[CheckQuantity("theta", th, "state", "angle from the downward vertical"),
                    CheckQuantity("theta_dot", th_d, "state", "θ̇"),
                    CheckQuantity("theta_ddot", th_dd, "derivative", "θ̈"),
                    CheckQuantity("g", g, "parameter", "gravity"),
                    CheckQuantity("l", l, "parameter", "length"),
                    CheckQuantity("E", sp.Symbol("E", real=True), "defined", "energy per m l²",
                                  lambda s: _energy(None))],
        domain={}, motion="θ̈ from the Euler–Lagrange equation of L")


class Pendulum(System):
    name = NAME
    summary = "a planar pendulum (a test's own system)"
    parameters = (Key("g", "m/s^2", "gravity"), Key("l", "m", "length"))
    initial = (Key("theta", "rad", "angle"), Key("theta_dot", "rad/s", "rate"))
    quantities = (Quantity("theta", "rad", "angle"),)

    def derivations(self):
        return (Derivation("acceleration", "θ̈ from the Euler–Lagrange equation", "", _acceleration,
                           lhs=lambda: th_dd, default=True),
                Derivation("energy", "the energy per m l²", "", _energy, default=True),
                Derivation("lagrangian", "L per unit mass", "", lambda o: _LAGRANGIAN))

    def check_system(self):
        return _table()


SCENE = f"""\
system = "{NAME}"
[parameters]
g = 9.81
l = 2.0
[initial]
theta = 1.0
theta_dot = 0.0
[time]
t_end = 1.0
samples = 2
[output]
quantities = ["theta"]
"""


@pytest.fixture
def pendulum(tmp_path):
    registry.register(Pendulum(), replace=True)
    path = tmp_path / "pendulum.toml"
    path.write_text(SCENE)
    yield path
    registry.unregister(NAME)


def _reference_acceleration(theta: float, g_: float, l_: float) -> mpmath.mpf:
    """The textbook pendulum, θ̈ = −(g/l) sin θ, at 30 digits."""
    with mpmath.workdps(30):
        return -mpmath.mpf(g_) / mpmath.mpf(l_) * mpmath.sin(mpmath.mpf(theta))


def test_derive_by_name_matches_the_textbook_pendulum(pendulum, capsys):
    out = derive(NAME)
    assert list(out) == ["acceleration", "energy"]            # the defaults, in order
    f = sp.lambdify([th, g, l], out["acceleration"], "mpmath")
    for theta, g_, l_ in [(0.3, 9.81, 2.0), (2.9, 1.0, 0.5), (-1.2, 3.0, 7.0)]:
        with mpmath.workdps(30):
            got = f(mpmath.mpf(theta), mpmath.mpf(g_), mpmath.mpf(l_))
            # exact SymPy expression evaluated at 30 digits: agreement to 1e-25 is the arithmetic's
            assert abs(got - _reference_acceleration(theta, g_, l_)) < mpmath.mpf(10) ** -25
    assert [n for n, _, _ in listing(NAME)] == ["acceleration", "energy", "lagrangian"]
    assert main(["derive", NAME, "--list"]) == 0
    text = capsys.readouterr().out
    assert text.startswith(f"{NAME}: a planar pendulum") and " * acceleration" in text and "   lagrangian" in text
    assert main(["derive", NAME, "energy", "--format", "python"]) == 0
    ns: dict = {}
    exec(capsys.readouterr().out, ns)  # noqa: S102 - generated from our own derivation
    # E = θ̇²/2 − (g/l) cos θ by hand; float arithmetic of a 3-term expression: 1e-14 relative
    assert math.isclose(ns[f"{NAME}_energy"](9.81, 2.0, 0.7, 1.3), 1.3**2 / 2 - 9.81 / 2.0 * math.cos(0.7),
                        rel_tol=1e-14)


def test_derive_through_a_scene_file_with_its_parameters(pendulum, capsys):
    assert main(["derive", str(pendulum), "--list"]) == 0
    assert " * acceleration" in capsys.readouterr().out
    acc = derive(str(pendulum), ["acceleration"], scene_parameters=True)["acceleration"]
    assert acc.free_symbols == {th}                            # g = 9.81 and l = 2.0 put in, exactly
    assert sp.simplify(acc + sp.Rational(981, 200) * sp.sin(th)) == 0
    assert main(["derive", str(pendulum), "acceleration", "--parameters", "--set", "g=1"]) == 0
    out = capsys.readouterr().out
    assert "scene=pendulum.toml" in out and "parameters=from the scene" in out
    acc = derive(str(pendulum), ["acceleration"], values={"g": 1}, scene_parameters=True)["acceleration"]
    assert sp.simplify(acc + sp.sin(th) / 2) == 0                # values (--set g=1) win over the scene's g
    # without --parameters the symbols stay
    assert derive(str(pendulum), ["acceleration"])["acceleration"].free_symbols == {th, g, l}


def test_check_by_name_and_through_a_scene(pendulum, capsys):
    assert check("dt(E) = 0", NAME).verdict == "on-shell"       # the energy is conserved on every motion
    assert check("theta_ddot = -g/l*sin(theta)", NAME).verdict == "on-shell"
    assert check("E = theta_dot**2/2", NAME).verdict == "false"
    assert main(["check", str(pendulum), "dt(E) = 0"]) == 0
    assert "on-shell" in capsys.readouterr().out
    # with the scene's parameters, g/l = 4.905 exactly: the claim with 4.905 holds, with 4.9 it does not
    assert main(["check", str(pendulum), "theta_ddot = -4.905*sin(theta)", "--parameters"]) == 0
    capsys.readouterr()
    assert main(["check", str(pendulum), "theta_ddot = -4.9*sin(theta)", "--parameters"]) == 1
    assert main(["check", NAME, "--symbols"]) == 0
    assert "theta_ddot" in capsys.readouterr().out


def test_unknown_names_list_the_registered_system(pendulum, capsys):
    assert main(["derive", "nope"]) == 2
    assert NAME in capsys.readouterr().err
    with pytest.raises(InvalidInputError, match=f"expected a system among .*{NAME}.*got 'spinning'"):
        check("E = E", "spinning")
    assert main(["derive", "heavy_top", "--parameters"]) == 2
    assert "--parameters: expected a scene file" in capsys.readouterr().err


def test_a_malformed_system_is_refused_naming_it():
    class Bad(System):
        name = "bad_dc"

        def derivations(self):
            return (Derivation("not a name", "x", "", lambda o: sp.Integer(1)),)

    class Empty(System):
        name = "empty_dc"

    registry.register(Bad(), replace=True)
    registry.register(Empty(), replace=True)
    try:
        with pytest.raises(InvalidInputError, match="expected distinct identifiers as the names of bad_dc's"):
            derive("bad_dc")
        with pytest.raises(InvalidInputError, match="expected a system with derivations for derive, got 'empty_dc'"):
            derive("empty_dc")
        with pytest.raises(InvalidInputError, match="expected a system among free_top, heavy_top, rigid_body, got 'empty_dc'"):
            check("E = E", "empty_dc")
    finally:
        registry.unregister("bad_dc")
        registry.unregister("empty_dc")


def test_a_built_in_system_through_a_scene_file(tmp_path, capsys):
    """A free-top scene: its derivations and symbols, and its parameters put in on request."""
    from mechderive.scenes.builtin import scene_text

    text = scene_text("free_top_tumbling")
    path = tmp_path / "free.toml"
    path.write_text(text)
    entries = derive_entries(str(path), ["energy"], scene_parameters=True)
    # T = ½ Σ I_a ω_a² (3.46) with the scene's moments (read here with tomllib), exactly
    I = [sp.Rational(repr(tomllib.loads(text)["parameters"][f"I{a}"])) for a in (1, 2, 3)]
    w = [state_symbol(f"omega{a}") for a in (1, 2, 3)]
    assert sp.expand(entries[0].value - sum(i * x**2 for i, x in zip(I, w)) / 2) == 0
    claim = "T = " + " + ".join(f"{i}*omega{a}**2/2" for a, i in zip((1, 2, 3), I))
    assert main(["check", str(path), claim, "--parameters"]) == 0          # with the scene's moments: identity
    assert "identity" in capsys.readouterr().out
    assert main(["check", str(path), claim]) == 1                          # for every body: false
    assert "T = " in render(entries, "text", system="free_top")
