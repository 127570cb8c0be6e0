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

Computing: everything is derived from :func:`cat_body` and the loop's formulas, compiled with
the body parameters (and β₀, T) as arguments, and kept in the disk cache
(:mod:`mechderive.core.codecache`, :mod:`mechderive.core.cbuild`) — the connection's functions
under ``deformable.cat.<quantity>``, the loop under ``deformable.cat.loop``, and Ṙ = RΩ(x(t), ẋ(t))
as one right-hand side of DOP853 compiled to C (``deformable_cat_flip``).  A second process
neither derives nor imports SymPy.  Without a C compiler R is integrated by Magnus steps
(:func:`.holonomy.rotation_along`) instead.

Conventions: section 3.7's R (active, r_i = R r̃_i; columns = the reference body's
axes in space components).  :func:`falling_cat_motion` reports section 3.1's
R(3.1) = R(3.7)ᵀ (e_a = R_ab ẽ_b, rows = body axes) as ``R11 … R33``, and the
scalar-first quaternion of the active rotation R(3.7) = R(3.1)ᵀ, as
:mod:`mechderive.kinematics.conversions` does.  Units: kg, m, s, rad.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from ...errors import IntegrationError, InvalidInputError
from .connection import ShapeConnection
from .holonomy import ShapeLoop, net_rotation, rotation_along

# SymPy is imported only inside the functions that derive (cat_body and the builders of the compiled
# functions): a process whose compiled functions are in the disk cache runs the cat without it.

__all__ = ["BODY_PARAMETERS", "DEFAULTS", "BACKENDS", "CACHE_NAME", "cat_body", "cat_connection", "cat_loop",
           "flip_bend", "FallingCat", "falling_cat", "falling_cat_motion", "cat_columns", "check_cat_parameters"]

#: Body parameters: the mass of each half (kg), joint-to-centre distance, ring radius, axial half-length (m).
BODY_PARAMETERS = ("half_mass", "joint_offset", "radius", "half_length")
#: Defaults (a 4 kg cat, halves 0.24 m long); ``peak_bend`` (rad, in (0, π)) is optional: by default it is
#: found by :func:`flip_bend`.
DEFAULTS = {"half_mass": 2.0, "joint_offset": 0.12, "radius": 0.05, "half_length": 0.10}
ALLOWED = BODY_PARAMETERS + ("peak_bend",)
#: How R(t) is integrated: ``"c"`` — DOP853 compiled to C with the derived Ṙ = RΩ (3.86) as one
#: right-hand side (:mod:`mechderive.solvers.dop853_c`); ``"magnus"`` — the adaptive Magnus steps of
#: :func:`.holonomy.rotation_along` on the compiled Ω_A (NumPy; no compiler needed); ``"auto"`` —
#: C where a compiler is found, else Magnus.
BACKENDS = ("auto", "c", "magnus")
#: The prefix of the names under which the cat's derived functions are kept in the disk cache
#: (:mod:`mechderive.core.codecache`): ``deformable.cat.connection``, ``deformable.cat.loop``, …;
#: the body parameters (and the loop's β₀, T) are arguments, never baked in.
CACHE_NAME = "deformable.cat"
#: The compiled stepper's name (a C identifier): DOP853 with the derived Ṙ = RΩ(x(t), ẋ(t)).
_STEPPER = "deformable_cat_flip"


@functools.cache
def _symbols() -> tuple[Any, ...]:
    """(bend, swivel, body parameters, t, β₀, T): the SymPy symbols of the cat and its loop."""
    import sympy as sp

    bend, swivel = sp.symbols("bend swivel", real=True)
    params = sp.symbols("half_mass joint_offset radius half_length", positive=True)
    peak, duration = sp.symbols("beta0 T", positive=True)
    return bend, swivel, params, sp.Symbol("t", real=True), peak, duration


def _active(axis: int, angle: Any) -> Any:
    """The active rotation by ``angle`` about axis e_axis: the transpose of section 3.1's passive R_a."""
    from ...kinematics.euler import axis_rotation

    return axis_rotation(axis, angle).T


