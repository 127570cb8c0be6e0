"""Work–precision of the user path for one's own body: an asymmetric heavy top as a ``rigid_body`` scene.

Case: principal moments I = (2, 3, 4) kg m² about the pivot, M = 1 kg, g = 9.81 m/s², centre of mass
c = (0.1, 0, 0.5) m in body components (a real body: the moments about the centre of mass obey the
triangle inequalities); let go at θ0 = 0.3, φ0 = ψ0 = 0 with ω(0) = (0, 0, 20) rad/s (body);
t_end = 20 s, 2001 samples (the issue's example scene; quick: 5 s, 501).  No closed form exists (I1 ≠ I2, c off the axis).

Rows:

* ``rigid_body scene`` — the whole user path, warm: :func:`~mechderive.scenes.schema.parse_scene` of
  the scene and :func:`~mechderive.scenes.planner.run_scene` (compiled (ω, q) equations from the disk
  cache, DOP853 in C, the error-estimate rerun and tolerance control, the drift check), at the
  scene's rtol;
* ``rigid_body integrate`` — the derived term alone through :func:`mechderive.solvers.driver.integrate`
  (no estimate), for the cost of the estimate above;
* ``baseline`` — the same body written by hand with ``sympy.physics.mechanics`` (``ReferenceFrame``
  body-fixed 'ZXZ' = the chapter's (3.54), ``RigidBody`` with the inertia about the pivot, the
  weight's potential, ``LagrangesMethod``) → ``lambdify(cse=True)`` of the full mass matrix and
  forcing → ``solve_ivp(DOP853)`` with ``np.linalg.solve`` per evaluation, atol = rtol/100, warm; its
  cold cost (import, derive, lambdify) is added in the ``baseline (cold)`` rows.

Error: max over the samples of max(|ω - ω_ref| / max|ω_ref|, |γ - γ_ref|) with γ = (R13, R23, R33)
the body components of the vertical; the reference is the derived term at rtol 2.3e-14 (SciPy's
floor), whose own error estimate (distance to a rerun) is reported.
"""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np

from ._common import median_time, nearest_error_speedups, row

__all__ = ["rigid_body_work_precision", "equal_error_speedups", "report_lines", "BODY", "INITIAL"]

BODY = dict(I1=2.0, I2=3.0, I3=4.0, M=1.0, g=9.81, center_of_mass=(0.1, 0.0, 0.5))
INITIAL = dict(phi=0.0, theta=0.3, psi=0.0, omega=(0.0, 0.0, 20.0))


def _scene(rtol: float, t_end: float, samples: int) -> dict:
    return {"system": "rigid_body", "method": "auto", "rtol": rtol,
            "parameters": {**BODY, "center_of_mass": list(BODY["center_of_mass"])},
            "initial": {**INITIAL, "omega": list(INITIAL["omega"])},
            "time": {"t_end": t_end, "samples": samples},
            "output": {"quantities": ["omega1", "omega2", "omega3", "R13", "R23", "R33"]}}


def _user_path() -> tuple[Any, dict]:
    """The asymmetric heavy top written by hand with sympy.physics.mechanics; (f(t, y), stage seconds)."""
    loaded = "sympy.physics.mechanics" in sys.modules
    t0 = time.perf_counter()
    import sympy as sp
    from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)
    t1 = time.perf_counter()
    phi, theta, psi = dynamicsymbols("phi theta psi")
    I1, I2, I3, M, g, c1, c2, c3 = sp.symbols("I1 I2 I3 M g c1 c2 c3", real=True)
    N, B = ReferenceFrame("N"), ReferenceFrame("B")
    B.orient_body_fixed(N, (phi, theta, psi), "ZXZ")
    P = Point("P")
    P.set_vel(N, 0)
    G = P.locatenew("G", c1 * B.x + c2 * B.y + c3 * B.z)
    G.v2pt_theory(P, N, B)
    body = RigidBody("body", G, B, M, (inertia(B, I1, I2, I3), P))  # inertia about the pivot
    body.potential_energy = M * g * G.pos_from(P).dot(N.z)
    LM = LagrangesMethod(Lagrangian(N, body), [phi, theta, psi])
    LM.form_lagranges_equations()
    mass, forcing = LM.mass_matrix_full, LM.forcing_full
    t2 = time.perf_counter()
    qs = [phi, theta, psi]
    args = [*qs, *(q.diff() for q in qs), I1, I2, I3, M, g, c1, c2, c3]
    f_mass = sp.lambdify(args, mass, cse=True)
    f_force = sp.lambdify(args, forcing, cse=True)
    t3 = time.perf_counter()
    p = (BODY["I1"], BODY["I2"], BODY["I3"], BODY["M"], BODY["g"], *BODY["center_of_mass"])

    def fun(_t: float, y: np.ndarray) -> np.ndarray:
        return np.linalg.solve(np.asarray(f_mass(*y, *p), dtype=float), np.asarray(f_force(*y, *p), dtype=float)[:, 0])

    return fun, dict(import_s=t1 - t0, import_already_loaded=loaded, derive_s=t2 - t1, lambdify_s=t3 - t2)


