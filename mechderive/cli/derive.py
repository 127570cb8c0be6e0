"""``mechderive derive``: print the toolkit's derived equations as text, LaTeX, SymPy, Python, C or JSON.

Examples::

    mechderive derive heavy_top                          # L (3.62), (φ̈, θ̈, ψ̈), p_ψ, p_φ, E
    mechderive derive heavy_top f_u p_phi --format latex
    mechderive derive heavy_top --shape solid_cone       # a uniform cone about its apex
    mechderive derive free_top stability_A
    mechderive derive rotation --sequence XYZ --frame space --format python
    mechderive derive angular_velocity --sequence zyx    # lower case: space-fixed, as in SciPy
    mechderive derive inertia solid_cone --pivot 0
    mechderive derive heavy_top --list
    mechderive derive my_top.toml --list                 # a scene file: the system it configures
    mechderive derive my_top.toml energy --parameters    # ... with its [parameters] numbers put in

Formats: ``text`` (unicode), ``latex`` (equation environments for amsmath, dots for rates),
``sympy`` (Python source rebuilding the exact SymPy objects: symbols with their assumptions, then
each object's ``str`` form with exact integers), ``python`` (standalone NumPy functions, cse'd,
argument order and units in each docstring; ``rotation``'s docstring shows the SciPy conversion),
``c`` (C99 functions writing to ``double *out``), ``json`` (text, LaTeX, str and srepr of each).

Nothing is imported from SymPy until the command runs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

FORMATS = ("text", "latex", "sympy", "python", "c", "json")


def add_parser(sub: "argparse._SubParsersAction") -> None:
    p = sub.add_parser(
        "derive",
        help="print derived equations (text, LaTeX, SymPy, Python, C, JSON)",
        description="Print a system's derived quantities: by default its Lagrangian, equations of motion and "
                    "conserved quantities; or the QUANTITY names given (see --list).  Systems: any system of "
                    "the registry (`mechderive scenes --systems`), rotation, angular_velocity, inertia SHAPE, "
                    "or a scene file SCENE.toml (the system it configures).",
    )
    p.add_argument("system", metavar="SYSTEM", help="a system of the registry (mechderive scenes --systems), rotation, "
                                                    "angular_velocity, inertia (then SHAPE first), or a scene file "
                                                    "ending .toml")
    p.add_argument("quantities", metavar="QUANTITY", nargs="*", help="quantities to print (default: the main ones)")
    p.add_argument("--format", default="text", metavar="FORMAT",
                   help=f"one of {', '.join(FORMATS)} (default text)")
    p.add_argument("--list", action="store_true", help="list the quantities with the chapter's equation numbers")
    p.add_argument("--sequence", default="ZXZ", metavar="SEQ",
                   help="Euler sequence, one of the 12 (ZXZ XYX YZY ZYZ XZX YXY XYZ YZX ZXY XZY ZYX YXZ); "
                        "lower case means space-fixed as in SciPy (default ZXZ)")
    p.add_argument("--frame", default=None, metavar="FRAME",
                   help="body (intrinsic, default) or space (extrinsic) axes for the sequence")
    form = p.add_mutually_exclusive_group()
    form.add_argument("--simplify", action="store_true", help="apply sympy.simplify to every result (slow)")
    form.add_argument("--cse", action="store_true", help="print text/LaTeX with common subexpressions pulled out")
    p.add_argument("--shape", default=None, metavar="SHAPE",
                   help="a standard body (solid_cone, disc, ...) whose derived inertia replaces I1, I2, I3 (and l)")
    p.add_argument("--pivot", default=None, metavar="Z",
                   help="pivot (0, 0, Z) on axis 3 in the shape's coordinates, e.g. -h/2 (with --shape)")
    p.add_argument("--moments", nargs=3, default=None, metavar=("I1", "I2", "I3"),
                   help="numeric principal moments (numbers like 1.5, 2e-3 or 1/3; 0 or 1e-300 to 1e300)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=NUMBER", dest="values",
                   help="substitute a number for a symbol (repeatable), e.g. --set g=9.81 (0 or 1e-300 to 1e300)")
    p.add_argument("--parameters", action="store_true",
                   help="with a scene file: substitute its [parameters] numbers for the symbols of those names "
                        "(--set takes precedence)")
    p.add_argument("--at", default=None, metavar="POINT",
                   help="with QUANTITY linearization: the equilibrium or steady motion, e.g. "
                        "\"theta=0.7, phi_dot=2.5\" (coordinates, velocities of cyclic ones or their momenta p_<q>)")
    p.set_defaults(run=run_cached)


def _number(value) -> float | str:
    """A float where ``value`` is a number (evaluated at 30 digits, then rounded once), else its text."""
    import sympy as sp

    x = sp.N(value, 30)
    return float(x) if x.is_real and x.is_number else str(value)


def _linearization(args: argparse.Namespace, target, scene_parameters: dict) -> int:
    """``derive SYSTEM linearization --at POINT``: small oscillations about an equilibrium or a steady motion."""
    import json

    from ..core.linearize import linearization_derivation
    from ..errors import InvalidInputError
    from ..systems import registry

    if args.at is None:
        raise InvalidInputError("derive linearization: expected --at 'name=value, ...' (the equilibrium or steady "
                                "motion), got none")
    if args.format not in ("text", "latex", "json"):
        raise InvalidInputError(f"derive linearization: expected --format text, latex or json, got {args.format!r}")
    system = registry.get(target) if isinstance(target, str) else target
    values = system.parameter_values(scene_parameters) if args.parameters and scene_parameters else None
    _, summary, lin = linearization_derivation(system, args.at, values)
    if args.format == "text":
        sys.stdout.write(summary.rstrip("\n") + "\n")
    elif args.format == "latex":
        sys.stdout.write(lin.latex().rstrip("\n") + "\n")
    else:
        sys.stdout.write(json.dumps({"system": system.name, "at": args.at, "text": summary, "latex": lin.latex(),
                                     "stable": lin.stable, "verdict": lin.verdict,
                                     "frequencies": [_number(f) for f in lin.frequencies],
                                     "growth_rates": [_number(g) for g in lin.growth_rates],
                                     "frequencies_exact": [str(f) for f in lin.frequencies],
                                     "growth_rates_exact": [str(g) for g in lin.growth_rates]}, indent=2) + "\n")
    return 0


def _shape_and_quantities(args: argparse.Namespace, spec) -> tuple[str | None, list[str]]:
    quantities = list(args.quantities)
    shape = args.shape
    if spec.requires_shape and shape is None:
        from ..errors import InvalidInputError
        from ..inertia.bodies import BODIES

        if not quantities or quantities[0] not in BODIES:
            got = quantities[0] if quantities else "none"
            raise InvalidInputError(f"expected a shape after {spec.name}, one of {', '.join(BODIES)}, got {got!r}")
        shape = quantities.pop(0)
    return shape, quantities


def run_cached(args: argparse.Namespace) -> int:
    """:func:`run`, or its answer replayed from the disk cache (:mod:`mechderive.core.textcache`)."""
    from .replay import cached

    return cached("derive", args, run)


def run(args: argparse.Namespace) -> int:
    from ..derive.catalog import system
    from ..derive.formats import render
    from ..derive.options import parse_assignment
    from ..errors import InvalidInputError
    from ..formulas.systems import find_system, is_scene_path

    scene = is_scene_path(args.system)
    # a scene file is read once: its system object and parameters go on
    target, scene_parameters = find_system(args.system) if scene else (args.system, {})
    if list(args.quantities) == ["linearization"]:
        return _linearization(args, target, scene_parameters)
    if args.at is not None:
        raise InvalidInputError("--at: expected with QUANTITY linearization only")
    spec = system(target)
    if args.format not in FORMATS:
        raise InvalidInputError(f"expected a format among {', '.join(FORMATS)}, got {args.format!r}")
    if args.parameters and not scene:
        raise InvalidInputError(f"--parameters: expected a scene file (SYSTEM ending .toml), got {args.system!r}")
    if args.list:
        width = max(len(q) for q in spec.quantities)
        print(f"{spec.name}: {spec.summary}")
        for name, q in spec.quantities.items():
            description, equation = q.description, q.equation
            mark = "*" if name in spec.defaults else " "
            eq = f"({equation})" if equation else ""
            print(f" {mark} {name:<{width}}  {eq:<8}  {description}")
        print("(* printed by default)")
        return 0
    from ..derive.api import derive_entries
    from ..derive.options import CLI_LABELS, Options

    shape, quantities = _shape_and_quantities(args, spec)
    values = dict(parse_assignment(v) for v in args.values)
    # Every text argument is read here, by the whitelist parser, and only what it built goes on:
    # the headers of the output show the parsed values, never the text typed.
    opts = Options(sequence=args.sequence, frame=args.frame, shape=shape, pivot=args.pivot, moments=args.moments,
                   values=values, labels=CLI_LABELS)
    entries = derive_entries(target, quantities or None, sequence=opts.sequence, frame=opts.frame, shape=shape,
                             pivot=opts.pivot, moments=opts.moments, values=opts.values, simplify=args.simplify,
                             labels=CLI_LABELS, scene_parameters=scene_parameters if args.parameters else False)
    shown = {"scene": Path(args.system).name} if scene else {}
    shown.update({"sequence": opts.sequence, "frame": opts.frame} if "sequence" in spec.takes else {})
    shown.update({"shape": shape, "pivot": opts.pivot,
                  "moments": " ".join(map(str, opts.moments)) if opts.moments else None})
    shown.update(opts.values)
    if args.parameters:
        shown["parameters"] = "from the scene"
    sys.stdout.write(render(entries, args.format, system=spec.name, summary=spec.summary, options=shown, cse=args.cse))
    return 0
