"""Symbolic derivation of the free asymmetric top's exact solution (sections 3.4.3–3.4.4, 3.5).

Body axes are relabelled (x, y, z) — a proper (det +1) signed permutation of
(1, 2, 3) — so that y is the intermediate axis and z the axis about which ω
circulates (the one whose component never vanishes).  In those axes Euler's
equations keep their cyclic form, and the derivation below finds, from the
ansatz

    ω_x = P cn(u | m),  ω_y = Q sn(u | m),  ω_z = S dn(u | m),  u = λ t + u0,

the amplitudes, rate and parameter in terms of 2T and L² (3.46)–(3.47):

* substituting the ansatz (with sn' = cn dn, cn' = -sn dn, dn' = -m sn cn) into
  the *derived* Euler equations gives three algebraic relations;
* 2T and L² must not depend on sn² — two more;
* SymPy solves them for P², S², λ², Q², m and verifies the ansatz identically.

For the orientation, L is put along the third axis of an inertial "L frame";
then L_body = |L| (sin θ sin ψ, sin θ cos ψ, cos θ) (column 3 of R, (3.57)), and
solving (3.58) for the Euler-angle rates gives φ̇ as a rational function of
sn², which SymPy splits into partial fractions

    φ̇ = c1 + c2 / (1 - n sn²(u | m)),

integrated exactly by the incomplete elliptic integral of the third kind.
"""

from __future__ import annotations

import functools

import sympy as sp

from ...core.model import SymbolicModel, derived
from ...core.symbols import state_symbol
from ...errors import DerivationError
from ...kinematics import euler
from . import model as free_top_model

__all__ = ["FreeTopExactModel", "model", "Ix", "Iy", "Iz", "E2", "L2", "L", "gaps"]

Ix, Iy, Iz = sp.symbols("I_x I_y I_z", positive=True)
E2, L2, L = sp.symbols("E2 L2 L", positive=True)  # 2T, L², |L|
#: G_k = 2T·I_k - L² = Σ_a I_a ω_a² (I_k - I_a) for k = x, y, z: the "gaps" every constant factors into
gaps = sp.symbols("G_x G_y G_z", real=True)
_P, _Q, _S, _lam, _m = sp.symbols("P Q S lambda m", real=True)
_sn, _cn, _dn = sp.symbols("sn cn dn", real=True)


