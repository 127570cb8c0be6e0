"""The free rigid body's formulas for ``derive`` and its symbols for ``check`` (sections 3.3–3.5).

:func:`derivations` lists what ``mechderive derive free_top`` prints, each value taken from the
derived model of :mod:`.model` (nothing typed in); :func:`check_system` names the symbols
``mechderive check free_top`` knows (the body components ω1, ω2, ω3 and their derivatives, the
principal moments, T and L²) and the real bodies its random points are drawn from.
"""

from __future__ import annotations

import functools
import random
from fractions import Fraction
from typing import Any, Mapping

import sympy as sp

from ...core.check_system import BodyRegion, Quantity, RigidBody, System, decimal4, jet_name
from ...core.symbols import state_symbol, to_state_symbols
from ...errors import InvalidInputError
from ..base import Derivation, Derivations

__all__ = ["derivations", "check_system"]

#: the title of ``derive``'s output
_SUMMARY = "the free rigid body in principal axes (sections 3.3–3.5)"

_s = state_symbol
_RATES = ("phi_dot", "theta_dot", "psi_dot")


def _symbols(*names: str) -> sp.Matrix:
    return sp.Matrix([_s(n) for n in names])


def _free():
    from .model import model

    return model()


def _lagrangian(o: Any) -> sp.Expr:
    """L = T = ½ ωᵀ diag(I1, I2, I3) ω with ω the body components (3.6) of the chosen Euler sequence."""
    from ...kinematics.sequences import sequence_model
    from .model import I1, I2, I3

    w = to_state_symbols(sequence_model(o.sequence, o.frame).angular_velocity_body)
    T = sp.expand((w.T * sp.diag(I1, I2, I3) * w)[0] / 2)
    parts = sp.collect(T, [I1, I2, I3], evaluate=False)
    return sum(k * sp.factor(v) for k, v in parts.items())


def _parameters(o: Any) -> dict:
    """{I1, I2, I3} of a shape about its pivot (default: its centre of mass), or the numeric moments."""
    from .model import I1, I2, I3

    if o.shape:
        p = o.body_parameters(default_pivot="centre")
        return {I1: p["I1"], I2: p["I2"], I3: p["I3"]}
    if o.moments:
        return dict(zip((I1, I2, I3), o.moments))
    return {}


_OMEGA_DOT = lambda: _symbols("omega1_dot", "omega2_dot", "omega3_dot")  # noqa: E731

# (name, meaning, equation, build, lhs, printed by default)
_TABLE: tuple = (
    ("lagrangian", "the Lagrangian L = T = ½ ω_a I_ab ω_b in Euler angles of the chosen sequence", "3.18",
     _lagrangian, lambda: sp.Symbol("L"), True),
    ("euler_equations", "Euler's equations solved for ω̇ (free body)", "3.33", lambda o: _free().free_rhs,
     _OMEGA_DOT, True),
    ("energy", "kinetic energy T, conserved", "3.46", lambda o: _free().energy, lambda: sp.Symbol("T"), True),
    ("angular_momentum_squared", "L² = L_a L_a, conserved", "3.47", lambda o: _free().angular_momentum_squared,
     lambda: sp.Symbol("L") ** 2, True),
    ("euler_equations_torque", "Euler's equations with a body torque τ, solved for ω̇", "3.33",
     lambda o: _free().euler_rhs, _OMEGA_DOT, False),
    ("angular_momentum", "body components L_a = I_ab ω_b", "3.28",
     lambda o: to_state_symbols(_free().angular_momentum_body), lambda: _symbols("L1", "L2", "L3"), False),
    ("energy_gradient", "L = ∇_ω T", "3.49", lambda o: _free().energy_gradient, lambda: _symbols("L1", "L2", "L3"),
     False),
    ("symmetric_equations", "the symmetric top I2 = I1: ω̇", "3.34", lambda o: _free().symmetric_rhs, _OMEGA_DOT,
     False),
    ("precession_rate", "Ω of the symmetric top's body-frame precession", "3.36",
     lambda o: _free().symmetric_precession_rate, lambda: sp.Symbol("Omega"), False),
    ("symmetric_solution", "(ω1, ω2)(t) of the symmetric top from (ω1, ω2)(0)", "3.37",
     lambda o: _free().symmetric_general_solution,
     lambda: sp.Matrix([sp.Symbol("omega1(t)"), sp.Symbol("omega2(t)")]), False),
    ("linearised", "I_a η̇_a about the steady spin ω = Ω e1", "3.42",
     lambda o: to_state_symbols(_free().linearised_axis1),
     lambda: sp.Matrix([sp.Symbol(f"I{a}") * _s(f"eta{a}_dot") for a in (1, 2, 3)]), False),
    ("stability_A", "A of I2 η̈2 = A η2 for a spin Ω about e1 (A > 0 unstable)", "3.44",
     lambda o: _free().stability_coefficient, lambda: sp.Symbol("A"), False),
    ("axis_stability", "A for a spin about each principal axis e1, e2, e3", "3.45",
     lambda o: sp.Matrix(_free().axis_stability_coefficients), lambda: sp.Matrix(sp.symbols("A_1 A_2 A_3")), False),
    ("growth_squared", "s(ω): the linearised eigenvalues about a steady ω are 0, ±√s", "3.44",
     lambda o: _free().growth_squared, lambda: sp.Symbol("s"), False),
    ("symmetric_euler_rates", "(φ̇, θ̇, ψ̇) of the free symmetric top with L along ẽ3", "3.60",
     lambda o: sp.Matrix([_free().symmetric_top_euler_rates_spin[_s(r)] for r in _RATES]),
     lambda: _symbols(*_RATES), False),
)


