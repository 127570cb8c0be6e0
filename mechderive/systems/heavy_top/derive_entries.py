"""The heavy symmetric top's formulas for ``derive`` and its symbols for ``check`` (section 3.6).

:func:`derivations` lists what ``mechderive derive heavy_top`` prints, each value taken from the
derived model of :mod:`.model` (nothing typed in), in the state symbols ``phi, theta, psi,
phi_dot, …``; :func:`check_system` names the symbols ``mechderive check heavy_top`` knows, their
derived definitions and the real tops its random points are drawn from.  The system object
(:mod:`.system`) hands both to the generic ``derive`` and ``check``.
"""

from __future__ import annotations

import functools
import math
import random
from fractions import Fraction
from typing import Any, Callable, Mapping

import sympy as sp

from ...core.check_system import BodyRegion, Quantity, RigidBody, System, ceil4, decimal4
from ...core.symbols import state_symbol, to_state_symbols
from ...errors import InvalidInputError
from ..base import Derivation, Derivations

__all__ = ["derivations", "check_system"]

#: the title of ``derive``'s output
_SUMMARY = "the heavy symmetric top (section 3.6)"

_s = state_symbol
_ZERO = "= 0"


def _symbols(*names: str) -> sp.Matrix:
    return sp.Matrix([_s(n) for n in names])


def _heavy():
    from .model import model

    return model()


def _parameters(o: Any) -> dict:
    """{I1, I3, l} of a shape about its pivot (default: the shape's frame origin), or the numeric moments."""
    from .model import I1, I3, l

    if o.shape:
        p = o.body_parameters(default_pivot="origin")
        if sp.simplify(p["I1"] - p["I2"]) != 0:
            raise InvalidInputError(f"{o.label('shape')}: expected a body symmetric about axis 3 (I1 = I2), got "
                                    f"I1 = {p['I1']}, I2 = {p['I2']} for {o.shape!r}")
        if p["l"].is_negative:
            raise InvalidInputError(f"{o.label('pivot' if o.pivot is not None else 'shape')}: expected the pivot "
                                    f"below the centre of mass (l >= 0), got l = {p['l']}")
        return {I1: p["I1"], I3: p["I3"], l: p["l"]}
    if o.moments:
        if o.moments[0] != o.moments[1]:
            raise InvalidInputError(f"{o.label('moments')}: expected I1 = I2 for the symmetric heavy top, got "
                                    f"{o.moments[0]} and {o.moments[1]}")
        return {I1: o.moments[0], I3: o.moments[2]}
    return {}


def _q(attr: str) -> Callable[[Any], Any]:
    return lambda o: to_state_symbols(getattr(_heavy(), attr))


