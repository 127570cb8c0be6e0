"""The falling cat (section 3.7) as a :class:`~mechderive.systems.base.System`.

A cat dropped upside down with zero angular momentum turns over by changing its shape: the body
turns by the holonomy P̃ exp ∮ Ω_A dx^A (3.98) of its shape loop (:mod:`.cat`).  Its parameters
(``half_mass joint_offset radius half_length peak_bend``) are all optional and open: a module may
add names (:func:`mechderive.scenes.schema.register_system_parameters`).  There is no initial
state (the cat starts at rest, straight, R = 1).  Drift: L, which must stay 0, against the angular
momentum its turn carries, max_t |Ĩ Ω|.

Importing this module derives nothing and imports no SymPy.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np

from ...errors import InvalidInputError, MechDeriveError
from ..base import Key, Quantity, Solved, System
from ..scene_keys import at, check_keys, number, rename_keys

if TYPE_CHECKING:  # pragma: no cover
    from ...core.drift import Drift
    from ...scenes.schema import Scene
    from ..scaling import Scaled

__all__ = ["FallingCat", "SYSTEM", "FALLING_CAT_PARAMETERS"]

_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))

#: The falling cat's own parameters, all optional: lengths and a mass > 0, ``peak_bend`` in (0, π)
#: (:func:`mechderive.systems.deformable.cat.check_cat_parameters` validates them).
FALLING_CAT_PARAMETERS: tuple[str, ...] = ("half_mass", "joint_offset", "radius", "half_length", "peak_bend")
_RANGES: dict[str, tuple[str, Callable[[float], bool]]] = {
    **{k: ("a number > 0", lambda x: x > 0) for k in FALLING_CAT_PARAMETERS},
    "peak_bend": ("a number in (0, π) (rad: the halves must not fold through each other)",
                  lambda x: 0 < x < math.pi),
}

_PARAMETERS = (
    Key("half_mass", "kg", "mass of each half of the body", required=False),
    Key("joint_offset", "m", "offset of the joint from each half's axis", required=False),
    Key("radius", "m", "radius of each half (rings of point masses)", required=False),
    Key("half_length", "m", "half the length of each half", required=False),
    Key("peak_bend", "rad", "largest bend of the shape loop, in (0, π) (default: the bend that turns the cat over)",
        required=False, scales_as="angle"),
)
_QUANTITIES = (
    *(Quantity(q, "1", f"rotation matrix entry {q} of the body frame") for q in _R_NAMES),
    *(Quantity(f"q{i}", "1", f"unit quaternion of R, component q{i} (sign kept continuous)") for i in range(4)),
    Quantity("flip_angle", "rad", "angle the body has turned by (π: turned over)"),
    *(Quantity(f"L{a}", "kg m^2/s", f"total angular momentum, component L{a} (zero up to the error)",
               scales_as="angular momentum") for a in (1, 2, 3)),
    Quantity("shape_bend", "rad", "the shape loop's bend x¹(t)"),
    Quantity("shape_swivel", "rad", "the shape loop's swivel x²(t)"),
)
_OUTPUT_KEYS = ("scene keys [parameters].half_mass, [parameters].joint_offset, [parameters].radius, "
                "[parameters].half_length, [time].t_end")
_SCALES_AS = {f"L{a}": "I ω (moments times rates; the cat's: mass · length² / t_end)" for a in (1, 2, 3)}


def _name_keys(exc: MechDeriveError, names: tuple[str, ...]) -> MechDeriveError:
    """``exc`` re-worded to start with the ``[parameters]`` keys it is about (unless it names its keys already)."""
    return exc if str(exc).startswith("scene ") else rename_keys(exc, "parameters", names)


def _integrate(scene: "Scene", t: np.ndarray) -> Solved:
    from ..scaling import units_of
    from .cat import cat_columns, falling_cat

    scaled = units_of(scene)
    try:
        cat = falling_cat(scene.parameters or None, duration=scene.t_end, samples=scene.samples, rtol=scene.rtol)
    except InvalidInputError as exc:
        raise _name_keys(exc, FALLING_CAT_PARAMETERS) from exc
    data = cat_columns(cat)
    cols = {q: np.asarray(data[q]) for q in scene.quantities}
    L = np.stack([data["L1"], data["L2"], data["L3"]], axis=-1)
    info = {"error_estimate": float(cat.error_estimate),
            "error_estimate_kind": "distance of R to a rerun at a 10× tighter tolerance (rad)",
            "integrator": {"c": "DOP853 (compiled C)", "magnus": "Magnus (order 4, adaptive)"}.get(cat.backend,
                                                                                                 cat.backend),
            "peak_bend": cat.peak_bend,
            "max_abs_L": float(np.ldexp(np.max(np.abs(L)), scaled.columns.get("L1", 0)))}
    return Solved(cols, info, cat)


def _units(scene: "Scene") -> "Scaled":
    """The units of the motion: the connection (3.87) depends on ratios of the masses and of the lengths
    only, and the orientation after a shape change on the fraction of the loop done (3.98), so the
    masses, lengths and duration are units as well."""
    from .. import scaling as u
    from .cat import BODY_PARAMETERS, DEFAULTS

    given = scene.parameters
    p = {**DEFAULTS, **given}
    lengths = [k for k in BODY_PARAMETERS if k != "half_mass"]
    a = u.exponent(p["half_mass"])
    b = max(u.exponent(p[k]) for k in lengths)
    c = u.exponent(scene.t_end)
    said = {"keys": _OUTPUT_KEYS, "scales": _SCALES_AS}
    if u.comfortable(a, b, c, *(u.exponent(p[k]) for k in lengths)):
        return u.Scaled(scene, scene, **said)
    params = {k: v for k, v in given.items() if k not in BODY_PARAMETERS}  # peak_bend: an angle
    params["half_mass"] = u.exact_ldexp(p["half_mass"], -a)
    for k in lengths:
        params[k] = u.exact_ldexp(p[k], -b)
        if params[k] is None:
            u.refuse_ratio(u.keys_text("parameters", lengths), "the lengths joint_offset, radius, half_length")
    t_end = u.exact_ldexp(scene.t_end, -c)
    scaled = dataclasses.replace(scene, parameters=params, t_end=t_end)
    # L = Σ m r × ṙ: mass · length² / time
    return u.Scaled(scene, scaled, time=-c, columns={f"L{i}": a + 2 * b - c for i in (1, 2, 3)},
                    note=(f"solved with masses, lengths and time in units of the scene's own (exact powers of two; "
                          f"t = t'·2^{c}); outputs converted back"), **said)


_SCENE = """\
# The falling cat (section 3.7): L = 0 throughout, yet the body ends up rotated.
system = "falling_cat"

