"""Catalog entries for section 3.3.1: Euler's equations, (3.31)–(3.33) and the torqued form.

The printed forms are compared with :class:`~mechderive.systems.free_top.model.FreeTopModel`,
which derives dL/dt in the body frame from L_a = I_ab ω_b (3.28) and ė_a = ω_ac e_c
(3.5)–(3.6) built from the so(3) generators; the cross products of the printed (3.32) are
SymPy's, an independent route to the same components.
"""

from __future__ import annotations

import sympy as sp

from ..systems.free_top import model as ft
from .checks import all_pass, same
from .registry import Claim, register

SECTION = "3.3.1"


def _m() -> ft.FreeTopModel:
    return ft.model()


def _free(expr: sp.Matrix) -> sp.Matrix:
    return expr.subs({tau: 0 for tau in ft.tau_symbols})


def _printed_3_32() -> sp.Matrix:
    """dL/dt = (dL_a/dt) e_a + L_a ω × e_a, in body components (e_a is the unit vector u_a)."""
    m = _m()
    Lb, w = m.angular_momentum_body, m.omega
    units = [sp.eye(3)[:, a] for a in range(3)]
    return sum((Lb[a].diff(ft.t) * units[a] + Lb[a] * w.cross(units[a]) for a in range(3)), sp.zeros(3, 1))


def _printed_3_33() -> sp.Matrix:
    w = _m().omega
    wd = w.diff(ft.t)
    return sp.Matrix([
        ft.I1 * wd[0] + w[1] * w[2] * (ft.I3 - ft.I2),
        ft.I2 * wd[1] + w[2] * w[0] * (ft.I1 - ft.I3),
        ft.I3 * wd[2] + w[0] * w[1] * (ft.I2 - ft.I1),
    ])


def _space_torque() -> sp.Matrix:
    """Rᵀ τ: the space components of the torque (r̃ = Rᵀ r), with R the generic R_ij of the derivation."""
    R = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"R{i + 1}{j + 1}", real=True))
    return R.T * sp.Matrix(ft.tau_symbols)


register(Claim(
    "3.31", SECTION,
    "a free body conserves L: on Euler's equations (τ = 0) the space components L̃ = Rᵀ L have dL̃/dt = 0 "
    "(for any R(t) with Ṙ = ωR)",
    "symbolic",
    printed=lambda: sp.zeros(3, 1),
    check=lambda f: same(f, _free(_m().space_rate_of_angular_momentum), "dL̃/dt on Euler's equations"),
))

register(Claim(
    "3.32", SECTION,
    "dL/dt = (dL_a/dt) e_a + L_a ω × e_a: body components of dL/dt (with principal axes, L_a = I_a ω_a)",
    "symbolic",
    printed=_printed_3_32,
    check=lambda f: same(f, _m().rate_of_angular_momentum, "dL/dt from ė_a = ω_ac e_c"),
))

register(Claim(
    "3.33", SECTION,
    "Euler's equations: I1ω̇1 + ω2ω3(I3 - I2) = 0, I2ω̇2 + ω3ω1(I1 - I3) = 0, I3ω̇3 + ω1ω2(I2 - I1) = 0",
    "symbolic",
    printed=_printed_3_33,
    check=lambda f: same(f, _free(_m().euler_equations), "Euler's equations (τ = 0)"),
))

register(Claim(
    "3.33 with torque", SECTION,
    "with a torque, L̇ = τ gives Euler's equations (3.33) with the body components τ_a of the torque on the RHS",
    "symbolic",
    printed=lambda: _printed_3_33() - sp.Matrix(ft.tau_symbols),
    check=lambda f: all_pass([
        same(f, _m().euler_equations, "I_aω̇_a + ... - τ_a"),
        # and on those equations the space components of L change at the space components of τ
        same(_m().space_rate_of_angular_momentum, _space_torque(), "dL̃/dt = Rᵀτ"),
    ]),
))