@functools.cache
def cat_body() -> Any:
    """The symbolic cat (a :class:`~.model.DeformableBody`): 12 point masses, shape coordinates (bend, swivel),
    parameters as in :data:`BODY_PARAMETERS`."""
    import sympy as sp

    from .model import DeformableBody, centred_positions

    bend, swivel, params, *_ = _symbols()
    m, a, rho, ell = params
    G = _active(1, swivel)  # carries e2 onto the bending axis n(ψ)
    local = [(ell, 0, 0), (-ell, 0, 0), (0, rho, 0), (0, -rho, 0), (0, 0, rho), (0, 0, -rho)]
    masses, points = [], []
    for side in (1, -1):  # front, rear
        Q = G * _active(2, side * bend / 2) * G.T
        for p in local:
            points.append(Q * (sp.Matrix([side * a, 0, 0]) + sp.Matrix(p)))
            masses.append(m / 6)
    return DeformableBody(masses, centred_positions(masses, points), [bend, swivel], parameters=list(params))


def _loop_expressions() -> list[Any]:
    """[β(t), ψ(t)] of the flip loop, SymPy expressions of t, β₀ and T."""
    import sympy as sp

    *_, t, peak, duration = _symbols()
    tau = t / duration
    return [peak * sp.sin(sp.pi * tau) ** 2, -(2 * sp.pi * tau - sp.sin(2 * sp.pi * tau))]


@functools.cache
def _loop_function() -> Callable[..., np.ndarray]:
    """f(t, β₀, T) → [[β, ψ], [β̇, ψ̇]], shape (..., 2, 2); ẋ by SymPy's derivative (disk-cached)."""
    from ...core.compile import compile_cached

    def build() -> tuple[list, list]:
        import sympy as sp

        *_, t, peak, duration = _symbols()
        x = _loop_expressions()
        return [t, peak, duration], [x, [sp.diff(e, t) for e in x]]
    return compile_cached(f"{CACHE_NAME}.loop", build)


def cat_loop(peak_bend: float, duration: float) -> ShapeLoop:
    """The flip loop β = β₀ sin²(πt/T), ψ = −2πt/T + sin(2πt/T), t ∈ [0, T]: straight → bent, swept, → straight.

    The swivel runs backwards (ψ: 0 → −2π) so that the cat turns the positive way about e1.

    Every shape velocity vanishes at t = 0 and T, and the formulas are analytic for all t
    (continued periodically outside [0, T]).
    """
    f = _loop_function()
    peak, T = float(peak_bend), float(duration)

    def shape(t: np.ndarray) -> np.ndarray:
        return f(np.asarray(t, dtype=float), peak, T)[..., 0, :]

    def velocity(t: np.ndarray) -> np.ndarray:
        return f(np.asarray(t, dtype=float), peak, T)[..., 1, :]

    return ShapeLoop.from_functions(shape, velocity, (0.0, T))


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
    _check_invertible(out)
    return out


def _check_invertible(p: Mapping[str, float]) -> None:
    """Refuse a body whose inertia Ĩ (3.87) is singular in double precision at the straight shape.

    There the axial moment is (4/3) m ρ² (the rings) and the transverse one (2/3) m (ρ² + ℓ² + 3 d²)
    (d the joint offset): Ω (3.92) needs Ĩ⁻¹, so their ratio (ρ² + ℓ² + 3 d²) / (2 ρ²) must stay below
    1/ε = 2^52.  Formed from the lengths' ratios to the largest, so no square under- or overflows.
    """
    rho, ell, d = p["radius"], p["half_length"], p["joint_offset"]
    big = max(rho, ell, d)
    r, l_, d_ = rho / big, ell / big, d / big
    ratio = (r * r + l_ * l_ + 3 * d_ * d_) / (2 * r * r) if r * r > 0 else float("inf")
    if not ratio <= 2.0**52:
        least = big * float(np.sqrt((l_ * l_ + 3 * d_ * d_) / (2.0**53 - 1)))
        raise InvalidInputError(
            f"expected `radius` >= {least:.6g} (the body's inertia (3.87) invertible in double precision: the "
            f"transverse/axial moment ratio (radius² + half_length² + 3 joint_offset²)/(2 radius²) <= 2^52), got "
            f"radius = {rho!r} with half_length = {ell!r}, joint_offset = {d!r}")


