"""Catalog entries for section 3.6: the heavy symmetric top, (3.62)–(3.83).

Every printed formula is compared with :class:`~mechderive.systems.heavy_top.model.HeavyTopModel`,
which derives L = T − V from ω of (3.58) and V = M g l R33, and everything else from L through
the generic Lagrangian layer (momenta, energy, Routhian) and algebra on its results.  The
qualitative statements are checked numerically: the roots of f(u) at seeded random states,
the three kinds of motion, and integrations of the derived Euler–Lagrange equations (uniform
precession, the sleeping top's threshold).

(3.66), (3.71) and (3.72) are definitions (a, b, u, α, β); the model uses them as such, and
(3.66) is checked for what the text says of it: a and b are constants of the motion.

(3.81) is verified in its domain.  It is the condition for real roots of the quadratic (3.80),
exactly I3²ω3² > 4 I1 M g l cos θ0, written for ω3 > 0 and cos θ0 > 0 (read |ω3| for a
negative spin).  For a hanging top, θ0 > π/2, the printed square root is imaginary and the text's
"the top has to be spinning fast enough" does not apply: the discriminant is positive for every
spin, and the two rates have opposite signs.  At θ0 = π/2 (3.80) is linear: one rate, Mgl/(I3ω3).
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

from ..core.compile import compile_expressions
from ..core.simplify import is_zero
from ..core.symbols import coordinate, state_symbol
from ..kinematics import euler
from ..systems.heavy_top import model as ht
from .checks import all_pass, same, same_numerically
from .registry import Claim, Outcome, register

I1, I3, M, g, l = ht.I1, ht.I3, ht.M, ht.g, ht.l
a, b, alpha, beta, u, u0, theta0, omega3 = ht.a, ht.b, ht.alpha, ht.beta, ht.u, ht.u0, ht.theta0, ht.omega3
theta, phi_dot, theta_dot, psi_dot = (state_symbol(n) for n in ("theta", "phi_dot", "theta_dot", "psi_dot"))
omega1, omega2 = state_symbol("omega1"), state_symbol("omega2")
c, s = sp.cos, sp.sin


def _m() -> ht.HeavyTopModel:
    return ht.model()


def _spin_derived(expr) -> sp.Expr:
    """``expr`` with the symbol ω3 replaced by the spin ψ̇ + φ̇ cos θ derived from ṘRᵀ (3.58)."""
    return sp.sympify(expr, strict=True).subs(omega3, _m().spin)


def _rate_along_motion(F) -> sp.Expr:
    """dF/dt along the derived equations of motion: Σ ∂F/∂q q̇ + ∂F/∂q̇ q̈(q, q̇)."""
    m = _m()
    F = sp.sympify(F, strict=True)
    return (sum(F.diff(q) * v for q, v in zip(m.positions, m.velocities))
            + sum(F.diff(v) * acc for v, acc in zip(m.velocities, m.accelerations)))


def _conserved(exprs, names: str) -> Outcome:
    for e, name in zip(exprs, names.split(", ")):
        if not is_zero(_rate_along_motion(e)):
            return Outcome(False, f"d({name})/dt ≠ 0 along the derived equations of motion")
    return Outcome(True, f"d/dt of {names} vanish exactly along the derived equations of motion")


# --- 3.6: the Lagrangian, constants of motion, reduction to θ --------------------------------

SECTION = "3.6"

register(Claim(
    "3.62", SECTION,
    "L = ½I1(ω1² + ω2²) + ½I3ω3² − Mgl cos θ = ½I1(θ̇² + sin²θ φ̇²) + ½I3(ψ̇ + cos θ φ̇)² − Mgl cos θ",
    "symbolic",
    printed=lambda: (
        I1 * (omega1**2 + omega2**2) / 2 + I3 * omega3**2 / 2 - M * g * l * c(theta),
        I1 * (theta_dot**2 + s(theta) ** 2 * phi_dot**2) / 2 + I3 * (psi_dot + c(theta) * phi_dot) ** 2 / 2
        - M * g * l * c(theta)),
    check=lambda f: all_pass([
        same(f[0].subs(dict(zip((omega1, omega2, omega3), euler.model().state_angular_velocity_body))),
             _m().state_lagrangian,
             "first line with ω from (3.58) vs ½ωᵀIω − V"),
        same(f[1], _m().state_lagrangian, "second line vs ½ωᵀIω − V"),
    ]),
    parts=("in ω", "in Euler angles"),
))


def _check_ignorable(f) -> Outcome:
    found = set(_m().cyclic_coordinates)
    ok = set(f) == found
    return Outcome(ok, f"∂L/∂q ≡ 0 exactly for {sorted(map(str, found))}; printed {sorted(map(str, f))}")


register(Claim(
    "3.62 ignorable", SECTION,
    "ψ and φ are ignorable coordinates (∂L/∂ψ = ∂L/∂φ = 0), θ is not",
    "symbolic",
    printed=lambda: (coordinate("psi"), coordinate("phi")),
    check=_check_ignorable,
    perturbed=lambda: (coordinate("theta"), coordinate("theta")),  # the coordinate that is not ignorable
    parts=("ψ", "φ"),
))

register(Claim(
    "3.63", SECTION,
    "p_ψ = I3(ψ̇ + cos θ φ̇) = I3ω3, the angular momentum about the symmetry axis",
    "symbolic",
    printed=lambda: (I3 * (psi_dot + c(theta) * phi_dot), I3 * omega3),
    check=lambda f: all_pass([same(f[0], _m().spin_momentum, "p_ψ vs ∂L/∂ψ̇"),
                              same(_spin_derived(f[1]), _m().spin_momentum, "I3ω3 vs ∂L/∂ψ̇")]),
    parts=("I3(ψ̇ + cos θ φ̇)", "I3ω3"),
))

register(Claim(
    "3.64", SECTION,
    "p_φ = I1 sin²θ φ̇ + I3 cos θ (ψ̇ + φ̇ cos θ)",
    "symbolic",
    printed=lambda: I1 * s(theta) ** 2 * phi_dot + I3 * c(theta) * (psi_dot + phi_dot * c(theta)),
    check=lambda f: same(f, _m().azimuthal_momentum, "p_φ vs ∂L/∂φ̇"),
))

register(Claim(
    "3.65", SECTION,
    "E = T + V = ½I1(θ̇² + φ̇² sin²θ) + ½I3ω3² + Mgl cos θ",
    "symbolic",
    printed=lambda: I1 * (theta_dot**2 + phi_dot**2 * s(theta) ** 2) / 2 + I3 * omega3**2 / 2 + M * g * l * c(theta),
    check=lambda f: same(_spin_derived(f), _m().energy, "E vs Σ q̇ ∂L/∂q̇ − L"),
))


def _printed_constants() -> tuple:
    return (I3 * (psi_dot + c(theta) * phi_dot),
            I1 * s(theta) ** 2 * phi_dot + I3 * c(theta) * (psi_dot + phi_dot * c(theta)),
            I1 * (theta_dot**2 + phi_dot**2 * s(theta) ** 2) / 2 + I3 * omega3**2 / 2 + M * g * l * c(theta))


register(Claim(
    "3.65 conserved", SECTION,
    "p_ψ, p_φ and E are constants of motion",
    "symbolic",
    printed=_printed_constants,
    check=lambda f: _conserved([f[0], f[1], _spin_derived(f[2])], "p_ψ, p_φ, E"),
    # An affine image of a constant is a constant, so perturb() cannot make these wrong; instead drop a
    # term: I3ψ̇ (ψ̇ = ω3 − φ̇ cos θ changes as θ and φ̇ do), p_φ without the spin's share I3ω3 cos θ,
    # E without the potential energy (each exchanges with the dropped term as θ changes).
    perturbed=lambda: (I3 * psi_dot, I1 * s(theta) ** 2 * phi_dot,
                       I1 * (theta_dot**2 + phi_dot**2 * s(theta) ** 2) / 2 + I3 * omega3**2 / 2),
    parts=("p_ψ", "p_φ", "E"),
))

register(Claim(
    "3.66", SECTION,
    "a = I3ω3/I1 and b = p_φ/I1 are constants (defined from the conserved p_ψ = I3ω3 and p_φ)",
    "symbolic",
    printed=lambda: (I3 * omega3 / I1, sp.Symbol("p_phi", real=True) / I1),
    check=lambda f: _conserved([_spin_derived(f[0]), f[1].subs(sp.Symbol("p_phi", real=True),
                                                                _m().azimuthal_momentum)], "a, b"),
    # affine images of a, b are constants too (see 3.65 conserved): a with ψ̇ for ω3, b with a factor cos θ
    perturbed=lambda: (I3 * psi_dot / I1, sp.Symbol("p_phi", real=True) * c(theta) / I1),
    parts=("a", "b"),
))

register(Claim(
    "3.67", SECTION,
    "φ̇ = (b − a cos θ)/sin²θ",
    "symbolic",
    printed=lambda: (b - a * c(theta)) / s(theta) ** 2,
    check=lambda f: same(f, _m().precession_rate_theta, "φ̇ vs p_φ = I1 b, p_ψ = I1 a solved"),
))

register(Claim(
    "3.68", SECTION,
    "ψ̇ = I1a/I3 − (b − a cos θ) cos θ/sin²θ",
    "symbolic",
    printed=lambda: I1 * a / I3 - (b - a * c(theta)) * c(theta) / s(theta) ** 2,
    check=lambda f: same(f, _m().spin_rate_theta, "ψ̇ vs p_φ = I1 b, p_ψ = I1 a solved"),
))


def _printed_veff() -> sp.Expr:
    return I1 * (b - a * c(theta)) ** 2 / (2 * s(theta) ** 2) + M * g * l * c(theta)


def _check_3_69(f) -> Outcome:
    m = _m()
    state = {k: v for k, v in m.constants_from_state.items() if k in (a, b)}
    return all_pass([
        same(f, m.reduced_energy, "E' vs the Routhian's energy less ½I3ω3²"),
        same(f.subs(state), m.reduced_energy_state, "E' at a, b of the state vs E − ½I3ω3²"),
    ])


register(Claim(
    "3.69", SECTION,
    "E' = E − ½I3ω3² = ½I1θ̇² + V_eff(θ), a constant",
    "symbolic",
    printed=lambda: I1 * theta_dot**2 / 2 + _printed_veff(),
    check=_check_3_69,
))

register(Claim(
    "3.70", SECTION,
    "V_eff(θ) = I1(b − a cos θ)²/(2 sin²θ) + Mgl cos θ",
    "symbolic",
    printed=_printed_veff,
    check=lambda f: same(f, _m().effective_potential_theta, "V_eff vs −R(θ̇ = 0) − ½I3ω3²"),
))


def _generic_f(m) -> sp.Expr:
    """f(u) found by the generic recipe (:mod:`mechderive.core.quadrature`: Routh reduction, then the substitution
    that makes q̇² a polynomial) on the model's own Lagrangian, in a, b, α, β by (3.66), (3.72), E' = E − p_ψ²/(2I3)."""
    from ..core.quadrature import find_substitution, reduce_to_quadrature

    found = find_substitution(reduce_to_quadrature(m))
    if found.name != "u = cos q":
        return sp.nan
    sym = {x.name: x for x in found.polynomial.free_symbols}
    p_phi, p_psi, E = sym["p_phi"], sym["p_psi"], sym["E"]
    in_ab = {p_phi: I1 * b, p_psi: I1 * a, E: I1 * alpha / 2 + I1**2 * a**2 / (2 * I3), M: beta * I1 / (2 * g * l)}
    return found.polynomial.as_expr().subs(in_ab).subs(found.variable, u)


def _check_3_73(f) -> Outcome:
    m = _m()
    at_state = f.subs(m.constants_from_state).subs(u, c(theta))
    return all_pass([
        same(f, m.f_u, "f(u) vs u̇² from (3.69)"),
        same(at_state, m.u_dot_squared, "f(cos θ) at a, b, α, β of the state vs (d cos θ/dt)²"),
        same(f, _generic_f(m), "f(u) vs the generic reduction of L with u = cos θ (core.quadrature)"),
    ])


register(Claim(
    "3.73", SECTION,
    "u̇² = (1 − u²)(α − βu) − (b − au)² ≡ f(u), u = cos θ, α = 2E'/I1, β = 2Mgl/I1",
    "symbolic",
    printed=lambda: (1 - u**2) * (alpha - beta * u) - (b - a * u) ** 2,
    check=_check_3_73,
))

def _generic_rate(m, name: str) -> sp.Expr:
    """ċ(u) of the cyclic coordinate ``name`` found by the generic recipe (:func:`mechderive.core.quadrature.cyclic_rates`,
    which the closed form of any Lagrangian integrates by partial fractions and Π), in a, b by (3.66)."""
    from ..core.quadrature import cyclic_rates, find_substitution, reduce_to_quadrature

    found = find_substitution(reduce_to_quadrature(m))
    entry = cyclic_rates(m, found).get(name)
    if found.name != "u = cos q" or entry is None or isinstance(entry, str):
        return sp.nan
    N, D = entry
    sym = {x.name: x for x in N.free_symbols | D.free_symbols}
    in_ab = {sym[k]: v for k, v in (("p_phi", I1 * b), ("p_psi", I1 * a)) if k in sym}
    return (N.as_expr() / D.as_expr()).subs(in_ab).subs(found.variable, u)


register(Claim(
    "3.74", SECTION,
    "φ̇ = (b − au)/(1 − u²)",
    "symbolic",
    printed=lambda: (b - a * u) / (1 - u**2),
    check=lambda f: all_pass([
        same(f, _m().precession_rate_u, "φ̇(u) vs (3.67) at cos θ = u"),
        same(f, _generic_rate(_m(), "phi"), "φ̇(u) vs the generic reduction's rate of φ (core.quadrature)"),
    ]),
))

register(Claim(
    "3.75", SECTION,
    "ψ̇ = I1a/I3 − u(b − au)/(1 − u²)",
    "symbolic",
    printed=lambda: I1 * a / I3 - u * (b - a * u) / (1 - u**2),
    check=lambda f: all_pass([
        same(f, _m().spin_rate_u, "ψ̇(u) vs (3.68) at cos θ = u"),
        same(f, _generic_rate(_m(), "psi"), "ψ̇(u) vs the generic reduction's rate of ψ (core.quadrature)"),
    ]),
))


def _check_limits(f) -> Outcome:
    got = _m().f_limits
    ok = tuple(f) == tuple(got)
    return Outcome(ok, f"f → {got[0]} as u → ∞ and {got[1]} as u → −∞ (leading term β u³, β = 2Mgl/I1 > 0); "
                       f"printed {tuple(f)}")


register(Claim(
    "3.76", SECTION,
    "f(u) is a cubic with f → +∞ as u → ∞ and f → −∞ as u → −∞",
    "symbolic",
    printed=lambda: (sp.oo, -sp.oo),
    check=_check_limits,
    perturbed=lambda: (-sp.oo, sp.oo),  # perturb() leaves ±∞ unchanged: flip each sign
    parts=("u → ∞", "u → −∞"),
))

register(Claim(
    "3.76 f(±1)", SECTION,
    "f(±1) = −(b ∓ a)² ≤ 0",
    "symbolic",
    printed=lambda: (-(b - a) ** 2, -(b + a) ** 2),
    check=lambda f: same(sp.Matrix(f), sp.Matrix(_m().f_at_poles), "(f(1), f(−1))"),
    parts=("f(1)", "f(−1)"),
))


# Random physical states for the qualitative claims: parameters and (θ, θ̇, φ̇, ψ̇), seeded.
_N_STATES = 400


def _random_states(seed: int, *, released: bool = False) -> np.ndarray:
    """Rows (I1, I3, M, g, l, θ, θ̇, φ̇, ψ̇); θ ∈ (0.15, π − 0.15), |θ̇| ≥ 0.2 unless ``released`` (θ̇ = φ̇ = 0)."""
    rng = np.random.default_rng(seed)
    n = _N_STATES
    rows = np.column_stack([
        rng.uniform(0.5, 2.0, n), rng.uniform(0.2, 2.0, n), rng.uniform(0.5, 2.0, n),
        rng.uniform(1.0, 10.0, n), rng.uniform(0.1, 1.0, n), rng.uniform(0.15, np.pi - 0.15, n),
        rng.choice([-1.0, 1.0], n) * rng.uniform(0.2, 3.0, n), rng.uniform(-3.0, 3.0, n), rng.uniform(-20.0, 20.0, n),
    ])
    if released:
        rows[:, 6] = rows[:, 7] = 0.0
    return rows


def _roots_and_ab(rows: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """The roots of f (compiled from the derivation) and (a, b) at each state."""
    m = _m()
    coeffs = m.f_coefficients_function()(*rows.T)
    ab = compile_expressions([m.constants_from_state[a], m.constants_from_state[b]], [*ht.PARAMETERS, *ht.STATE],
                             name="heavy_top_ab")(*rows.T)
    return [np.roots(cf) for cf in coeffs], ab


@functools.cache
def _root_counts() -> list[tuple[np.ndarray, np.ndarray, tuple[int, int], bool]]:
    """At each random state: (state, real roots of f, (roots in [−1, 1], above 1), whether the two inside bracket
    u = cos θ).  An imaginary part < 1e-9 is real: np.roots is accurate to ~1e-13 for these well-separated roots.
    Computed once per session."""
    rows = _random_states(376)
    roots, _ = _roots_and_ab(rows)
    out = []
    for row, r in zip(rows, roots):
        real = np.sort(r[np.abs(r.imag) < 1e-9].real)
        inside, above = real[(real >= -1) & (real <= 1)], real[real > 1]
        u_now = np.cos(row[5])
        out.append((row, real, (len(inside), len(above)), len(inside) == 2 and inside[0] < u_now < inside[1]))
    return out


def _check_two_roots(f) -> Outcome:
    """Count f's real roots in [−1, 1] and above 1 at random states."""
    states = _root_counts()
    for row, real, counts, brackets in states:
        if counts != tuple(f) or not brackets:
            return Outcome(False, f"at state {np.round(row, 3).tolist()}: roots {np.round(real, 6).tolist()}, "
                                  f"(in [−1, 1], above 1) = {counts}, printed {tuple(f)}")
    return Outcome(True, f"{len(states)} random states: two roots of f in [−1, 1] bracketing u = cos θ, one above 1")


