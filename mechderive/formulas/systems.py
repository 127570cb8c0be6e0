"""Each system's named symbols for ``mechderive check``, their definitions and time derivatives.

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

>>> heavy = get_system("heavy_top")
>>> heavy.symbol("u_dot") in heavy.names.values()
True
>>> heavy.definition(heavy.symbol("u_dot"))
-theta_dot*sin(theta)
>>> free = get_system("free_top")
>>> sp.expand(free.motion_dt(free.definition(free.symbol("T"))))   # (3.46): T is conserved
0
"""

from __future__ import annotations

import functools
import math
import random
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Callable, Iterable, Mapping

import sympy as sp

from ..core.symbols import as_symbolic, state_symbol
from ..errors import InvalidInputError

__all__ = ["Quantity", "BodyRegion", "System", "get_system", "SYSTEMS"]

_SUFFIX = {0: "", 1: "_dot", 2: "_ddot"}


def _jet_name(base: str, order: int) -> str:
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


def _decimal4(rng: random.Random, low: float, high: float) -> Fraction:
    """A uniform draw in (low, high) as an exact 4-decimal fraction (so that it prints exactly)."""
    return Fraction(f"{rng.uniform(low, high):.4f}")


def _ceil4(x: Fraction) -> Fraction:
    return Fraction(math.ceil(x * 10_000), 10_000)


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
        base = next(b for b in self.coordinates if sym == state_symbol(_jet_name(b, k)))
        nxt = state_symbol(_jet_name(base, k + 1))
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


# --- the heavy symmetric top (3.62)-(3.83) -------------------------------------------------------


def _draw_heavy_top(rng: random.Random) -> dict[str, Fraction]:
    """I3, M, g, l > 0 and a slack s > 0, then I1 = M l² + I3/2 + s (rounded up): always a real top."""
    I3, M, g = (_decimal4(rng, 0.5, 2.5) for _ in range(3))
    l = _decimal4(rng, 0.2, 1.2)
    slack = _decimal4(rng, 0.05, 1.5)
    return {"I1": _ceil4(M * l * l + I3 / 2 + slack), "I3": I3, "M": M, "g": g, "l": l}


def _heavy_top_refusal(values: Mapping[str, float]) -> str | None:
    from ..systems.heavy_top.parameters import check_params

    try:
        check_params(dict(values))
    except InvalidInputError as exc:
        return str(exc)
    if not all(values[k] > 0 for k in ("M", "g", "l")):
        return "expected M, g, l > 0 (a heavy top), got " + ", ".join(f"{k} = {values[k]:g}" for k in "Mgl")
    return None


_HEAVY_TOP_REGION = BodyRegion(
    parameters=("I1", "I3", "M", "g", "l"),
    condition="a real top: I1, I3, M, g, l > 0 and I1 ≥ M l² + I3/2, the triangle inequality about the "
              "centre of mass that the solvers require",
    draw=_draw_heavy_top,
    refusal=_heavy_top_refusal,
    widths=(1.0, 1.45),  # l and the slack: the narrowest independent draws
)


