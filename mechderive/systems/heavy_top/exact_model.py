"""Symbolic derivation of the heavy top's closed-form motion (section 3.6).

From the derived cubic u̇² = f(u) (3.73), written through its roots
u1 ≤ u2 ≤ u3 as f(u) = β (u - u1)(u - u2)(u - u3) (β is f's leading coefficient,
checked), the ansatz

    u(t) = u1 + (u2 - u1) sn²(v | m),    v = κ t + v0,

is substituted into u̇² = f(u) with sn' = cn dn, cn² = 1 - sn², dn² = 1 - m sn²;
requiring the identity in sn² gives κ² and m (derived, not typed).  The nutation
period is 2K(m)/κ.

The rates φ̇(u) (3.74) and ψ̇(u) (3.75), rational in u, become rational in sn²
along the ansatz, and SymPy's partial fractions give

    rate = c0 + Σ_i c_i / (1 - n_i sn²(v | m)),

each term integrating to an incomplete elliptic integral of the third kind,
∫ dt / (1 - n sn²) = Π(n; am v | m) / κ.
"""

from __future__ import annotations

import functools

import sympy as sp

from ...core.model import SymbolicModel, derived
from ...core.simplify import TrigField, factor, is_zero_rational, trig_normal
from ...errors import DerivationError
from . import model as heavy_model

__all__ = ["HeavyTopExactModel", "model", "u1", "u2", "u3"]

u1, u2, u3 = sp.symbols("u1 u2 u3", real=True)
_m = sp.Symbol("m", positive=True)
_x = sp.Symbol("x", nonnegative=True)  # sn²


def _is_zero_rational(expr: sp.Expr) -> bool:
    """Whether ``expr`` is identically 0: exactly, in the field of rational functions of its symbols, when it
    is one (the roots, constants and rates met here are: :func:`~mechderive.core.simplify.is_zero_rational`);
    else by :func:`sympy.simplify` (slow).  (cancel of the together-ed sum spent most of a partial-fraction
    derivation's time in Expr-level expansion, and the simplify it fell back on ~0.15 s to confirm that two
    distinct poles differ.)"""
    decided = is_zero_rational(expr)
    if decided is not None:
        return decided
    return sp.cancel(expr) == 0 or sp.simplify(expr) == 0


def _simple_poles(along: sp.Expr, x: sp.Symbol) -> tuple[sp.Expr, list[tuple[sp.Expr, sp.Expr]]]:
    """(c0, [(c_i, n_i)]) with ``along`` = c0 + Σ c_i / (1 − n_i x) identically in x (simple poles only, the
    terms of one pole merged), checked by rebuilding it."""
    c0, terms = sp.Integer(0), []
    for term in sp.Add.make_args(sp.expand(sp.apart(along, x, full=False))):
        num, den = sp.fraction(factor(term))
        if not den.has(x):
            c0 += term
            continue
        poly = sp.Poly(den, x)
        if poly.degree() != 1:
            raise DerivationError(f"expected simple poles in sn², got denominator {den}")
        if num.has(x):
            raise DerivationError(f"expected a constant numerator, got {num}")
        d1, d0 = poly.all_coeffs()
        c, n = num / d0, factor(-d1 / d0)
        for k, (c_old, n_old) in enumerate(terms):
            if _is_zero_rational(n - n_old):  # the same pole: one term
                terms[k] = (c_old + c, n_old)
                break
        else:
            terms.append((c, n))
    terms = [(factor(c), n) for c, n in terms]
    rebuilt = c0 + sum(c / (1 - n * x) for c, n in terms)
    if not _is_zero_rational(rebuilt - along):
        raise DerivationError("partial fractions do not reproduce the rate")
    return factor(c0), terms


