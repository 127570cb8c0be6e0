"""A scene in the units its own motion sets: exact powers of two, and what stays out of reach.

The scales of a motion are a choice of units: each system says how its scene changes with them
(:meth:`mechderive.systems.base.System.scale`, e.g. the heavy top's Lagrangian (3.62) is multiplied
by a constant when its moments and M g l are, and a change of the time unit multiplies the rates);
this module holds what every system's choice shares.

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

:func:`scale_scene` asks the scene's system for its units (the system refuses there, with
:func:`check_outputs`, a conserved quantity out of range), :func:`check_samples` refuses before the
solve, :func:`in_scene_units` converts the columns back (and refuses what overflows).  The helpers
(:func:`exponent`, :func:`exact_ldexp`, :func:`split_product`, :func:`scaled_time`, ...) are the
systems' for building their :class:`Scaled`.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Iterator

import numpy as np

from ..errors import InvalidInputError

if TYPE_CHECKING:  # pragma: no cover
    from ..scenes.schema import Scene

__all__ = ["Scaled", "scale_scene", "check_samples", "check_outputs", "check_integration_length", "in_scene_units",
           "keys_text", "units_of", "solving_in", "exponent", "exact_ldexp", "moment_exponent", "comfortable",
           "split_product", "scaled_time", "refuse_ratio", "reduce_angle", "MAX_INTEGRATED_RADIANS",
           "MAX_INTEGRATED_RADIANS_SCIPY", "DOUBLE_MAX"]

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
    #: what the system says of its units, for messages and the report: the scene keys the outputs' sizes depend
    #: on; per scaled output how it scales ("I ω (moments times rates)"); the fastest initial rate (rad/s, 0 where
    #: the outputs do not grow with a rate); the report's ``units`` note ("" for the default wording)
    keys: str = ""
    scales: dict[str, str] = field(default_factory=dict)
    fastest: float = 0.0
    note: str = ""

    @property
    def identity(self) -> bool:
        return self.scene is self.original

    def seconds(self, t_scaled: float) -> float:
        """A time of the solver's units in seconds."""
        return math.ldexp(t_scaled, -self.time)


def keys_text(table: str, names: list[str] | tuple[str, ...]) -> str:
    """``scene key(s) [table].a, [table].b`` for a message."""
    return ("scene keys " if len(names) > 1 else "scene key ") + ", ".join(f"[{table}].{n}" for n in names)


def exponent(x: float) -> int:
    """e with 2^(e-1) <= |x| < 2^e (frexp's), 0 for 0."""
    return math.frexp(x)[1] if x else 0


def exact_ldexp(x: float, e: int) -> float | None:
    """x·2^e if that is exact (normal or zero), else None."""
    if x == 0:
        return 0.0
    try:
        y = math.ldexp(x, e)
    except OverflowError:
        return None
    return y if y != 0 and abs(y) >= 2.2250738585072014e-308 and math.ldexp(y, -e) == x else None


def moment_exponent(moments: tuple[float, ...]) -> int:
    """The unit of the moments: the largest's order, lowered where the smallest would leave the normal doubles."""
    return min(exponent(max(moments)), exponent(min(moments)) + 1021)


def comfortable(*exponents: int) -> bool:
    return all(abs(e) <= _COMFORTABLE for e in exponents)


def split_product(factors: list[float], shift: int) -> list[float] | None:
    """Factors f_i' with Π f_i' = Π f_i·2^shift, each f_i' a normal double (exact); None if impossible."""
    if any(f == 0 for f in factors):
        return [0.0 if f == 0 else math.copysign(1.0, f) for f in factors]
    parts = [math.frexp(f) for f in factors]
    total = sum(e for _, e in parts) + shift
    n = len(parts)
    out = []
    for i, (mant, _) in enumerate(parts):
        e = total // n + (1 if i < total % n else 0)
        y = exact_ldexp(mant, e)
        if y is None:
            return None
        out.append(y)
    return out


def scaled_time(t_end: float, j: int) -> float:
    """t_end in units of 2^-j s (the motion's fastest rate ~2^j rad/s); refused where t_end·2^j is no double.

    Such a run turns the body by ~10^308 rad: beyond every method (the closed forms count 2^51 periods
    at most, an integration follows :data:`MAX_INTEGRATED_RADIANS`), so the bound said is the closed
    forms' order, 2^52 rad at the fastest rate.
    """
    scaled = exact_ldexp(t_end, j)
    if scaled is None and exponent(t_end) + j < 0:
        raise InvalidInputError(f"scene key [time].t_end: expected at least ~{math.ldexp(1.0, -1021 - j):.3g} s for a "
                                f"motion whose fastest rate is ~2^{j} rad/s (a shorter run turns it by less than the "
                                f"smallest normal double, 2^-1022 rad), got {t_end!r}")
    if scaled is None:
        raise InvalidInputError(f"scene key [time].t_end: expected at most ~{math.ldexp(1.0, 52 - j):.3g} s for a "
                                f"motion whose fastest rate is ~2^{j} rad/s (~2^52 rad of it: the closed forms' "
                                f"reach), got {t_end!r}")
    return scaled


def refuse_ratio(where: str, what: str) -> None:
    raise InvalidInputError(f"{where}: expected {what} within the double range (a ratio of at most ~2^1000 "
                            "between them), got values whose ratio is beyond it; no choice of units holds both")


