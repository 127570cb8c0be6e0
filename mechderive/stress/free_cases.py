"""Stress cases of the free rigid body: the separatrix and extreme moments of inertia.

References: :func:`.reference.free_reference`, an mpmath Taylor integration of Euler's equations
(3.33) and Ṙ = hat(ω) R typed in by hand, at 30 digits; 1 - m from the textbook formula at 40 digits.
"""

from __future__ import annotations

import mpmath
import numpy as np

from ..errors import UnphysicalInertiaError
from .checks import CF_TOL, INT_TOL, free_closed_form, free_integrators
from .core import Case, Collector
from .reference import euler_matrix, free_reference, free_top_m1

__all__ = ["CASES", "separatrix_omega"]

_REF = "mpmath Taylor integration (30 digits) of Euler's equations + Ṙ = hat(ω)R, typed in by hand"
_TOL = (f"closed form: ω {CF_TOL:g}·|ω0|, R {CF_TOL:g} (its ~1e-13 ×10); integrators {INT_TOL:g} and ≤ 10× "
        "their own estimate; drifts 1e-12 / 1e-9")

#: I = (1, 2, 2.25), ω = (0.75, 0.5, 1) lies exactly on the separatrix in binary:
#: Σ I_a (I_a - I2) ω_a² = -0.75² + 2.25·0.25·1 = 0 (tests/reference/make_free_top_reference.py).
SEP_MOMENTS = (1.0, 2.0, 2.25)
SEP_OMEGA = (0.75, 0.5, 1.0)
_R0 = [[float(x) for x in row] for row in euler_matrix(0.3, 0.7, -1.1).tolist()]


def separatrix_omega(one_minus_m: float) -> tuple[float, float, float]:
    """ω = (0.75, 0.5, ω3) with 1 - m ≈ |one_minus_m|, above (L² > 2T I2) for > 0, below for < 0.

    L² - 2T I2 = -ω1² + 0.5625 ω3² is linear in ω3², and 1 - m is proportional to it near 0
    (:func:`.reference.free_top_m1`): solved at 40 digits, then rounded to a float (so the
    realised 1 - m differs from the target by ≲ 4e-16 absolute; the row reports the realised value).
    """
    with mpmath.workdps(40):
        def m1(w3):  # free_top_m1's formula with ω3 an mpf (the float inputs of free_top_m1 would round it)
            Ix, Iy, Iz = (mpmath.mpf(x) for x in SEP_MOMENTS)
            wx, wy = mpmath.mpf(0.75), mpmath.mpf(0.5)
            E2 = Ix * wx**2 + Iy * wy**2 + Iz * w3**2
            L2 = (Ix * wx) ** 2 + (Iy * wy) ** 2 + (Iz * w3) ** 2
            D = L2 - E2 * Iy
            return ((Iz - Ix) * D / ((Iz - Iy) * (L2 - E2 * Ix)) if D > 0
                    else (Iz - Ix) * D / ((Iy - Ix) * (E2 * Iz - L2)))

        w3 = mpmath.findroot(lambda w: m1(w) - one_minus_m, mpmath.mpf(1))
    return (0.75, 0.5, float(w3))


#: Integrators near the separatrix: BASELINE.md measured every solve_ivp method stalling at ≥ 1.5e-8 at
#: 1 - m = 1e-6 (errors grow by ~1/√(1 - m) per passage of the saddle); what is required of them there is
#: an honest error estimate (≤ 10× off) and no worse than 1e-6.
_SEP_INT_TOL = 1e-6