def cat_connection(parameters: Mapping[str, Any] | None = None) -> ShapeConnection:
    """The cat's compiled positions, masses, Ω_A (3.87), Ω (3.92), … at ``parameters``, from the disk cache.

    The functions are derived from :func:`cat_body` (only when not cached) with the body parameters
    as arguments, kept under ``deformable.cat.<quantity>``.
    """
    params = check_cat_parameters(parameters)
    return _connection(tuple(params[k] for k in BODY_PARAMETERS))


@functools.lru_cache(maxsize=32)
def _connection(values: tuple[float, ...]) -> ShapeConnection:
    return ShapeConnection.cached(CACHE_NAME, cat_body, dimension=2, parameters=BODY_PARAMETERS,
                                  values=dict(zip(BODY_PARAMETERS, values)))


# --------------------------------------------------------------------------- integrating R(t)

def _stepper() -> Any:
    """DOP853 compiled to C on y = (t, R11 … R33), ẏ = (1, RΩ) (3.86), Ω(x(t), ẋ(t)) of (3.92) along the loop;
    parameters (half_mass, joint_offset, radius, half_length, β₀, T).  None without a C compiler.

    t is a state variable because the stepper integrates autonomous systems.
    """
    from ...solvers.dop853_c import compiled_dop853

    def build() -> tuple[Any, list, list]:
        import sympy as sp

        body = cat_body()
        bend, swivel, params, t, peak, duration = _symbols()
        x = _loop_expressions()
        along = {bend: x[0], swivel: x[1], body.velocities[0]: sp.diff(x[0], t),
                 body.velocities[1]: sp.diff(x[1], t)}
        Omega = body.angular_velocity.xreplace(along)  # (3.92) at x(t), ẋ(t)
        R = sp.Matrix(3, 3, lambda a, b: sp.Symbol(f"R{a + 1}{b + 1}", real=True))
        return sp.Matrix([1, *(R * Omega)]), [t, *R], [*params, peak, duration]
    return compiled_dop853(_STEPPER, build)


def _resolve_backend(backend: str) -> tuple[str, Any]:
    """(backend actually used, the compiled stepper or None)."""
    if backend not in BACKENDS:
        raise InvalidInputError(f"expected backend one of {', '.join(map(repr, BACKENDS))}, got {backend!r}")
    stepper = None if backend == "magnus" else _stepper()
    if stepper is None and backend == "c":
        from ...solvers.dop853_c import unavailable_error
        raise unavailable_error(_STEPPER, "magnus")
    return ("c" if stepper is not None else "magnus"), stepper


def _polar(R: np.ndarray) -> np.ndarray:
    """Newton steps of the polar decomposition, R(3 − RᵀR)/2, each orthogonal to O(|RᵀR − 1|²), until R is.

    DOP853 keeps RᵀR = 1 only to its tolerance (~1e-13 at the default rtol, ~1e-4 at the loosest a
    scene allows, 1e-2); the steps make each R a rotation to rounding (one step from 1e-13, three from
    1e-4) and move it by no more than that deviation (smoothly in t).
    """
    for _ in range(8):
        RtR = np.einsum("...ba,...bc->...ac", R, R)
        R = 0.5 * np.einsum("...ab,...bc->...ac", R, 3 * np.eye(3) - RtR)
        if not np.max(np.abs(RtR - np.eye(3)), initial=0.0) > 1e-8:  # the step just taken squared it to rounding
            return R
    return R


def _dop853_rtol(rtol: float) -> float:
    """The tolerance given to DOP853 for a target ``rtol`` of R: 100× tighter, at least SciPy's 100 ε.

    DOP853's tolerance bounds the error of each step, not of R at the end: for the default cat at
    tolerance 1e-12, R came out ~4e-12 from a run at 2.3e-14, while the Magnus steps at rtol 1e-12
    are ~1e-13 off (against the one-dimensional reduction of the tests).
    """
    from ...solvers.dop853_c import MIN_RTOL

    return max(rtol / 100, MIN_RTOL)


