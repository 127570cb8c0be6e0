"""Work–precision of the heavy-top integrators against the usual SymPy → lambdify → solve_ivp path.

Case (/work/shared/BASELINE.md, "Heavy symmetric top"): I1 = 1 (about the pivot), I3 = 0.5, M g l = 1,
let go at θ0 = 0.5 with θ̇ = φ̇ = 0, ψ̇ = 5; 100 nutation periods (T = 351.77 s), 2001 samples.
mechderive runs it with M = 1, g = 4, l = 0.25 (a body that exists: M = g = l = 1 would need I1_cm = 0
< I3/2, refused by ``check_params``); the user path uses M = g = l = 1 with the inertia given about the
pivot, exactly as in BASELINE.md.  Only M g l enters the motion.

Compared:

* ``integrate_heavy_top(method="DOP853")`` at rtol 1e-6 … 1e-13 (atol = rtol/100) — SciPy's stepping loop
  on the derived (ω, q) right-hand side;
* ``method="splitting"`` (kick–drift–kick with the exact free-top flow; orders 2, 4, 6) at steps
  h = Δt/n, Δt = T/2000 = 0.1759 s the sample spacing;
* the BASELINE user path: ``sympy.physics.mechanics`` (``ReferenceFrame.orient_body_fixed(..., 'ZXZ')``,
  ``RigidBody``, ``LagrangesMethod``) → ``LM.rhs()`` → ``lambdify(cse=True)`` → ``solve_ivp(DOP853)`` on the
  Euler angles, at rtol 1e-10 and 1e-13 (atol = rtol/100): warm (integration only) and cold (a fresh
  process: import, derivation, lambdify, integration, timed from outside).

Error: max over the 2001 samples and the three angles of |(φ, θ, ψ) - reference| (rad), φ and ψ
unwrapped.  Reference: the order-6 splitting at h = Δt/24; the script prints its distance to the same at
h = Δt/32 and to DOP853 at rtol 1e-13 on (ω, q) (independent methods: adaptive Runge–Kutta vs composition
of exact flows); the user path at rtol 1e-13 (DOP853 on the Euler angles) is a third.  Smaller steps do
not help the reference: over 351 s, rounding in millions of stages moves |L| and E by ~1e-14 and the
phase of ψ (≈ 1750 rad) by ~1e-11 – 1e-10.

How to read it: "time" is the median wall time of the integration alone over ``--repeat`` runs
(compilation and error-estimate reruns excluded; they are in the cold rows); "evals" are right-hand-side
calls (DOP853) or compiled stage calls, each one exact drift and one kick (splitting).  Absolute times
are noisy on shared machines; compare rows within one run.

    python benchmarks/bench_heavy_top_integrators.py            # full table (~1-2 min)
    python benchmarks/bench_heavy_top_integrators.py --quick    # 10 periods (201 samples), fewer rows
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

PERIOD = 3.5177  # nutation period (s), from the cubic (3.73); tests/test_heavy_top_integrate.py checks it
PARAMS = dict(I1=1.0, I3=0.5, M=1.0, g=4.0, l=0.25)
INITIAL = dict(theta=0.5, psi_dot=5.0)

# The BASELINE user code (sympy.physics.mechanics → LagrangesMethod → lambdify(cse) → solve_ivp) is the
# one `mechderive bench` times: mechderive.bench.work_precision._user_path, timing its own stages.
USER_PATH = r'''
import time, json, sys
import numpy as np
from scipy.integrate import solve_ivp
from mechderive.bench.work_precision import _user_path
fun, stages = _user_path()
def run(t, rtol):
    return solve_ivp(fun, (t[0], t[-1]), [0, 0.5, 0, 0, 0, 5.0], method="DOP853", t_eval=t, rtol=rtol,
                     atol=rtol / 100)
'''

COLD_USER = USER_PATH + r'''
t = np.linspace(0.0, float(sys.argv[1]), int(sys.argv[3]))
t3 = time.perf_counter()
sol = run(t, float(sys.argv[2]))
t4 = time.perf_counter()
print(json.dumps(dict(imports=stages["import_s"], derive=stages["derive_s"], lambdify=stages["lambdify_s"],
                      integrate=t4 - t3, nfev=int(sol.nfev))))
'''

COLD_OURS = r'''
import time, json, sys
t0 = time.perf_counter()
import numpy as np
from mechderive.systems.heavy_top.integrate import integrate_heavy_top
t1 = time.perf_counter()
t = np.linspace(0.0, float(sys.argv[1]), int(sys.argv[3]))
kw = json.loads(sys.argv[2])
first = integrate_heavy_top(dict(I1=1.0, I3=0.5, M=1.0, g=4.0, l=0.25), dict(theta=0.5, psi_dot=5.0),
                            t[:2], estimate_error=False, **kw)   # derive + compile
t2 = time.perf_counter()
run = integrate_heavy_top(dict(I1=1.0, I3=0.5, M=1.0, g=4.0, l=0.25), dict(theta=0.5, psi_dot=5.0),
                          t, estimate_error=False, **kw)
angles = run.euler_angles
t3 = time.perf_counter()
print(json.dumps(dict(imports=t1 - t0, derive_compile=t2 - t1, integrate=t3 - t2)))
'''


def cold(script: str, *args: str) -> tuple[float, dict]:
    """Wall time of a fresh ``python -c script args`` measured from outside, and its JSON report."""
    env_path = str(ROOT)
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin"}, cwd=ROOT)
    total = time.perf_counter() - start
    return total, json.loads(out.stdout.strip().splitlines()[-1])


def angle_error(angles: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(angles - ref)))


def main() -> None:
    from mechderive.systems.heavy_top.integrate import integrate_heavy_top, integrate_heavy_top_ensemble

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="10 periods, fewer rows")
    parser.add_argument("--repeat", type=int, default=3, help="runs per row (median time)")
    args = parser.parse_args()

    periods = 10 if args.quick else 100
    T = periods * PERIOD
    t = np.linspace(0.0, T, 20 * periods + 1)  # Δt = 0.176 s in both modes
    dt = t[1] - t[0]
    print(f"Heavy top I1 = 1, I3 = 0.5, M g l = 1, θ0 = 0.5, ψ̇0 = 5: {periods} nutation periods "
          f"(T = {T:.2f} s), {t.size} samples, Δt = {dt:.4f} s\n")

    def ours(**kw):
        runs = [integrate_heavy_top(PARAMS, INITIAL, t, estimate_error=False, **kw) for _ in range(args.repeat)]
        return runs[0], statistics.median(r.wall_time for r in runs)

    start = time.perf_counter()
    ref_run = integrate_heavy_top(PARAMS, INITIAL, t, method="splitting", order=6, step=dt / 24,
                                  estimate_error=False)
    ref = ref_run.euler_angles
    print(f"reference: splitting order 6, h = Δt/24 = {dt / 24:.3g} s ({time.perf_counter() - start:.1f} s); "
          f"energy drift {ref_run.energy_drift:.1e}")
    finer = integrate_heavy_top(PARAMS, INITIAL, t, method="splitting", order=6, step=dt / 32, estimate_error=False)
    print(f"  max |angles_ref - angles(h = Δt/32)| = {angle_error(finer.euler_angles, ref):.2e}  "
          "(bounds the reference's truncation error, ~(32/24)⁶ = 5.6 times the finer run's; rounding remains)")
    dop_ref = integrate_heavy_top(PARAMS, INITIAL, t, rtol=1e-13, atol=1e-15, estimate_error=False)
    print(f"  max |angles_ref - angles_DOP853(rtol 1e-13, atol 1e-15)| = {angle_error(dop_ref.euler_angles, ref):.2e}"
          f"  (θ alone: {np.max(np.abs(dop_ref.euler_angles[:, 1] - ref[:, 1])):.2e})\n")

    rows = []
    rtols = [1e-6, 1e-8, 1e-10, 1e-12, 1e-13] if args.quick else [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13]
    for rt in rtols:
        run, wall = ours(rtol=rt)
        rows.append(("mechderive DOP853 (ω, q)", f"rtol {rt:.0e}", wall, run.n_evaluations,
                     angle_error(run.euler_angles, ref), run.energy_drift, run.p_phi_drift))
    substeps = {2: [4, 16, 64], 4: [1, 2, 4, 8], 6: [1, 2, 4, 8]} if args.quick else \
        {2: [4, 8, 16, 32, 64], 4: [1, 2, 4, 8, 16], 6: [1, 2, 3, 4, 6, 8, 12, 16]}
    for order, ns in substeps.items():
        for n in ns:
            run, wall = ours(method="splitting", order=order, step=dt / n)
            rows.append((f"mechderive splitting order {order}", f"h = Δt/{n} = {dt / n:.3g}", wall, run.n_evaluations,
                         angle_error(run.euler_angles, ref), run.energy_drift, run.p_phi_drift))

    # --- the BASELINE user path -------------------------------------------------------------------
    namespace: dict = {}
    exec(USER_PATH, namespace)  # noqa: S102 - our own benchmark code, defined above
    for rt in (1e-10, 1e-13):
        times, sol = [], None
        for _ in range(args.repeat):
            s = time.perf_counter()
            sol = namespace["run"](t, rt)
            times.append(time.perf_counter() - s)
        err = angle_error(sol.y[:3].T, ref)
        rows.append(("user path: mechanics → lambdify → DOP853 (warm)", f"rtol {rt:.0e}", statistics.median(times),
                     int(sol.nfev), err, float("nan"), float("nan")))
        total, parts = cold(COLD_USER, str(T), str(rt), str(t.size))
        rows.append(("user path, cold process", f"rtol {rt:.0e}", total, parts["nfev"], err, float("nan"),
                     float("nan")))
        print(f"user path cold, rtol {rt:.0e}: total {total:.2f} s = imports {parts['imports']:.2f} + derive "
              f"{parts['derive']:.2f} + lambdify {parts['lambdify']:.2f} + integrate {parts['integrate']:.2f} "
              "(+ interpreter start)")
    for label, kw in (("DOP853 rtol 1e-10", dict(rtol=1e-10)), ("splitting order 6, h = Δt/6",
                                                                  dict(method="splitting", order=6, step=dt / 6))):
        total, parts = cold(COLD_OURS, str(T), json.dumps(kw), str(t.size))
        print(f"mechderive cold, {label}: total {total:.2f} s = imports {parts['imports']:.2f} + derive & compile "
              f"{parts['derive_compile']:.2f} + integrate & angles {parts['integrate']:.2f} (+ interpreter start)")
        run = integrate_heavy_top(PARAMS, INITIAL, t, estimate_error=False, **kw)
        rows.append((f"mechderive cold process, {label.split(',')[0]}", label.split(", ")[-1] if "," in label
                     else label.split(" ", 1)[1], total, run.n_evaluations, angle_error(run.euler_angles, ref),
                     run.energy_drift, run.p_phi_drift))

    print()
    print(f"| method | setting | time (s) | evals | max angle error (rad) | energy drift | p_φ drift |")
    print("|---|---|---|---|---|---|---|")
    for name, setting, wall, evals, err, ed, pd in rows:
        fmt = lambda x: "—" if math.isnan(x) else f"{x:.1e}"  # noqa: E731
        print(f"| {name} | {setting} | {wall:.3f} | {evals} | {err:.1e} | {fmt(ed)} | {fmt(pd)} |")

    print("\nBest time to a max angle error ≤ 1e-6 / 1e-8 / 1e-10:")
    for target in (1e-6, 1e-8, 1e-10):
        best = {}
        for name, setting, wall, evals, err, *_ in rows:
            if "cold" in name or err > target:
                continue
            key = "user path" if name.startswith("user") else name.split(" (")[0].split(" order")[0]
            if key not in best or wall < best[key][0]:
                best[key] = (wall, f"{name} {setting}")
        print(f"  ≤ {target:.0e}: " + "; ".join(f"{v[1]}: {v[0]:.3f} s" for v in best.values()))

    # --- ensemble throughput --------------------------------------------------------------------
    rng = np.random.default_rng(1)
    t_ens = np.linspace(0.0, 10.0, 11)
    for M in (1000, 10000) if not args.quick else (1000,):
        init = dict(theta=rng.uniform(0.0, math.pi, M), psi_dot=rng.uniform(-10, 10, M),
                    phi_dot=rng.uniform(-1, 1, M))
        ens = integrate_heavy_top_ensemble(PARAMS, init, t_ens, step=0.02, order=4)
        single = integrate_heavy_top(PARAMS, {k: v[0] for k, v in init.items()}, t_ens, method="splitting", order=4,
                                     step=0.02, estimate_error=False)
        print(f"\nensemble of {M} tops, order 4, h = 0.02, 10 s: {ens.wall_time:.2f} s, "
              f"{ens.body_steps_per_second:.3g} body-steps/s (one top alone: {single.n_steps / single.wall_time:.3g} "
              f"steps/s); max energy drift {ens.energy_drift.max():.1e}, p_φ {ens.p_phi_drift.max():.1e}, "
              f"p_ψ {ens.p_psi_drift.max():.1e}")


if __name__ == "__main__":
    main()
