"""``mechderive run`` and ``mechderive scenes``: solve a scene file, list and print the built-in ones."""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from typing import TYPE_CHECKING

from ..errors import InvalidInputError

if TYPE_CHECKING:  # pragma: no cover
    from pathlib import Path


def add_parsers(sub: "argparse._SubParsersAction") -> None:
    p = sub.add_parser(
        "run",
        help="solve a scene: derive, compile and evaluate only what it asks for",
        description="Solve a scene (a TOML file, or the name of a built-in scene; the default scene when "
        "omitted) and write the requested quantities.  Without -o, prints a summary.",
    )
    p.add_argument("scene", nargs="?", default=None, help="scene file (.toml) or built-in name (see `mechderive scenes`)")
    p.add_argument("-o", "--output", metavar="OUT", help="write the table to OUT.csv or OUT.npz (and the scene's "
                   "[output].summary to OUT.summary.json beside it)")
    p.add_argument("--json", action="store_true", help="print the run's report as JSON")
    p.add_argument("--plot", metavar="PNG", help="draw the motion to PNG (needs the `plot` extra: matplotlib)")
    p.add_argument("--animate", metavar="FILM", help="draw the moving body, ω, L and its traces to FILM.gif (or "
                   ".mp4 with ffmpeg on the PATH); needs the `plot` extra")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the disk cache of compiled code")
    p.set_defaults(run=run)

    s = sub.add_parser("scenes", help="list the built-in scenes, or print one as TOML; list the systems and "
                       "their quantities",
                       description="Without NAME, list the built-in scenes; with NAME, print it as TOML to start from.  "
                       "--systems lists the systems a scene may name, --quantities SYSTEM what a scene of SYSTEM "
                       "may output (name, unit, meaning).")
    s.add_argument("name", nargs="?", default=None)
    s.add_argument("--systems", action="store_true", help="list the systems (built in and registered)")
    s.add_argument("--quantities", metavar="SYSTEM", help="list the quantities of SYSTEM (a system's name, or a scene "
                   "file: its system as the scene defines it), with unit and meaning")
    s.set_defaults(run=scenes)


def _exists(path: str | Path, shown: str) -> bool:
    """Whether ``path`` names something; a name the system cannot look up is the user's error, said so."""
    try:
        os.stat(path)
    except (FileNotFoundError, NotADirectoryError, ValueError):  # ValueError: a NUL character
        return False
    except OSError as exc:  # too long, no permission to search a directory on the way, a loop of links
        raise InvalidInputError(f"scene file {shown}: cannot read it: {exc.strerror or exc}") from exc
    return True


def _suffix(name: str) -> str:
    """pathlib's ``PurePath(name).suffix`` of a name without separators."""
    i = name.rfind(".")
    return name[i:] if 0 < i < len(name) - 1 else ""


def _load(spec: str | None):
    from ..scenes.builtin import DEFAULT, find_builtin, list_scenes, load_builtin
    from ..scenes.output import _shown
    from ..scenes.schema import load_scene

    # the parsed TOML from the disk cache where this very text was read before (no TOML parser imported)
    if spec is None:
        return load_builtin(DEFAULT, cached=True)
    shown = _shown(spec)
    bare = spec not in ("", os.curdir, os.pardir) and os.sep not in spec and not (os.altsep and os.altsep in spec)
    if not bare or _exists(spec, shown) or _suffix(spec) == ".toml":
        # a path (pathlib is imported only here: ~6 ms of a warm run; a bare name is the same path to it)
        from pathlib import Path

        path = Path(spec)
        exists = _exists(path, shown)
        if path.suffix == ".toml" or exists:
            if not exists:
                raise InvalidInputError(f"scene file {shown}: expected an existing file, got no such file")
            return load_scene(path, cached=True)
    text = find_builtin(spec)  # not list_scenes(): that imports every system, the cat's and the Lagrangian's
    if text is not None:
        return load_scene(text, name=spec, cached=True)
    names = [n for n, _ in list_scenes()]
    raise InvalidInputError(f"scene {shown}: expected a .toml file or a built-in scene ({', '.join(names)})")


