"""The body-independent derivations of section 3.7: (3.86), (3.90)–(3.97) and (3.100)–(3.103).

Convention of section 3.7 (kept in this package)
------------------------------------------------
Positions are column vectors; the configuration is r_i = R r̃_i (3.84)–(3.85): R
*acts* on the representative shape r̃_i (an active rotation, body components →
space components).  Section 3.1's R, defined by e_a = R_ab ẽ_b, is the transpose:
R(3.1) = R(3.7)ᵀ.  The convective angular velocity is Ω = R⁻¹Ṙ (3.86), and
antisymmetric matrices are written with the toolkit's hat convention
hat(v)_ab = ε_abc v_c (:mod:`mechderive.kinematics.so3`), so Ω = hat(v) with
v_a = ½ ε_abc Ω_bc.

Everything below is derived by SymPy; nothing is typed in from the chapter (the
printed forms are only compared with these results, in
:mod:`mechderive.catalog.s3_7_deformable`):

1. (3.90) L = m r × ṙ of one point mass with r = R r̃, ṙ differentiated by SymPy,
   for *generic* 3×3 matrices R(t) (no orthogonality used) — also the form (3.91)
   and its ε-contraction (3.95);
2. with Ṙ = RΩ (3.86), Rᵀ L of a generic matrix R is det R times a polynomial free of R
   (an exact polynomial division), and det R = 1 for a rotation — a generic one, by the
   Cayley parametrisation R = (1 − A)⁻¹(1 + A), exact in rational arithmetic — so the
   body-frame momentum Rᵀ L is m r̃ × (r̃̇ + Ω r̃), independent of R;
3. its Ω-independent part is the apparent angular momentum L̃ (3.94), and minus its
   Jacobian with respect to v (Ω = hat(v)) is the inertia of the mass (3.93) —
   checked equal to the inertia module's (3.19);
4. both parts are linear in the masses, so for any number of masses
   Rᵀ L = L̃ − Ĩ v; L = 0 is solved for v with a general symmetric Ĩ: v = Ĩ⁻¹ L̃,
   Ω = hat(v) (3.92), and conversely, on L = 0, L̃ = Ĩ vee(Ω) (3.96)–(3.97);
5. (3.102): the right-ordered (later times on the right, (3.98)) Dyson series of
   Ω = Ω_A(x⁰ + εα) ε α̇^A expanded to O(ε²) with non-commuting symbols for Ω_A(x⁰) and
   ∂Ω_A/∂x^B; the coefficient of ½ ∮ α_A α̇_B dt is the field strength F_AB.

Step 5 gives F_AB = ∂Ω_B/∂x^A − ∂Ω_A/∂x^B + [Ω_A, Ω_B]; the chapter's (3.103) prints
the derivative terms the other way round (see the catalog).

>>> from mechderive.inertia.tensor import general_inertia_symbols
>>> d = model()
>>> v = general_inertia_symbols().inv() * apparent_momentum_symbols()      # Ĩ⁻¹ L̃
>>> sp.simplify(d.angular_velocity_solution - hat(v)) == sp.zeros(3, 3)    # Ω = hat(Ĩ⁻¹ L̃)
True
"""

from __future__ import annotations

import functools
from typing import Any, Mapping, Sequence

import sympy as sp
from sympy.polys.rings import PolyRing

from ...core.model import SymbolicModel, derived
from ...core.symbols import coordinate, state_symbol, t, to_state_symbols
from ...errors import DerivationError
from ...inertia.tensor import general_inertia_symbols, point_mass_tensor

__all__ = [
    "ConnectionDerivation",
    "model",
    "hat",
    "vee",
    "cayley_rotation",
    "cayley_parts",
    "generic_antisymmetric",
    "apparent_momentum_symbols",
    "evaluate_noncommutative",
]


def hat(v: Sequence[Any]) -> sp.Matrix:
    """The antisymmetric matrix hat(v)_ab = ε_abc v_c (the toolkit's so(3) convention).

    >>> hat([0, 0, 1])
    Matrix([
    [ 0, 1, 0],
    [-1, 0, 0],
    [ 0, 0, 0]])
    """
    w = list(v)
    return sp.Matrix(3, 3, lambda a, b: sum(sp.LeviCivita(a + 1, b + 1, c + 1) * w[c] for c in range(3)))


