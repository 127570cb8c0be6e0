"""Work–precision, throughput and start-up of mechderive against the usual SymPy → lambdify → solve_ivp path.

A thin wrapper around :mod:`mechderive.bench` (the code lives in the package so that an installed
user can run ``mechderive bench``); see benchmarks/README.md for what is compared and how to read it.

    python benchmarks/bench_work_precision.py                  # full run, a few minutes
    python benchmarks/bench_work_precision.py --quick          # 10 periods, fewer rows, ~15 s
    python benchmarks/bench_work_precision.py --plot wp.png    # also the log-log figure (matplotlib)
    python benchmarks/bench_work_precision.py --json           # every figure as JSON
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from mechderive.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main(["bench", *sys.argv[1:]]))
