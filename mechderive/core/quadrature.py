"""One coordinate left: q̇² = F(q) by reduction, and a substitution u = g(q) that makes it a polynomial.

The first step of finding a closed form (issue 16), for any :class:`~.lagrangian.LagrangianModel`:

1. Routh-reduce by the cyclic coordinates (:attr:`~.lagrangian.LagrangianModel.routhian`).  When one
   coordinate q remains, the Routhian's energy ½ M(q) q̇² + V_eff(q) = E is conserved (its part linear
   in q̇ does not enter the energy), so q̇² = F(q) = 2 (E − V_eff(q)) / M(q): a quadrature.
2. Search a small family of substitutions u = g(q) (:data:`SUBSTITUTIONS`) for one that makes
   u̇² = g'(q)² F(q) a polynomial in u of degree ≤ 4 (the first cubic or lower, else the first quartic) — then u(t) is an elliptic function of t (degree
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
from sympy.functions.elementary.hyperbolic import HyperbolicFunction
from sympy.functions.elementary.trigonometric import TrigonometricFunction

from ..errors import DerivationError
from .lagrangian import LagrangianModel
from .model import derived
from .simplify import trig_normal

__all__ = ["Quadrature", "Substitution", "Oscillation", "NoQuadrature", "NoSubstitution", "SUBSTITUTIONS",
           "reduce_to_quadrature", "find_substitution", "oscillation", "MAX_DEGREE", "Shape", "SHAPES",
           "cyclic_rates", "without_time_gauge", "one_free_coordinate"]

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
    #: the independent variable: "t", or the name of the cyclic coordinate the orbit is measured along
    independent: str = "t"


@dataclass(frozen=True)
class Substitution:
    """u = g(q) with u̇² = P(u), P a polynomial in u of ``degree`` ≤ 4 (``polynomial`` its sympy Poly)."""

    name: str
    u_of_q: sp.Expr
    polynomial: sp.Poly
    degree: int
    variable: sp.Symbol
    independent: str = "t"


def _u() -> sp.Symbol:
    return sp.Symbol("u", real=True)


#: (name, g(q), g⁻¹(u)) tried in this order: the first of degree ≤ 3 wins, else the first quartic
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


def reduce_to_quadrature(model: LagrangianModel, along: str | None = None) -> Quadrature:
    """q̇² = F(q) of ``model`` reduced by its cyclic coordinates (see the module's docstring); with ``along`` (the
    name of a cyclic coordinate c) the orbit equation (dq/dc)² = F(q)/ċ(q)² instead — Binet's for a central force,
    where u = 1/r makes it a quadratic while in t it is not a quartic."""
    if model.state_lagrangian.has(sp.Symbol("t")) or any(s.name == "t" for s in model.state_lagrangian.free_symbols):
        raise NoQuadrature("expected a Lagrangian without explicit time: the energy is not conserved")
    remaining = model.remaining_coordinates if model.cyclic_coordinates else model.coordinates
    if len(remaining) != 1:  # said before the Routhian is derived (seconds for an asymmetric top)
        cyc = ", ".join(str(q) for q in model.cyclic_coordinates) or "none"
        raise NoQuadrature(f"expected one coordinate left after the reduction by the cyclic coordinates ({cyc}), "
                           f"got {len(remaining)}: {', '.join(str(q) for q in remaining)}")
    if model.cyclic_coordinates:
        reduced = model.routhian
        potential = model.effective_potential
        momenta = tuple(model.momentum_symbols[q] for q in model.cyclic_coordinates)
    else:
        reduced = model.state_lagrangian
        potential = sp.Integer(0)
        momenta = ()
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
    if along is None:
        return Quadrature(q, mass, potential, E, F, momenta)
    # the orbit q(c) along a cyclic coordinate c: (dq/dc)² = q̇² / ċ², ċ from p_c (a function of q alone, or no
    # orbit equation of this kind: ċ would depend on q̇ too)
    found = [c for c in model.cyclic_coordinates if c.func.__name__ == along]
    if not found:
        raise NoQuadrature(f"expected a cyclic coordinate to measure the orbit along, got {along!r} (cyclic: "
                           f"{', '.join(c.func.__name__ for c in model.cyclic_coordinates) or 'none'})")
    rate = model.cyclic_velocities[model.velocities[model.coordinates.index(found[0])]]
    if rate.has(qd):
        raise NoQuadrature(f"expected d{along}/dt a function of {q} alone, got {rate}")
    return Quadrature(q, mass, potential, E, sp.factor(sp.together(F / rate**2)), momenta, along)


def _as_polynomial(expr: sp.Expr, u: sp.Symbol) -> sp.Poly | None:
    """``expr`` as a polynomial in u (after normal forms), or None if it is not one."""
    def transcendental(e: sp.Expr) -> bool:
        return any(f.has(u) for f in e.atoms(sp.Function))

    def slow(e: sp.Expr) -> sp.Expr | None:
        # SymPy's simplify costs seconds; it is only worth it where no function of u is left that the
        # faster normal forms could not remove (cos u under u = q stays cos u whatever simplify does)
        return None if transcendental(e) else sp.cancel(sp.simplify(e))

    forms = [lambda e: sp.cancel(sp.together(e))]
    # The first form is cancel's reduced fraction p/q in the expression's generators (u, the other symbols, atoms
    # such as acos u or √u).  The later forms are tried only where they could decide otherwise (with floats, whose
    # inexact gcd makes no reduced fraction unique, all are tried):
    exact = not expr.has(sp.Float)
    if not (exact and not expr.atoms(TrigonometricFunction, HyperbolicFunction)):
        # trig_normal rewrites sines and cosines only (expand_trig: the trigonometric and hyperbolic functions);
        # without any, it reduces the same rational function in the same generators to the same fraction
        forms.append(lambda e: sp.cancel(trig_normal(e)))
    if not (exact and expr.is_rational_function(*expr.free_symbols)):
        # a rational function of symbols whose reduced denominator has u is no polynomial in u, whatever
        # simplify writes it as (Kepler's u̇² = (2E m u² + 2 k m u − p²)/(m² u²) under u = q)
        forms.append(slow)
    for form in forms:
        try:
            e = form(expr)
        except (TypeError, ValueError, NotImplementedError, RecursionError, sp.PolynomialError):
            continue
        if e is None:
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
    """The first u = g(q) of :data:`SUBSTITUTIONS` with u̇² = P(u) a polynomial of degree ≤ 3, else the first
    quartic; raises :class:`NoSubstitution` naming the degrees found (beyond quartic) and F otherwise."""
    q, F = quadrature.coordinate, quadrature.F
    u = _u()
    found: list[str] = []
    best: Substitution | None = None
    for name, g, inverse in SUBSTITUTIONS:
        u_dot_sq = g(q).diff(q) ** 2 * F
        in_u = u_dot_sq.subs(q, inverse(u))
        p = _as_polynomial(in_u, u)
        if p is None:
            continue
        if p.degree() <= MAX_DEGREE:
            # past a quartic the search goes on for a lower degree (Binet's orbit: r gives a quartic, 1/r a
            # quadratic); a cubic or lower is taken at once (each further candidate costs a symbolic normal form)
            if best is None or p.degree() < best.degree:
                best = Substitution(name, g(q), p, p.degree(), u, quadrature.independent)
            if best.degree <= 3:
                break
            continue
        found.append(f"{name}: degree {p.degree()}")
    if best is not None:
        return best
    beyond = f" (polynomials beyond quartic: {'; '.join(found)})" if found else ""
    raise NoSubstitution(f"expected a substitution making q̇² = F(q) a polynomial of degree ≤ {MAX_DEGREE} in u; "
                         f"none of {', '.join(n for n, _, _ in SUBSTITUTIONS)} does{beyond}: F = {F}")


# --- one motion: turning points and period ----------------------------------------------------------

@dataclass(frozen=True)
class Oscillation:
    """The motion of u = g(q) between two roots of P, and what it means for q.

    ``u_range``: the roots (a, b) of P around u0 (the turning points of u); ``folds``: which of them are
    where g'(q) = 0 (q passes through there: not a turning point of q); ``u_period``: the period of u(t);
    ``period``: that of q — twice u's when one end is a fold (a libration through it), u's otherwise (a
    rotation through both folds, or an oscillation between two true turning points); ``kind``.
    Values are mpmath numbers at the working precision.
    """

    u_range: tuple
    folds: tuple[bool, bool]
    u_period: object
    period: object
    kind: str


def _real_roots(coeffs: list) -> list:
    import mpmath

    roots = mpmath.polyroots(coeffs, maxsteps=400, extraprec=6 * mpmath.mp.dps)
    tiny = mpmath.mpf(10) ** (-mpmath.mp.dps // 2)
    return sorted(mpmath.re(r) for r in roots if abs(mpmath.im(r)) <= tiny * (1 + abs(r)))


def _complete_integral(c: list, roots: list, a, b):
    """∫_a^b du / √P(u) for P of degree 2, 3 or 4 with leading coefficient c[0], between adjacent real roots
    a < b of P (P > 0 between): 2K(m)/√(...) with the modulus of the root configuration (Byrd & Friedman
    235.00-236.00 for three real roots, 252.00-257.00 for four, 259.00 for two and a complex pair).
    Checked in the tests against mpmath's quadrature of the same integral."""
    import mpmath

    deg = len(c) - 1
    lead = c[0]
    if deg == 2:
        return mpmath.pi / mpmath.sqrt(-lead)
    if deg == 3:
        r1, r2, r3 = roots
        if lead > 0:  # P > 0 on (r1, r2)
            m = (r2 - r1) / (r3 - r1)
        else:  # on (r2, r3)
            m = (r3 - r2) / (r3 - r1)
        return 2 * mpmath.ellipk(m) / mpmath.sqrt(abs(lead) * (r3 - r1))
    if len(roots) == 2:  # two real roots b < a and a complex pair b1 ± i a1 (Byrd & Friedman 259.00)
        import mpmath as mp

        pair = [z for z in mp.polyroots(c, maxsteps=400, extraprec=6 * mp.mp.dps) if abs(mp.im(z)) > 0]
        b1, a1 = mp.re(pair[0]), abs(mp.im(pair[0]))
        A, B = mp.sqrt((b - b1) ** 2 + a1**2), mp.sqrt((a - b1) ** 2 + a1**2)
        m = ((b - a) ** 2 - (A - B) ** 2) / (4 * A * B)
        return 2 * mp.ellipk(m) / mp.sqrt(abs(lead) * A * B)
    r1, r2, r3, r4 = roots
    if (a, b) == (r2, r3):
        m = (r3 - r2) * (r4 - r1) / ((r4 - r2) * (r3 - r1))
    else:  # (r1, r2) or (r3, r4)
        m = (r2 - r1) * (r4 - r3) / ((r3 - r1) * (r4 - r2))
    return 2 * mpmath.ellipk(m) / mpmath.sqrt(abs(lead) * (r3 - r1) * (r4 - r2))


