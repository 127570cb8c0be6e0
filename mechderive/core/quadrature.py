"""One coordinate left: q̇² = F(q) by reduction, and a substitution u = g(q) that makes it a polynomial.

The first step of finding a closed form (issue 16), for any :class:`~.lagrangian.LagrangianModel`:

1. Routh-reduce by the cyclic coordinates (:attr:`~.lagrangian.LagrangianModel.routhian`).  When one
   coordinate q remains, the Routhian's energy ½ M(q) q̇² + V_eff(q) = E is conserved (its part linear
   in q̇ does not enter the energy), so q̇² = F(q) = 2 (E − V_eff(q)) / M(q): a quadrature.
2. Search a small family of substitutions u = g(q) (:data:`SUBSTITUTIONS`) for one that makes
   u̇² = g'(q)² F(q) a polynomial in u of degree ≤ 4 — then u(t) is an elliptic function of t (degree
   3 and 4: Jacobi's; ≤ 2: trigonometric or hyperbolic).  For each candidate q is written as the
   inverse g⁻¹(u), the result brought to a normal form (cancel; sin, cos of acos u as √(1 − u²) ...) and
   accepted only if it is a polynomial in u whose coefficients are free of u.

The heavy top and the spherical pendulum come out as u = cos θ with a cubic (the chapter's f(u),
(3.73)); the simple pendulum as cos θ (cubic) as well.  Where the search fails, :class:`NoQuadrature`
or :class:`NoSubstitution` says why: more than one coordinate remains (the double pendulum, the
asymmetric heavy top), or no member of the family gives a polynomial of degree ≤ 4 (naming the best
degree found and F itself).

>>> import sympy as sp
>>> from mechderive.core.lagrangian import LagrangianModel
>>> from mechderive.core.symbols import coordinate, t
>>> m, g, l = sp.symbols("m g l", positive=True)
>>> th, ph = coordinate("theta"), coordinate("phi")
>>> L = m * l**2 * (th.diff(t)**2 + sp.sin(th)**2 * ph.diff(t)**2) / 2 + m * g * l * sp.cos(th)
>>> found = find_substitution(reduce_to_quadrature(LagrangianModel(L, [th, ph])))
>>> found.name, found.degree
('u = cos q', 3)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import sympy as sp

from ..errors import DerivationError
from .lagrangian import LagrangianModel

__all__ = ["Quadrature", "Substitution", "NoQuadrature", "NoSubstitution", "SUBSTITUTIONS",
           "reduce_to_quadrature", "find_substitution", "MAX_DEGREE"]

#: the largest degree of u̇² = P(u) solved by elliptic functions
MAX_DEGREE = 4


class NoQuadrature(DerivationError):
    """The reduction does not leave one coordinate with a conserved energy (the message says why)."""


class NoSubstitution(DerivationError):
    """No substitution of the family makes F a polynomial of degree ≤ 4 (the message says what was found)."""


@dataclass(frozen=True)
class Quadrature:
    """q̇² = F(q) after the reduction: the coordinate, M(q), V_eff(q), the energy symbol and F."""

    coordinate: sp.Symbol
    mass: sp.Expr
    effective_potential: sp.Expr
    energy: sp.Symbol
    F: sp.Expr
    momenta: tuple[sp.Symbol, ...]


@dataclass(frozen=True)
class Substitution:
    """u = g(q) with u̇² = P(u), P a polynomial in u of ``degree`` ≤ 4 (``polynomial`` its sympy Poly)."""

    name: str
    u_of_q: sp.Expr
    polynomial: sp.Poly
    degree: int
    variable: sp.Symbol


def _u() -> sp.Symbol:
    return sp.Symbol("u", real=True)


#: (name, g(q), g⁻¹(u)) tried in this order: the first that gives a polynomial of degree ≤ 4 wins
SUBSTITUTIONS: tuple[tuple[str, Callable[[sp.Expr], sp.Expr], Callable[[sp.Expr], sp.Expr]], ...] = (
    ("u = q", lambda q: q, lambda u: u),
    ("u = cos q", sp.cos, sp.acos),
    ("u = sin q", sp.sin, sp.asin),
    ("u = 1/q", lambda q: 1 / q, lambda u: 1 / u),
    ("u = q²", lambda q: q**2, sp.sqrt),
    ("u = cosh q", sp.cosh, sp.acosh),
    ("u = sin(q/2)", lambda q: sp.sin(q / 2), lambda u: 2 * sp.asin(u)),
    ("u = tan(q/2)", lambda q: sp.tan(q / 2), lambda u: 2 * sp.atan(u)),
)


def reduce_to_quadrature(model: LagrangianModel) -> Quadrature:
    """q̇² = F(q) of ``model`` reduced by its cyclic coordinates (see the module's docstring)."""
    if model.state_lagrangian.has(sp.Symbol("t")) or any(s.name == "t" for s in model.state_lagrangian.free_symbols):
        raise NoQuadrature("expected a Lagrangian without explicit time: the energy is not conserved")
    if model.cyclic_coordinates:
        remaining = model.remaining_coordinates
        reduced = model.routhian
        potential = model.effective_potential
        momenta = tuple(model.momentum_symbols[q] for q in model.cyclic_coordinates)
    else:
        remaining = model.coordinates
        reduced = model.state_lagrangian
        potential = sp.Integer(0)
        momenta = ()
    if len(remaining) != 1:
        cyc = ", ".join(str(q) for q in model.cyclic_coordinates) or "none"
        raise NoQuadrature(f"expected one coordinate left after the reduction by the cyclic coordinates ({cyc}), "
                           f"got {len(remaining)}: {', '.join(str(q) for q in remaining)}")
    index = model.coordinates.index(remaining[0])
    q, qd = model.positions[index], model.velocities[index]
    poly = sp.Poly(sp.expand(reduced), qd)
    if poly.degree() > 2:
        raise NoQuadrature(f"expected the reduced Lagrangian quadratic in {qd}, got degree {poly.degree()}")
    mass = sp.factor(2 * poly.coeff_monomial(qd**2))
    if not model.cyclic_coordinates:
        potential = sp.factor(-poly.coeff_monomial(1))
    if mass == 0:
        raise NoQuadrature(f"expected a kinetic term in {qd}, got none: {reduced}")
    E = sp.Symbol("E", real=True)
    F = sp.factor(sp.together(2 * (E - potential) / mass))
    return Quadrature(q, mass, potential, E, F, momenta)


def _as_polynomial(expr: sp.Expr, u: sp.Symbol) -> sp.Poly | None:
    """``expr`` as a polynomial in u (after normal forms), or None if it is not one."""
    for form in (lambda e: sp.cancel(sp.together(e)), lambda e: sp.cancel(sp.simplify(e))):
        try:
            e = form(expr)
        except (TypeError, ValueError, NotImplementedError, RecursionError):
            continue
        num, den = sp.fraction(e)
        if den.has(u):
            continue
        try:
            p = sp.Poly(sp.expand(num / den), u)
        except sp.PolynomialError:
            continue
        if any(c.has(u) for c in p.coeffs()) or not all(c.is_finite is not False for c in p.coeffs()):
            continue
        return p
    return None


def find_substitution(quadrature: Quadrature) -> Substitution:
    """The first u = g(q) of :data:`SUBSTITUTIONS` with u̇² = P(u) a polynomial of degree ≤ 4; raises
    :class:`NoSubstitution` naming the degrees found (a polynomial beyond quartic) and F otherwise."""
    q, F = quadrature.coordinate, quadrature.F
    u = _u()
    found: list[str] = []
    for name, g, inverse in SUBSTITUTIONS:
        u_dot_sq = g(q).diff(q) ** 2 * F
        in_u = u_dot_sq.subs(q, inverse(u))
        p = _as_polynomial(in_u, u)
        if p is None:
            continue
        if p.degree() <= MAX_DEGREE:
            return Substitution(name, g(q), p, p.degree(), u)
        found.append(f"{name}: degree {p.degree()}")
    beyond = f" (polynomials beyond quartic: {'; '.join(found)})" if found else ""
    raise NoSubstitution(f"expected a substitution making q̇² = F(q) a polynomial of degree ≤ {MAX_DEGREE} in u; "
                         f"none of {', '.join(n for n, _, _ in SUBSTITUTIONS)} does{beyond}: F = {F}")
