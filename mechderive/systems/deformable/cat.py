"""A falling cat: two jointed halves that turn over by π with zero angular momentum (section 3.7).

Model
-----
After Kane & Scher, "A dynamical explanation of the falling cat phenomenon",
Int. J. Solids Struct. 5 (1969) 663: the cat is two identical axially symmetric
rigid halves (front and rear) joined at the waist, which bend symmetrically about a
*swivelling* axis perpendicular to the body's long axis, with no relative twist.  The
gauge picture (shape space, connection, holonomy) is R. Montgomery's, "Gauge theory
of the falling cat", Fields Inst. Commun. 1 (1993) 193.  Here each half is six point
masses (mass/6 each): two on its axis at ±``half_length`` from its centre and four on
a ring of ``radius`` around it, so its inertia is axially symmetric (axial
(2/3) m ρ², transverse (1/3) m (ρ² + ℓ²) about its centre), and its centre is
``joint_offset`` from the joint.

Shape coordinates: the bend β (rad; the halves' axes meet at the angle π − β, so β = 0
is straight) and the swivel ψ (rad), the direction n(ψ) = (0, cos ψ, sin ψ) of the
bending axis.  The front half is the active rotation Q(n(ψ), β/2) of its straight
position, the rear half Q(n(ψ), −β/2); positions are measured from the centre of
mass.  Long axis: e1.

The flip: the closed loop β(t) = β₀ sin²(πt/T), ψ(t) = −2πt/T + sin(2πt/T), from the
straight shape back to it; the peak bend β₀ is found by root-finding so that the
net rotation (3.98) is exactly a half turn about e1.  With L = 0 the orientation obeys
Ṙ = RΩ (3.86), Ω from (3.92); by the symmetry of the halves Ω stays along e1.

Conventions: section 3.7's R (active, r_i = R r̃_i; columns = the reference body's
axes in space components).  :func:`falling_cat_motion` reports section 3.1's
R(3.1) = R(3.7)ᵀ (e_a = R_ab ẽ_b, rows = body axes) as ``R11 … R33``, and the
scalar-first quaternion of the active rotation R(3.7) = R(3.1)ᵀ, as
:mod:`mechderive.kinematics.conversions` does.  Units: kg, m, s, rad.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
import sympy as sp

from ...errors import InvalidInputError
from ...kinematics.euler import axis_rotation
from .holonomy import ShapeLoop, net_rotation, rotation_along
from .model import DeformableBody, centred_positions

__all__ = ["BODY_PARAMETERS", "DEFAULTS", "cat_body", "cat_loop", "flip_bend", "FallingCat", "falling_cat",
           "falling_cat_motion", "check_cat_parameters"]

#: Body parameters: the mass of each half (kg), joint-to-centre distance, ring radius, axial half-length (m).
BODY_PARAMETERS = ("half_mass", "joint_offset", "radius", "half_length")
#: Defaults (a 4 kg cat, halves 0.24 m long); ``peak_bend`` (rad, in (0, π)) is optional: by default it is
#: found by :func:`flip_bend`.
DEFAULTS = {"half_mass": 2.0, "joint_offset": 0.12, "radius": 0.05, "half_length": 0.10}
ALLOWED = BODY_PARAMETERS + ("peak_bend",)

bend, swivel = sp.symbols("bend swivel", real=True)
_SYMBOLS = sp.symbols("half_mass joint_offset radius half_length", positive=True)
_TIME = sp.Symbol("t", real=True)
_PEAK, _DURATION = sp.symbols("beta0 T", positive=True)


def _active(axis: int, angle: sp.Expr) -> sp.Matrix:
    """The active rotation by ``angle`` about axis e_axis: the transpose of section 3.1's passive R_a."""
    return axis_rotation(axis, angle).T


@functools.cache
def cat_body() -> DeformableBody:
    """The symbolic cat: 12 point masses, shape coordinates (bend, swivel), parameters as in :data:`BODY_PARAMETERS`."""
    m, a, rho, ell = _SYMBOLS
    G = _active(1, swivel)  # carries e2 onto the bending axis n(ψ)
    local = [(ell, 0, 0), (-ell, 0, 0), (0, rho, 0), (0, -rho, 0), (0, 0, rho), (0, 0, -rho)]
    masses, points = [], []
    for side in (1, -1):  # front, rear
        Q = G * _active(2, side * bend / 2) * G.T
        for p in local:
            points.append(Q * (sp.Matrix([side * a, 0, 0]) + sp.Matrix(p)))
            masses.append(m / 6)
    return DeformableBody(masses, centred_positions(masses, points), [bend, swivel], parameters=list(_SYMBOLS))


