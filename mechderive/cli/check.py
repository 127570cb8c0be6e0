"""``mechderive check``: decide a user's formula against a system's derived model.

Exit status: 0 identity or on-shell, 1 false, 2 input error, 3 undecided.
"""

from __future__ import annotations

import argparse
import json
import sys

from ..errors import InvalidInputError

_EPILOG = """\
syntax: plain maths, e.g. 'p_psi = I3*(psi_dot + cos(theta)*phi_dot)'; ^ means **; functions
sin cos tan asin acos atan atan2 sinh cosh tanh exp log sqrt Abs; dt(expr) is the total time
derivative; pi; Euler's number is exp(1).  A claim starting with '-' goes after '--'.

verdicts: identity (holds at every state, derivatives independent), on-shell (holds along every
motion), false (with a counterexample), undecided.  Exit status 0, 0, 1, 3; 2 for an input error.
Counterexamples are looked for among real bodies (free top: positive moments obeying the triangle
inequalities; heavy top: I1 >= M l^2 + I3/2), as the solvers require; --any-moments lifts that.
A numeric agreement counts only when the digits resolve every scale in the claim; an overflow or
a difference below the working precision is undecided, never an identity.

SYSTEM is a system of the registry that has check symbols (`mechderive scenes --systems`) or a scene
file ending .toml (the system it configures; --parameters puts its [parameters] in as --given).

examples:
  mechderive check heavy_top --symbols
  mechderive check heavy_top 'dt(E) = 0'
  mechderive check heavy_top 'phi_dot = (b - a*cos(theta))/sin(theta)**2'
  mechderive check free_top 'dt(omega1) = Omega*omega2' --given 'I2 = I1' --given 'Omega = omega3*(I1 - I3)/I1'
  mechderive check my_top.toml 'dt(E) = 0' --parameters
"""


def add_parser(sub: "argparse._SubParsersAction") -> None:
    p = sub.add_parser(
        "check",
        help="decide whether a formula is an identity, holds on every motion, or is false",
        description="Decide a claim 'LHS = RHS' about a system (one of the registry's, or a scene "
        "file's) against the "
        "toolkit's derived model: exactly where possible, else at random points with 30/60-digit arithmetic.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("system", metavar="SYSTEM", help="a system of the registry, or a scene file "
                                                    "ending .toml")
    p.add_argument("claim", metavar="CLAIM", nargs="?", help="the claim 'LHS = RHS'")
    p.add_argument("--given", metavar="'NAME = EXPR'", action="append", default=[],
                   help="define a new name, or specialise a state variable or parameter (repeatable)")
    p.add_argument("--symbols", action="store_true", help="list the system's symbols with their meanings")
    p.add_argument("--parameters", action="store_true",
                   help="with a scene file: specialise the system's parameters to the scene's [parameters] "
                        "(as --given 'NAME = NUMBER' does; a --given of the same name takes precedence)")
    p.add_argument("--json", action="store_true",
                   help="print {verdict, method, detail, counterexample?, assumptions?} as JSON")
    p.add_argument("--points", type=int, default=20, help="random points of the numeric method (≥ 20; default 20)")
    p.add_argument("--seed", type=int, default=20261121, help="seed of the random points")
    p.add_argument("--budget", type=float, default=5.0,
                   help="seconds the whole decision may take, at most 600 (default 5): parsing, expanding dt, "
                   "proofs, random points and simplification stop when it is spent and the verdict is "
                   "undecided (the one-time derivation of the system's model, up to ~4 s, comes before)")
    p.add_argument("--any-moments", action="store_true",
                   help="draw the parameters independently (any positive values), not only real bodies")
    p.set_defaults(run=run)


def _print_symbols(system, as_json: bool) -> None:
    rows = system.describe()
    if as_json:
        json.dump([{"name": n, "kind": k, "meaning": m} for n, k, m in rows], sys.stdout, indent=1, ensure_ascii=False)
        print()
        return
    print(f"{system.name}: {system.summary}")
    width = max(len(n) for n, _, _ in rows)
    for n, k, m in rows:
        print(f"  {n:<{width}}  {k:<10}  {m}")
    print("  pi          constant")


def _print_verdict(v) -> None:
    print(f"{v.verdict} ({v.method})")
    print(f"  {v.detail}")
    if v.counterexample:
        c = v.counterexample
        point = ", ".join(f"{k} = {x}" for k, x in c["point"].items())
        print("  counterexample: " + (point or "(both sides are constants)"))
        if "given" in c:
            print("    given: " + ", ".join(f"{k} = {x}" for k, x in c["given"].items()))
        if "body" in c:
            print("    the body: " + ", ".join(f"{k} = {x}" for k, x in c["body"].items()))
        print(f"    LHS = {c['lhs']}")
        print(f"    RHS = {c['rhs']}")
    for a in v.assumptions:
        print(f"  assumes {a}")


# check() names the argument an error is about by its keyword; here it is an option or a positional.
_OPTIONS = {"given ": "--given ", "points:": "--points:", "seed:": "--seed:", "budget:": "--budget:",
            "any_moments:": "--any-moments:", "system:": "SYSTEM:"}


def _on_the_command_line(message: str) -> str:
    """``message`` with its leading argument named as on the command line (``--given '…': …``)."""
    for keyword, option in _OPTIONS.items():
        if message.startswith(keyword):
            return option + message[len(keyword):]
    return message


def _scene_givens(system, parameters: dict, given: list[str]) -> list[str]:
    """``NAME = NUMBER`` for each scalar scene parameter that is a parameter of ``system`` and not in ``given``."""
    import re

    typed = {m.group(1) for g in given if (m := re.match(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*=", g))}
    out = []
    for name, value in parameters.items():
        if (isinstance(value, (int, float)) and not isinstance(value, bool) and name in system.names
                and system.kind(system.names[name]) == "parameter" and name not in typed):
            out.append(f"{name} = {float(value)!r}")
    return out


def run(args: argparse.Namespace) -> int:
    from ..formulas import check, get_system
    from ..formulas.systems import find_system, is_scene_path

    try:
        try:
            target, parameters = find_system(args.system) if is_scene_path(args.system) else (args.system, {})
            system = get_system(target)
        except InvalidInputError as exc:
            raise InvalidInputError(f"system: {exc}") from None
        if args.parameters and not is_scene_path(args.system):
            raise InvalidInputError(f"--parameters: expected a scene file (SYSTEM ending .toml), got {args.system!r}")
        given = list(args.given)
        if args.parameters:
            given += _scene_givens(system, parameters, given)
        if args.symbols:
            _print_symbols(system, args.json)
            if args.claim is None:
                return 0
        if args.claim is None:
            raise InvalidInputError("CLAIM: expected a claim like 'dt(E) = 0' (or --symbols), got none")
        verdict = check(args.claim, system, given=given, points=args.points, seed=args.seed,
                        budget=args.budget, any_moments=args.any_moments)
    except InvalidInputError as exc:
        message = _on_the_command_line(str(exc))
        if args.json:
            json.dump({"verdict": "error", "method": "none", "detail": message}, sys.stdout, ensure_ascii=False)
            print()
            return 2
        raise InvalidInputError(message) from None
    if args.json:
        json.dump(verdict.as_dict(), sys.stdout, indent=1, ensure_ascii=False)
        print()
    else:
        _print_verdict(verdict)
    return verdict.exit_status
