"""Cold start of ``mechderive run`` and the time saved by laziness, in fresh processes.

Each measurement is a new ``python`` process running ``mechderive run --json <scene>`` (the CLI's
``main``, as the console script calls it), timed from outside with ``time.perf_counter``; the
``--json`` report gives the stages (parse, derive, compile, solve, drift check, write) and the
process adds interpreter start and imports.  The driver prints afterwards which of SymPy, SciPy,
mpmath and matplotlib ended up imported.

* cold: a fresh, empty ``MECHDERIVE_CACHE_DIR`` — the run derives (SymPy) and compiles;
* warm: the same directory again — the compiled code is read from disk; median of a few runs;
* cache disabled (``MECHDERIVE_NO_DISK_CACHE=1``): every run derives and compiles.

Laziness: the default scene (10 nutation periods, 2001 samples) asking for ``u`` only, against
the same scene asking for every heavy-top quantity.
"""

from __future__ import annotations

import json
import statistics
import tempfile
from pathlib import Path

from ..errors import InvalidInputError
from ._common import package_env, python_subprocess

__all__ = ["cold_start", "laziness", "ALL_HEAVY_QUANTITIES"]

_DRIVER = (
    "import sys\n"
    "from mechderive.cli import main\n"
    "rc = main(sys.argv[1:])\n"
    "sys.stdout.flush()\n"
    "sys.stderr.write('\\n@@imported ' + ','.join(m for m in ('sympy', 'scipy', 'mpmath', 'matplotlib') "
    "if m in sys.modules) + '\\n')\n"
    "sys.exit(rc)\n"
)

ALL_HEAVY_QUANTITIES = ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot", "u", "energy", "p_phi", "p_psi",
                        "omega1", "omega2", "omega3", *(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)),
                        "apex_x", "apex_y", "apex_z")


def _run_cli(args: list[str], **env: str) -> dict:
    wall, out, err = python_subprocess(["-c", _DRIVER, *args], package_env(**env))
    report = json.loads(out)
    marker = [line for line in err.splitlines() if line.startswith("@@imported")]
    imported = marker[-1].split(" ", 1)[1].split(",") if marker and " " in marker[-1] else []
    return dict(wall=wall, timings=report["timings"], derived=len(report["derived"]),
                compiled=[c.rsplit(" (", 1)[-1].rstrip(")") for c in report["compiled"]],
                evaluated=report.get("details", {}).get("evaluated", []),
                imported=[m for m in imported if m])


def _summary(runs: list[dict]) -> dict:
    """The run of median wall time among ``runs`` (its own stage timings), with all walls listed."""
    ordered = sorted(runs, key=lambda r: r["wall"])
    mid = dict(ordered[(len(ordered) - 1) // 2])
    mid["walls"] = [r["wall"] for r in runs]
    mid["wall_median"] = statistics.median(r["wall"] for r in runs)
    return mid


def _warm_run(args: list[str], cache: str) -> tuple[dict, int]:
    """(run, misses): one run on the filled cache ``cache``.  The cache is keyed by the package's source, so
    an edit in between (a working tree shared with others) makes a run cold again: such a run is discarded
    and repeated (at most 3 times), and counted in ``misses``."""
    misses = 0
    while True:
        run = _run_cli(args, MECHDERIVE_CACHE_DIR=cache)
        if "compiled" not in run["compiled"] or misses >= 3:
            return run, misses
        misses += 1


def _warm_runs(args: list[str], n: int, cache: str) -> dict:
    """:func:`_summary` of ``n`` warm runs (see :func:`_warm_run`), with the number of ``misses``."""
    runs, misses = [], 0
    for _ in range(n):
        run, m = _warm_run(args, cache)
        runs.append(run)
        misses += m
    return {**_summary(runs), "misses": misses}


def _interpreter_start() -> float:
    walls = [python_subprocess(["-c", "pass"], package_env())[0] for _ in range(3)]
    return statistics.median(walls)


def cold_start(cache: str, *, quick: bool = False) -> dict:
    """``mechderive run --json`` (default scene) with the empty cache directory ``cache``, then warm runs on it."""
    if Path(cache).exists() and any(Path(cache).iterdir()):
        raise InvalidInputError(f"expected an empty cache directory for the cold run, got {cache!r} with files in it")
    cold = _run_cli(["run", "--json"], MECHDERIVE_CACHE_DIR=cache)
    warm = _warm_runs(["run", "--json"], 1 if quick else 3, cache)
    return dict(interpreter_start=_interpreter_start(), cold=cold, warm=warm)


def _scene_text(quantities: tuple[str, ...]) -> str:
    from ..scenes.builtin import scene_text

    lines = scene_text("default").splitlines()
    out = [f"quantities = {json.dumps(list(quantities))}" if line.startswith("quantities") else line
           for line in lines]
    return "\n".join(out) + "\n"


def laziness(cache: str, *, quick: bool = False) -> dict:
    """The default scene asking for ``u`` only against all quantities: warm cache (``cache``, filled by one
    untimed run of each scene first), and the cache disabled (skipped with ``quick``)."""
    result: dict = {}
    with tempfile.TemporaryDirectory(prefix="mechderive-bench-") as tmp:
        scenes = {"u": Path(tmp) / "u_only.toml", "all": Path(tmp) / "all_quantities.toml"}
        scenes["u"].write_text(_scene_text(("u",)))
        scenes["all"].write_text(_scene_text(ALL_HEAVY_QUANTITIES))
        for path in (scenes["all"], scenes["u"]):
            _run_cli(["run", "--json", str(path)], MECHDERIVE_CACHE_DIR=cache)  # fill the cache, untimed
        repeats = 1 if quick else 3
        warm: dict[str, list] = {key: [] for key in scenes}
        cold: dict[str, list] = {key: [] for key in scenes}
        misses = 0
        for _ in range(repeats):  # interleaved, so a change in the machine's load hits both alike
            for key, path in scenes.items():
                run, m = _warm_run(["run", "--json", str(path)], cache)
                warm[key].append(run)
                misses += m
                if not quick:  # each cold-derivation run costs seconds
                    cold[key].append(_run_cli(["run", "--json", str(path)], MECHDERIVE_NO_DISK_CACHE="1",
                                              MECHDERIVE_CACHE_DIR=cache))
        for key in scenes:
            result[f"{key}_warm"] = {**_summary(warm[key]), "misses": misses}
            if cold[key]:
                result[f"{key}_no_cache"] = _summary(cold[key])
    result["n_quantities_all"] = len(ALL_HEAVY_QUANTITIES)
    return result
