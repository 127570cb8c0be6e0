"""What ``mechderive derive`` can print: per system, quantity name → (description, equation, derivation).

Every value is taken from the toolkit's own derivations (the models of
:mod:`mechderive.systems`, :mod:`mechderive.kinematics`, :mod:`mechderive.inertia` and
:mod:`.sequences`); nothing here is a formula typed in.  Values are SymPy objects in the
state symbols ``phi, theta, psi, phi_dot, …`` (never functions of t), so that every format —
text, LaTeX, code — prints the same objects.  Each quantity also names its left-hand side
(a SymPy object, or :data:`ZERO` for "… = 0").

Systems: ``free_top``, ``heavy_top``, ``falling_cat``, ``rotation``, ``angular_velocity``,
``inertia`` (needs a shape).  :func:`listing` gives what can be asked of each, with the
chapter's equation numbers.

>>> [name for name, _, eq in listing("heavy_top")][:3]
['lagrangian', 'accelerations', 'p_psi']
>>> SYSTEMS["heavy_top"].quantities["p_phi"].equation
'3.64'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import sympy as sp

from ..core.codegen import ARGUMENTS
from ..core.symbols import state_symbol, to_state_symbols
from ..errors import InvalidInputError
from .options import Options, body_parameters

__all__ = ["ZERO", "Quantity", "System", "SYSTEMS", "ARGUMENTS", "listing", "system"]

#: Marks a quantity printed as "value = 0" (no left-hand side).
ZERO = "= 0"

_s = state_symbol


def _symbols(*names: str) -> sp.Matrix:
    return sp.Matrix([_s(n) for n in names])


_RATES = ("phi_dot", "theta_dot", "psi_dot")
_OMEGA = ("omega1", "omega2", "omega3")


@dataclass(frozen=True)
class Quantity:
    """One printable quantity: a one-line description, the chapter's equation number, a derivation."""

    description: str
    equation: str
    build: Callable[[Options], Any]
    lhs: Callable[[], Any] | str


@dataclass(frozen=True)
class System:
    """A system: its quantities (in listing order), those printed by default, and the options it takes."""

    name: str
    summary: str
    quantities: dict[str, Quantity]
    defaults: tuple[str, ...]
    takes: frozenset[str]
    parameters: Callable[[Options], dict] | None = None


# ------------------------------------------------------------------------------------- free top
def _free():
    from ..systems.free_top.model import model

    return model()


def _free_lagrangian(o: Options) -> sp.Expr:
    from ..systems.free_top.model import I1, I2, I3
    from .sequences import sequence_model

    w = to_state_symbols(sequence_model(o.sequence, o.frame).angular_velocity_body)
    T = sp.expand((w.T * sp.diag(I1, I2, I3) * w)[0] / 2)
    parts = sp.collect(T, [I1, I2, I3], evaluate=False)
    return sum(k * sp.factor(v) for k, v in parts.items())


def _free_parameters(o: Options) -> dict:
    from ..systems.free_top.model import I1, I2, I3

    if o.shape:
        p = body_parameters(o, default_pivot="centre")
        return {I1: p["I1"], I2: p["I2"], I3: p["I3"]}
    if o.moments:
        return dict(zip((I1, I2, I3), o.moments))
    return {}