class FreeTopExactModel(SymbolicModel):
    """Derived constants of the elliptic-function solution and of the precession angle."""

    @derived
    def ansatz_residuals(self) -> list[sp.Expr]:
        """Euler's equations with the ansatz substituted, divided by their common sn/cn/dn factor."""
        fm = free_top_model.model()
        w = free_top_model.omega_symbols()
        rhs = fm.euler_rhs.subs({free_top_model.I1: Ix, free_top_model.I2: Iy, free_top_model.I3: Iz})
        rhs = rhs.subs({tau: 0 for tau in free_top_model.tau_symbols})
        ansatz = {w[0]: _P * _cn, w[1]: _Q * _sn, w[2]: _S * _dn}
        rates = _lam * sp.Matrix([-_P * _sn * _dn, _Q * _cn * _dn, -_m * _S * _sn * _cn])
        res = (rates - rhs.subs(ansatz)).applyfunc(sp.expand)
        factors = [_sn * _dn, _cn * _dn, _sn * _cn]
        out = [sp.expand(res[i] / factors[i]) for i in range(3)]
        for e in out:
            if e.free_symbols & {_sn, _cn, _dn}:
                raise DerivationError(f"ansatz residual still depends on sn, cn, dn: {e}")
        return out

    @derived
    def constants(self) -> dict[str, sp.Expr]:
        """P², S², λ², Q², m and 1 - m as functions of I_x, I_y, I_z, 2T (``E2``) and L² (``L2``).

        Also ``Q`` itself in terms of P, S and λ (the sign of Q follows from theirs).
        """
        quad = {_cn**2: 1 - _sn**2, _dn**2: 1 - _m * _sn**2}
        two_T = sp.Poly(sp.expand((Ix * (_P * _cn) ** 2 + Iy * (_Q * _sn) ** 2 + Iz * (_S * _dn) ** 2).subs(quad)), _sn)
        L_sq = sp.Poly(sp.expand((Ix**2 * (_P * _cn) ** 2 + Iy**2 * (_Q * _sn) ** 2
                                  + Iz**2 * (_S * _dn) ** 2).subs(quad)), _sn)
        p2, s2 = sp.symbols("p2 s2")
        sol = sp.solve([two_T.coeff_monomial(1).subs({_P**2: p2, _S**2: s2}) - E2,
                        L_sq.coeff_monomial(1).subs({_P**2: p2, _S**2: s2}) - L2], [p2, s2], dict=True)[0]
        e1, e2, e3 = self.ansatz_residuals
        # The first two relations each give λ; their product eliminates P and Q.
        lam_a, lam_b = sp.solve(e1, _lam), sp.solve(e2, _lam)
        if len(lam_a) != 1 or len(lam_b) != 1:
            raise DerivationError(f"expected λ linear in each relation, got {lam_a}, {lam_b}")
        lam_sq = sp.factor(sp.cancel(lam_a[0] * lam_b[0]).subs(_S**2, sol[s2]))
        if lam_sq.free_symbols & {_P, _Q, _S}:
            raise DerivationError(f"λ² should depend on the conserved quantities only, got {lam_sq}")
        # Q from the second relation, m from the third: both only through squares.
        q_expr = sp.solve(e2, _Q)[0]
        q_sq = sp.factor(sp.expand(q_expr**2).subs({_P**2: sol[p2], _S**2: sol[s2], _lam**2: lam_sq}))
        m_expr = sp.cancel(sp.solve(e3, _m)[0].subs(_Q, q_expr))
        m_expr = sp.factor(sp.expand(m_expr).subs({_P**2: sol[p2], _lam**2: lam_sq}))
        m1_expr = sp.factor(1 - m_expr)
        out = {"P2": sp.factor(sol[p2]), "S2": sp.factor(sol[s2]), "lambda2": lam_sq, "Q2": q_sq,
               "m": m_expr, "m1": m1_expr, "Q": q_expr}
        self._verify(out)
        return out

    @staticmethod
    def _verify(c: dict[str, sp.Expr]) -> None:
        """The ansatz must satisfy every relation identically once the constants are inserted.

        The relations are written in the squared constants only (signs are fixed
        numerically from the initial condition), so each check is a rational
        identity in I_x, I_y, I_z, 2T and L², decided by ``cancel``.
        """
        p2, q2, s2, l2, m = c["P2"], c["Q2"], c["S2"], c["lambda2"], c["m"]
        relations = {
            "(λ P I_x)² = ((I_z - I_y) Q S)²": l2 * p2 * Ix**2 - (Iz - Iy) ** 2 * q2 * s2,
            "(λ Q I_y)² = ((I_z - I_x) S P)²": l2 * q2 * Iy**2 - (Iz - Ix) ** 2 * s2 * p2,
            "(λ m S I_z)² = ((I_y - I_x) P Q)²": l2 * m**2 * s2 * Iz**2 - (Iy - Ix) ** 2 * p2 * q2,
            "2T has no sn² term": -Ix * p2 + Iy * q2 - Iz * s2 * m,
            "L² has no sn² term": -(Ix**2) * p2 + Iy**2 * q2 - Iz**2 * s2 * m,
            "2T at sn = 0": Ix * p2 + Iz * s2 - E2,
            "L² at sn = 0": Ix**2 * p2 + Iz**2 * s2 - L2,
        }
        for name, expr in relations.items():
            if sp.cancel(sp.together(expr)) != 0:
                raise DerivationError(f"elliptic ansatz fails {name}")

    @derived
    def gap_constants(self) -> dict[str, sp.Expr]:
        """P², S², λ², Q², m and 1 - m as functions of I_x, I_y, I_z and the gaps G_k = 2T·I_k - L².

        Each constant of :attr:`constants` factors into moments, moment differences and
        factors linear in 2T and L²; every such factor is α·2T + β·L² = -β·G_k with
        I_k = -α/β, and is replaced by -β·G_k.  The point is numerical: G_k = Σ_a I_a ω_a² (I_k - I_a)
        is an exact sum of products of the (binary) inputs, so it can be formed without the
        cancellation of 2T·I_k - L² (which loses everything near a principal axis and
        decides the separatrix, G_y = 0).  Checked: substituting G_k back gives the constants.
        """
        out = {}
        moments = {Ix: gaps[0], Iy: gaps[1], Iz: gaps[2]}

        def replace_factor(f: sp.Expr) -> sp.Expr:
            if not f.free_symbols & {E2, L2}:
                return f
            poly = sp.Poly(f, E2, L2)
            if poly.total_degree() != 1 or poly.coeff_monomial(1) != 0:
                raise DerivationError(f"expected a factor linear and homogeneous in 2T and L², got {f}")
            alpha, beta = poly.coeff_monomial(E2), poly.coeff_monomial(L2)
            moment = sp.cancel(-alpha / beta)
            if moment not in moments:
                raise DerivationError(f"expected a factor 2T·I_k - L², got {f}")
            return -beta * moments[moment]

        def replace_factors(product: sp.Expr) -> sp.Expr:
            return sp.Mul(*[replace_factor(base) ** e for base, e in
                            (arg.as_base_exp() for arg in sp.Mul.make_args(product))])

        for name in ("P2", "S2", "lambda2", "Q2", "m", "m1"):
            expr = self.constants[name]
            num, den = sp.fraction(sp.factor(expr))
            new = replace_factors(num) / replace_factors(den)
            back = new.subs({gaps[0]: E2 * Ix - L2, gaps[1]: E2 * Iy - L2, gaps[2]: E2 * Iz - L2})
            if sp.cancel(back - expr) != 0:
                raise DerivationError(f"gap form of {name} does not reproduce it: {new}")
            out[name] = new
        return out

    @derived
    def precession_rate(self) -> sp.Expr:
        """φ̇ in terms of the body angular velocity, for L along the L frame's third axis.

        Derived by solving (3.58) for (φ̇, θ̇, ψ̇) and inserting L_body = |L|·(column 3 of R).
        """
        km = euler.model()
        names = ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")
        phi, theta, psi, phid, thetad, psid = (state_symbol(n) for n in names)
        w = free_top_model.omega_symbols()
        omega = km.state_angular_velocity_body
        rates = sp.solve([omega[a] - w[a] for a in range(3)], [phid, thetad, psid], dict=True)[0]
        Lb = sp.symbols("L_1 L_2 L_3", real=True)
        # L_body = |L| (sin θ sin ψ, sin θ cos ψ, cos θ): eliminate ψ and θ in favour of L_1, L_2, L_3.
        sin_t = sp.sqrt(Lb[0] ** 2 + Lb[1] ** 2) / L
        expr = rates[phid].subs({sp.sin(psi): Lb[0] / (L * sin_t), sp.cos(psi): Lb[1] / (L * sin_t)})
        expr = sp.simplify(expr.subs(sp.sin(theta), sin_t))
        return expr.subs({Lb[0]: Ix * w[0], Lb[1]: Iy * w[1], Lb[2]: Iz * w[2]})

    @derived
    def precession_partial_fractions(self) -> dict[str, sp.Expr]:
        """φ̇ = c1 + c2 / (1 - n sn²) along the elliptic solution: c1, c2 and n (characteristic)."""
        c = self.constants
        w = free_top_model.omega_symbols()
        x = sp.Symbol("x", nonnegative=True)  # sn²
        rate = self.precession_rate.subs({w[0]: _P * _cn, w[1]: _Q * _sn, w[2]: _S * _dn})
        rate = sp.together(sp.expand(rate))
        num, den = sp.fraction(rate)
        # Only squares of the amplitudes and of sn, cn appear (ω_x², ω_y²); write cn² = 1 - x, sn² = x.
        num = sp.expand(num).subs({_cn**2: 1 - x, _sn**2: x})
        den = sp.expand(den).subs({_cn**2: 1 - x, _sn**2: x})
        num = sp.expand(num.subs({_P**2: c["P2"], _Q**2: c["Q2"]}))
        den = sp.expand(den.subs({_P**2: c["P2"], _Q**2: c["Q2"]}))
        nd, dd = sp.Poly(num, x), sp.Poly(den, x)
        if nd.degree() != 1 or dd.degree() != 1:
            raise DerivationError(f"expected φ̇ linear/linear in sn², got degrees {nd.degree()}, {dd.degree()}")
        n1, n0 = nd.all_coeffs()
        d1, d0 = dd.all_coeffs()
        c1 = sp.factor(sp.simplify(n1 / d1))
        c2 = sp.factor(sp.simplify((n0 - n1 * d0 / d1) / d0))
        n_char = sp.factor(sp.simplify(-d1 / d0))
        # Check: c1 + c2/(1 - n x) reproduces num/den identically in x.
        if sp.simplify(sp.together(c1 + c2 / (1 - n_char * x) - num / den)) != 0:
            raise DerivationError("partial fractions of φ̇ do not reproduce it")
        return {"c1": c1, "c2": c2, "n": n_char}


@functools.cache
def model() -> FreeTopExactModel:
    """The process-wide exact-solution model."""
    return FreeTopExactModel()
