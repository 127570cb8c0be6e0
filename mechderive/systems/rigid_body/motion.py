"""Solving a rigid body about a fixed point: integration of the derived (ω, q) equations, or a closed form.

* **integration** (every body, any applied torque): DOP853 on the state (ω, q) — body ω and the
  unit quaternion of Rᵀ, never Euler angles, so θ = 0 exactly is an ordinary state — with the
  right-hand side derived in :mod:`.model`, compiled to C (:mod:`mechderive.solvers.driver`; SciPy's
  stepper where there is no compiler).  t is a state (t' = 1) where the applied torque depends on t.
  The error is measured on the run: the distance to a rerun at a tighter tolerance
  (:func:`mechderive.solvers.dop853.reference_tolerance`) of ω, R and the Euler angles
  (:func:`mechderive.solvers.half_angles.output_error_estimates`), rerun tighter by
  :func:`mechderive.solvers.driver.integrate_to_rtol` until it meets the scene's rtol.
* **the free top's closed form** (:func:`mechderive.systems.free_top.exact.exact_free_top`) where
  gravity exerts no torque (c = 0, M = 0 or g = 0) and no torque is applied;
* **the heavy symmetric top's closed form** (:func:`mechderive.systems.heavy_top.exact.exact_heavy_top`)
  where I1 = I2 and c = (0, 0, l) with l > 0 (the chapter's figure 42), M g > 0, with the initial
  Euler rates from ω by (3.58) solved; at θ = 0 or π exactly only a sleeping top (ω1 = ω2 = 0) maps.

Every solve returns a :class:`Motion`: ω and R at the sample times (always: the drift check needs
them), q and the Euler angles where asked for, and what the solver measured.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ...core.drift import Drift, drift
from ...errors import InvalidInputError, MechDeriveError
from ..base import OutOfReach

__all__ = ["Body", "Motion", "integrate_body", "integrate_bodies", "integration_start", "free_closed_form",
           "heavy_closed_form", "closed_form_plan", "columns", "drifts", "invariants", "conserved_axial", "MAX_INTEGRATED_RADIANS"]

#: An integration may follow at most this many radians of the motion's fastest rate (as the planner's
#: :data:`mechderive.systems.scaling.MAX_INTEGRATED_RADIANS`): beyond, a run takes minutes.
MAX_INTEGRATED_RADIANS = 2.0**18


@dataclass(frozen=True)
class Body:
    """Checked numbers of one body: principal moments about the fixed point, M, g, centre of mass c."""

    I: tuple[float, float, float]
    M: float
    g: float
    c: tuple[float, float, float]
    torque: Any = None  # a :class:`.torque.Torque` or None

    @property
    def values(self) -> list[float]:
        """(I1, I2, I3, M, g, c1, c2, c3): the order of :func:`.model.parameters`."""
        return [*self.I, self.M, self.g, *self.c]

    @property
    def mgc(self) -> float:
        """M g |c|: the largest |V| (the gravity potential V = M g ẑ·(Rᵀ c))."""
        return float(self.M * self.g * math.hypot(*self.c))

    @property
    def gravity_free(self) -> bool:
        return self.M == 0 or self.g == 0 or not any(self.c)


@dataclass
class Motion:
    """One solved motion at the sample times ``t``: ω (N, 3), R (N, 3, 3), q (N, 4) and (φ, θ, ψ) (N, 3)
    where computed, the error estimate of each output family and what the solver reports."""

    t: np.ndarray
    omega: np.ndarray
    R: np.ndarray
    quaternion: np.ndarray | None = None
    angles: np.ndarray | None = None
    estimates: dict = field(default_factory=dict)  # family ("omega", "rotation", "euler") -> estimate
    info: dict = field(default_factory=dict)
    solution: Any = None


# --- compiled pieces (derived once, cached on disk) ----------------------------------------------

@functools.cache
def _term(torque: Any) -> Any:
    """The driver's :class:`~mechderive.solvers.driver.Term` of this body's equations (one per torque text)."""
    from ...solvers.driver import Term

    timed = torque is not None and torque.depends_on_time()
    name = "rigid_body" if torque is None else f"rigid_body_tau_{torque.digest}"

    def build() -> tuple:
        import sympy as sp

        from ..free_top.integrate import gyroscopic_form
        from . import model as rm

        m = rm.model()
        applied = torque.expressions() if torque is not None else [0, 0, 0]
        generic = m.euler_rhs_generic.subs(dict(zip(rm.tau_symbols, applied)), simultaneous=True)
        wdot = gyroscopic_form(m.in_quaternion(generic), rm.omega_symbols())
        rhs = [*wdot, *m.quaternion_rhs]
        state = list(rm.state())
        if timed:
            rhs.append(sp.Integer(1))
            state.append(rm.time_symbol)
        return rhs, state, list(rm.parameters())
    return Term(name, build, quaternion=3), timed


@functools.cache
def _invariant_function() -> Callable[..., list]:
    """(E, L·ẽ3, dL1/dt, dL2/dt, dL3/dt)(I1..c3, ω1..3, R11..R33), compiled from the model."""
    from ...core.codecache import cached_lambdify

    def build() -> tuple:
        from . import model as rm

        m = rm.model()
        R = rm.rotation_symbols()
        args = [*rm.parameters(), *rm.omega_symbols(), *(R[i, j] for i in range(3) for j in range(3))]
        return args, [m.energy_generic, m.vertical_momentum_generic, *m.axial_momentum_rates]
    return cached_lambdify("rigid_body.invariants", build)[0]


def _evaluate(body: Body, omega: np.ndarray, R: np.ndarray) -> list[np.ndarray]:
    shape = omega.shape[:-1]
    with np.errstate(all="ignore"):
        out = _invariant_function()(*body.values, *np.moveaxis(omega, -1, 0), *np.moveaxis(R.reshape(shape + (9,)),
                                                                                           -1, 0))
    return [np.broadcast_to(np.asarray(v, dtype=float), shape) for v in out]


def invariants(body: Body, omega: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(E, L·ẽ3) along a motion: E = T + V (3.18, 3.65), L·ẽ3 = Σ I_a ω_a R_a3 (3.64), derived."""
    E, Lv, *_ = _evaluate(body, omega, R)
    return E, Lv