_FREE = {
    "lagrangian": Quantity("the Lagrangian L = T = ½ ω_a I_ab ω_b in Euler angles of the chosen sequence", "3.18",
                           _free_lagrangian, lambda: sp.Symbol("L")),
    "euler_equations": Quantity("Euler's equations solved for ω̇ (free body)", "3.33",
                                lambda o: _free().free_rhs, lambda: _symbols("omega1_dot", "omega2_dot", "omega3_dot")),
    "energy": Quantity("kinetic energy T, conserved", "3.46", lambda o: _free().energy, lambda: sp.Symbol("T")),
    "angular_momentum_squared": Quantity("L² = L_a L_a, conserved", "3.47",
                                         lambda o: _free().angular_momentum_squared, lambda: sp.Symbol("L") ** 2),
    "euler_equations_torque": Quantity("Euler's equations with a body torque τ, solved for ω̇", "3.33",
                                       lambda o: _free().euler_rhs,
                                       lambda: _symbols("omega1_dot", "omega2_dot", "omega3_dot")),
    "angular_momentum": Quantity("body components L_a = I_ab ω_b", "3.28",
                                 lambda o: to_state_symbols(_free().angular_momentum_body), lambda: _symbols("L1", "L2", "L3")),
    "energy_gradient": Quantity("L = ∇_ω T", "3.49", lambda o: _free().energy_gradient,
                                lambda: _symbols("L1", "L2", "L3")),
    "symmetric_equations": Quantity("the symmetric top I2 = I1: ω̇", "3.34", lambda o: _free().symmetric_rhs,
                                    lambda: _symbols("omega1_dot", "omega2_dot", "omega3_dot")),
    "precession_rate": Quantity("Ω of the symmetric top's body-frame precession", "3.36",
                                lambda o: _free().symmetric_precession_rate, lambda: sp.Symbol("Omega")),
    "symmetric_solution": Quantity("(ω1, ω2)(t) of the symmetric top from (ω1, ω2)(0)", "3.37",
                                   lambda o: _free().symmetric_general_solution,
                                   lambda: sp.Matrix([sp.Symbol("omega1(t)"), sp.Symbol("omega2(t)")])),
    "linearised": Quantity("I_a η̇_a about the steady spin ω = Ω e1", "3.42",
                           lambda o: to_state_symbols(_free().linearised_axis1),
                           lambda: sp.Matrix([sp.Symbol(f"I{a}") * _s(f"eta{a}_dot") for a in (1, 2, 3)])),
    "stability_A": Quantity("A of I2 η̈2 = A η2 for a spin Ω about e1 (A > 0 unstable)", "3.44",
                            lambda o: _free().stability_coefficient, lambda: sp.Symbol("A")),
    "axis_stability": Quantity("A for a spin about each principal axis e1, e2, e3", "3.45",
                               lambda o: sp.Matrix(_free().axis_stability_coefficients),
                               lambda: sp.Matrix(sp.symbols("A_1 A_2 A_3"))),
    "growth_squared": Quantity("s(ω): the linearised eigenvalues about a steady ω are 0, ±√s", "3.44",
                               lambda o: _free().growth_squared, lambda: sp.Symbol("s")),
    "symmetric_euler_rates": Quantity("(φ̇, θ̇, ψ̇) of the free symmetric top with L along ẽ3", "3.60",
                                      lambda o: sp.Matrix([_free().symmetric_top_euler_rates_spin[_s(r)] for r in _RATES]),
                                      lambda: _symbols(*_RATES)),
}

# ------------------------------------------------------------------------------------ heavy top
def _heavy():
    from ..systems.heavy_top.model import model

    return model()


def _heavy_parameters(o: Options) -> dict:
    from ..systems.heavy_top.model import I1, I3, l

    if o.shape:
        p = body_parameters(o, default_pivot="origin")
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


def _heavy_q(attr: str) -> Callable[[Options], Any]:
    return lambda o: to_state_symbols(getattr(_heavy(), attr))