register(Claim(
    "3.76 two roots", SECTION,
    "the motion is confined between two roots u1 < u2 of f in [−1, 1] (the third root lies above 1)",
    "numeric",
    printed=lambda: (2, 1),
    check=_check_two_roots,
    perturbed=lambda: (3, 0),  # all three roots in [−1, 1]; none above 1
    parts=("roots in [−1, 1]", "roots above 1"),
))


@functools.cache
def _kinds_of_motion() -> tuple[frozenset, str]:
    """The sign patterns (sign φ̇(u1), sign φ̇(u2)) met at random states, φ̇ = (b − au)/(1 − u²) (3.74).

    Reflecting φ → −φ, ψ → −ψ flips a, b and hence φ̇ everywhere, so patterns are normalised to
    φ̇(u1) > 0.  |b − au| < 1e-7 counts as zero (roots are found to ~1e-12 in u).
    """
    patterns = set()
    for released in (False, True):
        rows = _random_states(3761 + released, released=released)
        roots, ab = _roots_and_ab(rows)
        for r, (av, bv) in zip(roots, ab):
            real = np.sort(r[np.abs(r.imag) < 1e-9].real)
            u1, u2 = real[(real >= -1) & (real <= 1)][:2]
            num = [bv - av * x for x in (u1, u2)]
            sign = [0 if abs(n) < 1e-7 else int(np.sign(n)) for n in num]
            if sign[0] < 0:
                sign = [-x for x in sign]
            patterns.add(tuple(sign))
    return frozenset(patterns), f"{2 * _N_STATES} random states, half released at rest in θ and φ"