@functools.lru_cache(maxsize=256)
def conserved_axial(body: Body) -> tuple[bool, bool, bool]:
    """Which L_a = I_a ω_a the equations conserve for this body: those whose derived rate
    (:attr:`.model.RigidBodyModel.axial_momentum_rates`) vanishes — exactly, in floating point,
    where the parameters make each term vanish — at every one of several generic states."""
    if body.torque is not None:
        return (False, False, False)
    rng = np.random.default_rng(1)
    omega = rng.normal(size=(4, 3))
    from ...kinematics.conversions import quaternion_to_matrix

    q = rng.normal(size=(4, 4))
    R = quaternion_to_matrix(q / np.linalg.norm(q, axis=-1, keepdims=True))
    rates = _evaluate(body, omega, R)[2:]
    # A vanishing rate is a difference of equal terms, (I1 - I2) ω1 ω2 evaluated as I1 ω1 ω2 - I2 ω1 ω2:
    # zero to the rounding of its terms, not exactly.  A rate that does not vanish is of the size of the
    # terms themselves (random states, moments and M g |c| of order one relative to each other).
    size = max(body.I) * np.sum(omega**2, axis=-1) + body.mgc
    return tuple(bool(np.all(np.abs(r) <= 64 * np.finfo(float).eps * size)) for r in rates)  # type: ignore[return-value]


# --- integration --------------------------------------------------------------------------------

