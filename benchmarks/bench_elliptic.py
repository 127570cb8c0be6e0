"""Benchmark: mechderive.special.jacobi_sn_cn_dn against scipy.special.ellipj.

What is compared: wall time for sn, cn, dn at 10⁶ points (best of ``--repeat`` runs: the machine is shared, and the minimum is the least disturbed), and
the maximum error of each code against mpmath at 30 digits on a seeded subsample.  Both
codes get the same parameter: m is a double and m1 = 1 - m is its exact complement, so the
errors measure the algorithms, not the rounding of 1 - m1.

Columns: ``abs err`` is max |f - f_ref| over sn, cn, dn; ``dn rel`` is max |dn - dn_ref|/dn_ref
(dn ≈ √m1 is tiny near the separatrix, so only a relative error is meaningful there).
Rows ``u ∈ [0, 4K]`` sample one period; the row ``u ≈ 10⁶·4K`` samples the period a million
periods out (a test of the argument reduction).

Run: ``python benchmarks/bench_elliptic.py [--points N] [--sample N] [--repeat N]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import mpmath
import numpy as np
import scipy.special

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from mechderive.special import ellipk_m1, jacobi_sn_cn_dn  # noqa: E402


def _time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.min(times))


def _errors(u: np.ndarray, m: float, values) -> tuple[float, float]:
    sn, cn, dn = values
    worst_abs = worst_rel = 0.0
    with mpmath.workdps(30):
        mm = mpmath.mpf(m)
        for i, x in enumerate(u):
            ref = [mpmath.ellipfun(f, mpmath.mpf(float(x)), m=mm) for f in ("sn", "cn", "dn")]
            for got, r in zip((sn[i], cn[i], dn[i]), ref):
                worst_abs = max(worst_abs, float(abs(mpmath.mpf(float(got)) - r)))
            worst_rel = max(worst_rel, float(abs((mpmath.mpf(float(dn[i])) - ref[2]) / ref[2])))
    return worst_abs, worst_rel


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10**6)
    parser.add_argument("--sample", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(20261121)

    cases = [(m1, 0) for m1 in (0.62, 1e-3, 1e-6, 1e-9, 1e-12, 1e-14)] + [(0.62, 10**6)]
    print(f"{args.points:.0e} points, best of {args.repeat}; errors on {args.sample} points vs mpmath (30 digits)")
    header = (f"{'1 - m':>8} {'u':>12} | {'ours ms':>8} {'scipy ms':>8} | {'ours abs err':>12} {'scipy abs err':>13}"
              f" | {'ours dn rel':>11} {'scipy dn rel':>12}")
    print(header)
    print("-" * len(header))
    for m1_nominal, periods in cases:
        m = 1.0 - m1_nominal
        m1 = 1.0 - m  # exact complement of the double m
        K = float(ellipk_m1(m1))
        u = periods * 4 * K + rng.uniform(0.0, 4 * K, args.points)
        t_ours = _time(lambda: jacobi_sn_cn_dn(u, m, m1=m1), args.repeat)
        t_scipy = _time(lambda: scipy.special.ellipj(u, m), args.repeat)
        sub = u[: args.sample]
        e_ours = _errors(sub, m, jacobi_sn_cn_dn(sub, m, m1=m1))
        e_scipy = _errors(sub, m, scipy.special.ellipj(sub, m)[:3])
        where = "[0, 4K]" if periods == 0 else "≈ 1e6·4K"
        print(f"{m1_nominal:>8.0e} {where:>12} | {1e3 * t_ours:8.1f} {1e3 * t_scipy:8.1f} | "
              f"{e_ours[0]:12.1e} {e_scipy[0]:13.1e} | {e_ours[1]:11.1e} {e_scipy[1]:12.1e}")


if __name__ == "__main__":
    main()