def _check_targets(args: argparse.Namespace) -> None:
    """Refuse an output or plot file that could not be written before solving, not after."""
    from ..scenes.output import TABLE_SUFFIXES, check_output_path

    if args.output:
        check_output_path(args.output, TABLE_SUFFIXES, what="-o")
    if args.plot:
        import importlib.util

        from ..scenes.plot import PLOT_SUFFIXES

        check_output_path(args.plot, PLOT_SUFFIXES, what="--plot")
        if importlib.util.find_spec("matplotlib") is None:
            raise InvalidInputError("--plot needs matplotlib: pip install 'mechderive[plot]'")


def run(args: argparse.Namespace) -> int:
    own_process = getattr(args, "own_process", False)
    if own_process:
        import gc

        # No collection while NumPy and the planner load: each walks every object loaded so far, and the imports
        # allocate enough to set off dozens (~7% of a warm run's instructions, counted with callgrind).  What they
        # load lives as long as the process: frozen (gc.freeze), so later collections do not walk it either.
        gc.disable()
    try:
        from ..core import codecache
        from ..scenes.planner import run_scene
        from ..scenes.progress import Progress
    finally:
        if own_process:
            gc.freeze()
            gc.enable()

    if args.no_cache:
        codecache.set_disk_cache(False)
    start = time.perf_counter()
    _check_targets(args)
    scene = _load(args.scene)
    if args.output:
        from ..scenes.output import check_free_space

        check_free_space(args.output, scene.samples, 1 + len(scene.quantities), what="-o")
        if scene.summary:  # OUT.summary.json beside the table: refused before solving, like the table
            from ..scenes.output import check_output_path, summary_path

            check_output_path(summary_path(args.output), (".json",), what="-o's summary file")
    if args.animate:
        from ..scenes.animate import check_animation_target

        check_animation_target(args.animate, scene.model)
    parse_s = time.perf_counter() - start
    solve_scene = scene
    if args.plot or args.animate:
        wanted = (scene.model.plot_quantities if args.plot else ()) + (
            scene.model.animation_quantities if args.animate else ())
        extra = tuple(dict.fromkeys(q for q in wanted if q not in scene.quantities))
        solve_scene = dataclasses.replace(scene, quantities=scene.quantities + extra)
    with Progress(3, label=f"{scene.name or 'scene'}") as bar:
        bar.update(1)
        result = run_scene(solve_scene)
        bar.update(1)
        write_start = time.perf_counter()
        columns = result.output_columns()
        if args.output:
            from ..scenes.output import write_table

            write_table(args.output, result.t, columns, what="-o")
            if scene.summary:
                from ..scenes.output import summary_path, write_summary

                write_summary(summary_path(args.output), result.report, _summary_units(scene),
                              what="-o's summary file")
        if args.plot or args.animate:
            _warn_if_undersampled(scene, result)
        if args.plot:
            from ..scenes.plot import plot_result

            plot_result(result, args.plot, title=f"{scene.name or scene.system}", what="--plot")
        if args.animate:
            from ..scenes.animate import animate_result

            animate_result(result, args.animate, title=f"{scene.name or scene.system}")
        bar.update(1)
    report = dict(result.report)
    report["timings"] = {"parse": round(parse_s, 6), **report["timings"],
                         "write": round(time.perf_counter() - write_start, 6),
                         "total": round(time.perf_counter() - start, 6)}
    if args.json:
        from ..scenes.output import report_json

        print(report_json(report))
    else:
        _summary(scene, result, report, args)
    return 0


