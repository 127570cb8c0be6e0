"""Kinetic energy of a free body: centre-of-mass motion plus rotation about it (3.29)–(3.30).

Each point is r_i = R + Δr_i (3.29), with R the centre of mass, so Σ m_i Δr_i = 0.
Components: everything in body components — V = Ṙ written in the body frame
(the dot products in T do not depend on the frame), Δr_i constant, and the
rigid velocity Δṙ_i = ωᵀ Δr_i derived in :class:`~mechderive.inertia.tensor.PointMassModel`.

:class:`FreeBodyModel` derives T = ½ Σ m |V + Δṙ_i|² and splits it by setting
variables to zero: T(ω = 0) is the translational part, T(V = 0) the rotational
part, and the remainder is the cross term Σ m V·(ω × Δr_i), which vanishes
once Σ m Δr_i = 0 is imposed (solved for the last Δr_n).
"""

from __future__ import annotations

import functools

import sympy as sp

from ..core.model import SymbolicModel, derived
from ..errors import DerivationError, InvalidInputError
from .tensor import point_mass_model

__all__ = ["FreeBodyModel", "free_body_model"]


class FreeBodyModel(SymbolicModel):
    """T of ``n`` point masses moving rigidly, split into translation and rotation (3.30)."""

    def __init__(self, n: int = 3) -> None:
        super().__init__()
        if not (isinstance(n, int) and n >= 2):
            raise InvalidInputError(f"expected n >= 2 masses, got {n!r}")
        self.n = n
        self.points = point_mass_model(n)  # masses, Δr_i (body components), ω, rigid velocities
        self.masses = self.points.masses
        self.offsets = self.points.positions
        self.omega = self.points.omega
        self.V = sp.Matrix(sp.symbols("V1:4", real=True))  # Ṙ in body components
        self.M = sum(self.masses)

    @derived
    def kinetic_energy(self) -> sp.Expr:
        """T = ½ Σ m_i ṙ_i² with ṙ_i = V + Δṙ_i (first line of (3.30)), no constraint yet."""
        vel = [self.V + v for v in self.points.velocities]
        return sp.expand(sum(m * v.dot(v) for m, v in zip(self.masses, vel)) / 2)

    @derived
    def centre_of_mass_constraint(self) -> dict[sp.Symbol, sp.Expr]:
        """Σ m_i Δr_i = 0 solved for Δr_n."""
        first = sum((m * r for m, r in zip(self.masses, self.offsets)), sp.zeros(3, 1))
        sol = sp.solve(list(first), list(self.offsets[-1]), dict=True)
        if len(sol) != 1:
            raise DerivationError(f"expected one solution of Σ m Δr = 0, got {sol}")
        return sol[0]

    @derived
    def kinetic_energy_at_cm(self) -> sp.Expr:
        """T with Σ m Δr_i = 0 imposed."""
        return sp.cancel(self.kinetic_energy.subs(self.centre_of_mass_constraint))

    @derived
    def translational_energy(self) -> sp.Expr:
        """T at ω = 0: the motion of the centre of mass (½ M V² expected)."""
        return sp.factor(self.kinetic_energy_at_cm.subs({w: 0 for w in self.omega}))

    @derived
    def rotational_energy(self) -> sp.Expr:
        """T at V = 0: rotation about the centre of mass, in Δr_1..Δr_{n-1}."""
        return sp.cancel(self.kinetic_energy_at_cm.subs({v: 0 for v in self.V}))

    @derived
    def inertia_cm(self) -> sp.Matrix:
        """The inertia tensor (3.19) of the Δr_i, with the constraint imposed."""
        return self.points.inertia_tensor.subs(self.centre_of_mass_constraint).applyfunc(sp.cancel)

    @derived
    def cross_term(self) -> sp.Expr:
        """T - T(ω=0) - T(V=0) before the constraint: Σ m V·(ω × Δr_i), linear in Δr."""
        T = self.kinetic_energy
        return sp.expand(T - T.subs({w: 0 for w in self.omega}) - T.subs({v: 0 for v in self.V}))

    @derived
    def cross_term_at_cm(self) -> sp.Expr:
        """The cross term with Σ m Δr_i = 0: zero, so T separates (3.30)."""
        out = sp.cancel(self.cross_term.subs(self.centre_of_mass_constraint))
        if out != 0:
            raise DerivationError(f"expected the cross term to vanish at the centre of mass, got {out}")
        return out


@functools.cache
def free_body_model(n: int = 3) -> FreeBodyModel:
    """The process-wide :class:`FreeBodyModel` for ``n`` masses."""
    return FreeBodyModel(n)