_HEAVY = {
    "lagrangian": Quantity("the Lagrangian L = T − V", "3.62", _heavy_q("lagrangian"), lambda: sp.Symbol("L")),
    "accelerations": Quantity("the Euler–Lagrange equations of (3.62) solved for (φ̈, θ̈, ψ̈)", "3.62",
                              _heavy_q("accelerations"), lambda: _symbols("phi_ddot", "theta_ddot", "psi_ddot")),
    "p_psi": Quantity("p_ψ = I3 ω3, conserved (ψ ignorable)", "3.63", _heavy_q("spin_momentum"),
                      lambda: sp.Symbol("p_psi")),
    "p_phi": Quantity("p_φ, conserved (φ ignorable)", "3.64", _heavy_q("azimuthal_momentum"),
                      lambda: sp.Symbol("p_phi")),
    "energy": Quantity("the energy E = T + V, conserved", "3.65", _heavy_q("energy"), lambda: sp.Symbol("E")),
    "euler_lagrange": Quantity("d/dt ∂L/∂q̇ − ∂L/∂q for q = (φ, θ, ψ)", "3.62", _heavy_q("euler_lagrange"), ZERO),
    "mass_matrix": Quantity("M_ij = ∂²L/∂q̇_i∂q̇_j (M q̈ = F)", "3.62", _heavy_q("mass_matrix"),
                            lambda: sp.Symbol("M_q")),
    "forcing": Quantity("F of M q̈ = F", "3.62", _heavy_q("forcing"), lambda: sp.Symbol("F_q")),
    "kinetic_energy": Quantity("T = ½ ωᵀ diag(I1, I1, I3) ω with ω from (3.58)", "3.62", _heavy_q("kinetic_energy"),
                               lambda: sp.Symbol("T")),
    "potential_energy": Quantity("V = M g l R33", "3.62", _heavy_q("potential_energy"), lambda: sp.Symbol("V")),
    "spin": Quantity("the spin ω3 = ψ̇ + φ̇ cos θ", "3.63", _heavy_q("spin"), lambda: _s("omega3")),
    "constants": Quantity("a = I3ω3/I1, b = p_φ/I1, α = 2E'/I1, β = 2Mgl/I1 at the state", "3.72",
                          lambda o: sp.Matrix(list(_heavy().constants_from_state.values())),
                          lambda: sp.Matrix(list(_heavy().constants_from_state.keys()))),
    "precession_rate_theta": Quantity("φ̇(θ) from the conserved momenta", "3.67", _heavy_q("precession_rate_theta"),
                                      lambda: _s("phi_dot")),
    "spin_rate_theta": Quantity("ψ̇(θ) from the conserved momenta", "3.68", _heavy_q("spin_rate_theta"),
                                lambda: _s("psi_dot")),
    "reduced_energy": Quantity("E' = E − ½ I3 ω3² in θ, θ̇", "3.69", _heavy_q("reduced_energy"),
                               lambda: sp.Symbol("E'")),
    "effective_potential": Quantity("V_eff(θ)", "3.70", _heavy_q("effective_potential_theta"),
                                    lambda: sp.Symbol("V_eff")),
    "f_u": Quantity("f(u) with u̇² = f(u), u = cos θ", "3.73", _heavy_q("f_u"),
                    lambda: sp.Function("f")(sp.Symbol("u", real=True))),
    "precession_rate_u": Quantity("φ̇(u)", "3.74", _heavy_q("precession_rate_u"), lambda: _s("phi_dot")),
    "spin_rate_u": Quantity("ψ̇(u)", "3.75", _heavy_q("spin_rate_u"), lambda: _s("psi_dot")),
    "f_at_poles": Quantity("(f(1), f(−1)) ≤ 0", "3.76", lambda o: sp.Matrix(_heavy().f_at_poles),
                           lambda: sp.Matrix([sp.Function("f")(1), sp.Function("f")(-1)])),
    "released_u": Quantity("u at release (θ̇ = φ̇ = 0)", "3.77", _heavy_q("released_u"), lambda: sp.Symbol("u0")),
    "released_p_phi": Quantity("p_φ of a top released with φ̇ = 0", "3.78", _heavy_q("released_azimuthal_momentum"),
                               lambda: sp.Symbol("p_phi")),
    "uniform_precession": Quantity("the condition for precession without nutation at θ0", "3.80",
                                   lambda o: _heavy().uniform_precession_condition.rhs,
                                   lambda: _heavy().uniform_precession_condition.lhs),
    "precession_rates": Quantity("the slow and fast uniform precession rates φ̇ solving (3.80), slow the smaller |φ̇| "
                                 "(cancellation-free: M g l/(I3 ω3) at θ0 = π/2)", "3.80",
                                 lambda o: sp.Matrix(_heavy().precession_rates),
                                 lambda: sp.Matrix(sp.symbols("phidot_slow phidot_fast"))),
    "minimum_spin": Quantity("the least spin ω3 for uniform precession at θ0 (0 for θ0 ≥ π/2: any spin)", "3.81", _heavy_q("minimum_spin"),
                             lambda: sp.Symbol("omega_3min")),
    "sleeping_f": Quantity("f(u) of the sleeping top, θ = θ̇ = 0", "3.83", _heavy_q("sleeping_f"),
                           lambda: sp.Function("f")(sp.Symbol("u", real=True))),
    "sleeping_threshold_spin": Quantity("the spin below which the sleeping top is unstable", "3.83",
                                        _heavy_q("sleeping_threshold_spin"), lambda: sp.Symbol("omega_3c")),
}

