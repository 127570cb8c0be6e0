"""The planner: from a scene's requested quantities to the derivations, compilations and solves they need.

Each system maps every quantity name to what computes it.  Only those are run:
a heavy-top scene asking for ``u`` evaluates sn² of the nutation phase and nothing
else — not the amplitude, not Π, not the partial fractions of φ̇ and ψ̇ (which are
not even derived).  The report lists exactly what was derived and compiled in this
run (empty on a warm disk cache: see :mod:`mechderive.core.codecache`).

Method choice (``method = "auto"``): the closed form where the system has one
(free_top, heavy_top) — it is more accurate than integration at every rtol, and as fast
as the compiled DOP853 at its loosest tolerances (see ``benchmarks/``); integration
otherwise (falling_cat).  Near a pole passage φ and ψ each are ill-conditioned for any
method; the closed form's estimate says so (its conditioning), and the report says what
is well conditioned instead rather than switching methods silently.

Error estimates are measured on the run, never a constant: the closed forms' own
``error_estimate(t, quantities)`` (a residual of the derived equations at the samples,
scaled to an error in the output), the integrators' global estimate (a rerun at a tighter
tolerance).  ``rtol_met`` is ``estimate <= rtol`` (both absolute: angles in rad, R
entries), or ``None`` with ``rtol_met_reason`` when there is no estimate.

Drift of conserved quantities (:func:`mechderive.core.drift.drift`) is measured against a
scale of the motion, never the quantity's own initial value (which may be ~0, e.g.
p_φ = 0): for the heavy top E against max_t (T + |V|), p_φ and p_ψ against
max(|p_φ(0)|, |p_ψ(0)|, √(2 I1 T_max), √(I1 M g l)); for the free top T against T
and |L| against |L|; for the falling cat L (which must stay 0) against the angular
momentum its turn carries, max_t |Ĩ Ω|.  The same functions serve the closed form and
the integrator (from the trajectory's own invariants); ``drift_relative_to`` in the
report names each scale and its size.

``strict = false`` scenes run moments no rigid body has; ``waived`` in the report lists
the conditions that were waived (empty otherwise).

Extreme numbers (issue 12): a scene far from order one is solved in the units of its own motion,
exact powers of two (:mod:`.units`; the report's ``units`` says so), and what no choice of units
brings within double precision is refused before solving, naming the scene keys and the range
allowed — an output beyond the doubles (E = ½ I ω² of 1e600 J), a ``t_end`` beyond a closed form's
2^51 periods or an integration's :data:`~.units.MAX_INTEGRATED_RADIANS`.  With ``method = "auto"``
a motion the closed form cannot follow (within ~1e-75 rad of the pole or the bottom, ~1e-150 of the
separatrix) is integrated, and the note says why; ``method = "exact"`` refuses it, naming the keys.
A solver's own refusal is prefixed with the scene keys its message mentions.
"""

from __future__ import annotations

import contextvars
import functools
import math
import re
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..core import cbuild, codecache
from ..core.drift import Drift, drift
from ..core.model import derivation_log, derivation_seconds
from ..errors import InvalidInputError, MechDeriveError
from ..systems.heavy_top import parameters as heavy_top_parameters
from ..systems.base import OutOfReach as SystemOutOfReach, Solved
from .schema import FALLING_CAT_PARAMETERS, Scene, waived
from .units import (MAX_INTEGRATED_RADIANS, MAX_INTEGRATED_RADIANS_SCIPY, OUTPUT_KEYS, Scaled, check_invariants,
                    check_samples, in_scene_units, keys_text, scale_scene)

__all__ = ["RunResult", "run_scene"]

_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))


@dataclass
class RunResult:
    """The table a scene asked for (``t`` then the quantities, in order) and the run's report."""

    scene: Scene
    t: np.ndarray
    columns: dict[str, np.ndarray]
    report: dict[str, Any] = field(default_factory=dict)
    solution: Any = None  # the solved object (in the solver's units where the report has ``units``)


def _compiled(name: str, build: Callable[[], tuple], module: str = "numpy") -> Callable[..., list]:
    return codecache.cached_lambdify(name, build, module=module)[0]


# --- conserved quantities, derived and compiled like everything else -----------------------------

@functools.cache
def _heavy_invariants() -> Callable[..., list]:
    def build():
        from ..systems.heavy_top import model as hm

        m = hm.model()
        return [*hm.PARAMETERS, *hm.STATE], [m.energy, m.azimuthal_momentum, m.spin_momentum]
    return _compiled("heavy_top.invariants", build)


@functools.cache
def _free_invariants() -> Callable[..., list]:
    def build():
        from ..systems.free_top import model as fm

        m = fm.model()
        return [fm.I1, fm.I2, fm.I3, *fm.omega_symbols()], [m.energy, m.angular_momentum_squared]
    return _compiled("free_top.invariants", build)


