"""Export to :mod:`sympy.physics.mechanics`: a rigid body about a fixed point as frames, a body and L.

Any system whose check symbols (:meth:`~mechderive.systems.base.System.check_system`) describe a
rigid body about a fixed point in uniform gravity (:class:`~mechderive.formulas.systems.RigidBody`:
principal moments about the point, centre of mass, mass, gravity) is exported; the system is
found through the registry (:mod:`mechderive.systems.registry`), a scene file or a system object,
never by name here.  The heavy and free tops are two such systems.

The body frame B is oriented from the space frame N by ``B.orient_body_fixed(N, (φ, θ, ψ), "ZXZ")``,
and mechanics' direction cosine matrix ``B.dcm(N)`` is the chapter's R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ)
(3.54) — both define the *passive* matrix with b_i = dcm_ij n_j, e_a = R_ab ẽ_b — checked on every
build (exactly, by :func:`mechderive.core.simplify.is_zero`).  The coordinates are mechanics'
``dynamicsymbols`` φ(t), θ(t), ψ(t) (its own time symbol); :func:`MechanicsModel.to_state` maps
results to the toolkit's state symbols ``phi, phi_dot, phi_ddot, …``.

The body: a RigidBody of mass M with inertia dyadic I1 b1b1 + I2 b2b2 + I3 b3b3 *about the pivot*
O (mechanics takes the inertia about any point), centre of mass G at c_a b_a from O, O fixed in
N, gravity −M g n3, so V = M g (r_G · n3) (none where g = 0).  L = T − V is mechanics' own
``Lagrangian(N, body)``; :class:`sympy.physics.mechanics.LagrangesMethod` gives M q̈ = F.  The
heavy top (section 3.6) has I2 = I1 and c = l b3; the free top c = 0 and no gravity.

>>> m = to_mechanics("heavy_top")
>>> from mechderive.kinematics.euler_symbolic import model
>>> (m.to_state(m.frame.dcm(m.space)) - model().state_rotation).applyfunc(sp.expand) == sp.zeros(3, 3)
True
>>> from mechderive.core.simplify import is_zero
>>> from mechderive.systems.heavy_top.model import model as heavy_top
>>> is_zero(m.to_state(m.lagrangian) - heavy_top().state_lagrangian)      # (3.62)
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import sympy as sp

from ..core.symbols import state_symbol
from ..errors import DerivationError, InvalidInputError

__all__ = ["MechanicsModel", "to_mechanics", "exportable"]


@dataclass(frozen=True)
class MechanicsModel:
    """A :mod:`sympy.physics.mechanics` model: frames, pivot, body, Lagrangian and its LagrangesMethod."""

    space: Any          #: N, the space frame {ẽ_a}
    frame: Any          #: B, the body frame {e_a}
    pivot: Any          #: O, the fixed point
    body: Any           #: the RigidBody
    coordinates: tuple  #: (φ(t), θ(t), ψ(t)) as mechanics dynamicsymbols
    lagrangian: Any     #: L = T − V, mechanics' Lagrangian(N, body) − V
    method: Any         #: LagrangesMethod(L, coordinates), equations formed

    def to_state(self, expr: Any) -> Any:
        """``expr`` with q(t), q̇(t), q̈(t) replaced by the toolkit's symbols q, q_dot, q_ddot."""
        from sympy.physics.mechanics import dynamicsymbols

        t = dynamicsymbols._t
        subs = {}
        for q in self.coordinates:
            name = q.func.__name__
            subs[q.diff(t, 2)] = state_symbol(name + "_ddot")
            subs[q.diff(t)] = state_symbol(name + "_dot")
        from ..formulas.parse import as_expression

        out = (expr if isinstance(expr, sp.MatrixBase) else as_expression(expr, "`expr`")).subs(subs)
        return out.subs({q: state_symbol(q.func.__name__) for q in self.coordinates})

    def mass_matrix(self) -> sp.Matrix:
        """Mechanics' mass matrix M of M q̈ = F, in the toolkit's symbols."""
        return self.to_state(self.method.mass_matrix)

    def forcing(self) -> sp.Matrix:
        """Mechanics' forcing F of M q̈ = F, in the toolkit's symbols."""
        return self.to_state(self.method.forcing)


def exportable() -> tuple[str, ...]:
    """The registered systems that describe a rigid body about a fixed point, the latest registered first."""
    from ..formulas.systems import check_system_of, names

    def has_body(system: Any) -> bool:
        table = check_system_of(system)
        return table is not None and table.body is not None

    return tuple(reversed(names(has_body)))


def _body(system: Any) -> Any:
    from ..errors import MechDeriveError
    from ..formulas.systems import find_system, get_system, is_scene_path

    if isinstance(system, str) and not is_scene_path(system):
        from ..systems import registry

        if system not in registry.names():
            raise InvalidInputError(f"expected a system among {', '.join(exportable())}, got {system!r}")
    try:
        table = get_system(find_system(system)[0])
    except MechDeriveError:
        table = None
    if table is None or table.body is None:
        shown = system if isinstance(system, str) else getattr(system, "name", system)
        raise InvalidInputError(f"expected a system among {', '.join(exportable())}, got {shown!r}")
    return table.body


def to_mechanics(system: Any = "heavy_top") -> MechanicsModel:
    """Build ``system`` in :mod:`sympy.physics.mechanics` (module docstring): a registered system's
    name ("heavy_top", "free_top", …), a scene file (a path ending ``.toml``) or a system object,
    whose check symbols describe a rigid body about a fixed point.

    Uses the system's own parameter symbols (``I1 I3 M g l`` of the heavy top; ``I1 I2 I3`` of the
    free top), so results compare directly with :mod:`mechderive.systems`.
    """
    body_spec = _body(system)
    from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)

    from ..core.simplify import is_zero
    from ..kinematics.euler_symbolic import model as kinematics

    q = dynamicsymbols("phi theta psi", real=True)
    N = ReferenceFrame("N")
    B = ReferenceFrame("B")
    B.orient_body_fixed(N, tuple(q), "ZXZ")
    R = kinematics().state_rotation
    chapter = R.subs({state_symbol(n): qi for n, qi in zip(("phi", "theta", "psi"), q)}, simultaneous=True)
    if not all(is_zero(e) for e in B.dcm(N) - chapter):
        raise DerivationError("expected mechanics' B.dcm(N) to equal the chapter's R(φ, θ, ψ) (3.54)")
    O = Point("O")
    O.set_vel(N, 0)
    c1, c2, c3 = (sp.sympify(c, strict=True) for c in body_spec.centre_of_mass)
    G = O.locatenew("G", c1 * B.x + c2 * B.y + c3 * B.z)
    G.v2pt_theory(O, N, B)
    mass, gravity = body_spec.mass, sp.sympify(body_spec.gravity, strict=True)
    body = RigidBody("body", G, B, mass, (inertia(B, *body_spec.moments), O))
    if gravity != 0:
        body.potential_energy = mass * gravity * G.pos_from(O).dot(N.z)
    L = Lagrangian(N, body)
    method = LagrangesMethod(L, list(q), frame=N)
    method.form_lagranges_equations()
    return MechanicsModel(N, B, O, body, tuple(q), L, method)