def _check_three_kinds(f) -> Outcome:
    seen, how = _kinds_of_motion()
    slope = _m().released_f_slope  # f'(u0) where φ̇(u0) = 0 and f(u0) = 0: −β(1 − u0²)
    upper_only = same(slope, -beta * (1 - u0**2), "f' at a zero of φ̇ on a root of f")
    printed = {tuple(int(x) if float(x).is_integer() else x for x in p) for p in f}
    ok = seen == printed and upper_only.passed
    return Outcome(ok, f"sign patterns (φ̇(u1), φ̇(u2)) seen at {how}: {sorted(seen)}; φ̇ can vanish only at the "
                       f"upper root u2 (f' = −β(1 − u0²) < 0 there); printed {sorted(printed)}")


register(Claim(
    "3.6 three kinds", SECTION,
    "three kinds of motion by the sign of φ̇ at the roots u1 < u2: (+, +), (+, −), (+, 0) — up to φ, ψ → −φ, −ψ",
    "numeric",
    printed=lambda: [(1, 1), (1, -1), (1, 0)],
    check=_check_three_kinds,
    # kinds that do not occur: φ̇ vanishing at the lower root, the reflected pattern, φ̇ = 0 at both roots
    perturbed=lambda: [(0, 1), (-1, 1), (0, 0)],
    parts=("(+, +)", "(+, −)", "(+, 0)"),
))