class HeavyTopExactModel(SymbolicModel):
    """Derived constants of u(t) and the partial fractions of φ̇ and ψ̇ along it."""

    @derived
    def cubic_in_roots(self) -> sp.Expr:
        """f(u) = c3 (u - u1)(u - u2)(u - u3), with c3 f's leading coefficient (which must be β)."""
        c3 = heavy_model.model().f_coefficients[0]
        if not _is_zero_rational(c3 - heavy_model.beta):
            raise DerivationError(f"expected f(u)'s leading coefficient β, got {c3}")
        u = heavy_model.u
        return c3 * (u - u1) * (u - u2) * (u - u3)

    @derived
    def nutation_constants(self) -> dict[str, sp.Expr]:
        """κ² and m of u = u1 + (u2 - u1) sn²(κ t + v0 | m), from u̇² = f(u) identically in sn²."""
        u = heavy_model.u
        sn, cn, dn = sp.symbols("sn cn dn", real=True)
        # κ² and κ² m enter the identity linearly: solved for as (K2, P) by linear algebra, m = P / K2
        k2, p = sp.symbols("K2 P")
        ansatz = u1 + (u2 - u1) * sn**2
        u_dot_sq = 4 * (u2 - u1) ** 2 * sn**2 * cn**2 * dn**2 * k2  # (d/dt of the ansatz)², κ² = K2
        # the identity as a polynomial in x = sn² over the roots, β, K2 and m (cn² = 1 − x, dn² = 1 − m x): by
        # SymPy's sparse polynomials, composing f's factored form with the ansatz, instead of substituting into
        # and expanding expressions (most of this derivation's time)
        R = sp.polys.rings.ring([_x, _m, k2, p, *sorted(self.cubic_in_roots.free_symbols - {u}, key=str), u],
                                sp.QQ)[0]
        x_sq = {sn**2: _x, cn**2: 1 - _x, dn**2: 1 - _m * _x}
        lhs = R.from_expr(sp.Mul(*[x_sq.get(f, f) for f in sp.Mul.make_args(u_dot_sq)]))
        cubic = R.from_expr(self.cubic_in_roots).compose(R(u), R.from_expr(ansatz.xreplace(x_sq)))
        residual = R.zero
        i_m, i_k2 = R.gens.index(R(_m)), R.gens.index(R(k2))
        for monom, coeff in (lhs - cubic).terms():
            if monom[i_m] != monom[i_k2] * (monom[i_m] > 0):  # m only in κ² m
                raise DerivationError(f"expected m only in κ² m in the nutation identity, got {(lhs - cubic)}")
            # κ² m → P (linear in the unknowns)
            moved = list(monom)
            if monom[i_m]:
                moved[i_m], moved[i_k2] = 0, 0
                moved[R.gens.index(R(p))] = monom[i_m]
            residual += R({tuple(moved): coeff})
        # its coefficients of x^k, highest first (what Poly(residual.as_expr(), x).all_coeffs() gives), read off the
        # ring's terms: building that Poly from the expression was 40% of this derivation
        i_x, by_power = R.gens.index(R(_x)), {}
        for monom, coeff in residual.terms():
            by_power.setdefault(monom[i_x], {})[monom[:i_x] + (0,) + monom[i_x + 1:]] = coeff
        coeffs = [R(by_power[k]).as_expr() if k in by_power else sp.Integer(0) for k in range(max(by_power, default=0), -1, -1)]
        sol = list(sp.linsolve([c for c in coeffs if c != 0], [k2, p]))
        if len(sol) != 1 or any(v.free_symbols & {k2, p} for v in sol[0]):
            raise DerivationError(f"expected one (κ², κ² m) for the nutation ansatz, got {sol}")
        kappa_sq = factor(sol[0][0])
        m = factor(sol[0][1] / sol[0][0])
        return {"kappa2": kappa_sq, "m": m, "m1": factor(1 - m)}

    def _partial_fractions(self, rate_u: sp.Expr) -> dict:
        """rate(u) along the ansatz as c0 + Σ c_i/(1 - n_i x), x = sn²; returns {"c0": .., "terms": [(c_i, n_i)]}.

        The partial fractions are taken in u, where the rate is a rational function of one variable with
        linear poles (3.74)–(3.75) — fast — rather than in x after substituting the ansatz (a rational
        function of x, u1, u2, a, b, …: SymPy's apart solved for undetermined coefficients there, ~0.3 s a
        rate).  The ansatz is linear in x, so each pole maps to one: C/(p u + q) along u = u1 + (u2 − u1) x
        is [C/(p u1 + q)] / (1 − n x) with n = −p (u2 − u1)/(p u1 + q); distinct poles in u give distinct n.
        The result is checked to reproduce the rate along the ansatz identically."""
        u = heavy_model.u
        c0, terms = sp.Integer(0), []
        for term in sp.Add.make_args(heavy_model.partial_fractions_in_u(rate_u)):
            num, den = sp.fraction(factor(term))
            if not den.has(u):
                c0 += term
                continue
            poly = sp.Poly(den, u)
            if poly.degree() != 1 or num.has(u):
                raise DerivationError(f"expected simple poles in u with constant numerators, got {term}")
            p, q = poly.all_coeffs()
            at_u1 = p * u1 + q
            terms.append((factor(num / at_u1), factor(-p * (u2 - u1) / at_u1)))
        # (only checked against: the symbol u's nodes replaced, what subs does, without its matching)
        along = rate_u.xreplace({u: u1 + (u2 - u1) * _x})
        if not _is_zero_rational(c0 + sum(c / (1 - n * _x) for c, n in terms) - along):
            raise DerivationError("partial fractions do not reproduce the rate")
        # in a fixed order (of n), whatever order apart lists its terms in
        terms.sort(key=lambda cn: sp.default_sort_key(cn[1]))
        return {"c0": factor(c0), "terms": terms}

    @derived
    def f_taylor_state(self) -> tuple[sp.Expr, ...]:
        """The coefficients of w³, w², w, 1 in f(u0 + w) (3.73), u0 = cos θ0, in the parameters and the state.

        Measured from the start, the turning points are u_k = u0 + w_k with w1 ≤ 0 ≤ w2: the amplitude
        w2 − w1 and the distances from u0 keep their relative accuracy in double precision, where the
        roots of f in u lose it to cancellation when the amplitude is small (a fast top: u2 − u1 ~ 1e-4
        leaves 1e-12 of it).  The constant term is f(u0) = sin²θ0 θ̇0² (the energy at the start).
        """
        hm = heavy_model
        m = hm.model()
        cfs = m.constants_from_state
        # f's coefficients (in a, b, α, β) and u0 = cos θ0 in the state, as rational functions of cos θ, sin θ and
        # the symbols; f(u0 + w)'s coefficients by Horner's scheme there (dividing f by u − u0 again and again
        # leaves f(u0), f'(u0), f''(u0)/2, …): no expression is expanded, substituted into or simplified on the
        # way (that was most of a cold start's time here); the trig normal form at the end, as trig_normal's
        F = TrigField([*cfs.values(), sp.cos(hm.theta)])
        remaining = [F(c.xreplace(cfs)) for c in m.f_polynomial.all_coeffs()]  # highest power first
        u0, taylor = F(sp.cos(hm.theta)), []
        while remaining:
            partial = []
            for c in remaining:
                partial.append(c if not partial else partial[-1] * u0 + c)
            taylor.append(partial.pop())  # the remainder of the division by u − u0
            remaining = partial
        coeffs = tuple(factor(F.normal(c)) for c in reversed(taylor))
        if len(coeffs) != 4:
            raise DerivationError(f"expected a cubic f(u0 + w), got coefficients {coeffs}")
        return coeffs

    @derived
    def precession_fractions_shifted(self) -> dict:
        """φ̇ (3.74) along u = u0 + w1 + (w2 − w1) sn² as c0 + Σ c_i / (1 − n_i sn²), in the shifted symbols.

        Each linear factor (u − r) of φ̇'s denominator is written (u0 − r) + w with u0 − r a symbol
        (``d_pole`` for r = 1, ``d_bottom`` for r = −1: −2 sin²(θ0/2) and 2 cos²(θ0/2), exact at the
        poles), and the numerator's constant term in w, its value at u0, a symbol ``rate0`` (φ̇0 times
        the denominator at u0, from the state).  Returns {"c0", "terms": [(c_i, n_i)], "args": symbols,
        "values": {symbol: its expression in the state}}; checked to reproduce φ̇ identically.
        """
        hm = heavy_model
        rate = hm.model().precession_rate_u
        num, den = sp.fraction(sp.together(rate))
        w, x = sp.symbols("w x_shift", real=True)
        w1, amp, rate0 = sp.symbols("w1 amp rate0", real=True)
        gaps = {}
        factored_den = sp.Integer(1)
        const, factors = sp.factor_list(den, hm.u)
        for fac, mult in factors:
            poly = sp.Poly(fac, hm.u)
            if poly.degree() != 1:
                raise DerivationError(f"expected linear factors of φ̇'s denominator in u, got {fac}")
            lead, tail = poly.all_coeffs()
            r = -tail / lead
            if r not in (1, -1):
                raise DerivationError(f"expected φ̇'s poles at u = ±1, got u = {r}")
            d = sp.Symbol("d_pole" if r == 1 else "d_bottom", real=True)
            gaps[d] = r
            factored_den *= (lead * (d + w)) ** mult
        num_w = sp.Poly(sp.expand(num.subs(hm.u, hm.u0 + w)), w)
        coeffs = num_w.all_coeffs()
        num_shift = sum(c * w ** k for k, c in enumerate(reversed(coeffs[:-1]), start=1)) + rate0
        c0, terms = _simple_poles(sp.together((num_shift / (const * factored_den)).subs(w, w1 + amp * x)), x)
        th = hm.theta
        cfs = hm.model().constants_from_state
        values = {rate0: factor(trig_normal(coeffs[-1].subs(hm.u0, sp.cos(th)).subs(cfs)))}
        for d, r in gaps.items():
            # cos θ0 − r in the half angle: −2 sin²(θ0/2) or 2 cos²(θ0/2), no cancellation at the poles
            half = -2 * sp.sin(th / 2) ** 2 if r == 1 else 2 * sp.cos(th / 2) ** 2
            if sp.simplify(sp.expand_trig(half.subs(th, 2 * sp.Symbol("h")) - (sp.cos(2 * sp.Symbol("h")) - r))) != 0:
                raise DerivationError(f"expected cos θ − {r} = {half}")
            values[d] = half
        args = [hm.I1, hm.I3, hm.a, rate0, *sorted(gaps, key=str), w1, amp]
        return {"c0": c0, "terms": terms, "args": args, "values": values}

    @derived
    def precession_fractions(self) -> dict:
        """φ̇ (3.74) along u(t) as c0 + Σ c_i / (1 - n_i sn²)."""
        return self._partial_fractions(heavy_model.model().precession_rate_u)

    @derived
    def spin_fractions(self) -> dict:
        """ψ̇ (3.75) along u(t) as c0 + Σ c_i / (1 - n_i sn²)."""
        return self._partial_fractions(heavy_model.model().spin_rate_u)


@functools.cache
def model() -> HeavyTopExactModel:
    """The process-wide heavy-top closed-form model."""
    return HeavyTopExactModel()