def _rate_bound(body: Body, omega0: np.ndarray, R0: np.ndarray) -> float:
    """The fastest rate (rad/s) of a motion with no applied torque: |ω| ≤ √(2 T_max / I_min) with
    T ≤ E - min V = T0 + V0 + M g |c|, times the largest coupling of Euler's equations (3.33), and
    the pendulum's √(M g |c| / I_min)."""
    I = np.array(body.I)
    E, _ = invariants(body, omega0, R0)
    T_max = max(float(E) + body.mgc, 0.0)
    spin = math.sqrt(2.0 * T_max / I.min())
    coupling = max(1.0, *(abs(I[(a + 1) % 3] - I[(a + 2) % 3]) / I[a] for a in range(3)))
    return spin * coupling + math.sqrt(body.mgc / I.min())


def integration_start(body: Body, initial: dict, t: np.ndarray) -> tuple[Any, bool, list[float], tuple, list[float]]:
    """(the term, whether t is a state, y0 = (ω, q[, t0]), the half-angles (σ0, δ0) to follow, the parameter
    values) of an integration from the checked ``initial``; refuses a run longer than
    :data:`MAX_INTEGRATED_RADIANS` of the motion's fastest rate, naming ``[time].t_end``."""
    from ...kinematics.conversions import euler_to_quaternion, quaternion_to_matrix
    from ...solvers.half_angles import initial_half_angles

    term, timed = _term(body.torque)
    w0 = np.asarray(initial["omega"], dtype=float)
    q0 = euler_to_quaternion(initial["phi"], initial["theta"], initial["psi"])
    if body.torque is None:
        rate = _rate_bound(body, w0, quaternion_to_matrix(q0))
        if rate * float(t[-1] - t[0]) > MAX_INTEGRATED_RADIANS:
            limit = MAX_INTEGRATED_RADIANS / rate
            raise InvalidInputError(
                f"scene key [time].t_end: expected at most {limit:.6g} s for method 'integrate' "
                f"({MAX_INTEGRATED_RADIANS:.6g} rad at this motion's fastest rate, {rate:.6g} rad/s: a longer run "
                f"would take many minutes), got {float(t[-1]):.6g}")
    y0 = [*w0, *q0, *([float(t[0])] if timed else [])]
    return term, timed, y0, initial_half_angles(initial["phi"], initial["psi"]), body.values


def _outputs(tr: Any) -> tuple:
    """(ω, the unit quaternion, the Euler angles, max ||q| - 1|) of a run."""
    from ...solvers.half_angles import euler_angles_from_half_angles

    q = tr.y[:, 3:7]
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    q = q / norm
    return tr.y[:, :3], q, euler_angles_from_half_angles(q, _sleeping_split(q, tr.args)), \
        float(np.max(np.abs(norm - 1.0)))


def _estimated(main: Any, ref: Any, tol: float) -> dict:
    """A run at ``tol`` with its error measured against the reference run ``ref`` (ω, R, the Euler angles)."""
    from ...solvers.dop853 import reference_tolerance
    from ...solvers.half_angles import output_error_estimates

    rt_ref, factor = reference_tolerance(tol)
    w, q, ang, _ = out = _outputs(main)
    w_r, q_r, ang_r, _ = _outputs(ref)
    est = output_error_estimates((w, q, ang, None), (w_r, q_r, ang_r, None), factor, main.n_steps)
    est = {"omega": est["omega"], "rotation": est["rotation"], "euler": est["euler"]}
    kind = (f"distance to a rerun at rtol={rt_ref:.2g}" + (f", × {factor:.3g}" if factor != 1.0 else "")
            + ("" if rt_ref < tol else " (looser: no tighter run is possible; an upper bound)"))
    return dict(main=main, out=out, estimates=est, kind=kind)


def _motion(t: np.ndarray, r: dict, attempts: list, need: tuple[str, ...], timed: bool) -> Motion:
    from ...kinematics.conversions import quaternion_to_matrix

    main = r["main"]
    w, q, ang, norm_drift = r["out"]
    info = {"solver": "integration: DOP853 on (ω, q)" + (", t carried as a state" if timed else ""),
            "integrator": f"DOP853 ({'compiled C' if main.backend == 'c' else 'SciPy solve_ivp'})",
            "integrator_attempts": attempts, "rhs_evaluations": int(main.n_evaluations),
            "steps": main.n_steps, "error_estimate_kind": r["kind"] + "; of " + ", ".join(need),
            "quaternion_norm_drift": norm_drift}
    return Motion(t=t, omega=w, R=quaternion_to_matrix(q), quaternion=q, angles=ang, estimates=r["estimates"],
                  info=info, solution=main)