def oscillation(substitution: Substitution, values: dict, q0: float, *, dps: int = 40) -> Oscillation:
    """Turning points and period of the motion started at q = ``q0`` with the constants ``values``
    ({symbol: number}: the parameters, E and the conserved momenta), from u̇² = P(u).

    Raises :class:`NoSubstitution` for a motion that is not periodic: P < 0 at the start, no root of P on
    one side of u0 (unbounded), u0 on a double root (steady, or a separatrix) — saying which.
    """
    import mpmath

    with mpmath.workdps(dps):
        coeffs = [mpmath.mpf(sp.N(c.subs(values), dps + 10)) for c in substitution.polynomial.all_coeffs()]
        q = sp.Symbol("q")
        g = substitution.u_of_q.subs({s: q for s in substitution.u_of_q.free_symbols})
        u0 = mpmath.mpf(sp.N(g.subs(q, q0), dps + 10))
        P = lambda x: mpmath.polyval(coeffs, x)  # noqa: E731
        roots = _real_roots(coeffs)
        # the intervals between consecutive real roots where P > 0; the motion is the one holding u0, within the
        # rounding of constants given as doubles (a start at a turning point puts u0 on a root, to ~1e-16)
        slack = mpmath.mpf(2) ** -40 * (1 + abs(u0))
        ends = [-mpmath.inf, *roots, mpmath.inf]
        positive = []
        for lo, hi in zip(ends[:-1], ends[1:]):
            mid = (lo + hi) / 2 if mpmath.isfinite(lo) and mpmath.isfinite(hi) else \
                (hi - 1 if mpmath.isfinite(hi) else lo + 1 if mpmath.isfinite(lo) else mpmath.mpf(0))
            if P(mid) > 0 and lo - slack <= u0 <= hi + slack:
                positive.append((lo, hi))
        if not positive:
            if any(abs(r - u0) <= slack for r in roots):  # P ≤ 0 on both sides of its root u0: an equilibrium
                raise NoSubstitution(f"expected two distinct turning points, got the start on a double root of P at "
                                     f"u = {mpmath.nstr(u0, 8)}: a steady motion (no period)")
            raise NoSubstitution(f"expected u̇² = P(u0) ≥ 0 at the start, got {mpmath.nstr(P(u0), 5)}: the constants "
                                 f"do not belong to this start")
        if len(positive) > 1:
            raise NoSubstitution(f"expected the start inside one interval of motion, got it on a double root of P at u = "
                                 f"{mpmath.nstr(u0, 8)}: a steady motion or a separatrix (no period)")
        a, b = positive[0]
        if not (mpmath.isfinite(a) and mpmath.isfinite(b)):
            raise NoSubstitution(f"expected a bounded motion, got P(u) > 0 for all u {'<' if not mpmath.isfinite(a) else '>'} "
                                 f"u0 = {mpmath.nstr(u0, 8)} (roots {[mpmath.nstr(r, 8) for r in roots]}): unbounded")
        dg = sp.diff(g, q)
        inverse = dict((n, inv) for n, _, inv in SUBSTITUTIONS)[substitution.name]

        def fold(r) -> bool:
            qr = sp.N(inverse(sp.Float(mpmath.nstr(r, dps + 5), dps)), dps)
            return bool(abs(complex(sp.N(dg.subs(q, qr), dps))) <= 10.0 ** (-dps // 3))

        folds = (fold(a), fold(b))
        u_period = 2 * _complete_integral(coeffs, roots, a, b)
        if sum(folds) == 1:
            period, kind = 2 * u_period, "libration through a fold of the substitution"
        elif sum(folds) == 2:
            period, kind = u_period, "rotation"
        else:
            period, kind = u_period, "oscillation between turning points"
        return Oscillation((a, b), folds, u_period, period, kind)


# --- the substitution's shape: branches and folds, for q(t) from u(t) --------------------------------

@dataclass(frozen=True)
class Shape:
    """How q is read back from u = g(q) numerically (NumPy): ``dg`` = g'(q); ``inverse(u, q0)`` = g⁻¹(u) on the
    monotone branch of g holding q0; ``folds``: (u_e, q_e, repeat) for each value u_e where g'(q) = 0, at
    q = q_e + k·repeat (repeat None: once); near a fold |u − u_e| = σ² with q − q_e = ``scale``·f(σ/√2),
    f = ``local`` ("asin", "asinh" or "identity") — the coordinate in which q passes the fold smoothly.
    """

    dg: Callable
    inverse: Callable
    folds: tuple = ()
    local: str = "identity"
    scale: float = 1.0

    def fold_point(self, u_e: float, q0: float) -> float | None:
        """The point q_e of the fold at u = u_e nearest q0 (None if g has no fold there)."""
        for value, q_e, repeat in self.folds:
            if abs(value - u_e) <= 1e-9 * (1 + abs(value)):
                return q_e if repeat is None else q_e + repeat * round((q0 - q_e) / repeat)
        return None


def _np():
    import numpy

    return numpy


def _inverse_cos(u, q0):
    np = _np()
    base = 2 * np.pi * np.round(q0 / (2 * np.pi))
    return base + (1.0 if q0 - base >= 0 else -1.0) * np.arccos(np.clip(u, -1.0, 1.0))


def _inverse_sin(u, q0):
    np = _np()
    base = 2 * np.pi * np.round(q0 / (2 * np.pi))
    x = np.arcsin(np.clip(u, -1.0, 1.0))
    if abs(q0 - base) <= np.pi / 2:
        return base + x
    return base + (np.pi if q0 > base else -np.pi) - x


#: the numeric shape of each member of :data:`SUBSTITUTIONS`, by name
SHAPES: dict[str, Shape] = {
    "u = q": Shape(lambda q: _np().ones_like(q), lambda u, q0: u),
    "u = cos q": Shape(lambda q: -_np().sin(q), _inverse_cos,
                       ((1.0, 0.0, 2 * 3.141592653589793), (-1.0, 3.141592653589793, 2 * 3.141592653589793)),
                       "asin", 2.0),
    "u = sin q": Shape(lambda q: _np().cos(q), _inverse_sin,
                       ((1.0, 3.141592653589793 / 2, 2 * 3.141592653589793),
                        (-1.0, -3.141592653589793 / 2, 2 * 3.141592653589793)), "asin", 2.0),
    "u = 1/q": Shape(lambda q: -1.0 / q**2, lambda u, q0: 1.0 / u),
    "u = q²": Shape(lambda q: 2.0 * q, lambda u, q0: (1.0 if q0 >= 0 else -1.0) * _np().sqrt(_np().maximum(u, 0.0)),
                    ((0.0, 0.0, None),), "identity", 2.0**0.5),
    "u = cosh q": Shape(lambda q: _np().sinh(q),
                        lambda u, q0: (1.0 if q0 >= 0 else -1.0) * _np().arccosh(_np().maximum(u, 1.0)),
                        ((1.0, 0.0, None),), "asinh", 2.0),
    "u = sin(q/2)": Shape(lambda q: 0.5 * _np().cos(q / 2), lambda u, q0: 2.0 * _inverse_sin(u, q0 / 2),
                          ((1.0, 3.141592653589793, 4 * 3.141592653589793),
                           (-1.0, -3.141592653589793, 4 * 3.141592653589793)), "asin", 4.0),
    "u = tan(q/2)": Shape(lambda q: 0.5 / _np().cos(q / 2) ** 2,
                          lambda u, q0: 2.0 * _np().arctan(u) + 2 * _np().pi * _np().round(q0 / (2 * _np().pi))),
}


def cyclic_rates(model: LagrangianModel, substitution: Substitution) -> dict:
    """{cyclic coordinate name: (N, D)}: each cyclic coordinate's rate ċ as a rational function N(u)/D(u) of the
    substitution's u (sympy Polys in u over the parameters and momenta), or a string saying why it is not one
    (a rate odd in the fold's sense, e.g. sin q under u = cos q)."""
    u = substitution.variable
    inverse = dict((n, inv) for n, _, inv in SUBSTITUTIONS)[substitution.name]
    remaining = model.remaining_coordinates[0]
    position = model.positions[model.coordinates.index(remaining)]
    out: dict = {}
    for c in model.cyclic_coordinates:
        name = c.func.__name__
        rate = model.cyclic_velocities[model.velocities[model.coordinates.index(c)]]
        in_u = rate.subs(position, inverse(u))
        try:
            e = sp.cancel(sp.together(in_u))
        except (TypeError, ValueError, NotImplementedError, RecursionError):
            out[name] = f"d{name}/dt = {rate} is not a rational function of {substitution.name[4:]}"
            continue
        num, den = sp.fraction(e)
        try:
            N, D = sp.Poly(sp.expand(num), u), sp.Poly(sp.expand(den), u)
        except sp.PolynomialError:
            out[name] = f"d{name}/dt = {rate} is not a rational function of {substitution.name[4:]}"
            continue
        if any(x.has(u) for x in N.coeffs() + D.coeffs()):
            out[name] = f"d{name}/dt = {rate} is not a rational function of {substitution.name[4:]}"
            continue
        out[name] = (N, D)
    return out


class _FirstNotCyclic(LagrangianModel):
    """A model whose first coordinate is not counted as cyclic (see :func:`one_free_coordinate`)."""

    @derived
    def cyclic_coordinates(self) -> tuple:
        return tuple(self.coordinates[1:])


def one_free_coordinate(model: LagrangianModel) -> LagrangianModel:
    """``model`` itself, or, where every coordinate is cyclic (L = I θ̇²/2: a free rotor; m|ṙ|²/2: a free particle),
    the same L with its first coordinate counted as the one left (the reduction by all would leave none): q̇² = F
    constant, P of degree 0 under u = q — uniform motion — and the others' rates constant."""
    if not model.coordinates or model.remaining_coordinates:
        return model
    return _FirstNotCyclic(model.lagrangian, list(model.coordinates))


# --- explicit time that is only a gauge ----------------------------------------------------------------

def without_time_gauge(model: LagrangianModel) -> tuple[LagrangianModel, sp.Expr]:
    """(model', G): L' = L − dG(q, t)/dt − h(t), free of t, with the same equations of motion; raises
    :class:`NoQuadrature` where the explicit time is not of that form.

    The explicit time of a Lagrangian written in an accelerating frame's coordinates is often a total
    derivative: the Lagrange top whose pivot rises as z_P = a t²/2 has, in the inertial frame,
    L = T_P + ½M(at)² − M a t l sin θ θ̇ − M g (a t²/2 + l cos θ), and −M a t l sin θ θ̇ = d/dt(M a t l cos θ)
    − M a l cos θ: L' = T_P − M (g + a) l cos θ, the same top in a stronger gravity.  The t-dependent part
    must be Σ A_i(q, t) q̇_i + B(q, t) with ∂A_i/∂q_j symmetric; G = ∫ A dq is found by integrating A_i in
    q_i in turn and checked exactly.

    >>> import sympy as sp
    >>> from mechderive.core.symbols import coordinate, t
    >>> a, g = sp.symbols("a g", positive=True)
    >>> z = coordinate("z")
    >>> L = z.diff(t)**2 / 2 + a * t * z.diff(t) - g * z
    >>> reduced, G = without_time_gauge(LagrangianModel(L, [z]))
    >>> sp.expand(reduced.state_lagrangian)
    -a*z - g*z + z_dot**2/2
    """
    from .lagrangian import from_state_symbols
    from .simplify import is_zero

    L = sp.expand(model.state_lagrangian)
    times = [s for s in L.free_symbols if s.name == "t"]
    if not times:
        return model, sp.Integer(0)
    T = times[0]
    positions, velocities = model.positions, model.velocities
    timed = sp.Add(*[term for term in sp.Add.make_args(L) if term.has(T)])
    try:
        poly = sp.Poly(timed, *velocities)
    except sp.PolynomialError:
        poly = None
    if poly is None or poly.total_degree() > 1:
        raise NoQuadrature(f"expected the explicit time of L in terms at most linear in the velocities (a gauge), "
                           f"got {timed}")
    A = [poly.coeff_monomial(v) for v in velocities]
    G = sp.Integer(0)
    for q, a_q in zip(positions, A):
        rest = sp.expand(a_q - sp.diff(G, q))
        if rest != 0:
            G = G + sp.integrate(rest, q)
    if not all(is_zero(sp.diff(G, q) - a_q) for q, a_q in zip(positions, A)):
        raise NoQuadrature(f"expected the velocity terms with t a total derivative dG/dt, got {sp.Add(*[a * v for a, v in zip(A, velocities)])} "
                           "(not the gradient of any G(q, t))")
    reduced = sp.expand(L - sum(a_q * v for a_q, v in zip(A, velocities)) - sp.diff(G, T))
    # h(t): terms with no coordinate or velocity change no equation of motion
    kept = [term for term in sp.Add.make_args(reduced) if term.has(*positions, *velocities)]
    reduced = sp.Add(*kept)
    if reduced.has(T):
        raise NoQuadrature(f"expected L − dG/dt free of t, got {reduced} (a time dependence that is not a gauge)")
    return LagrangianModel(from_state_symbols(reduced, model.coordinates), list(model.coordinates)), G