def _initial_euler_rates() -> list[float]:
    from ..kinematics.rotations import euler_rates

    return [float(x) for x in euler_rates(INITIAL["theta"], INITIAL["psi"], *INITIAL["omega"])]


def _error(w: np.ndarray, gamma: np.ndarray, ref: tuple[np.ndarray, np.ndarray]) -> float:
    w_ref, g_ref = ref
    return float(max(np.max(np.abs(w - w_ref)) / np.max(np.abs(w_ref)), np.max(np.abs(gamma - g_ref))))


def rigid_body_work_precision(*, quick: bool = False, repeat: int = 3) -> dict:
    """The table (rows as dicts), the reference's own estimate and the baseline's cold cost."""
    from scipy.integrate import solve_ivp

    from ..kinematics.rotations import angular_velocity_body
    from ..scenes.planner import run_scene
    from ..scenes.schema import parse_scene
    from ..solvers.driver import integrate
    from ..systems import registry
    from ..systems.rigid_body.motion import _term

    user_fun, user_cold = _user_path()  # first, so its import of SymPy is what is measured
    t_end, samples = (5.0, 501) if quick else (20.0, 2001)
    t = np.linspace(0.0, t_end, samples)

    scene0 = parse_scene(_scene(1e-10, t_end, samples))
    system = registry.get("rigid_body")
    body = system.body(scene0.parameters)
    term, _ = _term(None)
    from ..kinematics.conversions import euler_to_quaternion, quaternion_to_matrix

    y0 = [*INITIAL["omega"], *euler_to_quaternion(INITIAL["phi"], INITIAL["theta"], INITIAL["psi"])]
    ref_run = integrate(term, y0, t, body.values, rtol=2.3e-14, atol=2.3e-17)
    ref = (ref_run.y[:, :3], quaternion_to_matrix(ref_run.y[:, 3:7] / np.linalg.norm(ref_run.y[:, 3:7], axis=-1,
                                                                                        keepdims=True))[:, :, 2])
    rows = []
    run_scene(scene0)  # warm-up: compiled code from the disk cache (or built once)
    for rt in ((1e-6, 1e-10) if quick else (1e-6, 1e-8, 1e-10, 1e-12)):
        def scene_run(rt=rt):
            return run_scene(parse_scene(_scene(rt, t_end, samples)))
        r, s, n = median_time(scene_run, repeat=repeat)
        c = r.columns
        w = np.stack([c["omega1"], c["omega2"], c["omega3"]], axis=-1)
        gamma = np.stack([c["R13"], c["R23"], c["R33"]], axis=-1)
        rows.append(row("rigid_body scene", f"rtol {rt:.0e}", s, _error(w, gamma, ref),
                        evals=int(r.report["details"]["rhs_evaluations"]), runs=n,
                        estimate=r.report["error_estimate"]))
    for rt in ((1e-8,) if quick else (1e-8, 1e-10, 1e-12)):
        def bare(rt=rt):
            return integrate(term, y0, t, body.values, rtol=rt, atol=rt * 1e-3, estimate_error=False)
        tr, s, n = median_time(bare, repeat=repeat)
        q = tr.y[:, 3:7] / np.linalg.norm(tr.y[:, 3:7], axis=-1, keepdims=True)
        rows.append(row("rigid_body integrate", f"rtol {rt:.0e}", s,
                        _error(tr.y[:, :3], quaternion_to_matrix(q)[:, :, 2], ref), evals=tr.n_evaluations, runs=n))

    rates = _initial_euler_rates()
    y_user = [INITIAL["phi"], INITIAL["theta"], INITIAL["psi"], *rates]
    cold_s = user_cold["import_s"] + user_cold["derive_s"] + user_cold["lambdify_s"]
    for rt in ((1e-8,) if quick else (1e-6, 1e-8, 1e-10)):
        def user(rt=rt):
            return solve_ivp(user_fun, (t[0], t[-1]), y_user, method="DOP853", t_eval=t, rtol=rt, atol=rt / 100)
        sol, s, n = median_time(user, repeat=min(repeat, 2), budget=20.0)
        ph, th, ps, dph, dth, dps = sol.y
        w = angular_velocity_body(ph, th, ps, dph, dth, dps)
        gamma = np.stack([np.sin(th) * np.sin(ps), np.sin(th) * np.cos(ps), np.cos(th)], axis=-1)  # (3.57)
        err = _error(w, gamma, ref)
        rows.append(row("baseline", f"rtol {rt:.0e}", s, err, evals=int(sol.nfev), runs=n))
        rows.append(row("baseline (cold)", f"rtol {rt:.0e}", s + cold_s, err, evals=int(sol.nfev), runs=n))
    nearest_error_speedups(rows, "baseline")
    for r in rows:
        if r["family"] == "baseline (cold)":
            r["speedup"] = r["speedup_vs"] = None
    return dict(case=dict(body=BODY, initial=INITIAL, t_end=t_end, samples=samples),
                reference_estimate=ref_run.error_estimate, baseline_cold=user_cold, rows=rows)


