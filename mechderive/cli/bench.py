"""``mechderive bench``: work–precision, throughput and start-up figures against the usual path."""

from __future__ import annotations

import argparse
import json
import sys


def add_parser(sub: "argparse._SubParsersAction") -> None:
    p = sub.add_parser(
        "bench",
        help="measure time against error: closed forms, integrators, the SymPy/solve_ivp baseline, start-up",
        description="Benchmark the toolkit against the usual sympy.physics.mechanics -> lambdify -> solve_ivp "
        "path: work-precision tables (heavy and free top), ensemble throughput, the cold and warm start of "
        "`mechderive run`, and the time saved by asking for fewer quantities.  A full run takes a few "
        "minutes; --quick well under half a minute.  Times are wall-clock on this machine: compare rows "
        "within one run.",
    )
    p.add_argument("--quick", action="store_true",
                   help="10 periods, fewer rows, ensembles up to 100 bodies, no laziness section unless --only names it")
    p.add_argument("--plot", metavar="PNG", help="draw the work-precision figure (needs the `plot` extra: matplotlib)")
    p.add_argument("--json", action="store_true", help="print every figure as JSON instead of the tables")
    p.add_argument("--only", metavar="SECTIONS",
                   help="comma-separated subset of heavy_top,free_top,ensemble,cold_start,laziness,rigid_body,"
                        "interactive,sweep")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..bench import SECTIONS, format_report, plot_work_precision, run_benchmarks
    from ..errors import InvalidInputError

    sections = None
    if args.only:
        sections = tuple(s.strip() for s in args.only.split(",") if s.strip())
        bad = [s for s in sections if s not in SECTIONS]
        if bad:
            raise InvalidInputError(f"--only: expected names among {', '.join(SECTIONS)}, got {bad[0]!r}")
    if args.plot and sections is not None and not ({"heavy_top", "free_top"} & set(sections)):
        raise InvalidInputError("--plot: expected heavy_top or free_top among the sections, got neither")
    if args.plot:
        import importlib.util

        from ..scenes.output import check_output_path
        from ..scenes.plot import PLOT_SUFFIXES

        check_output_path(args.plot, PLOT_SUFFIXES, what="--plot")  # before minutes of benchmarks
        if importlib.util.find_spec("matplotlib") is None:
            raise InvalidInputError("--plot needs matplotlib: pip install 'mechderive[plot]'")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    result = run_benchmarks(quick=args.quick, sections=sections, log=log)
    if args.plot:
        from ..scenes.output import atomic_output

        with atomic_output(args.plot, what="--plot") as tmp:  # the figure's format follows tmp's suffix
            plot_work_precision(result, str(tmp))
        result["meta"]["plot"] = args.plot
    if args.json:
        print(json.dumps(result, indent=1, default=str))
    else:
        sys.stdout.write(format_report(result))
        if args.plot:
            print(f"\ndrew {args.plot}")
    return 0
