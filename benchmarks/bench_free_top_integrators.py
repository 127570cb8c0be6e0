"""Work–precision of the free-top integrators, and throughput of the vectorised ensemble.

Case (as in /work/shared/BASELINE.md, "Free asymmetric top"): I = (1, 2, 3), ω(0) = (1, 0.5, 1),
R(0) = 1, 100 polhode periods (T = 679.0708 s; one period 4K(m)/λ = 6.790708 s), 2001 samples.

Compared: ``integrate_free_top(method="DOP853")`` at rtol 1e-6 … 1e-13 (atol = rtol/100) and
``method="splitting"`` (Lie–Poisson, orders 2, 4, 6) at steps h = Δt/n dividing the sample spacing
Δt = T/2000 = 0.3395 s (the splitting cuts every output interval into equal steps).  Error: max over the samples
and components of |ω - ω_ref|.  Reference: the order-6 splitting at h = Δt/85 ≈ 0.004 (≈ 5e-12 from the exact
elliptic solution on this case); the script prints its distance to DOP853 at rtol 1e-13 and, when
:mod:`mechderive.systems.free_top.exact` is importable, to the closed form.

How to read it: "time" is the median wall time of the integration alone (``wall_time``; the compile
and the error-estimate rerun excluded) over ``--repeat`` runs; "evals" is right-hand-side calls
(DOP853) or exact axis rotations (splitting); the drifts are max relative deviations of T and |L|.
Absolute times are noisy on shared machines; compare rows within one run.

    python benchmarks/bench_free_top_integrators.py            # full table (~1 min)
    python benchmarks/bench_free_top_integrators.py --quick    # fewer rows, shorter reference
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from mechderive.systems.free_top.integrate import integrate_free_top, integrate_free_top_ensemble  # noqa: E402

I = (1.0, 2.0, 3.0)
W0 = (1.0, 0.5, 1.0)
POLHODE_PERIOD = 6.790708010272314  # 4K(m)/λ for this case (mechderive.systems.free_top.exact)


def timed(repeat: int, **kwargs):
    runs = [integrate_free_top(I, W0, kwargs.pop("t"), estimate_error=False, **kwargs)]
    t = runs[0].t
    for _ in range(repeat - 1):
        runs.append(integrate_free_top(I, W0, t, estimate_error=False, **kwargs))
    return runs[0], statistics.median(r.wall_time for r in runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer rows and a coarser reference")
    parser.add_argument("--repeat", type=int, default=3, help="runs per row (median time)")
    args = parser.parse_args()

    periods = 10 if args.quick else 100
    t = np.linspace(0.0, periods * POLHODE_PERIOD, 2001)
    print(f"Free top I = {I}, ω0 = {W0}, {periods} polhode periods (T = {t[-1]:.4f} s), {t.size} samples")

    start = time.perf_counter()
    h_ref = (t[1] - t[0]) / math.ceil((t[1] - t[0]) / 0.004)
    ref = integrate_free_top(I, W0, t, method="splitting", order=6, step=h_ref, estimate_error=False)
    print(f"reference: splitting order 6, h = {h_ref:.4g} ({time.perf_counter() - start:.1f} s)")
    dop_ref = integrate_free_top(I, W0, t, rtol=1e-13, atol=1e-15, estimate_error=False)
    print(f"  |ω_ref - ω_DOP853(rtol 1e-13)| = {np.max(np.abs(dop_ref.omega - ref.omega)):.2e}")
    try:
        from mechderive.systems.free_top.exact import exact_free_top

        exact = exact_free_top(I, W0).omega(t)
        print(f"  |ω_ref - ω_exact (elliptic closed form)| = {np.max(np.abs(exact - ref.omega)):.2e}")
    except Exception as exc:  # the closed form is optional here
        print(f"  (exact solution not available: {type(exc).__name__})")

    rows = [("DOP853", f"rtol {r:.0e}", dict(method="DOP853", rtol=r, atol=r / 100))
            for r in ([1e-6, 1e-9, 1e-12, 1e-13] if args.quick else [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13])]
    # steps per sample interval Δt (the splitting cuts each interval into equal steps h = Δt/n)
    dt = t[1] - t[0]
    substeps = {2: [8, 16, 32, 64], 4: [2, 4, 8, 16], 6: [2, 4, 8, 16, 32]}
    if args.quick:
        substeps = {2: [2], 4: [1, 2], 6: [1, 2]}
    rows += [(f"splitting {p}", f"h = {dt / n:.3g}", dict(method="splitting", order=p, step=dt / n))
             for p, ns in substeps.items() for n in ns]

    print()
    print("| method | setting | time (s) | max abs error in ω | evals | µs/eval | energy drift | abs(L) drift |")
    print("|---|---|---|---|---|---|---|---|")
    for name, setting, kw in rows:
        run, wall = timed(args.repeat, t=t, **kw)
        err = np.max(np.abs(run.omega - ref.omega))
        print(f"| {name} | {setting} | {wall:.3f} | {err:.1e} | {run.n_evaluations} | "
              f"{1e6 * wall / run.n_evaluations:.2f} | {run.energy_drift:.1e} | {run.angular_momentum_drift:.1e} |")

    print()
    print("Ensemble throughput (splitting order 4, h = 0.05, output at the end only; random ω0, common I):")
    print("| M bodies | steps | time (s) | body-steps / s |")
    print("|---|---|---|---|")
    rng = np.random.default_rng(1)
    for M, n in ((1, 200), (100, 200), (10_000, 200), (100_000, 20)):
        w0 = rng.normal(size=(M, 3))
        ens = integrate_free_top_ensemble(I, w0, [0.0, 0.05 * n], step=0.05, order=4)
        print(f"| {M} | {n} | {ens.wall_time:.3f} | {ens.body_steps_per_second:.3g} |")
    one = integrate_free_top(I, W0, [0.0, 1000.0], method="splitting", order=4, step=0.05, estimate_error=False)
    print(f"| 1 (scalar kernel, integrate_free_top) | {one.n_steps} | {one.wall_time:.3f} | "
          f"{one.n_steps / one.wall_time:.3g} |")


if __name__ == "__main__":
    main()
