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
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..core import cbuild, codecache
from ..core.drift import Drift, drift
from ..core.model import derivation_log, derivation_seconds
from ..errors import InvalidInputError
from ..systems.heavy_top import parameters as heavy_top_parameters
from .schema import Scene, waived

__all__ = ["RunResult", "run_scene"]

_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))


@dataclass
class RunResult:
    """The table a scene asked for (``t`` then the quantities, in order) and the run's report."""

    scene: Scene
    t: np.ndarray
    columns: dict[str, np.ndarray]
    report: dict[str, Any] = field(default_factory=dict)
    solution: Any = None  # the solved object, for plots


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


def _heavy_exact(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..systems.heavy_top.exact import exact_heavy_top

    top = exact_heavy_top(scene.parameters, scene.initial, strict=scene.strict)
    need = _heavy_needs(scene.quantities)
    values, ps = top._evaluate(t, need)
    cols = _heavy_columns(scene.quantities, values, _heavy_parameters(scene))

    # measured on this run, at the very values output, from what the quantities need only
    # (HeavyTopSolution.error_estimate: residuals of the derived equations, quadrature of the rates)
    estimate = float(top.error_estimate(t, need))
    info = {"error_estimate": estimate,
            "evaluated": ps.computed, "motion_class": top.motion_class,
            "nutation_period": top.nutation_period}
    angles = [k for k in need if k in _POLE_CONDITIONED]
    if angles and estimate > scene.rtol:
        # Near the pole (or the bottom) φ and ψ each are ill-conditioned — the motion itself defines
        # them poorly there, and the estimate counts it; R, the apex and ω, built from the
        # well-conditioned half sums and differences, may still meet rtol: say so if they do.
        rest = [k for k in need if k not in _POLE_CONDITIONED] or ["R"]
        if top.error_estimate(t, rest) <= scene.rtol:
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


def _heavy_integrate(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..kinematics.rotations import euler_rates
    from ..systems.heavy_top.integrate import integrate_heavy_top

    traj, attempts = _integrate_to_rtol(
        lambda tol: integrate_heavy_top(scene.parameters, scene.initial, t, method="DOP853", rtol=tol,
                                        atol=tol * 1e-3, strict=scene.strict),
        lambda tr: tr.angle_error_estimate, scene.rtol)
    phi, theta, psi = traj.euler_angles.T
    values: dict[str, np.ndarray] = {"phi": phi, "theta": theta, "psi": psi, "u": np.cos(theta), "R": traj.R,
                                     "omega": traj.omega, "apex": traj.R[:, 2, :]}
    need = _heavy_needs(scene.quantities)
    if any(k in need for k in ("theta_dot", "phi_dot", "psi_dot")):
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
    est = traj.angle_error_estimate
    info = {"error_estimate": None if est is None else float(est),
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
    from ..systems.free_top.exact import exact_free_top

    moments, w0, R0 = _free_setup(scene)
    sol = exact_free_top(moments, w0, R0=R0, strict=scene.strict)
    cols = _free_columns(scene.quantities, lambda: sol.omega(t), lambda: sol.rotation(t),
                         lambda: sol.euler_angles(t), lambda: sol.quaternion(t), moments)
    # measured on this run, at the very values output (FreeTopSolution.error_estimate): ω relative to
    # |ω|, R and q in their entries, the Euler angles in rad
    estimate = float(sol.error_estimate(t, sorted({_FREE_EXACT_ESTIMATES[k] for k in _free_needs(scene.quantities)})))
    info = {"error_estimate": estimate, "kind": sol.kind, "polhode_period": sol.polhode_period, "m": sol.m}
    return cols, info, sol


#: The closed form's estimate (FreeTopSolution.error_estimate) that covers each output family.
_FREE_EXACT_ESTIMATES = {"omega": "omega", "rotation": "R", "quaternion": "R", "euler_angles": "euler_angles"}
#: The integrated free top's estimate that covers each output family of :func:`_free_needs`.
_FREE_ESTIMATES = {"omega": "omega_error_estimate", "rotation": "rotation_error_estimate",
                   "quaternion": "rotation_error_estimate", "euler_angles": "euler_angle_error_estimate"}


def _free_integrated_estimate(traj: Any, need: list[str]) -> float | None:
    """The largest of the run's measured estimates over the families the scene outputs.

    A scene of ω columns alone is not charged with the Euler angles' 2π per unresolved pole
    passage; one that outputs angles is.
    """
    values = [getattr(traj, _FREE_ESTIMATES[k]) for k in need]
    if any(v is None for v in values):
        return None
    return float(max(np.max(v) for v in values))


def _free_integrate(scene: Scene, t: np.ndarray) -> tuple[dict, dict, Any]:
    from ..systems.free_top.integrate import integrate_free_top

    moments, w0, R0 = _free_setup(scene)
    need = _free_needs(scene.quantities)
    traj, attempts = _integrate_to_rtol(
        lambda tol: integrate_free_top(moments, w0, t, R0=R0, method="DOP853", rtol=tol, atol=tol * 1e-3,
                                       strict=scene.strict),
        lambda tr: _free_integrated_estimate(tr, need), scene.rtol)
    # The Euler angles are counted along the integrator's own steps (never unwrapped from the
    # samples, which aliases at coarse sampling).
    cols = _free_columns(scene.quantities, lambda: traj.omega, lambda: traj.R, lambda: traj.euler_angles,
                         lambda: traj.quaternion, moments)
    info = {"error_estimate": _free_integrated_estimate(traj, need),
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

    cat = falling_cat(scene.parameters or None, duration=scene.t_end, samples=scene.samples, rtol=scene.rtol)
    data = cat_columns(cat)
    cols = {q: np.asarray(data[q]) for q in scene.quantities}
    L = np.stack([data["L1"], data["L2"], data["L3"]], axis=-1)
    info = {"error_estimate": float(cat.error_estimate),
            "error_estimate_kind": "distance of R to a rerun at a 10× tighter tolerance (rad)",
            "integrator": {"c": "DOP853 (compiled C)", "magnus": "Magnus (order 4, adaptive)"}.get(cat.backend,
                                                                                                 cat.backend),
            "peak_bend": cat.peak_bend, "max_abs_L": float(np.max(np.abs(L)))}
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


def choose_method(scene: Scene) -> tuple[str, str | None]:
    """(method, note): the solver a scene will use and, if the request cannot be met before the run, why."""
    system = _SYSTEMS[scene.system]
    if scene.method == "exact" and "exact" not in system:
        raise InvalidInputError(f"scene method 'exact': system {scene.system!r} has no closed form; "
                                "expected method 'auto' or 'integrate'")
    method = scene.method
    if method == "auto":
        method = "exact" if "exact" in system else "integrate"
    return method, None


def run_scene(scene: Scene) -> RunResult:
    """Solve ``scene``: derive, compile and evaluate only what its quantities need."""
    start = time.perf_counter()
    derived0, compiled0, seconds0 = len(derivation_log()), len(codecache.compile_log()), derivation_seconds()
    built0 = len(cbuild.build_log())
    t = np.linspace(0.0, scene.t_end, scene.samples)
    method, note = choose_method(scene)
    system = _SYSTEMS[scene.system]
    def compiled_since() -> list[tuple[str, str, float]]:
        # generated Python (lambdify) and generated C (the compiled steppers), each from memory, disk or new
        return codecache.compile_log()[compiled0:] + [(f"{name} (C)", "compiled" if how == "built" else how, s)
                                                      for name, how, s in cbuild.build_log()[built0:]]

    cols, info, solution = system[method](scene, t)
    solve_end = time.perf_counter()
    # what the solve stage itself derived and compiled (the drift check may derive more afterwards)
    solve_derive_s = derivation_seconds() - seconds0
    solve_compile_s = sum(s for _, _, s in compiled_since())
    drifts = system["drift"](scene, cols, solution, t)
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
    if rtol_reason is not None:
        report["rtol_met_reason"] = rtol_reason
    return RunResult(scene=scene, t=t, columns=cols, report=report, solution=solution)
