"""A scene in the units its own motion sets: exact powers of two, and what stays out of reach.

The scales of a motion are a choice of units.  For the heavy top the Lagrangian (3.62),
T - V = ½ I1 (θ̇² + φ̇² sin²θ) + ½ I3 (ψ̇ + φ̇ cos θ)² - M g l cos θ, is multiplied by a constant
when I1, I3 and M g l are (the motion is unchanged), and a change of the time unit t → t/c
multiplies the rates by c and leaves the motion the same if M g l is multiplied by c².
Euler's equations (3.33) of the free top are homogeneous in the moments and, with t → t/c,
ω → c ω, in time.  The falling cat's connection (3.87) depends on ratios of its masses and of
its lengths only, and the orientation after a shape change on the fraction of the loop done
(3.98), so its masses, lengths and duration are units as well.

So a scene whose numbers lie far outside the double range's comfortable middle (moments of
1e300 kg m², rates of 1e-300 rad/s, a cat of 1e300 kg) is solved as the same motion in units
where its moments and its fastest rate are of order one, and the output is converted back.
The units are powers of two, so every conversion is exact (short of overflow or subnormal
underflow, which are checked); a scene within 2^±64 of order one is solved as given, bit for
bit as before.

What no choice of units removes is refused with the scene keys it is about and the range that
is allowed, computed from the constraint itself:

* an output that is not a finite double in the scene's units (an energy of 1e600 J);
* a run longer than the method reaches — the closed forms count periods exactly up to 2^51
  (heavy top) or 2^50 (free top) of them, an integration follows at most
  :data:`MAX_INTEGRATED_RADIANS` of the motion's fastest rate;
* values whose ratio to the others is below what a double can hold at that scale;
* sample times that coincide (a ``t_end`` of a few subnormal steps).

:func:`scale_scene` chooses the units, :func:`check_samples` and :func:`check_invariants` refuse before
the solve, :func:`in_scene_units` converts the columns back (and refuses what overflows).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ..systems.heavy_top import parameters as heavy_top_parameters
from .schema import Scene

__all__ = ["Scaled", "scale_scene", "check_samples", "check_invariants", "in_scene_units", "keys_text",
           "MAX_INTEGRATED_RADIANS", "MAX_INTEGRATED_RADIANS_SCIPY", "DOUBLE_MAX", "OUTPUT_KEYS"]

DOUBLE_MAX = 1.7976931348623157e308
#: Scales within 2^±64 of one are solved as given (no conversion, so ordinary scenes are unchanged).
_COMFORTABLE = 64
#: The longest integration a scene may ask for, in radians of the motion's fastest rate: the
#: compiled DOP853 takes 60-600 right-hand sides per radian of a spinning top (measured: 6·10⁶ for
#: 10⁴ rad of a top at ψ̇ = 10³ rad/s, 6·10⁷ for 10⁶ rad at ψ̇ = 10⁵, rtol 1e-9, ~1 µs each), so
#: 2^18 rad is seconds to a few minutes of work, about where the stepper's own limit of 10⁷ steps
#: (:data:`mechderive.solvers.limits.MAX_STEPS`) would stop it anyway; a gyroscope at 100 rad/s for
#: 1000 s (10⁵ rad) is allowed.  SciPy's stepper (no C compiler) is ~100× slower per step: 2^14 rad.
#: Ctrl-C stops either within a second.
MAX_INTEGRATED_RADIANS = 2.0**18
MAX_INTEGRATED_RADIANS_SCIPY = 2.0**14

_RATE_KEYS = ("theta_dot", "phi_dot", "psi_dot")


@dataclass(frozen=True)
class Scaled:
    """A scene in its solver's units: ``scene`` (the original when ``identity``), times t' = t·2^``time``,
    and per output column the exponent e with value = value'·2^e (0 for absent names)."""

    original: Scene
    scene: Scene
    time: int = 0
    columns: dict[str, int] = field(default_factory=dict)
    rate: int = 0  # rad/s of the original per rad/s of the solver's units, as a power of two
    offsets: dict[str, float] = field(default_factory=dict)  # whole turns taken off an initial angle, added back

    @property
    def identity(self) -> bool:
        return self.scene is self.original

    def seconds(self, t_scaled: float) -> float:
        """A time of the solver's units in seconds."""
        return math.ldexp(t_scaled, -self.time)


