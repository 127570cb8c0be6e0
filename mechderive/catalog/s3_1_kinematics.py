"""Catalog entries for section 3.1 and 3.1.1: rotations and angular velocity, (3.1)–(3.10).

Each check compares the chapter's statement with what the toolkit derives from
R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ) (itself derived from so(3) exponentials), for
arbitrary time-dependent Euler angles φ(t), θ(t), ψ(t).
"""

from __future__ import annotations

import sympy as sp

from ..core.symbols import t
from ..kinematics import euler
from .checks import all_pass, same
from .registry import Claim, register

_r = sp.Matrix(sp.symbols("r1 r2 r3", real=True))  # body components of a point fixed in the body
_s = sp.Matrix(sp.symbols("s1 s2 s3", real=True))  # body components of a second body point


def _R() -> sp.Matrix:
    return euler.model().rotation


def _omega() -> sp.Matrix:
    return euler.model().angular_velocity_matrix


def _body_axes() -> list[sp.Matrix]:
    """e_a in space components: the rows of R (e_a = R_ab ẽ_b)."""
    R = _R()
    return [R[a, :].T for a in range(3)]


def _space_components(r: sp.Matrix) -> sp.Matrix:
    """r = r_a e_a written in space components, from the basis vectors themselves."""
    e = _body_axes()
    return sum((r[a] * e[a] for a in range(3)), sp.zeros(3, 1))


def _omega_space() -> sp.Matrix:
    """ω = ω_a e_a in space components."""
    return _space_components(euler.model().angular_velocity_body)


register(Claim(
    "3.1", "3.1",
    "distances between body points are constant: |r_i - r_j|² = |r̃_i - r̃_j|² for every R(t)",
    "symbolic",
    printed=lambda: ((_r - _s).T * (_r - _s))[0],
    check=lambda f: same(f, ((_space_components(_r) - _space_components(_s)).T
                              * (_space_components(_r) - _space_components(_s)))[0], "|r̃_i - r̃_j|²"),
))

register(Claim(
    "3.2", "3.1",
    "the body axes are orthonormal, e_a·e_b = δ_ab, i.e. R Rᵀ = 1 for R of (3.54)",
    "symbolic",
    printed=lambda: sp.eye(3),
    check=lambda f: same(f, sp.Matrix(3, 3, lambda a, b: (_body_axes()[a].T * _body_axes()[b])[0]), "e_a·e_b"),
))

register(Claim(
    "3.2 det R = 1", "3.1",
    "R has determinant +1 (a proper rotation, no reflection)",
    "symbolic",
    printed=lambda: sp.Integer(1),
    check=lambda f: same(f, _R().det(method="berkowitz"), "det R"),
))

register(Claim(
    "3.3", "3.1.1",
    "space components of a body vector are r̃_b = r_a R_ab",
    "symbolic",
    printed=lambda: sp.Matrix([sum(_r[a] * _R()[a, b] for a in range(3)) for b in range(3)]),
    check=lambda f: same(f, _space_components(_r), "r̃"),
))

register(Claim(
    "3.4", "3.1.1",
    "a body point moves with dr/dt = r_a (dR_ab/dt) ẽ_b",
    "symbolic",
    printed=lambda: sp.Matrix([sum(_r[a] * _R().diff(t)[a, b] for a in range(3)) for b in range(3)]),
    check=lambda f: same(f, _space_components(_r).diff(t), "dr̃/dt"),
))

register(Claim(
    "3.5", "3.1.1",
    "de_a/dt = ω_ac e_c with ω_ac = Ṙ_ab R_cb",
    "symbolic",
    printed=lambda: _R().diff(t) * _R().T,
    check=lambda f: same(sp.Matrix.hstack(*[sum((f[a, c] * _body_axes()[c] for c in range(3)), sp.zeros(3, 1))
                                           for a in range(3)]),
                         sp.Matrix.hstack(*[e.diff(t) for e in _body_axes()]), "Σ_c ω_ac e_c vs de_a/dt"),
))

register(Claim(
    "3.5 antisymmetry", "3.1.1",
    "ω is antisymmetric: ω_ac + ω_ca = 0",
    "symbolic",
    printed=lambda: sp.zeros(3, 3),
    check=lambda f: same(f, _omega() + _omega().T, "ω + ωᵀ"),
))

register(Claim(
    "3.6", "3.1.1",
    "ω_a = ½ ε_abc ω_bc, so (ω1, ω2, ω3) = (ω_23, ω_31, ω_12)",
    "symbolic",
    printed=lambda: sp.Matrix([_omega()[1, 2], _omega()[2, 0], _omega()[0, 1]]),
    check=lambda f: same(f, euler.model().angular_velocity_body, "ω_a"),
))

register(Claim(
    "3.7", "3.1.1",
    "de_a/dt = -ε_abc ω_b e_c = ω × e_a",
    "symbolic",
    printed=lambda: sp.Matrix.hstack(*[
        -sum((sp.LeviCivita(a + 1, b + 1, c + 1) * euler.model().angular_velocity_body[b] * _body_axes()[c]
              for b in range(3) for c in range(3)), sp.zeros(3, 1)) for a in range(3)]),
    check=lambda f: all_pass([
        same(f, sp.Matrix.hstack(*[e.diff(t) for e in _body_axes()]), "de_a/dt"),
        same(f, sp.Matrix.hstack(*[_omega_space().cross(e) for e in _body_axes()]), "ω × e_a"),
    ]),
))

register(Claim(
    "3.9", "3.1.1",
    "a body point moves with ṙ = ω × r (3.8)–(3.9)",
    "symbolic",
    printed=lambda: _omega_space().cross(_space_components(_r)),
    check=lambda f: same(f, _space_components(_r).diff(t), "dr̃/dt"),
))

register(Claim(
    "3.10", "3.1.1",
    "space components evolve by the convective angular velocity: dr̃_b/dt = r̃_a (R⁻¹Ṙ)_ab",
    "symbolic",
    printed=lambda: sp.Matrix([sum(_space_components(_r)[a] * euler.model().convective_angular_velocity_matrix[a, b]
                                   for a in range(3)) for b in range(3)]),
    check=lambda f: same(f, _space_components(_r).diff(t), "dr̃/dt"),
))

register(Claim(
    "3.10 Ω = Rᵀ ω R", "3.1.1",
    "the convective Ω = R⁻¹Ṙ is ω conjugated into the space frame, Ω = Rᵀ ω R; its vector is ω's space components",
    "symbolic",
    printed=lambda: _R().T * _omega() * _R(),
    check=lambda f: all_pass([
        same(f, euler.model().convective_angular_velocity_matrix, "Ω"),
        same(sp.Matrix([f[1, 2], f[2, 0], f[0, 1]]), _omega_space(), "vector of Ω vs space ω"),
    ]),
))