# (name, meaning, equation, build, lhs, printed by default)
_TABLE: tuple = (
    ("lagrangian", "the Lagrangian L = T − V", "3.62", _q("lagrangian"), lambda: sp.Symbol("L"), True),
    ("accelerations", "the Euler–Lagrange equations of (3.62) solved for (φ̈, θ̈, ψ̈)", "3.62",
     _q("accelerations"), lambda: _symbols("phi_ddot", "theta_ddot", "psi_ddot"), True),
    ("p_psi", "p_ψ = I3 ω3, conserved (ψ ignorable)", "3.63", _q("spin_momentum"), lambda: sp.Symbol("p_psi"), True),
    ("p_phi", "p_φ, conserved (φ ignorable)", "3.64", _q("azimuthal_momentum"), lambda: sp.Symbol("p_phi"), True),
    ("energy", "the energy E = T + V, conserved", "3.65", _q("energy"), lambda: sp.Symbol("E"), True),
    ("euler_lagrange", "d/dt ∂L/∂q̇ − ∂L/∂q for q = (φ, θ, ψ)", "3.62", _q("euler_lagrange"), _ZERO, False),
    ("mass_matrix", "M_ij = ∂²L/∂q̇_i∂q̇_j (M q̈ = F)", "3.62", _q("mass_matrix"), lambda: sp.Symbol("M_q"), False),
    ("forcing", "F of M q̈ = F", "3.62", _q("forcing"), lambda: sp.Symbol("F_q"), False),
    ("kinetic_energy", "T = ½ ωᵀ diag(I1, I1, I3) ω with ω from (3.58)", "3.62", _q("kinetic_energy"),
     lambda: sp.Symbol("T"), False),
    ("potential_energy", "V = M g l R33", "3.62", _q("potential_energy"), lambda: sp.Symbol("V"), False),
    ("spin", "the spin ω3 = ψ̇ + φ̇ cos θ", "3.63", _q("spin"), lambda: _s("omega3"), False),
    ("constants", "a = I3ω3/I1, b = p_φ/I1, α = 2E'/I1, β = 2Mgl/I1 at the state", "3.72",
     lambda o: sp.Matrix(list(_heavy().constants_from_state.values())),
     lambda: sp.Matrix(list(_heavy().constants_from_state.keys())), False),
    ("precession_rate_theta", "φ̇(θ) from the conserved momenta", "3.67", _q("precession_rate_theta"),
     lambda: _s("phi_dot"), False),
    ("spin_rate_theta", "ψ̇(θ) from the conserved momenta", "3.68", _q("spin_rate_theta"), lambda: _s("psi_dot"),
     False),
    ("reduced_energy", "E' = E − ½ I3 ω3² in θ, θ̇", "3.69", _q("reduced_energy"), lambda: sp.Symbol("E'"), False),
    ("effective_potential", "V_eff(θ)", "3.70", _q("effective_potential_theta"), lambda: sp.Symbol("V_eff"), False),
    ("f_u", "f(u) with u̇² = f(u), u = cos θ", "3.73", _q("f_u"),
     lambda: sp.Function("f")(sp.Symbol("u", real=True)), False),
    ("precession_rate_u", "φ̇(u)", "3.74", _q("precession_rate_u"), lambda: _s("phi_dot"), False),
    ("spin_rate_u", "ψ̇(u)", "3.75", _q("spin_rate_u"), lambda: _s("psi_dot"), False),
    ("f_at_poles", "(f(1), f(−1)) ≤ 0", "3.76", lambda o: sp.Matrix(_heavy().f_at_poles),
     lambda: sp.Matrix([sp.Function("f")(1), sp.Function("f")(-1)]), False),
    ("released_u", "u at release (θ̇ = φ̇ = 0)", "3.77", _q("released_u"), lambda: sp.Symbol("u0"), False),
    ("released_p_phi", "p_φ of a top released with φ̇ = 0", "3.78", _q("released_azimuthal_momentum"),
     lambda: sp.Symbol("p_phi"), False),
    ("uniform_precession", "the condition for precession without nutation at θ0", "3.80",
     lambda o: _heavy().uniform_precession_condition.rhs, lambda: _heavy().uniform_precession_condition.lhs, False),
    ("precession_rates", "the slow and fast uniform precession rates φ̇ solving (3.80), slow the smaller |φ̇| "
                         "(cancellation-free: M g l/(I3 ω3) at θ0 = π/2)", "3.80",
     lambda o: sp.Matrix(_heavy().precession_rates), lambda: sp.Matrix(sp.symbols("phidot_slow phidot_fast")), False),
    ("minimum_spin", "the least spin ω3 for uniform precession at θ0 (0 for θ0 ≥ π/2: any spin)", "3.81",
     _q("minimum_spin"), lambda: sp.Symbol("omega_3min"), False),
    ("sleeping_f", "f(u) of the sleeping top, θ = θ̇ = 0", "3.83", _q("sleeping_f"),
     lambda: sp.Function("f")(sp.Symbol("u", real=True)), False),
    ("sleeping_threshold_spin", "the spin below which the sleeping top is unstable", "3.83",
     _q("sleeping_threshold_spin"), lambda: sp.Symbol("omega_3c"), False),
)


@functools.cache
def derivations() -> Derivations:
    """What ``mechderive derive heavy_top`` can print, defaults first (L, (φ̈, θ̈, ψ̈), p_ψ, p_φ, E)."""
    takes = frozenset({"shape", "moments"})
    return Derivations((Derivation(name, meaning, eq, build, lhs=lhs, default=default, options=takes,
                                   substitute=_parameters)
                        for name, meaning, eq, build, lhs, default in _TABLE), summary=_SUMMARY)


# --- check ----------------------------------------------------------------------------------------


def _draw(rng: random.Random) -> dict[str, Fraction]:
    """I3, M, g, l > 0 and a slack s > 0, then I1 = M l² + I3/2 + s (rounded up): always a real top."""
    I3, M, g = (decimal4(rng, 0.5, 2.5) for _ in range(3))
    l = decimal4(rng, 0.2, 1.2)
    slack = decimal4(rng, 0.05, 1.5)
    return {"I1": ceil4(M * l * l + I3 / 2 + slack), "I3": I3, "M": M, "g": g, "l": l}


def _refusal(values: Mapping[str, float]) -> str | None:
    from .parameters import check_params

    try:
        check_params(dict(values))
    except InvalidInputError as exc:
        return str(exc)
    if not all(values[k] > 0 for k in ("M", "g", "l")):
        return "expected M, g, l > 0 (a heavy top), got " + ", ".join(f"{k} = {values[k]:g}" for k in "Mgl")
    return None


_REGION = BodyRegion(
    parameters=("I1", "I3", "M", "g", "l"),
    condition="a real top: I1, I3, M, g, l > 0 and I1 ≥ M l² + I3/2, the triangle inequality about the "
              "centre of mass that the solvers require",
    draw=_draw,
    refusal=_refusal,
    widths=(1.0, 1.45),  # l and the slack: the narrowest independent draws
)