# --------------------------------------------------------------------------------------------- angles

def reduce_angle(x: float) -> tuple[float, float]:
    """(x mod 2π in (-π, π], the whole turns taken off as the double nearest x minus it), exactly reduced."""
    import mpmath

    with mpmath.workprec(max(53, exponent(x)) + 80):
        r = mpmath.fmod(mpmath.mpf(x), 2 * mpmath.pi)
        if r > mpmath.pi:
            r -= 2 * mpmath.pi
        elif r <= -mpmath.pi:
            r += 2 * mpmath.pi
        return float(r), float(mpmath.mpf(x) - r)


def scale_scene(scene: Scene) -> Scaled:
    """The scene in the units of its own motion (its system's :meth:`~mechderive.systems.base.System.scale`);
    the scene itself when comfortable."""
    return scene.model.scale(scene)


#: The units of the scene being solved, for the systems' solvers (which take (scene, method, t)).
_UNITS: contextvars.ContextVar[Scaled | None] = contextvars.ContextVar("mechderive_scene_units", default=None)


def units_of(scene: Scene) -> Scaled:
    """The units ``scene`` is being solved in: those :func:`solving_in` set for it, or the scene's own."""
    scaled = _UNITS.get()
    return scaled if scaled is not None and scaled.scene is scene else Scaled(scene, scene)


@contextlib.contextmanager
def solving_in(scaled: Scaled) -> Iterator[None]:
    """While solving ``scaled.scene``, :func:`units_of` answers ``scaled``."""
    token = _UNITS.set(scaled)
    try:
        yield
    finally:
        _UNITS.reset(token)


# --------------------------------------------------------------------------------------------- reach

def check_samples(scene: Scene, t: np.ndarray) -> None:
    """Refuse sample times that coincide (a t_end of a few subnormal steps): the outputs are functions of t."""
    if scene.samples > 1 and not np.all(np.diff(t) > 0):
        fit = int(scene.t_end / np.spacing(scene.t_end)) + 1
        raise InvalidInputError(
            f"scene keys [time].t_end, [time].samples: expected distinct sample times (t_end / (samples - 1) at "
            f"least the spacing of doubles near t_end, {np.spacing(scene.t_end):.3g} s), got t_end = "
            f"{scene.t_end!r} with samples = {scene.samples}: at most {fit} samples fit in it")


def refuse_overflow(scaled: Scaled, q: str, big: float, e: int) -> None:
    """Refuse output ``q`` whose size ``big`` (solver's units) times 2^e leaves the doubles: say how large it is
    and, where it grows with the rates (as I ω or I ω²), how fast the scene may spin at these moments."""
    b = int(np.frexp(big)[1]) + e
    if b <= 1024:
        return
    how = scaled.scales.get(q, "the scene's units")
    power = 2 if how.startswith("I ω²") else 1
    fastest = scaled.fastest
    rates = "" if fastest == 0 else \
        f"; at these moments the rates must stay below ~{fastest * 2.0 ** ((1024 - b) / power):.3g} rad/s"
    raise InvalidInputError(f"{_keys(scaled)}: expected the output {q} within the double range "
                            f"(|{q}| ≤ {DOUBLE_MAX:.4g}), got |{q}| ~10^{b * 0.30103:.0f} for these values; {q} scales "
                            f"as {how}{rates}")


def _keys(scaled: Scaled) -> str:
    return scaled.keys or "scene tables [parameters], [initial]"


def check_outputs(scaled: Scaled, values: dict[str, float]) -> None:
    """Refuse up front a requested output whose value at t = 0 in the solver's units (``values``: a conserved
    quantity's, E, p_φ, |L|) is no double in the scene's units."""
    if scaled.identity:
        return
    wanted = set(scaled.original.quantities)
    for q, v in values.items():
        if q in wanted and v != 0 and scaled.columns.get(q, 0):
            refuse_overflow(scaled, q, abs(float(v)), scaled.columns[q])


def check_integration_length(scene: Scene, rate: float, scaled: Scaled) -> None:
    """Refuse, naming t_end, an integration longer than :data:`MAX_INTEGRATED_RADIANS` of the fastest
    rate (:data:`MAX_INTEGRATED_RADIANS_SCIPY` without the compiled stepper): minutes of work."""
    from ..core.cbuild import c_enabled

    budget, stepper = ((MAX_INTEGRATED_RADIANS, "") if c_enabled() else
                       (MAX_INTEGRATED_RADIANS_SCIPY, " on SciPy's stepper (no C compiler)"))
    if rate * scene.t_end > budget:
        if not math.isfinite(rate):
            raise InvalidInputError(
                f"{_keys(scaled)}: expected a motion whose fastest rate is a double for "
                f"method 'integrate', got moments and rates whose Euler equations turn it faster than ~1e308 rad/s")
        limit = scaled.seconds(budget / rate)
        raise InvalidInputError(
            f"scene key [time].t_end: expected at most {limit:.6g} s for method 'integrate'{stepper} "
            f"({budget:.6g} rad at this motion's fastest rate, "
            f"{float(np.ldexp(rate, scaled.rate)):.6g} rad/s: a longer run would take many minutes; "
            f"method = \"exact\" solves the free and heavy tops at any t_end), "
            f"got {scaled.original.t_end!r}")


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
            refuse_overflow(scaled, q, big, e)
        out[q] = np.ldexp(col, e)
    return out