def cat_loop(peak_bend: float, duration: float) -> ShapeLoop:
    """The flip loop β = β₀ sin²(πt/T), ψ = −2πt/T + sin(2πt/T), t ∈ [0, T]: straight → bent, swept, → straight.

    The swivel runs backwards (ψ: 0 → −2π) so that the cat turns the positive way about e1.

    Every shape velocity vanishes at t = 0 and T, and the formulas are analytic for all t
    (continued periodically outside [0, T]).
    """
    tau = _TIME / _DURATION
    exprs = [_PEAK * sp.sin(sp.pi * tau) ** 2, -(2 * sp.pi * tau - sp.sin(2 * sp.pi * tau))]
    exprs = [e.subs({_PEAK: sp.Float(peak_bend, 17), _DURATION: sp.Float(duration, 17)}) for e in exprs]
    return ShapeLoop.from_expressions(exprs, _TIME, (0.0, float(duration)))


def check_cat_parameters(parameters: Mapping[str, Any] | None) -> dict[str, float]:
    """The body parameters (defaults filled in) and, if given, ``peak_bend``; raises on anything else.

    >>> check_cat_parameters({"radius": 0.04})["radius"]
    0.04
    """
    given = dict(parameters or {})
    for key in given:
        if key not in ALLOWED:
            raise InvalidInputError(f"unknown parameter {key!r}: expected one of {', '.join(ALLOWED)}")
    out = dict(DEFAULTS)
    for key, value in given.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise InvalidInputError(f"expected `{key}` to be a number, got {value!r}")
        x = float(value)
        if not np.isfinite(x) or not x > 0:
            raise InvalidInputError(f"expected `{key}` finite and > 0, got {x!r}")
        out[key] = x
    if "peak_bend" in out and not out["peak_bend"] < np.pi:
        raise InvalidInputError(f"expected `peak_bend` in (0, π) (the halves must not fold through each other), "
                                f"got {out['peak_bend']!r}")
    return out


def _connection(params: Mapping[str, float]):
    return cat_body().numeric({k: params[k] for k in BODY_PARAMETERS})


def _sine_of_flip(connection: Any, peak: float, rtol: float) -> tuple[float, float, Any]:
    h = net_rotation(connection, cat_loop(peak, 1.0), rtol=rtol)
    R = h.R
    return 0.5 * (R[2, 1] - R[1, 2]), 0.5 * (R[1, 1] + R[2, 2]), h


def flip_bend(parameters: Mapping[str, Any] | None = None, *, rtol: float = 1e-13) -> float:
    """The peak bend β₀ (rad) of :func:`cat_loop` whose net rotation is a half turn about e1.

    Solves sin θ(β₀) = 0 with cos θ < 0 (θ the rotation angle about e1 of the holonomy) by Brent's
    method, bracketing on a grid of β₀; the net rotation does not depend on the duration (3.98).
    Cached per body.
    """
    params = check_cat_parameters(parameters)
    return _flip_bend(tuple(params[k] for k in BODY_PARAMETERS), float(rtol))


@functools.lru_cache(maxsize=32)
def _flip_bend(values: tuple[float, ...], rtol: float) -> float:
    from scipy.optimize import brentq

    params = dict(zip(BODY_PARAMETERS, values))
    conn = _connection(params)
    grid = np.linspace(0.2, 3.0, 15)
    values = [_sine_of_flip(conn, b, 1e-9)[:2] for b in grid]
    for (b0, (s0, c0)), (b1, (s1, c1)) in zip(zip(grid, values), zip(grid[1:], values[1:])):
        if s0 * s1 <= 0 and c0 < 0 and c1 < 0:
            return float(brentq(lambda b: _sine_of_flip(conn, b, rtol)[0], b0, b1, xtol=1e-15, rtol=1e-15))
    raise InvalidInputError(f"expected a body that can turn over with a bend below {grid[-1]:.2f} rad, "
                            f"got {params} (halves too slender to flip in one sweep)")


@dataclass(frozen=True)
class FallingCat:
    """A computed flip.

    Attributes
    ----------
    t : (N,) times (s); R : (N, 3, 3) orientation, section 3.7's active R(t) (R(0) = 1);
    shapes : (N, 2) (bend, swivel) in rad; flip_angle : (N,) rotation angle about e1, unwrapped (rad);
    angular_momentum : (N, 3) L = Σ m r × ṙ in space components (kg m²/s), from finite differences
    of r_i(t) = R(t) r̃_i(x(t)) — independent of Ω; peak_bend : β₀ (rad); error_estimate : the
    integrator's global error estimate of R (rad); parameters : the body parameters used.
    """

    t: np.ndarray
    R: np.ndarray
    shapes: np.ndarray
    flip_angle: np.ndarray
    angular_momentum: np.ndarray
    peak_bend: float
    error_estimate: float
    parameters: dict