def keys_text(table: str, names: list[str] | tuple[str, ...]) -> str:
    """``scene key(s) [table].a, [table].b`` for a message."""
    return ("scene keys " if len(names) > 1 else "scene key ") + ", ".join(f"[{table}].{n}" for n in names)


def _exponent(x: float) -> int:
    """e with 2^(e-1) <= |x| < 2^e (frexp's), 0 for 0."""
    return math.frexp(x)[1] if x else 0


def _exact_ldexp(x: float, e: int) -> float | None:
    """x·2^e if that is exact (normal or zero), else None."""
    if x == 0:
        return 0.0
    try:
        y = math.ldexp(x, e)
    except OverflowError:
        return None
    return y if y != 0 and abs(y) >= 2.2250738585072014e-308 and math.ldexp(y, -e) == x else None


def _moment_exponent(moments: tuple[float, ...]) -> int:
    """The unit of the moments: the largest's order, lowered where the smallest would leave the normal doubles."""
    return min(_exponent(max(moments)), _exponent(min(moments)) + 1021)


def _comfortable(*exponents: int) -> bool:
    return all(abs(e) <= _COMFORTABLE for e in exponents)


def _split_product(factors: list[float], shift: int) -> list[float] | None:
    """Factors f_i' with Π f_i' = Π f_i·2^shift, each f_i' a normal double (exact); None if impossible."""
    if any(f == 0 for f in factors):
        return [0.0 if f == 0 else math.copysign(1.0, f) for f in factors]
    parts = [math.frexp(f) for f in factors]
    total = sum(e for _, e in parts) + shift
    n = len(parts)
    out = []
    for i, (mant, _) in enumerate(parts):
        e = total // n + (1 if i < total % n else 0)
        y = _exact_ldexp(mant, e)
        if y is None:
            return None
        out.append(y)
    return out


def _scaled_time(t_end: float, j: int) -> float:
    """t_end in units of 2^-j s (the motion's fastest rate ~2^j rad/s); refused where t_end·2^j is no double.

    Such a run turns the body by ~10^308 rad: beyond every method (the closed forms count 2^51 periods
    at most, an integration follows :data:`MAX_INTEGRATED_RADIANS`), so the bound said is the closed
    forms' order, 2^52 rad at the fastest rate.
    """
    scaled = _exact_ldexp(t_end, j)
    if scaled is None and _exponent(t_end) + j < 0:
        raise InvalidInputError(f"scene key [time].t_end: expected at least ~{math.ldexp(1.0, -1021 - j):.3g} s for a "
                                f"motion whose fastest rate is ~2^{j} rad/s (a shorter run turns it by less than the "
                                f"smallest normal double, 2^-1022 rad), got {t_end!r}")
    if scaled is None:
        raise InvalidInputError(f"scene key [time].t_end: expected at most ~{math.ldexp(1.0, 52 - j):.3g} s for a "
                                f"motion whose fastest rate is ~2^{j} rad/s (~2^52 rad of it: the closed forms' "
                                f"reach), got {t_end!r}")
    return scaled


def _refuse_ratio(where: str, what: str) -> None:
    raise InvalidInputError(f"{where}: expected {what} within the double range (a ratio of at most ~2^1000 "
                            "between them), got values whose ratio is beyond it; no choice of units holds both")


# --------------------------------------------------------------------------------------------- tops

#: Initial φ, ψ of a heavy top beyond this (rad) are reduced mod 2π exactly before the solve: the closed
#: form adds φ0 to its phase in double-double, whose 2π carries ~1e-32 relative, so R would err ~|φ0|·1e-16.
_LARGEST_ANGLE = 4 * math.pi