@functools.cache
def derivations() -> Derivations:
    """What ``mechderive derive free_top`` can print, defaults first (L, Euler's equations, T, L²)."""
    takes = frozenset({"sequence", "shape", "moments"})
    return Derivations((Derivation(name, meaning, eq, build, lhs=lhs, default=default, options=takes,
                                   substitute=_parameters)
                        for name, meaning, eq, build, lhs, default in _TABLE), summary=_SUMMARY)


# --- check ----------------------------------------------------------------------------------------


def _draw(rng: random.Random) -> dict[str, Fraction]:
    """Second moments A = Σ m x², B = Σ m y², C = Σ m z² > 0, then I1 = B + C, I2 = C + A, I3 = A + B.

    Every such triple is a real body (I1 + I2 − I3 = 2C > 0 and cyclically) and every real body but
    a plate (C = 0) or a line has one, so the draw covers the region without rejecting any point.
    """
    A, B, C = (decimal4(rng, 0.05, 1.25) for _ in range(3))
    return {"I1": B + C, "I2": C + A, "I3": A + B}


def _refusal(values: Mapping[str, float]) -> str | None:
    from ...inertia.validate import check_principal_moments

    try:
        check_principal_moments(values["I1"], values["I2"], values["I3"])
    except InvalidInputError as exc:
        return str(exc)
    return None


_REGION = BodyRegion(
    parameters=("I1", "I2", "I3"),
    condition="a real body: I1, I2, I3 > 0 and I1 + I2 ≥ I3, I2 + I3 ≥ I1, I3 + I1 ≥ I2, the triangle "
              "inequalities that the solvers require",
    draw=_draw,
    refusal=_refusal,
    widths=(1.2,),
)


@functools.cache
def check_system() -> System:
    """The free top's symbols for ``mechderive check`` (their definitions are derived on first use)."""
    from . import model as ft

    m = ft.model
    qs: list[Quantity] = []
    for k, what in ((0, "body component ω{a} of the angular velocity (principal axes)"),
                    (1, "dω{a}/dt (fixed by Euler's equations (3.33) on a motion)"),
                    (2, "d²ω{a}/dt² (fixed by Euler's equations on a motion)")):
        for a in (1, 2, 3):
            name = jet_name(f"omega{a}", k)
            qs.append(Quantity(name, state_symbol(name), "state" if k == 0 else "derivative", what.format(a=a)))
    qs += [Quantity(f"I{a}", s, "parameter", f"principal moment of inertia about e{a}")
           for a, s in zip((1, 2, 3), (ft.I1, ft.I2, ft.I3))]
    qs += [
        Quantity("T", sp.Symbol("T", real=True), "defined", "kinetic energy ½ Σ I_a ω_a² (3.46), conserved",
                 lambda s: m().energy),
        Quantity("Lsq", sp.Symbol("Lsq", real=True), "defined",
                 "L² = Σ I_a² ω_a² (3.47), conserved (the components L_a are I_a*omega_a)",
                 lambda s: m().angular_momentum_squared),
    ]
    torque_free = {t: 0 for t in ft.tau_symbols}

    def highest() -> dict:
        rhs = m().euler_rhs.xreplace(torque_free)
        return {state_symbol(f"omega{a + 1}_dot"): rhs[a] for a in range(3)}

    lsq = "L² is Lsq; the body components L_a are I1*omega1, I2*omega2, I3*omega3"
    euler_angles = "the free top's state is omega1, omega2, omega3 (Euler angles belong to heavy_top)"
    return System(
        name="free_top",
        summary="free rigid body in principal axes (3.33): Euler's equations without torque",
        coordinates=("omega1", "omega2", "omega3"),
        order=1,
        highest=highest,
        quantities=qs,
        domain={},
        region=_REGION,
        hints={"L": lsq, "L2": lsq, "L1": lsq, "L3": lsq, "L_sq": lsq, "E": "the energy of the free top is T",
               "theta": euler_angles, "phi": euler_angles, "psi": euler_angles,
               "Omega": "define it with --given, e.g. --given 'Omega = omega3*(I1 - I3)/I1'"},
        motion="ω̇ from Euler's equations (3.33) without torque",
        body=RigidBody(moments=(ft.I1, ft.I2, ft.I3), centre_of_mass=(0, 0, 0), mass=sp.Symbol("M", positive=True),
                       gravity=sp.Integer(0)),
    )