def _heavy_top() -> System:
    from ..kinematics import euler as _euler
    from ..systems.heavy_top import model as ht

    m = ht.model
    theta = state_symbol("theta")

    def const(key: sp.Symbol) -> Callable[[System], sp.Expr]:
        return lambda s: m().constants_from_state[key]

    def omega(a: int) -> Callable[[System], sp.Expr]:
        return lambda s: _euler.model().state_angular_velocity_body[a]

    meanings = {
        "phi": "φ, precession angle (Euler angles (3.54))", "theta": "θ, nutation angle from the upward vertical",
        "psi": "ψ, spin angle", "phi_dot": "φ̇", "theta_dot": "θ̇", "psi_dot": "ψ̇",
        "phi_ddot": "φ̈ (fixed by the equations of motion on a motion)",
        "theta_ddot": "θ̈ (fixed by the equations of motion on a motion)",
        "psi_ddot": "ψ̈ (fixed by the equations of motion on a motion)",
    }
    qs: list[Quantity] = [Quantity(n, state_symbol(n), "derivative" if n.endswith("_ddot") else "state", text)
                          for n, text in meanings.items()]
    qs += [
        Quantity("I1", ht.I1, "parameter", "moment of inertia about e1 = e2 through the fixed point P"),
        Quantity("I3", ht.I3, "parameter", "moment of inertia about the symmetry axis e3"),
        Quantity("M", ht.M, "parameter", "mass"),
        Quantity("g", ht.g, "parameter", "gravitational acceleration"),
        Quantity("l", ht.l, "parameter", "distance from P to the centre of mass"),
    ]
    qs += [Quantity(f"omega{a + 1}", state_symbol(f"omega{a + 1}"), "defined",
                    f"body component ω{a + 1} of the angular velocity (3.58), derived from ṘRᵀ", omega(a))
           for a in range(3)]
    qs += [
        Quantity("p_psi", ht.p_psi, "defined", "p_ψ = ∂L/∂ψ̇ (3.63), conserved", lambda s: m().spin_momentum),
        Quantity("p_phi", ht.p_phi, "defined", "p_φ = ∂L/∂φ̇ (3.64), conserved",
                 lambda s: m().azimuthal_momentum),
        Quantity("T", sp.Symbol("T", real=True), "defined", "kinetic energy ½ωᵀIω",
                 lambda s: m().kinetic_energy),
        Quantity("V", sp.Symbol("V", real=True), "defined", "potential energy M g l cos θ",
                 lambda s: m().potential_energy),
        Quantity("Lagrangian", sp.Symbol("Lagrangian", real=True), "defined", "L = T − V (3.62)",
                 lambda s: m().state_lagrangian),
        Quantity("E", sp.Symbol("E", real=True), "defined", "energy T + V (3.65), conserved",
                 lambda s: m().energy),
        Quantity("E_prime", sp.Symbol("E_prime", real=True), "defined", "E' = E − ½ I3 ω3² (3.69)",
                 lambda s: m().reduced_energy_state),
        Quantity("a", ht.a, "defined", "a = I3 ω3 / I1 (3.66)", const(ht.a)),
        Quantity("b", ht.b, "defined", "b = p_φ / I1 (3.66)", const(ht.b)),
        Quantity("alpha", ht.alpha, "defined", "α = 2E'/I1 (3.72)", const(ht.alpha)),
        Quantity("beta", ht.beta, "defined", "β = 2 M g l / I1 (3.72)", const(ht.beta)),
        Quantity("u", ht.u, "defined", "u = cos θ (3.71)", lambda s: sp.cos(theta)),
        Quantity("u_dot", state_symbol("u_dot"), "defined", "u̇ = dt(u) = −sin θ θ̇",
                 lambda s: s.formal_dt(s.definition(ht.u))),
        Quantity("u_ddot", state_symbol("u_ddot"), "defined", "ü = dt(u_dot)",
                 lambda s: s.formal_dt(s.definition(state_symbol("u_dot")))),
    ]
    return System(
        name="heavy_top",
        summary="heavy symmetric top (3.62)-(3.83): Euler angles, θ from the upward vertical, I1 = I2 about P",
        coordinates=("phi", "theta", "psi"),
        order=2,
        highest=lambda: m().acceleration_map,
        quantities=qs,
        domain={"theta": (0.15, math.pi - 0.15), "phi": (-3.0, 3.0), "psi": (-3.0, 3.0)},
        region=_HEAVY_TOP_REGION,
        hints={
            "I2": "the heavy top is symmetric: I2 = I1",
            "L": "the Lagrangian is called Lagrangian",
            "omega": "the body components are omega1, omega2, omega3",
            "E_p": "E' is E_prime",
            "Omega": "define it with --given, e.g. --given 'Omega = phi_dot'",
        },
    )


# --- the free rigid body (3.33)-(3.49) -----------------------------------------------------------