def _rotations_c(stepper: Any, values: tuple[float, ...], peak: float, T: float, times: np.ndarray,
                 rtol: float) -> np.ndarray:
    """R(t) at ``times`` (increasing), R(times[0]) = 1, by the compiled stepper at tolerance ``rtol``: (N, 3, 3)."""
    y0 = np.concatenate([[times[0]], np.eye(3).ravel()])
    # R's entries are O(1) and cross zero: the absolute tolerance equals the relative one
    y, _ = stepper.solve(times, y0, [*values, peak, T], rtol, rtol)
    return _polar(y[:, 1:].reshape(-1, 3, 3))


def _stencil_rotations(conn: ShapeConnection, loop: ShapeLoop, R: np.ndarray, times: np.ndarray,
                       offsets: np.ndarray) -> np.ndarray:
    """R(t_k + o_j) = R(t_k) exp(Ω_kj) (3.98), Ω_kj one 6th-order Magnus step over [t_k, t_k + o_j]: (N, J, 3, 3).

    For the finite differences of L the stencil needs R smooth in o_j to rounding; DOP853's dense output
    is accurate only to its tolerance, and differently in each step.  One Magnus step over |o_j| ≤ 4δ
    is exact to rounding (error ~ (|Ω| 4δ)⁷) and exactly a rotation.
    """
    from ...kinematics.magnus import magnus_exponent
    from ...kinematics.so3 import expm_so3
    from .holonomy import _angular_velocity

    t, h = np.broadcast_arrays(times[:, None], offsets[None, :])
    exponent = magnus_exponent(_angular_velocity(conn, loop), t, h, order=6, ordering="right")
    return np.einsum("nab,nkbc->nkac", R, expm_so3(exponent))


def _half_turn_residual(values: tuple[float, ...], peak: float, rtol: float, backend: str,
                        stepper: Any) -> tuple[float, float]:
    """(sin θ, cos θ) of the net rotation's angle θ about e1 after one loop with peak bend ``peak`` (T = 1)."""
    if backend == "c":
        R = _rotations_c(stepper, values, peak, 1.0, np.array([0.0, 1.0]), _dop853_rtol(rtol))[-1]
    else:
        R = net_rotation(_connection(values), cat_loop(peak, 1.0), rtol=rtol).R
    return 0.5 * (R[2, 1] - R[1, 2]), 0.5 * (R[1, 1] + R[2, 2])


def _brent(f: Callable[[float], float], xa: float, xb: float, xtol: float, rtol: float, maxiter: int = 100) -> float:
    """A zero of f in [xa, xb] (f(xa) f(xb) ≤ 0) by Brent's method, step for step as SciPy's ``brentq``.

    Brent, *Algorithms for Minimization without Derivatives* (1973), ch. 4: inverse quadratic
    interpolation or secant steps, safeguarded by bisection; converged when the bracket is below
    xtol + rtol |x|.  Kept here so that a warm run does not import ``scipy.optimize`` (~0.5 s).
    """
    xpre, xcur = xa, xb
    fpre, fcur = f(xpre), f(xcur)
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and np.signbit(fpre) != np.signbit(fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):  # keep the better end as xcur
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # secant
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # inverse quadratic interpolation
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry  # a good short step
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = f(xcur)
    raise IntegrationError(f"expected Brent's method to converge in {maxiter} iterations, got the bracket "
                           f"[{min(xcur, xblk)!r}, {max(xcur, xblk)!r}]")


def flip_bend(parameters: Mapping[str, Any] | None = None, *, rtol: float = 1e-13, backend: str = "auto") -> float:
    """The peak bend β₀ (rad) of :func:`cat_loop` whose net rotation is a half turn about e1.

    Solves sin θ(β₀) = 0 with cos θ < 0 (θ the rotation angle about e1 of the holonomy (3.98)) by Brent's
    method, bracketing on a grid of β₀; the net rotation does not depend on the duration (3.98).
    Each θ(β₀) integrates Ṙ = RΩ (3.86) once around the loop (``backend``: see :data:`BACKENDS`).
    Cached per body.
    """
    params = check_cat_parameters(parameters)
    used, _ = _resolve_backend(backend)
    return _flip_bend(tuple(params[k] for k in BODY_PARAMETERS), float(rtol), used)