# ---------------------------------------------------------------------------------- falling cat
def _cat():
    from ..systems.deformable.cat import cat_body

    return cat_body()


_CAT = {
    "Omega_bend": Quantity("gauge potential Ω_A for A = bend (Ω = Ω_A ẋ^A at L = 0)", "3.87",
                           lambda o: _cat().connection[0], lambda: sp.Symbol("Omega_bend")),
    "Omega_swivel": Quantity("gauge potential Ω_A for A = swivel", "3.87",
                             lambda o: _cat().connection[1], lambda: sp.Symbol("Omega_swivel")),
    "field_strength": Quantity("F_AB, A = bend, B = swivel (as corrected in catalog 3.7)", "3.103",
                               lambda o: _cat().field_strength[0][1], lambda: sp.Symbol("F_bend,swivel")),
    "angular_velocity": Quantity("Ω = R⁻¹Ṙ = hat(Ĩ⁻¹ L̃) at L = 0", "3.92",
                                 lambda o: _cat().angular_velocity, lambda: sp.Symbol("Omega")),
    "inertia_tensor": Quantity("Ĩ of the shape", "3.93", lambda o: _cat().inertia_tensor, lambda: sp.Symbol("Itilde")),
    "apparent_angular_momentum": Quantity("L̃ of the shape change", "3.94",
                                          lambda o: _cat().apparent_angular_momentum, lambda: sp.Symbol("Ltilde")),
}

# ------------------------------------------------------------------------- rotation, angular velocity
def _kin(o: Options):
    from .sequences import sequence_model

    return sequence_model(o.sequence, o.frame)


def _axis(k: int) -> Callable[[Options], Any]:
    def build(o: Options) -> sp.Matrix:
        from ..kinematics.euler import axis_rotation

        return axis_rotation(k, sp.Symbol("alpha", real=True))
    return build


_ROTATION = {
    "R": Quantity("R(φ, θ, ψ), e_a = R_ab ẽ_b, for the chosen sequence", "3.54",
                  lambda o: to_state_symbols(_kin(o).rotation), lambda: sp.Symbol("R")),
    "A": Quantity("the active rotation A = Rᵀ (SciPy's Rotation.from_euler(...).as_matrix())", "3.54",
                  lambda o: to_state_symbols(_kin(o).rotation).T, lambda: sp.Symbol("A")),
    "R1": Quantity("R1(α) = exp(α J1)", "3.52", _axis(1), lambda: sp.Symbol("R_1")),
    "R2": Quantity("R2(α) = exp(α J2)", "3.52", _axis(2), lambda: sp.Symbol("R_2")),
    "R3": Quantity("R3(α) = exp(α J3)", "3.51", _axis(3), lambda: sp.Symbol("R_3")),
}