def integrate_body(body: Body, initial: dict, t: np.ndarray, rtol: float, *, need: tuple[str, ...] = ("omega",
                   "rotation"), backend: str = "auto") -> Motion:
    """Integrate the body from the checked ``initial`` (φ, θ, ψ, ω) at ``t[0]`` through ``t``, to ``rtol``.

    ``need``: the output families whose estimate counts ("omega", "rotation", "euler").
    """
    from ...solvers.dop853 import reference_tolerance
    from ...solvers.driver import integrate, integrate_to_rtol

    term, timed, y0, args0, par = integration_start(body, initial, t)

    def one(tol: float, at: float) -> Any:
        return integrate(term, y0, t, par, rtol=tol, atol=at, estimate_error=False, track=args0, backend=backend)

    def run(tol: float) -> dict:
        rt_ref, _ = reference_tolerance(tol)
        return _estimated(one(tol, tol * 1e-3), one(rt_ref, tol * 1e-3 * rt_ref / tol), tol)

    r, attempts = integrate_to_rtol(run, lambda r: _estimate(r, need), rtol)
    return _motion(t, r, attempts, need, timed)


def _estimate(r: dict, need: tuple[str, ...]) -> float:
    return max(r["estimates"][k] for k in need) if need else 0.0


def integrate_bodies(bodies: list[Body], initials: list[dict], t: np.ndarray, rtol: float, *,
                     need: tuple[str, ...] = ("omega", "rotation")) -> list[Motion | MechDeriveError] | None:
    """:func:`integrate_body` for M bodies with one torque (a sweep's points), their runs batched through
    the compiled stepper (:mod:`mechderive.solvers.batch`): [each point's motion, equal to
    :func:`integrate_body`'s bit for bit, or the error that stopped it (its refusal of the run's length,
    or the integrator's)]; None without a C compiler."""
    from ...solvers.batch import integrate_batch, integrate_to_rtol_batch
    from ...solvers.dop853 import reference_tolerance

    starts: list[Any] = []
    for body, initial in zip(bodies, initials):
        try:
            starts.append(integration_start(body, initial, t))
        except MechDeriveError as exc:
            starts.append(exc)
    ok = [i for i, s in enumerate(starts) if not isinstance(s, MechDeriveError)]
    out: list[Any] = list(starts)
    if not ok:
        return out
    term, timed = starts[ok[0]][0], starts[ok[0]][1]
    if any(starts[i][0] is not term for i in ok):
        raise InvalidInputError("expected bodies with one applied torque (one term) in a batch")
    y0 = np.array([starts[i][2] for i in ok])
    args0 = np.array([starts[i][3] for i in ok])
    par = np.array([starts[i][4] for i in ok])

    def run(tols: np.ndarray, points: np.ndarray) -> list | None:
        tols = [float(x) for x in tols]
        refs = [reference_tolerance(tol)[0] for tol in tols]
        main = integrate_batch(term, y0[points], t, par[points], rtol=tols, atol=[tol * 1e-3 for tol in tols],
                               estimate_error=False, track=args0[points])
        if main is None:
            return None
        ended = [j for j, m in enumerate(main) if not isinstance(m, MechDeriveError)]  # their references
        ref = dict(zip(ended, integrate_batch(term, y0[points[ended]], t, par[points[ended]],
                                              rtol=[refs[j] for j in ended],
                                              atol=[tols[j] * 1e-3 * refs[j] / tols[j] for j in ended],
                                              estimate_error=False, track=args0[points[ended]]) if ended else []))
        return [m if isinstance(m, MechDeriveError) else ref[j] if isinstance(ref[j], MechDeriveError) else
                _estimated(m, ref[j], tols[j]) for j, m in enumerate(main)]

    done = integrate_to_rtol_batch(run, lambda r, _: _estimate(r, need), rtol, len(ok))
    if done is None:
        return None
    for i, d in zip(ok, done):
        out[i] = d if isinstance(d, MechDeriveError) else _motion(t, d[0], d[1], need, timed)
    return out


