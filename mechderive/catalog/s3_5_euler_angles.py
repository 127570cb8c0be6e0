"""Catalog entries for section 3.5: Euler angles and the angular velocity in them, (3.50)–(3.58).

The chapter's printed matrices are compared with R1, R3 derived as so(3)
exponentials, with R = R3(ψ)R1(θ)R3(φ) built from them, and with ω derived
from ω = ṘRᵀ (3.5)–(3.6).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..core.symbols import state_symbol, to_state_symbols
from ..kinematics import euler
from .checks import same
from .registry import Claim, Outcome, register

phi, theta, psi = (state_symbol(n) for n in ("phi", "theta", "psi"))
phi_dot, theta_dot, psi_dot = (state_symbol(n) for n in ("phi_dot", "theta_dot", "psi_dot"))


def _printed_R3(x: sp.Expr) -> sp.Matrix:
    return sp.Matrix([[sp.cos(x), sp.sin(x), 0], [-sp.sin(x), sp.cos(x), 0], [0, 0, 1]])


def _printed_R1(x: sp.Expr) -> sp.Matrix:
    return sp.Matrix([[1, 0, 0], [0, sp.cos(x), sp.sin(x)], [0, -sp.sin(x), sp.cos(x)]])


def _printed_R() -> sp.Matrix:
    c, s = sp.cos, sp.sin
    return sp.Matrix([
        [c(psi) * c(phi) - c(theta) * s(phi) * s(psi), s(phi) * c(psi) + c(theta) * s(psi) * c(phi), s(theta) * s(psi)],
        [-c(phi) * s(psi) - c(theta) * c(psi) * s(phi), -s(psi) * s(phi) + c(theta) * c(psi) * c(phi), s(theta) * c(psi)],
        [s(theta) * s(phi), -s(theta) * c(phi), c(theta)],
    ])


def _state_R() -> sp.Matrix:
    return euler.model().state_rotation


def _R3_at(x: sp.Expr) -> sp.Matrix:
    return euler.axis_rotation(3, x)


def _R1_at(x: sp.Expr) -> sp.Matrix:
    return euler.axis_rotation(1, x)


register(Claim(
    "3.51", "3.5",
    "step 1: rotation by φ about ẽ3 is R3(φ) = [[cos φ, sin φ, 0], [-sin φ, cos φ, 0], [0, 0, 1]]",
    "symbolic",
    printed=lambda: _printed_R3(phi),
    check=lambda f: same(f, _R3_at(phi), "R3(φ) vs exp(φ J3)"),
))

register(Claim(
    "3.52", "3.5",
    "step 2: rotation by θ about the line of nodes e'1 is R1(θ) = [[1, 0, 0], [0, cos θ, sin θ], [0, -sin θ, cos θ]]",
    "symbolic",
    printed=lambda: _printed_R1(theta),
    check=lambda f: same(f, _R1_at(theta), "R1(θ) vs exp(θ J1)"),
))

register(Claim(
    "3.53", "3.5",
    "step 3: rotation by ψ about e''3 is R3(ψ)",
    "symbolic",
    printed=lambda: _printed_R3(psi),
    check=lambda f: same(f, _R3_at(psi), "R3(ψ) vs exp(ψ J3)"),
))

register(Claim(
    "3.54", "3.5",
    "R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ), written out longhand",
    "symbolic",
    printed=_printed_R,
    check=lambda f: same(f, _state_R(), "R longhand vs R3(ψ)R1(θ)R3(φ)"),
))


def _check_euler_theorem(formula: sp.Matrix) -> Outcome:
    """Euler's theorem: every rotation is R(φ, θ, ψ) for some angles.

    Draws 200 seeded random rotations (uniform on SO(3), SciPy), recovers angles with
    :func:`euler_angles_from_matrix`, and rebuilds the matrix from ``formula``; the
    largest entry error must be at rounding level (1e-12 allows ~10⁴ ulps).
    """
    from scipy.spatial.transform import Rotation

    from ..kinematics.conversions import from_scipy_rotation

    mats = from_scipy_rotation(Rotation.random(200, random_state=np.random.default_rng(354)))
    angles = euler.euler_angles_from_matrix(mats)
    f = sp.lambdify([phi, theta, psi], formula, "numpy")
    rebuilt = np.array([np.asarray(f(*a), dtype=float) for a in angles])
    err = float(np.max(np.abs(rebuilt - mats)))
    ok = err < 1e-12
    return Outcome(ok, f"200 random rotations rebuilt from their Euler angles, max error {err:.2e}")


register(Claim(
    "3.54 Euler's theorem", "3.5",
    "an arbitrary rotation is a product of three rotations: every R in SO(3) equals R(φ, θ, ψ) for some angles",
    "numeric",
    printed=_printed_R,
    check=_check_euler_theorem,
))


def _e3_space_in_body() -> sp.Matrix:
    """ẽ3 in body components: ẽ_b = R_ab e_a, so the components are column 3 of R."""
    return _state_R()[:, 2]


def _line_of_nodes_in_body() -> sp.Matrix:
    """e'1 in body components: e = R3(ψ)R1(θ) e', so e'_b = Σ_a [R3(ψ)R1(θ)]_ab e_a."""
    return (_R3_at(psi) * _R1_at(theta))[:, 0]