def _draw_free_top(rng: random.Random) -> dict[str, Fraction]:
    """Second moments A = Σ m x², B = Σ m y², C = Σ m z² > 0, then I1 = B + C, I2 = C + A, I3 = A + B.

    Every such triple is a real body (I1 + I2 − I3 = 2C > 0 and cyclically) and every real body but
    a plate (C = 0) or a line has one, so the draw covers the region without rejecting any point.
    """
    A, B, C = (_decimal4(rng, 0.05, 1.25) for _ in range(3))
    return {"I1": B + C, "I2": C + A, "I3": A + B}


def _free_top_refusal(values: Mapping[str, float]) -> str | None:
    from ..inertia.validate import check_principal_moments

    try:
        check_principal_moments(values["I1"], values["I2"], values["I3"])
    except InvalidInputError as exc:
        return str(exc)
    return None


_FREE_TOP_REGION = BodyRegion(
    parameters=("I1", "I2", "I3"),
    condition="a real body: I1, I2, I3 > 0 and I1 + I2 ≥ I3, I2 + I3 ≥ I1, I3 + I1 ≥ I2, the triangle "
              "inequalities that the solvers require",
    draw=_draw_free_top,
    refusal=_free_top_refusal,
    widths=(1.2,),
)


def _free_top() -> System:
    from ..systems.free_top import model as ft

    m = ft.model
    qs: list[Quantity] = []
    for k, what in ((0, "body component ω{a} of the angular velocity (principal axes)"),
                    (1, "dω{a}/dt (fixed by Euler's equations (3.33) on a motion)"),
                    (2, "d²ω{a}/dt² (fixed by Euler's equations on a motion)")):
        for a in (1, 2, 3):
            name = _jet_name(f"omega{a}", k)
            qs.append(Quantity(name, state_symbol(name), "state" if k == 0 else "derivative", what.format(a=a)))
    qs += [Quantity(f"I{a}", s, "parameter", f"principal moment of inertia about e{a}")
           for a, s in zip((1, 2, 3), (ft.I1, ft.I2, ft.I3))]
    qs += [
        Quantity("T", sp.Symbol("T", real=True), "defined", "kinetic energy ½ Σ I_a ω_a² (3.46), conserved",
                 lambda s: m().energy),
        Quantity("Lsq", sp.Symbol("Lsq", real=True), "defined",
                 "L² = Σ I_a² ω_a² (3.47), conserved (the components L_a are I_a*omega_a)",
                 lambda s: m().angular_momentum_squared),
    ]
    torque_free = {t: 0 for t in ft.tau_symbols}

    def highest() -> dict:
        rhs = m().euler_rhs.xreplace(torque_free)
        return {state_symbol(f"omega{a + 1}_dot"): rhs[a] for a in range(3)}

    lsq = "L² is Lsq; the body components L_a are I1*omega1, I2*omega2, I3*omega3"
    euler_angles = "the free top's state is omega1, omega2, omega3 (Euler angles belong to heavy_top)"
    return System(
        name="free_top",
        summary="free rigid body in principal axes (3.33): Euler's equations without torque",
        coordinates=("omega1", "omega2", "omega3"),
        order=1,
        highest=highest,
        quantities=qs,
        domain={},
        region=_FREE_TOP_REGION,
        hints={"L": lsq, "L2": lsq, "L1": lsq, "L3": lsq, "L_sq": lsq, "E": "the energy of the free top is T",
               "theta": euler_angles, "phi": euler_angles, "psi": euler_angles,
               "Omega": "define it with --given, e.g. --given 'Omega = omega3*(I1 - I3)/I1'"},
    )


#: The systems ``mechderive check`` knows, by name.
SYSTEMS: dict[str, Callable[[], System]] = {"heavy_top": _heavy_top, "free_top": _free_top}


@functools.cache
def get_system(name: str) -> System:
    """The system called ``name`` (its symbol table is cheap; definitions are derived on first use)."""
    if name not in SYSTEMS:
        raise InvalidInputError(f"expected a system among {', '.join(sorted(SYSTEMS))}, got {name!r}")
    return SYSTEMS[name]()
