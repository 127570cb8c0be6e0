"""Independent references for the free top's edge cases: Taylor integration of (3.33) and (3.11) in mpmath.

The equations are typed in by hand in :mod:`mechderive.stress.reference` (Euler's equations
I1 ω̇1 = (I2 - I3) ω2 ω3 cyclic, and Ṙ = hat(ω) R); nothing here uses the closed form.  Its step
control measures every Taylor coefficient against the *largest* component, which is right for
absolute accuracy but lets a component of 1e-200 lose all its digits; the edge cases need each
component to its own relative accuracy, so :class:`RelativeTaylor` sizes the step by each
component's own scale (Jorba & Zou's rule applied per component).

Tilts far below the working precision (ε ≤ 1e-20, down to denormals) are referenced by the
linear response: the solution is y(ε) = y(0) + Σ_b (∂y/∂s_b) s_b + O(ε²), where y(0) is the
steady rotation about the axis and ∂y/∂s_b the response to a unit tilt s_b, obtained from a run
with s_b = δ = 2^-90 of the big component (its own O(δ) relative error, grown by e^{σt} ≤ 1e5
about an unstable axis, stays below 1e-22).  For ε ≤ 1e-24 the neglected O(ε) e^{σt} is below
1e-19 relative: invisible in a double.
"""

from __future__ import annotations

import math
from typing import Sequence

import mpmath
import numpy as np

from mechderive.stress import reference as ref

#: the tilt of the linear-response runs, relative to the big component
_DELTA = 2.0**-90


class RelativeTaylor(ref.TaylorSolution):
    """A Taylor solution whose step keeps every component to its own relative accuracy."""

    def _step_size(self, c: list[list[mpmath.mpf]]) -> mpmath.mpf:
        N = self.order
        rho = mpmath.inf
        for ci in c:
            scale = max(abs(ci[0]), abs(ci[1]), abs(ci[2]))
            if scale == 0:
                continue
            for j in (N - 1, N):
                if ci[j] != 0:
                    rho = min(rho, (scale / abs(ci[j])) ** (mpmath.mpf(1) / j))
        if rho == mpmath.inf:  # a polynomial of low degree: the series is exact
            rho = mpmath.mpf(1e3)
        return rho / mpmath.e ** 2


def _field(moments: Sequence[float], rotation: bool):
    if rotation:
        return ref.free_top_field(moments)
    I1, I2, I3 = (mpmath.mpf(float(x)) for x in moments)
    return ref.QuadraticField.build(3, [[((I2 - I3) / I1, 1, 2)], [((I3 - I1) / I2, 2, 0)],
                                        [((I1 - I2) / I3, 0, 1)]])


def integrate(moments, omega0, times, *, R0=None, rotation: bool = True, dps: int = 30) -> list[list]:
    """y(t) = (ω, R row-major) or ω alone at the float times (taken exactly), at ``dps`` digits."""
    with mpmath.workdps(dps):
        y0 = [mpmath.mpf(float(x)) for x in omega0]
        if rotation:
            R = np.eye(3) if R0 is None else np.asarray(R0, dtype=float)
            y0 += [mpmath.mpf(float(R[i, j])) for i in range(3) for j in range(3)]
        sol = RelativeTaylor(_field(moments, rotation), y0)
        return [sol(float(t)) for t in times]


def near_axis(moments, big, axis: int, times, *, R0=None, dps: int = 40):
    """The reference for every ω0 = ``big`` along ``axis`` plus a tilt ≤ 1e-24·|big|, as a function of ω0.

    y(ω0) = y_steady + Σ_b J_b s_b, the linear response (see the module docstring): three runs
    serve every tilt.
    """
    steady = [0.0, 0.0, 0.0]
    steady[axis] = float(big)
    base = integrate(moments, steady, times, R0=R0, dps=dps)
    responses = {}
    for b in range(3):
        if b != axis:
            tilted = list(steady)
            tilted[b] = _DELTA * abs(float(big))
            responses[b] = (tilted[b], integrate(moments, tilted, times, R0=R0, dps=dps))

    def reference(omega0) -> list[list]:
        if float(omega0[axis]) != float(big) or max(abs(float(omega0[b])) for b in responses) > 1e-24 * abs(big):
            raise ValueError(f"expected ω0 = {big} along axis {axis} plus a tilt <= 1e-24 of it, got {omega0}")
        with mpmath.workdps(dps):
            out = [list(y) for y in base]
            for b, (delta, resp) in responses.items():
                s = mpmath.mpf(float(omega0[b])) / mpmath.mpf(delta)
                out = [[o + (yi - y0i) * s for o, yi, y0i in zip(row, r, b0)] for row, r, b0 in zip(out, resp, base)]
        return out

    return reference


def ulp(x: float) -> float:
    """The spacing of doubles at |x|: 2^(e - 52) for 2^e ≤ |x| < 2^(e+1), 2^-1074 below 2^-1022."""
    x = abs(float(x))
    if x < 2.0**-1022:
        return 2.0**-1074
    return 2.0 ** (math.frexp(x)[1] - 53)


def ulp_error(x: float, reference, floor: float = 0.0) -> float:
    """|x - reference| in ulp of max(|reference|, floor) (reference an mpf: exact difference)."""
    with mpmath.workdps(60):
        diff = abs(mpmath.mpf(float(x)) - reference)
    return float(diff) / ulp(max(abs(float(reference)), floor))
