"""Benchmark: the free top's exact solution against solve_ivp on 10⁶ time points.

Case (BASELINE.md): I = (1, 2, 3), ω(0) = (1, 0.5, 1), R(0) = 1, 100 polhode periods
(≈ 679 s).  Compared:

* ``exact``: mechderive's closed form (Jacobi elliptic functions, Π for the precession,
  constants at 40 digits, phase reduced in double-double) evaluated at 10⁶ points;
* ``DOP853``: scipy.integrate.solve_ivp at rtol 1e-12, atol 1e-14 on the compiled
  Euler equations + quaternion (mechderive.systems.free_top.integrate), dense output at
  the same points.

Errors: the exact solution's own error is measured against the committed 30-digit
mpmath reference (tests/reference/free_top_cases.json, case "generic", which uses a
random R(0); ω is independent of R(0)); DOP853's error is its difference from the exact
solution over all points (the exact solution is ~1e-15 accurate, so this is DOP853's).

Run: python benchmarks/bench_free_top_exact.py [--points N]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from mechderive.systems.free_top.exact import exact_free_top
from mechderive.systems.free_top.integrate import integrate_free_top

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10**6)
    args = parser.parse_args()
    I, w0 = (1.0, 2.0, 3.0), (1.0, 0.5, 1.0)

    start = time.perf_counter()
    sol = exact_free_top(I, w0)
    setup = time.perf_counter() - start
    t = np.linspace(0.0, 100 * sol.polhode_period, args.points)
    start = time.perf_counter()
    w_exact = sol.omega(t)
    t_omega = time.perf_counter() - start
    start = time.perf_counter()
    R_exact = sol.rotation(t)
    t_rot = time.perf_counter() - start

    ref = {c["name"]: c for c in json.loads((ROOT / "tests/reference/free_top_cases.json").read_text())["cases"]}
    case = ref["generic"]
    sol_ref = exact_free_top(case["moments"], case["omega0"], R0=np.array(case["R0"]))
    tr = np.array([p["t"] for p in case["points"]])
    err_w = np.max(np.abs(sol_ref.omega(tr) - np.array([[float(x) for x in p["omega"]] for p in case["points"]])))
    err_R = np.max(np.abs(sol_ref.rotation(tr) - np.array([[[float(x) for x in r] for r in p["R"]]
                                                            for p in case["points"]])))

    start = time.perf_counter()
    traj = integrate_free_top(I, w0, t, method="DOP853", rtol=1e-12, atol=1e-14, estimate_error=False)
    t_ivp = time.perf_counter() - start
    dw = np.max(np.abs(traj.omega - w_exact))
    dR = np.max(np.abs(traj.R - R_exact))

    print(f"free top I={I}, ω0={w0}, 100 polhode periods = {t[-1]:.2f} s, {args.points} points\n")
    print(f"{'method':<26} {'seconds':>9} {'max error ω':>12} {'max error R':>12}")
    print(f"{'exact ω(t)':<26} {setup + t_omega:9.3f} {err_w:12.1e} {'':>12}   (setup {setup:.3f} s)")
    print(f"{'exact ω(t) and R(t)':<26} {setup + t_omega + t_rot:9.3f} {err_w:12.1e} {err_R:12.1e}")
    print(f"{'solve_ivp DOP853 rtol 1e-12':<26} {t_ivp:9.3f} {dw:12.1e} {dR:12.1e}   "
          f"({traj.n_evaluations} RHS evaluations)")
    print("\nexact: errors vs the 30-digit mpmath reference (t up to 10⁴ periods);"
          " DOP853: difference from the exact solution over all points.")


if __name__ == "__main__":
    main()
