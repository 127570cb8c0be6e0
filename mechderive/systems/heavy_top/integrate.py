"""Numerical integration of the heavy symmetric top (3.62)–(3.75) on a non-singular state.

State: the body components ω_a of the angular velocity (rad/s) and the unit quaternion q of
A = Rᵀ (scalar first) — never Euler angles, whose equations are singular at θ = 0 (the
sleeping top of 3.6.3: there the usual Lagrangian right-hand side returns NaN).  The initial
state is given in the scene-file convention (Euler angles and rates, (3.54), (3.58)) and
converted exactly by (3.58) (:func:`initial_state`) and
:func:`~mechderive.kinematics.conversions.euler_to_quaternion`, so θ = 0 exactly and θ > π/2
(a hanging top) are ordinary states.  The Euler angles are recovered from q afterwards, their
turns counted along every step of the integrator (:mod:`mechderive.solvers.half_angles`), so
they do not depend on how coarsely the output is sampled.

Equations (derived in :mod:`.rigid_model`, compiled once): Euler's equations with the gravity
torque τ = M g l (R23, -R13, 0), evaluated in gyroscopic form ((I1 - I3)/I1) ω2 ω3 + τ1/I1
(:func:`~mechderive.systems.free_top.integrate.gyroscopic_form`), and q̇ = ½ q ⊗ (0, ω).

Parameters, ``params = dict(I1=, I3=, M=, g=, l=)``: the principal moments I1 = I2 and I3 about
the **pivot** (kg m²), the mass M (kg), gravity g (m/s²) and the pivot–centre-of-mass distance
l (m).  The motion depends on M, g, l only through M g l; M and l are still needed, separately,
to check that a rigid body with these moments exists: the moments about the centre of mass,
I1_cm = I1 - M l² (parallel axes) and I3_cm = I3, must satisfy the triangle inequality
I1_cm + I2_cm ≥ I3_cm, i.e. **I1 - M l² ≥ I3/2** (the triangle inequality holds about any
point, but the pivot's form, I3 ≤ 2 I1, is weaker and does not exclude impossible bodies).
Accepted: I1, I3, M > 0; g ≥ 0 (g = 0 or l = 0: the free symmetric top); l ≥ 0 (the centre of
mass on the +e3 side, as in the chapter's figure 42).  For example I1 = 1, I3 = 0.5 with M = l = 1
is refused (I1_cm = 0 < 0.25 — no body has it), while M g l = 1 realised as M = 1, g = 4,
l = 0.25 (I1_cm = 0.9375) gives the same motion.

Initial state, ``initial = dict(theta=, phi=, psi=, theta_dot=, phi_dot=, psi_dot=)`` (rad,
rad/s): ``theta`` in [0, π] is required, the others default to 0.

Methods (``method=``):

``"DOP853"``
    Adaptive, order 8, on (ω, q); ``rtol`` (default 1e-10), ``atol`` (default rtol/100).
    ``backend="auto"`` (default) runs the stepper compiled to C together with the derived
    right-hand side (:mod:`mechderive.solvers.dop853_c`, ~1 µs a step) where a C compiler is
    found, else SciPy's :func:`scipy.integrate.solve_ivp` (the same algorithm and steps, ~100×
    slower); ``"c"`` or ``"scipy"`` choose.  |q| is a first integral of q̇ = ½ q ⊗ (0, ω); it is
    integrated unconstrained and projected at output (its drift is reported).

``"splitting"``
    The kick–drift–kick splitting H = T + V (:mod:`mechderive.solvers.kick_drift`): the free
    symmetric top's exact flow (two commuting rotations, :attr:`.rigid_model.HeavyTopRigidModel.free_flow`)
    and the gravity kick L → L + h τ(q) — one derived stage map, looped in compiled C
    (:mod:`mechderive.solvers.kick_drift_c`) where a C compiler is found —, Strang-composed (order 2)
    and raised to order 4 / 6
    (Suzuki's 5-stage fractal / Yoshida's 7-stage solution A, ``order=``; default 4).  Fixed
    step: each interval of ``t_eval`` is cut into ceil(Δt/``step``) equal steps.  Both sub-flows
    are exact Hamiltonian flows, so the method is symplectic and time-reversible: the energy error
    stays bounded (no drift), and p_ψ = I3 ω3 and p_φ = L·ẽ3 — invariants of each sub-flow — are
    kept to rounding.

Units: any consistent set (SI above).

>>> import numpy as np
>>> params = dict(I1=1.0, I3=0.5, M=1.0, g=4.0, l=0.25)          # M g l = 1
>>> t = np.linspace(0.0, 3.5177, 3)
>>> run = integrate_heavy_top(params, dict(theta=0.5, psi_dot=5.0), t, rtol=1e-12)
>>> np.round(run.euler_angles[:, 1], 6).tolist()                 # θ: 0.5 → 0.7576 → 0.5 (one nutation period)
[0.5, 0.757638, 0.5]
>>> split = integrate_heavy_top(params, dict(theta=0.0, psi_dot=10.0), t, method="splitting", step=0.01)
>>> float(split.euler_angles[:, 1].max()), bool(split.p_phi_drift < 1e-14)   # a sleeping top stays upright
(0.0, True)
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ...core.validate import check_positive
from ...errors import IntegrationError, InvalidInputError, ShapeError  # noqa: F401 (IntegrationError re-exported)
from ...kinematics.conversions import euler_to_quaternion
from ...kinematics.rotations import continuous_euler_angles  # noqa: F401 (re-exported)
from ...solvers import driver
from ...solvers.dop853 import check_backend
from ...solvers.driver import METHODS, SPLITTING_BACKENDS, SPLITTING_ORDERS, Ensemble, Term, Trajectory  # noqa: F401
from ...solvers.half_angles import initial_half_angles
from ...solvers.limits import check_max_steps, check_outputs
from .parameters import INITIAL_KEYS, PARAM_KEYS, check_initial, check_params  # noqa: F401

__all__ = ["integrate_heavy_top", "integrate_heavy_top_ensemble", "HeavyTopTrajectory", "HeavyTopEnsemble",
           "check_params", "check_initial", "initial_state", "continuous_euler_angles", "IntegrationError",
           "METHODS", "SPLITTING_ORDERS", "PARAM_KEYS", "INITIAL_KEYS", "TERM"]


# --- results ---------------------------------------------------------------------------------

@dataclass
class HeavyTopTrajectory(Trajectory):
    """One integrated motion of the heavy symmetric top.

    Attributes (those of :class:`~mechderive.solvers.driver.Trajectory`: ``t`` (N,) times (s),
    ``omega`` (N, 3) body components of ω (rad/s), ``quaternion`` (N, 4) of A = Rᵀ, scalar first,
    projected onto |q| = 1, ``y`` the state as integrated, ``invariants``, ...; and)
    ----------
    euler_angles : (N, 3) Euler angles (φ, θ, ψ) (3.54) with R(φ, θ, ψ) = R: θ = 2 atan2(√(q1² + q2²),
        √(q0² + q3²)) ∈ [0, π]; φ and ψ continuous, their turns counted along every step of the
        integrator — refined with its dense output where needed — not unwrapped from the samples
        (:mod:`~mechderive.solvers.half_angles`), so they are right at any sampling.  Near θ = 0 only
        φ + ψ is well conditioned (near π, φ - ψ).  A run starting exactly at θ = 0 (π) with the apex
        moving takes φ - ψ (φ + ψ) from the direction in which the apex leaves; a top sleeping exactly
        there splits φ + ψ (φ - ψ) between φ and ψ as the initial rates do.
    params : the checked parameters (floats).
    method, order : ``"DOP853"`` (order ``None``) or ``"splitting"`` with its order.
    energy_drift : max_t |E(t) - E(t0)| / (T(t0) + M g l), E = T + V of (3.65) (V ranges over ±M g l).
    p_phi_drift, p_psi_drift : max_t |p(t) - p(t0)| / L_scale for p_φ = L·ẽ3 (3.64) and p_ψ = I3 ω3
        (3.63); L_scale = max(|L(t0)|, √(I1 M g l)) (or 1 if both vanish).
    quaternion_norm_drift : max_t | |q| - 1 | before projection.
    n_evaluations : right-hand-side evaluations (DOP853) or compiled stage calls (splitting:
        each one exact free-top drift plus one kick).
    n_steps : accepted steps (DOP853) or fixed steps (splitting).
    omega_error_estimate : estimated max_t |ω - ω_exact| (rad/s), or ``None``.
    rotation_error_estimate : estimated max_t of the rotation angle between R and R_exact (rad), widened
        to bound every |R_ij - R_exact,ij| and |q - q_exact| too, or ``None``.
    euler_angle_error_estimate : estimated max_t |Δφ|, |Δθ|, |Δψ| of ``euler_angles`` (rad), or
        ``None``; at least 2π n when the apex passed n times closer to the pole (or the bottom) than
        the error of R can resolve (``unresolved_passages``): φ and ψ are then known only modulo 2π
        (φ ± ψ and R are not affected).
    angle_error_estimate : the largest of the three above — one estimate that covers everything
        output (ω in rad/s; R, q and the angles in rad), or ``None``.
    error_estimate_kind : how the estimates were obtained (see :func:`integrate_heavy_top`).
    wall_time : seconds spent in the main integration (excluding the error-estimate rerun).
    backend : ``"c"`` (compiled), ``"scipy"`` (SciPy's DOP853) or ``"python"`` (the splitting in Python).
    unresolved_passages : see ``euler_angle_error_estimate`` (0 without an estimate).
    pole_clearance : lower bounds of min_t sin(θ/2) and of min_t cos(θ/2) along the integrated path
        (its distances, in the quaternion, from the pole and from the bottom); ``inf`` where it stays
        exactly at θ = 0 (θ = π) throughout, 0 where a step could not resolve its passage.
    """
    params: dict | None = None
    energy_drift: float = 0.0
    p_phi_drift: float = 0.0
    p_psi_drift: float = 0.0

    @property
    def angle_error_estimate(self) -> float | None:
        """The largest of the three estimates (ω, R, Euler angles), or None: ``error_estimate``."""
        return self.error_estimate


@dataclass
class HeavyTopEnsemble(Ensemble):
    """M heavy tops integrated together by the splitting: arrays (N, M, ·), drifts (M,).

    See :class:`HeavyTopTrajectory` for the fields; ``theta`` is θ(t) of every member.
    """

    params: dict | None = None
    energy_drift: np.ndarray | None = None
    p_phi_drift: np.ndarray | None = None
    p_psi_drift: np.ndarray | None = None

    @property
    def theta(self) -> np.ndarray:
        """(N, M) nutation angle θ = arccos R33, computed as atan2(√(R13² + R23²), R33) from q."""
        q0, q1, q2, q3 = np.moveaxis(self.quaternion, -1, 0)
        # R33 = q0² - q1² - q2² + q3², √(R13² + R23²) = 2 √((q0² + q3²)(q1² + q2²)) for |q| = 1
        return np.arctan2(2.0 * np.sqrt((q0**2 + q3**2) * (q1**2 + q2**2)), q0**2 + q3**2 - q1**2 - q2**2)


# --- the derived system ----------------------------------------------------------------------

def _symbols() -> tuple[list, list, list]:
    from ...systems.free_top.model import omega_symbols
    from .rigid_model import momentum_symbols, parameters, quaternion_symbols

    return [*omega_symbols(), *quaternion_symbols()], [*momentum_symbols(), *quaternion_symbols()], list(parameters())


def _rhs_exprs() -> Any:
    """(ω̇, q̇) of :attr:`.rigid_model.HeavyTopRigidModel.rhs`, Euler's equations in gyroscopic form."""
    import sympy as sp

    from ..free_top.integrate import gyroscopic_form
    from ..free_top.model import omega_symbols
    from .rigid_model import model

    m = model()
    return sp.Matrix([*gyroscopic_form(m.euler_rhs, omega_symbols()), *m.quaternion_rhs])


def _build() -> tuple:
    state, _, par = _symbols()
    return _rhs_exprs(), state, par


def _invariant_exprs() -> list:
    """E (3.65), p_φ (3.64), p_ψ (3.63) of the model, in (ω, q) and the parameters."""
    from .rigid_model import model

    m = model()
    return [m.energy, m.p_phi, m.p_psi]


def _stage() -> tuple:
    """kick(h_kick) ∘ free_flow(h_free), derived: (stage map, (L, q), h_free, h_kick, parameters)."""
    from .rigid_model import h_free, h_kick, model

    _, state, par = _symbols()
    return model().stage_map, state, h_free, h_kick, par


def _inertia(params: Sequence[Any]) -> np.ndarray:
    """(I1, I1, I3) from the parameters (I1, I3, M, g, l) (scalars or (M,) arrays)."""
    return np.stack(np.broadcast_arrays(*(np.asarray(params[k], dtype=float) for k in (0, 0, 1))), axis=-1)


#: The heavy top for the driver: (ω̇, q̇) in the parameters (I1, I3, M, g, l), its invariants, and the
#: kick–drift–kick splitting on the derived stage map.
TERM = Term("heavy_top", _build, invariants=_invariant_exprs, invariant_names=("energy", "p_phi", "p_psi"),
            quaternion=3, rhs_module="math", splitting="kick_drift", stage=_stage, inertia=_inertia,
            passage_note="; the apex passed {n} time(s) closer to the pole (or the bottom) than the error of R: the "
                         "turns of φ and ψ are then not determined (2π each time; φ ± ψ and R are)")


def _rhs() -> Callable[..., list]:
    """(ω̇, q̇) as the scalar function SciPy's stepper calls, of (ω1..3, q0..3, I1, I3, M, g, l)."""
    return TERM.rhs("math")


def _compiled_dop853() -> Any:
    """The DOP853 stepper compiled to C with (ω̇, q̇), or None without a C compiler (or with it switched off)."""
    return driver._compiled(TERM)


def _compiled_splitting() -> Any:
    """The splitting compiled to C with the derived stage map, or None without a usable C compiler."""
    return driver._compiled_splitting(TERM)


@functools.cache
def _euler_rates_to_omega() -> Callable[..., Any]:
    """Vectorised ω(φ, θ, ψ, φ̇, θ̇, ψ̇), shape (..., 3), compiled from the model (disk-cached)."""
    from ...core.compile import compile_cached

    def build():
        from ...core.symbols import state_symbol
        from .rigid_model import model

        names = ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")
        return [state_symbol(n) for n in names], list(model().angular_velocity_from_euler_rates)
    return compile_cached("heavy_top.euler_rates_to_omega", build)


def _param_values(p: Mapping[str, Any]) -> list[Any]:
    return [p[k] for k in PARAM_KEYS]


def _evaluate_invariants(omega: np.ndarray, q: np.ndarray, p: Mapping[str, Any]) -> np.ndarray:
    """(E, p_φ, p_ψ) at ω (..., 3), q (..., 4), shape (..., 3)."""
    w, qq = np.moveaxis(omega, -1, 0), np.moveaxis(q, -1, 0)
    vals = [np.asarray(v, dtype=float) for v in TERM.invariant_function()(*_param_values(p), *w, *qq)]
    return np.stack(np.broadcast_arrays(*vals), axis=-1)


def _drifts(inv: np.ndarray, omega: np.ndarray, q: np.ndarray,
            p: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scaled max deviations of E, p_φ, p_ψ (``inv`` (N, ..., 3)) from their initial values; omega (N, ..., 3),
    q (N, ..., 4)."""
    no_gravity = dict(p, g=0.0 * np.asarray(p["g"]))
    T0 = _evaluate_invariants(omega[0], q[0], no_gravity)[..., 0]
    mgl = np.asarray(p["M"]) * np.asarray(p["g"]) * np.asarray(p["l"])
    e_scale = T0 + mgl
    e_scale = np.where(e_scale > 0, e_scale, 1.0)
    I = np.stack(np.broadcast_arrays(p["I1"], p["I1"], p["I3"]), axis=-1)
    L0 = np.linalg.norm(I * omega[0], axis=-1)
    l_scale = np.maximum(L0, np.sqrt(np.asarray(p["I1"]) * mgl))
    l_scale = np.where(l_scale > 0, l_scale, 1.0)
    dev = np.max(np.abs(inv - inv[0]), axis=0)
    return dev[..., 0] / e_scale, dev[..., 1] / l_scale, dev[..., 2] / l_scale


# --- input checks ----------------------------------------------------------------------------

def initial_state(initial: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(ω0, q0) from checked Euler angles and rates: ω of (3.58), q of R(φ, θ, ψ)ᵀ (exact at θ = 0).

    ω comes from :attr:`.rigid_model.HeavyTopRigidModel.angular_velocity_from_euler_rates` (the same
    as :func:`~mechderive.kinematics.euler.angular_velocity_body`, which the tests check, but ~20×
    cheaper to derive in a fresh process); q from :func:`~mechderive.kinematics.conversions.euler_to_quaternion`.

    >>> w0, q0 = initial_state(check_initial(dict(theta=0.0, phi=0.3, psi=0.4, psi_dot=5.0)))
    >>> w0.tolist(), (np.round(q0, 12) + 0.0).tolist()
    ([0.0, 0.0, 5.0], [0.939372712847, 0.0, 0.0, 0.342897807455])
    """
    w0 = np.asarray(_euler_rates_to_omega()(*(initial[k] for k in ("phi", "theta", "psi", "phi_dot", "theta_dot",
                                                                  "psi_dot"))), dtype=float)
    return w0, euler_to_quaternion(initial["phi"], initial["theta"], initial["psi"])


# --- the public entry points -----------------------------------------------------------------

def integrate_heavy_top(params: Mapping[str, float], initial: Mapping[str, float], t_eval: Sequence[float], *,
                        method: str = "DOP853", rtol: float | None = None, atol: float | None = None,
                        step: float | None = None, order: int | None = None,
                        estimate_error: bool = True, backend: str = "auto", strict: bool = True,
                        max_steps: int | None = None) -> HeavyTopTrajectory:
    """Integrate the heavy symmetric top from Euler angles and rates at ``t_eval[0]``.

    Parameters
    ----------
    params : dict(I1, I3, M, g, l): moments about the pivot (kg m²), mass (kg), gravity (m/s²),
        pivot–centre-of-mass distance (m); or dict(I1, I3, Mgl) (only M g l enters the motion);
        checked by :func:`check_params`.
    strict : ``False`` accepts a top no rigid body is (I1 - M l² < I3/2, see :func:`check_params`).
    initial : dict(theta, phi, psi, theta_dot, phi_dot, psi_dot) (rad, rad/s); θ ∈ [0, π]
        required, the others default to 0; checked by :func:`check_initial`.
    t_eval : strictly increasing output times (s), at least 2.
    method : ``"DOP853"`` (``rtol``, ``atol``, ``backend``) or ``"splitting"`` (``step`` (s)
        required, ``order`` 2, 4 (default) or 6).
    backend : ``"auto"`` (compiled C where a C compiler is found), ``"c"`` (raises
        :class:`IntegrationError` without a compiler), or the uncompiled path: ``"scipy"``
        (DOP853) / ``"python"`` (the splitting's stage loop in Python).
    estimate_error : estimate the error of every output by one extra run — ``omega_error_estimate``
        (rad/s), ``rotation_error_estimate`` (R and q, rad), ``euler_angle_error_estimate`` (rad) and
        their maximum ``angle_error_estimate``, the recipe in ``error_estimate_kind`` (as
        :func:`mechderive.solvers.driver.integrate` says: a rerun at rtol/1000, or Richardson).
    max_steps : steps allowed to each run (default 10⁷, :func:`mechderive.solvers.driver.integrate`).

    Raises :class:`~mechderive.errors.InvalidInputError` (or its subclasses
    :class:`~mechderive.errors.UnphysicalInertiaError`, :class:`~mechderive.errors.NonFiniteValueError`)
    on bad input, :class:`IntegrationError` when a run cannot reach ``t_eval[-1]``: the state stops
    being finite (a value out of floating-point range, or a motion that blows up), the step size
    collapses, or ``max_steps`` is reached.  Compiled runs return to Python every ~0.05 s, so Ctrl-C
    stops them.
    """
    method = driver.check_method(method)
    max_steps = check_max_steps(max_steps)
    if method == "DOP853":
        backend = check_backend(backend)
    elif backend not in SPLITTING_BACKENDS:
        raise InvalidInputError(f"expected backend one of {', '.join(map(repr, SPLITTING_BACKENDS))} with "
                                f"method='splitting', got {backend!r}")
    p = check_params(params, strict=strict)
    if any(np.ndim(v) for v in p.values()):
        raise ShapeError("expected scalar `params` values (use integrate_heavy_top_ensemble for arrays), got arrays")
    init = check_initial(initial)
    if any(np.ndim(v) for v in init.values()):
        raise ShapeError("expected scalar `initial` values (use integrate_heavy_top_ensemble for arrays), got arrays")
    t = driver.check_times(t_eval)
    w0, q0 = initial_state(init)
    rtol, atol, step, order = driver.check_method_options(method, rtol=rtol, atol=atol, step=step, order=order)
    rtol = 1e-10 if rtol is None else rtol
    with np.errstate(all="ignore"):  # a state out of range is said by the checks below, not as RuntimeWarnings
        run = driver.integrate(TERM, np.concatenate([w0, q0]), t, _param_values(p), method=method, rtol=rtol,
                               atol=rtol / 100 if atol is None else atol, step=step, order=order, backend=backend,
                               estimate_error=estimate_error, track=initial_half_angles(init["phi"], init["psi"]),
                               euler_rates=(float(init["phi_dot"]), float(init["psi_dot"])), max_steps=max_steps)
        e, pf, ps = _drifts(run.invariants, run.omega, run.quaternion, p)
        traj = run.extend(HeavyTopTrajectory, params=p, energy_drift=float(e), p_phi_drift=float(pf),
                          p_psi_drift=float(ps))
    driver.check_trajectory(traj, dict(energy_drift=traj.energy_drift, p_phi_drift=traj.p_phi_drift,
                                       p_psi_drift=traj.p_psi_drift))
    return traj


def integrate_heavy_top_ensemble(params: Mapping[str, Any], initial: Mapping[str, Any], t_eval: Sequence[float], *,
                                 step: float, order: int = 4, strict: bool = True,
                                 max_steps: int | None = None) -> HeavyTopEnsemble:
    """Integrate M heavy tops at once with the splitting (vectorised over members).

    Every value of ``params`` and ``initial`` may be a scalar or an array of shape (M,); M is
    their common broadcast length.  Outputs are (N, M, ·): mind N·M·56 bytes.  ``params`` may give
    ``Mgl`` in place of M, g, l; ``strict=False`` accepts tops no rigid body is (see :func:`check_params`).
    ``max_steps`` as in :func:`integrate_heavy_top` (steps of each member); a member whose state stops
    being finite raises :class:`IntegrationError` naming it.

    >>> import numpy as np
    >>> ens = integrate_heavy_top_ensemble(dict(I1=1.0, I3=0.5, M=1.0, g=4.0, l=0.25),
    ...                                    dict(theta=np.array([0.0, 0.5, 2.5]), psi_dot=5.0),
    ...                                    [0.0, 1.0], step=0.01)
    >>> ens.omega.shape, bool(ens.p_psi_drift.max() < 1e-14)
    ((2, 3, 3), True)
    """
    p = check_params(params, strict=strict)
    init = check_initial(initial)
    try:
        shape = np.broadcast_shapes(*(np.shape(v) for v in (*p.values(), *init.values())))
    except ValueError as exc:
        raise ShapeError(f"expected `params` and `initial` values of shape () or (M,), got shapes "
                         f"{[np.shape(v) for v in (*p.values(), *init.values())]}") from exc
    if len(shape) > 1:
        raise ShapeError(f"expected `params` and `initial` values of shape () or (M,), got broadcast shape {shape}")
    M = shape[0] if shape else 1
    init = {k: np.broadcast_to(v, (M,)).astype(float) for k, v in init.items()}
    pv = {k: (v if np.ndim(v) == 0 else np.asarray(v, dtype=float)) for k, v in p.items()}
    t = driver.check_times(t_eval)
    step = check_positive(step, "step")
    order = driver.check_order(order)
    w0, q0 = initial_state(init)
    ens = driver.integrate_ensemble(TERM, np.concatenate([w0, q0], axis=-1), t, _param_values(pv), step=step,
                                    order=order, max_steps=max_steps)
    with np.errstate(all="ignore"):
        e, pf, ps = _drifts(ens.invariants, ens.omega, ens.quaternion, pv)
    check_outputs("the kick–drift–kick splitting", dict(omega=ens.omega, quaternion=ens.quaternion, energy_drift=e,
                                                        p_phi_drift=pf, p_psi_drift=ps))
    return ens.extend(HeavyTopEnsemble, params=pv, energy_drift=e, p_phi_drift=pf, p_psi_drift=ps)
