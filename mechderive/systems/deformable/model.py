"""A deformable body of point masses: its gauge potential Ω_A and field strength F_AB, section 3.7.

Input (Python API only — no text is parsed): masses m_i and representative positions
r̃_i(x) (3.84) as SymPy expressions of the shape coordinates x^A (and of declared
parameter symbols), with the centre of mass at the origin for every shape.

Convention of section 3.7 (see :mod:`.derivation`): r_i = R r̃_i, R acting on
column vectors — the *active* rotation, the transpose of section 3.1's R
(e_a = R_ab ẽ_b, so R(3.1) = R(3.7)ᵀ); Ω = R⁻¹Ṙ (3.86); antisymmetric matrices in
the hat convention hat(v)_ab = ε_abc v_c.

Derived quantities (each lazily, logged in ``derived``):

- ``inertia_tensor``: Ĩ(x) (3.93), the sum of the per-mass −∂(R⁻¹L)/∂v;
- ``apparent_angular_momentum``: L̃(x, ẋ) (3.94), with r̃̇_i = (∂r̃_i/∂x^A) ẋ^A;
- ``angular_velocity``: Ω(x, ẋ) = hat(Ĩ⁻¹L̃) (3.92), the general solution of L = 0;
- ``connection``: Ω_A(x) = ∂Ω/∂ẋ^A (3.87), checked to make Ω linear in ẋ;
- ``field_strength``: F_AB(x) from the small-loop expansion (3.102), i.e.
  F_AB = ∂Ω_B/∂x^A − ∂Ω_A/∂x^B + [Ω_A, Ω_B] — the corrected (3.103);
- ``regauged(S)``: the same body with representatives S(x) r̃_i (3.88), whose
  connection is derived anew (the law (3.89) is only *checked*, in the catalog).

Units: any consistent set (kg, m, rad; Ω_A in rad per unit of x^A).

>>> import sympy as sp
>>> x = sp.Symbol("x", real=True)
>>> body = DeformableBody([1, 1], [(x, 0, 0), (-x, 0, 0)], [x])   # a dumbbell stretching along e1
>>> body.inertia_tensor
Matrix([
[0,      0,      0],
[0, 2*x**2,      0],
[0,      0, 2*x**2]])
"""

from __future__ import annotations

import numbers
import random
from typing import Any, Iterable, Mapping, Sequence

import mpmath
import sympy as sp

from ...core.model import SymbolicModel, derived
from ...core.symbols import state_symbol
from ...errors import DerivationError, InvalidInputError, ShapeError
from . import derivation
from .derivation import apparent_momentum_symbols, evaluate_noncommutative, hat, vee

__all__ = ["DeformableBody", "centred_positions"]


def _as_expr(value: Any, what: str) -> sp.Expr:
    """A SymPy expression from a SymPy object or a Python number; text is refused (never sympified)."""
    if isinstance(value, sp.Basic):
        return value  # type: ignore[return-value]
    if isinstance(value, numbers.Number) and not isinstance(value, bool):
        if isinstance(value, numbers.Integral):
            return sp.Integer(int(value))
        if isinstance(value, numbers.Rational):
            return sp.Rational(value.numerator, value.denominator)
        if isinstance(value, numbers.Real):
            return sp.Float(float(value))
    raise InvalidInputError(f"expected {what} to be a SymPy expression or a real number, got {type(value).__name__} {value!r}")


def _as_vector(value: Any, what: str) -> sp.Matrix:
    if isinstance(value, str) or not isinstance(value, (sp.MatrixBase, Sequence)):
        raise InvalidInputError(f"expected {what} to be a 3-vector of SymPy expressions, got {type(value).__name__}")
    entries = list(value)
    if len(entries) != 3:
        raise ShapeError(f"expected {what} to have 3 components, got {len(entries)}")
    return sp.Matrix([_as_expr(e, f"each component of {what}") for e in entries])


