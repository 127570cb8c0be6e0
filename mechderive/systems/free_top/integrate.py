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

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ...core.validate import as_finite_array, check_positive, check_rotation_matrix
from ...errors import IntegrationError, InvalidInputError, ShapeError  # noqa: F401 (IntegrationError re-exported)
from ...kinematics.conversions import matrix_to_quaternion, quaternion_to_matrix
from ...solvers import driver
from ...solvers.dop853 import check_backend
from ...solvers.driver import (METHODS, RICHARDSON_MARGIN, SPLITTING_ORDERS, Ensemble, Term, Trajectory,  # noqa: F401
                               check_times as _check_times, interval_steps as _interval_steps)
from ...solvers.half_angles import half_angles_of_quaternion
from ...solvers.limits import check_max_steps, check_outputs

__all__ = ["integrate_free_top", "integrate_free_top_ensemble", "FreeTopTrajectory", "FreeTopEnsemble",
           "IntegrationError", "METHODS", "SPLITTING_ORDERS", "RICHARDSON_MARGIN", "gyroscopic_form", "TERM"]

Torque = Callable[[float, np.ndarray, np.ndarray], Any]


# --- results ---------------------------------------------------------------------------------

@dataclass
class FreeTopTrajectory(Trajectory):
    """One integrated motion.

    Attributes (those of :class:`~mechderive.solvers.driver.Trajectory`: ``t`` (N,) times (s),
    ``omega`` (N, 3) body components of ω (rad/s), ``quaternion`` (N, 4) of A = Rᵀ, scalar first,
    projected onto |q| = 1, ``y`` the state as integrated, ``invariants``, ...; and)
    ----------
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
    energy_drift: float = 0.0
    angular_momentum_drift: float = 0.0


@dataclass
class FreeTopEnsemble(Ensemble):
    """M free bodies integrated together by the splitting (shapes (N, M, ·)); see :class:`FreeTopTrajectory`."""

    energy_drift: np.ndarray | None = None
    angular_momentum_drift: np.ndarray | None = None


# --- the derived system ----------------------------------------------------------------------

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


def _invariant_exprs() -> list:
    """T (3.46) and L² (3.47) of the model, in ω and I1..3."""
    from .model import model

    m = model()
    return [m.energy, m.angular_momentum_squared]


def _inertia(params: Sequence[Any]) -> np.ndarray:
    """(I1, I2, I3) from the parameters (I1, I2, I3, τ1, τ2, τ3) (scalars or (M,) arrays)."""
    return np.stack(np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in params[:3])), axis=-1)


#: The free body for the driver: (ω̇, q̇) in parameters (I1..3, τ1..3), its invariants T and L²,
#: the Lie–Poisson splitting.
TERM = Term("free_top", _state_exprs, invariants=_invariant_exprs, invariant_names=("energy", "L_squared"),
            quaternion=3, rhs_module="math", splitting="lie_poisson", inertia=_inertia)


def _state_rhs() -> Callable[..., list]:
    """(ω̇, q̇) as the scalar function SciPy's stepper calls, of (ω1..3, q0..3, I1..3, τ1..3)."""
    return TERM.rhs("math")


def _compiled_dop853() -> Any:
    """The DOP853 stepper compiled to C with (ω̇, q̇) of the free body (τ as parameters), or None."""
    return driver._compiled(TERM)


