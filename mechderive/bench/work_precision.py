"""Work–precision: wall time against max error, heavy top and free asymmetric top.

Heavy top (the BASELINE.md case): I1 = 1 about the pivot, I3 = 0.5, M g l = 1 (M = 0.1, g = 10,
l = 1: a body that passes the triangle-inequality check; only M g l enters the motion), let go at
θ0 = 0.5 with θ̇ = φ̇ = 0, ψ̇ = 5; 100 nutation periods (351.77 s), 2001 samples.  Error: max over
the samples of |(θ, φ, ψ) - closed form| (rad; φ, ψ unwrapped, ψ reaches ≈ 1750 rad so its rounding
floor is ~2e-13).  The closed form's own error is measured against 30-digit mpmath values (below).

Free top: I = (1, 2, 3), ω(0) = (1, 0.5, 1), 100 polhode periods (679.07 s), 2001 samples; error
max |ω - ω_closed form| (rad/s).

Rows: the closed form (setup at 40 digits + evaluation, warm process); ``integrate_*`` with
DOP853 on the derived (ω, q) right-hand side, compiled to C ("DOP853 (C)", the default backend) and
through SciPy's ``solve_ivp`` ("DOP853 (SciPy)"), and with the splitting (composed
exact sub-flows, fixed step h = Δt/n, Δt the sample spacing); for the heavy top, the BASELINE user
path: ``sympy.physics.mechanics`` (``ReferenceFrame`` body-fixed 'ZXZ', ``RigidBody`` with the
inertia about the pivot, ``LagrangesMethod``) → ``LM.rhs()`` → ``lambdify(cse=True)`` →
``solve_ivp(DOP853)`` on the Euler angles, atol = rtol/100.  "Warm" rows time the integration alone
(compiled code memoised, one warm-up call first); the user path's cold cost (import, derive,
lambdify, timed in this process) is added in its "cold" rows.  ``mechderive run``'s cold start is
timed in fresh processes by :mod:`mechderive.bench.startup`.
"""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np

from ._common import median_time, nearest_error_speedups, row

__all__ = ["heavy_top_work_precision", "free_top_work_precision", "HEAVY_PARAMS", "HEAVY_INITIAL",
           "FREE_MOMENTS", "FREE_OMEGA0"]

HEAVY_PARAMS = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
HEAVY_INITIAL = dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0)
FREE_MOMENTS = (1.0, 2.0, 3.0)
FREE_OMEGA0 = (1.0, 0.5, 1.0)

# 30-digit mpmath values copied from tests/reference/heavy_top_cases.json (case "cusps_released",
# the same top; made by tests/reference/make_heavy_top_reference.py) and free_top_cases.json (case
# "generic", same I and ω(0); ω does not depend on its R(0)), so an installed package can measure the
# closed forms' own error; tests/test_bench.py checks the copies against the files.
#: (t, φ, θ, ψ)
HEAVY_REFERENCE = (
    (0.4, "0.0241531830675295018100783910267", "0.535797481480127018938387029763",
     "1.9790584034233316851873465541"),
    (1.3, "0.458363749170846226393324499473", "0.720588364465333907423432474377",
     "6.13347101218402521503625004832"),
    (2.9, "1.54877883821561991947796495615", "0.578130741124617738976156464936",
     "13.3119349520148926265668426895"),
    (352.87154916942853, "163.102845093048850535938618117", "0.684788170007409312140500042533",
     "1638.54072829187428793103656656"),
    (35179.35491694285, "16279.3364343808694403029948092", "0.723279244413510218946005502599",
     "163340.378122513005344329921165"),
)
#: (t, ω1, ω2, ω3)
FREE_REFERENCE = (
    (0.5, "0.659810290411902617224644477289", "0.902579847252618824604122048365",
     "0.900990125608754802705416235285"),
    (1.7, "-0.41030267102950709696230942587", "1.04002486419606914973068525226",
     "0.850166313504588724832091453894"),
    (3.1, "-1.10334023998295972116589166505", "-0.180666307966772959891308604266",
     "1.03559317706740020624747671977"),
    (69.20708010272314, "-0.0491770278741545162716666812334", "1.11695193268531687058690153424",
     "0.816990081553530932105788936614"),
    (67909.98010272314, "-1.11687270247946369674870617359", "0.0509447392398799777470643394109",
     "1.04041732549071875357079155863"),
)


def _heavy_closed_form_error() -> float:
    """Max |closed form - 30-digit reference| over θ and the wrapped φ, ψ (t up to 10⁴ periods)."""
    import mpmath

    from ..systems.heavy_top.exact import exact_heavy_top

    top = exact_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL)
    t = np.array([p[0] for p in HEAVY_REFERENCE])
    worst = float(np.max(np.abs(top.theta(t) - np.array([float(p[2]) for p in HEAVY_REFERENCE]))))
    for col, f in ((1, top.phi), (3, top.psi)):
        got = f(t, wrapped=True)
        for g, p in zip(got, HEAVY_REFERENCE):
            with mpmath.workdps(40):
                x = mpmath.mpf(p[col])
                ref = float(x - 2 * mpmath.pi * mpmath.nint(x / (2 * mpmath.pi)))
            d = g - ref
            worst = max(worst, abs((d + np.pi) % (2 * np.pi) - np.pi))
    return worst