def centred_positions(masses: Sequence[Any], positions: Sequence[Any]) -> list[sp.Matrix]:
    """r_i − Σ m_j r_j / Σ m_j: the positions measured from their centre of mass (no simplification).

    Section 3.7 factors out translations by putting every shape's centre of mass at the
    origin; :class:`DeformableBody` requires it and does not silently recentre.

    >>> centred_positions([1, 3], [(0, 0, 0), (4, 0, 0)])
    [Matrix([
    [-3],
    [ 0],
    [ 0]]), Matrix([
    [1],
    [0],
    [0]])]
    """
    ms = [_as_expr(m, "each mass") for m in masses]
    rs = [_as_vector(r, "each position") for r in positions]
    if len(ms) != len(rs):
        raise ShapeError(f"expected as many positions as masses ({len(ms)}), got {len(rs)}")
    centre = sum((m * r for m, r in zip(ms, rs)), sp.zeros(3, 1)) / sum(ms)
    return [r - centre for r in rs]


def _tidy(expr: sp.Expr) -> sp.Expr:
    """A shorter, equal form of a polynomial in sines and cosines: reduced modulo cos² + sin² = 1.

    The exact normal form of :mod:`mechderive.core.simplify` (cos x, sin x → c, s; reduce by
    c² + s² − 1), without its rational-function steps, which are slow on the long sums of
    (3.93)–(3.94).  Anything else (denominators, other functions) is only expanded.
    """
    e = sp.expand(expr)
    args = sorted({f.args[0] for f in e.atoms(sp.sin, sp.cos)}, key=sp.default_sort_key)
    fwd, back, gens, basis = {}, {}, [], []
    for i, a in enumerate(args):
        c, s = sp.Dummy(f"c{i}"), sp.Dummy(f"s{i}")
        fwd[sp.cos(a)], fwd[sp.sin(a)] = c, s
        back[c], back[s] = sp.cos(a), sp.sin(a)
        gens += [c, s]
        basis.append(c**2 + s**2 - 1)
    if not gens:
        return e
    try:
        _, rem = sp.reduced(sp.expand(e.xreplace(fwd)), basis, *gens, order="lex")
    except sp.PolificationFailed:
        return e
    return sp.factor_terms(sp.expand(rem).xreplace(back))