def _heavy_drifts(p: dict, energy: Any, p_phi: Any, p_psi: Any, cos_theta: Any) -> dict[str, Drift]:
    """E, p_φ, p_ψ (3.63)-(3.65) along a heavy top's motion against scales of that motion.

    E against max_t (T + |V|) with V = M g l cos θ, T = E - V: the size of the terms E sums.
    p_φ and p_ψ against max(|p_φ(0)|, |p_ψ(0)|, √(2 I1 T_max), √(I1 M g l)): the momenta's own
    size, that of the angular momentum the kinetic energy implies (|L| ~ √(2 I T)), and the
    momentum gravity gives in a time √(I1 / M g l) — so p_φ = 0 is measured against p_ψ, the
    sleeping top's p_ψ against itself, a top let go from rest against √(I1 M g l).
    """
    I1, mgl = float(p["I1"]), float(p["M"] * p["g"] * p["l"])
    E, pf, ps = (np.asarray(x, dtype=float) for x in (energy, p_phi, p_psi))
    V = mgl * np.asarray(cos_theta, dtype=float)
    T = np.maximum(E - V, 0.0)
    with np.errstate(invalid="ignore"):
        e_scale = float(np.nanmax(T + np.abs(V))) if np.any(np.isfinite(T)) else float("nan")
        t_max = float(np.nanmax(T)) if np.any(np.isfinite(T)) else 0.0
    # (√(I1 M g l) is finite: a momentum undefined at t = 0 does not make the scale undefined)
    p_scale = float(np.nanmax([abs(pf[0]), abs(ps[0]), np.sqrt(2.0 * I1 * t_max), np.sqrt(I1 * mgl)]))
    momenta = "max(|p_φ(0)|, |p_ψ(0)|, √(2 I1 T_max), √(I1 M g l))"
    return {"energy": drift(E, e_scale, "max_t (T + |V|)"), "p_phi": drift(pf, p_scale, momenta),
            "p_psi": drift(ps, p_scale, momenta)}


def _heavy_parameters(scene: Scene) -> dict:
    """I1 I3 M g l for the compiled functions (``Mgl`` realised as M = 1, g = Mgl, l = 1: only M g l enters)."""
    return heavy_top_parameters.check_params(scene.parameters, strict=scene.strict)


# --- heavy top ---------------------------------------------------------------------------------

_HEAVY_DIRECT = {"theta": "theta", "phi": "phi", "psi": "psi", "theta_dot": "theta_dot", "phi_dot": "phi_dot",
                 "psi_dot": "psi_dot", "u": "u"}


def _heavy_needs(names: tuple[str, ...]) -> list[str]:
    need: list[str] = []
    for q in names:
        if q in _HEAVY_DIRECT:
            key = _HEAVY_DIRECT[q]
        elif q in _R_NAMES:
            key = "R"
        elif q.startswith("apex_"):
            key = "apex"
        elif q.startswith("omega"):
            key = "omega"
        elif q in ("energy", "p_phi", "p_psi"):
            need.extend(k for k in ("theta", "theta_dot", "phi_dot", "psi_dot") if k not in need)
            continue
        else:
            raise InvalidInputError(f"unknown heavy_top quantity {q!r}")
        if key not in need:
            need.append(key)
    return need


def _heavy_columns(names: tuple[str, ...], values: dict[str, np.ndarray], params: dict) -> dict[str, np.ndarray]:
    """The requested columns from the solver's values; ``params`` in :data:`PARAM_KEYS` form (checked)."""
    out: dict[str, np.ndarray] = {}
    inv = None
    for q in names:
        if q in _HEAVY_DIRECT:
            out[q] = values[_HEAVY_DIRECT[q]]
        elif q in _R_NAMES:
            out[q] = values["R"][..., int(q[1]) - 1, int(q[2]) - 1]
        elif q.startswith("apex_"):
            out[q] = values["apex"][..., "xyz".index(q[-1])]
        elif q.startswith("omega"):
            out[q] = values["omega"][..., int(q[-1]) - 1]
        else:
            if inv is None:
                p = [params[k] for k in ("I1", "I3", "M", "g", "l")]
                inv = _heavy_invariants()(*p, values["theta"], values["theta_dot"], values["phi_dot"], values["psi_dot"])
            out[q] = np.broadcast_to(np.asarray(inv[("energy", "p_phi", "p_psi").index(q)], float), values["theta"].shape)
    return out


#: The heavy top's quantities that are ill-conditioned near a pole passage (only φ ± ψ is defined there).
_POLE_CONDITIONED = ("phi", "psi", "phi_wrapped", "psi_wrapped", "phi_dot", "psi_dot")


class _OutOfReach(InvalidInputError):
    """A closed form cannot follow this motion (it says why); ``method = "auto"`` integrates it instead."""


#: The heavy top's estimate names whose values are rates (rad/s): in a scaled scene their estimate scales too.
_HEAVY_RATE_ESTIMATES = ("theta_dot", "phi_dot", "psi_dot", "u_dot", "omega")
_HEAVY_STATE_KEYS = ("theta", "theta_dot", "phi_dot", "psi_dot")


def _heavy_estimate(top: Any, t: np.ndarray, names: list[str], scaled: Scaled) -> float:
    """The closed form's estimate over ``names`` in the scene's units (a rate's estimate converted from the solver's)."""
    if scaled.rate == 0:
        return float(top.error_estimate(t, names))
    rates = [k for k in names if k in _HEAVY_RATE_ESTIMATES]
    others = [k for k in names if k not in _HEAVY_RATE_ESTIMATES]
    return max(float(top.error_estimate(t, others)) if others else 0.0,
               float(np.ldexp(top.error_estimate(t, rates), scaled.rate)) if rates else 0.0)