@functools.lru_cache(maxsize=32)
def _flip_bend(values: tuple[float, ...], rtol: float, backend: str) -> float:
    _, stepper = _resolve_backend(backend)
    grid = np.linspace(0.2, 3.0, 15)
    signs = [_half_turn_residual(values, b, 1e-9, backend, stepper) for b in grid]
    for (b0, (s0, c0)), (b1, (s1, c1)) in zip(zip(grid, signs), zip(grid[1:], signs[1:])):
        if s0 * s1 <= 0 and c0 < 0 and c1 < 0:
            return float(_brent(lambda b: _half_turn_residual(values, b, rtol, backend, stepper)[0], b0, b1,
                                xtol=1e-15, rtol=1e-15))
    # the turn at the largest bend: short of π, the body is too stout for any bend in the grid; past it,
    # it turned over at a bend below the grid's first (too slender for the search)
    short = signs[-1][0] > 0
    p = dict(zip(BODY_PARAMETERS, values))
    raise InvalidInputError(
        f"expected a body whose halves turn it over with a peak bend between {grid[0]:.2f} and {grid[-1]:.2f} rad "
        f"(the default cat's, radius/half_length = {DEFAULTS['radius'] / DEFAULTS['half_length']:.3g}, do), "
        f"got `radius`/`half_length` = {p['radius'] / p['half_length']:.3g} (`joint_offset`/`half_length` = "
        f"{p['joint_offset'] / p['half_length']:.3g}): "
        + ("too stout, a bend of 3.00 rad turns it by less than π" if short else
           "too slender, it turns by π at a bend below 0.20 rad"))


@dataclass(frozen=True)
class FallingCat:
    """A computed flip.

    Attributes
    ----------
    t : (N,) times (s); R : (N, 3, 3) orientation, section 3.7's active R(t) (R(0) = 1);
    shapes : (N, 2) (bend, swivel) in rad; flip_angle : (N,) rotation angle about e1, unwrapped (rad);
    angular_momentum : (N, 3) L = Σ m r × ṙ in space components (kg m²/s), from finite differences
    of r_i(t) = R(t) r̃_i(x(t)) — independent of Ω; peak_bend : β₀ (rad); error_estimate : the
    integrator's global error estimate of R (rad); parameters : the body parameters used;
    backend : how R was integrated, ``"c"`` or ``"magnus"`` (see :data:`BACKENDS`).
    """

    t: np.ndarray
    R: np.ndarray
    shapes: np.ndarray
    flip_angle: np.ndarray
    angular_momentum: np.ndarray
    peak_bend: float
    error_estimate: float
    parameters: dict
    backend: str = "magnus"


#: 8th-order central differences: f'(t) ≈ Σ_j c_j f(t + jδ)/δ, j = −4 … 4.
_FD = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0.0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])