class DeformableBody(SymbolicModel):
    """Point masses m_i at r̃_i(x^1 … x^n): Ĩ (3.93), L̃ (3.94), Ω (3.92), Ω_A (3.87), F_AB (3.102)–(3.103).

    Parameters
    ----------
    masses
        N masses (SymPy expressions or numbers), not known to be non-positive.
    positions
        N representative positions r̃_i, each 3 SymPy expressions of ``coordinates`` and
        ``parameters``, with Σ m_i r̃_i = 0 for every shape (checked at random points with
        30-digit arithmetic; see :func:`centred_positions`).
    coordinates
        The shape coordinates x^A (distinct SymPy symbols); the shape velocities are the
        symbols ``<name>_dot``.
    parameters
        Other symbols the masses and positions may contain (lengths, masses…), given
        numbers only when compiling (:meth:`numeric`).
    """

    def __init__(self, masses: Sequence[Any], positions: Sequence[Any], coordinates: Sequence[Any], *,
                 parameters: Sequence[Any] = ()) -> None:
        super().__init__()
        if isinstance(masses, str) or not isinstance(masses, Sequence) or len(masses) == 0:
            raise InvalidInputError(f"expected a non-empty sequence of masses, got {masses!r}")
        if isinstance(positions, str) or not isinstance(positions, Sequence):
            raise InvalidInputError(f"expected a sequence of positions, got {type(positions).__name__}")
        self.coordinates = self._symbols(coordinates, "shape coordinates", allow_empty=False)
        self.parameters = self._symbols(parameters, "parameters", allow_empty=True)
        clash = set(self.coordinates) & set(self.parameters)
        if clash:
            raise InvalidInputError(f"expected parameters distinct from the shape coordinates, got {sorted(map(str, clash))} in both")
        self.masses = tuple(_as_expr(m, "each mass") for m in masses)
        self.positions = tuple(_as_vector(r, f"position {i + 1}") for i, r in enumerate(positions))
        if len(self.masses) != len(self.positions):
            raise ShapeError(f"expected as many positions as masses ({len(self.masses)}), got {len(self.positions)}")
        for i, m in enumerate(self.masses):
            if m.is_positive is False or m.is_zero:
                raise InvalidInputError(f"expected mass {i + 1} > 0, got {m}")
        allowed = set(self.coordinates) | set(self.parameters)
        used = set().union(*(m.free_symbols for m in self.masses), *(r.free_symbols for r in self.positions))
        if used - allowed:
            raise InvalidInputError(
                f"expected masses and positions in the shape coordinates {[str(s) for s in self.coordinates]} "
                f"and parameters {[str(s) for s in self.parameters]}, got undeclared symbols {sorted(map(str, used - allowed))}")
        self.velocities = tuple(state_symbol(f"{x.name}_dot") for x in self.coordinates)
        self._check_centre_of_mass()

    @staticmethod
    def _symbols(values: Any, what: str, *, allow_empty: bool) -> tuple[sp.Symbol, ...]:
        if isinstance(values, (str, sp.Basic)) or not isinstance(values, Iterable):
            raise InvalidInputError(f"expected {what} as a sequence of SymPy symbols, got {type(values).__name__}")
        out = tuple(values)
        if not out and not allow_empty:
            raise InvalidInputError(f"expected at least one of the {what}, got none")
        for s in out:
            if not isinstance(s, sp.Symbol):
                raise InvalidInputError(f"expected {what} to be SymPy symbols, got {type(s).__name__} {s!r}")
        if len(set(out)) != len(out):
            raise InvalidInputError(f"expected distinct {what}, got {[str(s) for s in out]}")
        return out

    def _random_point(self, rng: random.Random) -> dict[sp.Symbol, mpmath.mpf]:
        return {s: mpmath.mpf(rng.uniform(0.3, 1.3)) for s in (*self.coordinates, *self.parameters)}

    def _check_centre_of_mass(self) -> None:
        # Each mass and position evaluated once at three random points, to 30 digits and summed there:
        # 10× faster than lambdifying the long sums to mpmath (the cat's 12 masses).
        rng = random.Random(37)
        for _ in range(3):
            point = {s: sp.Float(str(x), 30) for s, x in self._random_point(rng).items()}
            masses = [sp.N(m.xreplace(point), 30) for m in self.masses]
            positions = [[sp.N(c.xreplace(point), 30) for c in r] for r in self.positions]
            got = [sp.Add(*(m * r[a] for m, r in zip(masses, positions))) for a in range(3)]
            size = sp.Add(*(abs(m) * sum(abs(c) for c in r) for m, r in zip(masses, positions)))
            if max(abs(v) for v in got) > 1e-20 * (1 + size):
                where = ", ".join(f"{s}={float(v):.3g}" for s, v in point.items())
                raise InvalidInputError(
                    "expected the centre of mass at the origin for every shape (Σ m_i r̃_i = 0; see "
                    f"centred_positions), got Σ m r̃ = ({', '.join(f'{float(sp.re(v)):.3g}' for v in got)}) "
                    f"at {where}")

    @property
    def dimension(self) -> int:
        """n, the number of shape coordinates."""
        return len(self.coordinates)

    # ------------------------------------------------------------------ kinematics of the shape
    @derived
    def reduced_positions(self) -> tuple[sp.Matrix, ...]:
        """The r̃_i with entries expanded and reduced modulo cos² + sin² = 1 (equal, shorter)."""
        return tuple(r.applyfunc(_tidy) for r in self.positions)

    @derived
    def position_jacobians(self) -> tuple[sp.Matrix, ...]:
        """∂r̃_i/∂x^A, one 3×n matrix per mass."""
        xs = sp.Matrix(self.coordinates)
        return tuple(r.jacobian(xs).applyfunc(_tidy) for r in self.reduced_positions)

    @derived
    def shape_velocities(self) -> tuple[sp.Matrix, ...]:
        """r̃̇_i = (∂r̃_i/∂x^A) ẋ^A."""
        return tuple(J * sp.Matrix(self.velocities) for J in self.position_jacobians)

    def _per_mass(self, expr: sp.Matrix, rates: Sequence[sp.Matrix] | None = None) -> sp.Matrix:
        """Σ_i of a per-mass formula of :mod:`.derivation` at m_i, r̃_i and (if given) r̃̇_i = ``rates[i]``."""
        d = derivation.model()
        names = [state_symbol(f"rtilde{a}") for a in (1, 2, 3)]
        dots = [state_symbol(f"rtilde{a}_dot") for a in (1, 2, 3)]
        total = sp.zeros(*expr.shape)
        for i, (m, r) in enumerate(zip(self.masses, self.reduced_positions)):
            subs = {d.mass: m, **dict(zip(names, r))}
            if rates is not None:
                subs.update(zip(dots, rates[i]))
            total += expr.xreplace(subs)
        return total

    @derived
    def inertia_tensor(self) -> sp.Matrix:
        """Ĩ_ab(x) (3.93): Σ_i of the per-mass inertia −∂(R⁻¹L)/∂v of :mod:`.derivation`."""
        return self._per_mass(derivation.model().inertia_per_mass).applyfunc(_tidy)

    @derived
    def apparent_angular_momentum(self) -> sp.Matrix:
        """L̃_a(x, ẋ) (3.94): Σ_i of the per-mass Ω-independent part of R⁻¹L, with r̃̇_i = ∂_A r̃_i ẋ^A.

        The per-mass L̃ is linear in r̃̇ (checked), so L̃ = Σ_A ẋ^A L̃[r̃̇_i → ∂_A r̃_i]; each
        coefficient is simplified separately.
        """
        per_mass = derivation.model().apparent_angular_momentum
        dots = sp.Matrix([state_symbol(f"rtilde{a}_dot") for a in (1, 2, 3)])
        if per_mass.jacobian(dots).free_symbols & set(dots) or any(e != 0 for e in per_mass.subs({d: 0 for d in dots})):
            raise DerivationError("expected the apparent angular momentum to be linear in the shape velocities")
        total = sp.zeros(3, 1)
        for A, xdot in enumerate(self.velocities):
            coeff = self._per_mass(per_mass, [J.col(A) for J in self.position_jacobians]).applyfunc(_tidy)
            total += coeff * xdot
        return total

    # ------------------------------------------------------------------ gauge potential
    @derived
    def angular_velocity_vector(self) -> sp.Matrix:
        """v(x, ẋ) with Ω = hat(v): the general solution of L = 0 of :mod:`.derivation` at this Ĩ, L̃."""
        from ...inertia.tensor import general_inertia_symbols

        general = vee(derivation.model().angular_velocity_solution)
        if _tidy(self.inertia_tensor.det()) == 0:
            raise InvalidInputError("expected an inertia tensor Ĩ(x) invertible for generic shapes (masses not all "
                                    "on one line through the centre of mass), got det Ĩ ≡ 0")
        I, Lt = general_inertia_symbols(), apparent_momentum_symbols()
        subs = {I[a, b]: self.inertia_tensor[a, b] for a in range(3) for b in range(a, 3)}
        subs.update(zip(Lt, self.apparent_angular_momentum))
        return general.subs(subs, simultaneous=True)

    @derived
    def angular_velocity(self) -> sp.Matrix:
        """Ω(x, ẋ) = hat(v), Ω_ab = ε_abc v_c (3.92): the convective angular velocity at L = 0."""
        return hat(self.angular_velocity_vector)

    @derived
    def connection_vectors(self) -> sp.Matrix:
        """Row A: the vector of Ω_A(x) = ∂Ω/∂ẋ^A (3.87); checked that Ω = Ω_A ẋ^A exactly.

        Ω is linear in ẋ because ∂Ω/∂ẋ^A contains no ẋ and Ω vanishes at ẋ = 0.
        """
        v = self.angular_velocity_vector
        rows = v.jacobian(sp.Matrix(self.velocities)).T
        if rows.free_symbols & set(self.velocities):
            raise DerivationError("expected ∂Ω/∂ẋ^A to be independent of ẋ (Ω linear in ẋ, (3.87))")
        if any(e != 0 for e in v.subs({s: 0 for s in self.velocities})):
            raise DerivationError("expected Ω = 0 at ẋ = 0 (no shape change, no rotation)")
        return rows

    @derived
    def connection(self) -> tuple[sp.Matrix, ...]:
        """Ω_A(x) (3.87), the n antisymmetric 3×3 gauge-potential matrices hat(row A of ``connection_vectors``)."""
        return tuple(hat(self.connection_vectors.row(A)) for A in range(self.dimension))

    @derived
    def connection_derivatives(self) -> tuple[tuple[sp.Matrix, ...], ...]:
        """∂Ω_A/∂x^B as [A][B] 3×3 matrices (needed by (3.101)–(3.103))."""
        return tuple(tuple(Omega_A.diff(x) for x in self.coordinates) for Omega_A in self.connection)

    # ------------------------------------------------------------------ field strength
    @derived
    def field_strength(self) -> tuple[tuple[sp.Matrix, ...], ...]:
        """F_AB(x) [A][B]: the coefficient of ½∮α_Aα̇_B dt in the small-loop expansion (3.102).

        Built from the non-commuting form of :attr:`.derivation.ConnectionDerivation.field_strength_form`
        (Ω_1, Ω_2, ∂Ω_1/∂x², ∂Ω_2/∂x¹ relabelled to A, B — the derivation shows that each pair's
        coefficient involves only that pair), so F_AB = ∂_AΩ_B − ∂_BΩ_A + [Ω_A, Ω_B], F_BA = −F_AB.
        """
        form = derivation.model().field_strength_form
        base = form[(1, 2)]
        P1, P2 = sp.Symbol("Omega_1", commutative=False), sp.Symbol("Omega_2", commutative=False)
        D12, D21 = sp.Symbol("dOmega_1_2", commutative=False), sp.Symbol("dOmega_2_1", commutative=False)
        for (A, B), other in form.items():  # the pairs of the n = 3 derivation are relabellings of (1, 2)
            relabel = {P1: sp.Symbol(f"Omega_{A}", commutative=False), P2: sp.Symbol(f"Omega_{B}", commutative=False),
                       D12: sp.Symbol(f"dOmega_{A}_{B}", commutative=False),
                       D21: sp.Symbol(f"dOmega_{B}_{A}", commutative=False)}
            if sp.expand(base.subs(relabel, simultaneous=True) - other) != 0:
                raise DerivationError(f"expected F_{A}{B} to be F_12 relabelled, got {other}")
        n, Om, dOm = self.dimension, self.connection, self.connection_derivatives
        F = [[sp.zeros(3, 3) for _ in range(n)] for _ in range(n)]
        for A in range(n):
            for B in range(A + 1, n):
                values = {P1: Om[A], P2: Om[B], D12: dOm[A][B], D21: dOm[B][A]}
                F[A][B] = evaluate_noncommutative(base, values)
                F[B][A] = -F[A][B]
        return tuple(tuple(row) for row in F)

    @derived
    def field_strength_vectors(self) -> list[list[list[sp.Expr]]]:
        """vee(F_AB) as a nested [A][B][a] list (each F_AB is antisymmetric in a, b)."""
        return [[list(vee(F_AB)) for F_AB in row] for row in self.field_strength]

    # ------------------------------------------------------------------ gauge transformation (3.88)
    def regauged(self, S: Any) -> "DeformableBody":
        """The same body with the representatives S(x) r̃_i (3.88); its Ω_A are derived anew.

        ``S`` must be a rotation matrix (SymPy, 3×3) of the shape coordinates and parameters;
        SᵀS = 1 and det S = 1 are checked at random points with 30 digits.  The regauged body is kept
        per S, like any derived quantity: asking again returns the same body and derives nothing more.
        """
        if not isinstance(S, sp.MatrixBase) or S.shape != (3, 3):
            raise ShapeError(f"expected S as a 3×3 SymPy Matrix, got {getattr(S, 'shape', type(S).__name__)}")
        kept = self.__dict__.setdefault("_regauged_bodies", {})
        key = sp.ImmutableMatrix(S)
        if key not in kept:
            kept[key] = self._regauged(S)
        return kept[key]

    def _regauged(self, S: sp.MatrixBase) -> "DeformableBody":
        syms = [*self.coordinates, *self.parameters]
        extra = S.free_symbols - set(syms)
        if extra:
            raise InvalidInputError(f"expected S to depend on the shape coordinates and parameters only, got {sorted(map(str, extra))}")
        f = sp.lambdify(syms, [*(S.T * S - sp.eye(3)), S.det() - 1], "mpmath")
        rng = random.Random(41)
        with mpmath.workdps(30):
            for _ in range(3):
                point = self._random_point(rng)
                worst = max(abs(v) for v in f(*[point[s] for s in syms]))
                if worst > 1e-20:
                    raise InvalidInputError(f"expected S to be a rotation (SᵀS = 1, det S = 1), got a deviation {float(worst):.3g}")
        return DeformableBody(self.masses, [S * r for r in self.positions], self.coordinates, parameters=self.parameters)

    # ------------------------------------------------------------------ numbers
    def numeric(self, values: Mapping[Any, float] | None = None):
        """A :class:`~.connection.ShapeConnection`: the compiled Ω_A, F_AB, … at parameter ``values``.

        ``values`` maps each parameter (symbol, or its name) to a finite number.
        """
        from .connection import ShapeConnection

        return ShapeConnection(self, values)
