"""Built-in scenes: ready-made TOML scene files with a one-line description each.

The texts are ordinary scene files (:mod:`.schema`), so ``scene_text(name)`` can be
saved, edited and run again.  The heavy tops share the top of the chapter's examples:
I1 = 1 (about the pivot), I3 = 0.5, M g l = 1 (M = 0.1, g = 10, l = 1); its sleeping
threshold (3.83) is ω3 = 2 √(I1 M g l) / I3 = 4 rad/s.  The free tops have I = (1, 2, 3).
The gyroscope is the textbook's horizontal one, given with ``Mgl`` (only M g l enters the motion).

>>> [name for name, _ in list_scenes()][:3]
['default', 'heavy_top_looping', 'heavy_top_hanging']
>>> load_builtin("default").t_end
35.177
"""

from __future__ import annotations

from .schema import Scene, load_scene
from ..errors import InvalidInputError

__all__ = ["list_scenes", "scene_text", "load_builtin"]

_HEAVY_TOP = """\
[parameters]            # I1 about the pivot; M g l = 1
I1 = 1.0
I3 = 0.5
M = 0.1
g = 10.0
l = 1.0
"""

_FREE_TOP = """\
[parameters]
I1 = 1.0
I2 = 2.0
I3 = 3.0
"""

# name -> (description, TOML text)
_SCENES: dict[str, tuple[str, str]] = {
    "default": (
        "heavy top let go from rest at θ = 0.5 with spin 5 rad/s: cusped nutation (3.6.1), 10 nutation periods",
        f"""\
# A heavy top let go at θ0 = 0.5 with θ̇ = φ̇ = 0 and ψ̇ = ω3 = 5 rad/s (section 3.6.1):
# θ nutates between 0.5 and 0.7576 with period 3.5177 s; the apex traces cusps.
system = "heavy_top"
method = "auto"

{_HEAVY_TOP}
[initial]
theta = 0.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 5.0

[time]
t_end = 35.177          # 10 nutation periods
samples = 2001

[output]
quantities = ["theta", "phi", "psi"]
"""),
    "heavy_top_looping": (
        "heavy top pushed against its spin: φ̇ changes sign and the apex draws loops (figure 44)",
        f"""\
# Let go at θ0 = 0.5 with φ̇ = -0.5 rad/s against the spin ψ̇ = 5 rad/s: b - a u changes sign
# between the turning points θ = 0.5 and θ ≈ 1.095, so the apex path loops (figure 44, middle).
system = "heavy_top"

{_HEAVY_TOP}
[initial]
theta = 0.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = -0.5
psi_dot = 5.0

[time]
t_end = 20.0
samples = 2001

[output]
quantities = ["theta", "phi", "psi", "apex_x", "apex_y", "apex_z"]
"""),
    "heavy_top_hanging": (
        "heavy top let go below the pivot at θ = 2.5 with spin 5 rad/s",
        f"""\
# Let go below the horizontal, θ0 = 2.5, spin ψ̇ = 5 rad/s: θ nutates between 2.5 and about 2.638.
system = "heavy_top"

{_HEAVY_TOP}
[initial]
theta = 2.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 5.0

[time]
t_end = 20.0
samples = 2001

[output]
quantities = ["theta", "phi", "psi", "apex_x", "apex_y", "apex_z"]
"""),
    "sleeping_top": (
        "upright heavy top (θ = 0) spinning at 6 rad/s, above the threshold 2√(I1 M g l)/I3 = 4 rad/s: stable",
        f"""\
# A sleeping top (3.6.3): θ = θ̇ = 0 with ω3 = 6 rad/s > 2 √(I1 M g l) / I3 = 4 rad/s, so it stays up.
# φ and ψ are not separately defined at θ = 0; ask for the apex instead.
system = "heavy_top"

{_HEAVY_TOP}
[initial]
theta = 0.0
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 6.0

[time]
t_end = 10.0
samples = 1001

[output]
quantities = ["theta", "energy", "apex_x", "apex_y", "apex_z"]
"""),
    "free_top_tumbling": (
        "free asymmetric top, I = (1, 2, 3), ω(0) = (1, 0.5, 1): ω circles e3 (L² > 2 T I2), 100 s",
        f"""\
# A free asymmetric top (3.4.4): ω moves on a closed polhode, the body tumbles.
system = "free_top"

{_FREE_TOP}
[initial]
omega = [1.0, 0.5, 1.0]  # body frame, rad/s; Euler angles default to 0 (R(0) = 1)

[time]
t_end = 100.0
samples = 2001

[output]
quantities = ["omega1", "omega2", "omega3", "R11", "R12", "R13", "R21", "R22", "R23", "R31", "R32", "R33"]
"""),
    "free_top_near_separatrix": (
        "free top with L² - 2 T I2 = 1e-10 L²: a polhode just on the e3 side of the separatrix (3.4.4, figure 33)",
        f"""\
# L² - 2 T I2 = Σ I_a (I_a - I2) ω_a² = 3 ω3² - ω1² is set to 1.00000036e-10 L² by the choice of ω3
# (ω3 = sqrt((ω1² (1 + ε) + 4 ε ω2²) / (3 (1 - 3 ε))), ε = 1e-10, rounded to the nearest double).
system = "free_top"

{_FREE_TOP}
[initial]
omega = [1.0, 0.5, 0.5773502693339634]

[time]
t_end = 100.0
samples = 4001

[output]
quantities = ["omega1", "omega2", "omega3", "energy", "L_norm"]
"""),
    "tennis_racket": (
        "spin about the intermediate axis with a 1e-6 perturbation: the tennis-racket flip (3.4.3)",
        f"""\
# Spin ω2 = 1 rad/s about the intermediate axis, ω1 = ω3 = 1e-6: unstable (3.4.3); the perturbation
# grows like exp(ω2 √((I2 - I1)(I3 - I2) / (I1 I3)) t) = exp(0.577 t) and the body flips over.
system = "free_top"

{_FREE_TOP}
[initial]
omega = [1e-6, 1.0, 1e-6]

[time]
t_end = 100.0
samples = 4001

[output]
quantities = ["omega1", "omega2", "omega3"]
"""),
    "gyroscope": (
        "horizontal gyroscope let go at θ = π/2 (p_φ = 0), spin 300 rad/s: dips 8.34° and precesses at 2.59 rad/s "
        "(≈ M g l / (I3 ω3) = 2.62)",
        """\
# The horizontal gyroscope (3.6.2): let go at θ = π/2 with φ̇ = 0, so p_φ = 0 and the apex starts at a cusp.
# It dips to θ = 98.34° and nutates with period 0.1752 s while precessing at 2.588 rad/s on average,
# near the leading-order M g l / (I3 ω3) = 2.616 rad/s.  Only M g l enters the motion: given as Mgl
# (M = 1 kg, g = 9.81 m/s², l = 0.1 m; I1 = 0.010625 kg m² about the pivot, I3 = 0.00125 kg m²).
system = "heavy_top"

[parameters]
I1 = 0.010625
I3 = 0.00125
Mgl = 0.981

[initial]
theta = 1.5707963267948966
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 300.0

[time]
t_end = 1.7522257106587  # 10 nutation periods
samples = 2001

[output]
quantities = ["theta", "phi", "apex_x", "apex_y", "apex_z", "p_phi"]
"""),
    "falling_cat": (
        "a cat dropped upside down with zero angular momentum turns over by changing shape (3.7)",
        """\
# The falling cat (section 3.7): L = 0 throughout, yet the body ends up rotated.
system = "falling_cat"

[time]
t_end = 1.0
samples = 201

[output]
quantities = ["flip_angle", "L1", "L2", "L3"]
"""),
}


def list_scenes() -> list[tuple[str, str]]:
    """The built-in scenes as ``(name, description)`` pairs, in a fixed order."""
    return [(name, description) for name, (description, _) in _SCENES.items()]


def scene_text(name: str) -> str:
    """The TOML text of the built-in scene ``name``.

    >>> scene_text("nope")
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: unknown built-in scene 'nope': expected one of default, ...
    """
    if not isinstance(name, str) or name not in _SCENES:
        raise InvalidInputError(f"unknown built-in scene {name!r}: expected one of {', '.join(_SCENES)}")
    return _SCENES[name][1]


def load_builtin(name: str) -> Scene:
    """The built-in scene ``name``, parsed and checked, with ``Scene.name == name``."""
    return load_scene(scene_text(name), name=name)