def falling_cat(parameters: Mapping[str, Any] | None = None, *, duration: float = 1.0, samples: int = 101,
                rtol: float = 1e-12, backend: str = "auto") -> FallingCat:
    """The flip over t ∈ [0, duration]: orientation, shapes and the space angular momentum at ``samples`` times.

    L is computed from its definition Σ m_i r_i × ṙ_i with ṙ_i by 8th-order central differences
    (step δ = min(10⁻³ T, Δt/10)) of r_i(t) = R(t) r̃_i(x(t)), R integrated on [−4δ, T + 4δ]
    (the loop's formulas continue analytically) — so it tests Ω and the integration together.
    (With DOP853, R is integrated on [0, T] and continued from each sample to its stencil by one
    Magnus step: then L tests Ω and the orthogonality of R, and the flip angle tests R's accuracy.)

    ``backend`` (see :data:`BACKENDS`) integrates Ṙ = RΩ (3.86) and finds the peak bend.  The error
    estimate is the Magnus steps' own (step doubling), or for compiled DOP853 (run at rtol/100, at
    least 100 ε) the largest entry of R minus a second run at 10× that tolerance — an upper estimate,
    the error falling with the tolerance.  With DOP853 the stencil of the differences is R(t_k)
    continued by one Magnus step to each t_k + jδ (:func:`_stencil_rotations`).
    """
    params = check_cat_parameters(parameters)
    if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not np.isfinite(duration) \
            or not duration > 0:
        raise InvalidInputError(f"expected `duration` (t_end) finite and > 0, got {duration!r}")
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2:
        raise InvalidInputError(f"expected `samples` to be an integer >= 2, got {samples!r}")
    used, stepper = _resolve_backend(backend)
    peak = params.get("peak_bend")
    if peak is None:
        peak = flip_bend(params, backend=used)
    values = tuple(params[k] for k in BODY_PARAMETERS)
    conn = _connection(values)
    T = float(duration)
    times = np.linspace(0.0, T, int(samples))
    delta = min(1e-3 * T, (times[1] - times[0]) / 10)
    offsets = delta * np.arange(-4, 5)
    stencil = (times[:, None] + offsets[None, :]).ravel()
    loop = cat_loop(peak, T)
    if used == "c":
        tol = _dop853_rtol(rtol)
        centre = _rotations_c(stepper, values, float(peak), T, times, tol)
        estimate = float(np.max(np.abs(centre - _rotations_c(stepper, values, float(peak), T, times, 10 * tol))))
        rotations = _stencil_rotations(conn, loop, centre, times, offsets)
    else:
        extended = ShapeLoop.from_functions(loop.shape, loop.velocity, (stencil[0], stencil[-1]))
        run = rotation_along(conn, extended, rtol=rtol, t_eval=stencil)
        rotations, estimate = run.rotations, run.error_estimate
    Rs = rotations.reshape(len(times), 9, 3, 3)
    start = Rs[0, 4]
    Rs = np.einsum("ba,nkbc->nkac", start, Rs)  # R(0) = 1: a constant rotation of the whole motion
    shapes_all = loop.shape(stencil).reshape(len(times), 9, 2)
    r = np.einsum("nkab,nkib->nkia", Rs, conn.positions(shapes_all))  # (N, 9, masses, 3)
    rdot = np.einsum("k,nkia->nia", _FD, r) / delta
    L = np.einsum("i,nia->na", conn.masses, np.cross(r[:, 4], rdot))
    R = Rs[:, 4]
    flip = np.unwrap(np.arctan2(R[:, 2, 1] - R[:, 1, 2], R[:, 1, 1] + R[:, 2, 2]))
    return FallingCat(times, R, shapes_all[:, 4], flip, L, float(peak), estimate,
                      {k: params[k] for k in BODY_PARAMETERS}, used)


def falling_cat_motion(parameters: dict | None = None, *, t_end: float, samples: int,
                       rtol: float = 1e-12) -> dict[str, np.ndarray]:
    """Time series of the falling cat for a scene: a 180° flip over t ∈ [0, t_end] with L = 0.

    Returns arrays of length ``samples`` named ``t``; ``R11 … R33`` — the orientation of the
    cat's reference body in section 3.1's convention e_a = R_ab ẽ_b, i.e. R(3.1) = R(3.7)ᵀ;
    ``q0 q1 q2 q3`` — the scalar-first unit quaternion of the active rotation R(3.7) (sign
    continuous in time, q0(0) = 1); ``flip_angle`` (rad, 0 → π); ``shape_bend``,
    ``shape_swivel`` (rad); ``L1 L2 L3`` — the angular momentum in space components
    (kg m²/s, zero to integration accuracy).  ``parameters``: see :func:`check_cat_parameters`;
    ``rtol`` as in :func:`falling_cat`.
    """
    return cat_columns(falling_cat(parameters, duration=t_end, samples=samples, rtol=rtol))


def cat_columns(cat: FallingCat) -> dict[str, np.ndarray]:
    """The named time series of :func:`falling_cat_motion` from a computed :class:`FallingCat`."""
    from ...kinematics.conversions import matrix_to_quaternion

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