def _heavy_exact(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..systems.heavy_top.exact import exact_heavy_top

    scaled = _units(scene)

    try:
        top = exact_heavy_top(scene.parameters, scene.initial, strict=scene.strict)
    except InvalidInputError as exc:
        raise _OutOfReach(f"{keys_text('initial', _HEAVY_STATE_KEYS)} (with the parameters): {exc}") from exc
    if t[-1] > top.t_max:
        raise InvalidInputError(
            f"scene key [time].t_end: expected at most {scaled.seconds(top.t_max):.6g} s for this motion in closed "
            f"form (2^51 nutation periods of {scaled.seconds(top.nutation_period):.6g} s: beyond, the period count "
            f"is no longer an exact integer in double precision), got {scaled.original.t_end!r}")
    need = _heavy_needs(scene.quantities)
    values, ps = top._evaluate(t, need)
    cols = _heavy_columns(scene.quantities, values, _heavy_parameters(scene))

    # measured on this run, at the very values output, from what the quantities need only
    # (HeavyTopSolution.error_estimate: residuals of the derived equations, quadrature of the rates)
    estimate = _heavy_estimate(top, t, need, scaled)
    info = {"error_estimate": estimate,
            "evaluated": ps.computed, "motion_class": top.motion_class,
            "nutation_period": scaled.seconds(top.nutation_period)}
    angles = [k for k in need if k in _POLE_CONDITIONED]
    if angles and estimate > scene.rtol:
        # Near the pole (or the bottom) φ and ψ each are ill-conditioned — the motion itself defines
        # them poorly there, and the estimate counts it; R, the apex and ω, built from the
        # well-conditioned half sums and differences, may still meet rtol: say so if they do.
        rest = [k for k in need if k not in _POLE_CONDITIONED] or ["R"]
        if _heavy_estimate(top, t, rest, scaled) <= scene.rtol:
            info["error_estimate_kind"] = "near-pole conditioning of φ, ψ"
    return cols, info, top


#: Integrator runs per scene at most: the first at the scene's rtol, then tightened.
_MAX_ATTEMPTS = 3


def _integrate_to_rtol(run: Callable[[float], Any], estimate: Callable[[Any], float | None],
                       rtol: float) -> tuple[Any, list[dict]]:
    """Run the integrator at the scene's rtol; while the global error estimate exceeds it, rerun tighter.

    DOP853 bounds the error per step; over many steps the global error grows past it (×20 over
    ten nutation periods is typical).  The global error of a high-order method scales close to
    linearly with its tolerance, so the next tolerance is the last one times rtol/estimate, with
    a safety factor 1/2, down to the smallest SciPy accepts (2.3e-14).  With the compiled
    stepper a rerun costs milliseconds.  Returns the last run and one record per attempt.
    """
    from ..solvers.dop853 import SCIPY_MIN_RTOL

    tol, attempts = rtol, []
    while True:
        traj = run(tol)
        est = estimate(traj)
        attempts.append({"integrator_rtol": tol, "error_estimate": est})
        if est is None or est <= rtol or len(attempts) >= _MAX_ATTEMPTS or tol <= SCIPY_MIN_RTOL:
            return traj, attempts
        tol = max(tol * 0.5 * rtol / est, SCIPY_MIN_RTOL)


def _heavy_rate_bound(scene: Scene) -> float:
    """The fastest rate of a heavy top's motion (rad/s): of the body's ω, of its nutation, of the pendulum.

    ω3 = ψ̇ + φ̇ cos θ is constant (p_ψ = I3 ω3, 3.64); ω1² + ω2² ≤ 2 T / I1 with T ≤ E - V ≤ T0 + 2 M g l
    (3.65); the fast nutation turns at a = I3 ω3 / I1 (3.70), which exceeds ω3 where I3 > I1 (a body
    only with strict = false); the pendulum's rate √(M g l / I1) sets the time scale of a top let go
    from rest.  Square roots are taken before the quotients, so nothing overflows.
    """
    p, s = _heavy_parameters(scene), scene.initial
    I1, I3, mgl = p["I1"], p["I3"], p["M"] * p["g"] * p["l"]
    th = s["theta"]
    w3 = abs(s["psi_dot"] + s["phi_dot"] * math.cos(th))
    transverse = math.hypot(s["theta_dot"], s["phi_dot"] * math.sin(th))  # √(ω1² + ω2²) at t = 0
    pendulum = math.sqrt(mgl) / math.sqrt(I1)
    return max(math.hypot(transverse, 2.0 * pendulum), w3, w3 * (I3 / I1) if w3 else 0.0, pendulum)


def _check_integration_length(scene: Scene, rate: float, scaled: Scaled) -> None:
    """Refuse, naming t_end, an integration longer than :data:`~.units.MAX_INTEGRATED_RADIANS` of the fastest
    rate (:data:`~.units.MAX_INTEGRATED_RADIANS_SCIPY` without the compiled stepper): minutes of work."""
    from ..core.cbuild import c_enabled

    budget, stepper = ((MAX_INTEGRATED_RADIANS, "") if c_enabled() else
                       (MAX_INTEGRATED_RADIANS_SCIPY, " on SciPy's stepper (no C compiler)"))
    if rate * scene.t_end > budget:
        if not math.isfinite(rate):
            raise InvalidInputError(
                f"{OUTPUT_KEYS[scaled.original.system]}: expected a motion whose fastest rate is a double for "
                f"method 'integrate', got moments and rates whose Euler equations turn it faster than ~1e308 rad/s")
        limit = scaled.seconds(budget / rate)
        raise InvalidInputError(
            f"scene key [time].t_end: expected at most {limit:.6g} s for method 'integrate'{stepper} "
            f"({budget:.6g} rad at this motion's fastest rate, "
            f"{float(np.ldexp(rate, scaled.rate)):.6g} rad/s: a longer run would take many minutes; "
            f"method = \"exact\" solves the free and heavy tops at any t_end), "
            f"got {scaled.original.t_end!r}")


def _heavy_integrate(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..kinematics.rotations import euler_rates
    from ..systems.heavy_top.integrate import integrate_heavy_top

    scaled = _units(scene)

    _check_integration_length(scene, _heavy_rate_bound(scene), scaled)
    rate_unit = 2.0**scaled.rate

    def estimate(tr: Any) -> float | None:
        # ω in rad/s of the scene, R and the angles in rad (HeavyTopTrajectory.angle_error_estimate's parts)
        parts = (tr.omega_error_estimate, tr.rotation_error_estimate, tr.euler_angle_error_estimate)
        if any(x is None for x in parts):
            return None
        return float(max(parts[0] * rate_unit, parts[1], parts[2]))

    traj, attempts = _integrate_to_rtol(
        lambda tol: integrate_heavy_top(scene.parameters, scene.initial, t, method="DOP853", rtol=tol,
                                        atol=tol * 1e-3, strict=scene.strict),
        estimate, scene.rtol)
    phi, theta, psi = traj.euler_angles.T
    values: dict[str, np.ndarray] = {"phi": phi, "theta": theta, "psi": psi, "u": np.cos(theta), "R": traj.R,
                                     "omega": traj.omega, "apex": traj.R[:, 2, :]}
    need = _heavy_needs(scene.quantities)
    if any(k in need for k in ("theta_dot", "phi_dot", "psi_dot")):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            rates = euler_rates(theta, psi, *traj.omega.T)  # singular where sin θ = 0: inf/nan reported there
        values.update(phi_dot=rates[:, 0], theta_dot=rates[:, 1], psi_dot=rates[:, 2])
    # E, p_φ, p_ψ from ω and R (the integrator's own invariants), not through the Euler rates,
    # which are singular at θ = 0.
    inv = np.asarray(traj.invariants, dtype=float)
    cols = _heavy_columns(tuple(q for q in scene.quantities if q not in ("energy", "p_phi", "p_psi")), values,
                          _heavy_parameters(scene))
    for k, name in enumerate(("energy", "p_phi", "p_psi")):
        if name in scene.quantities:
            cols[name] = inv[:, k]
    cols = {q: cols[q] for q in scene.quantities}
    est = estimate(traj)
    info = {"error_estimate": est,
            "error_estimate_kind": traj.error_estimate_kind,
            "integrator": f"DOP853 ({'compiled C' if traj.backend == 'c' else 'SciPy solve_ivp'})",
            "integrator_attempts": attempts,
            "rhs_evaluations": int(traj.n_evaluations),
            "integrator_drift": {"energy": float(np.max(traj.energy_drift)),
                                 "p_phi": float(np.max(traj.p_phi_drift)),
                                 "p_psi": float(np.max(traj.p_psi_drift))}}
    return cols, info, traj


def _heavy_drift(scene: Scene, cols: dict, solution: Any, t: np.ndarray) -> dict[str, Drift]:
    p = _heavy_parameters(scene)
    if hasattr(solution, "_evaluate") and not any(q in cols for q in ("phi", "psi", "phi_dot", "psi_dot", "energy",
                                                                      "p_phi", "p_psi", "omega1", "omega2",
                                                                      "omega3", "apex_x", "apex_y", "R11")):
        # Only u or θ asked for: check the energy through u̇² = f(u) (3.73), which needs nothing
        # beyond u itself; p_φ and p_ψ enter the closed form as the constants b and a, exactly.
        # Its scale: the size of f's terms at |u| ≤ 1.
        v, _ = solution._evaluate(t, ["u", "u_dot"])
        c3, c2, c1, c0 = solution.f_coefficients
        f = ((c3 * v["u"] + c2) * v["u"] + c1) * v["u"] + c0
        return {"energy (u̇² - f(u))": drift(v["u_dot"] ** 2 - f, abs(c0) + abs(c1) + abs(c2) + abs(c3),
                                             "|c0| + |c1| + |c2| + |c3| of f(u)", reference=0.0)}
    if hasattr(solution, "_evaluate"):
        v, _ = solution._evaluate(t, ["theta", "theta_dot", "phi_dot", "psi_dot"])
        E, pf, ps = _heavy_invariants()(*(p[k] for k in heavy_top_parameters.PARAM_KEYS), v["theta"],
                                        v["theta_dot"], v["phi_dot"], v["psi_dot"])
        return _heavy_drifts(p, E, pf, ps, np.cos(v["theta"]))
    # the integrator's own invariants, from ω and R (no Euler rates, singular at θ = 0)
    inv = np.asarray(solution.invariants, dtype=float)
    return _heavy_drifts(p, inv[:, 0], inv[:, 1], inv[:, 2], solution.R[:, 2, 2])


# --- free top ----------------------------------------------------------------------------------

def _free_setup(scene: Scene) -> tuple[tuple, np.ndarray, np.ndarray]:
    from ..kinematics.rotations import rotation_matrix

    p, s = scene.parameters, scene.initial
    moments = (p["I1"], p["I2"], p["I3"])
    R0 = rotation_matrix(s.get("phi", 0.0), s.get("theta", 0.0), s.get("psi", 0.0))
    return moments, np.asarray(s["omega"], dtype=float), R0


def _free_columns(names: tuple[str, ...], omega: Callable[[], np.ndarray], rotation: Callable[[], np.ndarray],
                  angles: Callable[[], np.ndarray], quaternion: Callable[[], np.ndarray],
                  moments: tuple) -> dict[str, np.ndarray]:
    cache: dict[str, np.ndarray] = {}

    def get(key: str, make: Callable[[], np.ndarray]) -> np.ndarray:
        if key not in cache:
            cache[key] = make()
        return cache[key]

    out: dict[str, np.ndarray] = {}
    I = np.array(moments)
    for q in names:
        if q.startswith("omega"):
            out[q] = get("omega", omega)[:, int(q[-1]) - 1]
        elif q in ("L1", "L2", "L3"):
            out[q] = get("omega", omega)[:, int(q[-1]) - 1] * I[int(q[-1]) - 1]
        elif q in ("energy", "L_norm"):
            w = get("omega", omega)
            E, L2 = _free_invariants()(*moments, *w.T)
            out[q] = np.asarray(E, float) if q == "energy" else np.sqrt(np.asarray(L2, float))
        elif q in _R_NAMES:
            out[q] = get("R", rotation)[:, int(q[1]) - 1, int(q[2]) - 1]
        elif q in ("phi", "theta", "psi"):
            out[q] = get("angles", angles)[:, ("phi", "theta", "psi").index(q)]
        elif q in ("q0", "q1", "q2", "q3"):
            out[q] = get("q", quaternion)[:, int(q[1])]
        else:
            raise InvalidInputError(f"unknown free_top quantity {q!r}")
    return out


def _free_needs(names: tuple[str, ...]) -> list[str]:
    """The solution's methods the quantities come from: omega, rotation, euler_angles, quaternion."""
    need: list[str] = []
    for q in names:
        key = ("omega" if q.startswith("omega") or q in ("L1", "L2", "L3", "energy", "L_norm") else
               "rotation" if q in _R_NAMES else "euler_angles" if q in ("phi", "theta", "psi") else "quaternion")
        if key not in need:
            need.append(key)
    return need


def _free_exact(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..systems.free_top.exact import MAX_TRACKING_POINTS, TRACKING_STEP, exact_free_top

    scaled = _units(scene)

    moments, w0, R0 = _free_setup(scene)
    try:
        sol = exact_free_top(moments, w0, R0=R0, strict=scene.strict)
    except InvalidInputError as exc:
        raise _OutOfReach(f"scene keys [parameters], [initial].omega: {exc}") from exc
    if t[-1] > sol.t_max:
        raise InvalidInputError(
            f"scene key [time].t_end: expected at most {scaled.seconds(sol.t_max):.6g} s for this motion in closed "
            f"form (2^50 quarter periods or turns: beyond, the count is no longer an exact integer in double "
            f"precision), got {scaled.original.t_end!r}")
    need = _free_needs(scene.quantities)
    if "euler_angles" in need:
        # the continuous Euler angles are tracked on a grid of TRACKING_STEP rad of the fastest turn
        fastest = float(np.sqrt(2.0 * sol.energy / min(moments)))
        points = t[-1] * fastest / TRACKING_STEP + len(t)
        if points > MAX_TRACKING_POINTS:
            limit = (MAX_TRACKING_POINTS - len(t)) * TRACKING_STEP / fastest
            raise InvalidInputError(
                f"scene key [time].t_end: expected at most {scaled.seconds(max(limit, 0.0)):.6g} s for continuous "
                f"Euler angles (phi, theta, psi) of this motion ({MAX_TRACKING_POINTS} tracking points of "
                f"{TRACKING_STEP} rad), got {scaled.original.t_end!r}; R or the quaternion need no tracking")
    cols = _free_columns(scene.quantities, lambda: sol.omega(t), lambda: sol.rotation(t),
                         lambda: sol.euler_angles(t), lambda: sol.quaternion(t), moments)
    # measured on this run, at the very values output (FreeTopSolution.error_estimate): ω relative to
    # |ω|, R and q in their entries, the Euler angles in rad — none of them depends on the units
    estimate = float(sol.error_estimate(t, sorted({_FREE_EXACT_ESTIMATES[k] for k in need})))
    info = {"error_estimate": estimate, "kind": sol.kind, "polhode_period": scaled.seconds(sol.polhode_period),
            "m": sol.m}
    return cols, info, sol


#: The closed form's estimate (FreeTopSolution.error_estimate) that covers each output family.
_FREE_EXACT_ESTIMATES = {"omega": "omega", "rotation": "R", "quaternion": "R", "euler_angles": "euler_angles"}
#: The integrated free top's estimate that covers each output family of :func:`_free_needs`.
_FREE_ESTIMATES = {"omega": "omega_error_estimate", "rotation": "rotation_error_estimate",
                   "quaternion": "rotation_error_estimate", "euler_angles": "euler_angle_error_estimate"}


def _free_integrated_estimate(traj: Any, need: list[str], rate_unit: float = 1.0) -> float | None:
    """The largest of the run's measured estimates over the families the scene outputs (ω's in the scene's rad/s).

    A scene of ω columns alone is not charged with the Euler angles' 2π per unresolved pole
    passage; one that outputs angles is.
    """
    values = [getattr(traj, _FREE_ESTIMATES[k]) for k in need]
    if any(v is None for v in values):
        return None
    return float(max(np.max(v) * (rate_unit if k == "omega" else 1.0) for k, v in zip(need, values)))


def _free_rate_bound(moments: tuple, w0: np.ndarray) -> float:
    """The fastest rate of a free top's motion (rad/s): |ω| ≤ √(2T / I_min) times the largest coupling of
    Euler's equations (3.33), |I_b - I_c| / I_a (at least 1), the rate at which ω's direction changes.

    Square roots and quotients are taken in an order that cannot overflow for any positive moments.
    """
    I = [float(x) for x in moments]
    two_T = math.fsum((math.sqrt(i) * abs(w)) ** 2 for i, w in zip(I, w0))  # Σ I ω², by √I|ω| to stay finite
    spin = math.sqrt(two_T) / math.sqrt(min(I))
    coupling = max(1.0, *(abs(I[(a + 1) % 3] - I[(a + 2) % 3]) / I[a] for a in range(3)))
    return spin * coupling


def _free_integrate(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..systems.free_top.integrate import integrate_free_top

    scaled = _units(scene)

    moments, w0, R0 = _free_setup(scene)
    _check_integration_length(scene, _free_rate_bound(moments, w0), scaled)
    need = _free_needs(scene.quantities)
    rate_unit = 2.0**scaled.rate
    traj, attempts = _integrate_to_rtol(
        lambda tol: integrate_free_top(moments, w0, t, R0=R0, method="DOP853", rtol=tol, atol=tol * 1e-3,
                                       strict=scene.strict),
        lambda tr: _free_integrated_estimate(tr, need, rate_unit), scene.rtol)
    # The Euler angles are counted along the integrator's own steps (never unwrapped from the
    # samples, which aliases at coarse sampling).
    cols = _free_columns(scene.quantities, lambda: traj.omega, lambda: traj.R, lambda: traj.euler_angles,
                         lambda: traj.quaternion, moments)
    info = {"error_estimate": _free_integrated_estimate(traj, need, rate_unit),
            "integrator": f"DOP853 ({'compiled C' if traj.backend == 'c' else 'SciPy solve_ivp'})",
            "integrator_attempts": attempts,
            "rhs_evaluations": int(traj.n_evaluations)}
    return cols, info, traj


def _free_drift(scene: Scene, cols: dict, solution: Any, t: np.ndarray) -> dict[str, Drift]:
    """E = T against T and |L| against |L| (both ≥ 0, zero only at rest), closed form or integrated ω."""
    moments, _, _ = _free_setup(scene)
    w = solution.omega(t) if callable(getattr(solution, "omega", None)) else solution.omega
    E, L2 = _free_invariants()(*moments, *np.asarray(w).T)
    E, L = np.asarray(E, float), np.sqrt(np.asarray(L2, float))
    with np.errstate(invalid="ignore"):
        return {"energy": drift(E, float(np.nanmax(E)), "max_t T"),
                "L_norm": drift(L, float(np.nanmax(L)), "max_t |L|")}


# --- falling cat -------------------------------------------------------------------------------

def _cat_integrate(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..systems.deformable.cat import cat_columns, falling_cat

    scaled = _units(scene)

    try:
        cat = falling_cat(scene.parameters or None, duration=scene.t_end, samples=scene.samples, rtol=scene.rtol)
    except InvalidInputError as exc:
        raise _name_keys(exc, "parameters", tuple(FALLING_CAT_KEYS)) from exc
    data = cat_columns(cat)
    cols = {q: np.asarray(data[q]) for q in scene.quantities}
    L = np.stack([data["L1"], data["L2"], data["L3"]], axis=-1)
    info = {"error_estimate": float(cat.error_estimate),
            "error_estimate_kind": "distance of R to a rerun at a 10× tighter tolerance (rad)",
            "integrator": {"c": "DOP853 (compiled C)", "magnus": "Magnus (order 4, adaptive)"}.get(cat.backend,
                                                                                                 cat.backend),
            "peak_bend": cat.peak_bend,
            "max_abs_L": float(np.ldexp(np.max(np.abs(L)), scaled.columns.get("L1", 0)))}
    return cols, info, cat


def _cat_drift(scene: Scene, cols: dict, solution: Any, t: np.ndarray) -> dict[str, Drift]:
    """L (zero: the cat is dropped at rest) against the angular momentum its turn carries, max_t |Ĩ Ω|.

    The shape change x(t) turns the body at Ω = Ω_A ẋ^A (3.92) with angular momentum Ĩ Ω; the
    shape motion carries -Ĩ Ω, so that L = 0 — a cancellation of terms of this size.
    """
    from ..systems.deformable.cat import cat_connection, cat_loop

    conn = cat_connection(solution.parameters)
    loop = cat_loop(solution.peak_bend, scene.t_end)
    x = loop.shape(solution.t)
    turn = np.einsum("...ab,...b->...a", conn.inertia(x), conn.angular_velocity(x, loop.velocity(solution.t)))
    scale = float(np.max(np.linalg.norm(turn, axis=-1)))
    return {"L": drift(solution.angular_momentum, scale, "max_t |Ĩ Ω|", reference=np.zeros(3))}


_SYSTEMS: dict[str, dict[str, Callable]] = {
    "heavy_top": {"exact": _heavy_exact, "integrate": _heavy_integrate, "drift": _heavy_drift},
    "free_top": {"exact": _free_exact, "integrate": _free_integrate, "drift": _free_drift},
    "falling_cat": {"integrate": _cat_integrate, "drift": _cat_drift},
}


def _registered(model: Any) -> dict[str, Callable]:
    """The planner's table for a system of the registry (:class:`~mechderive.systems.base.System`)."""
    def solver(method: str) -> Callable:
        def solve(scene: Scene, t: np.ndarray) -> tuple:
            try:
                return tuple(model.solve(scene, method, t))
            except SystemOutOfReach as exc:
                raise _OutOfReach(str(exc)) from exc
        return solve

    table: dict[str, Callable] = {m: solver(m) for m in model.methods}
    table["drift"] = lambda scene, cols, solution, t: model.drift(scene, Solved(cols, {}, solution), t)
    return table


def _system_table(scene: Scene) -> dict[str, Callable]:
    return _SYSTEMS[scene.system] if scene.system in _SYSTEMS else _registered(scene.model)


def choose_method(scene: Scene) -> tuple[str, str | None]:
    """(method, note): the solver a scene will use and, if the request cannot be met before the run, why."""
    system = _system_table(scene)
    if scene.method == "exact" and "exact" not in system:
        raise InvalidInputError(f"scene method 'exact': system {scene.system!r} has no closed form; "
                                "expected method 'auto' or 'integrate'")
    method = scene.method
    if method == "auto":
        method = "exact" if "exact" in system else "integrate"
    return method, None


#: The falling cat's [parameters] names (its messages name them bare).
FALLING_CAT_KEYS = FALLING_CAT_PARAMETERS
#: The keys a message of each system's solvers may name, per table.
_SCENE_KEYS = {
    "heavy_top": (("parameters", ("I1", "I3", "M", "g", "l", "Mgl")),
                  ("initial", ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot"))),
    "free_top": (("parameters", ("I1", "I2", "I3")), ("initial", ("omega", "phi", "theta", "psi"))),
    "falling_cat": (("parameters", FALLING_CAT_KEYS),),
}


def _mentioned(message: str, names: tuple[str, ...]) -> list[str]:
    claim = message.split(";")[0]
    return [k for k in names if re.search(rf"(?<![A-Za-z0-9_]){re.escape(k)}(?![A-Za-z0-9_])", claim)]


def _name_keys(exc: MechDeriveError, table: str, names: tuple[str, ...]) -> MechDeriveError:
    """``exc`` re-worded to start with the scene keys of ``table`` that it is about (the table if none)."""
    message = str(exc)
    if message.startswith("scene "):
        return exc
    found = _mentioned(message, names)
    where = keys_text(table, found) if found else f"scene table [{table}]"
    return type(exc)(f"{where}: {message}")


def _scene_error(scene: Scene, exc: MechDeriveError) -> MechDeriveError:
    """A solver's refusal as a scene's: naming the keys its message mentions, else the tables it is about.

    The planner checks what it can before solving and names the keys itself; this is for what
    only a solver can find (it says what and why; the scene's keys are named in front).
    """
    message = str(exc)
    if message.startswith("scene "):
        return exc
    tables = _SCENE_KEYS.get(scene.system) or (
        ("parameters", tuple(k.name for k in scene.model.parameters)),
        ("initial", tuple(k.name for k in scene.model.initial)))
    keys = [f"[{table}].{k}" for table, names in tables for k in _mentioned(message, names)]
    where = ("scene keys " + ", ".join(keys) if len(keys) > 1 else f"scene key {keys[0]}" if keys else
             "scene tables " + ", ".join(f"[{table}]" for table, _ in tables))
    return type(exc)(f"{where}: {message}")


#: The units of the scene being solved (:mod:`.units`), for the system functions (which take (scene, t)).
_UNITS: contextvars.ContextVar[Scaled | None] = contextvars.ContextVar("mechderive_scene_units", default=None)


def _units(scene: Scene) -> Scaled:
    """The units ``scene`` is being solved in: those :func:`run_scene` chose, or the scene's own."""
    scaled = _UNITS.get()
    return scaled if scaled is not None and scaled.scene is scene else Scaled(scene, scene)


def _with_units(scaled: Scaled, solve: Callable, scene: Scene, t: np.ndarray) -> tuple:
    token = _UNITS.set(scaled)
    try:
        return solve(scene, t)
    finally:
        _UNITS.reset(token)


def _solve(scene: Scene, method: str, scaled: Scaled, t: np.ndarray) -> tuple[str, str | None, tuple]:
    """(method used, note, (columns, info, solution)) in the solver's units; ``auto`` integrates where the
    closed form cannot follow the motion, and says so."""
    system = _system_table(scene)
    work = scaled.scene
    try:
        return method, None, _with_units(scaled, system[method], work, t)
    except _OutOfReach as exc:
        if scene.method != "auto":
            raise InvalidInputError(str(exc)) from exc
        try:
            result = _with_units(scaled, system["integrate"], work, t)
        except MechDeriveError as second:
            raise type(second)(f"{_scene_error(work, second)} (and the closed form cannot follow this motion "
                               f"either: {exc.__cause__})") from second
        return "integrate", f"integrated: the closed form cannot follow this motion ({exc.__cause__})", result


def run_scene(scene: Scene) -> RunResult:
    """Solve ``scene``: derive, compile and evaluate only what its quantities need.

    A scene whose numbers are far from order one is solved in the units of its own motion and
    converted back exactly (:mod:`.units`); what cannot be computed in double precision is refused
    with the scene keys it depends on and the range allowed.  With ``method = "auto"`` a motion the
    closed form cannot follow (within ~1e-75 rad of the pole, ~1e-150 of the separatrix) is
    integrated instead, and the report's note says so.
    """
    start = time.perf_counter()
    derived0, compiled0, seconds0 = len(derivation_log()), len(codecache.compile_log()), derivation_seconds()
    built0 = len(cbuild.build_log())
    t = np.linspace(0.0, scene.t_end, scene.samples)
    check_samples(scene, t)
    method, note = choose_method(scene)
    system = _system_table(scene)
    if scene.system == "falling_cat":
        # the cat's parameters are open in the schema: checked here, in the scene's own units (the
        # bounds in the messages are then the scene's), before they are scaled
        from ..systems.deformable.cat import check_cat_parameters

        try:
            check_cat_parameters(scene.parameters or None)
        except InvalidInputError as exc:
            raise _name_keys(exc, "parameters", FALLING_CAT_KEYS) from exc
    scaled = scale_scene(scene)
    work = scaled.scene
    t_work = t if scaled.identity else np.linspace(0.0, work.t_end, work.samples)
    check_invariants(scaled)

    def compiled_since() -> list[tuple[str, str, float]]:
        # generated Python (lambdify) and generated C (the compiled steppers), each from memory, disk or new
        return codecache.compile_log()[compiled0:] + [(f"{name} (C)", "compiled" if how == "built" else how, s)
                                                      for name, how, s in cbuild.build_log()[built0:]]

    try:
        method, fallback, (cols, info, solution) = _solve(scene, method, scaled, t_work)
    except MechDeriveError as exc:
        raise _scene_error(scene, exc) from exc
    if fallback:
        note = fallback
    solve_end = time.perf_counter()
    # what the solve stage itself derived and compiled (the drift check may derive more afterwards)
    solve_derive_s = derivation_seconds() - seconds0
    solve_compile_s = sum(s for _, _, s in compiled_since())
    drifts = system["drift"](work, cols, solution, t_work)
    cols = in_scene_units(scaled, cols)
    if info.get("error_estimate") is not None:
        for q in scaled.offsets:
            if q in cols:
                # the turns added back: the rounding of φ0 itself and of each output, a few ulp of the larger
                with np.errstate(over="ignore"):  # spacing of the largest double is inf: so is the estimate
                    info["error_estimate"] = max(info["error_estimate"], 4 * float(np.spacing(max(
                        float(np.max(np.abs(cols[q]))), abs(scaled.original.initial[q])))))
    derived = derivation_log()[derived0:]
    compiled = compiled_since()
    derive_s = derivation_seconds() - seconds0
    compile_s = sum(s for _, how, s in compiled)
    total = time.perf_counter() - start
    estimate = info.get("error_estimate")
    rtol_met, rtol_reason = None, None
    if estimate is None:
        rtol_reason = "no error estimate: rtol not verified"
        note = (note + "; " if note else "") + rtol_reason
    else:
        # The estimates are absolute (angles in rad, R entries): compared with rtol as is,
        # since a relative error of a growing angle would mean nothing.
        rtol_met = bool(estimate <= scene.rtol)
        if not rtol_met:
            if info.get("error_estimate_kind") == "near-pole conditioning of φ, ψ":
                why = (f"error estimate {estimate:.2g} (near-pole conditioning of φ, ψ) exceeds the requested rtol "
                       f"{scene.rtol:g}: not met; R, the apex and ω are well conditioned (ask for those), or method "
                       "'integrate' estimates its own error at the samples")
            else:
                why = f"error estimate {estimate:.2g} exceeds the requested rtol {scene.rtol:g}: not met"
            note = (note + "; " if note else "") + why
    for k, v in list(cols.items()):
        if not np.all(np.isfinite(v)):
            bad = int(np.sum(~np.isfinite(v)))
            note = (note + "; " if note else "") + f"{k}: {bad} sample(s) not defined (e.g. φ̇, ψ̇ at θ = 0)"
    let_through = waived(scene)
    if let_through:
        note = (note + "; " if note else "") + ("strict = false: waived " + "; ".join(let_through)
                                                + " (no rigid body has these moments)")
    report = {
        "system": scene.system,
        "method": method,
        "derived": [name for name, _ in derived],
        "compiled": [f"{name} ({how})" for name, how, _ in compiled],
        "timings": {"derive": round(derive_s, 6), "compile": round(compile_s, 6),
                    "solve": round(max(solve_end - start - solve_derive_s - solve_compile_s, 0.0), 6),
                    "drift_check": round(max(total - (solve_end - start) - (derive_s - solve_derive_s)
                                             - (compile_s - solve_compile_s), 0.0), 6)},
        "error_estimate": info.pop("error_estimate", None),
        "drift": {k: d.value for k, d in drifts.items()},
        "drift_relative_to": {k: d.relative_to for k, d in drifts.items()},
        "rtol": scene.rtol,
        "rtol_met": rtol_met,
        "note": note,
        "waived": let_through,
        "details": info,
    }
    if not scaled.identity:
        report["units"] = _units_note(scaled)
    if rtol_reason is not None:
        report["rtol_met_reason"] = rtol_reason
    return RunResult(scene=scene, t=t, columns=cols, report=report, solution=solution)


def _units_note(scaled: Scaled) -> str:
    """What the report's ``units`` says: the scene was solved in units of its own motion (powers of two)."""
    if scaled.original.system == "falling_cat":
        return (f"solved with masses, lengths and time in units of the scene's own (exact powers of two; "
                f"t = t'·2^{-scaled.time}); outputs converted back")
    return (f"solved in units where the moments and the fastest rate are of order one (exact powers of two: "
            f"rates ×2^{-scaled.rate}, t ×2^{scaled.time}); outputs converted back")
