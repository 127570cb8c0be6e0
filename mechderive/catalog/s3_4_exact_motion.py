"""Catalog entries for section 3.4.4: the exact motion of the asymmetric top.

The chapter states (without formulas) that "the analytic solution for the general
motion of an asymmetric top ... involv[es] Jacobian elliptic functions" and that the
polhode curves are closed, so the body-frame motion is periodic.  The toolkit derives
that solution (:mod:`mechderive.systems.free_top.exact_model`); these entries check it
against mpmath integrations of Euler's equations (3.33), independent of the closed form.
"""

from __future__ import annotations

import functools

import mpmath
import numpy as np
import sympy as sp

from .registry import Claim, Outcome, register

_CASE = ((1.0, 2.0, 3.0), (1.0, 0.5, 1.0))
_u = sp.Symbol("u", real=True)
_P, _Q, _S = sp.symbols("P Q S", real=True)
_sn, _cn, _dn = (sp.Function(name) for name in ("sn", "cn", "dn"))


@functools.cache
def _integrate(t_end: float, dps: int = 20) -> tuple[float, ...]:
    """ω(t_end) from an mpmath Taylor integration of Euler's equations (3.33) at ``dps`` digits (kept: a reference)."""
    (I1, I2, I3), w0 = _CASE
    with mpmath.workdps(dps):
        f = lambda t, w: [(I2 - I3) * w[1] * w[2] / I1, (I3 - I1) * w[2] * w[0] / I2, (I1 - I2) * w[0] * w[1] / I3]
        sol = mpmath.odefun(f, 0, [mpmath.mpf(x) for x in w0])
        return tuple(float(x) for x in sol(mpmath.mpf(t_end)))


def _printed_solution() -> sp.Matrix:
    """The elliptic-function form: (ω_x, ω_y, ω_z) = (P cn u, Q sn u, S dn u), u = λt + u0."""
    return sp.Matrix([_P * _cn(_u), _Q * _sn(_u), _S * _dn(_u)])


def _check_solution(form: sp.Matrix) -> Outcome:
    """Evaluate ``form`` with the derived constants and compare with integration at t = 0.9, 2.3, 4.1 s."""
    from ..systems.free_top.exact import exact_free_top

    sol = exact_free_top(*_CASE)
    P, Q, S = sol._amp
    lam, u0 = sol._lam.hi + sol._lam.lo, sol._u0.hi + sol._u0.lo
    worst = 0.0
    with mpmath.workdps(20):
        funcs = {"sn": lambda x: mpmath.ellipfun("sn", x, m=sol.m), "cn": lambda x: mpmath.ellipfun("cn", x, m=sol.m),
                 "dn": lambda x: mpmath.ellipfun("dn", x, m=sol.m)}
        f = sp.lambdify([_u, _P, _Q, _S], form, [funcs, "mpmath"])
        for t in (0.9, 2.3, 4.1):
            relabelled = np.array(f(lam * t + u0, P, Q, S), dtype=float).ravel()
            body = relabelled @ sol._perm
            ref = np.array(_integrate(t))
            worst = max(worst, float(np.max(np.abs(body - ref))))
    # 1e-12: the closed form is exact; both sides are evaluated to ~1e-15 here.
    return Outcome(worst < 1e-12, f"closed form vs 20-digit integration at 3 times: max |Δω| = {worst:.1e}")


register(Claim(
    "3.4.4 elliptic solution", "3.4.4",
    "the general motion of the asymmetric top is given by Jacobi elliptic functions: "
    "ω = (P cn u, Q sn u, S dn u) in suitably ordered axes, u = λt + u0",
    "integration",
    printed=_printed_solution,
    check=_check_solution,
))


def _check_closed(difference: sp.Matrix) -> Outcome:
    """ω(T) - ω(0) from integration over the derived polhode period T = 4K(m)/λ, against ``difference``."""
    from ..systems.free_top.exact import exact_free_top

    T = exact_free_top(*_CASE).polhode_period
    got = np.array(_integrate(T)) - np.array(_CASE[1])
    claimed = np.array(sp.Matrix(difference), dtype=float).ravel()
    err = float(np.max(np.abs(got - claimed)))
    # 1e-12: a 20-digit integration over one period; a non-closing polhode would miss by O(1).
    return Outcome(err < 1e-12, f"ω(T) - ω(0) over T = 4K/λ = {T:.6f} s differs from the claim by {err:.1e}")


register(Claim(
    "3.4.4 polhode closed", "3.4.4",
    "the polhode is closed: ω returns to its initial value after T = 4K(m)/λ, so the body-frame motion is periodic",
    "integration",
    printed=lambda: sp.zeros(3, 1),
    check=_check_closed,
))
