"""Why the rotation is a *path-ordered* exponential: the derivations of section 3.1.2, (3.11)–(3.16).

Everything here is derived by SymPy from the equation of motion (3.11), Ṙ = ωR,
with ω_ab = ε_abc ω_c (body components ω_c), and from the definition (3.13) of exp.
The chapter's printed formulas are only compared with these derivations, in
:mod:`mechderive.catalog.s3_1_path_ordered`.

Two angular velocities are used:

* a *generic* one, ω_c = w_c(t) with undefined functions w_c, for identities that
  hold for every ω ((3.14), and the failure of (3.12));
* a *polynomial* test one (default w = (1, 2t, 3t² − 1), whose values at different
  times do not commute), for which every integral of the Dyson series (3.16) is
  done exactly.

To expose the order of the non-commuting products, the amplitude is scaled,
ω → εω: the solution is then a power series R = Σ εⁿ Dₙ whose coefficients follow
from (3.11) by matching powers of ε — the Picard iteration Ḋₙ = ω Dₙ₋₁, Dₙ(0) = 0.
D₂ is the path-ordered double integral of (3.16).
"""

from __future__ import annotations

import functools

import sympy as sp

from ..core.model import SymbolicModel, derived
from ..core.symbols import state_symbol, t

__all__ = ["DysonModel", "model", "so3_matrix", "TEST_ANGULAR_VELOCITY"]

#: Integration variables of (3.16): t' (earlier) and t'' (later).
t1 = sp.Symbol("t'", real=True)
t2 = sp.Symbol("t''", real=True)
#: The amplitude ε that counts powers of ω.
eps = state_symbol("epsilon")


def so3_matrix(w: sp.Matrix) -> sp.Matrix:
    """The antisymmetric matrix ω_ab = ε_abc ω_c of the body components ``w`` (section 3.1.2).

    >>> so3_matrix(sp.Matrix([0, 0, 1]))
    Matrix([
    [ 0, 1, 0],
    [-1, 0, 0],
    [ 0, 0, 0]])
    """
    return sp.Matrix(3, 3, lambda a, b: sum(sp.LeviCivita(a + 1, b + 1, c + 1) * w[c] for c in range(3)))


#: The polynomial test angular velocity (body components, rad/s), a function of t.
TEST_ANGULAR_VELOCITY = sp.Matrix([1, 2 * t, 3 * t**2 - 1])


def _integrate(m: sp.Matrix, var: sp.Symbol, lo: sp.Expr, hi: sp.Expr) -> sp.Matrix:
    return m.applyfunc(lambda e: sp.integrate(sp.expand(e), (var, lo, hi)))


class DysonModel(SymbolicModel):
    """Derivations behind (3.12)–(3.16), lazily computed and logged."""

    def __init__(self, test_angular_velocity: sp.Matrix = TEST_ANGULAR_VELOCITY) -> None:
        super().__init__()
        self.test_w = sp.Matrix(test_angular_velocity)

    # ---------------------------------------------------------------- generic ω
    @derived
    def generic_components(self) -> sp.Matrix:
        """Body components w_c(t), undefined functions of t."""
        return sp.Matrix([sp.Function(f"w{c}", real=True)(t) for c in (1, 2, 3)])

    @derived
    def generic_omega(self) -> sp.Matrix:
        """ω(t), ω_ab = ε_abc w_c(t)."""
        return so3_matrix(self.generic_components)

    @derived
    def generic_integral(self) -> sp.Matrix:
        """M(t) = ∫_0^t ω(t') dt', the exponent of the naive guess (3.12), as unevaluated integrals.

        ω ↦ ω_ab is linear, so M_ab = ε_abc ∫ w_c: one integral per component, keeping
        signs outside the integrals so that identities reduce to polynomial ones in them.
        """
        comps = self.generic_components.subs(t, t1)
        return so3_matrix(comps.applyfunc(lambda e: sp.Integral(e, (t1, 0, t))))

    @derived
    def half_square_derivative(self) -> sp.Matrix:
        """d/dt (½ M²), the left side of (3.14), by the product and Leibniz rules."""
        M = self.generic_integral
        return (M * M / 2).diff(t)

    @derived
    def naive_residual(self) -> sp.Matrix:
        """The ε² coefficient of d/dt exp(εM) − εω exp(εM): how far (3.12) misses (3.11).

        exp is the series (3.13); its terms beyond ½(εM)² are O(ε³) and cannot contribute.
        """
        M, w = self.generic_integral, self.generic_omega
        naive = sp.eye(3) + eps * M + eps**2 * M * M / 2
        residual = (naive.diff(t) - eps * w * naive).applyfunc(sp.expand)
        return residual.applyfunc(lambda e: e.coeff(eps, 2))

    # ---------------------------------------------------------------- polynomial test ω
    @derived
    def test_omega(self) -> sp.Matrix:
        """ω(t) of the polynomial test angular velocity."""
        return so3_matrix(self.test_w)

    @derived
    def dyson_terms(self) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix]:
        """D₀, D₁, D₂ of R = Σ εⁿ Dₙ for Ṙ = εωR, R(0) = 1, from Dₙ(t) = ∫_0^t ω(s) Dₙ₋₁(s) ds.

        Matching powers of ε in (3.11) — no ordering is assumed, it comes out of the ODE.
        """
        w_s = self.test_omega.subs(t, t1)
        D0 = sp.eye(3)
        D1 = _integrate(w_s * D0, t1, 0, t)
        D2 = _integrate(w_s * D1.subs(t, t1), t1, 0, t)
        return D0, D1, D2

    @derived
    def second_order_solution(self) -> sp.Matrix:
        """D₀ + ε D₁ + ε² D₂: the solution of Ṙ = εωR to O(ε³)."""
        D0, D1, D2 = self.dyson_terms
        return (D0 + eps * D1 + eps**2 * D2).applyfunc(sp.expand)


@functools.cache
def model() -> DysonModel:
    """The process-wide Dyson-series model (its derivations are shared)."""
    return DysonModel()