def _omega_body() -> sp.Matrix:
    return euler.model().state_angular_velocity_body


register(Claim(
    "3.56", "3.5.2",
    "ω = φ̇ ẽ3 + θ̇ e'1 + ψ̇ e3",
    "symbolic",
    printed=lambda: phi_dot * _e3_space_in_body() + theta_dot * _line_of_nodes_in_body()
    + psi_dot * sp.Matrix([0, 0, 1]),
    check=lambda f: same(f, _omega_body(), "ω body components vs ṘRᵀ"),
))

register(Claim(
    "3.57", "3.5.2",
    "ẽ3 = sin θ sin ψ e1 + sin θ cos ψ e2 + cos θ e3 and e'1 = cos ψ e1 - sin ψ e2",
    "symbolic",
    printed=lambda: (sp.Matrix([sp.sin(theta) * sp.sin(psi), sp.sin(theta) * sp.cos(psi), sp.cos(theta)]),
                     sp.Matrix([sp.cos(psi), -sp.sin(psi), 0])),
    check=lambda f: same(sp.Matrix.hstack(*f), sp.Matrix.hstack(_e3_space_in_body(), _line_of_nodes_in_body()),
                         "(ẽ3, e'1) in body axes"),
    parts=("ẽ3", "e'1"),
))

register(Claim(
    "3.58", "3.5.2",
    "body components ω = (φ̇ sin θ sin ψ + θ̇ cos ψ, φ̇ sin θ cos ψ - θ̇ sin ψ, ψ̇ + φ̇ cos θ)",
    "symbolic",
    printed=lambda: sp.Matrix([
        phi_dot * sp.sin(theta) * sp.sin(psi) + theta_dot * sp.cos(psi),
        phi_dot * sp.sin(theta) * sp.cos(psi) - theta_dot * sp.sin(psi),
        psi_dot + phi_dot * sp.cos(theta),
    ]),
    check=lambda f: same(f, _omega_body(), "ω body components vs ½ε_abc(ṘRᵀ)_bc"),
))

register(Claim(
    "3.58 space axes", "3.5.2",
    "\"by playing a similar game\": ω in space axes = φ̇ ẽ3 + θ̇ e'1 + ψ̇ e3 with e'1 = (cos φ, sin φ, 0), "
    "e3 = (sin θ sin φ, -sin θ cos φ, cos θ)",
    "symbolic",
    printed=lambda: phi_dot * sp.Matrix([0, 0, 1]) + theta_dot * sp.Matrix([sp.cos(phi), sp.sin(phi), 0])
    + psi_dot * sp.Matrix([sp.sin(theta) * sp.sin(phi), -sp.sin(theta) * sp.cos(phi), sp.cos(theta)]),
    check=lambda f: same(f, to_state_symbols(euler.model().angular_velocity_space), "space ω vs Rᵀω"),
))
