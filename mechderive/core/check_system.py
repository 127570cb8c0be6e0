"""A system's named symbols for ``mechderive check``: the type each system's ``check_system()`` returns.

Below the systems (each builds one in its ``derive_entries.check_system()``); the ``check``
machinery of :mod:`mechderive.formulas` reads it.  Re-exported by :mod:`mechderive.formulas.systems`.

A system names four kinds of symbols:

- **state**: the variables a motion gives values to at each instant (heavy top: the Euler angles
  and their rates; free top: the body components ω1, ω2, ω3);
- **derivatives**: time derivatives of the state beyond it (heavy top: ``theta_ddot`` …; free top:
  ``omega1_dot``, ``omega1_ddot`` …) — free variables in an identity, fixed by the equations of
  motion on a motion;
- **parameters**: constants of the body (moments of inertia, M g l);
- **defined** quantities: a name for a function of the state and the parameters, *derived* from
  the system's model (never typed in here), e.g. the heavy top's a := I3 ω3 / I1 (3.66) with
  ω3 from (3.58), or E := the energy (3.65).  A claim is decided after every defined name is
  replaced by its definition.

Real bodies.  A system's :class:`BodyRegion` states which parameter values a real body has (the
solvers' own validators decide) and draws values inside that region by a parametrisation of
every real body (free top: I1 = B + C, I2 = C + A, I3 = A + B from the second moments A, B,
C > 0; heavy top: I1 = M l² + I3/2 + a slack > 0); ``check`` samples there by default.

Time derivatives.  A system's state has a jet: q → q_dot → q_ddot → q_d3 … (formal symbols).
:meth:`System.formal_dt` is the chain rule over that jet (every derivative an independent
variable: what an *identity* must survive); :meth:`System.motion_dt` is the derivative along
the flow of the equations of motion (accelerations from the model's Euler–Lagrange equations,
or ω̇ from Euler's equations): what an *on-shell* claim needs.
The heavy and free tops build theirs in ``mechderive/systems/*/derive_entries.py``.
"""

from __future__ import annotations

import functools
import math
import random
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Callable, Iterable, Mapping

import sympy as sp

from ..errors import InvalidInputError
from .symbols import as_symbolic, state_symbol

__all__ = ["Quantity", "BodyRegion", "RigidBody", "System", "jet_name", "decimal4", "ceil4"]

_SUFFIX = {0: "", 1: "_dot", 2: "_ddot"}


def jet_name(base: str, order: int) -> str:
    return base + _SUFFIX.get(order, f"_d{order}")


@dataclass(frozen=True)
class Quantity:
    """One named symbol of a system: its kind (state, derivative, parameter, defined) and meaning."""

    name: str
    symbol: sp.Symbol
    kind: str
    meaning: str
    define: Callable[["System"], sp.Expr] | None = None


@dataclass(frozen=True)
class BodyRegion:
    """The parameters of a real body, as the solvers accept them: where ``check`` draws them by default.

    ``draw(rng)`` gives exact values (4-decimal fractions) strictly inside the region *by
    construction*, from a parametrisation of every real body, never by rejecting draws;
    ``refusal(values)`` is the solvers' own validator, returning its message or None;
    ``condition`` states the region; ``widths`` are the widths of the independently drawn
    variables of the parametrisation (for the false-positive bound).
    """

    parameters: tuple[str, ...]
    condition: str
    draw: Callable[[random.Random], dict[str, Fraction]]
    refusal: Callable[[Mapping[str, float]], str | None]
    widths: tuple[float, ...]


def decimal4(rng: random.Random, low: float, high: float) -> Fraction:
    """A uniform draw in (low, high) as an exact 4-decimal fraction (so that it prints exactly)."""
    return Fraction(f"{rng.uniform(low, high):.4f}")


def ceil4(x: Fraction) -> Fraction:
    return Fraction(math.ceil(x * 10_000), 10_000)


@dataclass(frozen=True)
class RigidBody:
    """A rigid body about a fixed point O in uniform gravity, in a system's own parameter symbols.

    ``moments`` are the principal moments (I1, I2, I3) *about O* along the body axes e1, e2, e3;
    ``centre_of_mass`` its body components from O; gravity is −``gravity`` ẽ3 on the ``mass``, so
    V = M g ẽ3·(Rᵀ c) (0 where ``gravity`` is 0).  The orientation is the chapter's Euler angles
    (φ, θ, ψ) (3.54).  :func:`mechderive.interop.to_mechanics` builds this body in
    :mod:`sympy.physics.mechanics`.
    """

    moments: tuple
    centre_of_mass: tuple
    mass: sp.Expr
    gravity: sp.Expr


