"""Ensemble throughput: bodies × steps per second of the vectorised splitting.

Heavy tops: the BASELINE top's parameters, random θ0 ∈ (0.1, π - 0.1), ψ̇0 ∈ (-10, 10),
φ̇0 ∈ (-1, 1) (seed 1), order 4, h = 0.02 s.  Free tops: I = (1, 2, 3), random ω0 ~ N(0, 1)³
(seed 1), order 4, h = 0.05 s.  Output at the end only (the (N, M, ·) arrays stay small).  The
time is the ensemble's own ``wall_time`` (the stepping loop); "one top alone" is the scalar
path (``integrate_*(method="splitting")``) at the same step, for scale.
"""

from __future__ import annotations

import math

import numpy as np

from .work_precision import FREE_MOMENTS, FREE_OMEGA0, HEAVY_INITIAL, HEAVY_PARAMS

__all__ = ["ensemble_throughput"]


def ensemble_throughput(*, quick: bool = False) -> dict:
    """Rows (system, M, steps, seconds, body-steps/s) for M = 1, 100, 10⁴ (quick: 1, 100)."""
    from ..systems.free_top.integrate import integrate_free_top, integrate_free_top_ensemble
    from ..systems.heavy_top.integrate import integrate_heavy_top, integrate_heavy_top_ensemble

    sizes = (1, 100) if quick else (1, 100, 10_000)
    n_steps = 100 if quick else 250
    rows = []
    rng = np.random.default_rng(1)
    h = 0.02
    integrate_heavy_top_ensemble(HEAVY_PARAMS, dict(theta=np.array([0.5, 0.6])), [0.0, h], step=h)  # compile
    for M in sizes:
        init = dict(theta=rng.uniform(0.1, math.pi - 0.1, M), psi_dot=rng.uniform(-10, 10, M),
                    phi_dot=rng.uniform(-1, 1, M))
        ens = integrate_heavy_top_ensemble(HEAVY_PARAMS, init, [0.0, n_steps * h], step=h, order=4)
        rows.append(dict(system="heavy top", M=M, steps=ens.n_steps, step=h, seconds=ens.wall_time,
                         body_steps_per_second=ens.body_steps_per_second,
                         max_energy_drift=float(ens.energy_drift.max())))
    one = integrate_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL, [0.0, n_steps * h], method="splitting", order=4, step=h,
                              estimate_error=False)
    rows.append(dict(system="heavy top", M="1 (scalar path)", steps=one.n_steps, step=h, seconds=one.wall_time,
                     body_steps_per_second=one.n_steps / one.wall_time, max_energy_drift=one.energy_drift))
    h = 0.05
    integrate_free_top_ensemble(FREE_MOMENTS, np.ones((2, 3)), [0.0, h], step=h)
    for M in sizes:
        w0 = rng.normal(size=(M, 3))
        ens = integrate_free_top_ensemble(FREE_MOMENTS, w0, [0.0, n_steps * h], step=h, order=4)
        rows.append(dict(system="free top", M=M, steps=ens.n_steps, step=h, seconds=ens.wall_time,
                         body_steps_per_second=ens.body_steps_per_second,
                         max_energy_drift=float(ens.energy_drift.max())))
    one = integrate_free_top(FREE_MOMENTS, FREE_OMEGA0, [0.0, n_steps * h], method="splitting", order=4, step=h,
                             estimate_error=False)
    rows.append(dict(system="free top", M="1 (scalar path)", steps=one.n_steps, step=h, seconds=one.wall_time,
                     body_steps_per_second=one.n_steps / one.wall_time, max_energy_drift=one.energy_drift))
    return dict(rows=rows)