# --- 3.6.1: letting the top go ----------------------------------------------------------------

SECTION_61 = "3.6.1"


def _check_3_77(f) -> Outcome:
    m = _m()
    # at a release θ̇ = 0: f(cos θ) = 0 exactly, and f'(u0) = −β(1 − u0²) < 0 makes u0 the upper root u2
    coeffs = m.f_coefficients_state
    f_at_release = sum(cf * c(theta) ** (3 - k) for k, cf in enumerate(coeffs)).subs(theta_dot, 0).subs(phi_dot, 0)
    root = Outcome(bool(is_zero(f_at_release)), "f(cos θ) = 0 at θ̇ = φ̇ = 0")
    upper = same(m.released_f_slope, -beta * (1 - u0**2), "f'(u0) at a release")
    return all_pass([same(f, m.released_u, "u where φ̇(u) = 0"), root, upper])


register(Claim(
    "3.77", SECTION_61,
    "released with θ̇ = φ̇ = 0: f(u0) = 0 with u0 the upper root u2, and b − a u0 = 0 so u0 = b/a",
    "symbolic",
    printed=lambda: b / a,
    check=_check_3_77,
))

register(Claim(
    "3.78", SECTION_61,
    "p_φ = I1φ̇ sin²θ + I3ω3 cos θ = I3ω3 cos θ(t=0)",
    "symbolic",
    printed=lambda: (I1 * phi_dot * s(theta) ** 2 + I3 * omega3 * c(theta), I3 * omega3 * c(theta)),
    check=lambda f: all_pass([same(f[0], _m().azimuthal_momentum_spin, "p_φ in ω3"),
                              same(f[1], _m().released_azimuthal_momentum, "p_φ at φ̇ = 0")]),
    parts=("p_φ", "p_φ at release"),
))