def _separatrix(one_minus_m: float | None, quick: bool = False, integrators: bool = False):
    if one_minus_m is None:
        w0, name = SEP_OMEGA, "separatrix-exact"
        what = "exactly on the separatrix (m = 1: hyperbolic motion), t up to 30"
    else:
        w0 = separatrix_omega(one_minus_m)
        side = "above" if one_minus_m > 0 else "below"
        name = f"separatrix-{abs(one_minus_m):.0e}-{side}".replace("e-0", "e-")
        what = f"1 - m = {abs(one_minus_m):g} {side} the separatrix (L² {'>' if one_minus_m > 0 else '<'} 2T I2), 2 periods"

    def run(col: Collector) -> None:
        with mpmath.workdps(40):
            m1 = free_top_m1(SEP_MOMENTS, w0)
        col.details["1 - m (textbook, 40 digits, signed by side)"] = float(m1)
        col.summary.append(f"1 - m = {abs(float(m1)):.3g}")
        if one_minus_m is None:
            col.condition("reference", "1 - m = 0 exactly", m1 == 0)
            t = np.linspace(0.0, 30.0, 61)
        else:
            period = float(_period_guess(w0))
            t = np.linspace(0.0, 2 * period, 81)
        ref = free_reference(SEP_MOMENTS, w0, _R0, t)
        sol = free_closed_form(col, SEP_MOMENTS, w0, np.array(_R0), t, ref)
        if sol is not None:
            expect = "separatrix" if one_minus_m is None else "elliptic"
            col.condition("closed form", f"kind = {expect}", sol.kind == expect, f"got {sol.kind}")
            if one_minus_m is not None:
                col.compare("closed form", "1 - m (relative)", sol.m1, abs(float(m1)), 1e-12, scale=abs(float(m1)))
        if integrators:
            free_integrators(col, SEP_MOMENTS, w0, np.array(_R0), t, ref, step=0.01, tol=_SEP_INT_TOL)

    return Case(name=name, family="1 free-top separatrix", description=what, system="free_top",
                inputs=f"I = {SEP_MOMENTS}, ω0 = ({w0[0]:g}, {w0[1]:g}, {w0[2]:.17g}), R0 = R(0.3, 0.7, -1.1)",
                methods=("closed form",) + (("DOP853", "splitting-6") if integrators else ()),
                reference=_REF, tolerance=_TOL.replace(f"integrators {INT_TOL:g}", f"integrators {_SEP_INT_TOL:g}"),
                run=run, quick=quick)


def _period_guess(w0) -> mpmath.mpf:
    from .reference import free_top_period

    with mpmath.workdps(40):
        return free_top_period(SEP_MOMENTS, w0)


def _free_inertia(name: str, moments, w0, description: str, quick: bool = False, refusals: bool = False):
    def run(col: Collector) -> None:
        from ..systems.free_top.exact import exact_free_top
        from ..systems.free_top.integrate import integrate_free_top

        with mpmath.workdps(40):
            from .reference import free_top_period

            T = float(free_top_period(moments, w0))
        t = np.linspace(0.0, min(2 * T, 10.0), 61)
        ref = free_reference(moments, w0, _R0, t)
        free_closed_form(col, moments, w0, np.array(_R0), t, ref)
        free_integrators(col, moments, w0, np.array(_R0), t, ref, step=min(0.01, T / 400))
        if refusals:
            bad = (moments[0], moments[1], moments[0] + moments[1] + 1e-3)
            col.expect_refusal("closed form", f"I = {bad} (I1 + I2 < I3)", lambda: exact_free_top(bad, w0),
                               UnphysicalInertiaError)
            col.expect_refusal("DOP853", f"I = {bad}", lambda: integrate_free_top(bad, w0, [0.0, 1.0]),
                               UnphysicalInertiaError)

    return Case(name=f"inertia-free-{name}", family="6 inertia ratios", description=description, system="free_top",
                inputs=f"I = {moments}, ω0 = {w0}, R0 = R(0.3, 0.7, -1.1)",
                methods=("closed form", "DOP853", "splitting-6"), reference=_REF, tolerance=_TOL, run=run,
                quick=quick)


CASES = [
    _separatrix(None, quick=True, integrators=True),
    *(_separatrix(s * x, integrators=(x == 1e-6)) for x in (1e-6, 1e-10, 1e-12, 1e-14) for s in (1, -1)),
    _free_inertia("near-symmetric", (1.0, 1.0 + 1e-9, 2.0), (0.3, 0.4, 1.0),
                  "I2 - I1 = 1e-9: m ~ 1e-10, nearly the symmetric top (3.37)", quick=True),
    _free_inertia("plate", (1.0, 1e3, 1e3 + 1 - 1e-6), (10.0, 0.1, 0.01),
                  "I3/I1 ~ 1e3, 1e-6 inside the triangle inequality, fast spin about the small axis"),
    _free_inertia("plate-exact", (1.0, 1e3, 1e3 + 1), (0.01, 0.1, 1.0),
                  "I1 + I2 = I3 exactly (a plane body, allowed); I1 + I2 < I3 must be refused", refusals=True),
    _free_inertia("rod", (1e-3, 1.0, 1.0), (1.0, 0.2, 0.3), "a thin rod: I1/I2 = 1e-3, symmetric about axis 1"),
]