def _sleeping_split(q: np.ndarray, args: np.ndarray) -> np.ndarray:
    """(σ, δ) with ψ carrying the whole turn where only φ + ψ (or φ - ψ) exists along the entire run.

    A body that stays exactly at θ = 0 (q1 = q2 = 0 throughout) turns by φ + ψ only, and the tracker
    would share it equally between φ and ψ; the spin about e3 is ψ's (the heavy top's closed form and
    (3.63): ψ̇ = ω3, φ̇ = 0 there), so φ is kept at φ0: δ - δ0 = -(σ - σ0).  At θ = π (q0 = q3 = 0
    throughout) likewise σ - σ0 = -(δ - δ0).
    """
    out = np.array(args, dtype=float, copy=True)
    if not np.any(q[:, 1:3]):
        out[:, 1] = args[0, 1] - (args[:, 0] - args[0, 0])
    elif not np.any(q[:, [0, 3]]):
        out[:, 0] = args[0, 0] - (args[:, 1] - args[0, 1])
    return out


# --- closed forms --------------------------------------------------------------------------------

def closed_form_plan(body: Body, initial: dict) -> tuple[str, str]:
    """(which closed form, why it applies): ("free", …) or ("heavy", …); raises :class:`OutOfReach` saying
    why none applies."""
    if body.torque is not None:
        raise OutOfReach("an applied torque: no closed form (closed forms: the free top, the heavy symmetric top)")
    if body.gravity_free:
        why = ("c = 0: gravity exerts no torque about the centre of mass" if not any(body.c) else
               "M g = 0: no gravity torque")
        return "free", f"the free top's closed form (Jacobi elliptic functions, 3.4): {why}"
    I1, I2, I3 = body.I
    c1, c2, c3 = body.c
    if I1 != I2 or c1 != 0 or c2 != 0:
        raise OutOfReach("no closed form for this body (closed forms: c = 0, the free top; I1 = I2 with c on axis 3, "
                         f"the heavy symmetric top), got I1 = {I1:g}, I2 = {I2:g}, c = ({c1:g}, {c2:g}, {c3:g})")
    if c3 < 0 or body.g < 0:
        raise OutOfReach("the heavy top's closed form takes the centre of mass on +e3 above the pivot (l = c3 > 0, "
                         f"g > 0, figure 42), got c3 = {c3:g}, g = {body.g:g}")
    w1, w2, _ = initial["omega"]
    if math.sin(initial["theta"]) == 0.0 and (w1 != 0.0 or w2 != 0.0):
        raise OutOfReach("the heavy top's closed form starts from Euler rates, which are not defined at θ = "
                         f"{initial['theta']:g} with ω1, ω2 = {w1:g}, {w2:g} ≠ 0")
    return "heavy", ("the heavy symmetric top's closed form (3.73)-(3.75): I1 = I2 and c = (0, 0, l), "
                     f"l = {c3:g}")


def _continuous_sign(q: np.ndarray) -> np.ndarray:
    """q with its sign chosen continuous along the samples (q and -q are the same rotation)."""
    flip = np.cumsum(np.r_[0, (np.sum(q[1:] * q[:-1], axis=-1) < 0).astype(int)]) % 2
    return np.where(flip[:, None] == 1, -q, q)


def _t_max_check(t: np.ndarray, t_max: float, what: str) -> None:
    if t[-1] > t_max:
        raise InvalidInputError(f"scene key [time].t_end: expected at most {t_max:.6g} s for this motion in closed "
                                f"form ({what}: beyond, the count is no longer an exact integer in double "
                                f"precision), got {float(t[-1]):.6g}")