@dataclass
class System:
    """A system's symbols, the jet of its state and the flow of its equations of motion.

    ``coordinates`` are the base names of the jet; ``order`` is the order of the equations of
    motion (2: the state is q, q_dot; 1: the state is q); ``highest`` derives the on-shell value
    of each coordinate's ``order``-th derivative as {symbol: expression in the state}.
    """

    name: str
    summary: str
    coordinates: tuple[str, ...]
    order: int
    highest: Callable[[], dict]
    quantities: list[Quantity]
    domain: dict[str, tuple[float, float]]
    hints: dict[str, str] = field(default_factory=dict)
    region: BodyRegion | None = None
    #: how the flow is obtained, in the verdict of an on-shell claim ("ω̇ from Euler's equations …")
    motion: str = "the equations of motion"
    #: the rigid body about a fixed point this system is, for :mod:`mechderive.interop` (None: not one)
    body: RigidBody | None = None

    def __post_init__(self) -> None:
        self.names = {q.name: q.symbol for q in self.quantities}
        self.quantities_by_name = {q.name: q for q in self.quantities}
        self._by_symbol = {q.symbol: q for q in self.quantities}
        self._parent: dict[sp.Symbol, sp.Symbol] = {}
        self._child: dict[sp.Symbol, sp.Symbol] = {}
        self._order_of: dict[sp.Symbol, int] = {}
        for base in self.coordinates:
            self._order_of[state_symbol(base)] = 0
            self._jet(state_symbol(base), 2)  # the names a user can type: q, q_dot, q_ddot
        self._definitions: dict[sp.Symbol, sp.Expr] = {}
        self._on_shell: dict[sp.Symbol, sp.Expr] = {}

    # --- names -------------------------------------------------------------------------------

    def symbol(self, name: str) -> sp.Symbol:
        """The symbol called ``name`` (raises for an unknown name)."""
        if name not in self.names:
            raise InvalidInputError(f"expected a symbol of {self.name}, got {name!r}")
        return self.names[name]

    def quantity(self, sym: sp.Symbol) -> Quantity | None:
        return self._by_symbol.get(sym)

    def kind(self, sym: sp.Symbol) -> str:
        """'state', 'derivative', 'parameter', 'defined', or 'other' for a symbol of no name here."""
        q = self._by_symbol.get(sym)
        if q is not None:
            return q.kind
        return "derivative" if self._order(sym) is not None else "other"

    @property
    def state(self) -> tuple[sp.Symbol, ...]:
        """The state symbols: each coordinate's jet below ``order``."""
        return tuple(self._jet(state_symbol(b), k) for k in range(self.order) for b in self.coordinates)

    def sampling_range(self, sym: sp.Symbol) -> tuple[float, float]:
        """Where random values of ``sym`` are drawn: the system's range, else by the symbol's sign."""
        if sym.name in self.domain:
            return self.domain[sym.name]
        return (0.5, 2.5) if sym.is_positive else (-2.0, 2.0)

    # --- the jet -----------------------------------------------------------------------------

    def _order(self, sym: sp.Symbol) -> int | None:
        return self._order_of.get(sym)

    def _jet(self, base: sp.Symbol, order: int) -> sp.Symbol:
        sym = base
        for _ in range(order):
            sym = self.next_derivative(sym)
        return sym

    def next_derivative(self, sym: sp.Symbol) -> sp.Symbol | None:
        """The formal d/dt of a jet symbol (theta → theta_dot → theta_ddot → theta_d3 …), else None."""
        if sym in self._child:
            return self._child[sym]
        k = self._order(sym)
        if k is None:
            return None
        base = next(b for b in self.coordinates if sym == state_symbol(jet_name(b, k)))
        nxt = state_symbol(jet_name(base, k + 1))
        # _child last: it marks the entry complete, so an interruption in between (a time budget's
        # alarm) leaves a state that the next call completes
        self._parent[nxt], self._order_of[nxt] = sym, k + 1
        self._child[sym] = nxt
        return nxt

    def formal_dt(self, expr: sp.Expr) -> sp.Expr:
        """d/dt by the chain rule over the jet, every derivative an independent variable."""
        out = sp.Integer(0)
        for s in sorted(expr.free_symbols, key=sp.default_sort_key):
            nxt = self.next_derivative(s)
            if nxt is not None:
                out += expr.diff(s) * nxt
        return out

    # --- the motion --------------------------------------------------------------------------

    @functools.cached_property
    def flow(self) -> dict:
        """{state symbol: its time derivative on a motion}, in the state and the parameters."""
        acc = self.highest()
        out = {}
        for s in self.state:
            nxt = self.next_derivative(s)
            out[s] = acc[nxt] if self._order(nxt) == self.order else nxt
        return out

    def on_shell(self, expr: sp.Expr) -> sp.Expr:
        """``expr`` with every derivative beyond the state replaced by its value on a motion."""
        subs = {s: self._on_shell_value(s) for s in expr.free_symbols
                if (self._order(s) or 0) >= self.order}
        return expr.xreplace(subs) if subs else expr

    def _on_shell_value(self, sym: sp.Symbol) -> sp.Expr:
        if sym not in self._on_shell:
            k = self._order(sym)
            if k == self.order:
                self._on_shell[sym] = self.highest()[sym]
            else:
                self._on_shell[sym] = self.motion_dt(self._on_shell_value(self._parent[sym]))
        return self._on_shell[sym]

    def motion_dt(self, expr: sp.Expr) -> sp.Expr:
        """d/dt along a motion: Σ ∂expr/∂s · ṡ over the state s, with ṡ from the equations of motion."""
        expr = self.on_shell(expr)
        flow = self.flow
        return sum((expr.diff(s) * flow[s] for s in self.state if expr.has(s)), sp.Integer(0))

    # --- definitions -------------------------------------------------------------------------

    def definition(self, sym: sp.Symbol) -> sp.Expr:
        """The derived definition of a defined symbol, in the state (and its jet) and the parameters."""
        if sym not in self._definitions:
            q = self._by_symbol.get(sym)
            if q is None or q.define is None:
                raise InvalidInputError(f"expected a defined quantity of {self.name}, got {sym}")
            self._definitions[sym] = as_symbolic(q.define(self))
        return self._definitions[sym]

    def expand_definitions(self, expr: sp.Expr) -> sp.Expr:
        """``expr`` with every defined symbol replaced by its definition."""
        subs = {s: self.definition(s) for s in expr.free_symbols if self.kind(s) == "defined"}
        return expr.xreplace(subs) if subs else expr

    def prepare(self, names: Iterable[str]) -> None:
        """Derive now the definitions of the ``names`` that are defined quantities, and the flow of the
        equations of motion if any name is ``dt`` or a derivative beyond the state: the system's own
        fixed cost (up to about 4 s for all of the heavy top's, once per process), kept out of a
        claim's time budget."""
        names = set(names)
        for q in self.quantities:
            if q.kind == "defined" and q.name in names:
                self.definition(q.symbol)
        if "dt" in names or any(self.quantities_by_name[n].kind == "derivative" for n in names
                                if n in self.quantities_by_name):
            self.flow
            for s in self.state:
                if self._order(s) == self.order - 1:
                    self._on_shell_value(self.next_derivative(s))

    def describe(self) -> list[tuple[str, str, str]]:
        """(name, kind, meaning) of every symbol, in the listing order."""
        return [(q.name, q.kind, q.meaning) for q in self.quantities]


