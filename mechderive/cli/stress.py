"""``mechderive stress``: the stress cases of principle 5, one row per case (see :mod:`mechderive.stress`)."""

from __future__ import annotations

import argparse
import json
import sys
import time


def add_parser(sub: "argparse._SubParsersAction") -> None:
    p = sub.add_parser(
        "stress",
        help="run the edge cases (separatrix, poles, huge spin, long times, ...) against mpmath references",
        description="Run the stress cases, each against an independent 30-digit mpmath reference, and print "
        "one row per case: worst error / tolerance, conserved-quantity drift, NaN, verdict.  Verdicts: "
        "'met'; 'said so' (the toolkit declared a request unattainable: a pass); 'not met' (silent "
        "inaccuracy, NaN, or valid input refused).  Exit status 1 if any case is not met.",
    )
    p.add_argument("--quick", action="store_true", help="only the bounded subset (about 30 s)")
    p.add_argument("--case", metavar="NAME", action="append",
                   help="only this case, or the cases starting with NAME (e.g. 'pole'); repeatable")
    p.add_argument("--json", action="store_true", help="print the result rows (with every check) as JSON")
    p.add_argument("--list", action="store_true", help="list the cases and exit")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..stress import run_case, select
    from ..stress.core import format_header, format_row

    cases = select(args.case, quick=args.quick)
    if args.list:
        for c in cases:
            print(f"{c.name:<34} {'quick ' if c.quick else '      '}{c.description}")
        return 0
    start = time.perf_counter()
    results = []
    if not args.json:
        print(format_header(), flush=True)
    for case in cases:
        results.append(run_case(case))
        if not args.json:
            print(format_row(results[-1]), flush=True)  # one row per case, as it finishes
    failed = [r for r in results if not r.passed]
    if args.json:
        json.dump([r.as_dict() for r in results], sys.stdout, indent=1, ensure_ascii=False)
        print()
    else:
        counts = {v: sum(r.verdict == v for r in results) for v in ("met", "said so", "not met")}
        print(f"\n{len(results)} cases: {counts['met']} met, {counts['said so']} said so, {counts['not met']} not met "
              f"in {time.perf_counter() - start:.1f} s")
    return 1 if failed else 0
