"""Shared pieces of the benchmarks: timing, rows, the speed-up rule, subprocesses.

Times are ``time.perf_counter`` wall seconds.  :func:`median_time` repeats a call while
that is cheap (at most ``repeat`` runs and about ``budget`` seconds) and returns the
median, so slow rows are timed once and fast ones several times.
"""

from __future__ import annotations

import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

from ..errors import BenchmarkError

__all__ = ["median_time", "row", "nearest_error_speedups", "python_subprocess", "package_env"]


def median_time(fn: Callable[[], Any], *, repeat: int, budget: float = 3.0) -> tuple[Any, float, int]:
    """(last result, median seconds, runs): call ``fn`` up to ``repeat`` times, stopping once ``budget`` s are spent.

    >>> _, seconds, runs = median_time(lambda: sum(range(10)), repeat=3)
    >>> runs, seconds >= 0.0
    (3, True)
    """
    times: list[float] = []
    result = None
    while True:
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
        if len(times) >= repeat or sum(times) >= budget:
            return result, statistics.median(times), len(times)


def row(family: str, setting: str, seconds: float, max_error: float | None, *, evals: int | None = None,
        runs: int = 1, **extra: Any) -> dict:
    """One line of a work-precision table (a plain dict, so ``--json`` prints it as is)."""
    return dict(family=family, setting=setting, seconds=float(seconds),
                max_error=None if max_error is None else float(max_error), evals=evals, runs=runs,
                speedup=None, speedup_vs=None, **extra)


def nearest_error_speedups(rows: Sequence[dict], reference_family: str) -> None:
    """Fill ``speedup`` of every other row: the time of the ``reference_family`` row whose error is
    nearest on a log scale, divided by the row's time; ``speedup_vs`` names that row and starts with
    ">" when the row is more accurate than every reference row (then the reference's best is used).

    >>> rows = [row("b", "rtol 1e-8", 1.0, 1e-6), row("b", "rtol 1e-13", 2.0, 1e-10), row("x", "h", 0.1, 1e-12)]
    >>> nearest_error_speedups(rows, "b"); rows[2]["speedup"], rows[2]["speedup_vs"]
    (20.0, '> b rtol 1e-13')
    """
    refs = [r for r in rows if r["family"] == reference_family and r["max_error"]]
    if not refs:
        return
    best = min(refs, key=lambda r: r["max_error"])
    for r in rows:
        if r["family"] == reference_family or not r["max_error"] or r["seconds"] <= 0:
            continue
        near = min(refs, key=lambda b: abs(math.log(r["max_error"] / b["max_error"])))
        beyond = r["max_error"] < best["max_error"]
        near = best if beyond else near
        r["speedup"] = near["seconds"] / r["seconds"]
        r["speedup_vs"] = ("> " if beyond else "") + f"{near['family']} {near['setting']}"


def package_env(**extra: str) -> dict:
    """The environment for a child Python that imports this very ``mechderive`` (plus ``extra``)."""
    root = str(Path(__file__).resolve().parents[2])
    env = dict(os.environ)
    env.pop("MECHDERIVE_NO_DISK_CACHE", None)  # each measurement sets the cache state it means
    env.update(extra)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def python_subprocess(args: Sequence[str], env: dict, *, timeout: float = 600) -> tuple[float, str, str]:
    """(wall seconds measured from outside, stdout, stderr) of ``python *args``; raises on a non-zero exit."""
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise BenchmarkError(f"benchmark subprocess failed (exit {proc.returncode}): {proc.stderr.strip()[-2000:]}")
    return wall, proc.stdout, proc.stderr
