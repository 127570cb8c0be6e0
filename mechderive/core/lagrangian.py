"""Lagrangian mechanics, derived: Euler–Lagrange equations, momenta, energy, Routh reduction.

A :class:`LagrangianModel` starts from a Lagrangian L(q, q̇, t) in generalised coordinates
q_i(t) — functions of the time symbol made by :func:`~mechderive.core.symbols.coordinate` —
and derives, lazily and each logged in ``model.derived``:

==========================  =====================================================================
``state_lagrangian``        L in the plain state symbols ``q, q_dot`` (see :func:`to_state_symbols`)
``euler_lagrange``          d/dt ∂L/∂q̇_i − ∂L/∂q_i, each = 0, in functions of t
``mass_matrix``             M_ij = ∂²L/∂q̇_i∂q̇_j
``forcing``                 F with M q̈ = F: F_i = ∂L/∂q_i − Σ_j ∂²L/∂q̇_i∂q_j q̇_j − ∂²L/∂q̇_i∂t
``accelerations``           q̈ = M⁻¹F (column, in coordinate order; ``acceleration_map`` keyed by q_ddot)
``momenta``                 p_i = ∂L/∂q̇_i
``generalised_forces``      ∂L/∂q_i
``cyclic_coordinates``      the q_c with ∂L/∂q_c ≡ 0 (decided exactly), whose p_c are conserved
``conserved_momenta``       {q_c: p_c(q, q̇)}
``energy_function``         h = Σ q̇_i ∂L/∂q̇_i − L (conserved when ∂L/∂t = 0)
``momentum_symbols``        {q_c: p_<name>}, the conserved values used as parameters below
``cyclic_velocities``       {q̇_c: …} solved from p_c = ∂L/∂q̇_c, in the remaining q, q̇ and the p_c
``routhian``                R = L − Σ_c p_c q̇_c at those velocities: the Lagrangian of the rest
``effective_potential``     V_eff = −R at zero remaining velocities (so h = R₂ + V_eff)
``reduced_accelerations``   the remaining q̈ from R's own Euler–Lagrange equations
==========================  =====================================================================

Sign convention of the Routhian: R = L − Σ p_c q̇_c, so that R *is* a Lagrangian for the
remaining coordinates (some texts define its negative; the equations of motion agree).
The reduced energy Σ_r q̇_r ∂R/∂q̇_r − R equals h.

Two ways to give the Lagrangian: construct ``LagrangianModel(L, coordinates)``, or subclass,
set ``coordinates`` and override the ``lagrangian`` quantity with a ``@derived`` method that
derives it (see :class:`mechderive.systems.heavy_top.model.HeavyTopModel`).

The spherical pendulum (θ from the downward vertical):

>>> from mechderive.core.symbols import coordinate, t
>>> m, g, l = sp.symbols("m g l", positive=True)
>>> theta, phi = coordinate("theta"), coordinate("phi")
>>> L = m * l**2 * (theta.diff(t)**2 + sp.sin(theta)**2 * phi.diff(t)**2) / 2 + m * g * l * sp.cos(theta)
>>> pendulum = LagrangianModel(L, [theta, phi])
>>> pendulum.cyclic_coordinates
(phi(t),)
>>> pendulum.effective_potential
-g*l*m*cos(theta) + p_phi**2/(2*l**2*m*sin(theta)**2)
>>> pendulum.derived
['lagrangian', 'state_lagrangian', 'generalised_forces', 'cyclic_coordinates', 'momentum_symbols', 'momenta', 'cyclic_velocities', 'routhian_normal', 'routhian', 'effective_potential']
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.polys.polyerrors import BasePolynomialError

from ..errors import DerivationError, InvalidInputError
from .compile import compile_scalar
from .model import SymbolicModel, derived
from .simplify import TrigField, factor, is_zero, trig_normal
from .symbols import as_symbolic, state_symbol, t, to_state_symbols

__all__ = ["LagrangianModel", "from_state_symbols", "vanishes"]


def vanishes(expr: Any) -> bool:
    """Whether ``expr`` is identically zero: exactly for trigonometric rational functions, else ``sp.simplify``."""
    expr = as_symbolic(expr)
    if expr == 0:
        return True
    decided = is_zero(expr)
    if decided is not None:
        return decided
    return sp.simplify(expr) == 0


def _normal(expr: Any) -> sp.Expr:
    """An exact, fast simplification: the trig normal form (sin² + cos² = 1 reduced), factored."""
    return factor(trig_normal(expr))


def _solve_in_field(A: sp.Matrix, rhs: sp.Matrix) -> list | None:
    """The solution of A x = rhs, each entry as :func:`_normal` gives it; None where this route cannot tell: the
    entries are not rational in sines, cosines and symbols, or the elimination meets a zero pivot column or
    det A ≡ 0 modulo sin² + cos² = 1 (a pivot nonzero in the field may vanish as a function) — the caller then
    decides by expressions.

    By Gaussian elimination in the field of rational functions of the cosines, sines and symbols
    (:class:`~mechderive.core.simplify.TrigField`): the solution of a regular system over a field is unique, so
    it is the very element that LUsolve's expressions stand for, and its normal form is the one
    :func:`trig_normal` finds for them — without building those nested expressions and taking them apart
    again (three quarters of the cyclic velocities' time on a cold start's serial path).
    """
    try:
        F = TrigField([*A, *rhs])
        rows = [[F(A[i, j]) for j in range(A.cols)] + [F(rhs[i])] for i in range(A.rows)]
    except (ValueError, BasePolynomialError, InvalidInputError):
        return None
    n = A.rows
    det = F.field.one
    for k in range(n):
        pivot = next((i for i in range(k, n) if rows[i][k] != 0), None)
        if pivot is None:
            return None
        rows[k], rows[pivot] = rows[pivot], rows[k]
        det *= rows[k][k]
        for i in range(k + 1, n):
            f = rows[i][k] / rows[k][k]
            if f != 0:
                rows[i] = [x - f * y for x, y in zip(rows[i], rows[k])]
    if F.normal(det) == 0:  # zero as a function though not in the field (sin² + cos² − 1)
        return None
    x = [F.field.zero] * n
    for k in reversed(range(n)):
        x[k] = (rows[k][n] - sum((rows[k][j] * x[j] for j in range(k + 1, n)), F.field.zero)) / rows[k][k]
    return [factor(F.normal(v)) for v in x]


def _name(q: sp.Expr) -> str:
    return q.func.__name__


def from_state_symbols(expr: Any, coordinates: Sequence[sp.Expr]) -> Any:
    """Inverse of :func:`to_state_symbols` for ``coordinates``: q, q_dot, q_ddot → q(t), q̇(t), q̈(t).

    >>> from mechderive.core.symbols import coordinate
    >>> x = coordinate("x")
    >>> from_state_symbols(state_symbol("x_dot") * state_symbol("x"), [x])
    x(t)*Derivative(x(t), t)
    """
    subs = {}
    for q in coordinates:
        n = _name(q)
        subs[state_symbol(n)] = q
        subs[state_symbol(n + "_dot")] = q.diff(t)
        subs[state_symbol(n + "_ddot")] = q.diff(t, 2)
    return as_symbolic(expr).xreplace(subs)


def _check_coordinates(coordinates: Sequence[Any]) -> tuple[sp.Expr, ...]:
    if isinstance(coordinates, (str, sp.Basic)) or not hasattr(coordinates, "__iter__"):
        raise InvalidInputError(f"expected a sequence of coordinates like [coordinate('r')], got {coordinates!r}")
    coords = tuple(coordinates)
    if not coords:
        raise InvalidInputError("expected at least one coordinate, got none")
    for q in coords:
        if not (isinstance(q, AppliedUndef) and q.args == (t,)):
            raise InvalidInputError(
                f"expected each coordinate to be a function of t like coordinate('{q}'), got {q!r}")
    if len(set(coords)) != len(coords):
        raise InvalidInputError(f"expected distinct coordinates, got {list(coords)}")
    return coords


def _check_lagrangian(lagrangian: Any, coordinates: tuple[sp.Expr, ...]) -> sp.Expr:
    """``lagrangian`` as a SymPy scalar expression in ``coordinates``, their velocities and t, or raise."""
    L = as_symbolic(lagrangian, "the Lagrangian")
    if not isinstance(L, sp.Expr) or getattr(L, "is_Matrix", False):
        raise InvalidInputError(f"expected the Lagrangian as a scalar SymPy expression, got {type(L).__name__}")
    names = {_name(q) + suffix: _name(q) for q in coordinates for suffix in ("", "_dot", "_ddot")}
    plain = sorted(s.name for s in L.free_symbols if s.name in names)
    if plain:
        raise InvalidInputError(
            f"expected the coordinates as functions of t (coordinate('{names[plain[0]]}')), "
            f"got the plain symbol {plain[0]} in the Lagrangian")
    for d in L.atoms(sp.Derivative):
        if d.expr in coordinates and d.derivative_count > 1:
            raise InvalidInputError(f"expected at most first derivatives of the coordinates, got {d}")
    # velocities first, so that q(t) inside Derivative(q(t), t) is not replaced on its own
    stripped = L.xreplace({q.diff(t): sp.Dummy() for q in coordinates}).xreplace({q: sp.Dummy() for q in coordinates})
    extra = sorted({str(a) for a in stripped.atoms(AppliedUndef, sp.Derivative) if t in a.free_symbols})
    if extra:
        listed = ", ".join(map(str, coordinates))
        raise InvalidInputError(
            f"expected the Lagrangian to be a function of the coordinates ({listed}), their velocities "
            f"and t, got also {', '.join(extra)}")
    missing = [q.diff(t) for q in coordinates if not L.has(q.diff(t))]
    if missing:
        raise InvalidInputError(
            f"expected the Lagrangian to contain the velocity of every coordinate, got none of "
            f"{', '.join(map(str, missing))}")
    return L


def _mass_and_forcing(L: sp.Expr, qs: Sequence[sp.Symbol], qdots: Sequence[sp.Symbol]) -> tuple[sp.Matrix, sp.Matrix]:
    """M = ∂²L/∂q̇∂q̇ and F = ∂L/∂q − (∂²L/∂q̇∂q) q̇ − ∂²L/∂q̇∂t, so that the E–L equations read M q̈ = F."""
    p = sp.Matrix([L.diff(v) for v in qdots])
    M = p.jacobian(list(qdots))
    F = sp.Matrix([L.diff(q) for q in qs]) - p.jacobian(list(qs)) * sp.Matrix(qdots) - p.diff(t)
    return M.applyfunc(sp.expand), F.applyfunc(sp.expand)


def _solve_accelerations(M: sp.Matrix, F: sp.Matrix) -> sp.Matrix:
    det = M.det(method="berkowitz")
    if vanishes(det):
        raise InvalidInputError(
            f"expected a regular Lagrangian (det ∂²L/∂q̇∂q̇ ≠ 0), got det = {sp.simplify(det)}")
    return M.LUsolve(F).applyfunc(_normal)


class LagrangianModel(SymbolicModel):
    """A mechanical system given by its Lagrangian L(q, q̇, t); every quantity derived lazily.

    Parameters
    ----------
    lagrangian
        L as a SymPy expression in the coordinates (functions of t), their first derivatives, t
        and constant parameters.  Omit it in a subclass that derives its own ``lagrangian``.
    coordinates
        The generalised coordinates q_i(t), e.g. ``[coordinate("r"), coordinate("phi")]``; a
        subclass may set the class attribute ``coordinates`` instead.

    Raises :class:`~mechderive.errors.InvalidInputError` when the Lagrangian involves other
    functions of t, plain symbols named like the coordinates, second derivatives, or misses a
    coordinate's velocity.  Results are in the state symbols ``q, q_dot`` (names of the
    coordinates) unless a docstring says "functions of t".
    """

    coordinates: tuple[sp.Expr, ...] = ()

    def __init__(self, lagrangian: Any = None, coordinates: Sequence[Any] | None = None) -> None:
        super().__init__()
        given = coordinates if coordinates is not None else type(self).coordinates
        self.coordinates = _check_coordinates(given)
        overridden = getattr(type(self), "lagrangian") is not LagrangianModel.__dict__["lagrangian"]
        if lagrangian is None and not overridden:
            raise InvalidInputError("expected a Lagrangian (a SymPy expression), got None")
        if lagrangian is not None and overridden:
            raise InvalidInputError(
                f"expected no Lagrangian for {type(self).__name__}, which derives its own, got {lagrangian!r}")
        self._given = None if lagrangian is None else _check_lagrangian(lagrangian, self.coordinates)

    # --- names ------------------------------------------------------------------------------

    @property
    def positions(self) -> tuple[sp.Symbol, ...]:
        """The state symbols q of the coordinates, in order."""
        return tuple(state_symbol(_name(q)) for q in self.coordinates)

    @property
    def velocities(self) -> tuple[sp.Symbol, ...]:
        """The state symbols q_dot, in order."""
        return tuple(state_symbol(_name(q) + "_dot") for q in self.coordinates)

    @property
    def acceleration_symbols(self) -> tuple[sp.Symbol, ...]:
        """The state symbols q_ddot, in order (the rows of :attr:`accelerations`)."""
        return tuple(state_symbol(_name(q) + "_ddot") for q in self.coordinates)

    def _index(self, q: sp.Expr) -> int:
        return self.coordinates.index(q)

    # --- the Lagrangian and Euler–Lagrange equations ---------------------------------------

    @derived
    def lagrangian(self) -> sp.Expr:
        """L(q(t), q̇(t), t) as given at construction (subclasses derive it), functions of t."""
        return self._given

    @derived
    def state_lagrangian(self) -> sp.Expr:
        """L in the state symbols ``q, q_dot`` (checked like a given Lagrangian)."""
        return to_state_symbols(_check_lagrangian(self.lagrangian, self.coordinates))

    @derived
    def momenta(self) -> sp.Matrix:
        """Generalised momenta p_i = ∂L/∂q̇_i (column, coordinate order)."""
        L = self.state_lagrangian
        return sp.Matrix([sp.expand(L.diff(v)) for v in self.velocities])

    @derived
    def generalised_forces(self) -> sp.Matrix:
        """∂L/∂q_i (column): dp_i/dt equals it on the equations of motion."""
        L = self.state_lagrangian
        return sp.Matrix([sp.expand(L.diff(q)) for q in self.positions])

    @derived
    def euler_lagrange(self) -> sp.Matrix:
        """d/dt ∂L/∂q̇_i − ∂L/∂q_i (column, each = 0 on a motion), in functions of t."""
        back = lambda e: from_state_symbols(e, self.coordinates)  # noqa: E731
        return sp.Matrix([sp.expand(back(p).diff(t) - back(f)) for p, f in zip(self.momenta, self.generalised_forces)])

    @derived
    def mass_matrix(self) -> sp.Matrix:
        """M_ij = ∂²L/∂q̇_i∂q̇_j: the Euler–Lagrange equations read M q̈ = F (see :attr:`forcing`)."""
        return _mass_and_forcing(self.state_lagrangian, self.positions, self.velocities)[0]

    @derived
    def forcing(self) -> sp.Matrix:
        """F_i = ∂L/∂q_i − Σ_j ∂²L/∂q̇_i∂q_j q̇_j − ∂²L/∂q̇_i∂t, the right-hand side of M q̈ = F."""
        return _mass_and_forcing(self.state_lagrangian, self.positions, self.velocities)[1]

    @derived
    def accelerations(self) -> sp.Matrix:
        """q̈ = M⁻¹F (column, coordinate order), each entry simplified; raises for a singular M."""
        return _solve_accelerations(self.mass_matrix, self.forcing)

    @property
    def acceleration_map(self) -> dict:
        """{q_ddot: q̈(q, q̇)}: :attr:`accelerations` keyed by the acceleration symbols (derives them)."""
        return dict(zip(self.acceleration_symbols, self.accelerations))

    @derived
    def energy_function(self) -> sp.Expr:
        """h = Σ q̇_i ∂L/∂q̇_i − L; dh/dt = −∂L/∂t on a motion (the energy when L = T − V, T quadratic)."""
        return sp.expand(sum(v * p for v, p in zip(self.velocities, self.momenta)) - self.state_lagrangian)

    # --- ignorable coordinates and Routh reduction -----------------------------------------

    @derived
    def cyclic_coordinates(self) -> tuple[sp.Expr, ...]:
        """The ignorable coordinates q_c(t), those with ∂L/∂q_c ≡ 0 (decided exactly), in order."""
        return tuple(q for q, f in zip(self.coordinates, self.generalised_forces) if vanishes(f))

    @derived
    def conserved_momenta(self) -> dict:
        """{q_c(t): p_c(q, q̇)} for the cyclic coordinates: dp_c/dt = ∂L/∂q_c = 0."""
        return {q: self.momenta[self._index(q)] for q in self.cyclic_coordinates}

    @derived
    def momentum_symbols(self) -> dict:
        """{q_c(t): p_<name>}: real symbols standing for the conserved momenta's values."""
        syms = {q: sp.Symbol("p_" + _name(q), real=True) for q in self.cyclic_coordinates}
        clash = [s for s in syms.values() if s.name in {f.name for f in self.state_lagrangian.free_symbols}]
        if clash:
            raise InvalidInputError(f"expected the Lagrangian not to use the momentum symbol names, got {clash[0]}")
        return syms

    @property
    def remaining_coordinates(self) -> tuple[sp.Expr, ...]:
        """The coordinates that are not cyclic (derives ``cyclic_coordinates``)."""
        return tuple(q for q in self.coordinates if q not in self.cyclic_coordinates)

    @derived
    def cyclic_velocities(self) -> dict:
        """{q̇_c: …}: the cyclic velocities solved from p_c = ∂L/∂q̇_c, in the remaining q, q̇ and the p_c."""
        cyc = self.cyclic_coordinates
        if not cyc:
            raise DerivationError("expected at least one cyclic coordinate to reduce, got none")
        unknowns = [self.velocities[self._index(q)] for q in cyc]
        eqs = [self.momenta[self._index(q)] - self.momentum_symbols[q] for q in cyc]
        try:
            A, rhs = sp.linear_eq_to_matrix(eqs, unknowns)
        except sp.polys.polyerrors.PolynomialError:
            A = None
        if A is None or A.has(*unknowns):
            raise DerivationError(f"expected momenta linear in the cyclic velocities {unknowns}, got {eqs}")
        sol = _solve_in_field(A, rhs)
        if sol is None:  # decided by expressions: only a system singular as a function is refused
            if vanishes(A.det(method="berkowitz")):
                raise DerivationError(f"expected p_c = ∂L/∂q̇_c solvable for {unknowns}, got a singular system {A}")
            sol = [_normal(x) for x in A.LUsolve(rhs)]
        return dict(zip(unknowns, sol))

    @derived
    def routhian_normal(self) -> sp.Expr:
        """The Routhian :attr:`routhian` in the trig normal form: one fraction, as it comes (not collected by
        powers of the velocities — for derivations that go on from its value, not for reading)."""
        p = self.momentum_symbols
        R = self.state_lagrangian - sum(p[q] * self.velocities[self._index(q)] for q in self.cyclic_coordinates)
        # the keys are the velocity symbols themselves: replacing those nodes (xreplace) is the substitution
        R = trig_normal(R.xreplace(self.cyclic_velocities))
        if R.has(*self.cyclic_velocities) or any(R.has(self.positions[self._index(q)]) for q in self.cyclic_coordinates):
            raise DerivationError(f"expected the Routhian free of the cyclic coordinates and velocities, got {R}")
        return R

    @derived
    def routhian(self) -> sp.Expr:
        """R = L − Σ_c p_c q̇_c with the cyclic velocities eliminated: a Lagrangian of the rest, p_c as parameters."""
        return _collect_velocities(self.routhian_normal, self._remaining_velocities())

    def _remaining_velocities(self) -> list[sp.Symbol]:
        return [self.velocities[self._index(q)] for q in self.remaining_coordinates]

    @derived
    def effective_potential(self) -> sp.Expr:
        """V_eff = −R(q̇_r = 0): the reduced energy is Σ_r q̇_r ∂R/∂q̇_r − R = R₂ + V_eff, R₂ quadratic in q̇_r."""
        return _collect_velocities(-self.routhian.subs({q: 0 for q in self._remaining_velocities()}), [])

    @derived
    def reduced_accelerations(self) -> sp.Matrix:
        """The remaining q̈_r from the Euler–Lagrange equations of the Routhian (column, in coordinate order)."""
        qs = [self.positions[self._index(q)] for q in self.remaining_coordinates]
        M, F = _mass_and_forcing(self.routhian, qs, self._remaining_velocities())
        return _solve_accelerations(M, F)

    # --- numbers ----------------------------------------------------------------------------

    def ode_rhs(self, parameters: Sequence[sp.Symbol]) -> Callable[..., list]:
        """The first-order system for :func:`scipy.integrate.solve_ivp`: ``rhs(t, y, *values)``.

        ``y = (q..., q_dot...)`` in coordinate order, ``values`` the numbers of ``parameters``
        (every other free symbol of :attr:`accelerations`).  Compiled once with
        :func:`~mechderive.core.compile.compile_scalar` (cached process-wide).
        """
        acc = self.accelerations
        args = [t, *self.positions, *self.velocities, *parameters]
        missing = acc.free_symbols - set(args)
        if missing:
            raise InvalidInputError(
                f"expected parameters including {', '.join(sorted(map(str, missing)))}, "
                f"got [{', '.join(map(str, parameters))}]")
        f = compile_scalar(acc, args, name=f"{type(self).__name__}.accelerations")
        if "ode_rhs" not in self.compiled:
            self.compiled.append("ode_rhs")
        n = len(self.coordinates)

        def rhs(time: float, y: Sequence[float], *values: float) -> list:
            return [*y[n:], *f(time, *y, *values)]

        return rhs


def _collect_velocities(expr: sp.Expr, velocities: Sequence[sp.Symbol]) -> sp.Expr:
    """``expr`` as a sum of terms by powers of ``velocities``, each coefficient factored (readable, exact)."""
    expr = sp.expand(expr)
    if not velocities:
        return _tidy(expr)
    poly = sp.Poly(expr, *velocities)
    return sum((sp.Mul(*[v**k for v, k in zip(velocities, m)]) * _tidy(c) for m, c in poly.terms()), sp.Integer(0))


def _tidy(expr: sp.Expr) -> sp.Expr:
    """Terms grouped over common denominators where that shortens them; no trig rewriting beyond that."""
    expr = sp.expand(expr)
    parts = sp.Add.make_args(expr)
    by_den: dict[Any, list] = {}
    for p in parts:
        _, den = sp.fraction(sp.together(p))
        by_den.setdefault(den, []).append(p)
    return sp.Add(*[factor(sp.Add(*ps)) for ps in by_den.values()])
