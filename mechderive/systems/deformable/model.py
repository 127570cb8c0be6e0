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

import math
import numbers
import random
from typing import Any, Iterable, Mapping, Sequence

import mpmath
import sympy as sp
from sympy.polys.rings import PolyRing

from ...core.model import SymbolicModel, derived
from ...core.symbols import state_symbol
from ...errors import DerivationError, InvalidInputError, ShapeError
from . import derivation
from .derivation import apparent_momentum_symbols, evaluate_noncommutative, hat, vee

__all__ = ["DeformableBody", "centred_positions"]

_SINGULAR = ("expected an inertia tensor Ĩ(x) invertible for generic shapes (masses not all on one line through "
             "the centre of mass), got det Ĩ ≡ 0")


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


class _NotInRing(DerivationError):
    """An expression outside the exact ring of :class:`_TrigPolynomials` (internal: caught where raised, and the
    expressions are then used as they are)."""


class _TrigPolynomials:
    """Polynomials in cos a_k, sin a_k (generators c_k, s_k) modulo c_k² + s_k² − 1, as SymPy sparse polynomials.

    The normal form keeps every c_k to at most the first power (c_k² → 1 − s_k²).  The c_k² + s_k² − 1 share
    no variables, so they are a Gröbner basis for any order with c_k > s_k and this normal form is the
    remainder ``sympy.reduced`` computes (lex order), without its general division algorithm.  Products
    are taken between polynomials, not by expanding products of long SymPy sums — the cost of (3.92)
    for a body whose Ĩ and L̃ are long trigonometric polynomials.

    Two representations.  Where every expression is a polynomial with rational coefficients in the
    c_k, s_k, its other symbols and their reciprocals (the 1/m of centred positions), elements of the
    ring ℚ[c, s, symbols, reciprocals] (``sympy.polys.rings``, built from the expression tree without
    ``expand``; a symbol times its reciprocal is cancelled by :meth:`normal`).  Otherwise ``Poly`` in the
    c_k, s_k over the domain SymPy chooses (Floats, roots, sums in denominators …), or ``PolynomialError``.

    The arguments a_k are identified after expansion (cos(y(x + ½)) and cos(xy + y/2) are one generator);
    no relation between different arguments (x and 2x) is used.
    """

    def __init__(self, args: Iterable[sp.Expr], symbols: Sequence[sp.Symbol] | None = None) -> None:
        spelled: dict[sp.Expr, list[sp.Expr]] = {}
        for a in args:
            spelled.setdefault(sp.expand(a), []).append(a)
        self.args = sorted(spelled, key=sp.default_sort_key)
        self.fwd: dict[sp.Expr, sp.Symbol] = {}
        self.back: dict[sp.Symbol, sp.Expr] = {}
        gens: list[sp.Symbol] = []
        for k, a in enumerate(self.args):
            c, s = sp.Dummy(f"c{k}"), sp.Dummy(f"s{k}")
            for b in spelled[a]:
                self.fwd[sp.cos(b)], self.fwd[sp.sin(b)] = c, s
            self.back[c], self.back[s] = sp.cos(a), sp.sin(a)
            gens += [c, s]
        self._pairs: list[tuple[int, int]] = []  # (index of a symbol x, index of 1/x) among the generators
        if symbols is None:
            self.ring: PolyRing | None = None
            self.gens: tuple[sp.Symbol, ...] = tuple(gens) or (sp.Dummy("unused"),)
            return
        symbols = list(symbols)
        inverses = [sp.Dummy(f"inv_{x.name}") for x in symbols]
        for i, (x, inv) in enumerate(zip(symbols, inverses)):
            self.back[inv] = 1 / x
            self._pairs.append((len(gens) + i, len(gens) + len(symbols) + i))
        self.ring = PolyRing([*gens, *symbols, *inverses] or [sp.Dummy("unused")], sp.QQ)
        self.gens = tuple(self.ring.symbols)
        elements = dict(zip(self.gens, self.ring.gens))
        self._element_of = {f: elements[g] for f, g in self.fwd.items()}
        self._element_of.update((x, elements[x]) for x in symbols)
        self._reciprocal_of = {x: elements[inv] for x, inv in zip(symbols, inverses)}

    @classmethod
    def convert(cls, exprs: Sequence[sp.Expr], *, general: bool = True) -> tuple["_TrigPolynomials", list[Any]]:
        """The ring of every sine and cosine in ``exprs``, and ``exprs`` in it (``PolynomialError`` if impossible).

        ``general=False``: only the exact ring ℚ[c, s, symbols, reciprocals] (``PolynomialError`` otherwise).
        """
        args = {f.args[0] for e in exprs for f in e.atoms(sp.sin, sp.cos)}
        exact = cls(args, sorted(set().union(*(e.free_symbols for e in exprs)), key=sp.default_sort_key))
        try:
            cache: dict[sp.Expr, Any] = {}
            return exact, [exact.normal(exact._element(e, cache)) for e in exprs]
        except _NotInRing as e:  # not a polynomial over ℚ in these symbols (a Float, a root, π, a sum in a denominator …)
            if not general:
                raise sp.PolynomialError(str(e)) from None
        ring = cls(args)
        return ring, [sp.Poly(e.xreplace(ring.fwd), *ring.gens) for e in exprs]

    def _element(self, e: sp.Expr, cache: dict) -> Any:
        """``e`` in ℚ[c, s, symbols, reciprocals], built from its tree (``_NotInRing`` where it is not in it)."""
        hit = cache.get(e)
        if hit is not None:
            return hit
        ring = self.ring
        if e in self._element_of:
            out = self._element_of[e]
        elif e.is_Add:
            out = ring.zero
            for a in e.args:
                out = out + self._element(a, cache)
        elif e.is_Mul:
            out = ring.one
            for a in e.args:
                out = out * self._element(a, cache)
        elif e.is_Pow and e.exp.is_Integer:
            if e.exp >= 0:
                out = self._element(e.base, cache) ** int(e.exp)
            elif e.base in self._reciprocal_of:
                out = self._reciprocal_of[e.base] ** int(-e.exp)
            else:
                raise _NotInRing(f"a denominator {e.base} that is not a symbol")
        elif e.is_Rational:  # not a Float: ℚ would silently make it rational
            out = ring.ground_new(sp.QQ(int(e.p), int(e.q)))
        else:
            raise _NotInRing(f"not a polynomial over the rationals: {e}")
        cache[e] = out
        return out

    def _terms(self, p: Any) -> dict:
        return dict(p.items()) if self.ring is not None else dict(p.terms())

    def normal(self, p: Any) -> Any:
        """``p`` with each x^a inv_x^b written as x^(a−b) or inv_x^(b−a) (like terms then combine)."""
        if not self._pairs:
            return p
        out: dict[tuple[int, ...], Any] = {}
        for monom, coeff in self._terms(p).items():
            m = list(monom)
            for i, j in self._pairs:
                common = min(m[i], m[j])
                m[i] -= common
                m[j] -= common
            key = tuple(m)
            out[key] = out[key] + coeff if key in out else coeff
        return self.ring.from_dict({m: c for m, c in out.items() if c})

    def has_trig(self, p: Any) -> bool:
        """Whether ``p`` has a term with a c_k or s_k."""
        n = 2 * len(self.args)
        return any(any(m[:n]) for m in self._terms(p))

    def reduce(self, p: Any) -> Any:
        """The normal form of ``p``: each c_k^(2q+r) replaced by c_k^r (1 − s_k²)^q, expanded binomially."""
        p = self.normal(p)
        pairs = len(self.args)
        terms = self._terms(p)
        if not any(m[2 * k] > 1 for m in terms for k in range(pairs)):
            return p
        out: dict[tuple[int, ...], Any] = {}
        for monom, coeff in terms.items():
            expansion = [((), 1)]
            for k in range(pairs):
                q, r = divmod(monom[2 * k], 2)
                ks = monom[2 * k + 1]
                factors = [((r, ks + 2 * j), (-1) ** j * math.comb(q, j)) for j in range(q + 1)]
                expansion = [(m + m2, f * f2) for m, f in expansion for m2, f2 in factors]
            rest = monom[2 * pairs:]
            for m, f in expansion:
                m = m + rest
                out[m] = out[m] + coeff * f if m in out else coeff * f
        out = {m: c for m, c in out.items() if c}
        if self.ring is not None:
            return self.ring.from_dict(out)
        return sp.Poly.from_dict(out or {(0,) * len(self.gens): 0}, *self.gens, domain=p.domain)

    def expanded(self, p: Any) -> sp.Expr:
        """``p`` as an expanded SymPy expression in sines and cosines."""
        e = p.as_expr() if self.ring is not None else sp.expand(p.as_expr())
        return e.xreplace(self.back)

    def expr(self, p: Any) -> sp.Expr:
        """``p`` back in sines and cosines, expanded, with common factors pulled out (``factor_terms``)."""
        return sp.factor_terms(self.expanded(p))

    def tidy(self, p: Any) -> tuple[Any, sp.Expr]:
        """(the polynomial, the expression) of :func:`_tidy`: reduced and ``factor_terms``-ed if it has a sine or
        cosine, else only expanded."""
        p = self.normal(p)
        if not self.has_trig(p):
            return p, self.expanded(p)
        p = self.reduce(p)
        return p, self.expr(p)

    def diff(self, p: Any, x: sp.Symbol) -> Any:
        """∂p/∂x in the exact ring: through x, its reciprocal (∂(1/x)/∂x = −1/x²) and every c_k, s_k
        (∂c_k/∂x = −s_k ∂a_k/∂x, ∂s_k/∂x = c_k ∂a_k/∂x); ``_NotInRing`` if some ∂a_k/∂x is not in the ring."""
        ring = self.ring
        x_gen, inv = self._element_of[x], self._reciprocal_of[x]
        out = p.diff(x_gen) - inv**2 * p.diff(inv)
        gens = ring.gens
        for k, a in enumerate(self.args):
            da = sp.diff(a, x)
            if da != 0:
                c, s = gens[2 * k], gens[2 * k + 1]
                out += self._element(da, {}) * (c * p.diff(s) - s * p.diff(c))
        return self.normal(out)

    def substitute(self, expr: sp.Expr, values: Mapping[sp.Symbol, Any]) -> Any:
        """The polynomial ``expr`` in the symbols of ``values`` evaluated at those ring elements."""
        cache: dict[sp.Expr, Any] = dict(values)
        return self.normal(self._element(expr, cache))

    def degree_in(self, p: Any, gens: Sequence[Any]) -> tuple[int, int]:
        """(lowest, highest) total degree of the terms of ``p`` in the generators ``gens`` (elements)."""
        where = [self.ring.gens.index(g) for g in gens]
        degrees = [sum(m[i] for i in where) for m in p.keys()] or [0]
        return min(degrees), max(degrees)

    def coefficient(self, p: Any, gen: Any) -> Any:
        """The coefficient of the generator ``gen`` (an element) in ``p``, linear in it."""
        i = self.ring.gens.index(gen)
        out = {m[:i] + (0,) + m[i + 1:]: c for m, c in p.items() if m[i] == 1}
        return self.ring.from_dict(out)

    def cancel(self, p: Any, q: Any) -> tuple[Any, Any]:
        """p/q with the common polynomial factors of p and q divided out (a unit normalises q)."""
        return p.cancel(q) if self.ring is not None else p.cancel(q, include=True)


