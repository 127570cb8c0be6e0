"""One integration driver for every system: a derived term, a solver, a tolerance controller, one trajectory.

* A :class:`Term` is a derived, autonomous first-order system y' = f(y; p): its SymPy right-hand
  side (built on demand), its state and parameter symbols, its invariants (functions of (p, y)),
  and, optionally, where a unit quaternion of A = Rᵀ sits in the state (renormalised on output, R
  from it, its Euler half-angles followed along the steps: :mod:`.half_angles`) and a stage map
  for the splittings.  A non-autonomous system carries t as a state variable with t' = 1.
* Two solvers (``method=``): DOP853 (adaptive) — compiled to C (:mod:`.dop853_c`) where a compiler
  exists, SciPy's stepper on the compiled right-hand side otherwise (:func:`.dop853.run_dop853`);
  and the splittings (fixed step, order 2, 4 or 6, :mod:`.composition`) of a rigid body's state
  (ω, q): kick–drift–kick on the term's derived stage map (:mod:`.kick_drift`, compiled by
  :mod:`.kick_drift_c`), or the free body's Lie–Poisson splitting (:mod:`.lie_poisson`).
  :func:`integrate_ensemble` runs M members of a splitting at once.
* Every run can measure its global error: DOP853 by the distance to a rerun at a tighter
  tolerance (:func:`.dop853.reference_tolerance`), a splitting by Richardson's extrapolation
  against a run at half the step; with a quaternion the estimate is split into ω, R and the Euler
  angles (:func:`.half_angles.output_error_estimates`).
* :func:`integrate_to_rtol` is the controller: rerun tighter while the measured global error exceeds
  the requested tolerance.
* :class:`Trajectory` holds the states at the output times, the invariants along them, what the run
  measured, and the orientation outputs (``quaternion``, ``R``, ``euler_angles``); system modules
  subclass it to add named fields (:class:`~mechderive.systems.free_top.integrate.FreeTopTrajectory`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import InvalidInputError
from .composition import suzuki_fractal, yoshida6
from .dop853 import SCIPY_MIN_RTOL, check_backend, run_dop853
from .half_angles import euler_angles_from_half_angles, output_error_estimates, sleeping_split
from .limits import check_fixed_steps, check_max_steps, check_outputs, first_nonfinite_row, nonfinite_state

__all__ = ["Term", "Trajectory", "Ensemble", "integrate", "integrate_ensemble", "integrate_to_rtol", "MAX_ATTEMPTS",
           "METHODS", "SPLITTING_ORDERS", "SPLITTING_BACKENDS", "RICHARDSON_MARGIN", "PASSAGE_NOTE", "check_times",
           "check_method", "check_order", "check_method_options", "interval_steps", "project_quaternion",
           "check_trajectory", "next_tolerance"]

METHODS = ("DOP853", "splitting")
#: Composition weights used for each order of the splittings (see mechderive.solvers.composition).
SPLITTING_ORDERS: dict[int, tuple[float, ...]] = {2: (1.0,), 4: suzuki_fractal(4), 6: yoshida6()}
#: The splittings' backends: the stage loop compiled to C with the derived stage map, or Python.
SPLITTING_BACKENDS = ("auto", "c", "python")
#: Richardson's |y_h - y_(h/2)| · 2^p/(2^p - 1) is the error up to relative corrections O(h) (a few %
#: at the steps used); this margin makes the reported estimate cover them.
RICHARDSON_MARGIN = 1.25
#: Appended to ``error_estimate_kind`` when the tracked angles passed a pole unresolved ({n}: how often).
PASSAGE_NOTE = ("; e3 passed {n} time(s) closer to ±ẽ3 than the error of R: the turns of φ and ψ are then not "
                "determined (2π each time; φ ± ψ and R are)")
_SPLITTINGS = ("kick_drift", "lie_poisson")
_LABELS = {"kick_drift": "the kick–drift–kick splitting", "lie_poisson": "the Lie–Poisson splitting"}


@dataclass(frozen=True)
class Term:
    """A derived system y' = f(y; p).

    ``name`` keys the compiled code in the caches (one name per derived system: a system built from a
    user's text includes a hash of that text).  ``build()`` returns (right-hand-side expressions, state
    symbols, parameter symbols) and runs — deriving with SymPy — only when the compiled code is in no
    cache.  ``invariants()`` returns the invariants' expressions in the parameter and state symbols,
    named by ``invariant_names`` (evaluated on the state with the quaternion renormalised).
    ``quaternion``: index of q0 of a unit quaternion (q0, q1, q2, q3) of A = Rᵀ in the state, or None.
    ``omega``: indices of the body angular velocity in the state (the "omega" part of the split error
    estimate; default every component outside the quaternion).
    ``rhs_module``: "numpy" or "math" — what SciPy's stepper calls: "math" is a scalar function of
    Python floats, ~3× faster a call, for expressions ``math`` has every function of.
    ``splitting``: "kick_drift" (the stage map ``stage``) or "lie_poisson" (the free body's exact axis
    flows; the parameters start with I1, I2, I3), for a state (ω1, ω2, ω3, q0, …, q3); ``stage()``
    returns (stage-map expressions in (L, q), the state symbols (L1..3, q0..3), h_drift, h_kick,
    parameter symbols) (:mod:`.kick_drift`); ``inertia(params)`` the principal moments (3,) (or (M, 3)
    for parameter arrays) with L_a = I_a ω_a.
    ``passage_note``: the text added to ``error_estimate_kind`` when the tracked angles passed a
    pole unresolved (``{n}`` the count).
    """

    name: str
    build: Callable[[], tuple[Sequence[Any], Sequence[Any], Sequence[Any]]]
    invariants: Callable[[], Sequence[Any]] | None = None
    invariant_names: tuple[str, ...] = ()
    quaternion: int | None = None
    omega: tuple[int, ...] | None = None
    rhs_module: str = "numpy"
    splitting: str | None = None
    stage: Callable[[], tuple] | None = None
    inertia: Callable[[Sequence[Any]], Any] | None = None
    passage_note: str = PASSAGE_NOTE

    def rhs(self, module: str = "numpy") -> Callable[..., list]:
        """f compiled for ``module`` ("numpy", or "math": Python floats), called as f(*y, *p)."""
        return _lambdified(self, "rhs", module)

    def invariant_function(self) -> Callable[..., list] | None:
        """g(*p, *y) -> list of the invariants, or None when the term has none."""
        return None if self.invariants is None else _lambdified(self, "invariants", "numpy")

    def omega_indices(self, n: int) -> tuple[int, ...]:
        """The indices of ω in a state of ``n`` components."""
        if self.omega is not None:
            return tuple(self.omega)
        q = self.quaternion
        return tuple(i for i in range(n) if q is None or not q <= i < q + 4)


@functools.cache
def _lambdified(term: Term, what: str, module: str) -> Callable[..., list]:
    """The term's right-hand side (args y, p) or invariants (args p, y), lambdified (cse) for ``module``
    and kept in the disk cache under ``driver.<name>.<what>``."""
    from ..core.codecache import cached_lambdify

    def build() -> tuple:
        exprs, state, params = term.build()
        if what == "rhs":
            return [*state, *params], list(exprs)
        return [*params, *state], list(term.invariants())
    return cached_lambdify(f"driver.{term.name}.{what}", build, module=module)[0]


def _compiled(term: Term) -> Any:
    """The term's compiled DOP853 stepper, or None (looked up on every run, not kept here: the C path may be
    switched off, and :mod:`~mechderive.core.cbuild` checks its cached library before each use)."""
    from .dop853_c import compiled_dop853

    def build() -> tuple:
        import sympy as sp

        exprs, state, params = term.build()
        return sp.Matrix(list(exprs)), list(state), list(params)
    return compiled_dop853(term.name, build)


@dataclass
class Trajectory:
    """States ``y`` (N, n) at the times ``t`` (N,), with what the run measured.

    ``error_estimate`` is one estimate of the largest error of everything output, or None when no
    second run was made: without a quaternion the largest distance, over the samples and the state
    components, to the second run (times its factor); with one the largest of ``estimates``.
    ``component_error`` the distance per state component (n,).  ``invariants`` (N, k) are the term's
    invariants along the run, named by ``invariant_names``.  ``args``: the tracked half-angles
    (σ, δ) (N, 2), when asked for.  ``wall``: seconds of the main run (not the second one).
    ``method``, ``order``: "DOP853" (order None) or "splitting" with its order.

    With a quaternion in the state: ``quaternion`` (N, 4) renormalised (``y`` keeps it as integrated;
    |q| is a first integral of q̇ = ½ q ⊗ (0, ω), so ``quaternion_norm_drift`` = max ||q| - 1|
    measures the integrator's error), ``R`` the chapter's matrices from it (e_a = R_ab ẽ_b),
    ``euler_angles`` (N, 3) (φ, θ, ψ) (3.54) with φ and ψ continuous from the tracked half-angles;
    ``estimates`` = {"omega": rad/s, "rotation": rad, "euler": rad or None} of
    :func:`~.half_angles.output_error_estimates`, ``unresolved_passages`` and ``pole_clearance``
    (lower bounds of min sin(θ/2) and min cos(θ/2) along the tracked path).
    """

    t: np.ndarray
    y: np.ndarray
    n_evaluations: int
    n_steps: int | None
    backend: str
    wall: float
    error_estimate: float | None = None
    component_error: np.ndarray | None = None
    error_estimate_kind: str = ""
    invariants: np.ndarray | None = None
    invariant_names: tuple[str, ...] = ()
    args: np.ndarray | None = None  # tracked quaternion half-angles (N, 2), when asked for
    extra: dict = field(default_factory=dict)
    method: str = "DOP853"
    order: int | None = None
    omega_index: tuple[int, ...] = ()
    quaternion: np.ndarray | None = None
    euler_angles: np.ndarray | None = None
    quaternion_norm_drift: float | None = None
    estimates: dict | None = None
    unresolved_passages: int = 0
    pole_clearance: tuple[float, float] = (math.inf, math.inf)

    def invariant(self, name: str) -> np.ndarray:
        return self.invariants[:, self.invariant_names.index(name)]

    @property
    def omega(self) -> np.ndarray:
        """(N, 3) body components of ω (the term's ``omega`` components of ``y``)."""
        i = self.omega_index
        return self.y[:, i[0]:i[-1] + 1] if i and i == tuple(range(i[0], i[-1] + 1)) else self.y[:, list(i)]

    @functools.cached_property
    def R(self) -> np.ndarray:
        """(N, 3, 3) rotation matrices of the chapter's convention, e_a = R_ab ẽ_b (from ``quaternion``)."""
        from ..kinematics.conversions import quaternion_to_matrix

        return quaternion_to_matrix(self.quaternion)

    @property
    def wall_time(self) -> float:
        return self.wall

    @property
    def omega_error_estimate(self) -> float | None:
        return None if self.estimates is None else self.estimates["omega"]

    @property
    def rotation_error_estimate(self) -> float | None:
        return None if self.estimates is None else self.estimates["rotation"]

    @property
    def euler_angle_error_estimate(self) -> float | None:
        return None if self.estimates is None else self.estimates["euler"]

    def extend(self, cls: type, **named: Any) -> Any:
        """This trajectory as the subclass ``cls`` with its own fields ``named``."""
        return cls(**{f.name: getattr(self, f.name) for f in dataclasses.fields(Trajectory)}, **named)


@dataclass
class Ensemble:
    """M members integrated together by a splitting: ``y`` (N, M, n), ``quaternion`` (N, M, 4) renormalised,
    ``quaternion_norm_drift`` (M,), ``invariants`` (N, M, k); ``n_steps`` composed steps of each member."""

    t: np.ndarray
    y: np.ndarray
    quaternion: np.ndarray
    quaternion_norm_drift: np.ndarray
    order: int
    n_steps: int
    wall: float
    invariants: np.ndarray | None = None
    invariant_names: tuple[str, ...] = ()

    @property
    def omega(self) -> np.ndarray:
        """(N, M, 3) body components of ω."""
        return self.y[..., :3]

    @property
    def R(self) -> np.ndarray:
        """(N, M, 3, 3) rotation matrices, e_a = R_ab ẽ_b."""
        from ..kinematics.conversions import quaternion_to_matrix

        return quaternion_to_matrix(self.quaternion)

    @property
    def wall_time(self) -> float:
        return self.wall

    @property
    def body_steps_per_second(self) -> float:
        """Throughput: members × steps / wall time."""
        return self.y.shape[1] * self.n_steps / self.wall if self.wall > 0 else math.inf

    def extend(self, cls: type, **named: Any) -> Any:
        """This ensemble as the subclass ``cls`` with its own fields ``named``."""
        return cls(**{f.name: getattr(self, f.name) for f in dataclasses.fields(Ensemble)}, **named)


# --- checks shared by the systems ------------------------------------------------------------

def check_times(t_eval: Any) -> np.ndarray:
    """``t_eval`` as a float array: finite, strictly increasing, at least 2 times."""
    from ..core.validate import as_finite_array

    t = as_finite_array(t_eval, "t_eval", shape=(None,))
    if t.size < 2:
        raise InvalidInputError(f"expected `t_eval` to hold at least 2 times, got {t.size}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        k = int(bad[0])
        raise InvalidInputError(
            f"expected `t_eval` strictly increasing, got t_eval[{k + 1}] = {t[k + 1]:g} <= t_eval[{k}] = {t[k]:g}")
    return t


def check_method(method: str) -> str:
    if method not in METHODS:
        raise InvalidInputError(f"expected method one of {', '.join(map(repr, METHODS))}, got {method!r}")
    return method


def check_order(order: int) -> int:
    if order not in SPLITTING_ORDERS:
        raise InvalidInputError(f"expected order one of {', '.join(map(str, SPLITTING_ORDERS))}, got {order!r}")
    return order


def check_method_options(method: str, *, rtol: Any, atol: Any, step: Any, order: Any
                         ) -> tuple[float | None, float | None, float | None, int | None]:
    """(rtol, atol, step, order) checked for ``method``: DOP853 takes rtol and atol (None: the caller's
    defaults), not step or order; the splitting takes step (required) and order (default 4), not rtol
    or atol."""
    from ..core.validate import check_positive

    if method == "DOP853":
        for name, value in (("step", step), ("order", order)):
            if value is not None:
                raise InvalidInputError(f"expected `{name}` only with method='splitting', got {name}={value!r} "
                                        "with method='DOP853'")
        return (None if rtol is None else check_positive(rtol, "rtol"),
                None if atol is None else check_positive(atol, "atol"), None, None)
    for name, value in (("rtol", rtol), ("atol", atol)):
        if value is not None:
            raise InvalidInputError(f"expected `{name}` only with method='DOP853', got {name}={value!r} "
                                    "with method='splitting' (set `step` instead)")
    if step is None:
        raise InvalidInputError("expected a step size `step` > 0 with method='splitting', got step=None")
    step = check_positive(step, "step")
    return None, None, step, check_order(4 if order is None else order)


def interval_steps(t: np.ndarray, step: float, refine: int = 1) -> list[tuple[int, float]]:
    """(n, h) for each output interval: n = refine · ceil(Δt/step) equal steps of h = Δt/n."""
    out = []
    for dt in np.diff(t):
        n = max(1, math.ceil(dt / step - 1e-9)) * refine
        out.append((n, float(dt) / n))
    return out


def project_quaternion(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(q/|q|, max over time (axis 0) of ||q| - 1|) for q of shape (N, ..., 4)."""
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    return q / norm, np.max(np.abs(norm[..., 0] - 1.0), axis=0)


def check_trajectory(traj: Trajectory, named: dict[str, Any]) -> None:
    """Raise :class:`~mechderive.errors.IntegrationError` naming the first output that is not finite:
    ω, the quaternion, the Euler angles, then ``named`` (a system's drifts), |q|'s drift, the estimates."""
    check_outputs(f"{traj.method} (backend {traj.backend!r})", dict(
        omega=traj.omega, quaternion=traj.quaternion, euler_angles=traj.euler_angles, **named,
        quaternion_norm_drift=traj.quaternion_norm_drift, omega_error_estimate=traj.omega_error_estimate,
        rotation_error_estimate=traj.rotation_error_estimate,
        euler_angle_error_estimate=traj.euler_angle_error_estimate))


# --- one run ---------------------------------------------------------------------------------

@dataclass
class _Run:
    """What a method produced: the states (N, n) as integrated, the tracking, the second run (or None)."""

    y: np.ndarray
    args: np.ndarray | None
    closest: Any
    near: Any
    nfev: int
    steps: int | None
    wall: float
    backend: str
    ref: tuple | None  # (y, args, near) of the second run
    factor: float
    kind: str


def integrate(term: Term, y0: Sequence[float], t: Sequence[float], params: Sequence[float], *,
              rtol: float | None = None, atol: float | None = None, backend: str = "auto",
              estimate_error: bool = True, track: Sequence[float] | None = None, max_steps: int | None = None,
              method: str = "DOP853", step: float | None = None, order: int | None = None,
              euler_rates: tuple[float, float] | None = None,
              parameters_at: Callable[[float, np.ndarray], Sequence[float]] | None = None) -> Trajectory:
    """Integrate ``term`` from ``y0`` at ``t[0]`` through the increasing times ``t`` with parameter values ``params``.

    ``method="DOP853"`` (``rtol`` required, ``atol`` default ``rtol * 1e-3``): ``backend`` "c" (the
    compiled stepper; an error where there is no compiler), "scipy", or "auto" (C where available).
    ``method="splitting"`` (the term's ``splitting``; state (ω, q)): ``step`` (required; each output
    interval is cut into ceil(Δt/step) equal steps), ``order`` 2, 4 (default) or 6, ``backend``
    "auto", "c" (the compiled stage loop) or "python".
    ``estimate_error``: measure the global error by a second run: DOP853 — the distance to a rerun at
    rtol/1000, atol/1000, × 1/(1 - √r) for the ratio r of the tolerances
    (:func:`~.dop853.reference_tolerance`: the rerun's rtol is floored at 2.3e-14, SciPy's limit;
    below 2.3e-13 it runs looser, at 10·rtol, and the figure is an upper bound ~10× the error);
    splitting — Richardson with the known order p, |y_h - y_(h/2)| · 2^p / (2^p - 1) · 1.25 (the
    rerun, at step/2, costs twice the main run).  With a quaternion the estimate is split into ω,
    R (and q) and the Euler angles (:func:`~.half_angles.output_error_estimates`).  ``track = (σ0, δ0)`` follows the half-angles of the term's
    quaternion (it must have one; the splitting always tracks, from the arguments of q0 where not
    given); ``euler_rates = (φ̇0, ψ̇0)`` splits φ ± ψ between φ and ψ on a motion staying exactly at
    θ = 0 or π (:func:`~.half_angles.sleeping_split`).  ``parameters_at(t, y)``: the parameter values
    computed in Python at every evaluation (an applied torque given as a Python function; DOP853 on
    SciPy only).  ``max_steps``: steps allowed to each run (default :data:`~.limits.MAX_STEPS` = 10⁷):
    DOP853 stops there with an error saying where it got to; the splitting, whose steps are known
    in advance, refuses at once.  Raises :class:`~mechderive.errors.IntegrationError` when the run
    cannot reach ``t[-1]``.
    """
    t = np.asarray(t, dtype=float)
    y0 = np.asarray(y0, dtype=float)
    par = tuple(float(x) for x in params)
    tracking = None
    if track is not None:
        if term.quaternion is None:
            raise InvalidInputError(f"term {term.name!r} has no quaternion to track")
        tracking = (term.quaternion, tuple(track))
    with np.errstate(all="ignore"):  # a state out of range is said by the checks, not as RuntimeWarnings
        if method == "DOP853":
            if rtol is None:
                raise InvalidInputError("expected `rtol` > 0 with method='DOP853', got rtol=None")
            run = _run_dop853(term, t, y0, par, rtol, rtol * 1e-3 if atol is None else atol, backend, estimate_error,
                              tracking, max_steps, parameters_at)
        elif method == "splitting":
            if step is None:
                raise InvalidInputError("expected a step size `step` > 0 with method='splitting', got step=None")
            run = _run_splitting(term, t, y0, par, float(step), check_order(4 if order is None else order), backend,
                                 estimate_error, tracking, check_max_steps(max_steps))
        else:
            check_method(method)
        return _trajectory(term, t, par, run, method, order if method == "splitting" else None, euler_rates)


def _run_dop853(term: Term, t: np.ndarray, y0: np.ndarray, par: tuple, rtol: float, atol: float, backend: str,
                estimate_error: bool, tracking: tuple | None, max_steps: int | None,
                parameters_at: Callable | None) -> _Run:
    check_backend(backend)
    if parameters_at is not None and backend == "c":
        raise InvalidInputError("expected backend='auto' or 'scipy' with `parameters_at` (it calls back into Python), "
                                "got backend='c'")
    compiled = None if backend == "scipy" or parameters_at is not None else _compiled(term)
    if compiled is None and backend == "c":
        from .dop853_c import unavailable_error
        raise unavailable_error(term.name, "scipy")
    fun = None
    if compiled is None:
        rhs = term.rhs(term.rhs_module)
        if parameters_at is None:
            def fun(_t: float, y: np.ndarray) -> list:
                return rhs(*y.tolist(), *par)
        else:
            def fun(t_: float, y: np.ndarray) -> list:
                return rhs(*y.tolist(), *parameters_at(t_, y))
    sol, wall, ref, kind, factor = run_dop853(fun, t, y0, rtol, atol, reference=estimate_error, compiled=compiled,
                                              params=par, track=tracking, max_steps=max_steps)
    if ref is not None:
        kind = f"distance to {kind}"
    return _Run(y=np.ascontiguousarray(sol.y.T), args=sol.args, closest=sol.closest, near=sol.near, nfev=int(sol.nfev),
                steps=sol.steps, wall=wall, backend="scipy" if compiled is None else "c",
                ref=None if ref is None else (ref.y.T, ref.args, ref.near), factor=factor, kind=kind)


def _trajectory(term: Term, t: np.ndarray, par: tuple, run: _Run, method: str, order: int | None,
                euler_rates: tuple[float, float] | None) -> Trajectory:
    y, n = run.y, run.y.shape[1]
    omega = term.omega_indices(n)
    traj = Trajectory(t=t, y=y, n_evaluations=run.nfev, n_steps=run.steps, backend=run.backend, wall=run.wall,
                      error_estimate_kind=run.kind, args=run.args, method=method, order=order, omega_index=omega)
    state = y
    if term.quaternion is not None:
        qs = slice(term.quaternion, term.quaternion + 4)
        quat, norm_drift = project_quaternion(y[:, qs])
        traj.quaternion, traj.quaternion_norm_drift = quat, float(norm_drift)
        if run.args is not None:
            traj.euler_angles = _angles(quat, run.args, euler_rates)
            traj.pole_clearance = (float(run.closest[1]), float(run.closest[0]))
        state = y.copy()
        state[:, qs] = quat
    if run.ref is not None:
        y_ref, args_ref, near_ref = run.ref
        traj.component_error = np.max(np.abs(y - y_ref), axis=0) * run.factor
        traj.error_estimate = float(np.max(traj.component_error)) if traj.component_error.size else 0.0
        if term.quaternion is not None:
            _split_estimates(term, traj, run, quat, y_ref[:, qs], args_ref, near_ref, euler_rates)
    fn = term.invariant_function()
    if fn is not None:
        vals = fn(*par, *state.T)
        traj.invariants = np.stack([np.broadcast_to(np.asarray(v, float), t.shape) for v in vals], axis=-1)
        traj.invariant_names = term.invariant_names
    return traj


def _angles(q: np.ndarray, args: np.ndarray, euler_rates: tuple[float, float] | None) -> np.ndarray:
    return euler_angles_from_half_angles(q, args if euler_rates is None else sleeping_split(q, args, euler_rates))


def _split_estimates(term: Term, traj: Trajectory, run: _Run, quat: np.ndarray, q_ref: np.ndarray,
                     args_ref: np.ndarray | None, near_ref: Any, euler_rates: tuple[float, float] | None) -> None:
    """The error estimate split into ω, R and the Euler angles (:func:`~.half_angles.output_error_estimates`)."""
    q_ref = q_ref / np.linalg.norm(q_ref, axis=-1, keepdims=True)
    w, w_ref = run.y[:, list(traj.omega_index)], run.ref[0][:, list(traj.omega_index)]
    tracked = traj.euler_angles is not None
    zeros = np.zeros((len(quat), 3))
    ang_ref = _angles(q_ref, args_ref, euler_rates) if tracked else zeros
    est = output_error_estimates((w, quat, traj.euler_angles if tracked else zeros, run.near if tracked else None),
                                 (w_ref, q_ref, ang_ref, near_ref if tracked else None), run.factor, run.steps)
    traj.estimates = {"omega": est["omega"], "rotation": est["rotation"], "euler": est["euler"] if tracked else None}
    traj.error_estimate = max(v for v in traj.estimates.values() if v is not None)
    if traj.method == "DOP853":  # (the splitting's Richardson recipe names them already)
        traj.error_estimate_kind += "; ω, R and the Euler angles" if tracked else "; ω and R"
    traj.unresolved_passages = est["unresolved_passages"]
    if traj.unresolved_passages:
        traj.error_estimate_kind += term.passage_note.format(n=traj.unresolved_passages)


# --- the splittings --------------------------------------------------------------------------

@dataclass(frozen=True)
class _Splitter:
    """One way to run a term's splitting: ``rows(y, params, pieces, weights, t0, done)`` gives the state
    after every composed step (row 0 y; :meth:`.kick_drift_c.CompiledSplitting.propagate_recorded`)."""

    label: str
    backend: str
    rows: Callable[..., np.ndarray]
    per_step: Callable[[Sequence[float]], int]


def _check_splitting_term(term: Term, n: int) -> None:
    if term.splitting not in _SPLITTINGS or term.inertia is None or (term.splitting == "kick_drift"
                                                                       and term.stage is None):
        raise InvalidInputError(f"expected a term with a splitting (one of {', '.join(_SPLITTINGS)}, its inertia and, "
                                f"for kick_drift, its stage map) for method='splitting', got term {term.name!r} with "
                                f"splitting={term.splitting!r}")
    if term.quaternion != 3 or n != 7 or term.omega_indices(n) != (0, 1, 2):
        raise InvalidInputError(f"expected the state (ω1, ω2, ω3, q0, q1, q2, q3) for method='splitting', got "
                                f"{n} components with the quaternion at {term.quaternion}")


def _python_rows(label: str, one: Callable[..., list]) -> Callable[..., np.ndarray]:
    """rows() of a splitting stepped in Python by ``one(state, params, h, n, weights, record, t0)``."""
    def rows(y: np.ndarray, par: Sequence[float], pieces: list, weights: Sequence[float], t0: float,
             done: int) -> np.ndarray:
        out, at = [y.tolist()], t0
        for n, h in pieces:
            out.append(one(out[-1], par, h, n, weights, out, at))
            at += n * h
        arr = np.array(out)
        bad = first_nonfinite_row(arr)
        if bad is not None:  # NaN passes through math's functions silently: said here, per batch
            steps = np.repeat([h for _, h in pieces], [n for n, _ in pieces])[:max(bad - 1, 0)]
            raise nonfinite_state(label, t=t0 + float(np.sum(steps)), steps=done + len(steps))
        return arr
    return rows


def _splitter(term: Term, backend: str, par: Sequence[float]) -> _Splitter:
    from . import kick_drift, lie_poisson

    label = _LABELS[term.splitting]
    if backend not in SPLITTING_BACKENDS:
        raise InvalidInputError(f"expected backend one of {', '.join(map(repr, SPLITTING_BACKENDS))} with "
                                f"method='splitting', got {backend!r}")
    if term.splitting == "lie_poisson":
        if backend == "c":
            raise InvalidInputError("expected backend 'auto' or 'python' for the Lie–Poisson splitting (it has no "
                                    "compiled loop), got backend='c'")
        inertia = [float(i) for i in term.inertia(par)]

        def axis_flows(s: list, p: Any, h: float, n: int, weights: Any, record: list, at: float) -> list:
            L, q = lie_poisson.propagate(list(s[:3]), list(s[3:]), inertia, h, n, weights, record=record, t0=at)
            return [*L, *q]
        return _Splitter(label, "python", _python_rows(label, axis_flows), lie_poisson.subflows_per_step)
    compiled = None if backend == "python" else _compiled_splitting(term)
    if compiled is None and backend == "c":
        from .dop853_c import unavailable_error
        raise unavailable_error(term.name, "python", kind="kdk")
    if compiled is not None:
        def rows(y: np.ndarray, p: Sequence[float], pieces: list, weights: Any, t0: float, done: int) -> np.ndarray:
            return compiled.propagate_recorded(y, p, pieces, weights, t0=t0)
        return _Splitter(label, "c", rows, kick_drift.stages_per_step)
    stage = _stage_function(term, False)

    def stages(s: list, p: Any, h: float, n: int, weights: Any, record: list, at: float) -> list:
        return kick_drift.propagate(stage, s, p, h, n, weights, record=record, t0=at)
    return _Splitter(label, "python", _python_rows(f"{label} (Python)", stages), kick_drift.stages_per_step)


def _compiled_splitting(term: Term) -> Any:
    """The term's compiled kick–drift–kick loop, or None (looked up on every run, as :func:`_compiled`)."""
    from .kick_drift_c import compiled_splitting

    return compiled_splitting(term.name, term.stage)


@functools.cache
def _stage_function(term: Term, vectorised: bool) -> Callable[..., Any]:
    """The stage map compiled: f(L1..3, q0..3, h_drift, h_kick, *params) (scalar, or vectorised over arrays)."""
    from ..core.compile import compile_expressions, compile_scalar

    exprs, state, h_drift, h_kick, params = term.stage()
    args = [*state, h_drift, h_kick, *params]
    compile_ = compile_expressions if vectorised else compile_scalar
    return compile_(list(exprs), args, name=f"{term.name}_stage")


def _splitting_path(splitter: _Splitter, inertia: np.ndarray, y0: np.ndarray, par: Sequence[float],
                    args0: Sequence[float], t: np.ndarray, step: float, weights: tuple[float, ...],
                    refine: int = 1) -> tuple[np.ndarray, Any, int]:
    """((ω, raw q) (N, 7), the tracker's result, composed steps): the state after every step is followed by
    :func:`~.half_angles.follow_fixed_steps`, so the angles' turns are counted per step."""
    from .half_angles import follow_fixed_steps

    yL = np.array([*(inertia * y0[:3]), *y0[3:]])
    clock = [float(t[0]), 0]  # the time and the steps done where the next pieces start, for messages

    def advance(y: np.ndarray, pieces: list[tuple[int, float]]) -> np.ndarray:
        t0, done = clock
        clock[0] += sum(n * h for n, h in pieces)
        clock[1] += sum(n for n, _ in pieces)
        return splitter.rows(y, par, pieces, weights, t0, done)

    intervals = interval_steps(t, step, refine)
    ends, args, tracker = follow_fixed_steps(yL, inertia, args0, intervals, advance)
    arr = np.vstack([yL, ends])
    return np.hstack([arr[:, :3] / inertia, arr[:, 3:]]), (args, tracker.closest, tracker.near), \
        sum(n for n, _ in intervals)


def _run_splitting(term: Term, t: np.ndarray, y0: np.ndarray, par: tuple, step: float, order: int, backend: str,
                   estimate_error: bool, tracking: tuple | None, max_steps: int) -> _Run:
    _check_splitting_term(term, y0.size)
    weights = SPLITTING_ORDERS[order]
    # the steps are known before running: the longest run (the estimate's, at step/2) is checked
    refine = 2 if estimate_error else 1
    check_fixed_steps(_LABELS[term.splitting], sum(n for n, _ in interval_steps(t, step, refine)), max_steps,
                      step=step / refine, t_end=float(t[-1]))
    splitter = _splitter(term, backend, par)  # compiled (once per process) outside the timed run
    inertia = np.asarray(term.inertia(par), dtype=float)
    args0 = tracking[1] if tracking is not None else (math.atan2(y0[6], y0[3]), math.atan2(y0[5], y0[4]))
    start = time.perf_counter()
    y, (args, closest, near), n_steps = _splitting_path(splitter, inertia, y0, par, args0, t, step, weights)
    wall = time.perf_counter() - start
    ref, kind, factor = None, "not requested", 1.0
    if estimate_error:
        y_ref, (args_ref, _, near_ref), _ = _splitting_path(splitter, inertia, y0, par, args0, t, step, weights, 2)
        ref, factor = (y_ref, args_ref, near_ref), RICHARDSON_MARGIN * 2.0**order / (2.0**order - 1.0)
        kind = (f"Richardson: max |y_h - y_(h/2)| · 2^{order}/(2^{order} - 1) · {RICHARDSON_MARGIN}, y = ω, the "
                "orientation and the Euler angles")
    return _Run(y=y, args=args, closest=closest, near=near, nfev=n_steps * splitter.per_step(weights) + (len(t) - 1),
                steps=n_steps, wall=wall, backend=splitter.backend, ref=ref, factor=factor, kind=kind)


def integrate_ensemble(term: Term, y0: Any, t: Sequence[float], params: Sequence[Any], *, step: float,
                       order: int = 4, max_steps: int | None = None) -> Ensemble:
    """Integrate M members of ``term``'s splitting at once (vectorised over members), from ``y0`` (M, 7)
    = (ω, q) each, with ``params`` scalars or (M,) arrays; outputs (N, M, ·) at ``t``.

    ``step``, ``order`` and ``max_steps`` (steps of each member) as in :func:`integrate`; a member
    whose state stops being finite raises :class:`~mechderive.errors.IntegrationError` naming it.
    """
    from . import kick_drift, lie_poisson

    y0 = np.asarray(y0, dtype=float)
    M = y0.shape[0]
    _check_splitting_term(term, y0.shape[1])
    t = np.asarray(t, dtype=float)
    weights = SPLITTING_ORDERS[check_order(order)]
    intervals = interval_steps(t, step)
    label = _LABELS[term.splitting]
    check_fixed_steps(label, sum(n for n, _ in intervals), check_max_steps(max_steps), step=step, t_end=float(t[-1]))
    inertia = np.asarray(term.inertia(params), dtype=float)  # (3,) or (M, 3)
    I = np.broadcast_to(inertia, (M, 3))
    w0, q0 = y0[:, :3], y0[:, 3:]
    if term.splitting == "lie_poisson":
        I_cols = inertia.T if inertia.ndim == 2 else inertia  # (3, M) or (3,)
        state: Any = (np.array((I * w0).T, order="C"), np.array(q0.T, order="C"))  # (3, M), (4, M): writable copies

        def advance(s: Any, h: float, n: int) -> Any:
            lie_poisson.propagate_ensemble(s[0], s[1], I_cols, h, n, weights)
            return s

        def rows(s: Any) -> np.ndarray:
            return np.vstack(s).T
    else:
        stage, par = _stage_function(term, True), list(params)
        state = [*(I * w0).T, *q0.T]

        def advance(s: Any, h: float, n: int) -> Any:
            return kick_drift.propagate_ensemble(stage, s, par, h, n, weights)

        def rows(s: Any) -> np.ndarray:
            return np.stack(s, axis=-1)
    omegas, quats = [w0.copy()], [q0.copy()]
    n_total = 0
    start = time.perf_counter()
    with np.errstate(all="ignore"):  # a state out of range is said below, not as RuntimeWarnings
        for k, (n, h) in enumerate(intervals):
            state = advance(state, h, n)
            now = rows(state)
            bad = first_nonfinite_row(now)
            if bad is not None:
                raise nonfinite_state(label, t=float(t[k]), steps=n_total, member=bad)
            n_total += n
            omegas.append(now[:, :3] / I)
            quats.append(now[:, 3:])
    wall = time.perf_counter() - start
    with np.errstate(all="ignore"):
        omega, q_raw = np.stack(omegas), np.stack(quats)
        quat, norm_drift = project_quaternion(q_raw)
        ens = Ensemble(t=t, y=np.concatenate([omega, q_raw], axis=-1), quaternion=quat,
                       quaternion_norm_drift=norm_drift, order=order, n_steps=n_total, wall=wall)
        fn = term.invariant_function()
        if fn is not None:
            vals = fn(*params, *np.moveaxis(omega, -1, 0), *np.moveaxis(quat, -1, 0))
            ens.invariants = np.stack([np.broadcast_to(np.asarray(v, float), omega.shape[:2]) for v in vals], axis=-1)
            ens.invariant_names = term.invariant_names
    return ens


#: Integrator runs per scene at most: the first at the scene's rtol, then tightened.
MAX_ATTEMPTS = 3


def integrate_to_rtol(run: Callable[[float], Any], estimate: Callable[[Any], float | None],
                      rtol: float) -> tuple[Any, list[dict]]:
    """Run the integrator at ``rtol``; while the global error estimate exceeds it, rerun tighter.

    DOP853 bounds the error per step; over many steps the global error grows past it (×20 over
    ten nutation periods is typical).  The global error of a high-order method scales close to
    linearly with its tolerance, so the next tolerance is the last one times rtol/estimate, with
    a safety factor 1/2, down to the smallest SciPy accepts (2.3e-14).  With the compiled
    stepper a rerun costs milliseconds.  Returns the last run and one record per attempt.
    """
    tol, attempts = rtol, []
    while True:
        traj = run(tol)
        est = estimate(traj)
        attempts.append({"integrator_rtol": tol, "error_estimate": est})
        tol = next_tolerance(tol, est, rtol, len(attempts))
        if tol is None:
            return traj, attempts


def next_tolerance(tol: float, est: float | None, rtol: float, attempts: int) -> float | None:
    """The tolerance of the next run after ``attempts`` runs, the last at ``tol`` measuring ``est``, or None
    where :func:`integrate_to_rtol` stops (one rule for a single run and a batch, :mod:`.batch`)."""
    if est is None or est <= rtol or attempts >= MAX_ATTEMPTS or tol <= SCIPY_MIN_RTOL:
        return None
    return max(tol * 0.5 * rtol / est, SCIPY_MIN_RTOL)