#: 8th-order central differences: f'(t) ≈ Σ_j c_j f(t + jδ)/δ, j = −4 … 4.
_FD = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0.0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])


def falling_cat(parameters: Mapping[str, Any] | None = None, *, duration: float = 1.0, samples: int = 101,
                rtol: float = 1e-12) -> FallingCat:
    """The flip over t ∈ [0, duration]: orientation, shapes and the space angular momentum at ``samples`` times.

    L is computed from its definition Σ m_i r_i × ṙ_i with ṙ_i by 8th-order central differences
    (step δ = min(10⁻³ T, Δt/10)) of r_i(t) = R(t) r̃_i(x(t)), R integrated on [−4δ, T + 4δ]
    (the loop's formulas continue analytically) — so it tests Ω and the integration together.
    """
    params = check_cat_parameters(parameters)
    if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not np.isfinite(duration) \
            or not duration > 0:
        raise InvalidInputError(f"expected `duration` (t_end) finite and > 0, got {duration!r}")
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2:
        raise InvalidInputError(f"expected `samples` to be an integer >= 2, got {samples!r}")
    peak = params.get("peak_bend")
    if peak is None:
        peak = flip_bend(params)
    conn = _connection(params)
    T = float(duration)
    times = np.linspace(0.0, T, int(samples))
    delta = min(1e-3 * T, (times[1] - times[0]) / 10)
    offsets = delta * np.arange(-4, 5)
    stencil = (times[:, None] + offsets[None, :]).ravel()
    loop = cat_loop(peak, T)
    extended = ShapeLoop.from_functions(loop.shape, loop.velocity, (stencil[0], stencil[-1]))
    run = rotation_along(conn, extended, rtol=rtol, t_eval=stencil)
    Rs = run.rotations.reshape(len(times), 9, 3, 3)
    start = Rs[0, 4]
    Rs = np.einsum("ba,nkbc->nkac", start, Rs)  # R(0) = 1: a constant rotation of the whole motion
    shapes_all = loop.shape(stencil).reshape(len(times), 9, 2)
    r = np.einsum("nkab,nkib->nkia", Rs, conn.positions(shapes_all))  # (N, 9, masses, 3)
    rdot = np.einsum("k,nkia->nia", _FD, r) / delta
    L = np.einsum("i,nia->na", conn.masses, np.cross(r[:, 4], rdot))
    R = Rs[:, 4]
    flip = np.unwrap(np.arctan2(R[:, 2, 1] - R[:, 1, 2], R[:, 1, 1] + R[:, 2, 2]))
    return FallingCat(times, R, shapes_all[:, 4], flip, L, float(peak), run.error_estimate,
                      {k: params[k] for k in BODY_PARAMETERS})


def falling_cat_motion(parameters: dict | None = None, *, t_end: float, samples: int) -> dict[str, np.ndarray]:
    """Time series of the falling cat for a scene: a 180° flip over t ∈ [0, t_end] with L = 0.

    Returns arrays of length ``samples`` named ``t``; ``R11 … R33`` — the orientation of the
    cat's reference body in section 3.1's convention e_a = R_ab ẽ_b, i.e. R(3.1) = R(3.7)ᵀ;
    ``q0 q1 q2 q3`` — the scalar-first unit quaternion of the active rotation R(3.7) (sign
    continuous in time, q0(0) = 1); ``flip_angle`` (rad, 0 → π); ``shape_bend``,
    ``shape_swivel`` (rad); ``L1 L2 L3`` — the angular momentum in space components
    (kg m²/s, zero to integration accuracy).  ``parameters``: see :func:`check_cat_parameters`.
    """
    from ...kinematics.conversions import matrix_to_quaternion

    cat = falling_cat(parameters, duration=t_end, samples=samples)
    R31 = np.swapaxes(cat.R, -1, -2)
    out: dict[str, np.ndarray] = {"t": cat.t}
    for a in range(3):
        for b in range(3):
            out[f"R{a + 1}{b + 1}"] = R31[:, a, b]
    q = matrix_to_quaternion(R31)
    for n in range(1, len(q)):  # q and −q are the same rotation: keep the sign continuous
        if np.dot(q[n], q[n - 1]) < 0:
            q[n] = -q[n]
    for k in range(4):
        out[f"q{k}"] = q[:, k]
    out["flip_angle"] = cat.flip_angle
    out["shape_bend"], out["shape_swivel"] = cat.shapes[:, 0], cat.shapes[:, 1]
    for a in range(3):
        out[f"L{a + 1}"] = cat.angular_momentum[:, a]
    return out
