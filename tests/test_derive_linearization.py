"""``mechderive derive SCENE.toml linearization --at ...``: small oscillations through the command line.

The reference is the spherical pendulum's known result for small oscillations about conical motion
at angle θ0 (precession Ω² = g / (l cos θ0)): ω² = Ω² (1 + 3 cos² θ0).
"""

import json
import math

import pytest

from mechderive.cli import main

SCENE = """\
system = "lagrangian"
coordinates = ["theta", "phi"]
lagrangian = "m*l**2/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + m*g*l*cos(theta)"
[parameters]
m = 1.0
l = 1.0
g = 9.81
[initial]
theta = 1.0
phi = 0.0
theta_dot = 0.0
phi_dot = 2.0
[time]
t_end = 10.0
samples = 11
[output]
quantities = ["theta"]
"""


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "spherical.toml"
    path.write_text(SCENE)
    return str(path)


def test_conical_pendulum_frequency(scene, capsys):
    theta0 = 0.7
    omega2 = 9.81 / math.cos(theta0)
    at = f"theta={theta0}, phi_dot=sqrt(9.81/cos({theta0}))"
    assert main(["derive", scene, "linearization", "--at", at, "--parameters", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # the frequency is printed to 12 digits: 1e-10 relative covers that rounding
    assert float(out["frequencies"][0]) == pytest.approx(math.sqrt(omega2 * (1 + 3 * math.cos(theta0) ** 2)),
                                                         rel=1e-10)
    assert out["stable"] is True


def test_not_a_steady_motion_is_refused_with_the_steady_rates(scene, capsys):
    assert main(["derive", scene, "linearization", "--at", "theta=0.7, phi_dot=2", "--parameters"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "relative equilibrium" in err and "phi_dot = " in err


def test_at_is_required_and_only_with_linearization(scene, capsys):
    assert main(["derive", scene, "linearization"]) == 2
    assert "expected --at" in capsys.readouterr().err
    assert main(["derive", scene, "energy", "--at", "theta=0"]) == 2
    assert "--at: expected with QUANTITY linearization only" in capsys.readouterr().err


HEAVY_MGL = """\
system = "heavy_top"
[parameters]
I1 = 1.0
I3 = 0.5
Mgl = 1.0
[initial]
theta = 0.0
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 5.0
[time]
t_end = 1.0
samples = 2
[output]
quantities = ["theta"]
"""


@pytest.mark.parametrize("spin", [5.0, 3.0])
def test_sleeping_top_given_with_mgl(tmp_path, capsys, spin):
    """(3.83) by hand: a = I3 ω3 / I1, α = 2 M g l / I1, u2 = a²/α − 1; the nutation about θ = 0 has
    ω² = (u2 − 1) M g l / (2 I1) — stable above I3 ω3 = 2 √(I1 M g l) (ω3 = 4 here), growing below."""
    path = tmp_path / "sleeping.toml"
    path.write_text(HEAVY_MGL)
    assert main(["derive", str(path), "linearization", "--parameters", "--at",
                 f"theta=0, phi_dot=0, psi_dot={spin}", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    a, alpha = 0.5 * spin / 1.0, 2.0 * 1.0 / 1.0
    w2 = (a**2 / alpha - 2.0) * 1.0 / 2.0
    if w2 > 0:
        assert out["stable"] is True and out["frequencies"] == [pytest.approx(math.sqrt(w2), rel=1e-12)]
    else:
        assert out["stable"] is False and out["growth_rates"] == [pytest.approx(math.sqrt(-w2), rel=1e-12)]