def _summary(scene, result, report, args) -> None:
    t = result.t
    print(f"scene {scene.name or '(file)'}: {scene.system}, {scene.samples} samples on [{t[0]:g}, {t[-1]:g}] s, "
          f"method {report['method']}")
    for k, v in report.get("details", {}).items():
        if isinstance(v, (int, float, str)) and k != "evaluated":
            print(f"  {k}: {v:.10g}" if isinstance(v, float) else f"  {k}: {v}")
    est = report["error_estimate"]
    print(f"  error estimate: {est:.2g}" if isinstance(est, float) else "  error estimate: not available")
    print("  drift of conserved quantities: " + ", ".join(f"{k} {v:.2g}" for k, v in report["drift"].items()))
    if report.get("note"):
        print(f"  note: {report['note']}")
    if scene.summary:
        _print_summary(scene, report)
    timing = report["timings"]
    print("  seconds: " + ", ".join(f"{k} {v:.3f}" for k, v in timing.items()))
    fresh = sum(not c.endswith("(disk)") for c in report["compiled"])
    print(f"  derived {len(report['derived'])} quantities, compiled {fresh} functions, "
          f"{len(report['compiled']) - fresh} loaded from the disk cache")
    if scene.given_with_units:
        si = {f"[{table}].{k.name}": k.unit for table, keys in (("parameters", scene.model.parameters),
                                                                ("initial", scene.model.initial)) for k in keys}
        values = {**{f"[parameters].{k}": v for k, v in scene.parameters.items()},
                  **{f"[initial].{k}": v for k, v in scene.initial.items()}}
        print("  given with units: " + "; ".join(
            f"{key} = {text} = {_shown_value(values.get(key), si.get(key, ''))}"
            for key, text in scene.given_with_units.items()))
    names = list(scene.quantities)
    shown = result.output_columns()
    heads = [f"{n} [{scene.output_units[n]}]" if n in scene.output_units else n for n in names]
    width = max(12, *(len(n) + 1 for n in heads))
    print("\n" + "t".rjust(10) + "".join(" " + n.rjust(width + 6) for n in heads))
    rows = range(len(t)) if len(t) <= 8 else [0, 1, 2, len(t) // 2, len(t) - 3, len(t) - 2, len(t) - 1]
    for i in rows:
        print(f"{t[i]:10.4f}" + "".join(f" {shown[n][i]:{width + 6}.12g}" for n in names))
    if args.output:
        print(f"\nwrote {args.output}")
        if scene.summary:
            from ..scenes.output import summary_path

            print(f"wrote {summary_path(args.output)}")
    if args.plot:
        print(f"drew {args.plot}")
    if args.animate:
        print(f"drew {args.animate}")


#: fewer samples per period than this and a picture cannot show the motion (a nutation drawn as a polygon)
MIN_SAMPLES_PER_PERIOD = 20


def _warn_if_undersampled(scene, result) -> None:
    """Warn on stderr when the samples are too few to resolve the motion's period (nutation, polhode)."""
    try:
        period = scene.model.period(scene)
    except Exception:  # noqa: BLE001 - a period that cannot be had is no reason to refuse a picture
        period = None
    if period is None or not period > 0:
        return
    import numpy as np

    t = result.t
    per_period = period / float(np.max(np.diff(t))) if len(t) > 1 else 0.0
    if per_period < MIN_SAMPLES_PER_PERIOD:
        print(f"mechderive: warning: {per_period:.3g} samples per period ({period:.4g} s) are too few to draw the "
              f"motion (at least {MIN_SAMPLES_PER_PERIOD}): use [time] samples_per_period = 50, or more samples",
              file=sys.stderr)


def _summary_units(scene) -> dict[str, str]:
    """{name: SI unit} of the scene's per-motion quantities ("" where the system does not know it)."""
    units = {q.name: q.unit for q in scene.model.summaries}
    return {name: units.get(name, "") for name in scene.summary}


def _shown_value(value, unit: str) -> str:
    """A per-motion value as the summary prints it: numbers to 12 digits with their unit, tables inline."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return str(value)
    if isinstance(value, (int, float)):
        unit = "" if unit in ("", "1") else f" {unit}"
        return f"{value:.12g}{unit}"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_shown_value(v, '')}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(f"{x:.12g}" for x in value) + "]" + ("" if unit in ("", "1") else f" {unit}")
    return str(value)


def _print_summary(scene, report) -> None:
    """The scene's per-motion quantities, one per line: value, unit, and the measured estimate (or why not)."""
    units = _summary_units(scene)
    width = max(len(n) for n in scene.summary)
    print("  per-motion quantities:")
    for name in scene.summary:
        value, error = report["summary"][name], report["summary_error"][name]
        if isinstance(error, str):
            extra = f"  ({error})"
        elif isinstance(error, (int, float)) and not isinstance(error, bool):
            extra = f"  (± {error:.2g})"
        else:
            extra = ""
        print(f"    {name:<{width}} = {_shown_value(value, units[name])}{extra}")


def scenes(args: argparse.Namespace) -> int:
    from ..scenes.builtin import list_scenes, scene_text

    if args.systems or args.quantities is not None:
        if args.name is not None:
            raise InvalidInputError(f"scenes: expected NAME or --systems/--quantities, got both ({args.name!r})")
        if args.systems:
            _systems()
        if args.quantities is not None:
            _quantities(args.quantities)
        return 0
    if args.name is None:
        for name, description in list_scenes():
            print(f"{name:<26} {description}")
        return 0
    sys.stdout.write(scene_text(args.name))
    return 0


def _systems() -> None:
    """Each system a scene may name, with its chapter section and what it is (from the registry)."""
    from ..systems import registry

    for name in registry.names():
        system = registry.get(name)
        section = f" ({system.section})" if system.section else ""
        print(f"{name:<14} {system.summary}{section}")


def _quantities(name: str) -> None:
    """What a scene of the system ``name`` (or of a scene file's system) may output: each quantity with its
    unit and meaning."""
    from ..systems import registry

    if name.endswith(".toml"):
        system = _load(name).model  # a family (lagrangian) as the scene defines it
    else:
        system = registry.get(name)
    quantities, summaries = system.quantities, system.summaries
    if not quantities:
        print(f"{name}: the quantities depend on the scene's definition ({', '.join(system.extra_keys)})")
        return
    width = max(len(q.name) for q in quantities + summaries)
    # a quantity without a unit is one the system cannot know it of (a user's Lagrangian): "-", not "1"
    units = max(len(q.unit or "-") for q in quantities + summaries)
    print("[output].quantities (columns, one value per sample):")
    for q in quantities:
        print(f"  {q.name:<{width}}  {q.unit or '-':<{units}}  {q.meaning}")
    if summaries:
        print("[output].summary (per-motion quantities, one value per run):")
        for q in summaries:
            print(f"  {q.name:<{width}}  {q.unit or '-':<{units}}  {q.meaning}")


def quantities_markdown() -> str:
    """The README's list of each registered system's output columns and per-motion quantities (a test keeps
    the README equal to it): name, unit, meaning; systems whose quantities depend on the scene are left out."""
    from ..systems import registry

    lines: list[str] = []
    for name in (n for n in registry.names() if registry.get(n).quantities):
        system = registry.get(name)
        lines += [f"**{name}** — columns (`quantities`): "
                  + ", ".join(f"`{q.name}` ({q.unit or '-'})" for q in system.quantities) + ".", ""]
        if system.summaries:
            lines += [f"| `{name}` per-motion quantity (`summary`) | unit | meaning |", "|---|---|---|"]
            lines += [f"| `{q.name}` | {q.unit or '-'} | {q.meaning.replace('|', chr(92) + '|')} |"
                      for q in system.summaries]
            lines.append("")
    return "\n".join(lines).rstrip("\n") + "\n"