def _free_closed_form_error() -> float:
    from ..systems.free_top.exact import exact_free_top

    sol = exact_free_top(FREE_MOMENTS, FREE_OMEGA0)
    t = np.array([p[0] for p in FREE_REFERENCE])
    ref = np.array([[float(x) for x in p[1:]] for p in FREE_REFERENCE])
    return float(np.max(np.abs(sol.omega(t) - ref)))


# --- the BASELINE user path -------------------------------------------------------------------

def _user_path() -> tuple[Any, dict]:
    """The usual SymPy route to a heavy-top right-hand side; (f(t, y), stage seconds)."""
    loaded = "sympy.physics.mechanics" in sys.modules
    t0 = time.perf_counter()
    import sympy as sp
    from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)
    t1 = time.perf_counter()
    phi, theta, psi = dynamicsymbols("phi theta psi")
    I1, I3, M, g, l = sp.symbols("I1 I3 M g l", positive=True)
    N, B = ReferenceFrame("N"), ReferenceFrame("B")
    B.orient_body_fixed(N, (phi, theta, psi), "ZXZ")
    P = Point("P")
    P.set_vel(N, 0)
    G = P.locatenew("G", l * B.z)
    G.v2pt_theory(P, N, B)
    top = RigidBody("top", G, B, M, (inertia(B, I1, I1, I3), P))  # inertia about the pivot
    top.potential_energy = M * g * G.pos_from(P).dot(N.z)
    LM = LagrangesMethod(Lagrangian(N, top), [phi, theta, psi])
    LM.form_lagranges_equations()
    rhs = LM.rhs()
    t2 = time.perf_counter()
    qs = [phi, theta, psi]
    f = sp.lambdify([*qs, *(q.diff() for q in qs), I1, I3, M, g, l], list(rhs), cse=True)
    t3 = time.perf_counter()
    p = tuple(HEAVY_PARAMS[k] for k in ("I1", "I3", "M", "g", "l"))

    def fun(_t: float, y: np.ndarray) -> list:
        return f(*y, *p)

    return fun, dict(import_s=t1 - t0, import_already_loaded=loaded, derive_s=t2 - t1, lambdify_s=t3 - t2)


def _angles_error(angles: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(angles - ref)))


