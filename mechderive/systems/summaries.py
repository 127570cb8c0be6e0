"""Per-motion quantities every system can offer: the period of a periodic motion and the invariants' values.

A system without a closed form measures both on its solution (a ``lagrangian`` system that reduces to
u̇² = P(u) takes the period from :func:`mechderive.core.quadrature.oscillation` instead): the period by
:func:`mechderive.core.periodic.measure_period` on the reduced state (the coordinates that are not
cyclic, and the velocities), the invariants as their value at t = 0 with, as estimate, their largest
deviation along the run (the system's own :meth:`~mechderive.systems.base.System.drift`, which already
computes them).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from .base import Quantity

__all__ = ["PERIOD", "REDUCED_PERIOD", "invariant_quantities", "period_of", "invariants_of"]

PERIOD = Quantity("period", "s", "period of the reduced motion (the non-cyclic coordinates and the velocities), "
                  "measured on the solution; none if it does not return within the run", "time")
#: the period of a system given by its Lagrangian, which may reduce to a quadrature (:mod:`mechderive.core.quadrature`)
REDUCED_PERIOD = Quantity("period", "s", "period of the reduced motion (the non-cyclic coordinates and the "
                          "velocities): in closed form where L reduces to u̇² = P(u), P of degree ≤ 4, else measured "
                          "on the solution; none if it does not return within the run", "time")


def invariant_quantities(described: Mapping[str, tuple[str, str, str]]) -> tuple[Quantity, ...]:
    """The summaries of the invariants ``described`` ({name: (unit, meaning, scales_as)})."""
    return tuple(Quantity(name, unit, f"{meaning}: its value at t = 0 (estimate: its variation along the run)",
                          scales_as) for name, (unit, meaning, scales_as) in described.items())


def period_of(t: np.ndarray, state: np.ndarray, errors: Any = None) -> tuple[Any, Any]:
    """(period, estimate) of the sampled reduced ``state``, or (None, the reason there is none)."""
    from ..core.periodic import measure_period

    found = measure_period(t, state, component_errors=errors)
    return (found.period, found.estimate) if found.period is not None else (None, found.reason)


def invariants_of(drifts: Mapping[str, Any], names: tuple[str, ...], why_not: str) -> dict[str, tuple[Any, Any]]:
    """{name: (value at t = 0, largest deviation along the run)} of the invariants among ``names``; one the
    motion does not conserve is (None, ``why_not``)."""
    out = {}
    for name in names:
        d = drifts.get(name)
        if d is None:
            out[name] = (None, f"{name} is not conserved along this motion: {why_not}")
        else:
            out[name] = (float(d.start), float(d.deviation))
    return out
