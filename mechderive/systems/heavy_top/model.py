"""Symbolic model of the heavy symmetric top, section 3.6: derived through the Lagrangian layer.

Conventions.  The top is pinned at P; I1 = I2 and I3 are its principal moments *about P*,
l is the distance from P to the centre of mass, which lies on the symmetry axis e3.  Euler
angles as in (3.54), R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ) with e_a = R_ab ẽ_b, and θ measured
from the upward vertical ẽ3.  Units: any consistent set (moments mass × length², rates in
rad per unit time).

Nothing of (3.62)–(3.83) is typed in.  Two inputs:

- T = ½ ωᵀ diag(I1, I1, I3) ω with the body components ω of (3.58), derived from ṘRᵀ by
  :mod:`mechderive.kinematics.euler`;
- V = M g × (height of the centre of mass l e3 above P) = M g l ẽ3·e3 = M g l R33.

and the text's definitions, used as such: a = I3ω3/I1, b = p_φ/I1 (3.66), E' = E − ½I3ω3²,
u = cos θ (3.71), α = 2E'/I1, β = 2Mgl/I1 (3.72).  From L = T − V the generic
:class:`~mechderive.core.lagrangian.LagrangianModel` finds φ and ψ ignorable, their momenta
(3.63)–(3.64), the energy (3.65), the Routhian that gives (3.67)–(3.70), and the equations of
motion.  The rest follows by algebra on those results: f(u) of (3.73) from E' (u̇² = f(u)),
the released top (3.77)–(3.78), uniform precession (3.79)–(3.81) and the sleeping top
(3.82)–(3.83).

Symbols: ``I1 I3 M g l`` (positive), ``a b alpha`` (real), ``beta`` (positive), ``u u0`` (real),
``theta0`` (real), ``omega3`` (the spin, real), ``p_phi p_psi`` (conserved momenta); state
symbols ``phi theta psi phi_dot theta_dot psi_dot`` (:mod:`mechderive.core.symbols`).

>>> m = model()
>>> m.cyclic_coordinates
(phi(t), psi(t))
>>> m.precession_rate_u           # (3.74)
(-a*u + b)/(1 - u**2)
>>> m.f_u                         # (3.73), u̇² = f(u)
-alpha*u**2 + alpha + beta*u**3 - beta*u - (a*u - b)**2
>>> m.sleeping_threshold_spin     # (3.83): I3 ω3 = 2 √(I1 M g l)
2*sqrt(I1)*sqrt(M)*sqrt(g)*sqrt(l)/I3
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import sympy as sp

from ...core.lagrangian import LagrangianModel, from_state_symbols, vanishes
from ...core.model import derived
from ...core.simplify import as_fraction, factor, is_zero, is_zero_rational, trig_normal
from ...core.symbols import as_symbolic, euler_angles, state_symbol, t, to_state_symbols
from ...errors import DerivationError
from ...kinematics import euler as _euler

__all__ = ["HeavyTopModel", "model", "I1", "I3", "M", "g", "l", "a", "b", "alpha", "beta", "u", "u0", "theta0",
           "omega3", "p_phi", "p_psi", "PARAMETERS", "STATE"]

I1, I3, M, g, l = sp.symbols("I1 I3 M g l", positive=True)
a, b, alpha = sp.symbols("a b alpha", real=True)
beta = sp.Symbol("beta", positive=True)
u, u0, theta0 = sp.symbols("u u0 theta0", real=True)
omega3 = state_symbol("omega3")
p_phi, p_psi = sp.symbols("p_phi p_psi", real=True)
E_prime = sp.Symbol("E_prime", real=True)

phi, theta, psi = (state_symbol(n) for n in ("phi", "theta", "psi"))
phi_dot, theta_dot, psi_dot = (state_symbol(n) for n in ("phi_dot", "theta_dot", "psi_dot"))

#: The parameters, in the argument order of the compiled functions.
PARAMETERS = (I1, I3, M, g, l)
#: The state the constants of motion depend on (φ and ψ are ignorable), in argument order.
STATE = (theta, theta_dot, phi_dot, psi_dot)


def _readable(expr: sp.Expr, collect: tuple = (I1, I3)) -> sp.Expr:
    """``expr`` collected on ``collect``, each coefficient in the shorter of two exact forms.

    The trig normal form writes cos² as 1 − sin²; rewriting sin² as 1 − cos² and factoring
    sometimes gives a perfect square, e.g. φ̇² cos²θ + 2φ̇ψ̇ cos θ + ψ̇² = (ψ̇ + φ̇ cos θ)².
    """
    parts = sp.collect(sp.expand(expr), list(collect), evaluate=False)
    out = sp.Integer(0)
    for key, coeff in parts.items():
        out += key * _shorter_form(coeff)
    return out


@functools.lru_cache(maxsize=64)
def _shorter_form(coeff: sp.Expr) -> sp.Expr:
    """``coeff`` or its factored form in cos θ (sin² as 1 − cos²), the shorter: for :func:`_readable`, which
    meets the same coefficients again (T's in E, E's I1 part in E'), each factored once (a third of the
    factorisations before the fork of a cold start were repeats)."""
    alt = factor(sp.expand(coeff.replace(sp.sin, lambda x: sp.sqrt(1 - sp.cos(x) ** 2))))
    return alt if sp.count_ops(alt) < sp.count_ops(coeff) else coeff


def _in_u(expr: sp.Expr) -> sp.Expr:
    """``expr`` with θ = arccos u (so cos θ = u, sin θ = √(1 − u²) for 0 ≤ θ ≤ π), as one fraction."""
    expr = as_symbolic(expr)
    # θ enters the heavy top's quantities through cos θ and even powers of sin θ: those are replaced
    # structurally (u and (1 − u²)^k) — the same rational function of u that the substitution θ = arccos u
    # gives, without SymPy's subs (slow) or √(1 − u²) as an extra generator for cancel
    sin_sq = lambda x: x.is_Pow and x.base == sp.sin(theta) and x.exp.is_Integer and x.exp.is_even  # noqa: E731
    direct = expr.xreplace({sp.cos(theta): u}).replace(sin_sq, lambda x: (1 - u**2) ** (x.exp // 2))
    if direct.has(theta):  # an odd power of sin θ, or θ elsewhere: the general route
        return factor(sp.cancel(expr.subs(theta, sp.acos(u))))
    return factor(as_fraction(direct))


@functools.lru_cache(maxsize=8)
def partial_fractions_in_u(rate: sp.Expr) -> sp.Expr:
    """``rate``, a rational function of u, in partial fractions in u (SymPy's apart): shared by the rates near
    the poles (:attr:`HeavyTopModel.rates_near_poles`) and their partial fractions along the nutation
    (:mod:`.exact_model`), which take the same decomposition of φ̇ (3.74) and ψ̇ (3.75)."""
    return _apart(sp.together(rate), u)


def _apart(f: sp.Expr, x: sp.Symbol) -> sp.Expr:
    """``sympy.apart(f, x)`` (undetermined coefficients, ``full=False``), the same expression, by SymPy's own
    steps (:func:`sympy.polys.partfrac.apart`: P/Q over a common content, the polynomial part split off, the
    denominators cleared, each term factored) except one: where Q's factors are distinct and linear in x (the
    rates' 1 ∓ u), the numerator of 1/f for a factor f = l x + t is the residue P(r)/q(r) at its root r = −t/l,
    q = Q/f (at r every other term's q vanishes), which is the value the linear system SymPy's ``solve`` sets up
    there has as its one solution — each term is then factored (a normal form of its value, so the same
    expression; by :func:`~mechderive.core.simplify.factor`, sympy.factor's expression).  SymPy's route for anything else.  Checked against ``sympy.apart`` in the tests."""
    try:
        from sympy.polys.partfrac import apart_undetermined_coeffs
        from sympy.polys.polyoptions import set_defaults
        from sympy.polys.polytools import parallel_poly_from_expr
    except ImportError:  # pragma: no cover - a SymPy without them
        return sp.apart(f, x)
    f = as_symbolic(f)
    if f.is_Atom or not f.is_commutative:
        return sp.apart(f, x)
    P, Q = f.as_numer_denom()
    try:
        (P, Q), _ = parallel_poly_from_expr((P, Q), x, **set_defaults({}, extension=True))
    except sp.PolynomialError:
        return sp.apart(f, x)
    if P.is_multivariate:
        return sp.apart(f, x)
    common, P, Q = P.cancel(Q)
    poly, P = P.div(Q, auto=True)
    P, Q = P.rat_clear_denoms(Q)
    if Q.degree() <= 1:
        partial = P / Q
    else:
        _, factors = Q.factor_list()
        if all(k == 1 and fac.degree() == 1 for fac, k in factors):
            partial = sp.Integer(0)
            for fac, _ in factors:
                lead, tail = fac.all_coeffs()
                root, q = -tail / lead, Q.quo(fac)
                partial += P.as_expr().xreplace({x: root}) / q.as_expr().xreplace({x: root}) / fac.as_expr()
        else:
            partial = apart_undetermined_coeffs(P, Q)
    terms = sp.Integer(0)
    for term in sp.Add.make_args(partial):
        terms += factor(term)  # (this package's: sympy.factor's expression, checked in tests/test_core.py)
    return common * (poly.as_expr() + terms)


def _over_one_minus_u2(expr: sp.Expr) -> sp.Expr:
    """A rational function of u over (1 − u²), as one fraction or as (polynomial) + N(u)/(1 − u²), the shorter.

    ``expr`` as :func:`_in_u` gives it: one fraction, factored (not factored again: that was half the time)."""
    num, den = sp.fraction(expr)
    scale = sp.cancel(den / (1 - u**2))
    if scale.has(u):
        return expr
    whole = factor(num / scale) / (1 - u**2)
    q, r = sp.div(sp.Poly(num, u), sp.Poly(den, u))
    split = factor(q.as_expr()) + factor(r.as_expr() / scale) / (1 - u**2)
    return min((whole, split), key=sp.count_ops)


def _theta_form(expr: sp.Expr) -> sp.Expr:
    """A rational function of cos θ and sin²θ, tidied through u = cos θ and written back with sin²θ = 1 − u²."""
    return _over_one_minus_u2(_in_u(expr)).subs(u, sp.cos(theta)).subs(1 - sp.cos(theta) ** 2, sp.sin(theta) ** 2)


def _product_replaced(expr: sp.Expr, factors: tuple, new: sp.Expr) -> sp.Expr:
    """``expr.subs(Mul(*factors), new)``: where ``expr`` is a product with each of ``factors`` once (as factor
    leaves the passage factors), those factors are replaced by ``new`` directly (subs' matching of a product
    pattern — breaking up powers, powdenest — was a fifth of :attr:`HeavyTopModel.passage_factors`); where one of
    them is absent there is nothing to match (subs finds a product only among products of its factors); any other
    shape goes to subs."""
    if not all(expr.has(f) for f in factors):
        return expr
    args = list(sp.Mul.make_args(expr))
    rest = [a for a in args if a not in factors]
    if all(args.count(f) == 1 for f in factors) and not any(r.has(f) for r in rest for f in factors):
        return sp.Mul(*rest, new)
    return expr.subs(sp.Mul(*factors), new)


#: A sample point with cos θ0 > 0 and ω3 > 0, used only to pick between the roots SymPy returns.
_SAMPLE = {I1: 3, I3: 2, M: 1, g: sp.Rational(98, 10), l: sp.Rational(1, 2), omega3: 40, theta0: sp.Rational(1, 2)}


def _positive_at_sample(candidates: list) -> sp.Expr:
    """The one candidate that is positive at :data:`_SAMPLE` (raise if not exactly one)."""
    pos = [c for c in candidates if sp.N(c.subs(_SAMPLE)) > 0]
    if len(pos) != 1:
        raise DerivationError(f"expected exactly one positive candidate, got {candidates}")
    return pos[0]


class HeavyTopModel(LagrangianModel):
    """The heavy symmetric top of section 3.6, derived from L = T − V; every quantity lazy.

    Coordinates (φ(t), θ(t), ψ(t)) in that order: :attr:`accelerations` are (φ̈, θ̈, ψ̈).
    """

    coordinates = euler_angles()

    # --- (3.62): the Lagrangian -------------------------------------------------------------

    @derived
    def kinetic_energy(self) -> sp.Expr:
        """T = ½ ωᵀ diag(I1, I1, I3) ω with ω from (3.58) (derived from ṘRᵀ); state symbols."""
        w = _euler.model().state_angular_velocity_body
        # the trig normal form, tidied by _readable (which finds the perfect square (ψ̇ + φ̇ cos θ)²); a
        # trigsimp pass between them (simplify_trig) found nothing shorter, and took ~0.3 s of a cold start
        return _readable(trig_normal((w.T * sp.diag(I1, I1, I3) * w)[0] / 2))

    @derived
    def potential_energy(self) -> sp.Expr:
        """V = M g ẽ3·(l e3) = M g l R33 (e3·ẽ3 = R33 since e_a = R_ab ẽ_b): M g l cos θ."""
        return M * g * l * _euler.model().state_rotation[2, 2]

    @derived
    def lagrangian(self) -> sp.Expr:
        """L = T − V (3.62), in functions of t."""
        return from_state_symbols(self.kinetic_energy - self.potential_energy, self.coordinates)

    # --- (3.63)-(3.65): constants of motion ---------------------------------------------------

    @derived
    def spin(self) -> sp.Expr:
        """ω3 = ψ̇ + φ̇ cos θ, the body component of ω along the symmetry axis (3.58)."""
        return _euler.model().state_angular_velocity_body[2]

    @derived
    def spin_momentum(self) -> sp.Expr:
        """p_ψ = ∂L/∂ψ̇ (3.63), conserved since ψ is ignorable; checked equal to I3 ω3."""
        p = self.conserved_momenta[self.coordinates[2]]
        if not vanishes(p - I3 * self.spin):
            raise DerivationError(f"expected p_ψ = I3 ω3, got {p}")
        return factor(p)

    @derived
    def azimuthal_momentum(self) -> sp.Expr:
        """p_φ = ∂L/∂φ̇ (3.64), conserved since φ is ignorable."""
        return _readable(self.conserved_momenta[self.coordinates[0]])

    @derived
    def energy(self) -> sp.Expr:
        """E = Σ q̇ ∂L/∂q̇ − L (3.65), checked equal to T + V (T is quadratic in the rates)."""
        h = self.energy_function
        # h − T − V expanded is 0 term by term here (h is Σ q̇ ∂L/∂q̇ − L expanded, of this very T and V): that is a
        # proof, in ~1 ms; vanishes (exact modulo sin² + cos² = 1, ~40 ms on a cold start's serial path) decides
        # where it is not
        difference = h - self.kinetic_energy - self.potential_energy
        if sp.expand(difference) != 0 and not vanishes(difference):
            raise DerivationError(f"expected the energy function to equal T + V, got {h}")
        return _readable(self.kinetic_energy + self.potential_energy)

    @derived
    def reduced_energy_state(self) -> sp.Expr:
        """E' = E − ½ I3 ω3² as a function of the state (the text's definition before (3.69))."""
        return _readable(sp.expand(self.energy - I3 * self.spin**2 / 2))

    @derived
    def constants_from_state(self) -> dict:
        """{a, b, α, β} of (3.66), (3.72) in the parameters and the state (θ, θ̇, φ̇, ψ̇)."""
        return {a: I3 * self.spin / I1, b: self.azimuthal_momentum / I1,
                alpha: 2 * self.reduced_energy_state / I1, beta: 2 * M * g * l / I1}

    # --- (3.66)-(3.70): reduction to θ ------------------------------------------------------

    @derived
    def momenta_in_ab(self) -> dict:
        """{p_φ: I1 b, p_ψ: I1 a}: the definitions (3.66) solved, with p_ψ = I3 ω3 from (3.63)."""
        _ = self.spin_momentum  # establishes p_ψ = I3 ω3
        sym = self.momentum_symbols
        pf, ps = sym[self.coordinates[0]], sym[self.coordinates[2]]
        # a linear system: linsolve (sp.solve's check of the solution imports sympy.physics.units, ~0.3 s)
        sol = list(sp.linsolve([I1 * a - I3 * omega3, I1 * b - pf, ps - I3 * omega3], [pf, ps, omega3]))
        if len(sol) != 1 or any(v.free_symbols & {pf, ps, omega3} for v in sol[0]):
            raise DerivationError(f"expected one solution for (p_φ, p_ψ) in a, b, got {sol}")
        return {pf: sol[0][0], ps: sol[0][1]}

    def _rate_in_ab(self, name: str) -> sp.Expr:
        """The cyclic velocity ``name`` solved from the conserved momenta, in a, b and θ, as it comes."""
        return self.cyclic_velocities[state_symbol(name)].subs(self.momenta_in_ab)

    def _rate_in_u(self, name: str) -> sp.Expr:
        """The cyclic velocity ``name`` in a, b and u = cos θ: one fraction."""
        return _in_u(self._rate_in_ab(name))

    def _rate(self, name: str) -> sp.Expr:
        return _theta_form(self._rate_in_ab(name))

    @derived
    def precession_rate_theta(self) -> sp.Expr:
        """φ̇ as a function of θ, a, b (3.67): solved from the conserved momenta."""
        return self._rate("phi_dot")

    @derived
    def spin_rate_theta(self) -> sp.Expr:
        """ψ̇ as a function of θ, a, b (3.68): solved from the conserved momenta."""
        return self._rate("psi_dot")

    @derived
    def spin_energy(self) -> sp.Expr:
        """½ I3 ω3² in the conserved momenta (= p_ψ²/(2 I3)): the constant E' leaves out."""
        # the normal form, factored (the θ, θ̇ it must be free of cancel in the normal form: exact)
        e = factor(trig_normal((I3 * self.spin**2 / 2).subs(self.cyclic_velocities)))
        if e.has(theta, theta_dot):
            raise DerivationError(f"expected ½ I3 ω3² to depend on the momenta only, got {e}")
        return e

    @derived
    def effective_potential_theta(self) -> sp.Expr:
        """V_eff(θ) of (3.70): the Routhian's effective potential less ½ I3 ω3², in a, b."""
        v = _in_u((self.effective_potential - self.spin_energy).subs(self.momenta_in_ab))
        gravity = sp.expand(v).coeff(M)
        return M * factor(gravity).subs(u, sp.cos(theta)) + _theta_form(v - M * gravity)

    @derived
    def reduced_energy_terms(self) -> tuple[sp.Expr, sp.Expr]:
        """(c, W(θ)) with E' = c θ̇² + W(θ) (3.69): the Routhian's energy Σ θ̇ ∂R/∂θ̇ − R (which is E) less
        ½ I3 ω3², in θ, a, b, expanded as it comes (not tidied: f(u) takes them, and brings W to u itself) — from
        the Routhian's normal form, not its readable :attr:`routhian` (collecting and factoring it by powers of θ̇
        was a third of the Routhian's time on a cold start's critical path, for a form expanded again here)."""
        R = self.routhian_normal
        h = sp.expand((theta_dot * R.diff(theta_dot) - R - self.spin_energy).subs(self.momenta_in_ab))
        mass, rest = h.coeff(theta_dot, 2), h.coeff(theta_dot, 0)
        if sp.expand(h - mass * theta_dot**2 - rest) != 0 or mass.has(theta):
            raise DerivationError(f"expected E' = c θ̇² + W(θ) with constant c, got {h}")
        return mass, rest

    @derived
    def reduced_energy(self) -> sp.Expr:
        """E' (3.69) in θ, θ̇, a, b, readable: ½ I1 θ̇² + the gravity term + the rest over sin²θ."""
        mass, rest = self.reduced_energy_terms
        gravity = sp.expand(_in_u(rest)).coeff(M)
        return factor(mass) * theta_dot**2 + M * factor(gravity).subs(u, sp.cos(theta)) + \
            _theta_form(rest - M * gravity.subs(u, sp.cos(theta)))

    # --- (3.71)-(3.76): the cubic f(u) ------------------------------------------------------

    @derived
    def u_dot_squared(self) -> sp.Expr:
        """u̇² for u = cos θ (3.71), by differentiating cos θ(t): sin²θ θ̇²."""
        return to_state_symbols(sp.cos(self.coordinates[1]).diff(t) ** 2)

    @derived
    def f_u(self) -> sp.Expr:
        """f(u) of (3.73): u̇² with θ̇² from E' = ½I1θ̇² + V_eff, E' = I1α/2, Mgl = I1β/2, cos θ = u.

        A polynomial in u (checked) with coefficients in a, b, α, β.  From E' as the Routhian gives it, not
        from the readable :attr:`reduced_energy` (tidying W(θ) only to bring it to u again here was ~15% of
        the derivations of a cold ``run``): f is brought to its own form below, whatever W's form.
        """
        mass, rest = self.reduced_energy_terms
        rate_squared = (E_prime - rest) / mass  # θ̇² from (3.69)
        (M_of_beta,), = sp.linsolve([beta - 2 * M * g * l / I1], [M])  # (3.72) for M: linear
        f = self.u_dot_squared.subs(theta_dot**2, rate_squared).subs({E_prime: I1 * alpha / 2, M: M_of_beta})
        f = sp.cancel(_in_u(f))
        if not f.is_polynomial(u) or f.free_symbols - {u, a, b, alpha, beta}:
            raise DerivationError(f"expected f(u) polynomial in u with coefficients in a, b, α, β, got {f}")
        # readable: the part in α, β factored as (1 − u²)(α − βu) would be, the rest as −(b − au)²
        rest = sp.expand(f).coeff(alpha, 0).coeff(beta, 0)
        return sp.expand(f - rest) + factor(rest)

    @derived
    def f_polynomial(self) -> sp.Poly:
        """f(u) (3.73) as a :class:`sympy.Poly` in u over the coefficients a, b, α, β."""
        return sp.Poly(self.f_u, u)

    @derived
    def precession_rate_u(self) -> sp.Expr:
        """φ̇(u) of (3.74): (3.67) at cos θ = u — from the solved velocity itself, not from the readable (3.67)
        brought back to u (:func:`_in_u` gives the same factored fraction of either: half the time)."""
        return _over_one_minus_u2(self._rate_in_u("phi_dot"))

    @derived
    def spin_rate_u(self) -> sp.Expr:
        """ψ̇(u) of (3.75): (3.68) at cos θ = u, like :attr:`precession_rate_u`."""
        return _over_one_minus_u2(self._rate_in_u("psi_dot"))

    @derived
    def rates_near_poles(self) -> tuple[sp.Expr, sp.Expr]:
        """(φ̇, ψ̇) of (3.74)–(3.75) in x = 1 − u, y = 1 + u and d∓ = b ∓ a: their partial fractions in u.

        Formed so in floating point, nothing cancels near the pole or the bottom: 1 ∓ u enter
        themselves (not 1 − u² from a rounded u), and b − a (tiny near a pole passage) as a number
        known to full relative accuracy.  Symbols ``x_pole y_bottom d_minus d_plus`` (real).
        """
        x, y, dm, dp = sp.symbols("x_pole y_bottom d_minus d_plus", real=True)
        out = []
        for rate in (self.precession_rate_u, self.spin_rate_u):
            parts = partial_fractions_in_u(rate).xreplace({u - 1: -x, u + 1: y})
            # symbols replaced by expressions free of every key: replacing those nodes (xreplace) is the substitution,
            # without subs' matching (a quarter of this derivation, on the prefetching child's critical path)
            parts = sp.expand(parts.xreplace({a: (dp - dm) / 2, b: (dp + dm) / 2}))
            if parts.has(u):
                raise DerivationError(f"expected the rate in 1 − u and 1 + u only, got {parts}")
            back = parts.xreplace({x: 1 - u, y: 1 + u, dm: b - a, dp: b + a})
            if is_zero_rational(back - rate) is not True:
                raise DerivationError(f"expected the partial fractions to reproduce {rate}, got {parts}")
            out.append(sp.collect(parts, [x, y], factor))
        return tuple(out)  # type: ignore[return-value]

    @derived
    def f_at_poles(self) -> tuple[sp.Expr, sp.Expr]:
        """(f(1), f(−1)) (3.76), factored."""
        return tuple(factor(self.f_u.subs(u, x)) for x in (1, -1))  # type: ignore[return-value]

    @derived
    def f_limits(self) -> tuple[sp.Expr, sp.Expr]:
        """(lim f as u → +∞, lim f as u → −∞) (3.76): ±∞ since the leading term is β u³, β > 0."""
        return sp.limit(self.f_u, u, sp.oo), sp.limit(self.f_u, u, -sp.oo)

    @derived
    def f_coefficients(self) -> tuple[sp.Expr, ...]:
        """The coefficients of u³, u², u, 1 in f(u) (3.73), in a, b, α, β."""
        coeffs = tuple(factor(c) for c in self.f_polynomial.all_coeffs())
        if len(coeffs) != 4:
            raise DerivationError(f"expected a cubic f(u), got coefficients {coeffs}")
        return coeffs

    @derived
    def f_coefficients_state(self) -> tuple[sp.Expr, ...]:
        """The coefficients of u³, u², u, 1 in f(u) as functions of the parameters and the state (θ, θ̇, φ̇, ψ̇).

        a, b, α, β replaced by their definitions (3.66), (3.72) evaluated at the state; then
        f(cos θ) = sin²θ θ̇² at that state, and the roots of f bound the motion in u.
        """
        return tuple(factor(trig_normal(c.subs(self.constants_from_state))) for c in self.f_coefficients)

    def f_coefficients_function(self) -> Callable[..., Any]:
        """Compiled ``f(I1, I3, M, g, l, theta, theta_dot, phi_dot, psi_dot)`` → shape (..., 4): f's coefficients of u³, u², u, 1.

        For a numeric root finder: ``numpy.roots(f(...))`` gives u1 ≤ u2 in [−1, 1] and a third root ≥ 1.
        """
        return self.compile("f_coefficients", list(self.f_coefficients_state), [*PARAMETERS, *STATE])

    def invariants_function(self) -> Callable[..., Any]:
        """Compiled ``f(I1, I3, M, g, l, theta, theta_dot, phi_dot, psi_dot)`` → shape (..., 3): (E, p_φ, p_ψ)."""
        exprs = [self.energy, self.azimuthal_momentum, self.spin_momentum]
        return self.compile("invariants", exprs, [*PARAMETERS, *STATE])

    @derived
    def passage_factors(self) -> tuple[sp.Expr, sp.Expr]:
        """(b − a, b + a) of (3.66) in the state with θ = 2h, as 2 sin²h·(…)/I1 and 2 cos²h·(…)/I1.

        f(±1) = −(b ∓ a)² (3.76): the apex reaches the pole (bottom) only if b = a (b = −a).
        Next to the pole b − a is a difference of nearly equal numbers, p_φ/I1 − I3ω3/I1 with
        1 − cos θ lost; in this form its factor sin²(θ/2) carries θ's smallness with full relative
        accuracy (and cos²(θ/2) next to the bottom), so that whether b ∓ a is zero, and how small,
        can be told from the state at any working precision.  Checked equal to b ∓ a.
        """
        h = sp.Symbol("h", real=True)
        c = self.constants_from_state
        out = []
        for sign in (-1, 1):
            expr = c[b] + sign * c[a]
            # (xreplace: the symbol θ's node replaced, what subs does here, without its matching)
            in_h = sp.expand_trig(expr.xreplace({theta: 2 * h}))
            # the normal form modulo sin² + cos² = 1 (in sin h), factored: b − a has the factor sin²h; b + a the
            # factor (sin h − 1)(sin h + 1), which is −cos²h — written so, or 1 − sin h would cancel at the bottom
            half = _product_replaced(factor(trig_normal(in_h)), (sp.sin(h) - 1, sp.sin(h) + 1), -sp.cos(h) ** 2)
            if not any(f in (sp.sin(h) ** 2, sp.cos(h) ** 2) for f in sp.Mul.make_args(half)):
                half = factor(sp.trigsimp(factor(in_h)))  # the general (slow) route
            if not is_zero(half - in_h):  # (exactly: by is_zero's unreduced fraction, no normal form built)
                raise DerivationError(f"expected b {'+' if sign > 0 else '−'} a in the half angle, got {half}")
            out.append(half.xreplace({h: theta / 2}))
        return tuple(out)  # type: ignore[return-value]

    # --- (3.77)-(3.78): letting the top go ----------------------------------------------------

    @derived
    def released_u(self) -> sp.Expr:
        """u at release (3.77): the root of φ̇(u) = 0, i.e. of b − a u = 0."""
        num, _ = sp.fraction(sp.together(self.precession_rate_u))
        sol = sp.solve(num, u)
        if len(sol) != 1:
            raise DerivationError(f"expected one zero of φ̇(u), got {sol}")
        return sol[0]

    @derived
    def released_f_slope(self) -> sp.Expr:
        """f'(u0) for a top released at rest in θ and φ (b = a u0 and f(u0) = 0): −β(1 − u0²) < 0.

        Negative slope: f > 0 just below u0, so u0 is the upper root u2 and θ increases.
        """
        f = self.f_u.subs(b, a * u0)
        alpha_rel = sp.solve(f.subs(u, u0), alpha)
        if len(alpha_rel) != 1:
            raise DerivationError(f"expected one α with f(u0) = 0, got {alpha_rel}")
        return factor(f.diff(u).subs(u, u0).subs(alpha, alpha_rel[0]))

    @derived
    def azimuthal_momentum_spin(self) -> sp.Expr:
        """p_φ in θ, φ̇ and the spin ω3 (3.78): ψ̇ eliminated with ω3 = ψ̇ + φ̇ cos θ."""
        rate = sp.solve(omega3 - self.spin, psi_dot)[0]
        return _readable(sp.expand(self.azimuthal_momentum.subs(psi_dot, rate)), (I1, I3))

    @derived
    def released_azimuthal_momentum(self) -> sp.Expr:
        """p_φ at release, φ̇ = 0 (3.78): I3 ω3 cos θ."""
        return factor(self.azimuthal_momentum_spin.subs(phi_dot, 0))

    # --- (3.79)-(3.81): uniform precession ---------------------------------------------------

    @derived
    def double_root_conditions(self) -> tuple[sp.Expr, sp.Expr]:
        """(f(u0), f'(u0)) (3.79): both vanish at a double root u0 — motion with θ̇ ≡ 0."""
        return self.f_u.subs(u, u0), sp.expand(self.f_u.diff(u)).subs(u, u0)

    @derived
    def uniform_precession_half_beta(self) -> sp.Expr:
        """½β from (3.79) with φ̇ = φ̇(u0) (3.74): b and α eliminated, giving a φ̇ − φ̇² u0."""
        b_of_rate = sp.solve(phi_dot - self.precession_rate_u.subs(u, u0), b)[0]
        f0, df0 = (c.subs(b, b_of_rate) for c in self.double_root_conditions)
        alpha_sol = sp.solve(f0, alpha)
        if len(alpha_sol) != 1:
            raise DerivationError(f"expected f(u0) = 0 linear in α, got {alpha_sol}")
        beta_sol = sp.solve(factor(df0.subs(alpha, alpha_sol[0])), beta)
        if len(beta_sol) != 1:
            raise DerivationError(f"expected f'(u0) = 0 linear in β, got {beta_sol}")
        return sp.expand(beta_sol[0] / 2)

    @derived
    def uniform_precession_condition(self) -> sp.Equality:
        """(3.80): M g l = I1 β/2 with a = I3ω3/I1 and u0 = cos θ0, a quadratic in φ̇."""
        rhs = (I1 * self.uniform_precession_half_beta).subs({a: I3 * omega3 / I1, u0: sp.cos(theta0)})
        return sp.Eq(M * g * l, factor(sp.expand(rhs)))

    @derived
    def uniform_precession_polynomial(self) -> sp.Poly:
        """rhs − lhs of (3.80) as a polynomial in φ̇ (degree 2 when cos θ0 ≠ 0, 1 at θ0 = π/2)."""
        eq = self.uniform_precession_condition
        return sp.Poly(sp.expand(eq.rhs - eq.lhs), phi_dot)

    @derived
    def precession_discriminant(self) -> sp.Expr:
        """The discriminant of (3.80) in φ̇: I3²ω3² − 4 I1 M g l cos θ0 (real rates iff ≥ 0)."""
        return factor(sp.discriminant(self.uniform_precession_polynomial.as_expr(), phi_dot))

    @derived
    def precession_rates(self) -> tuple[sp.Expr, sp.Expr]:
        """(slow, fast): the two roots φ̇ of (3.80), slow the one of smaller |φ̇|, in a form free of cancellation.

        (3.80) is A φ̇² + B φ̇ + C = 0 (A = −I1 cos θ0, B = I3 ω3, C = −M g l, read off the derived
        polynomial).  The textbook (−B ± √disc)/(2A) subtracts nearly equal numbers for the slow
        root whenever 4AC ≪ B² — a fast spin, or θ0 near π/2, where A → 0 (in floating point it
        gave φ̇_slow = 0 for the horizontal gyroscope instead of M g l/(I3 ω3)).  With
        q = −(B + s √disc)/2, s = ±1 the sign of B (+1 at B = 0), the roots are C/q and q/A (their
        product is C/A, Vieta), and B + s √disc adds two numbers of one sign.  C/q is the slow
        root: |q|² ≥ |AC| (checked below by algebra).  At cos θ0 = 0 (3.80) is linear and C/q is
        its root M g l/(I3 ω3); the fast root is then infinite (q/A with A = 0).

        For ω3 > 0 (and any θ0) these are the textbook's (B ∓ √disc)/(2 I1 cos θ0), in that
        order; for cos θ0 < 0 (a hanging top) the two are real for every spin and of opposite signs.
        """
        poly = self.uniform_precession_polynomial
        if poly.degree() != 2:
            raise DerivationError(f"expected (3.80) quadratic in φ̇, got {poly}")
        A, B, C = poly.all_coeffs()
        disc = self.precession_discriminant
        if sp.expand(disc - (B**2 - 4 * A * C)) != 0:
            raise DerivationError(f"expected the discriminant B² − 4AC, got {disc}")
        s = sp.Symbol("s")
        q = -(B + s * sp.sqrt(disc)) / 2
        slow, fast = -C / -q, -q / -A  # (−C, −A, −q > 0 for a top above the horizontal spinning ω3 > 0)
        for sign in (1, -1):
            for r in (slow, fast):
                # each a root of A φ̇² + B φ̇ + C for either sign (with √disc² = disc)
                if sp.expand(sp.numer(sp.together(poly.as_expr().subs(phi_dot, r.subs(s, sign))))) != 0:
                    raise DerivationError(f"expected {r} (s = {sign}) to solve (3.80)")
        # slow has the smaller modulus: |q|² − |AC| = ((|B| + √disc)² − 4|AC|)/4 ≥ 0 since
        # √disc ≥ 0 and disc = B² − 4AC ≥ B² − 4|AC|; checked for the symbols as positive numbers
        x, y, w = sp.symbols("x y w", nonnegative=True)  # |B|, √disc, 4|AC| with y² ≥ x² − w
        if not sp.expand(((x + y) ** 2 - w) - (x**2 - w) - (y**2 + 2 * x * y)) == 0:
            raise DerivationError("expected |q|² ≥ |AC|")
        # the sign of B = I3 ω3 is that of its factors not known positive (ω3)
        sign_B = sp.Piecewise((1, sp.Mul(*[f for f in sp.Mul.make_args(B) if not f.is_positive]) >= 0), (-1, True))
        return slow.subs(s, sign_B), fast.subs(s, sign_B)

    @derived
    def minimum_spin(self) -> sp.Expr:
        """(3.81): the least spin ω3 ≥ 0 with real precession rates, (2/I3)√(M g l I1 max(cos θ0, 0)).

        For cos θ0 > 0 the ω3 > 0 at which the discriminant vanishes.  For cos θ0 ≤ 0 (a top at or
        below the horizontal) the discriminant I3²ω3² − 4 I1 M g l cos θ0 is ≥ 0 at every spin
        (checked: its value at ω3 = 0 is a positive multiple of −cos θ0, and it grows with ω3²),
        so any spin is enough and the minimum is 0 — the same root with cos θ0 replaced by
        max(cos θ0, 0), continuous at θ0 = π/2.
        """
        disc = self.precession_discriminant
        at_rest = factor(disc.subs(omega3, 0))
        k = sp.Symbol("k", positive=True)
        if not (sp.expand(disc - at_rest).subs(omega3, k).is_positive and at_rest.subs(sp.cos(theta0), -k).is_positive):
            raise DerivationError(f"expected the discriminant ≥ 0 for cos θ0 ≤ 0 at any spin, got {disc}")
        root = _positive_at_sample(sp.solve(disc, omega3))
        return root.subs(sp.cos(theta0), sp.Max(sp.cos(theta0), 0))

    # --- (3.82)-(3.83): the sleeping top -----------------------------------------------------

    @derived
    def sleeping_constants(self) -> dict:
        """{b: …, β: …} at θ = θ̇ = 0 (3.82), with a and α at the same state substituted back."""
        upright = {theta: 0, theta_dot: 0}
        c = {k: sp.simplify(v.subs(upright)) for k, v in self.constants_from_state.items()}
        spin_of_a = sp.solve(a - c[a], psi_dot)
        if len(spin_of_a) != 1:
            raise DerivationError(f"expected a linear in ψ̇ upright, got {c[a]}")
        b_up = sp.simplify(c[b].subs(psi_dot, spin_of_a[0]))
        beta_up = sp.simplify(c[beta] - c[alpha] + alpha)
        return {b: b_up, beta: beta_up}

    @derived
    def sleeping_f(self) -> sp.Expr:
        """f(u) for the sleeping top (3.83): (3.73) with b = a and β = α, factored."""
        return factor(self.f_u.subs(self.sleeping_constants))

    @derived
    def sleeping_roots(self) -> dict:
        """{root: multiplicity} of the sleeping top's f(u): a double root at 1 and u2 = a²/α − 1."""
        return sp.roots(sp.Poly(self.sleeping_f, u))

    @derived
    def sleeping_second_root(self) -> sp.Expr:
        """u2, the root of the sleeping top's f(u) other than u = 1 (3.83)."""
        others = [r for r in self.sleeping_roots if r != 1]
        if len(others) != 1 or self.sleeping_roots.get(sp.Integer(1)) != 2:
            raise DerivationError(f"expected a double root at u = 1 and one more, got {self.sleeping_roots}")
        return others[0]

    @derived
    def sleeping_second_root_spin(self) -> sp.Expr:
        """u2 in the spin: a = I3ω3/I1 and α = β = 2Mgl/I1 substituted (u2 > 1: stable, (3.83) case 1)."""
        return sp.expand(self.sleeping_second_root.subs({a: I3 * omega3 / I1, alpha: 2 * M * g * l / I1}))

    @derived
    def sleeping_threshold_spin(self) -> sp.Expr:
        """The spin ω3 > 0 at which u2 = 1: below it the sleeping top is unstable ((3.83), last paragraph)."""
        return _positive_at_sample(sp.solve(self.sleeping_second_root_spin - 1, omega3))


@functools.cache
def model() -> HeavyTopModel:
    """The process-wide heavy-top model (derivations shared by every caller)."""
    return HeavyTopModel()