def free_closed_form(body: Body, initial: dict, t: np.ndarray, need: tuple[str, ...], strict: bool) -> Motion:
    """The free top's closed form, :func:`~mechderive.systems.free_top.exact.exact_free_top`."""
    from ...kinematics.rotations import rotation_matrix
    from ..free_top.exact import exact_free_top

    R0 = rotation_matrix(initial["phi"], initial["theta"], initial["psi"])
    try:
        sol = exact_free_top(body.I, initial["omega"], R0=R0, strict=strict)
    except InvalidInputError as exc:
        raise OutOfReach(f"the free top's closed form: {exc}") from exc
    _t_max_check(t, sol.t_max, "2^50 quarter periods or turns")
    names = {"omega": "omega", "rotation": "R", "euler": "euler_angles"}
    angles = sol.euler_angles(t) if "euler" in need else None
    q = sol.quaternion(t) if "quaternion" in need else None
    est = float(sol.error_estimate(t, sorted({names[k] for k in need if k in names} | {"omega", "R"})))
    return Motion(t=t, omega=sol.omega(t), R=sol.rotation(t), quaternion=q, angles=angles,
                  estimates={k: est for k in ("omega", "rotation", "euler")},
                  info={"kind": sol.kind, "polhode_period": sol.polhode_period}, solution=sol)


def heavy_closed_form(body: Body, initial: dict, t: np.ndarray, need: tuple[str, ...], strict: bool) -> Motion:
    """The heavy symmetric top's closed form, :func:`~mechderive.systems.heavy_top.exact.exact_heavy_top`,
    with l = c3 and the Euler rates of (3.58) solved for ω (at sin θ = 0: a sleeping top, ψ̇ = ω3)."""
    from ...kinematics.conversions import matrix_to_quaternion
    from ...kinematics.rotations import euler_rates
    from ..heavy_top.exact import exact_heavy_top

    th, w = initial["theta"], initial["omega"]
    if math.sin(th) == 0.0:
        rates = (0.0, 0.0, float(w[2]))
    else:
        rates = tuple(float(x) for x in euler_rates(th, initial["psi"], *w))
    I1, _, I3 = body.I
    params = dict(I1=I1, I3=I3, M=body.M, g=body.g, l=body.c[2])
    init = dict(phi=initial["phi"], theta=th, psi=initial["psi"], phi_dot=rates[0], theta_dot=rates[1],
                psi_dot=rates[2])
    try:
        top = exact_heavy_top(params, init, strict=strict)
    except InvalidInputError as exc:
        raise OutOfReach(f"the heavy top's closed form: {exc}") from exc
    _t_max_check(t, top.t_max, "2^51 nutation periods")
    names = ["omega", "R"] + (["phi", "theta", "psi"] if "euler" in need else [])
    values = top.evaluate(t, names)
    est = float(top.error_estimate(t, names))
    angles = np.stack([values["phi"], values["theta"], values["psi"]], axis=-1) if "euler" in need else None
    q = _continuous_sign(matrix_to_quaternion(values["R"])) if "quaternion" in need else None
    return Motion(t=t, omega=values["omega"], R=values["R"], quaternion=q, angles=angles,
                  estimates={k: est for k in ("omega", "rotation", "euler")},
                  info={"motion_class": top.motion_class, "nutation_period": top.nutation_period,
                        "initial_euler_rates": dict(zip(("phi_dot", "theta_dot", "psi_dot"), rates))},
                  solution=top)


# --- outputs --------------------------------------------------------------------------------------

_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))


