"""``mechderive bench``: what the toolkit buys over the usual SymPy → lambdify → solve_ivp path, measured.

Five measurements (see each module's docstring for the case and what is timed):

1. heavy-top work–precision (:mod:`.work_precision`): closed form, our DOP853 and splitting, and
   the BASELINE user path (``sympy.physics.mechanics`` → ``lambdify(cse=True)`` → ``solve_ivp``),
   warm and with its derivation cost; speed-ups at comparable error;
2. the same, smaller, for the free asymmetric top;
3. ensemble throughput of the vectorised splitting (:mod:`.ensemble`);
4. cold start of ``mechderive run`` by stage in fresh processes, cold and warm disk cache
   (:mod:`.startup`);
5. the time saved by laziness (a scene asking for ``u`` only against one asking for everything);
6. one's own body through the user path (:mod:`.rigid_body`): an asymmetric heavy top as a ``rigid_body``
   scene against the same body written by hand with ``sympy.physics.mechanics`` → ``solve_ivp``;
7. interactive speed (:mod:`.interactive`), sweeps (:mod:`.sweep`), and the closed forms the toolkit finds
   itself for the issue-16 systems against the compiled DOP853 (:mod:`.closed_forms`).

:func:`check_targets` compares them with the issue's targets (:mod:`.report`).  ``quick=True``:
10 periods, fewer rows, M ≤ 100, no cache-disabled runs, and section 5 only when asked for.  Nothing here is a test: figures are
wall-clock times on whatever machine runs them; compare rows within one run.
"""

from __future__ import annotations

import datetime
import os
import platform
import sys
import tempfile
import time
from typing import Callable

from ..errors import InvalidInputError
from .report import check_targets, format_report, plot_work_precision

__all__ = ["run_benchmarks", "format_report", "plot_work_precision", "check_targets", "SECTIONS"]

SECTIONS = ("heavy_top", "free_top", "ensemble", "cold_start", "laziness", "rigid_body", "interactive", "sweep",
            "closed_forms")


def _versions() -> dict:
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for dist in ("numpy", "scipy", "sympy", "mpmath"):
        try:
            out[dist] = version(dist)
        except PackageNotFoundError:
            out[dist] = "not installed"
    return out


def _load() -> str:
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover - not on every platform
        return "n/a"


def run_benchmarks(*, quick: bool = False, sections: tuple[str, ...] | None = None,
                   log: Callable[[str], None] | None = None) -> dict:
    """Run the benchmark ``sections`` and return every figure as plain data (JSON-ready), with the targets.

    ``sections`` defaults to all of :data:`SECTIONS`, except ``laziness``, ``rigid_body``, ``interactive``, ``sweep`` and
    ``closed_forms``
    (a minute of fresh processes) when ``quick``
    (the first needs a cold derivation of every heavy-top quantity, ~5-10 s, the second the baseline's
    derivation with ``sympy.physics.mechanics``, ~3 s; name them to have them anyway).
    """
    if sections is None:
        sections = tuple(s for s in SECTIONS
                         if not (quick and s in ("laziness", "rigid_body", "interactive", "sweep", "closed_forms")))
    unknown = [s for s in sections if s not in SECTIONS]
    if unknown:
        raise InvalidInputError(f"expected sections among {', '.join(SECTIONS)}, got {unknown[0]!r}")
    say = log or (lambda _msg: None)
    seconds: dict[str, float] = {}
    clock = [time.perf_counter()]

    def lap(name: str) -> None:
        now = time.perf_counter()
        seconds[name] = round(now - clock[0], 3)
        clock[0] = now

    repeat = 1 if quick else 3
    result: dict = {"meta": dict(date=datetime.datetime.now().isoformat(timespec="minutes"), quick=quick,
                                 sections=list(sections),
                                 machine=f"{platform.machine()}, {os.cpu_count()} CPUs, {platform.system()}",
                                 python=platform.python_version(), versions=_versions(), load_before=_load())}
    if "heavy_top" in sections:
        from .work_precision import heavy_top_work_precision

        say("heavy top: work-precision (closed form, DOP853, splitting, baseline user path) ...")
        result["heavy_top"] = heavy_top_work_precision(quick=quick, repeat=repeat)
        lap("heavy_top")
    if "free_top" in sections:
        from .work_precision import free_top_work_precision

        say("free top: work-precision ...")
        result["free_top"] = free_top_work_precision(quick=quick, repeat=repeat)
        lap("free_top")
    if "ensemble" in sections:
        from .ensemble import ensemble_throughput

        say("ensembles: throughput ...")
        result["ensemble"] = ensemble_throughput(quick=quick)
        lap("ensemble")
    if "rigid_body" in sections:
        from .rigid_body import rigid_body_work_precision

        say("rigid_body scene: asymmetric heavy top, user path vs sympy.physics.mechanics ...")
        result["rigid_body"] = rigid_body_work_precision(quick=quick, repeat=repeat)
        lap("rigid_body")
    if "interactive" in sections:
        from .interactive import interactive

        say("interactive: derive, check, run, verify in fresh processes, cold and warm, vs the usual path ...")
        result["interactive"] = interactive(quick=quick)
        lap("interactive")
    if "sweep" in sections:
        from .sweep import sweep_throughput

        say("sweep: points per second, local pool and Dask, 1 and 2 workers ...")
        result["sweep"] = sweep_throughput(quick=quick)
        lap("sweep")
    if "closed_forms" in sections:
        from .closed_forms import closed_form_table

        say("closed forms found by the toolkit: each issue-16 system against the compiled DOP853 ...")
        result["closed_forms"] = closed_form_table(quick=quick)
        lap("closed_forms")
    if "cold_start" in sections or "laziness" in sections:
        from .startup import cold_start, laziness

        with tempfile.TemporaryDirectory(prefix="mechderive-bench-cache-") as cache:
            if "cold_start" in sections:
                say("mechderive run: cold and warm start in fresh processes ...")
                result["cold_start"] = cold_start(cache, quick=quick)
                lap("cold_start")
            if "laziness" in sections:
                say("laziness: u only vs all quantities, in fresh processes ...")
                result["laziness"] = laziness(cache, quick=quick)
                lap("laziness")
    result["meta"]["section_seconds"] = seconds
    result["meta"]["load_after"] = _load()
    result["meta"]["executable"] = sys.executable
    result["targets"] = check_targets(result)
    return result