@functools.cache
def _released_signs() -> dict[str, frozenset]:
    """The signs met at seeded random points (once per session): θ̈ at release, φ̇·a for u below u0."""
    m = _m()
    rng = np.random.default_rng(378)
    acc = compile_expressions(m.accelerations[1], [*ht.PARAMETERS, *ht.STATE], name="heavy_top_theta_ddot")
    rows = _random_states(3781, released=True)
    sign_fall = set(np.sign(acc(*rows.T)).astype(int).tolist())
    rate = compile_expressions(m.precession_rate_u.subs(b, a * u0), [a, u0, u], name="released_phi_dot")
    av = rng.choice([-1.0, 1.0], 500) * rng.uniform(0.1, 10.0, 500)
    u0v = rng.uniform(-0.95, 0.95, 500)
    uv = u0v - rng.uniform(0.01, 1.0, 500) * (u0v + 1)
    sign_precession = set(np.sign(rate(av, u0v, uv) * av).astype(int).tolist())
    return {"theta_ddot": frozenset(sign_fall), "phi_dot_times_spin": frozenset(sign_precession)}


def _check_released_motion(f) -> Outcome:
    """θ̈ at release (derived equations) and sign(φ̇)·sign(a) for u below u0, at seeded random points."""
    seen = _released_signs()
    sign_fall, sign_precession = seen["theta_ddot"], seen["phi_dot_times_spin"]
    ok = all(seen[k] == {f[k]} for k in seen)
    return Outcome(ok, f"signs seen: θ̈ at release {sorted(sign_fall)}, φ̇·ω3 for u < u0 {sorted(sign_precession)}; "
                       f"printed {f}")


