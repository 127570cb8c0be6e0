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
from ...errors import DerivationError
from . import model as heavy_model

__all__ = ["HeavyTopExactModel", "model", "u1", "u2", "u3"]

u1, u2, u3 = sp.symbols("u1 u2 u3", real=True)
_kappa, _m = sp.symbols("kappa m", positive=True)
_x = sp.Symbol("x", nonnegative=True)  # sn²


def _is_zero_rational(expr: sp.Expr) -> bool:
    """Whether ``expr`` is identically 0: by :func:`sympy.cancel` (exact and fast for the rational functions of
    the roots and constants met here), else by :func:`sympy.simplify` (slow, for anything else)."""
    return sp.cancel(expr) == 0 or sp.simplify(expr) == 0


class HeavyTopExactModel(SymbolicModel):
    """Derived constants of u(t) and the partial fractions of φ̇ and ψ̇ along it."""

    @derived
    def cubic_in_roots(self) -> sp.Expr:
        """f(u) = c3 (u - u1)(u - u2)(u - u3), with c3 f's leading coefficient (which must be β)."""
        c3 = heavy_model.model().f_coefficients[0]
        if sp.simplify(c3 - heavy_model.beta) != 0:
            raise DerivationError(f"expected f(u)'s leading coefficient β, got {c3}")
        u = heavy_model.u
        return c3 * (u - u1) * (u - u2) * (u - u3)

    @derived
    def nutation_constants(self) -> dict[str, sp.Expr]:
        """κ² and m of u = u1 + (u2 - u1) sn²(κ t + v0 | m), from u̇² = f(u) identically in sn²."""
        u = heavy_model.u
        sn, cn, dn = sp.symbols("sn cn dn", real=True)
        ansatz = u1 + (u2 - u1) * sn**2
        u_dot_sq = (2 * (u2 - u1) * sn * cn * dn * _kappa) ** 2
        residual = sp.expand((u_dot_sq - self.cubic_in_roots.subs(u, ansatz))
                             .subs({cn**2: 1 - sn**2, dn**2: 1 - _m * sn**2}))
        residual = sp.expand(residual.subs(sn, sp.sqrt(_x)))
        coeffs = sp.Poly(residual, _x).all_coeffs()
        sol = sp.solve([c for c in coeffs if c != 0], [_kappa, _m], dict=True)
        if len(sol) != 1:
            raise DerivationError(f"expected one (κ, m) for the nutation ansatz, got {sol}")
        kappa_sq = sp.factor(sol[0][_kappa] ** 2)
        m = sp.factor(sol[0][_m])
        return {"kappa2": kappa_sq, "m": m, "m1": sp.factor(1 - m)}

    def _partial_fractions(self, rate_u: sp.Expr) -> dict:
        """rate(u) along the ansatz as c0 + Σ c_i/(1 - n_i x), x = sn²; returns {"c0": .., "terms": [(c_i, n_i)]}."""
        u = heavy_model.u
        along = sp.together(rate_u.subs(u, u1 + (u2 - u1) * _x))
        parts = sp.apart(along, _x, full=False)
        c0 = sp.Integer(0)
        terms = []
        for term in sp.Add.make_args(sp.expand(parts)):
            num, den = sp.fraction(sp.factor(term))
            if not den.has(_x):
                c0 += term
                continue
            poly = sp.Poly(den, _x)
            if poly.degree() != 1:
                raise DerivationError(f"expected simple poles in sn², got denominator {den}")
            d1, d0 = poly.all_coeffs()
            if num.has(_x):
                raise DerivationError(f"expected a constant numerator, got {num}")
            c, n = num / d0, sp.factor(-d1 / d0)
            for k, (c_old, n_old) in enumerate(terms):
                if _is_zero_rational(n - n_old):  # same pole: merge the numerators
                    terms[k] = (c_old + c, n_old)
                    break
            else:
                terms.append((c, n))
        terms = [(sp.factor(c), n) for c, n in terms]
        # Check: the decomposition reproduces the rate identically in x.
        rebuilt = c0 + sum(c / (1 - n * _x) for c, n in terms)
        if not _is_zero_rational(sp.together(rebuilt - along)):
            raise DerivationError("partial fractions do not reproduce the rate")
        return {"c0": sp.factor(c0), "terms": terms}

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