def from_lagrangian_model(name: str, summary: str, lagrangian: sp.Expr, positions: Iterable[sp.Symbol],
                          velocities: Iterable[sp.Symbol], parameters: Iterable[sp.Symbol]) -> System:
    """The ``check`` symbols of a system given by its Lagrangian in the state symbols (q, q_dot, parameters).

    The state is q, q_dot; q_ddot is fixed on a motion by the Euler–Lagrange equations (M q̈ = F,
    derived here); ``Lagrangian``, ``energy`` (h = Σ q̇ ∂L/∂q̇ − L) and each ``p_<q>`` = ∂L/∂q̇ are
    defined quantities.  What :meth:`mechderive.systems.base.System.check_system` gives by default for a
    system that offers :meth:`~mechderive.systems.base.System.lagrangian_model`.
    """
    from .lagrangian import _mass_and_forcing, _solve_accelerations

    L = as_symbolic(lagrangian)
    qs, vs, ps = tuple(positions), tuple(velocities), tuple(parameters)
    names = tuple(q.name for q in qs)

    @functools.cache
    def accelerations() -> dict:
        M, F = _mass_and_forcing(L, qs, vs)
        return dict(zip((state_symbol(n + "_ddot") for n in names), _solve_accelerations(M, F)))

    quantities = [Quantity(n, state_symbol(n), "state", f"coordinate {n}") for n in names]
    quantities += [Quantity(n + "_dot", state_symbol(n + "_dot"), "state", f"velocity of {n}") for n in names]
    quantities += [Quantity(n + "_ddot", state_symbol(n + "_ddot"), "derivative",
                            f"acceleration of {n} (fixed by the equations of motion on a motion)") for n in names]
    quantities += [Quantity(p.name, p, "parameter", "a parameter of the Lagrangian") for p in ps]
    quantities += [Quantity("Lagrangian", sp.Symbol("Lagrangian", real=True), "defined", "L", lambda s: L),
                   Quantity("energy", sp.Symbol("energy", real=True), "defined", "h = Σ q̇ ∂L/∂q̇ − L",
                            lambda s: sp.expand(sum(v * L.diff(v) for v in vs) - L))]
    quantities += [Quantity(f"p_{n}", sp.Symbol(f"p_{n}", real=True), "defined", f"p_{n} = ∂L/∂{n}_dot",
                            lambda s, v=v: L.diff(v)) for n, v in zip(names, vs)]
    return System(name=name, summary=summary, coordinates=names, order=2, highest=accelerations,
                  quantities=quantities, domain={}, motion="the Euler–Lagrange equations of L")