def _reduce_angle(x: float) -> tuple[float, float]:
    """(x mod 2π in (-π, π], the whole turns taken off as the double nearest x minus it), exactly reduced."""
    import mpmath

    with mpmath.workprec(max(53, _exponent(x)) + 80):
        r = mpmath.fmod(mpmath.mpf(x), 2 * mpmath.pi)
        if r > mpmath.pi:
            r -= 2 * mpmath.pi
        elif r <= -mpmath.pi:
            r += 2 * mpmath.pi
        return float(r), float(mpmath.mpf(x) - r)


def _heavy_angles(scene: Scene, scaled: Scaled) -> Scaled:
    """``scaled`` with a large initial φ or ψ reduced mod 2π (the motion does not depend on them: both are
    cyclic (3.63)-(3.64)); the turns taken off are added back to the output columns of φ and ψ."""
    big = {k: scene.initial[k] for k in ("phi", "psi") if abs(scene.initial[k]) > _LARGEST_ANGLE}
    if not big:
        return scaled
    reduced, offsets = {}, {}
    for k, x in big.items():
        reduced[k], offsets[k] = _reduce_angle(x)
    work = dataclasses.replace(scaled.scene, initial={**scaled.scene.initial, **reduced}, strict=False)
    return dataclasses.replace(scaled, scene=work, offsets=offsets)


def _heavy(scene: Scene) -> Scaled:
    return _heavy_angles(scene, _heavy_units(scene))