_ANGULAR = {
    "body": Quantity("body components ω_a of ω = ṘRᵀ", "3.58",
                     lambda o: to_state_symbols(_kin(o).angular_velocity_body), lambda: _symbols(*_OMEGA)),
    "space": Quantity("space components ω̃ = Rᵀω", "3.58",
                      lambda o: to_state_symbols(_kin(o).angular_velocity_space),
                      lambda: sp.Matrix(sp.symbols("omegatilde_1 omegatilde_2 omegatilde_3"))),
    "matrix": Quantity("ω_ac = Ṙ_ab R_cb", "3.5",
                       lambda o: to_state_symbols(_kin(o).angular_velocity_matrix), lambda: sp.Symbol("omega")),
    "convective": Quantity("Ω = R⁻¹Ṙ", "3.10",
                           lambda o: to_state_symbols(_kin(o).convective_angular_velocity_matrix),
                           lambda: sp.Symbol("Omega")),
    "euler_rates": Quantity("(φ̇, θ̇, ψ̇) from the body ω (singular at gimbal lock)", "3.58",
                            lambda o: _kin(o).euler_rates, lambda: _symbols(*_RATES)),
}

# -------------------------------------------------------------------------------------- inertia
def _body(o: Options):
    from ..inertia.bodies import body_inertia_symbolic

    return body_inertia_symbolic(o.shape)


def _about_pivot(o: Options) -> sp.Matrix:
    z = o.pivot_expr()
    return _body(o).inertia_about(sp.Matrix([0, 0, z if z is not None else 0])).applyfunc(sp.factor)


_INERTIA = {
    "centre_of_mass": Quantity("the centre of mass in the body's coordinates", "3.20",
                               lambda o: _body(o).centre_of_mass, lambda: sp.Symbol("r_cm")),
    "inertia_cm": Quantity("I about the centre of mass, by integrating ρ over the body", "3.20",
                           lambda o: _body(o).inertia_cm, lambda: sp.Symbol("I_cm")),
    "inertia_pivot": Quantity("I about the pivot (0, 0, z), by default the frame origin (parallel axes)", "3.25",
                              _about_pivot, lambda: sp.Symbol("I_P")),
    "principal_moments": Quantity("the principal moments (I1, I2, I3) about the centre of mass", "3.21",
                                  lambda o: sp.Matrix([_body(o).inertia_cm[a, a] for a in range(3)]),
                                  lambda: sp.Matrix(sp.symbols("I1 I2 I3"))),
}

_NUMBERS = frozenset({"values"})
SYSTEMS: dict[str, System] = {
    "free_top": System("free_top", "the free rigid body in principal axes (sections 3.3–3.5)", _FREE,
                       ("lagrangian", "euler_equations", "energy", "angular_momentum_squared"),
                       _NUMBERS | {"sequence", "shape", "moments"}, _free_parameters),
    "heavy_top": System("heavy_top", "the heavy symmetric top (section 3.6)", _HEAVY,
                        ("lagrangian", "accelerations", "p_psi", "p_phi", "energy"),
                        _NUMBERS | {"shape", "moments"}, _heavy_parameters),
    "falling_cat": System("falling_cat", "the falling cat, two jointed halves (section 3.7)", _CAT,
                          ("Omega_bend", "Omega_swivel", "field_strength"), _NUMBERS),
    "rotation": System("rotation", "rotation matrices of Euler angles (section 3.5)", _ROTATION, ("R",),
                       _NUMBERS | {"sequence"}),
    "angular_velocity": System("angular_velocity", "angular velocity in Euler angles (sections 3.1.1, 3.5.2)",
                               _ANGULAR, ("body", "space"), _NUMBERS | {"sequence"}),
    "inertia": System("inertia", "inertia of a standard body SHAPE (section 3.2)", _INERTIA,
                      ("centre_of_mass", "inertia_cm", "inertia_pivot"), _NUMBERS | {"shape"}),
}


def system(name: str) -> System:
    """The :class:`System` called ``name``; raises listing the systems otherwise."""
    if name not in SYSTEMS:
        raise InvalidInputError(f"expected a system among {', '.join(SYSTEMS)}, got {name!r}")
    return SYSTEMS[name]


def listing(name: str) -> list[tuple[str, str, str]]:
    """[(quantity, description, equation number)] of a system, defaults first."""
    return [(q, spec.description, spec.equation) for q, spec in system(name).quantities.items()]
