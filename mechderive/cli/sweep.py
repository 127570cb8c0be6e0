"""``mechderive sweep``: a scene over a grid or a random sample of its values (see :mod:`mechderive.sweeps`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def add_parser(sub: "argparse._SubParsersAction") -> None:
    p = sub.add_parser(
        "sweep",
        help="compute per-motion quantities over a grid or a random sample of a scene's values (a map)",
        description="Read SWEEP (a scene with a [sweep] table: grid = {key = [start, stop, count], ...} or "
        "random = {samples = N, seed = S, key = [low, high], ...}, and summary = [...]) and write one row per "
        "point: the swept values, each per-motion quantity with its measured estimate, error_estimate, status "
        "(ok, or refused: why) and path (batch: NumPy over the chunk; point: the planner, one by one).  The table "
        "is the same bit for bit whatever --workers or --dask; chunks are written to OUT.parts/ as they finish, "
        "and --resume continues an interrupted sweep from them.",
    )
    p.add_argument("sweep", metavar="SWEEP", help="the sweep file (TOML)")
    p.add_argument("-o", "--output", metavar="OUT", required=True, help="the table: .csv, .npz or .parquet")
    p.add_argument("--plot", metavar="PNG", help="draw the map of the first quantity (needs mechderive[plot])")
    p.add_argument("--plot-quantity", metavar="NAME", help="the quantity --plot draws (default: the first)")
    p.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: every core)")
    p.add_argument("--dask", metavar="ADDRESS", help="run the chunks on a Dask cluster: a scheduler's address "
                   "(tcp://host:8786) or local:N for a LocalCluster of N workers (needs mechderive[cluster])")
    p.add_argument("--resume", action="store_true", help="continue from the chunks in OUT.parts/")
    p.add_argument("--json", action="store_true", help="print the run's report as JSON")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..scenes.progress import Progress
    from ..sweeps.run import run_sweep
    from ..sweeps.spec import load_sweep
    from ..sweeps.table import check_output

    sweep = load_sweep(Path(args.sweep))
    output = check_output(args.output)
    quantity = args.plot_quantity or sweep.summary[0]
    if args.plot_quantity and args.plot_quantity not in sweep.summary:
        from ..errors import InvalidInputError

        raise InvalidInputError(f"sweep --plot-quantity: expected one of the sweep's summary "
                                f"({', '.join(sweep.summary)}), got {args.plot_quantity!r}")
    with Progress(sweep.points, label=f"sweep {sweep.name or Path(args.sweep).stem}", rate_unit="points") as bar:
        result = run_sweep(sweep, output, workers=args.workers, dask=args.dask, resume=args.resume,
                           progress=lambda done, total: bar.update(done - bar.done))
    if args.plot:
        from ..sweeps.plot import plot_map

        plot_map(result.table, [a.name for a in sweep.axes], quantity, args.plot, units=result.report["units"],
                 grid=sweep.kind == "grid")
        result.report["plot"] = args.plot
    r = result.report
    if args.json:
        json.dump(r, sys.stdout, indent=1, ensure_ascii=False)
        print()
        return 0
    print(f"{r['points']} points in {r['chunks']} chunks ({r['backend']}): {r['ok']} ok, {r['refused']} refused; "
          f"{r['batched']} batched, {r['one_by_one']} one by one")
    rate = f", {r['points_per_second']:.0f} points/s" if r["points_per_second"] else ""
    resumed = f" ({r['resumed_chunks']} chunks resumed)" if r["resumed_chunks"] else ""
    print(f"{r['seconds']:.2f} s{rate}{resumed} -> {r['output']}" + (f", map {r['plot']}" if args.plot else ""))
    return 0
