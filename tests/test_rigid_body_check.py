"""``check`` and small oscillations for ``system = "rigid_body"`` (the Euler–Poisson equations in (ω, γ)).

References: the conservation of E and L·ẽ3 is the chapter's (3.64)-(3.65) generalised; the spectrum
of the sleeping asymmetric top is compared with the eigenvalues of a Jacobian taken by central
differences of Euler–Poisson equations written by hand in this file.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from mechderive.cli import main

SCENE = """\
system = "rigid_body"
[parameters]
I1 = 2.0
I2 = 3.0
I3 = 4.0
M = 1.0
g = 9.81
center_of_mass = [0.0, 0.0, 0.5]
[initial]
omega = [0.0, 0.0, 20.0]
[time]
t_end = 1.0
samples = 2
[output]
quantities = ["omega1"]
"""


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "body.toml"
    path.write_text(SCENE)
    return str(path)


@pytest.mark.parametrize("claim", ["dt(energy) = 0", "dt(L_vertical) = 0", "dt(R13**2 + R23**2 + R33**2) = 0"])
def test_conserved_on_every_motion(claim, capsys):
    assert main(["check", "rigid_body", claim]) == 0
    assert capsys.readouterr().out.startswith("on-shell")


def test_the_free_euler_equation_is_false_under_gravity(capsys):
    assert main(["check", "rigid_body", "I1*dt(omega1) = (I2 - I3)*omega2*omega3"]) == 1
    assert "counterexample" in capsys.readouterr().out


def _euler_poisson(x: np.ndarray, I=(2.0, 3.0, 4.0), Mg=9.81, c=(0.0, 0.0, 0.5)) -> np.ndarray:
    """By hand: I ω̇ = (I ω) × ω + c × (−M g γ) in body components, γ̇ = γ × ω."""
    w, gam = x[:3], x[3:]
    I = np.array(I)
    wdot = (np.cross(I * w, w) + np.cross(np.array(c), -Mg * gam)) / I
    return np.concatenate([wdot, np.cross(gam, w)])


def test_sleeping_asymmetric_top_spectrum(scene, capsys):
    at = "omega1=0, omega2=0, omega3=20, R13=0, R23=0, R33=1"
    assert main(["derive", scene, "linearization", "--parameters", "--at", at, "--format", "json"]) == 0
    got = sorted(json.loads(capsys.readouterr().out)["frequencies"])
    x0, h = np.array([0, 0, 20.0, 0, 0, 1.0]), 1e-5
    J = np.column_stack([(_euler_poisson(x0 + h * e) - _euler_poisson(x0 - h * e)) / (2 * h) for e in np.eye(6)])
    ref = sorted({round(abs(z.imag), 9) for z in np.linalg.eigvals(J) if abs(z) > 1e-6})
    # the hand-written system is polynomial of degree 2: central differences are exact up to rounding
    # of ~1e-16/h² · |x|² ≈ 1e-9 relative
    assert got == pytest.approx(ref, rel=1e-8)