def heavy_top_work_precision(*, quick: bool = False, repeat: int = 3) -> dict:
    """The heavy-top work-precision table (rows as dicts) with the closed form's reference error."""
    from scipy.integrate import solve_ivp

    from ..systems.heavy_top.exact import exact_heavy_top
    from ..systems.heavy_top.integrate import integrate_heavy_top

    # the user path first, so its import of SymPy is measured before anything else loads it
    user_fun, user_cold = _user_path()

    periods = 10 if quick else 100
    top = exact_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL)  # warm-up: compiled constants, memoised
    T = periods * top.nutation_period
    t = np.linspace(0.0, T, 20 * periods + 1)  # Δt = T/2000 = 0.176 s in both modes
    dt = t[1] - t[0]
    top.evaluate(t[:3], ["theta", "phi", "psi"])

    def closed() -> np.ndarray:
        sol = exact_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL)
        out = sol.evaluate(t, ["phi", "theta", "psi"])
        return np.stack([out["phi"], out["theta"], out["psi"]], axis=-1)

    ref, t_closed, n_closed = median_time(closed, repeat=max(repeat, 5))
    split = {}
    for label, names in (("setup", None), ("theta", ["theta"])):
        def part(names=names):
            sol = exact_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL)
            if names:
                sol.evaluate(t, names)
        split[label] = median_time(part, repeat=max(repeat, 5))[1]
    split["theta_phi_psi"] = t_closed
    ref_error = _heavy_closed_form_error()
    rows = [row("closed form", "setup + θ, φ, ψ", t_closed, ref_error, runs=n_closed, error_vs="30-digit mpmath")]

    integrate_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL, t[:2], estimate_error=False)  # compile once (C)
    integrate_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL, t[:2], estimate_error=False, backend="scipy")
    integrate_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL, t[:2], method="splitting", step=dt, estimate_error=False)

    def ours(**kw):
        def go():
            run = integrate_heavy_top(HEAVY_PARAMS, HEAVY_INITIAL, t, estimate_error=False, **kw)
            return run, run.euler_angles
        (run, angles), seconds, n = median_time(go, repeat=repeat)
        return run, angles, seconds, n

    rtols = (1e-6, 1e-10, 1e-13) if quick else (1e-6, 1e-8, 1e-10, 1e-12, 1e-13, 1e-14)
    scipy_rtols = (1e-10,) if quick else (1e-8, 1e-10, 1e-13)
    for backend, label, rts in (("c", "DOP853 (C)", rtols), ("scipy", "DOP853 (SciPy)", scipy_rtols)):
        for rt in rts:
            run, angles, s, n = ours(rtol=rt, backend=backend)
            rows.append(row(label, f"rtol {rt:.0e}", s, _angles_error(angles, ref), evals=run.n_evaluations,
                            runs=n))
    steps = {4: (2,), 6: (2, 8)} if quick else {4: (1, 2, 4, 8), 6: (1, 2, 4, 8, 16)}
    for order, ns in steps.items():
        for k in ns:
            run, angles, s, n = ours(method="splitting", order=order, step=dt / k)
            rows.append(row(f"splitting order {order}", f"h = Δt/{k} = {dt / k:.3g} s", s, _angles_error(angles, ref),
                            evals=run.n_evaluations, runs=n))

    y0 = [HEAVY_INITIAL[k] for k in ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")]
    cold_s = user_cold["import_s"] + user_cold["derive_s"] + user_cold["lambdify_s"]
    for rt in ((1e-8, 1e-13) if quick else (1e-8, 1e-10, 1e-13)):
        def user(rt=rt):
            return solve_ivp(user_fun, (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=rt, atol=rt / 100)
        sol, s, n = median_time(user, repeat=repeat)
        err = _angles_error(sol.y[:3].T, ref)
        rows.append(row("baseline", f"rtol {rt:.0e}", s, err, evals=int(sol.nfev), runs=n))
        rows.append(row("baseline (cold)", f"rtol {rt:.0e}", s + cold_s, err, evals=int(sol.nfev), runs=n))
    nearest_error_speedups(rows, "baseline")
    for r in rows:
        if r["family"] == "baseline (cold)":
            r["speedup"] = r["speedup_vs"] = None
    return dict(case=dict(parameters=HEAVY_PARAMS, initial=HEAVY_INITIAL, periods=periods, t_end=float(T),
                          samples=int(t.size), dt=float(dt), psi_end=float(ref[-1, 2])),
                reference_error=ref_error, closed_form_split=split, baseline_cold=user_cold, rows=rows)


def free_top_work_precision(*, quick: bool = False, repeat: int = 3) -> dict:
    """The free-top work-precision table; speed-ups are against the SciPy DOP853 row of nearest error."""
    from ..systems.free_top.exact import exact_free_top
    from ..systems.free_top.integrate import integrate_free_top

    periods = 10 if quick else 100
    sol = exact_free_top(FREE_MOMENTS, FREE_OMEGA0)
    T = periods * sol.polhode_period
    t = np.linspace(0.0, T, 20 * periods + 1)
    dt = t[1] - t[0]
    sol.omega(t[:3])

    def closed() -> np.ndarray:
        return exact_free_top(FREE_MOMENTS, FREE_OMEGA0).omega(t)

    ref, t_closed, n_closed = median_time(closed, repeat=max(repeat, 5))
    ref_error = _free_closed_form_error()
    rows = [row("closed form", "setup + ω", t_closed, ref_error, runs=n_closed, error_vs="30-digit mpmath")]
    integrate_free_top(FREE_MOMENTS, FREE_OMEGA0, t[:2], estimate_error=False)
    integrate_free_top(FREE_MOMENTS, FREE_OMEGA0, t[:2], estimate_error=False, backend="scipy")
    integrate_free_top(FREE_MOMENTS, FREE_OMEGA0, t[:2], method="splitting", step=dt, estimate_error=False)

    def ours(**kw):
        return median_time(lambda: integrate_free_top(FREE_MOMENTS, FREE_OMEGA0, t, estimate_error=False, **kw),
                           repeat=repeat)

    for backend, label in (("scipy", "DOP853 (SciPy)"), ("c", "DOP853 (C)")):
        for rt in ((1e-8, 1e-13) if quick else (1e-8, 1e-10, 1e-12, 1e-13)):
            run, s, n = ours(rtol=rt, atol=rt / 100, backend=backend)
            rows.append(row(label, f"rtol {rt:.0e}", s, float(np.max(np.abs(run.omega - ref))),
                            evals=run.n_evaluations, runs=n))
    steps = {4: (4,), 6: (4,)} if quick else {4: (4, 8, 16), 6: (2, 4, 8, 16)}
    for order, ns in steps.items():
        for k in ns:
            run, s, n = ours(method="splitting", order=order, step=dt / k)
            rows.append(row(f"splitting order {order}", f"h = Δt/{k} = {dt / k:.3g} s", s,
                            float(np.max(np.abs(run.omega - ref))), evals=run.n_evaluations, runs=n))
    nearest_error_speedups(rows, "DOP853 (SciPy)")
    return dict(case=dict(moments=FREE_MOMENTS, omega0=FREE_OMEGA0, periods=periods, t_end=float(T),
                          samples=int(t.size), dt=float(dt)),
                reference_error=ref_error, rows=rows)
