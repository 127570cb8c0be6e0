"""The drift of a conserved quantity, measured against a scale of the motion.

A quantity that the equations conserve drifts, numerically, by max_t |x(t) - x(0)|.  Divided
by its own |x(0)| this means nothing when x(0) is near zero: a gyroscope let go with
p_φ = I1 φ̇ sin²θ + I3 ω3 cos θ = 0 at θ = π/2 has p_φ(0) = I3 ω3 cos(fl(π/2)) ≈ 1e-17, and
a deviation of 1e-16 — the rounding of the terms I3 ω3 cos θ ~ 0.4 it is a sum of — would
read as a "drift" of 10.  So the drift is divided by a *scale of the motion*: a size the
terms of x have along this motion, which the caller derives from the motion's own
quantities and names (e.g. "max(|p_φ|, |p_ψ|, √(I1·2T), √(I1·M g l))").  Where even that
scale is zero (a body at rest) the absolute deviation is reported, and says so.

>>> d = drift([1e-17, -3e-17, 2e-17], 0.375, "|p_ψ|")
>>> round(d.value / 4e-17 * 0.375, 12), d.relative_to
(1.0, '|p_ψ| = 0.375')
>>> drift([0.0, 0.0], 0.0, "T").relative_to
'absolute (the scale T of the motion is 0)'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Drift", "drift"]


@dataclass(frozen=True)
class Drift:
    """``value`` = max_t |x(t) - reference| / ``scale``; ``relative_to`` names the scale and gives its size.

    ``deviation`` is max_t |x(t) - reference| itself and ``start`` the quantity's value at the first sample
    (a scalar quantity's; NaN for a vector): a run's per-motion summary reports an invariant as
    ``start`` ± ``deviation``.
    """

    value: float
    scale: float
    relative_to: str
    deviation: float = float("nan")
    start: float = float("nan")


def drift(series: Any, scale: float, relative_to: str, *, reference: Any = None) -> Drift:
    """The drift of ``series`` (samples along axis 0; a vector quantity along the last axis) against ``scale``.

    The deviation of each sample from ``reference`` (default: the first sample; give 0 for a
    quantity that must vanish) is its absolute value, or its Euclidean norm for vectors
    (shape (N, k)).  ``scale`` is a size of the motion (≥ 0, see the module docstring) named by
    ``relative_to``.  Samples where the quantity is not defined (NaN, ±inf) make the drift NaN
    and are counted in ``relative_to``: a conserved quantity that cannot be evaluated is not
    conserved to any measurable accuracy.
    """
    x = np.asarray(series, dtype=float)
    scale = float(scale)
    if x.size == 0:
        return Drift(0.0, scale, f"{relative_to} = {scale:.3g}", 0.0)
    ref = x[0] if reference is None else np.asarray(reference, dtype=float)
    dev = np.abs(x - ref)
    if x.ndim > 1:
        dev = np.sqrt(np.sum(dev.reshape(len(x), -1) ** 2, axis=-1))
    bad = int(np.sum(~np.isfinite(dev)))
    worst = float(np.max(dev)) if bad == 0 else float("nan")
    undefined = f"; undefined at {bad} sample(s)" if bad else ""
    start = float(x[0]) if x.ndim == 1 else float("nan")
    if not np.isfinite(scale):
        return Drift(worst, scale, f"absolute (the scale {relative_to} of the motion is not defined){undefined}",
                     worst, start)
    if not scale > 0:
        return Drift(worst, 0.0, f"absolute (the scale {relative_to} of the motion is 0){undefined}", worst, start)
    return Drift(worst / scale, scale, f"{relative_to} = {scale:.3g}{undefined}", worst, start)