def vee(m: sp.Matrix) -> sp.Matrix:
    """v_a = ½ ε_abc m_bc, the inverse of :func:`hat` on antisymmetric matrices.

    >>> vee(hat([1, 2, 3])).T
    Matrix([[1, 2, 3]])
    """
    return sp.Matrix([sp.Rational(1, 2) * sum(sp.LeviCivita(a + 1, b + 1, c + 1) * m[b, c]
                                               for b in range(3) for c in range(3)) for a in range(3)])


def cayley_rotation(c: Sequence[Any]) -> sp.Matrix:
    """The rotation (1 − A)⁻¹(1 + A), A = hat(c): every rotation except the half turns, rational in c."""
    numerator, denominator = cayley_parts(c)
    return (numerator / denominator).applyfunc(sp.cancel)


def cayley_parts(c: Sequence[Any]) -> tuple[sp.Matrix, sp.Expr]:
    """(N, d) with :func:`cayley_rotation` = N/d: N = adj(1 − A)(1 + A) polynomial, d = det(1 − A) = 1 + c·c.

    >>> N, d = cayley_parts(sp.symbols("c1:4"))
    >>> d
    c1**2 + c2**2 + c3**2 + 1
    """
    A = hat(c)
    one_minus = sp.eye(3) - A
    return (one_minus.adjugate() * (sp.eye(3) + A)).applyfunc(sp.expand), sp.expand(one_minus.det())


@functools.cache
def generic_antisymmetric() -> sp.Matrix:
    """Ω = [[0, Ω12, Ω13], [−Ω12, 0, Ω23], [−Ω13, −Ω23, 0]] in the symbols ``Omega12 Omega13 Omega23``."""
    o12, o13, o23 = sp.symbols("Omega12 Omega13 Omega23", real=True)
    return sp.Matrix([[0, o12, o13], [-o12, 0, o23], [-o13, -o23, 0]])


@functools.cache
def apparent_momentum_symbols() -> sp.Matrix:
    """General components (L̃1, L̃2, L̃3) of the apparent angular momentum, symbols ``Ltilde1..3``."""
    return sp.Matrix(sp.symbols("Ltilde1:4", real=True))


def _require_zero(m: Any, what: str, *, rational: bool = False) -> None:
    exprs = list(m) if isinstance(m, sp.MatrixBase) else [m]
    for e in exprs:
        e = sp.cancel(sp.together(e)) if rational else sp.expand(e)
        if e != 0:
            raise DerivationError(f"expected {what} to vanish identically, got {e}")


def _state_form(m: sp.Matrix) -> sp.Matrix:
    """:func:`~mechderive.core.symbols.to_state_symbols` of ``m`` whose functions of t are q(t) and q'(t) only.

    Then the substitution q'(t) → q_dot, q(t) → q is one ``xreplace`` (whole subtrees matched, so q(t)
    inside q'(t) is never replaced first) — ~5× faster than ``subs``; anything else goes to
    ``to_state_symbols``.
    """
    undefined = sp.core.function.AppliedUndef
    derivatives, functions = m.atoms(sp.Derivative), m.atoms(undefined)
    if not all(isinstance(d.expr, undefined) and d.variables == (t,) and d.expr.args == (t,) for d in derivatives) \
            or not all(f.args == (t,) for f in functions):
        return to_state_symbols(m)
    subs = {d: state_symbol(d.expr.func.__name__ + "_dot") for d in derivatives}
    subs.update((f, state_symbol(f.func.__name__)) for f in functions)
    return m.xreplace(subs)