[time]
t_end = 1.0
samples = 201

[output]
quantities = ["flip_angle", "L1", "L2", "L3"]
"""


class FallingCat(System):
    """A deformable body turning at zero angular momentum by a loop of shape changes (3.7)."""

    name = "falling_cat"
    free_times = False  # the shape loop spans [0, t_end]: the flip is defined over its own duration
    summary = "a cat dropped upside down with zero angular momentum turns over by changing shape"
    section = "3.7"
    parameters = _PARAMETERS
    open_parameters = True
    quantities = _QUANTITIES
    methods = ("integrate",)
    #: measured: 11,250 bytes per sample of maxrss growth from 4·10⁴ samples (its L is taken by differences
    #: over a 9-point stencil of rotations per sample)
    bytes_per_sample = 12_500
    plot_quantities = ("flip_angle",)

    def check_parameters(self, given: Mapping[str, Any], *, strict: bool = True) -> dict[str, Any]:
        """Each given parameter a finite number (its own range for the cat's: :data:`FALLING_CAT_PARAMETERS`),
        and a body whose inertia is invertible; all are optional."""
        names = tuple(k.name for k in self.parameters)
        check_keys(given, "parameters", names, (), "parameter for system 'falling_cat'")
        p = {}
        for k in (k for k in names if k in given):  # registered names: any finite number
            expected, valid = _RANGES.get(k, ("a finite number", lambda x: True))
            p[k] = number(at("parameters", k), given[k], expected=expected, valid=valid)
        from .cat import check_cat_parameters  # no SymPy: only the checks

        try:
            check_cat_parameters({k: v for k, v in p.items() if k in FALLING_CAT_PARAMETERS})
        except InvalidInputError as exc:
            raise rename_keys(exc, "parameters", names) from exc
        return p

    def check_initial(self, given: Mapping[str, Any], parameters: Mapping[str, Any]) -> dict[str, Any]:
        """None: the cat starts at rest, straight, with R = 1."""
        check_keys(given, "initial", (), (), "initial value for system 'falling_cat'")
        return {}

    def scale(self, scene: "Scene") -> "Scaled":
        # the parameters (open in the schema) checked in the scene's own units, so that the bounds the
        # messages state are the scene's, before they are scaled
        from .cat import check_cat_parameters

        try:
            check_cat_parameters(scene.parameters or None)
        except InvalidInputError as exc:
            raise _name_keys(exc, FALLING_CAT_PARAMETERS) from exc
        return _units(scene)

    def solve(self, scene: "Scene", method: str, t: np.ndarray) -> Solved:
        return _integrate(scene, t)

    def drift(self, scene: "Scene", solved: Solved, t: np.ndarray) -> dict[str, "Drift"]:
        """L (zero: the cat is dropped at rest) against the angular momentum its turn carries, max_t |Ĩ Ω|.

        The shape change x(t) turns the body at Ω = Ω_A ẋ^A (3.92) with angular momentum Ĩ Ω; the
        shape motion carries -Ĩ Ω, so that L = 0 — a cancellation of terms of this size.
        """
        from ...core.drift import drift
        from .cat import cat_connection, cat_loop

        solution = solved.solution
        conn = cat_connection(solution.parameters)
        loop = cat_loop(solution.peak_bend, scene.t_end)
        x = loop.shape(solution.t)
        turn = np.einsum("...ab,...b->...a", conn.inertia(x), conn.angular_velocity(x, loop.velocity(solution.t)))
        scale = float(np.max(np.linalg.norm(turn, axis=-1)))
        return {"L": drift(solution.angular_momentum, scale, "max_t |Ĩ Ω|", reference=np.zeros(3))}

    def derivations(self) -> tuple:
        from .derive_entries import derivations

        return derivations()

    def check_system(self) -> Any:
        from .derive_entries import check_system

        return check_system()

    def plot(self, result: Any, figure: Any) -> bool:
        """The flip angle against t."""
        figure.set_size_inches(6.5, 4.8)
        ax = figure.add_subplot(1, 1, 1)
        ax.plot(result.t, result.columns["flip_angle"], color="C0")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("flip angle (rad)")
        ax.set_title("rotation of the body at zero angular momentum")
        ax.grid(True, alpha=0.3)
        return True

    def example_scene(self) -> str:
        return _SCENE

    def builtin_scenes(self) -> tuple[tuple[str, str, str], ...]:
        return (("falling_cat", "a cat dropped upside down with zero angular momentum turns over by changing shape "
                 "(3.7)", _SCENE),)


SYSTEM = FallingCat()