def _heavy_units(scene: Scene) -> Scaled:
    p, s = scene.parameters, scene.initial
    I1, I3 = p["I1"], p["I3"]
    gravity = [p["Mgl"], 1.0, 1.0] if "Mgl" in p else [p["M"], p["g"], p["l"]]
    k = _moment_exponent((I1, I3))
    mgl_exp = sum(_exponent(f) for f in gravity) if all(gravity) else None
    rate_exps = [_exponent(s[r]) for r in _RATE_KEYS if s[r] != 0]
    # the fastest rate: the largest of the rates, and of √(M g l / I1), the pendulum's
    candidates = rate_exps + ([(mgl_exp - _exponent(I1)) // 2] if mgl_exp is not None else [])
    j = max(candidates) if candidates else 0
    if _comfortable(k, j) and (mgl_exp is None or _comfortable(mgl_exp)):
        return Scaled(scene, scene)
    where = keys_text("parameters", ("I1", "I3") + (("Mgl",) if "Mgl" in p else ("M", "g", "l")))
    I1s, I3s = _exact_ldexp(I1, -k), _exact_ldexp(I3, -k)
    if I1s is None or I3s is None:
        _refuse_ratio(keys_text("parameters", ("I1", "I3")), "the moments I1 and I3")
    g = _split_product(gravity, -k - 2 * j)
    if g is None:
        _refuse_ratio(where, "M g l against I1 and the rates")
    rates = {}
    for r in _RATE_KEYS:
        v = _exact_ldexp(s[r], -j)
        if v is None:
            # a rate below 2^-1022 of the fastest: as good as zero against it over any reachable time,
            # but not exactly: say so rather than change the motion
            _refuse_ratio(keys_text("initial", _RATE_KEYS), "theta_dot, phi_dot, psi_dot and √(M g l / I1)")
        rates[r] = v
    t_end = _scaled_time(scene.t_end, j)
    params = {"I1": I1s, "I3": I3s, **dict(zip(("M", "g", "l"), g))}
    scaled = dataclasses.replace(scene, parameters=params, initial={**s, **rates}, t_end=t_end, strict=False)
    columns = {**{q: j for q in ("theta_dot", "phi_dot", "psi_dot", "omega1", "omega2", "omega3")},
               "energy": k + 2 * j, "p_phi": k + j, "p_psi": k + j}
    return Scaled(scene, scaled, time=j, columns=columns, rate=j)


def _free(scene: Scene) -> Scaled:
    p, s = scene.parameters, scene.initial
    I = (p["I1"], p["I2"], p["I3"])
    w = s["omega"]
    k = _moment_exponent(I)
    nonzero = [_exponent(x) for x in w if x != 0]
    j = max(nonzero) if nonzero else 0
    if _comfortable(k, j) and _comfortable(*(_exponent(x) for x in I)):
        return Scaled(scene, scene)
    Is = [_exact_ldexp(x, -k) for x in I]
    if any(x is None for x in Is):
        _refuse_ratio(keys_text("parameters", ("I1", "I2", "I3")), "the moments")
    ws = [_exact_ldexp(x, -j) for x in w]
    if any(x is None for x in ws):
        _refuse_ratio("scene key [initial].omega", "the components of omega")
    t_end = _scaled_time(scene.t_end, j)
    scaled = dataclasses.replace(scene, parameters=dict(zip(("I1", "I2", "I3"), Is)),
                                 initial={**s, "omega": tuple(ws)}, t_end=t_end, strict=False)
    columns = {**{f"omega{a}": j for a in (1, 2, 3)}, **{f"L{a}": k + j for a in (1, 2, 3)},
               "L_norm": k + j, "energy": k + 2 * j}
    return Scaled(scene, scaled, time=j, columns=columns, rate=j)


# --------------------------------------------------------------------------------------------- the cat

def _cat(scene: Scene) -> Scaled:
    from ..systems.deformable.cat import BODY_PARAMETERS, DEFAULTS

    given = scene.parameters
    p = {**DEFAULTS, **given}
    lengths = [k for k in BODY_PARAMETERS if k != "half_mass"]
    a = _exponent(p["half_mass"])
    b = max(_exponent(p[k]) for k in lengths)
    c = _exponent(scene.t_end)
    if _comfortable(a, b, c, *(_exponent(p[k]) for k in lengths)):
        return Scaled(scene, scene)
    params = {k: v for k, v in given.items() if k not in BODY_PARAMETERS}  # peak_bend: an angle
    params["half_mass"] = _exact_ldexp(p["half_mass"], -a)
    for k in lengths:
        params[k] = _exact_ldexp(p[k], -b)
        if params[k] is None:
            _refuse_ratio(keys_text("parameters", lengths), "the lengths joint_offset, radius, half_length")
    t_end = _exact_ldexp(scene.t_end, -c)
    scaled = dataclasses.replace(scene, parameters=params, t_end=t_end)
    # L = Σ m r × ṙ: mass · length² / time
    return Scaled(scene, scaled, time=-c, columns={f"L{i}": a + 2 * b - c for i in (1, 2, 3)})


def scale_scene(scene: Scene) -> Scaled:
    """The scene in the units of its own motion (see the module docstring); the scene itself when comfortable."""
    legacy = {"heavy_top": _heavy, "free_top": _free, "falling_cat": _cat}.get(scene.system)
    return legacy(scene) if legacy is not None else scene.model.scale(scene)


# --------------------------------------------------------------------------------------------- reach

def check_samples(scene: Scene, t: np.ndarray) -> None:
    """Refuse sample times that coincide (a t_end of a few subnormal steps): the outputs are functions of t."""
    if scene.samples > 1 and not np.all(np.diff(t) > 0):
        fit = int(scene.t_end / np.spacing(scene.t_end)) + 1
        raise InvalidInputError(
            f"scene keys [time].t_end, [time].samples: expected distinct sample times (t_end / (samples - 1) at "
            f"least the spacing of doubles near t_end, {np.spacing(scene.t_end):.3g} s), got t_end = "
            f"{scene.t_end!r} with samples = {scene.samples}: at most {fit} samples fit in it")


def _refuse_overflow(scaled: Scaled, q: str, big: float, e: int) -> None:
    """Refuse output ``q`` whose size ``big`` (solver's units) times 2^e leaves the doubles: say how large it is
    and, where it grows with the rates (as I ω or I ω²), how fast the scene may spin at these moments."""
    b = int(np.frexp(big)[1]) + e
    if b <= 1024:
        return
    power = 2 if _SCALES_AS[q].startswith("I ω²") else 1
    fastest = _largest_rate(scaled)
    rates = "" if q in _CAT_L or fastest == 0 else \
        f"; at these moments the rates must stay below ~{fastest * 2.0 ** ((1024 - b) / power):.3g} rad/s"
    raise InvalidInputError(f"{OUTPUT_KEYS[scaled.original.system]}: expected the output {q} within the double range "
                            f"(|{q}| ≤ {DOUBLE_MAX:.4g}), got |{q}| ~10^{b * 0.30103:.0f} for these values; {q} scales "
                            f"as {_SCALES_AS[q]}{rates}")


def _largest_rate(scaled: Scaled) -> float:
    s = scaled.original.initial
    rates = s.get("omega", ()) if scaled.original.system == "free_top" else [s.get(k, 0.0) for k in _RATE_KEYS]
    return float(max((abs(r) for r in rates), default=0.0))


def check_invariants(scaled: Scaled) -> None:
    """Refuse up front a requested conserved quantity (E, p_φ, p_ψ, |L|) that is no double in the scene's units."""
    if scaled.identity:
        return
    work, wanted = scaled.scene, set(scaled.original.quantities)
    if work.system == "heavy_top":
        p, s = heavy_top_parameters.check_params(work.parameters, strict=False), work.initial
        th, w3 = s["theta"], s["psi_dot"] + s["phi_dot"] * np.cos(s["theta"])
        E = 0.5 * (p["I1"] * (s["theta_dot"] ** 2 + (s["phi_dot"] * np.sin(th)) ** 2) + p["I3"] * w3 ** 2) \
            + p["M"] * p["g"] * p["l"] * np.cos(th)
        values = {"energy": E, "p_psi": p["I3"] * w3,
                  "p_phi": p["I1"] * np.sin(th) ** 2 * s["phi_dot"] + p["I3"] * w3 * np.cos(th)}
    elif work.system == "free_top":
        I, w = np.array([work.parameters[k] for k in ("I1", "I2", "I3")]), np.array(work.initial["omega"])
        values = {"energy": 0.5 * float(np.dot(I, w * w)), "L_norm": float(np.linalg.norm(I * w))}
    else:
        return
    for q, v in values.items():
        if q in wanted and v != 0 and scaled.columns.get(q, 0):
            _refuse_overflow(scaled, q, abs(float(v)), scaled.columns[q])


def in_scene_units(scaled: Scaled, cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The columns in the scene's units; refused, naming the keys they scale with, where they leave the doubles."""
    if scaled.identity:
        return cols
    out = {}
    for q, col in cols.items():
        e = scaled.columns.get(q, 0)
        if q in scaled.offsets:
            out[q] = col + scaled.offsets[q]
            continue
        if e == 0:
            out[q] = col
            continue
        big = float(np.nanmax(np.abs(np.where(np.isfinite(col), col, 0.0)), initial=0.0))
        if big > 0:
            _refuse_overflow(scaled, q, big, e)
        out[q] = np.ldexp(col, e)
    return out


_CAT_L = ("L1", "L2", "L3")
OUTPUT_KEYS = {"heavy_top": "scene keys [parameters].I1, [parameters].I3, [initial].theta_dot, [initial].phi_dot, "
                             "[initial].psi_dot",
                "free_top": "scene keys [parameters].I1, [parameters].I2, [parameters].I3, [initial].omega",
                "falling_cat": "scene keys [parameters].half_mass, [parameters].joint_offset, [parameters].radius, "
                               "[parameters].half_length, [time].t_end"}
_SCALES_AS = {**{q: "the rates" for q in ("theta_dot", "phi_dot", "psi_dot", "omega1", "omega2", "omega3")},
              "energy": "I ω² (moments times rates squared, and M g l)", "p_phi": "I ω (moments times rates)",
              "p_psi": "I ω (moments times rates)", "L_norm": "I ω (moments times rates)",
              **{f"L{a}": "I ω (moments times rates; the cat's: mass · length² / t_end)" for a in (1, 2, 3)}}