register(Claim(
    "3.78 released motion", SECTION_61,
    "a released top starts to fall (θ̈ > 0) and then precesses in the sense of its spin (φ̇ ω3 > 0): "
    "motion of the third kind",
    "numeric",
    printed=lambda: {"theta_ddot": 1, "phi_dot_times_spin": 1},
    check=_check_released_motion,
    perturbed=lambda: {"theta_ddot": -1, "phi_dot_times_spin": -1},  # rises; precesses against the spin
    parts=("sign of θ̈", "sign of φ̇ω3"),
))


# --- 3.6.2: uniform precession ----------------------------------------------------------------

SECTION_62 = "3.6.2"

register(Claim(
    "3.79", SECTION_62,
    "a double root u0: f(u0) = (1 − u0²)(α − βu0) − (b − au0)² = 0 and "
    "f'(u0) = −2u0(α − βu0) − β(1 − u0²) + 2a(b − au0) = 0",
    "symbolic",
    printed=lambda: ((1 - u0**2) * (alpha - beta * u0) - (b - a * u0) ** 2,
                     -2 * u0 * (alpha - beta * u0) - beta * (1 - u0**2) + 2 * a * (b - a * u0)),
    check=lambda f: same(sp.Matrix(f), sp.Matrix(_m().double_root_conditions), "(f(u0), f'(u0))"),
    parts=("f(u0)", "f'(u0)"),
))

register(Claim(
    "3.79 combined", SECTION_62,
    "combining (3.79) with φ̇ = (b − au0)/(1 − u0²): ½β = aφ̇ − φ̇²u0",
    "symbolic",
    printed=lambda: a * phi_dot - phi_dot**2 * u0,
    check=lambda f: same(f, _m().uniform_precession_half_beta, "½β with b, α eliminated"),
))


def _printed_3_80() -> sp.Equality:
    return sp.Eq(M * g * l, phi_dot * (I3 * omega3 - I1 * phi_dot * c(theta0)))


register(Claim(
    "3.80", SECTION_62,
    "Mgl = φ̇(I3ω3 − I1φ̇ cos θ0)",
    "symbolic",
    printed=_printed_3_80,
    check=lambda f: same(f.rhs - f.lhs, _m().uniform_precession_condition.rhs - _m().uniform_precession_condition.lhs,
                         "(3.80) rhs − lhs"),
))


def _check_two_rates(f) -> Outcome:
    m = _m()
    poly = m.uniform_precession_polynomial
    roots_ok = all(same_numerically(poly.as_expr().subs(phi_dot, r), 0, ranges={theta0: (0.05, 1.5)}).passed
                   for r in m.precession_rates)
    ok = poly.degree() == f and roots_ok
    return Outcome(ok, f"(3.80) has degree {poly.degree()} in φ̇ (for cos θ0 ≠ 0; linear at θ0 = π/2), its two roots "
                       f"(slow, fast) check; printed {f}")


register(Claim(
    "3.80 two rates", SECTION_62,
    "(3.80) is quadratic in φ̇: two precession rates, slow and fast, without nutation",
    "symbolic",
    printed=lambda: 2,
    check=_check_two_rates,
))

_PRECESSION_CASE = {I1: 1.0, I3: 0.6, M: 1.0, g: 9.81, l: 0.1, omega3: 20.0, theta0: 0.6}


