"""The equations of motion of a :class:`~.definition.Definition`, derived from its Lagrangian.

From L(q, q̇, t) the generic :class:`~mechderive.core.lagrangian.LagrangianModel` derives the
Euler–Lagrange equations d/dt ∂L/∂q̇ − ∂L/∂q = 0, i.e. M(q, q̇, t) q̈ = b with the mass matrix
M = ∂²L/∂q̇∂q̇ and b = ∂L/∂q − (∂²L/∂q̇∂q) q̇ − ∂²L/∂q̇∂t; the momenta p = ∂L/∂q̇; the Jacobi
integral h = q̇·p − L (conserved when ∂L/∂t = 0: the energy when L = T − V with T quadratic).
A coordinate q_c with ∂L/∂q_c ≡ 0 (decided exactly: absent from L, or a trigonometric rational
∂L/∂q_c that reduces to 0) is cyclic and p_c is conserved.

q̈ = M⁻¹ b is obtained in one of two ways (:attr:`LagrangianEquations.solve_kind` says which):

* ``"symbolic"``, for n ≤ :data:`SYMBOLIC_MAX_N` coordinates and a Lagrangian of at most
  :data:`SYMBOLIC_MAX_OPS` operations (decided on L, so that no derivation is needed to know it
  once the code is compiled): SymPy's LU solve, each q̈_i simplified exactly
  (trigonometric normal form, factored) — the readable equations ``derive`` prints;
* ``"elimination"`` otherwise: M and b are left as derived and the LU elimination of M q̈ = b is
  generated unsimplified after them (pivots chosen on the structural zeros of M only); the
  generated code (C or NumPy, common subexpressions shared) evaluates the numbers of M and b at
  each step and eliminates them — a compiled numeric solve, O(n³) per step, with no symbolic
  inverse.  Without numeric pivoting this is the stable LDLᵀ elimination when M is definite (a
  kinetic energy); for an indefinite M a pivot may vanish where M does not: the initial state is
  refused then (:meth:`LagrangianEquations.pivot_function`), and a motion through such a state
  stops with an :class:`~mechderive.errors.IntegrationError`.
"""

from __future__ import annotations

import functools
import random
from typing import Any, Callable, Sequence

import numpy as np
import sympy as sp

from ...core.codecache import cached_lambdify
from ...core.lagrangian import LagrangianModel, from_state_symbols, vanishes
from ...core.model import SymbolicModel, derived
from ...core.simplify import is_zero
from ...core.symbols import coordinate, t as TIME
from ...solvers.driver import Term
from .definition import Definition

__all__ = ["LagrangianEquations", "equations", "SYMBOLIC_MAX_N", "SYMBOLIC_MAX_OPS", "CONDITION_LIMIT"]

#: Largest number of coordinates whose accelerations are solved for symbolically.
SYMBOLIC_MAX_N = 3
#: Largest Lagrangian (SymPy operation count) whose accelerations are solved for symbolically.
SYMBOLIC_MAX_OPS = 300
#: A mass matrix whose condition number exceeds this is refused as singular at that state: the
#: accelerations would lose all but ~4 of the 16 digits of a double.
CONDITION_LIMIT = 1e12


def _structural_zero(e: Any) -> bool:
    return e == 0


