"""Section 3.4: component-wise accuracy of the free top's closed form in ulp, against 40-digit references.

The anchor (issue 11) is a production exact free-body solver (Principia's ``EulerSolver``) whose
tests bound the angular momentum retrieved at t = 0 component-wise at 209 ulp for random bodies
and 11,126 ulp near the separatrix.  Ours, measured the same way and at later times too:

* **ω and L_body = Iω**: e_a = |x_a - r_a| / ulp(max(|r_a|, 2^-40·A_a)) per component, r the
  40-digit reference (mpmath Taylor integration of (3.33), tests/_free_top_reference.py), A_a the
  size of the component over the run (the largest of |ω0_a| and the reference values).  The floor
  only matters within 2^-40·A_a of a zero crossing, where the phase itself (exact to ~|u|·1e-32)
  limits the relative accuracy of any method.
* **L_space = R(t)ᵀ I ω(t)** (constant): in ulp of |L|.  R is accurate absolutely (its entries are
  O(1)), so a space component much smaller than |L| is a difference of O(|L|) products and cannot
  be relatively accurate; |L| is the natural unit.

Bounds asserted (the issue's targets): ≤ 100 ulp random and near the axes, ≤ 2,000 ulp near the
separatrix.  Measured: a few ulp everywhere (the slow test prints the full table).
"""

from __future__ import annotations

import numpy as np
import pytest

from mechderive.kinematics.rotations import rotation_matrix
from mechderive.systems.free_top.exact import exact_free_top

from ._free_top_reference import integrate, ulp, ulp_error

BOUNDS = {"random": 100, "near axes": 100, "separatrix": 2000}
ANCHOR = {"random": 209, "near axes": None, "separatrix": 11126}


def _moments(rng):
    while True:  # Principia's draw (uniform in (0, 10), sorted), kept if a body can have it (3.22)
        I = np.sort(rng.uniform(0.0, 10.0, 3))
        if I[0] + I[1] >= I[2] and I[0] > 0:
            return I


def draws(category: str, n: int, seed: int = 42):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        I = _moments(rng)
        if category == "random":
            w = rng.uniform(-10.0, 10.0, 3)
        elif category == "near axes":
            axis, k = rng.integers(3), rng.integers(1, 321)
            w = rng.choice([-1.0, 1.0], 3) * rng.uniform(0.5, 1.0, 3) * 10.0 ** -float(k)
            w[axis] = rng.uniform(0.5, 2.0) * rng.choice([-1.0, 1.0])
        else:
            # Principia's separatrix draw, L² = 2T I_2 up to the rounding of ω_z (1 - m ~ 1e-16),
            # or a nearly symmetric body on its separatrix to rounding (1 - m down to ~1e-30)
            wx = rng.uniform(-10.0, 10.0)
            if rng.uniform() < 0.5:
                I = np.array([I[0], I[1], I[1] * (1 + 2.0 ** -float(rng.integers(10, 40)))])
            wz = wx * np.sqrt(I[0] * (I[1] - I[0]) / (I[2] * (I[2] - I[1])))
            w = np.array([wx, rng.uniform(-10.0, 10.0), wz * rng.choice([-1.0, 1.0])])
        yield I, w, rng


def measure(category: str, n: int, seed: int = 42, *, space: bool = False) -> dict:
    """Worst component-wise ulp errors of ω(0), ω(t), L_body(t) and (``space``) L_space(t)."""
    worst = {"omega(0)": 0.0, "omega(t)": 0.0, "L_body(t)": 0.0, "L_space(t)": 0.0}
    for I, w, rng in draws(category, n, seed):
        R0 = rotation_matrix(*rng.uniform(-3.0, 3.0, 3))
        sol = exact_free_top(I, w, R0=R0)
        span = sol.polhode_period if np.isfinite(sol.polhode_period) else 5.0
        times = np.concatenate([[0.0], np.sort(rng.uniform(0.0, min(2 * span, 30.0 / np.linalg.norm(w)), 2))])
        ref = integrate(I, w, times, R0=R0 if space else None, rotation=space, dps=40)
        om = sol.omega(times)
        amp = np.max(np.abs(np.array([[float(v) for v in y[:3]] for y in ref] + [list(w)])), axis=0)
        for i in range(len(times)):
            key = "omega(0)" if i == 0 else "omega(t)"
            for a in range(3):
                worst[key] = max(worst[key], ulp_error(om[i, a], ref[i][a], 2.0**-40 * amp[a]))
                L = float(I[a]) * om[i, a]  # one rounding more than ω_a: the anchor's quantity
                worst["L_body(t)"] = max(worst["L_body(t)"],
                                         ulp_error(L, ref[i][a] * float(I[a]), 2.0**-40 * amp[a] * I[a]))
        if space:
            L0 = R0.T @ (I * w)
            Ln = np.linalg.norm(L0)
            Ls = np.einsum("nab,na->nb", sol.rotation(times), I * om)
            worst["L_space(t)"] = max(worst["L_space(t)"], float(np.max(np.abs(Ls - L0))) / ulp(Ln))
    return worst


@pytest.mark.parametrize("category", list(BOUNDS))
def test_ulp_errors_sample(category):
    # a bounded sample (the slow test below takes 200 draws per category)
    worst = measure(category, 6)
    assert max(worst.values()) <= BOUNDS[category], worst
    worst = measure(category, 2, seed=7, space=True)
    assert worst["L_space(t)"] <= BOUNDS[category], worst


@pytest.mark.slow
def test_ulp_table():
    lines = [f"{'':12s} {'ω(0)':>8s} {'ω(t)':>8s} {'L_body':>8s} {'L_space':>8s}  bound  anchor"]
    for category in BOUNDS:
        worst = measure(category, 200)
        worst["L_space(t)"] = measure(category, 40, seed=7, space=True)["L_space(t)"]
        lines.append(f"{category:12s} " + " ".join(f"{worst[k]:8.1f}" for k in worst)
                     + f"  {BOUNDS[category]:5d}  {ANCHOR[category] or '-'}")
        assert max(worst.values()) <= BOUNDS[category], (category, worst)
    print("\n".join(lines))