def _check_uniform_integration(f) -> Outcome:
    """Both roots φ̇ of the formula, numerically; each started at θ = θ0, θ̇ = 0, ψ̇ = ω3 − φ̇ cos θ0 and
    integrated (DOP853, rtol = atol = 1e-12) for 5 s by the derived equations: θ must stay at θ0 within
    1e-8 (integration error ~1e-11; a rate off by 1e-4 relative nutates by ~1e-6)."""
    from scipy.integrate import solve_ivp

    m = _m()
    case = _PRECESSION_CASE
    poly = sp.Poly(sp.expand((f.rhs - f.lhs).subs(case)), phi_dot)
    rates = [complex(r) for r in np.roots([float(x) for x in poly.all_coeffs()])]
    if any(abs(r.imag) > 0 for r in rates):
        return Outcome(False, f"the formula's rates are not real: {rates}")
    rhs = m.ode_rhs(ht.PARAMETERS)
    params = tuple(case[p] for p in ht.PARAMETERS)
    worst = 0.0
    for r in (x.real for x in rates):
        y0 = [0.0, case[theta0], 0.0, r, 0.0, case[omega3] - r * np.cos(case[theta0])]
        sol = solve_ivp(rhs, (0.0, 5.0), y0, args=params, method="DOP853", rtol=1e-12, atol=1e-12)
        worst = max(worst, float(np.max(np.abs(sol.y[1] - case[theta0]))))
    ok = worst < 1e-8
    return Outcome(ok, f"rates {np.round([x.real for x in rates], 6).tolist()} rad/s: max |θ − θ0| = {worst:.1e} over 5 s")


register(Claim(
    "3.80 no nutation", SECTION_62,
    "precessing at either root of (3.80) the top keeps θ = θ0 (θ̇ ≡ 0) under the derived equations of motion",
    "integration",
    printed=_printed_3_80,
    check=_check_uniform_integration,
))


def _check_3_81(f) -> Outcome:
    m = _m()
    upright = {theta0: (0.02, 1.55)}
    threshold = same_numerically(f, m.minimum_spin, ranges=upright)
    # (b) the printed condition ω3 > f decides real rates like the discriminant, for ω3 > 0, cos θ0 > 0
    rng = np.random.default_rng(381)
    fn = compile_expressions(f, [I1, I3, M, g, l, theta0], name="printed_minimum_spin")
    disc = compile_expressions(m.precession_discriminant, [I1, I3, M, g, l, theta0, omega3], name="precession_disc")
    pars = rng.uniform(0.3, 2.0, (5, 2000))
    th = rng.uniform(0.02, np.pi / 2 - 0.02, 2000)
    w = fn(*pars, th) * rng.uniform(0.5, 1.5, 2000)
    agree = bool(np.all((w > fn(*pars, th)) == (disc(*pars, th, w) > 0)))
    # (c) hanging top: the printed root is imaginary, and the discriminant is positive for every spin
    k = sp.Symbol("k", positive=True)  # cos θ0 = −k
    hanging = sp.expand(m.precession_discriminant.subs(c(theta0), -k))
    imaginary = sp.sympify(f, strict=True).subs(c(theta0), -k).is_real is False
    ok = threshold.passed and agree and bool(hanging.is_positive) and imaginary
    return Outcome(ok, f"for cos θ0 > 0: {threshold.detail}; the condition matches discriminant > 0 at 2000 random "
                       f"points: {agree}; for cos θ0 = −k < 0 the discriminant is {hanging} > 0 for any ω3 and the "
                       f"printed root is imaginary: {imaginary}")


register(Claim(
    "3.81", SECTION_62,
    "uniform precession needs ω3 > (2/I3)√(Mgl I1 cos θ0) — for ω3 > 0 and θ0 < π/2 (exactly I3²ω3² > "
    "4I1Mgl cos θ0); a hanging top (θ0 > π/2) precesses uniformly at any spin",
    "numeric",
    printed=lambda: 2 / I3 * sp.sqrt(M * g * l * I1 * c(theta0)),
    check=_check_3_81,
))


# --- 3.6.3: the sleeping top ------------------------------------------------------------------

SECTION_63 = "3.6.3"

register(Claim(
    "3.82", SECTION_63,
    "spinning upright, θ = θ̇ = 0: a = b and α = β",
    "symbolic",
    printed=lambda: {b: a, beta: alpha},
    check=lambda f: same(sp.Matrix([f[b], f[beta]]), sp.Matrix([_m().sleeping_constants[b], _m().sleeping_constants[beta]]),
                         "(b, β) at θ = θ̇ = 0"),
    parts=("b", "β"),
))

register(Claim(
    "3.83", SECTION_63,
    "f(u) = (1 − u)²(α(1 + u) − a²): a double zero at u = 1",
    "symbolic",
    printed=lambda: (1 - u) ** 2 * (alpha * (1 + u) - a**2),
    check=lambda f: same(f, _m().sleeping_f, "f(u) with b = a, β = α"),
))