class LagrangianEquations(SymbolicModel):
    """The derived equations of one :class:`~.definition.Definition` (every quantity in the state symbols)."""

    def __init__(self, definition: Definition) -> None:
        super().__init__()
        #: the first definition of these dynamics (others differ only in their output expressions)
        self.definition = definition
        self.positions = definition.positions
        self.velocities = definition.velocities
        self.parameter_symbols = definition.dynamics_symbols
        self.functions = tuple(coordinate(q) for q in definition.coordinates)
        self.name = f"lagrangian_{definition.dynamics_digest}"

    # --- the derivation ------------------------------------------------------------------------

    @functools.cached_property
    def lagrangian_model(self) -> LagrangianModel:
        """The generic :class:`~mechderive.core.lagrangian.LagrangianModel` of L (coordinates as functions of t)."""
        return LagrangianModel(from_state_symbols(self.definition.lagrangian, self.functions), self.functions)

    @property
    def state_lagrangian(self) -> sp.Expr:
        return self.definition.lagrangian

    @property
    def euler_lagrange(self) -> sp.Matrix:
        """d/dt ∂L/∂q̇_i − ∂L/∂q_i (each = 0 on a motion), in functions of t."""
        return self.lagrangian_model.euler_lagrange

    @property
    def mass_matrix(self) -> sp.Matrix:
        """M = ∂²L/∂q̇∂q̇."""
        return self.lagrangian_model.mass_matrix

    @property
    def forcing(self) -> sp.Matrix:
        """b with M q̈ = b."""
        return self.lagrangian_model.forcing

    @property
    def momenta(self) -> sp.Matrix:
        """p = ∂L/∂q̇ (column, coordinate order)."""
        return self.lagrangian_model.momenta

    @property
    def energy(self) -> sp.Expr:
        """The Jacobi integral h = q̇·∂L/∂q̇ − L."""
        return self.lagrangian_model.energy_function

    @derived
    def cyclic(self) -> tuple[str, ...]:
        """The names of the cyclic coordinates: ∂L/∂q ≡ 0, decided exactly (undecided counts as not cyclic)."""
        L = self.definition.lagrangian
        out = []
        for name, q in zip(self.definition.coordinates, self.positions):
            if q not in L.free_symbols or is_zero(L.diff(q)) is True:
                out.append(name)
        return tuple(out)

    @functools.cached_property
    def solve_kind(self) -> str:
        """"symbolic" or "elimination": how q̈ = M⁻¹b is obtained (module docstring)."""
        if len(self.positions) > SYMBOLIC_MAX_N:
            return "elimination"
        return "symbolic" if sp.count_ops(self.definition.lagrangian) <= SYMBOLIC_MAX_OPS else "elimination"

    @derived
    def accelerations(self) -> sp.Matrix:
        """q̈ = M⁻¹ b (column, coordinate order), by the way :attr:`solve_kind` says."""
        if self.solve_kind == "symbolic":
            return self.lagrangian_model.accelerations
        return self.mass_matrix.LUsolve(self.forcing, iszerofunc=_structural_zero)

    @property
    def acceleration_map(self) -> dict:
        """{q_ddot: q̈(q, q̇)}."""
        return self.lagrangian_model.acceleration_map if self.solve_kind == "symbolic" else dict(
            zip(self.lagrangian_model.acceleration_symbols, self.accelerations))

    # --- what is compiled ----------------------------------------------------------------------

    @property
    def state(self) -> tuple[sp.Symbol, ...]:
        """The integrated state: q, q̇, and t where L depends on it (t' = 1)."""
        return (*self.positions, *self.velocities, *((TIME,) if self.definition.uses_time else ()))

    @property
    def conserved_names(self) -> tuple[str, ...]:
        """``energy`` (where ∂L/∂t = 0) and ``p_<q>`` of each cyclic coordinate."""
        return ((() if self.definition.uses_time else ("energy",))
                + tuple(f"p_{q}" for q in self.cyclic))

    @functools.cached_property
    def term(self) -> Term:
        """The driver's term: y = (q, q̇[, t]), y' = (q̇, q̈[, 1]); invariants energy, every p_c, and their scales."""
        names = ("energy", *(f"p_{q}" for q in self.cyclic))
        return Term(self.name, self._build, self._invariants,
                    (*names, *(f"scale_{n}" for n in names)))

    def _build(self) -> tuple[list, list, list]:
        rhs = [*self.velocities, *self.accelerations, *((sp.Integer(1),) if self.definition.uses_time else ())]
        return rhs, list(self.state), list(self.parameter_symbols)

    def _invariants(self) -> list:
        index = {q: i for i, q in enumerate(self.definition.coordinates)}
        exprs = [self.energy, *(self.momenta[index[q]] for q in self.cyclic)]
        # a scale of each: the sum of the sizes of its terms (the size its rounding is relative to)
        scales = [sp.Add(*[sp.Abs(a) for a in sp.Add.make_args(sp.expand(e))]) for e in exprs]
        return [*exprs, *scales]

    def _arguments(self) -> list:
        return [*self.parameter_symbols, *self.positions, *self.velocities, TIME]

    def mass_function(self) -> Callable[..., list]:
        """M compiled to NumPy, called as M(*parameters, *q, *q̇, t) -> the n² entries, row-major."""
        return cached_lambdify(f"{self.name}.mass_matrix", lambda: (self._arguments(), self.mass_matrix))[0]

    def expression_function(self, definition: Definition) -> Callable[..., list]:
        """The output expressions of ``definition`` (of these dynamics) compiled to NumPy, called as
        f(*all its parameters, *q, *q̇, t) -> list (an expression may use parameters L does not)."""
        d = definition

        def build() -> tuple:
            return [*d.parameter_symbols, *self.positions, *self.velocities, TIME], [e for _, e in d.expressions]
        return cached_lambdify(f"lagrangian_{d.digest}.expressions", build)[0]

    def pivot_function(self) -> Callable[..., list]:
        """The pivots of the generated elimination (the diagonal of U in M = P L U with the same structural
        row exchanges), compiled to NumPy, called as f(*parameters, *q, *q̇, t)."""
        def build() -> tuple:
            _, U, _ = self.mass_matrix.LUdecomposition(iszerofunc=_structural_zero)
            return self._arguments(), [U[k, k] for k in range(U.rows)]
        return cached_lambdify(f"{self.name}.pivots", build)[0]

    # --- regularity ------------------------------------------------------------------------------

    def mass_at(self, parameters: Sequence[float], q: Sequence[float], qdot: Sequence[float],
                time: float = 0.0) -> np.ndarray:
        """M at one state, as an n×n array of floats."""
        n = len(self.positions)
        with np.errstate(all="ignore"):
            vals = self.mass_function()(*parameters, *q, *qdot, time)
        return np.array([complex(v).real if np.iscomplexobj(v) else float(v) for v in vals]).reshape(n, n)

    def singular_reason(self) -> str | None:
        """Why M is singular for every state (a symbolically zero determinant), or None.

        Decided without the determinant where possible: M regular at one random state proves
        det M ≢ 0; only when the random states are all singular is det M simplified.
        """
        L = self.definition.lagrangian
        missing = [v.name for v in self.velocities if v not in L.free_symbols]
        if missing:
            return f"L does not depend on {', '.join(missing)}, so ∂²L/∂q̇∂q̇ has a zero row"
        rng = random.Random(self.definition.digest)
        n = len(self.positions)
        for _ in range(3):
            p = [rng.uniform(0.5, 1.5) for _ in self.parameter_symbols]
            q = [rng.uniform(0.3, 1.3) for _ in range(n)]
            v = [rng.uniform(0.3, 1.3) for _ in range(n)]
            M = self.mass_at(p, q, v, rng.uniform(0.3, 1.3))
            if np.all(np.isfinite(M)) and np.linalg.cond(M) < 1e8:
                return None
        det = self.mass_matrix.det(method="berkowitz")
        if vanishes(det):
            rank = self.mass_matrix.rank(simplify=True)
            return f"det ∂²L/∂q̇∂q̇ ≡ 0 (the mass matrix has rank {rank} < {n} for every state)"
        return None


_EQUATIONS: dict[str, LagrangianEquations] = {}


def equations(definition: Definition) -> LagrangianEquations:
    """The equations of ``definition``: one derivation per dynamics (coordinates, L, its parameters) in a
    process, shared by the definitions that differ only in their output expressions."""
    key = definition.dynamics_digest
    eq = _EQUATIONS.get(key)
    if eq is None:
        if len(_EQUATIONS) >= 64:
            _EQUATIONS.pop(next(iter(_EQUATIONS)))
        eq = _EQUATIONS.setdefault(key, LagrangianEquations(definition))
    return eq