def evaluate_noncommutative(expr: sp.Expr, values: Mapping[sp.Symbol, sp.Matrix]) -> sp.Matrix:
    """Evaluate a polynomial in non-commuting symbols by substituting matrices (products kept in order).

    >>> P = sp.symbols("P Q", commutative=False)
    >>> evaluate_noncommutative(P[0] * P[1] - P[1] * P[0], {P[0]: hat([1, 0, 0]), P[1]: hat([0, 1, 0])}) == hat([0, 0, -1])
    True
    """
    expr = sp.expand(expr)
    size = next(iter(values.values())).shape[0]
    total = sp.zeros(size, size)
    for term in sp.Add.make_args(expr):
        coeff, factors = term.args_cnc()
        product = sp.eye(size)
        for f in factors:
            base, power = (f.base, int(f.exp)) if isinstance(f, sp.Pow) else (f, 1)
            if base not in values:
                raise DerivationError(f"expected a value for the non-commuting symbol {base}, got none")
            for _ in range(power):
                product = product * values[base]
        total += sp.Mul(*coeff) * product
    return total


class ConnectionDerivation(SymbolicModel):
    """The derivations 1–5 of the module docstring, each lazily, for one generic point mass.

    Symbols: the mass ``m``; the shape components r̃_a(t) (``rtilde1..3`` and
    ``rtilde1_dot..`` in state form); generic matrices R(t) with entries ``R11..R33``;
    Ω12, Ω13, Ω23; the general symmetric Ĩ (``I11 .. I33``) and L̃ (``Ltilde1..3``).
    """

    def __init__(self) -> None:
        super().__init__()
        self.mass = sp.Symbol("m", positive=True)
        self.shape = sp.Matrix([coordinate(f"rtilde{a}") for a in (1, 2, 3)])
        self.matrix = sp.Matrix(3, 3, lambda a, b: coordinate(f"R{a + 1}{b + 1}"))
        self.cayley = sp.symbols("c1:4", real=True)

    # ---------------------------------------------------------------- (3.90), (3.91), (3.95)
    @derived
    def space_angular_momentum(self) -> sp.Matrix:
        """(3.90) for one mass: L = m r × ṙ with r = R r̃ and ṙ = d(R r̃)/dt, generic matrices R(t).

        In state symbols: ``R11 .. R33``, ``R11_dot ..``, ``rtilde1 ..``, ``rtilde1_dot ..``.
        """
        r = self.matrix * self.shape
        # r and ṙ put in state symbols before the cross product: the same result (a substitution commutes
        # with products), with fewer terms to walk
        return (self.mass * _state_form(r).cross(_state_form(r.diff(t)))).applyfunc(sp.expand)

    @derived
    def epsilon_contracted_momentum(self) -> list[list[sp.Expr]]:
        """(3.95): ε_afg L_a for f, g = 1..3 (a 3×3 nested list), from :attr:`space_angular_momentum`."""
        L = self.space_angular_momentum
        return [[sp.expand(sum(sp.LeviCivita(a + 1, f + 1, g + 1) * L[a] for a in range(3))) for g in range(3)]
                for f in range(3)]

    # ---------------------------------------------------------------- rotation, Ṙ = RΩ (3.86)
    @derived
    def rotation(self) -> sp.Matrix:
        """A generic rotation: the Cayley matrix of (c1, c2, c3); checked RᵀR = 1 and det R = 1."""
        # In polynomials: R = N/d, so RᵀR = 1 and det R = 1 are NᵀN = d²·1 and det N = d³.
        N, d = cayley_parts(self.cayley)
        _require_zero(N.T * N - d**2 * sp.eye(3), "NᵀN − d²·1 of the Cayley matrix N/d")
        _require_zero(N.det(method="berkowitz") - d**3, "det N − d³ of the Cayley matrix N/d")
        return (N / d).applyfunc(sp.cancel)

    def _on_rotation(self, expr: Any, R: sp.Matrix) -> Any:
        """Substitute R → ``R`` and Ṙ → RΩ (the definition (3.86) of Ω) in ``expr``.

        The keys are symbols, so the simultaneous substitution is an ``xreplace``.
        """
        Rdot = R * generic_antisymmetric()
        subs = {}
        for a in range(3):
            for b in range(3):
                subs[state_symbol(f"R{a + 1}{b + 1}")] = R[a, b]
                subs[state_symbol(f"R{a + 1}{b + 1}_dot")] = Rdot[a, b]
        return expr.xreplace(subs)

    @derived
    def body_frame_momentum(self) -> sp.Matrix:
        """R⁻¹ L = Rᵀ L for a rotation R with Ṙ = RΩ: derived, and checked free of R.

        For a *generic* matrix R (nine symbols, no orthogonality used) with Ṙ = RΩ, Rᵀ L is a
        polynomial of degree 3 in the entries of R; it is divided exactly by det R (the remainder
        must vanish and the quotient must be free of R).  For a rotation det R = 1
        (:attr:`rotation` checks it on the generic Cayley rotation), so the quotient is Rᵀ L.
        (Dividing in the Cayley parameters instead gives the same quotient at 10× the cost.)
        """
        _ = self.rotation  # det R = 1 for every rotation: what makes the quotient R⁻¹L
        entries = [state_symbol(f"R{a}{b}") for a in (1, 2, 3) for b in (1, 2, 3)]
        R = sp.Matrix(3, 3, entries)
        top = R.T * self._on_rotation(self.space_angular_momentum, R)
        # In the ring ℚ[R11 … R33, the other symbols] (sympy.polys.rings): the products are expanded and the
        # division done on sparse polynomials, ~15× faster than expanding SymPy products and dividing Polys.
        # The quotient of an exact division is unique, so it does not depend on how it is computed.
        others = sorted(set().union(*(e.free_symbols for e in top)) - set(entries), key=sp.default_sort_key)
        ring = PolyRing([*entries, *others], sp.QQ)
        det = ring.from_expr(R.det())
        body = []
        for e in top:
            (q,), r = ring.from_expr(e).div([det])
            if r or any(any(m[:9]) for m in q.keys()):
                raise DerivationError(f"expected R⁻¹L to be independent of the orientation, got remainder {r.as_expr()}")
            body.append(q.as_expr())
        return sp.Matrix(body)

    @derived
    def apparent_angular_momentum(self) -> sp.Matrix:
        """L̃ (3.94) of one mass: the part of R⁻¹L that remains when Ω = 0 (a constant orientation)."""
        zero = {s: 0 for s in generic_antisymmetric().free_symbols}
        return self.body_frame_momentum.subs(zero).applyfunc(sp.expand)

    @derived
    def rotation_vector(self) -> sp.Matrix:
        """v with Ω = hat(v): (Ω23, −Ω13, Ω12), i.e. v_a = ½ ε_abc Ω_bc."""
        return vee(generic_antisymmetric())

    @derived
    def inertia_per_mass(self) -> sp.Matrix:
        """Ĩ (3.93) of one mass: −∂(R⁻¹L)/∂v, checked equal to (3.19) of :mod:`mechderive.inertia.tensor`."""
        W = generic_antisymmetric()
        v = sp.Matrix(sp.symbols("v1:4", real=True))
        body = self.body_frame_momentum.xreplace({W[1, 2]: v[0], W[0, 2]: -v[1], W[0, 1]: v[2]})  # symbols: simultaneous
        I = -body.jacobian(v)
        shape = to_state_symbols(self.shape)
        _require_zero(I - point_mass_tensor(self.mass, shape), "−∂(R⁻¹L)/∂v − (3.19)")
        _require_zero(body - self.apparent_angular_momentum + I * v, "R⁻¹L − (L̃ − Ĩ v)")  # exactly linear in v
        return I.applyfunc(sp.expand)

    # ---------------------------------------------------------------- (3.92), (3.96), (3.97)
    @derived
    def angular_velocity_solution(self) -> sp.Matrix:
        """Ω (3.92) solving L = 0, i.e. L̃ − Ĩ v = 0 (the sum of the per-mass laws), for a general Ĩ and L̃.

        The unknowns are the independent entries Ω12, Ω13, Ω23 of the antisymmetric Ω;
        the result is a rational function of ``I11 .. I33`` and ``Ltilde1..3``.
        """
        _ = self.inertia_per_mass  # establishes R⁻¹L = L̃ − Ĩ v for each mass, hence for a sum
        I, Lt, W = general_inertia_symbols(), apparent_momentum_symbols(), generic_antisymmetric()
        equations = list(Lt - I * vee(W))
        unknowns = [W[0, 1], W[0, 2], W[1, 2]]
        # linsolve: the linear system's solution set (a third of solve's time, the same solution)
        solutions = sp.linsolve(equations, unknowns)
        if not isinstance(solutions, sp.FiniteSet) or len(solutions) != 1:
            raise DerivationError(f"expected one solution of L = 0 for Ω, got {solutions}")
        (solution,) = solutions
        if set().union(*(e.free_symbols for e in solution)) & set(unknowns):
            raise DerivationError(f"expected one solution of L = 0 for Ω, got the family {solution}")
        return W.xreplace({w: sp.factor(e) for w, e in zip(unknowns, solution)})

    @derived
    def apparent_momentum_on_shell(self) -> sp.Matrix:
        """(3.97): on L = 0, L̃ expressed by Ĩ and a general antisymmetric Ω (solved from L̃ − Ĩ v = 0)."""
        _ = self.inertia_per_mass
        I, Lt, W = general_inertia_symbols(), apparent_momentum_symbols(), generic_antisymmetric()
        sol = sp.solve(list(Lt - I * vee(W)), list(Lt), dict=True)[0]
        return Lt.subs(sol).applyfunc(sp.expand)

    # ---------------------------------------------------------------- (3.100)–(3.103)
    @derived
    def small_loop_second_order(self) -> dict[tuple[int, int], sp.Expr]:
        """The O(ε²) term of P̃ exp ∮Ω (later times to the right) for a loop x = x⁰ + εα, n = 3.

        Returns {(A, B): c_AB} (A < B, 1-based) with the ε² term = Σ_{A<B} c_AB M_AB,
        M_AB = ∮ α_A α̇_B dt, c_AB a polynomial in the non-commuting symbols ``Omega_A``
        (Ω_A(x⁰)) and ``dOmega_A_B`` (∂Ω_A/∂x^B at x⁰).  See :meth:`field_strength_form`.
        """
        n = 3
        P = [sp.Symbol(f"Omega_{A}", commutative=False) for A in range(1, n + 1)]
        D = [[sp.Symbol(f"dOmega_{A}_{B}", commutative=False) for B in range(1, n + 1)] for A in range(1, n + 1)]
        T = sp.Symbol("T", positive=True)
        t1, t2 = sp.symbols("t1 t2", real=True)
        alpha = [sp.Function(f"alpha{A}", real=True) for A in range(1, n + 1)]
        eps = sp.Symbol("epsilon", positive=True)

        def omega(s: sp.Symbol) -> sp.Expr:  # (3.87) with (3.100)–(3.101), x = x⁰ + εα
            return sum(((P[A] + eps * sum(D[A][B] * alpha[B](s) for B in range(n))) * eps * alpha[A](s).diff(s)
                        for A in range(n)), sp.Integer(0))

        # P̃ ordering: R = 1 + ∫Ω + ∫_0^T dt2 ∫_0^{t2} dt1 Ω(t1) Ω(t2) + …, later time t2 on the right.
        closed = {alpha[A](T): alpha[A](0) for A in range(n)}
        # Every integral below is of a derivative (α̇_A, d(α_A α_B)/dt): manualintegrate's rule for
        # derivatives (the fundamental theorem) gives it directly; the default algorithms (heurisch, risch)
        # reach the same result ~50× slower.
        first_order = sp.integrate(sp.expand(omega(t2)).coeff(eps, 1), (t2, 0, T), manual=True).subs(closed)
        if sp.expand(first_order) != 0:
            raise DerivationError(f"expected the O(ε) term ∮Ω_A(x⁰) dα_A to vanish, got {first_order}")
        terms: dict[tuple, sp.Expr] = {}
        for expr, inner in ((sp.expand(omega(t2)), False), (sp.expand(omega(t1) * omega(t2)), True)):
            for term in sp.Add.make_args(expr):
                c, nc = term.args_cnc()
                integrand = sp.Mul(*c).coeff(eps, 2)
                if integrand == 0:
                    continue
                if inner:  # ∫_0^{t2} α̇_A(t1) dt1 = α_A(t2) − α_A(0)
                    integrand = sp.integrate(integrand, (t1, 0, t2), manual=True)
                terms[tuple(nc)] = terms.get(tuple(nc), 0) + integrand
        # The identities used below, on a closed loop (α(T) = α(0)): ∮ d(α_A α_B) = 0, so M_BA = −M_AB, M_AA = 0.
        for A in range(n):
            for B in range(A, n):
                product = alpha[A](t2) * alpha[B](t2)
                total = sp.integrate(sp.Derivative(product, t2), (t2, 0, T), manual=True).subs(closed)
                if sp.expand(total) != 0:
                    raise DerivationError(f"expected ∮ d(α_A α_B) = 0 on a closed loop, got {total}")
        # Each coefficient is ∫_0^T dt2 of a sum of α_A(t2) α̇_B(t2) and α_A(0) α̇_B(t2).
        M = {(A, B): sp.Symbol(f"M_{A + 1}{B + 1}") for A in range(n) for B in range(n)}
        result: dict[tuple[int, int], sp.Expr] = {}
        for key, integrand in terms.items():
            total = sp.Integer(0)
            for piece in sp.Add.make_args(sp.expand(integrand)):
                total += self._loop_integral(piece, alpha, t2, M)
            # M_AA = ½[α_A²] = 0 and M_BA = −M_AB (∮ d(α_A α_B) = 0 on a closed loop)
            total = total.subs({M[(A, A)]: 0 for A in range(n)})
            total = sp.expand(total.subs({M[(B, A)]: -M[(A, B)] for A in range(n) for B in range(A + 1, n)}))
            for A in range(n):
                for B in range(A + 1, n):
                    c = total.coeff(M[(A, B)])
                    if c != 0:
                        result[(A + 1, B + 1)] = result.get((A + 1, B + 1), 0) + c * sp.Mul(*key)
        return {k: sp.expand(v) for k, v in result.items()}

    @staticmethod
    def _loop_integral(piece: sp.Expr, alpha: list, s: sp.Symbol, M: dict) -> sp.Expr:
        """∮ of one integrand term: c α_A(s) α̇_B(s) → c M_AB; c α_A(0) α̇_B(s) → 0 (closed loop)."""
        coeff, value, rate = sp.Integer(1), None, None
        for f in sp.Mul.make_args(piece):
            if f.is_number:
                coeff *= f
            elif isinstance(f, sp.Derivative) and f.variables == (s,) and f.expr.func in alpha:
                rate = alpha.index(f.expr.func)
            elif f.func in alpha and f.args in ((s,), (0,)):
                value = (alpha.index(f.func), f.args[0])
            else:
                raise DerivationError(f"expected an integrand α_A α̇_B, got the factor {f} in {piece}")
        if value is None or rate is None:
            raise DerivationError(f"expected an integrand α_A α̇_B, got {piece}")
        if value[1] == 0:
            return sp.Integer(0)  # α_A(0) ∮ α̇_B = α_A(0)(α_B(T) − α_B(0)) = 0
        return coeff * M[(value[0], rate)]

    @derived
    def field_strength_form(self) -> dict[tuple[int, int], sp.Expr]:
        """F_AB (A < B) as a non-commuting polynomial: the ε² term of (3.102) is ½ Σ_{A,B} F_AB M_AB.

        Since M is antisymmetric, ½ Σ_{A,B} F_AB M_AB = Σ_{A<B} F_AB M_AB: F_AB = c_AB of
        :attr:`small_loop_second_order`.  The result is
        ``dOmega_B_A − dOmega_A_B + Omega_A Omega_B − Omega_B Omega_A``.
        """
        return dict(self.small_loop_second_order)


@functools.cache
def model() -> ConnectionDerivation:
    """The process-wide :class:`ConnectionDerivation`."""
    return ConnectionDerivation()