def equal_error_speedups(result: dict) -> tuple[bool, list[str]]:
    """For every baseline row, the fastest ``rigid_body scene`` row with an error at most the baseline's:
    (all ≥ 50× faster, one line per baseline row)."""
    rows = result["rows"]
    ours = [r for r in rows if r["family"] == "rigid_body scene"]
    met, lines = True, []
    for b in sorted((r for r in rows if r["family"] == "baseline"), key=lambda r: -r["max_error"]):
        ok = [r for r in ours if r["max_error"] <= b["max_error"]]
        if not ok:
            met = False
            lines.append(f"baseline {b['setting']} ({b['max_error']:.1e}): no scene row reaches it")
            continue
        r = min(ok, key=lambda r: r["seconds"])
        ratio = b["seconds"] / r["seconds"]
        met = met and ratio >= 50
        lines.append(f"vs baseline {b['setting']} ({b['max_error']:.1e}, {b['seconds']:.3f} s): {ratio:.0f}× by the "
                     f"scene at {r['setting']} ({r['max_error']:.1e}, {r['seconds'] * 1e3:.1f} ms)")
    return met, lines


def report_lines(result: dict, table: Any) -> list[str]:
    """The section of :func:`mechderive.bench.format_report` (``table`` renders the rows)."""
    c, bc = result["case"], result["baseline_cold"]
    lines = [f"## 6. Your own body: an asymmetric heavy top as a rigid_body scene, I = (2, 3, 4), M = 1, "
             f"c = (0.1, 0, 0.5), θ0 = 0.3, ω(0) = (0, 0, 20); t_end = {c['t_end']:g} s, {c['samples']} samples",
             "Error: max(|ω - ω_ref| / max|ω_ref|, |γ - γ_ref|), γ = (R13, R23, R33); reference: the derived term at "
             f"rtol 2.3e-14 (its own estimate {result['reference_estimate']:.1e}).  'rigid_body scene' = parse + "
             "run_scene, warm, with the error-estimate rerun and the drift check.", ""]
    lines += table(result["rows"], "1", "speed-up vs baseline")
    lines += ["", f"baseline cold cost: import sympy.physics.mechanics {bc['import_s']:.2f} s + derive "
                  f"{bc['derive_s']:.2f} s + lambdify(cse) {bc['lambdify_s']:.2f} s.", ""]
    return lines
