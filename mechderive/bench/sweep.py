"""Sweeps: points per second for each backend and worker count, in one run (issue 15).

The sweep is the issue's heavy-top map (θ, ψ̇, φ̇ over figure 44's regions; class, nutation period,
turning angles, mean precession), as a random sample of ``points`` (fixed seed): each backend computes
the same table, which is checked bit for bit against the first.  Also measured: the free top's batched
flip interval and polhode period, and the one-by-one path (every point through the planner, what a
system without a batch gets), so that the batch's gain is a figure.  Times are wall times of
:func:`~mechderive.sweeps.run.run_sweep` on a warm cache, pool or cluster start-up included.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from ..errors import MechDeriveError

__all__ = ["sweep_throughput", "report_lines"]

_TOP = {"system": "heavy_top",
        "parameters": {"I1": 1.0, "I3": 0.5, "M": 1.0, "g": 9.81, "l": 0.1},
        "initial": {"theta": 0.5, "phi": 0.0, "psi": 0.0, "theta_dot": 0.0, "phi_dot": 0.0, "psi_dot": 20.0}}
_SUMMARY = ["motion_class", "nutation_period", "theta_min", "theta_max", "mean_precession_rate"]


def _heavy(points: int, summary: list[str], chunk: int) -> dict:
    return {**_TOP, "sweep": {"random": {"samples": points, "seed": 1, "theta": [0.05, 3.09],
                                         "psi_dot": [0.5, 40.0], "phi_dot": [-5.0, 5.0]},
                              "summary": summary, "chunk": chunk}}


def _free(points: int) -> dict:
    return {"system": "free_top", "parameters": {"I1": 1.0, "I2": 2.0, "I3": 3.0},
            "initial": {"omega": [1e-6, 1.0, 1e-6]},
            "sweep": {"random": {"samples": points, "seed": 1, "I3": [2.05, 2.95], "omega[0]": [1e-6, 0.5]},
                      "summary": ["flip_interval", "polhode_period"], "chunk": 10_000}}


def _time(document: dict, out: Path, **backend) -> tuple[float, dict]:
    from ..sweeps.run import run_sweep
    from ..sweeps.spec import parse_sweep

    sweep = parse_sweep(document, name="bench")
    start = time.perf_counter()
    result = run_sweep(sweep, out, **backend)
    return time.perf_counter() - start, result


def sweep_throughput(*, quick: bool = False) -> dict:
    """{rows: [{sweep, backend, points, seconds, points_per_second, one_by_one, identical}], ...}."""
    import numpy as np

    points = 20_000 if quick else 200_000
    rows = []
    with tempfile.TemporaryDirectory(prefix="mechderive-bench-sweep-") as tmp:
        doc = _heavy(points, _SUMMARY, 10_000)
        _time(_heavy(2_000, _SUMMARY, 1_000), Path(tmp) / "warm.npz", workers=1)  # derive/compile once
        first = None
        backends = [("local", {"workers": 1}), ("local", {"workers": 2}), ("dask", {"dask": "local:1"}),
                    ("dask", {"dask": "local:2"})]
        for i, (kind, backend) in enumerate(backends):
            try:
                seconds, result = _time(doc, Path(tmp) / f"heavy{i}.npz", **backend)
            except MechDeriveError as exc:  # dask not installed: said in the table, the rest still measured
                rows.append({"sweep": "heavy top (batched)", "backend": f"{kind} {backend}", "error": str(exc)})
                continue
            table = result.table
            if first is None:
                first = table
            identical = all(np.asarray(first[k]).tobytes() == np.asarray(table[k]).tobytes()
                            if np.asarray(table[k]).dtype.kind == "f" else list(first[k]) == list(table[k])
                            for k in first)
            rows.append({"sweep": "heavy top (batched)", "backend": result.report["backend"], "points": points,
                         "seconds": round(seconds, 3), "points_per_second": round(points / seconds),
                         "one_by_one": result.report["one_by_one"], "identical": identical})
        n_free = points
        seconds, result = _time(_free(n_free), Path(tmp) / "free.npz", workers=2)
        rows.append({"sweep": "free top (batched)", "backend": result.report["backend"], "points": n_free,
                     "seconds": round(seconds, 3), "points_per_second": round(n_free / seconds),
                     "one_by_one": result.report["one_by_one"], "identical": None})
        n_point = 100 if quick else 400
        # "steady" is not batched: every point goes through the planner (the 40-digit closed form)
        seconds, result = _time(_heavy(n_point, _SUMMARY + ["steady"], 50), Path(tmp) / "point.npz", workers=2)
        rows.append({"sweep": "heavy top (one by one, planner)", "backend": result.report["backend"],
                     "points": n_point, "seconds": round(seconds, 3), "points_per_second": round(n_point / seconds, 1),
                     "one_by_one": result.report["one_by_one"], "identical": None})
        # an integrated system: every point integrated (compiled DOP853 with its error estimate) and its
        # summaries measured on the trajectory, one by one through the planner
        from ..systems import registry

        n_rb = 8 if quick else 24
        seconds, result = _time(_rigid(registry.get("rigid_body").example_scene(), n_rb), Path(tmp) / "rb.npz",
                                workers=2)
        rows.append({"sweep": "rigid body (integrated, one by one)", "backend": result.report["backend"],
                     "points": n_rb, "seconds": round(seconds, 3), "points_per_second": round(n_rb / seconds, 1),
                     "one_by_one": result.report["one_by_one"], "identical": None})
    return {"rows": rows, "points": points}


def _rigid(example: str, points: int) -> dict:
    """The rigid_body system's example scene (an asymmetric heavy top, 20 s) over its tilt and spin."""
    import tomllib

    doc = tomllib.loads(example)
    doc["output"] = {"quantities": [doc["output"]["quantities"][0]]}
    doc["sweep"] = {"random": {"samples": points, "seed": 1, "theta": [0.1, 1.5], "omega[2]": [10.0, 30.0]},
                    "summary": ["period", "energy", "L_vertical"]}
    return doc


def report_lines(result: dict) -> list[str]:
    lines = ["## 8. Sweeps: points per second by backend (warm cache, start-up included)", "",
             "| sweep | backend | points | time | points/s | one by one | same table |",
             "|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        if "error" in r:
            lines.append(f"| {r['sweep']} | {r['backend']} | — | — | — | — | {r['error']} |")
            continue
        same = "" if r["identical"] is None else ("bit for bit" if r["identical"] else "DIFFERS")
        lines.append(f"| {r['sweep']} | {r['backend']} | {r['points']} | {r['seconds']:.2f} s | "
                     f"{r['points_per_second']:,} | {r['one_by_one']} | {same} |")
    return lines + [""]
