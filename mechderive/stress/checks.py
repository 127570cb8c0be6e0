"""Shared checks of the stress cases: one method's outputs against a reference run, recorded in a Collector.

Tolerances (the one-line justifications the result rows quote):

* closed forms, R and apex 1e-12 absolute, ω 1e-12·|ω(0)|, θ 1e-12 rad: the closed forms are
  built to ~1e-13 (40-digit constants, double-double phase; their own tests at 1e-13), ×10 margin;
  the references are good to ~1e-25.
* angles that grow (φ, ψ): 1e-12 + 8 ulp(|angle|) after wrapping — a float angle of size A
  cannot be closer than its own rounding.
* integrators: error ≤ 1e-9 (DOP853 at rtol 1e-12 / splitting of order 6 with small steps, over a
  few periods: 1000× the requested local accuracy for global growth), *and* error ≤ 10× the
  integrator's own error estimate + 1e-13 — an estimate that is too optimistic is silent inaccuracy.
* conserved quantities: closed form 1e-12 (relative to T(0) + M g l, or to T(0) and |L(0)| for the
  free top; their rounding), integrators 1e-9.
* scene runs: error ≤ the scene's rtol when the run reports ``rtol_met``, and ≤ 10× its reported
  error estimate + 1e-13; ``rtol_met = False`` with a note is the toolkit saying so.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..errors import DerivationError
from .core import Collector
from .reference import RefRun

__all__ = ["TOP", "INITIAL_KEYS", "full_initial", "heavy_closed_form", "heavy_integrators", "heavy_scenes",
           "free_closed_form", "free_integrators", "CF_TOL", "INT_TOL"]

#: The chapter's example top (BASELINE.md): I1 = 1 about the pivot, I3 = 0.5, M g l = 1.
TOP = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
INITIAL_KEYS = ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")
CF_TOL = 1e-12
INT_TOL = 1e-9
_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))


def full_initial(initial: dict) -> dict:
    return {k: float(initial.get(k, 0.0)) for k in INITIAL_KEYS}


def _ulp_tol(values: np.ndarray, tol: float) -> float:
    return tol + 8 * float(np.spacing(np.max(np.abs(values)))) if np.size(values) else tol


# --- heavy top ---------------------------------------------------------------------------------

def heavy_invariants(params: dict, omega: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, ...]:
    """E = ½(I1(ω1² + ω2²) + I3 ω3²) + M g l R33, p_φ = L·ẽ3 = Σ_a I_a ω_a R_a3, p_ψ = I3 ω3 (hand-written)."""
    I = np.array([params["I1"], params["I1"], params["I3"]])
    mgl = params["M"] * params["g"] * params["l"]
    E = 0.5 * np.sum(I * omega**2, axis=-1) + mgl * R[..., 2, 2]
    p_phi = np.sum(I * omega * R[..., :, 2], axis=-1)
    return E, p_phi, I[2] * omega[..., 2]


def _heavy_drift(col: Collector, method: str, params: dict, omega: np.ndarray, R: np.ndarray, limit: float) -> None:
    E, pf, ps = heavy_invariants(params, omega, R)
    I = np.array([params["I1"], params["I1"], params["I3"]])
    mgl = params["M"] * params["g"] * params["l"]
    e_scale = 0.5 * float(np.sum(I * omega[0] ** 2)) + mgl
    l_scale = max(float(np.linalg.norm(I * omega[0])), float(np.sqrt(params["I1"] * mgl)))
    col.drift(method, "energy", float(np.max(np.abs(E - E[0]))) / e_scale, limit)
    col.drift(method, "p_phi", float(np.max(np.abs(pf - pf[0]))) / l_scale, limit)
    col.drift(method, "p_psi", float(np.max(np.abs(ps - ps[0]))) / l_scale, limit)


def heavy_closed_form(col: Collector, params: dict, initial: dict, t: np.ndarray, ref: RefRun, *,
                      angles: str = "euler", tol: float = CF_TOL) -> Any:
    """exact_heavy_top against the reference: θ, R, apex, ω, and φ, ψ (``angles``: 'euler' each,
    'sum' φ + ψ near θ = 0, 'difference' φ - ψ near θ = π, 'none')."""
    from ..systems.heavy_top.exact import exact_heavy_top

    m = "closed form"
    top = col.attempt(m, "exact_heavy_top", lambda: exact_heavy_top(params, initial))
    if top is None:
        return None
    col.details.update(kind=top.kind, motion_class=top.motion_class, m=top.m, m1=top.m1,
                       nutation_period=top.nutation_period, conditioning=top.conditioning)
    col.summary.append(f"conditioning {top.conditioning:.2g}")
    th = col.attempt(m, "theta", lambda: top.evaluate(t, ["theta"])["theta"])
    if th is not None:
        col.compare(m, "θ", th, ref.angles[:, 1], tol)
    out = col.attempt(m, "φ, ψ, R, apex, ω", lambda: top.evaluate(t, ["phi", "psi", "R", "apex", "omega"]))
    if out is None:
        return top
    col.compare(m, "R", out["R"], ref.R, tol)
    col.compare(m, "apex", out["apex"], ref.R[:, 2, :], tol)
    w_scale = float(np.linalg.norm(ref.omega[0])) or 1.0
    col.compare(m, "ω/|ω0|", out["omega"], ref.omega, tol, scale=w_scale)
    phi, psi = out["phi"], out["psi"]
    if angles == "euler":
        col.compare(m, "φ", phi, ref.angles[:, 0], _ulp_tol(phi, tol), angle=True)
        col.compare(m, "ψ", psi, ref.angles[:, 2], _ulp_tol(psi, tol), angle=True)
    elif angles == "sum":
        col.compare(m, "φ+ψ", phi + psi, ref.phi_plus_psi, _ulp_tol(phi + psi, tol), angle=True)
    elif angles == "difference":
        col.compare(m, "φ-ψ", phi - psi, ref.phi_minus_psi, _ulp_tol(phi - psi, tol), angle=True)
    if np.all(np.isfinite(out["omega"])) and np.all(np.isfinite(out["R"])):
        _heavy_drift(col, m, params, out["omega"], out["R"], tol)
    return top


def heavy_integrators(col: Collector, params: dict, initial: dict, t: np.ndarray, ref: RefRun, *,
                      methods: Sequence[str] = ("DOP853", "splitting"), rtol: float = 1e-12, step: float = 0.01,
                      order: int = 6, tol: float = INT_TOL) -> dict:
    """integrate_heavy_top by each method against the reference: R (and its own estimate), θ, drifts."""
    from ..systems.heavy_top.integrate import integrate_heavy_top

    runs = {}
    for method in methods:
        kw = dict(rtol=rtol) if method == "DOP853" else dict(step=step, order=order)
        label = method if method == "DOP853" else f"splitting-{order}"
        traj = col.attempt(label, "integrate", lambda: integrate_heavy_top(params, initial, t, method=method, **kw))
        if traj is None:
            continue
        runs[method] = traj
        ang = traj.euler_angles
        col._finite(label, "Euler angles", ang)
        col._finite(label, "ω", traj.omega)
        err = col.compare(label, "R", traj.R, ref.R, tol)
        col.honest_estimate(label, "R", err, traj.angle_error_estimate)
        col.compare(label, "θ", ang[:, 1], ref.angles[:, 1], tol)
        for name in ("energy", "p_phi", "p_psi"):
            col.drift(label, name, float(getattr(traj, f"{name}_drift")), tol)
    return runs


def heavy_scenes(col: Collector, params: dict, initial: dict, t: np.ndarray, ref: RefRun, *,
                 methods: Sequence[str] = ("auto", "integrate"), rtol: float = 1e-10) -> None:
    """run_scene (the planner behind ``mechderive run``) over ``t``: no NaN, R and apex honest."""
    from ..scenes.planner import run_scene
    from ..scenes.schema import Scene

    quantities = ("theta", "phi", "psi", "apex_x", "apex_y", "apex_z", "omega1", "omega2", "omega3",
                  "energy", "p_phi", "p_psi", *_R_NAMES)
    for method in methods:
        label = f"scene {method}"
        scene = Scene(system="heavy_top", method=method, rtol=rtol, parameters=dict(params),
                      initial=full_initial(initial), t_end=float(t[-1]), samples=len(t), quantities=quantities)
        if not np.array_equal(scene.times(), t):
            raise DerivationError("the scene's sample times differ from the reference's")
        res = col.attempt(label, "run_scene", lambda: run_scene(scene))
        if res is None:
            continue
        for q in quantities:
            col._finite(label, q, res.columns[q])
        R = np.stack([res.columns[n] for n in _R_NAMES], axis=-1).reshape(-1, 3, 3)
        if not np.all(np.isfinite(R)):
            continue
        err = float(np.max(np.abs(R - ref.R)))
        est = res.report.get("error_estimate")
        note = res.report.get("note") or ""
        if not res.report.get("rtol_met", True):
            col.said_so(label, "R", err, rtol, note)
            continue
        col.compare(label, "R (rtol_met)", R, ref.R, rtol, note=f"reported estimate {est}")
        col.honest_estimate(label, "R", err, est)


# --- free top ----------------------------------------------------------------------------------

def _free_drift(col: Collector, method: str, moments: Sequence[float], omega: np.ndarray, limit: float) -> None:
    I = np.asarray(moments, dtype=float)
    T = 0.5 * np.sum(I * omega**2, axis=-1)
    L = np.linalg.norm(I * omega, axis=-1)
    col.drift(method, "energy", float(np.max(np.abs(T - T[0])) / T[0]), limit)
    col.drift(method, "|L|", float(np.max(np.abs(L - L[0])) / L[0]), limit)


def free_closed_form(col: Collector, moments, omega0, R0, t: np.ndarray, ref: RefRun, *,
                     tol: float = CF_TOL) -> Any:
    """exact_free_top against the reference: ω (relative to |ω0|) and R."""
    from ..systems.free_top.exact import exact_free_top

    m = "closed form"
    sol = col.attempt(m, "exact_free_top", lambda: exact_free_top(moments, omega0, R0=R0))
    if sol is None:
        return None
    col.details.update(kind=sol.kind, m=sol.m, m1=sol.m1, polhode_period=sol.polhode_period)
    scale = float(np.linalg.norm(omega0))
    w = col.attempt(m, "omega", lambda: sol.omega(t))
    if w is not None:
        col.compare(m, "ω/|ω0|", w, ref.omega, tol, scale=scale)
        if np.all(np.isfinite(w)):
            _free_drift(col, m, moments, w, tol)
    R = col.attempt(m, "rotation", lambda: sol.rotation(t))
    if R is not None:
        col.compare(m, "R", R, ref.R, tol)
    return sol


def free_integrators(col: Collector, moments, omega0, R0, t: np.ndarray, ref: RefRun, *,
                     rtol: float = 1e-12, step: float = 0.01, order: int = 6, tol: float = INT_TOL) -> None:
    """integrate_free_top (DOP853 and the Lie–Poisson splitting) against the reference."""
    from ..systems.free_top.integrate import integrate_free_top

    scale = float(np.linalg.norm(omega0))
    for method in ("DOP853", "splitting"):
        kw = dict(rtol=rtol, atol=rtol * 1e-2) if method == "DOP853" else dict(step=step, order=order)
        label = method if method == "DOP853" else f"splitting-{order}"
        traj = col.attempt(label, "integrate", lambda: integrate_free_top(moments, omega0, t, R0=R0, method=method,
                                                                           **kw))
        if traj is None:
            continue
        err = col.compare(label, "ω/|ω0|", traj.omega, ref.omega, tol, scale=scale)
        col.honest_estimate(label, "ω/|ω0|", err, None if traj.error_estimate is None
                            else float(traj.error_estimate) / scale)
        col.compare(label, "R", traj.R, ref.R, tol)
        col.drift(label, "energy", float(traj.energy_drift), tol)
        col.drift(label, "|L|", float(traj.angular_momentum_drift), tol)