@functools.cache
def check_system() -> System:
    """The heavy top's symbols for ``mechderive check`` (their definitions are derived on first use)."""
    from ...kinematics import euler_symbolic as _euler
    from . import model as ht

    m = ht.model
    theta = state_symbol("theta")

    def const(key: sp.Symbol) -> Callable[[System], sp.Expr]:
        return lambda s: m().constants_from_state[key]

    def omega(a: int) -> Callable[[System], sp.Expr]:
        return lambda s: _euler.model().state_angular_velocity_body[a]

    meanings = {
        "phi": "φ, precession angle (Euler angles (3.54))", "theta": "θ, nutation angle from the upward vertical",
        "psi": "ψ, spin angle", "phi_dot": "φ̇", "theta_dot": "θ̇", "psi_dot": "ψ̇",
        "phi_ddot": "φ̈ (fixed by the equations of motion on a motion)",
        "theta_ddot": "θ̈ (fixed by the equations of motion on a motion)",
        "psi_ddot": "ψ̈ (fixed by the equations of motion on a motion)",
    }
    qs: list[Quantity] = [Quantity(n, state_symbol(n), "derivative" if n.endswith("_ddot") else "state", text)
                          for n, text in meanings.items()]
    qs += [
        Quantity("I1", ht.I1, "parameter", "moment of inertia about e1 = e2 through the fixed point P"),
        Quantity("I3", ht.I3, "parameter", "moment of inertia about the symmetry axis e3"),
        Quantity("M", ht.M, "parameter", "mass"),
        Quantity("g", ht.g, "parameter", "gravitational acceleration"),
        Quantity("l", ht.l, "parameter", "distance from P to the centre of mass"),
    ]
    qs += [Quantity(f"omega{a + 1}", state_symbol(f"omega{a + 1}"), "defined",
                    f"body component ω{a + 1} of the angular velocity (3.58), derived from ṘRᵀ", omega(a))
           for a in range(3)]
    qs += [
        Quantity("p_psi", ht.p_psi, "defined", "p_ψ = ∂L/∂ψ̇ (3.63), conserved", lambda s: m().spin_momentum),
        Quantity("p_phi", ht.p_phi, "defined", "p_φ = ∂L/∂φ̇ (3.64), conserved",
                 lambda s: m().azimuthal_momentum),
        Quantity("T", sp.Symbol("T", real=True), "defined", "kinetic energy ½ωᵀIω",
                 lambda s: m().kinetic_energy),
        Quantity("V", sp.Symbol("V", real=True), "defined", "potential energy M g l cos θ",
                 lambda s: m().potential_energy),
        Quantity("Lagrangian", sp.Symbol("Lagrangian", real=True), "defined", "L = T − V (3.62)",
                 lambda s: m().state_lagrangian),
        Quantity("E", sp.Symbol("E", real=True), "defined", "energy T + V (3.65), conserved",
                 lambda s: m().energy),
        Quantity("E_prime", sp.Symbol("E_prime", real=True), "defined", "E' = E − ½ I3 ω3² (3.69)",
                 lambda s: m().reduced_energy_state),
        Quantity("a", ht.a, "defined", "a = I3 ω3 / I1 (3.66)", const(ht.a)),
        Quantity("b", ht.b, "defined", "b = p_φ / I1 (3.66)", const(ht.b)),
        Quantity("alpha", ht.alpha, "defined", "α = 2E'/I1 (3.72)", const(ht.alpha)),
        Quantity("beta", ht.beta, "defined", "β = 2 M g l / I1 (3.72)", const(ht.beta)),
        Quantity("u", ht.u, "defined", "u = cos θ (3.71)", lambda s: sp.cos(theta)),
        Quantity("u_dot", state_symbol("u_dot"), "defined", "u̇ = dt(u) = −sin θ θ̇",
                 lambda s: s.formal_dt(s.definition(ht.u))),
        Quantity("u_ddot", state_symbol("u_ddot"), "defined", "ü = dt(u_dot)",
                 lambda s: s.formal_dt(s.definition(state_symbol("u_dot")))),
    ]
    return System(
        name="heavy_top",
        summary="heavy symmetric top (3.62)-(3.83): Euler angles, θ from the upward vertical, I1 = I2 about P",
        coordinates=("phi", "theta", "psi"),
        order=2,
        highest=lambda: m().acceleration_map,
        quantities=qs,
        domain={"theta": (0.15, math.pi - 0.15), "phi": (-3.0, 3.0), "psi": (-3.0, 3.0)},
        region=_REGION,
        hints={
            "I2": "the heavy top is symmetric: I2 = I1",
            "L": "the Lagrangian is called Lagrangian",
            "omega": "the body components are omega1, omega2, omega3",
            "E_p": "E' is E_prime",
            "Omega": "define it with --given, e.g. --given 'Omega = phi_dot'",
        },
        motion="θ̈, φ̈, ψ̈ from the Euler–Lagrange equations of L = T − V",
        body=RigidBody(moments=(ht.I1, ht.I1, ht.I3), centre_of_mass=(0, 0, ht.l), mass=ht.M, gravity=ht.g),
    )
