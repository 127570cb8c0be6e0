"""Numerical integration of the free (or torqued) rigid body: Euler's equations (3.33) plus orientation.

State: the body components ω_a of the angular velocity (rad/s) and the orientation
as the unit quaternion q (scalar first) of the active rotation A = Rᵀ — never Euler
angles, which are singular at θ = 0.  Output R(t) is the chapter's passive matrix,
e_a = R_ab ẽ_b (rows = body axes in space components), with Ṙ = hat(ω) R (3.11).

Equations, all derived and compiled, not typed in:

* ω̇ from :attr:`FreeTopModel.euler_rhs` (Euler's equations with torque, (3.33) extended:
  I1 ω̇1 = (I2 - I3) ω2 ω3 + τ1 and cyclically, τ in body components), evaluated in that
  grouping (:func:`gyroscopic_form`: exactly 0 for equal moments);
* q̇ = ½ q ⊗ (0, ω), derived from Ṙ = hat(ω) R in :mod:`mechderive.solvers.quaternion`;

compiled together into one scalar function with :func:`compile_scalar`.  The Euler angles of
R(t) are returned too, their turns counted along every step (:mod:`mechderive.solvers.half_angles`).

Methods (``method=``):

``"DOP853"``
    Dormand–Prince 8(5,3), adaptive, ``rtol`` / ``atol`` (default 1e-10 / 1e-12, applied to ω
    and q alike), output at ``t_eval`` by the 7th-order dense output.  ``backend="auto"``
    (default) runs it compiled to C with the derived right-hand side
    (:mod:`mechderive.solvers.dop853_c`) where a C compiler is found and no ``torque`` is
    given, else SciPy's :func:`scipy.integrate.solve_ivp` (the same steps, ~100× slower);
    ``"c"`` or ``"scipy"`` choose.
    The quaternion is integrated unconstrained — |q| is a first integral of
    q̇ = ½ q ⊗ (0, ω), so its drift measures the integrator's error — then
    *projected* (q/|q|) at output; the drift before projection is reported, not hidden.
    A torque τ(t, ω, R) (body components, N·m) may be given.

``"splitting"``
    The explicit Lie–Poisson splitting of the free body (McLachlan 1993, PRL 71, 3043;
    Touma & Wisdom 1994; :mod:`mechderive.solvers.lie_poisson`): exact rotations
    about the body axes, Strang-composed (order 2) and raised to order 4 / 6 by
    Suzuki's 5-stage fractal / Yoshida's 7-stage solution A (``order=``).  |L| is
    kept to rounding and the energy error stays bounded over arbitrarily long runs.
    Fixed step: each interval of ``t_eval`` is cut into ceil(Δt/step) equal steps.
    Free body only.

Units: any consistent set (kg m², rad/s, s, N m).

>>> import numpy as np
>>> run = integrate_free_top([1.0, 2.0, 3.0], [1.0, 0.5, 1.0], np.linspace(0.0, 5.0, 6),
...                          rtol=1e-12, atol=1e-14)
>>> np.round(run.omega[-1], 9).tolist()       # mpmath (30 digits): 0.325386510, -1.069637144, 0.837829812
[0.32538651, -1.069637144, 0.837829812]
>>> run.R.shape, bool(run.energy_drift < 1e-11)
((6, 3, 3), True)
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ...core.validate import as_finite_array, check_positive, check_rotation_matrix
from ...errors import IntegrationError, InvalidInputError, ShapeError  # noqa: F401 (IntegrationError re-exported)
from ...kinematics.conversions import matrix_to_quaternion, quaternion_to_matrix
from ...solvers import lie_poisson
from ...solvers.dop853 import check_backend, run_dop853
from ...solvers.limits import (MAX_STEPS, check_fixed_steps, check_max_steps, check_outputs, first_nonfinite_row,
                               nonfinite_state)
from ...solvers.composition import suzuki_fractal, yoshida6
from ...solvers.half_angles import (euler_angles_from_half_angles, follow_fixed_steps, initial_half_angles,
                                    output_error_estimates)

__all__ = ["integrate_free_top", "integrate_free_top_ensemble", "FreeTopTrajectory", "FreeTopEnsemble",
           "IntegrationError", "METHODS", "SPLITTING_ORDERS", "RICHARDSON_MARGIN", "gyroscopic_form"]

METHODS = ("DOP853", "splitting")
#: Composition weights used for each order of the splitting (see mechderive.solvers.composition).
SPLITTING_ORDERS: dict[int, tuple[float, ...]] = {2: (1.0,), 4: suzuki_fractal(4), 6: yoshida6()}
#: Richardson's |y_h - y_(h/2)| · 2^p/(2^p - 1) is the error up to relative corrections O(h) (a few %
#: at the steps used); this margin makes the reported estimate cover them.
RICHARDSON_MARGIN = 1.25

Torque = Callable[[float, np.ndarray, np.ndarray], Any]


# --- results ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class FreeTopTrajectory:
    """One integrated motion.

    Attributes
    ----------
    t : (N,) times (s); ``t[0]`` is the initial time.
    omega : (N, 3) body components of ω (rad/s).
    quaternion : (N, 4) unit quaternion of A = Rᵀ, scalar first (projected onto |q| = 1).
    euler_angles : (N, 3) Euler angles (φ, θ, ψ) (3.54) with R(φ, θ, ψ) = R, φ and ψ continuous, their
        turns counted along every step of the integrator, not unwrapped from the samples
        (:mod:`~mechderive.solvers.half_angles`; as for the heavy top,
        :class:`~mechderive.systems.heavy_top.integrate.HeavyTopTrajectory`); at t0 those of R0 from
        :func:`~mechderive.kinematics.rotations.euler_angles_from_matrix`, except that a run starting
        exactly at θ = 0 (π) with e3 moving takes φ - ψ (φ + ψ) from the direction in which it leaves.
    R : (N, 3, 3) the chapter's R, e_a = R_ab ẽ_b (computed from ``quaternion`` on access).
    energy_drift : max_t |T(t) - T(t0)| / T(t0), T = ½ I_a ω_a² (3.46); physical, not an error, under torque.
    angular_momentum_drift : max_t | |L|(t) - |L|(t0) | / |L|(t0), |L|² from (3.47).
    quaternion_norm_drift : max_t | |q| - 1 | before projection.
    n_evaluations : right-hand-side evaluations (DOP853) or exact axis sub-flows (splitting).
    n_steps : accepted steps (DOP853) or fixed steps (splitting).
    error_estimate : one estimate that covers everything output — the largest of the three below
        (ω in rad/s; R, q and the angles in rad) — or ``None`` if not requested.
    omega_error_estimate : estimated max_t |ω - ω_exact| (rad/s), or ``None``.
    rotation_error_estimate : estimated max_t of the rotation angle between R and R_exact (rad), widened
        to bound every |R_ij - R_exact,ij| and |q - q_exact| too, or ``None``.
    euler_angle_error_estimate : estimated max_t |Δφ|, |Δθ|, |Δψ| (rad), or ``None``; at least 2π n when
        e3 passed n times closer to ẽ3 (or -ẽ3) than the error of R can resolve
        (``unresolved_passages``: φ and ψ are then known only modulo 2π).
    error_estimate_kind : how they were obtained (see :func:`integrate_free_top`).
    wall_time : seconds spent in the main run (excluding the error-estimate run).
    backend : ``"c"`` (compiled DOP853), ``"scipy"`` (SciPy's DOP853) or ``"python"`` (the splitting).
    unresolved_passages : see ``euler_angle_error_estimate`` (0 without an estimate).
    pole_clearance : lower bounds of min_t sin(θ/2) and min_t cos(θ/2) along the integrated path.
    """

    t: np.ndarray
    omega: np.ndarray
    quaternion: np.ndarray
    euler_angles: np.ndarray
    method: str
    order: int | None
    energy_drift: float
    angular_momentum_drift: float
    quaternion_norm_drift: float
    n_evaluations: int
    n_steps: int | None
    error_estimate: float | None
    error_estimate_kind: str
    wall_time: float
    backend: str = "scipy"
    omega_error_estimate: float | None = None
    rotation_error_estimate: float | None = None
    euler_angle_error_estimate: float | None = None
    unresolved_passages: int = 0
    pole_clearance: tuple[float, float] = (math.inf, math.inf)

    @functools.cached_property
    def R(self) -> np.ndarray:
        """(N, 3, 3) rotation matrices of the chapter's convention, e_a = R_ab ẽ_b."""
        return quaternion_to_matrix(self.quaternion)


@dataclass(frozen=True)
class FreeTopEnsemble:
    """M free bodies integrated together by the splitting (shapes (N, M, ·)); see :class:`FreeTopTrajectory`."""

    t: np.ndarray
    omega: np.ndarray
    quaternion: np.ndarray
    order: int
    energy_drift: np.ndarray
    angular_momentum_drift: np.ndarray
    quaternion_norm_drift: np.ndarray
    n_steps: int
    wall_time: float

    @property
    def R(self) -> np.ndarray:
        """(N, M, 3, 3) rotation matrices, e_a = R_ab ẽ_b."""
        return quaternion_to_matrix(self.quaternion)

    @property
    def body_steps_per_second(self) -> float:
        """Throughput: bodies × steps / wall time."""
        return self.omega.shape[1] * self.n_steps / self.wall_time if self.wall_time > 0 else math.inf


# --- compiled equations ----------------------------------------------------------------------

def gyroscopic_form(rows: Any, omega: Sequence[Any]) -> list:
    """Euler's equations (3.33) regrouped for evaluation: ((I_b - I_c)/I_a) ω_b ω_c + rest, per row.

    The model states them expanded, I_b ω_b ω_c / I_a - I_c ω_b ω_c / I_a; evaluated so, the two
    products round differently and leave ~ε·I_b ω_b ω_c / I_a where the exact value is 0 (I_b = I_c:
    a symmetric body's ω̇_a = 0 drifts by 1e-10 over 100 s at I = (1, 1e3, 1e3)) — an error no rerun
    at a tighter tolerance can see, since it is in the equation.  Forming the difference of the
    moments first is exact when they are equal and keeps full relative accuracy when they are close.
    Each row is the same expression (checked by the tests), only grouped.
    """
    import itertools

    import sympy as sp

    products = [a * b for a, b in itertools.combinations_with_replacement(omega, 2)]
    out = []
    for row in rows:
        terms = sp.collect(sp.expand(row), products, evaluate=False)
        out.append(sp.Add(*(sp.together(c) * m for m, c in terms.items())))
    return out


def _state_exprs() -> tuple[Any, list, list]:
    """((ω̇, q̇), state symbols (ω, q), parameter symbols (I1..3, τ1..3)) of the free body."""
    import sympy as sp

    from ...solvers.quaternion import quaternion_rate_expressions
    from .model import I1, I2, I3, model, omega_symbols, tau_symbols

    w = omega_symbols()
    q = sp.symbols("q0:4", real=True)
    exprs = sp.Matrix([*gyroscopic_form(model().euler_rhs, w), *quaternion_rate_expressions(q, w)])
    return exprs, [*w, *q], [I1, I2, I3, *tau_symbols]


@functools.cache
def _state_rhs() -> Callable[..., list]:
    """(ω̇, q̇) as one compiled scalar function of (ω1..3, q0..3, I1..3, τ1..3)."""
    from ...core.compile import compile_scalar

    exprs, state, par = _state_exprs()
    return compile_scalar(exprs, [*state, *par], name="free_top_state_rhs")


def _compiled_dop853() -> Any:
    """The DOP853 stepper compiled to C with (ω̇, q̇) of the free body (τ as parameters), or None."""
    from ...solvers.dop853_c import compiled_dop853

    return compiled_dop853("free_top", _state_exprs)


@functools.cache
def _invariants() -> tuple[Callable[..., Any], Callable[..., Any]]:
    """Vectorised T(ω, I) (3.46) and L²(ω, I) (3.47), compiled from the model (disk-cached)."""
    from ...core.compile import compile_cached

    def build(quantity: str):
        def derive():
            from .model import I1, I2, I3, model, omega_symbols

            return [*omega_symbols(), I1, I2, I3], getattr(model(), quantity)
        return derive
    return (compile_cached("free_top.energy", build("energy")),
            compile_cached("free_top.L_squared", build("angular_momentum_squared")))


def _drifts(omega: np.ndarray, inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Max relative deviation of T and |L| from their initial values; omega (N, ..., 3), inertia (..., 3)."""
    energy, lsq = _invariants()
    w = np.moveaxis(omega, -1, 0)
    Ia = np.moveaxis(np.broadcast_to(inertia, omega.shape), -1, 0)
    T = np.asarray(energy(w[0], w[1], w[2], Ia[0], Ia[1], Ia[2]))
    L = np.sqrt(np.asarray(lsq(w[0], w[1], w[2], Ia[0], Ia[1], Ia[2])))

    def rel(x: np.ndarray) -> np.ndarray:
        scale = np.where(x[0] > 0, x[0], 1.0)
        return np.max(np.abs(x - x[0]), axis=0) / scale

    return rel(T), rel(L)


# --- input checks ----------------------------------------------------------------------------

def _check_inertia(I: Any, shape: tuple[int | None, ...], strict: bool = True) -> np.ndarray:
    from ...inertia.validate import check_principal_moments

    arr = as_finite_array(I, "I", shape=shape)
    check_principal_moments(arr[..., 0], arr[..., 1], arr[..., 2], strict=strict)
    return arr


def _check_times(t_eval: Any) -> np.ndarray:
    t = as_finite_array(t_eval, "t_eval", shape=(None,))
    if t.size < 2:
        raise InvalidInputError(f"expected `t_eval` to hold at least 2 times, got {t.size}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        k = int(bad[0])
        raise InvalidInputError(
            f"expected `t_eval` strictly increasing, got t_eval[{k + 1}] = {t[k + 1]:g} <= t_eval[{k}] = {t[k]:g}")
    return t


def _check_method(method: str) -> str:
    if method not in METHODS:
        raise InvalidInputError(f"expected method one of {', '.join(map(repr, METHODS))}, got {method!r}")
    return method


def _check_order(order: int) -> int:
    if order not in SPLITTING_ORDERS:
        raise InvalidInputError(f"expected order one of {', '.join(map(str, SPLITTING_ORDERS))}, got {order!r}")
    return order


def _initial_quaternion(R0: Any, name: str = "R0") -> np.ndarray:
    if R0 is None:
        return np.array([1.0, 0.0, 0.0, 0.0])
    arr = np.asarray(R0, dtype=float)
    if arr.shape != (3, 3):
        raise ShapeError(f"expected `{name}` to have shape (3, 3), got {arr.shape}")
    return matrix_to_quaternion(check_rotation_matrix(arr, name))


def _initial_half_angles(q0: np.ndarray) -> tuple[np.ndarray, tuple[float, float]]:
    """(q0 with the sign of euler_to_quaternion(φ0, θ0, ψ0), (σ0, δ0)) for the Euler angles of R(q0)."""
    from ...kinematics.conversions import euler_to_quaternion
    from ...kinematics.rotations import euler_angles_from_matrix

    phi, theta, psi = (float(v) for v in euler_angles_from_matrix(quaternion_to_matrix(q0)))
    if float(np.dot(euler_to_quaternion(phi, theta, psi), q0)) < 0.0:
        q0 = -q0  # the same rotation; the tracked arguments are those of euler_to_quaternion's sign
    return q0, initial_half_angles(phi, psi)


def _project(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(q/|q|, max over time of ||q| - 1|) for q of shape (N, ..., 4)."""
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    return q / norm, np.max(np.abs(norm[..., 0] - 1.0), axis=0)


# --- the public entry points -----------------------------------------------------------------

def integrate_free_top(I: Sequence[float], omega0: Sequence[float], t_eval: Sequence[float], *,
                       R0: Any = None, method: str = "DOP853", rtol: float | None = None,
                       atol: float | None = None, step: float | None = None, order: int | None = None,
                       torque: Torque | None = None, estimate_error: bool = True,
                       backend: str = "auto", strict: bool = True, max_steps: int | None = None) -> FreeTopTrajectory:
    """Integrate Euler's equations (3.33) and the orientation from ω(t_eval[0]) = omega0, R(t_eval[0]) = R0.

    Parameters
    ----------
    I : principal moments (I1, I2, I3), positive, obeying the triangle inequalities (kg m²).
    strict : ``False`` accepts moments that violate the triangle inequalities (no rigid body has
        them, e.g. (3, 3, 9)); positive, finite moments are required all the same.
    omega0 : initial body components of ω (rad/s).
    t_eval : strictly increasing output times (s), at least 2; the motion starts at ``t_eval[0]``.
    R0 : initial rotation matrix (e_a = R_ab ẽ_b); default the identity.
    method : ``"DOP853"`` (adaptive; ``rtol``, ``atol``, ``torque``) or ``"splitting"``
        (geometric, fixed step ``step`` (s), ``order`` 2, 4 (default) or 6; free body only).
    torque : τ(t, ω, R) -> body components (3,) of the applied torque (DOP853 only; runs on SciPy,
        since it calls back into Python).
    backend : DOP853 only: ``"auto"``, ``"c"`` (raises :class:`IntegrationError` without a C
        compiler, or with a torque) or ``"scipy"``.
    estimate_error : estimate the error of every output — ω (rad/s), R and q, the Euler angles
        (rad) — by one extra run: ``omega_error_estimate``, ``rotation_error_estimate``,
        ``euler_angle_error_estimate`` and their maximum ``error_estimate``, the recipe in
        ``error_estimate_kind`` (:func:`~mechderive.solvers.half_angles.output_error_estimates`):
        DOP853 — the distance to a rerun at rtol/1000, atol/1000, × 1/(1 - √r) for the ratio r of
        the tolerances (:func:`~mechderive.solvers.dop853.reference_tolerance`: the rerun's rtol
        is floored at 2.3e-14, SciPy's limit; below 2.3e-13 it runs looser, at 10·rtol, and the
        figure is an upper bound ~10× the error); splitting — Richardson with the known order p,
        |y_h - y_(h/2)| · 2^p / (2^p - 1) · 1.25 (the rerun costs twice the main run).
    max_steps : steps allowed to each run (default :data:`~mechderive.solvers.limits.MAX_STEPS` = 10⁷):
        DOP853 stops there with an :class:`IntegrationError` saying where it got to; the splitting,
        whose steps are known in advance, refuses at once.

    Raises :class:`~mechderive.errors.UnphysicalInertiaError`, :class:`~mechderive.errors.ShapeError`,
    :class:`~mechderive.errors.InvalidInputError` on bad input, :class:`IntegrationError` when a run
    cannot reach ``t_eval[-1]``: the state stops being finite (a value out of floating-point range, or
    a torque that blows the motion up), the step size collapses, or ``max_steps`` is reached.
    Compiled runs return to Python every ~0.05 s, so Ctrl-C stops them.
    """
    method = _check_method(method)
    max_steps = check_max_steps(max_steps)
    backend = check_backend(backend)
    inertia = _check_inertia(I, (3,), strict)
    w0 = as_finite_array(omega0, "omega0", shape=(3,))
    t = _check_times(t_eval)
    q0 = _initial_quaternion(R0)
    if method == "DOP853":
        for name, value in (("step", step), ("order", order)):
            if value is not None:
                raise InvalidInputError(f"expected `{name}` only with method='splitting', got {name}={value!r} "
                                        "with method='DOP853'")
        rtol = 1e-10 if rtol is None else check_positive(rtol, "rtol")
        atol = 1e-12 if atol is None else check_positive(atol, "atol")
        if torque is not None and not callable(torque):
            raise InvalidInputError(f"expected `torque` to be callable τ(t, omega, R), got {torque!r}")
        return _checked(_run_dop853, inertia, w0, q0, t, rtol, atol, torque, estimate_error, backend, max_steps)
    if backend != "auto":
        raise InvalidInputError(f"expected `backend` only with method='DOP853', got backend={backend!r} "
                                "with method='splitting'")
    for name, value in (("rtol", rtol), ("atol", atol)):
        if value is not None:
            raise InvalidInputError(f"expected `{name}` only with method='DOP853', got {name}={value!r} "
                                    "with method='splitting' (set `step` instead)")
    if torque is not None:
        raise InvalidInputError("expected torque=None with method='splitting' (a free-body integrator), "
                                "got a torque; use method='DOP853'")
    if step is None:
        raise InvalidInputError("expected a step size `step` > 0 with method='splitting', got step=None")
    step = check_positive(step, "step")
    order = _check_order(4 if order is None else order)
    return _checked(_run_splitting, inertia, w0, q0, t, step, order, estimate_error, max_steps)


def integrate_free_top_ensemble(I: Any, omega0: Any, t_eval: Sequence[float], *, step: float, order: int = 4,
                                R0: Any = None, strict: bool = True, max_steps: int | None = None) -> FreeTopEnsemble:
    """Integrate M free bodies at once with the Lie–Poisson splitting (for stability maps).

    ``omega0`` has shape (M, 3); ``I`` shape (3,) (common) or (M, 3) (one body each);
    ``R0`` None, (3, 3) or (M, 3, 3).  Output arrays are (N, M, ·): mind N·M·56 bytes.
    ``strict=False`` accepts moments no rigid body has (as :func:`integrate_free_top`).
    ``max_steps`` as in :func:`integrate_free_top` (steps of each member); a member whose state stops
    being finite raises :class:`IntegrationError` naming it.

    >>> import numpy as np
    >>> w0 = np.array([[1.0, 0.5, 1.0], [0.0, 1.0, 0.01]])
    >>> ens = integrate_free_top_ensemble([1.0, 2.0, 3.0], w0, [0.0, 5.0], step=0.01, order=6)
    >>> np.round(ens.omega[-1, 0], 9).tolist()
    [0.32538651, -1.069637144, 0.837829812]
    """
    w0 = as_finite_array(omega0, "omega0", shape=(None, 3))
    M = w0.shape[0]
    inertia = _check_inertia(I, (M, 3) if np.ndim(I) == 2 else (3,), strict)
    t = _check_times(t_eval)
    step = check_positive(step, "step")
    order = _check_order(order)
    intervals = _interval_steps(t, step)
    check_fixed_steps("the Lie–Poisson splitting", sum(n for n, _ in intervals), check_max_steps(max_steps),
                      step=step, t_end=float(t[-1]))
    if R0 is None or np.ndim(R0) == 2:
        q0 = np.broadcast_to(_initial_quaternion(R0), (M, 4))
    else:
        arr = np.asarray(R0, dtype=float)
        if arr.shape != (M, 3, 3):
            raise ShapeError(f"expected `R0` to have shape (3, 3) or ({M}, 3, 3), got {arr.shape}")
        q0 = matrix_to_quaternion(check_rotation_matrix(arr, "R0"))
    weights = SPLITTING_ORDERS[order]
    I_cols = inertia.T if inertia.ndim == 2 else inertia  # (3, M) or (3,)
    L = np.array((np.broadcast_to(inertia, (M, 3)) * w0).T, order="C")  # (3, M), a writable copy
    q = np.array(q0.T, order="C")  # (4, M)
    omegas, quats = [w0.copy()], [q0.copy()]
    n_total = 0
    start = time.perf_counter()
    with np.errstate(all="ignore"):  # a state out of range is said below, not as RuntimeWarnings
        for k, (n, h) in enumerate(intervals):
            lie_poisson.propagate_ensemble(L, q, I_cols, h, n, weights)
            bad = first_nonfinite_row(np.vstack([L, q]).T)
            if bad is not None:
                raise nonfinite_state("the Lie–Poisson splitting", t=float(t[k]), steps=n_total, member=bad)
            n_total += n
            omegas.append((L / np.reshape(I_cols, (3, -1))).T.copy())
            quats.append(q.T.copy())
    wall = time.perf_counter() - start
    with np.errstate(all="ignore"):
        omega = np.stack(omegas)
        quat, norm_drift = _project(np.stack(quats))
        e_drift, l_drift = _drifts(omega, inertia)
    check_outputs("the Lie–Poisson splitting", dict(omega=omega, quaternion=quat, energy_drift=e_drift,
                                                    angular_momentum_drift=l_drift))
    return FreeTopEnsemble(t=t, omega=omega, quaternion=quat, order=order, energy_drift=e_drift,
                           angular_momentum_drift=l_drift, quaternion_norm_drift=norm_drift, n_steps=n_total,
                           wall_time=wall)


# --- the two methods -------------------------------------------------------------------------

def _checked(run: Callable[..., FreeTopTrajectory], *args: Any) -> FreeTopTrajectory:
    """``run(*args)`` with NumPy's overflow warnings off, its outputs then required finite (a state
    within the floating-point range whose energy or tracking overflows is said once, clearly)."""
    with np.errstate(all="ignore"):
        traj = run(*args)
    check_outputs(f"{traj.method} (backend {traj.backend!r})", dict(
        omega=traj.omega, quaternion=traj.quaternion, euler_angles=traj.euler_angles,
        energy_drift=traj.energy_drift, angular_momentum_drift=traj.angular_momentum_drift,
        quaternion_norm_drift=traj.quaternion_norm_drift, omega_error_estimate=traj.omega_error_estimate,
        rotation_error_estimate=traj.rotation_error_estimate,
        euler_angle_error_estimate=traj.euler_angle_error_estimate))
    return traj


def _run_dop853(inertia: np.ndarray, w0: np.ndarray, q0: np.ndarray, t: np.ndarray, rtol: float, atol: float,
                torque: Torque | None, estimate_error: bool, backend: str,
                max_steps: int = MAX_STEPS) -> FreeTopTrajectory:
    I1, I2, I3 = (float(x) for x in inertia)
    compiled = None
    if backend == "c" and torque is not None:
        raise IntegrationError("expected backend='auto' or 'scipy' with a torque (it calls back into Python), "
                               "got backend='c'")
    if backend != "scipy" and torque is None:
        compiled = _compiled_dop853()
        if compiled is None and backend == "c":
            from ...solvers.dop853_c import unavailable_error
            raise unavailable_error("free_top", "scipy")
    rhs = _state_rhs() if compiled is None else None

    if compiled is not None:
        fun = None
    elif torque is None:
        def fun(_t: float, y: np.ndarray) -> list:
            return rhs(*y.tolist(), I1, I2, I3, 0.0, 0.0, 0.0)
    else:
        def fun(t_: float, y: np.ndarray) -> list:
            q = y[3:] / np.linalg.norm(y[3:])
            tau = np.asarray(torque(t_, y[:3].copy(), quaternion_to_matrix(q)), dtype=float)
            if tau.shape != (3,):
                raise ShapeError(f"expected `torque(t, omega, R)` to return shape (3,), got {tau.shape}")
            if not np.all(np.isfinite(tau)):
                raise InvalidInputError(f"expected `torque(t, omega, R)` finite, got {tau.tolist()} at t = {t_:g}")
            return rhs(*y.tolist(), I1, I2, I3, *tau.tolist())

    q0, args0 = _initial_half_angles(q0)
    y0 = np.concatenate([w0, q0])

    sol, wall, ref, kind, factor = run_dop853(fun, t, y0, rtol, atol, reference=estimate_error, compiled=compiled,
                                              params=(I1, I2, I3, 0.0, 0.0, 0.0), track=(3, args0), max_steps=max_steps)
    reference = None
    if ref is not None:
        reference = (ref.y[:3].T, ref.y[3:].T, ref.args, ref.near)
        kind = f"distance to {kind}; ω, R and the Euler angles"
    return _finish(inertia, t, (sol.y[:3].T.copy(), sol.y[3:].T, sol.args, sol.closest, sol.near), method="DOP853",
                   order=None, n_evaluations=int(sol.nfev), n_steps=sol.steps, wall=wall, reference=reference,
                   kind=kind, factor=factor, backend="scipy" if compiled is None else "c")


def _finish(inertia: np.ndarray, t: np.ndarray, run: tuple, *, method: str, order: int | None, n_evaluations: int,
            n_steps: int | None, wall: float, reference: tuple | None, kind: str, factor: float,
            backend: str) -> FreeTopTrajectory:
    """The trajectory from ``run`` = (ω, raw q, tracked (σ, δ), closest, near) and a reference run's
    (ω, raw q, (σ, δ), near) or None, whose distance × ``factor`` gives the estimates."""
    omega, q_raw, args, closest, near = run
    quat, norm_drift = _project(q_raw)
    angles = euler_angles_from_half_angles(quat, args)
    est = dict(omega=None, rotation=None, euler=None, unresolved_passages=0)
    err = None
    if reference is not None:
        w_ref, q_ref, args_ref, near_ref = reference
        q_ref = q_ref / np.linalg.norm(q_ref, axis=-1, keepdims=True)
        est = output_error_estimates((omega, quat, angles, near),
                                     (w_ref, q_ref, euler_angles_from_half_angles(q_ref, args_ref), near_ref), factor,
                                     n_steps)
        err = max(est["omega"], est["rotation"], est["euler"])
        if est["unresolved_passages"]:
            kind += (f"; e3 passed {est['unresolved_passages']} time(s) closer to ±ẽ3 than the error of R: the "
                     "turns of φ and ψ are then not determined (2π each time; φ ± ψ and R are)")
    e_drift, l_drift = _drifts(omega, inertia)
    return FreeTopTrajectory(t=t, omega=omega, quaternion=quat, euler_angles=angles, method=method, order=order,
                             energy_drift=float(e_drift), angular_momentum_drift=float(l_drift),
                             quaternion_norm_drift=float(norm_drift), n_evaluations=n_evaluations, n_steps=n_steps,
                             error_estimate=err, error_estimate_kind=kind, wall_time=wall, backend=backend,
                             omega_error_estimate=est["omega"], rotation_error_estimate=est["rotation"],
                             euler_angle_error_estimate=est["euler"], unresolved_passages=est["unresolved_passages"],
                             pole_clearance=(float(closest[1]), float(closest[0])))


def _interval_steps(t: np.ndarray, step: float, refine: int = 1) -> list[tuple[int, float]]:
    """(n, h) for each output interval: n = refine · ceil(Δt/step) equal steps of h = Δt/n."""
    out = []
    for dt in np.diff(t):
        n = max(1, math.ceil(dt / step - 1e-9)) * refine
        out.append((n, float(dt) / n))
    return out


def _splitting_path(inertia: np.ndarray, w0: np.ndarray, q0: np.ndarray, args0: tuple[float, float], t: np.ndarray,
                    step: float, weights: tuple[float, ...], refine: int = 1) -> tuple[tuple, int]:
    """((ω, raw q, (σ, δ), closest, near) at ``t``, steps): the state between every two steps is followed
    by :func:`~mechderive.solvers.half_angles.follow_fixed_steps`."""
    y0 = np.array([*(inertia * w0), *q0])
    clock = [float(t[0]), 0]  # the time and the steps done where the next pieces start, for messages

    def advance(y: np.ndarray, pieces: list[tuple[int, float]]) -> np.ndarray:
        t0, done = clock
        clock[0] += sum(n * h for n, h in pieces)
        clock[1] += sum(n for n, _ in pieces)
        rows, at = [tuple(y)], t0
        for n, h in pieces:
            L, q = lie_poisson.propagate(list(rows[-1][:3]), list(rows[-1][3:]), inertia, h, n, weights, record=rows,
                                         t0=at)
            rows.append((*L, *q))
            at += n * h
        out = np.array(rows)
        bad = first_nonfinite_row(out)
        if bad is not None:  # NaN passes through math's functions silently: said here, per batch
            steps = np.repeat([h for _, h in pieces], [n for n, _ in pieces])[:max(bad - 1, 0)]
            raise nonfinite_state("the Lie–Poisson splitting", t=t0 + float(np.sum(steps)), steps=done + len(steps))
        return out

    intervals = _interval_steps(t, step, refine)
    ends, args, tracker = follow_fixed_steps(y0, inertia, args0, intervals, advance)
    arr = np.vstack([y0, ends])
    return (arr[:, :3] / inertia, arr[:, 3:], args, tracker.closest, tracker.near), sum(n for n, _ in intervals)


def _run_splitting(inertia: np.ndarray, w0: np.ndarray, q0: np.ndarray, t: np.ndarray, step: float, order: int,
                   estimate_error: bool, max_steps: int = MAX_STEPS) -> FreeTopTrajectory:
    weights = SPLITTING_ORDERS[order]
    # the steps are known before running: the longest run (the estimate's, at step/2) is checked
    refine = 2 if estimate_error else 1
    check_fixed_steps("the Lie–Poisson splitting", sum(n for n, _ in _interval_steps(t, step, refine)), max_steps,
                      step=step / refine, t_end=float(t[-1]))
    q0, args0 = _initial_half_angles(q0)
    start = time.perf_counter()
    run, n_steps = _splitting_path(inertia, w0, q0, args0, t, step, weights)
    wall = time.perf_counter() - start
    reference, kind, factor = None, "not requested", 1.0
    if estimate_error:
        fine, _ = _splitting_path(inertia, w0, q0, args0, t, step, weights, refine=2)
        reference, factor = (fine[0], fine[1], fine[2], fine[4]), RICHARDSON_MARGIN * 2**order / (2**order - 1)
        kind = (f"Richardson: max |y_h - y_(h/2)| · 2^{order}/(2^{order} - 1) · {RICHARDSON_MARGIN}, y = ω, the "
                "orientation and the "
                "Euler angles")
    n_sub = n_steps * lie_poisson.subflows_per_step(weights) + (len(t) - 1)
    return _finish(inertia, t, run, method="splitting", order=order, n_evaluations=n_sub, n_steps=n_steps,
                   wall=wall, reference=reference, kind=kind, factor=factor, backend="python")
