"""Sweeps: points per second for each backend and worker count, in one run (issue 15).

The sweep is the issue's heavy-top map (θ, ψ̇, φ̇ over figure 44's regions; class, nutation period,
turning angles, mean precession), as a random sample of ``points`` (fixed seed): each backend computes
the same table, which is checked bit for bit against the first.  Also measured: the free top's batched
flip interval and polhode period, and the one-by-one path (every point through the planner, what a
system without a batch gets), so that the batch's gain is a figure; and two systems that integrate (the
rigid_body example, a double pendulum from its Lagrangian), their chunks batched through the compiled
stepper, with one process's points per second one by one and batched on the same points.  Times are wall times of
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
        # systems that integrate: every point integrated (compiled DOP853 with its error estimate, rerun tighter
        # where it misses rtol) and its summaries measured on the trajectory, the chunk's runs batched in C
        from ..systems import registry

        n_int = 40 if quick else 200
        for label, doc in (("rigid body (integrated, batched)", _rigid(registry.get("rigid_body").example_scene(),
                                                                         n_int)),
                           ("double pendulum (lagrangian, integrated, batched)", _double_pendulum(n_int))):
            seconds, result = _time(doc, Path(tmp) / "int.npz", workers=2)
            rows.append({"sweep": label, "backend": result.report["backend"], "points": n_int,
                         "seconds": round(seconds, 3), "points_per_second": round(n_int / seconds, 1),
                         "one_by_one": result.report["one_by_one"], "identical": None})
    integrated = [integrated_throughput(doc, 10 if quick else 40) for doc in
                  (_rigid(registry.get("rigid_body").example_scene(), 0), _double_pendulum(0))]
    return {"rows": rows, "points": points, "integrated": integrated}


def _double_pendulum(points: int) -> dict:
    """A user's Lagrangian with no closed form (two equal rods), over its first angle, second rate and g."""
    return {"system": "lagrangian", "coordinates": ["a", "b"], "method": "auto", "rtol": 1e-10,
            "lagrangian": "m*l**2/2*(2*a_dot**2 + b_dot**2 + 2*a_dot*b_dot*cos(a - b)) + m*g*l*(2*cos(a) + cos(b))",
            "parameters": {"m": 1.0, "l": 1.0, "g": 9.81}, "initial": {"a": 0.3, "b": 0.0, "a_dot": 0.0, "b_dot": 0.0},
            "time": {"t_end": 10.0, "samples": 501}, "output": {"quantities": ["a"]},
            "sweep": {"random": {"samples": points, "seed": 1, "a": [0.05, 0.5], "b_dot": [-1.0, 1.0], "g": [5.0, 15.0]},
                      "summary": ["period", "energy"]}}


def integrated_throughput(document: dict, points: int) -> dict:
    """Points per CPU second of one process on ``points`` points of a sweep that integrates: one by one through the
    planner (what every point cost before the batch) and batched (:mod:`mechderive.solvers.batch`), the same
    points, warm; with the largest relative difference between the two tables' numbers (0: bit for bit)."""
    import numpy as np

    from ..sweeps import evaluate
    from ..sweeps.spec import parse_sweep

    document = {**document, "sweep": {**document["sweep"], "chunk": points}}
    document["sweep"][next(k for k in ("random", "grid") if k in document["sweep"])]["samples"] = points
    sweep = parse_sweep(document, name="bench")
    evaluate.evaluate_chunk(parse_sweep({**document, "sweep": {**document["sweep"], "chunk": 2}}), 0)  # warm
    # CPU seconds of this process: the machine's other work does not count (both paths run in one thread)
    start = time.process_time()
    batched = evaluate.evaluate_chunk(sweep, 0)
    t_batch = time.process_time() - start
    has_batch = evaluate.has_batch
    evaluate.has_batch = lambda model: False  # every point through the planner
    try:
        start = time.process_time()
        single = evaluate.evaluate_chunk(sweep, 0)
        t_single = time.process_time() - start
    finally:
        evaluate.has_batch = has_batch
    worst = 0.0
    for name in sweep.summary:
        a, b = np.asarray(batched[name], dtype=float), np.asarray(single[name], dtype=float)
        with np.errstate(all="ignore"):
            rel = np.where(a == b, 0.0, np.abs(a - b) / np.maximum(np.abs(b), 1e-300))
        worst = max(worst, float(np.max(np.where(np.isnan(a) & np.isnan(b), 0.0, rel))))
    return {"system": sweep.scene.system, "points": points, "single_points_per_second": round(points / t_single, 1),
            "batched_points_per_second": round(points / t_batch, 1),
            "batched_by_batch": int(sum(p == "batch" for p in batched["path"])), "worst_relative_difference": worst}


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
    if result.get("integrated"):
        lines += ["", "Systems that integrate, one process, the same points (warm; points per CPU second): one by one "
                  "through the planner against the chunk batched through the compiled stepper",
                  "", "| system | points | one by one, points/s | batched, points/s | answered by the batch | "
                  "largest relative difference |", "|---|---|---|---|---|---|"]
        for r in result["integrated"]:
            lines.append(f"| {r['system']} | {r['points']} | {r['single_points_per_second']:,} | "
                         f"{r['batched_points_per_second']:,} | {r['batched_by_batch']} | "
                         f"{r['worst_relative_difference']:.1g} |")
    return lines + [""]