def families(names: tuple[str, ...]) -> tuple[str, ...]:
    """The output families the quantities ``names`` come from: omega, rotation, quaternion, euler."""
    out: list[str] = []
    for q in names:
        if q.startswith("omega") or q in ("L1", "L2", "L3", "p_psi"):
            fam = ("omega",)
        elif q in _R_NAMES or q.startswith("apex_"):
            fam = ("rotation",)
        elif q in ("q0", "q1", "q2", "q3"):
            fam = ("rotation", "quaternion")
        elif q == "theta":  # from R, as well conditioned as R: |Δθ| ≤ the rotation angle between R and R_exact
            fam = ("rotation",)
        elif q in ("phi", "psi"):
            fam = ("euler",)
        else:  # energy, L_vertical: from ω and R
            fam = ("omega", "rotation")
        out.extend(f for f in fam if f not in out)
    return tuple(out)


def columns(names: tuple[str, ...], motion: Motion, body: Body) -> dict[str, np.ndarray]:
    """The requested columns from a solved motion."""
    out: dict[str, np.ndarray] = {}
    inv = None
    for q in names:
        if q.startswith("omega"):
            out[q] = motion.omega[:, int(q[-1]) - 1]
        elif q in ("L1", "L2", "L3"):
            a = int(q[-1]) - 1
            out[q] = body.I[a] * motion.omega[:, a]
        elif q == "p_psi":
            out[q] = body.I[2] * motion.omega[:, 2]
        elif q in _R_NAMES:
            out[q] = motion.R[:, int(q[1]) - 1, int(q[2]) - 1]
        elif q.startswith("apex_"):
            out[q] = motion.R[:, 2, "xyz".index(q[-1])]
        elif q in ("q0", "q1", "q2", "q3"):
            out[q] = motion.quaternion[:, int(q[1])]
        elif q == "theta":
            # θ = arccos R33 ∈ [0, π], as atan2(√(R13² + R23²), R33): accurate at 0 and π alike
            R = motion.R
            out[q] = np.arctan2(np.hypot(R[:, 0, 2], R[:, 1, 2]), R[:, 2, 2])
        elif q in ("phi", "psi"):
            out[q] = motion.angles[:, ("phi", "theta", "psi").index(q)]
        elif q in ("energy", "L_vertical"):
            if inv is None:
                inv = invariants(body, motion.omega, motion.R)
            out[q] = inv[0] if q == "energy" else inv[1]
        else:
            raise InvalidInputError(f"unknown rigid_body quantity {q!r}")
    return out


def drifts(body: Body, motion: Motion) -> dict[str, Drift]:
    """E and L·ẽ3 (and p_ψ = I3 ω3 where the derivation finds it conserved) against scales of the motion.

    E against max_t (T + |V|) (the size of the terms E sums; |V| ≤ M g |c|); the momenta against
    max(|L·ẽ3(0)|, |p_ψ(0)|, √(2 I_max T_max), √(I_max M g |c|)): the momenta's own size, that of the
    angular momentum the kinetic energy implies, and the momentum gravity gives in a time
    √(I / M g |c|) — so a body let go from rest is measured against the latter.  With an applied
    torque nothing is conserved: E and L·ẽ3 are outputs only, and no drift is reported.
    """
    if body.torque is not None:
        return {}
    E, Lv = invariants(body, motion.omega, motion.R)
    I = np.array(body.I)
    T = 0.5 * np.sum(I * motion.omega**2, axis=-1)
    V = E - T
    with np.errstate(invalid="ignore"):
        e_scale = float(np.nanmax(T + np.abs(V)))
        t_max = float(np.nanmax(T))
    p_psi = body.I[2] * motion.omega[:, 2]
    p_scale = float(np.nanmax([abs(Lv[0]), abs(p_psi[0]), math.sqrt(2.0 * I.max() * t_max),
                               math.sqrt(I.max() * body.mgc)]))
    momenta = "max(|L_vertical(0)|, |p_ψ(0)|, √(2 I_max T_max), √(I_max M g |c|))"
    out = {"energy": drift(E, e_scale, "max_t (T + |V|)"), "L_vertical": drift(Lv, p_scale, momenta)}
    if conserved_axial(body)[2]:
        out["p_psi"] = drift(p_psi, p_scale, momenta)
    return out