def _tidy(expr: sp.Expr) -> sp.Expr:
    """A shorter, equal form of a polynomial in sines and cosines: reduced modulo cos² + sin² = 1.

    The exact normal form of :mod:`mechderive.core.simplify` (cos x, sin x → c, s; reduce by
    c² + s² − 1), without its rational-function steps, which are slow on the long sums of
    (3.93)–(3.94).  Anything else (denominators, other functions) is only expanded.  The same
    expression as expanding, reducing with ``sympy.reduced`` (basis c² + s² − 1, lex order) and
    ``factor_terms``, computed with :class:`_TrigPolynomials`.
    """
    try:
        ring, (p,) = _TrigPolynomials.convert([expr])
    except sp.PolynomialError:
        return sp.expand(expr)
    return ring.tidy(p)[1]


class DeformableBody(SymbolicModel):
    """Point masses m_i at r̃_i(x^1 … x^n): Ĩ (3.93), L̃ (3.94), Ω (3.92), Ω_A (3.87), F_AB (3.102)–(3.103).

    Parameters
    ----------
    masses
        N masses (SymPy expressions or numbers), not known to be non-positive.
    positions
        N representative positions r̃_i, each 3 SymPy expressions of ``coordinates`` and
        ``parameters``, with Σ m_i r̃_i = 0 for every shape (checked exactly on polynomials in sines
        and cosines, else at random points with 30-digit arithmetic; see :func:`centred_positions`).
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
        self._twin_polynomials()
        self._check_centre_of_mass()

    def _twin_polynomials(self) -> None:
        """The masses and positions (and the shape velocities) as elements of one exact ring, if they are in it.

        Where every mass and position is a polynomial over ℚ in sines, cosines, the symbols and their
        reciprocals, the derived quantities are computed on these *twins* — sparse polynomials, multiplied
        and reduced exactly (:class:`_TrigPolynomials`) — and written as expressions once, the same
        expressions as expanding and :func:`_tidy`-ing SymPy sums (5–10× slower).  ``self._twin`` maps a
        quantity's name to its twin; ``self._ring`` is None (and the expressions are used) otherwise.
        """
        self._ring: _TrigPolynomials | None = None
        self._twin: dict[str, Any] = {}
        n = len(self.masses)
        try:  # the coordinates too: a generator of the ring (for ∂/∂x^A) even if no position has x^A
            ring, polys = _TrigPolynomials.convert(
                [*self.masses, *(c for r in self.positions for c in r), *self.velocities, *self.coordinates],
                general=False)
        except sp.PolynomialError:
            return
        self._ring = ring
        self._twin["masses"] = polys[:n]
        self._twin["positions"] = [polys[n + 3 * i: n + 3 * i + 3] for i in range(n)]
        self._twin["velocities"] = polys[4 * n: 4 * n + self.dimension]

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
        if self._ring is not None:  # exactly: Σ m_i r̃_i reduces to the zero polynomial
            ring, ms, rs = self._ring, self._twin["masses"], self._twin["positions"]
            if not any(ring.reduce(sum((m * r[a] for m, r in zip(ms, rs)), ring.ring.zero)) for a in range(3)):
                return
        # Otherwise (and to report a non-zero sum, or one zero only by identities between different angles):
        # each mass and position evaluated once at three random points, to 30 digits and summed there:
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
        if self._ring is None:
            return tuple(r.applyfunc(_tidy) for r in self.positions)
        tidied = [[self._ring.tidy(c) for c in r] for r in self._twin["positions"]]
        self._twin["reduced_positions"] = [[p for p, _ in r] for r in tidied]
        return tuple(sp.Matrix([e for _, e in r]) for r in tidied)

    @derived
    def position_jacobians(self) -> tuple[sp.Matrix, ...]:
        """∂r̃_i/∂x^A, one 3×n matrix per mass."""
        reduced = self.reduced_positions
        if self._ring is not None:
            try:
                ring = self._ring
                tidied = [[[ring.tidy(ring.diff(c, x)) for x in self.coordinates] for c in r]
                          for r in self._twin["reduced_positions"]]
            except _NotInRing:  # an angle whose derivative is not a polynomial (cos √x): differentiate expressions
                pass
            else:
                self._twin["position_jacobians"] = [[[p for p, _ in row] for row in J] for J in tidied]
                return tuple(sp.Matrix([[e for _, e in row] for row in J]) for J in tidied)
        xs = sp.Matrix(self.coordinates)
        return tuple(r.jacobian(xs).applyfunc(_tidy) for r in reduced)

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

    def _per_mass_twin(self, expr: sp.Matrix, rates: Sequence[Sequence[Any]] | None = None) -> list[tuple[Any, sp.Expr]]:
        """:meth:`_per_mass` on the twins, each entry tidied: [(polynomial, expression)] in row-major order."""
        d = derivation.model()
        names = [state_symbol(f"rtilde{a}") for a in (1, 2, 3)]
        dots = [state_symbol(f"rtilde{a}_dot") for a in (1, 2, 3)]
        ring = self._ring
        totals = [ring.ring.zero] * len(expr)
        for i, (m, r) in enumerate(zip(self._twin["masses"], self._twin["reduced_positions"])):
            values = {d.mass: m, **dict(zip(names, r))}
            if rates is not None:
                values.update(zip(dots, rates[i]))
            for k, e in enumerate(expr):
                totals[k] += ring.substitute(e, values)
        return [ring.tidy(p) for p in totals]

    @derived
    def inertia_tensor(self) -> sp.Matrix:
        """Ĩ_ab(x) (3.93): Σ_i of the per-mass inertia −∂(R⁻¹L)/∂v of :mod:`.derivation`."""
        per_mass = derivation.model().inertia_per_mass
        if self._ring is None:
            return self._per_mass(per_mass).applyfunc(_tidy)
        _ = self.reduced_positions  # derived (and logged) with the twins used here
        tidied = self._per_mass_twin(per_mass)
        self._twin["inertia_tensor"] = [p for p, _ in tidied]
        return sp.Matrix(3, 3, [e for _, e in tidied])

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
        jacobians = self.position_jacobians
        twins = self._twin.get("position_jacobians")
        if twins is None:
            for A, xdot in enumerate(self.velocities):
                coeff = self._per_mass(per_mass, [J.col(A) for J in jacobians]).applyfunc(_tidy)
                total += coeff * xdot
            return total
        twin, coefficients = [self._ring.ring.zero] * 3, []
        for A, (xdot, rate) in enumerate(zip(self.velocities, self._twin["velocities"])):
            tidied = self._per_mass_twin(per_mass, [[row[A] for row in J] for J in twins])
            total += sp.Matrix([e for _, e in tidied]) * xdot
            twin = [t + p * rate for t, (p, _) in zip(twin, tidied)]
            coefficients.append([e for _, e in tidied])
        self._twin["apparent_angular_momentum"] = twin
        self._twin["apparent_momentum_coefficients"] = coefficients  # L̃_A, expressions (connection_vectors)
        return total

    # ------------------------------------------------------------------ gauge potential
    @derived
    def angular_velocity_vector(self) -> sp.Matrix:
        """v(x, ẋ) with Ω = hat(v): the general solution of L = 0 of :mod:`.derivation` at this Ĩ, L̃ (3.92).

        The general solution is v_a = N_a(Ĩ, L̃)/D_a(Ĩ), N_a and D_a polynomials (D_a = det Ĩ).  For a body
        whose Ĩ and L̃ have polynomial twins (:meth:`_twin_polynomials`) each component is written in the
        shorter of two equal forms:

        * *expanded*: N_a and D_a evaluated on the twins — products taken exactly and reduced modulo
          cos² + sin² = 1 — with their common factors cancelled (e.g. for the cat, whose Ĩ is
          block-diagonal, v_1 = L̃_1/Ĩ_11; for a body turned by S(x), whose products collapse);
        * *factored*: N_a(Ĩ, L̃)/D_a(Ĩ) with the entries of Ĩ and L̃ put in as they are, when expanding
          would multiply out long sums (several independent angles) into more terms than that.

        Otherwise the entries are substituted into the general solution as it stands.  Either way the
        same function of x and ẋ as substituting into the general solution.
        """
        from ...inertia.tensor import general_inertia_symbols

        general = vee(derivation.model().angular_velocity_solution)
        I, Lt = general_inertia_symbols(), apparent_momentum_symbols()
        Itilde, Ltilde = self.inertia_tensor, self.apparent_angular_momentum
        values = {I[a, b]: Itilde[a, b] for a in range(3) for b in range(a, 3)}
        if "apparent_angular_momentum" not in self._twin:  # not polynomials: substitute into the solution
            if _tidy(Itilde.det()) == 0:
                raise InvalidInputError(_SINGULAR)
            values.update(zip(Lt, Ltilde))
            return general.subs(values, simultaneous=True)
        ring = self._ring
        at = {I[a, b]: self._twin["inertia_tensor"][3 * a + b] for a in range(3) for b in range(a, 3)}
        at.update(zip(Lt, self._twin["apparent_angular_momentum"]))

        def terms(e: sp.Expr) -> int:  # the number of terms e has when written with the twins' entries
            return sum(sum(k * len(at[x]) for x, k in zip(at, m)) or 1 for m in sp.Poly(e, *at).monoms())

        parts, out = [], []
        for e in general:
            num, den = sp.fraction(sp.together(e))
            if den.free_symbols & set(Lt) or any(sum(m) != 1 for m in sp.Poly(num, *Lt).monoms()):
                raise DerivationError("expected the solution Ω of L = 0 linear in L̃, with a denominator free of L̃")
            det = ring.reduce(ring.substitute(den, at))
            if not det:
                raise InvalidInputError(_SINGULAR)
            p, q = ring.cancel(ring.reduce(ring.substitute(num, at)), det)
            if len(p) + len(q) <= terms(num) + terms(den):
                # a factor of det Ĩ divided out, not only a constant
                self._twin["cancelled"] = self._twin.get("cancelled", False) or q * det.LC != det * q.LC
                parts.append(("expanded", p, q))
                # not factor_terms-ed: on these sums it costs more than it shortens (−1 % of the operations)
                out.append(ring.expanded(p) / ring.expanded(q))
            else:
                parts.append(("factored", num, den))
                out.append(num.xreplace(dict(zip(Lt, Ltilde))).xreplace(values) / den.xreplace(values))
        self._twin["angular_velocity_vector"] = parts  # what connection_vectors reads ∂v/∂ẋ^A from
        return sp.Matrix(out)

    @property
    def cancels_singular_factors(self) -> bool:
        """Whether Ω (:attr:`angular_velocity_vector`, hence Ω_A) had factors of det Ĩ cancelled, so that it may
        stay finite where Ĩ is singular; then :meth:`.connection.ShapeConnection.connection` checks det Ĩ at
        every shape, not only where Ω_A is not finite.  True before Ω is derived."""
        if not self.is_derived("angular_velocity_vector"):
            return True
        return bool(self._twin.get("cancelled", False))

    @derived
    def angular_velocity(self) -> sp.Matrix:
        """Ω(x, ẋ) = hat(v), Ω_ab = ε_abc v_c (3.92): the convective angular velocity at L = 0."""
        return hat(self.angular_velocity_vector)

    @derived
    def connection_vectors(self) -> sp.Matrix:
        """Row A: the vector of Ω_A(x) = ∂Ω/∂ẋ^A (3.87); checked that Ω = Ω_A ẋ^A exactly.

        Ω is linear in ẋ because ∂Ω/∂ẋ^A contains no ẋ and Ω vanishes at ẋ = 0.  For the components of v
        kept in the forms of :attr:`angular_velocity_vector`, ∂v_a/∂ẋ^A is read off exactly: *expanded*,
        v_a = p_a/q_a with q_a free of ẋ and every term of p_a of degree one in ẋ (checked, the same two
        conditions), the coefficient of ẋ^A in p_a over q_a; *factored*, v_a = N_a(Ĩ, L̃)/D_a(Ĩ) with N_a
        linear in L̃ (checked there) and L̃ = L̃_A ẋ^A, N_a(Ĩ, L̃_A)/D_a(Ĩ).
        """
        v = self.angular_velocity_vector
        parts = self._twin.get("angular_velocity_vector")
        if parts is None:
            rows = v.jacobian(sp.Matrix(self.velocities)).T
            if rows.free_symbols & set(self.velocities):
                raise DerivationError("expected ∂Ω/∂ẋ^A to be independent of ẋ (Ω linear in ẋ, (3.87))")
            if any(e != 0 for e in v.subs({s: 0 for s in self.velocities})):
                raise DerivationError("expected Ω = 0 at ẋ = 0 (no shape change, no rotation)")
            return rows
        from ...inertia.tensor import general_inertia_symbols

        I, Lt = general_inertia_symbols(), apparent_momentum_symbols()
        values = {I[a, b]: self.inertia_tensor[a, b] for a in range(3) for b in range(a, 3)}
        coefficients = self._twin["apparent_momentum_coefficients"]
        ring, rates = self._ring, self._twin["velocities"]
        rows = sp.zeros(self.dimension, 3)
        for a, (form, p, q) in enumerate(parts):
            if form == "factored":
                for A, coefficient in enumerate(coefficients):
                    rows[A, a] = p.xreplace(dict(zip(Lt, coefficient))).xreplace(values) / q.xreplace(values)
                continue
            if ring.degree_in(q, rates) != (0, 0):
                raise DerivationError("expected the denominator of Ω to be independent of ẋ")
            if p and ring.degree_in(p, rates) != (1, 1):
                raise DerivationError("expected Ω linear in ẋ and Ω = 0 at ẋ = 0 (no shape change, no rotation)"
                                      " (3.87)")
            den = ring.expanded(q)
            for A, rate in enumerate(rates):
                rows[A, a] = ring.expanded(ring.coefficient(p, rate)) / den
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