register(Claim(
    "3.83 second root", SECTION_63,
    "the second root of f is u2 = a²/α − 1",
    "symbolic",
    printed=lambda: a**2 / alpha - 1,
    check=lambda f: same(f, _m().sleeping_second_root, "the root of f other than the double root at 1"),
))

register(Claim(
    "3.83 threshold", SECTION_63,
    "u2 > 1 ⟺ ω3² > 4I1Mgl/I3² (stable); u2 < 1 ⟺ ω3² < 4I1Mgl/I3² (unstable)",
    "symbolic",
    printed=lambda: 4 * I1 * M * g * l / I3**2,
    check=lambda f: all_pass([
        same(f, _m().sleeping_threshold_spin ** 2, "ω3² at u2 = 1"),
        same(_m().sleeping_second_root_spin.subs(omega3, sp.sqrt(f)), 1, "u2 at the printed ω3²"),
    ]),
))

_SLEEPING_CASE = (1.0, 0.5, 1.0, 4.0, 0.25)  # I1, I3, M, g, l: Mgl = 1


def _check_sleeping_integration(f) -> Outcome:
    """Released near upright (θ = 1e-3, θ̇ = φ̇ = 0) at spins 0.3 % above and below √(printed ω3²),
    integrated 60 s by the derived equations (DOP853, rtol 1e-10): above, θ stays below 0.05 (the
    bound from f is ≈ 0.013); below, it exceeds 0.1 (≈ 0.155).  A threshold 0.5 % off swaps one of them."""
    from scipy.integrate import solve_ivp

    rhs = _m().ode_rhs(ht.PARAMETERS)
    crit = float(sp.sqrt(sp.sympify(f, strict=True).subs(dict(zip(ht.PARAMETERS, _SLEEPING_CASE)))))
    top = {}
    for k in (0.997, 1.003):
        sol = solve_ivp(rhs, (0.0, 60.0), [0.0, 1e-3, 0.0, 0.0, 0.0, k * crit], args=_SLEEPING_CASE,
                        method="DOP853", rtol=1e-10, atol=1e-12, max_step=0.05)
        top[k] = float(np.max(sol.y[1]))
    ok = top[1.003] < 0.05 and top[0.997] > 0.1
    return Outcome(ok, f"max θ at 1.003 × threshold: {top[1.003]:.4f}; at 0.997 ×: {top[0.997]:.4f}")


register(Claim(
    "3.83 stability", SECTION_63,
    "above ω3² = 4I1Mgl/I3² the sleeping top stays near upright when disturbed; below it falls away",
    "integration",
    printed=lambda: 4 * I1 * M * g * l / I3**2,
    check=_check_sleeping_integration,
))

def _check_3_83_generic(f) -> Outcome:
    """The generic linearization (Routh-reduced, :mod:`mechderive.core.linearize`) of the Lagrangian (3.62)
    about the sleeping top θ = 0, φ̇ = 0, ψ̇ = ω3: its nutation ω² must vanish exactly at the printed ω3²
    and be positive above it (twice the printed value) and negative below (half)."""
    from ..core.linearize import linearize_lagrangian

    m = _m()
    lin = linearize_lagrangian(m.state_lagrangian, (ht.phi, ht.theta, ht.psi),
                               (ht.phi_dot, ht.theta_dot, ht.psi_dot), {ht.theta: 0, ht.phi_dot: 0, ht.psi_dot: omega3})
    if len(lin.squared_frequencies) != 1:
        return Outcome(False, f"expected one nutation mode, got ω² = {lin.squared_frequencies}")
    (w_sq,) = lin.squared_frequencies
    at = {k: sp.simplify(w_sq.subs(omega3, sp.sqrt(k * f))) for k in (sp.Rational(1, 2), 1, 2)}
    ok = at[1] == 0 and bool(sp.simplify(at[2]).is_positive) and bool(sp.simplify(at[sp.Rational(1, 2)]).is_negative)
    return Outcome(ok, f"ω² = {sp.factor(w_sq)}: 0 at the printed ω3², {sp.factor(at[2])} at twice it, "
                       f"{sp.factor(at[sp.Rational(1, 2)])} at half")


register(Claim(
    "3.83 generic", SECTION_63,
    "the sleeping top is stable iff ω3² > 4I1Mgl/I3² — from the generic linearization of L (3.62) at θ = 0",
    "symbolic",
    printed=lambda: 4 * I1 * M * g * l / I3**2,
    check=_check_3_83_generic,
    perturbed=lambda: 2 * I1 * M * g * l / I3**2,
))

register(Claim(
    "3.83 friction", SECTION_63,
    "the top starts to fall when friction has slowed it to I3ω3 = 2√(I1Mgl)",
    "symbolic",
    printed=lambda: 2 * sp.sqrt(I1 * M * g * l),
    check=lambda f: same(f, I3 * _m().sleeping_threshold_spin, "I3ω3 at u2 = 1"),
))