def _drifts(invariants: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Max relative deviation of T and |L| from their initial values; invariants (N, ..., 2) = (T, L²)."""
    def rel(x: np.ndarray) -> np.ndarray:
        scale = np.where(x[0] > 0, x[0], 1.0)
        return np.max(np.abs(x - x[0]), axis=0) / scale

    return rel(invariants[..., 0]), rel(np.sqrt(invariants[..., 1]))


# --- input checks ----------------------------------------------------------------------------

def _check_inertia(I: Any, shape: tuple[int | None, ...], strict: bool = True) -> np.ndarray:
    from ...inertia.validate import check_principal_moments

    arr = as_finite_array(I, "I", shape=shape)
    check_principal_moments(arr[..., 0], arr[..., 1], arr[..., 2], strict=strict)
    return arr


def _initial_quaternion(R0: Any, name: str = "R0") -> np.ndarray:
    if R0 is None:
        return np.array([1.0, 0.0, 0.0, 0.0])
    arr = np.asarray(R0, dtype=float)
    if arr.shape != (3, 3):
        raise ShapeError(f"expected `{name}` to have shape (3, 3), got {arr.shape}")
    return matrix_to_quaternion(check_rotation_matrix(arr, name))


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
    estimate_error : estimate the error of every output by one extra run — ``omega_error_estimate``
        (rad/s), ``rotation_error_estimate`` (R and q, rad), ``euler_angle_error_estimate`` (rad) and
        their maximum ``error_estimate``, the recipe in ``error_estimate_kind`` (as
        :func:`mechderive.solvers.driver.integrate` says: a rerun at rtol/1000, or Richardson).
    max_steps : steps allowed to each run (default 10⁷, :func:`mechderive.solvers.driver.integrate`).

    Raises :class:`~mechderive.errors.UnphysicalInertiaError`, :class:`~mechderive.errors.ShapeError`,
    :class:`~mechderive.errors.InvalidInputError` on bad input, :class:`IntegrationError` when a run
    cannot reach ``t_eval[-1]``: the state stops being finite (a value out of floating-point range, or
    a torque that blows the motion up), the step size collapses, or ``max_steps`` is reached.
    Compiled runs return to Python every ~0.05 s, so Ctrl-C stops them.
    """
    method = driver.check_method(method)
    max_steps = check_max_steps(max_steps)
    backend = check_backend(backend)
    inertia = _check_inertia(I, (3,), strict)
    w0 = as_finite_array(omega0, "omega0", shape=(3,))
    t = _check_times(t_eval)
    q0 = _initial_quaternion(R0)
    if method == "splitting":
        if backend != "auto":
            raise InvalidInputError(f"expected `backend` only with method='DOP853', got backend={backend!r} "
                                    "with method='splitting'")
        if torque is not None and rtol is None and atol is None:  # (a given rtol or atol is said first, below)
            raise InvalidInputError("expected torque=None with method='splitting' (a free-body integrator), "
                                    "got a torque; use method='DOP853'")
    rtol, atol, step, order = driver.check_method_options(method, rtol=rtol, atol=atol, step=step, order=order)
    par = (*(float(x) for x in inertia), 0.0, 0.0, 0.0)
    parameters_at = None
    if torque is not None:
        if not callable(torque):
            raise InvalidInputError(f"expected `torque` to be callable τ(t, omega, R), got {torque!r}")
        if backend == "c":
            raise IntegrationError("expected backend='auto' or 'scipy' with a torque (it calls back into Python), "
                                   "got backend='c'")
        parameters_at = _torque_parameters(torque, par[:3])
    q0, args0 = half_angles_of_quaternion(q0)
    with np.errstate(all="ignore"):  # a state out of range is said by the checks below, not as RuntimeWarnings
        run = driver.integrate(TERM, np.concatenate([w0, q0]), t, par, method=method,
                               rtol=1e-10 if rtol is None else rtol, atol=1e-12 if atol is None else atol,
                               step=step, order=order, backend=backend, estimate_error=estimate_error, track=args0,
                               max_steps=max_steps, parameters_at=parameters_at)
        e_drift, l_drift = _drifts(run.invariants)
        traj = run.extend(FreeTopTrajectory, energy_drift=float(e_drift), angular_momentum_drift=float(l_drift))
    driver.check_trajectory(traj, dict(energy_drift=traj.energy_drift,
                                       angular_momentum_drift=traj.angular_momentum_drift))
    return traj


def _torque_parameters(torque: Torque, inertia: tuple) -> Callable[[float, np.ndarray], tuple]:
    """The parameters (I1..3, τ1..3) at (t, y): τ(t, ω, R) of the caller's function, checked."""
    def at(t_: float, y: np.ndarray) -> tuple:
        q = y[3:] / np.linalg.norm(y[3:])
        tau = np.asarray(torque(t_, y[:3].copy(), quaternion_to_matrix(q)), dtype=float)
        if tau.shape != (3,):
            raise ShapeError(f"expected `torque(t, omega, R)` to return shape (3,), got {tau.shape}")
        if not np.all(np.isfinite(tau)):
            raise InvalidInputError(f"expected `torque(t, omega, R)` finite, got {tau.tolist()} at t = {t_:g}")
        return (*inertia, *tau.tolist())
    return at


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
    order = driver.check_order(order)
    if R0 is None or np.ndim(R0) == 2:
        q0 = np.broadcast_to(_initial_quaternion(R0), (M, 4))
    else:
        arr = np.asarray(R0, dtype=float)
        if arr.shape != (M, 3, 3):
            raise ShapeError(f"expected `R0` to have shape (3, 3) or ({M}, 3, 3), got {arr.shape}")
        q0 = matrix_to_quaternion(check_rotation_matrix(arr, "R0"))
    par = (*(inertia[..., a] for a in range(3)), 0.0, 0.0, 0.0)
    ens = driver.integrate_ensemble(TERM, np.concatenate([w0, q0], axis=-1), t, par, step=step, order=order,
                                    max_steps=max_steps)
    with np.errstate(all="ignore"):
        e_drift, l_drift = _drifts(ens.invariants)
    check_outputs("the Lie–Poisson splitting", dict(omega=ens.omega, quaternion=ens.quaternion, energy_drift=e_drift,
                                                    angular_momentum_drift=l_drift))
    return ens.extend(FreeTopEnsemble, energy_drift=e_drift, angular_momentum_drift=l_drift)
