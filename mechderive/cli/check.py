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
    p.add_argument("--file", metavar="FILE", default=None,
                   help="check every claim of FILE in one process: one per line, blank lines and # comments "
                        f"ignored, at most {MAX_FILE_CLAIMS} claims ('-' reads standard input); a summary "
                        "follows, and the exit status is that of the worst verdict")
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
    p.set_defaults(run=run_cached)


#: Claims a ``--file`` may hold: each is decided within its own --budget, so 1000 take at most ~1.4 hours.
MAX_FILE_CLAIMS = 1000
#: The exit status of a run of claims is the worst one: false (1) before undecided (3) before holds (0).
_SEVERITY = {0: 0, 3: 1, 1: 2, 2: 3}


def _claims_of(source: str) -> list[tuple[int, str]]:
    """(line number, claim) of a claims file read as data (never evaluated): ``#`` starts a comment."""
    if source == "-":
        text = sys.stdin.read(1_000_001)
        if len(text) > 1_000_000:
            raise InvalidInputError("--file -: expected at most 1000000 characters, got more")
    else:
        from pathlib import Path

        from ..scenes.schema import _read_file

        try:
            text = _read_file(Path(source), repr(source))
        except InvalidInputError as exc:
            raise InvalidInputError("--file " + str(exc).removeprefix("scene ")) from None
    claims = [(n, line.split("#", 1)[0].strip()) for n, line in enumerate(text.splitlines(), 1)]
    claims = [(n, c) for n, c in claims if c]
    if not claims:
        raise InvalidInputError(f"--file {source!r}: expected at least one claim (one per line), got none")
    if len(claims) > MAX_FILE_CLAIMS:
        raise InvalidInputError(f"--file {source!r}: expected at most {MAX_FILE_CLAIMS} claims, got {len(claims)}")
    return claims


def _run_file(args: argparse.Namespace, system, given: list[str]) -> int:
    """Decide every claim of ``--file``; one line per claim (or a JSON list), then the counts."""
    import time

    from ..formulas import check

    start, records, worst = time.perf_counter(), [], 0
    for line, claim in _claims_of(args.file):
        try:
            v = check(claim, system, given=given, points=args.points, seed=args.seed, budget=args.budget,
                      any_moments=args.any_moments)
            record = {"line": line, "claim": claim, **v.as_dict()}
            status = v.exit_status
        except InvalidInputError as exc:  # this line only: the others are still decided
            record = {"line": line, "claim": claim, "verdict": "error", "method": "none",
                      "detail": _on_the_command_line(str(exc))}
            status = 2
        worst = max(worst, status, key=_SEVERITY.__getitem__)
        records.append(record)
        if not args.json:
            print(f"{line:>4}  {record['verdict']:<9} {claim}")
            if record["verdict"] not in ("identity", "on-shell"):
                print(f"        {record['detail']}")
    counts: dict[str, int] = {}
    for r in records:
        counts[r["verdict"]] = counts.get(r["verdict"], 0) + 1
    seconds = time.perf_counter() - start
    if args.json:
        json.dump({"claims": records, "summary": counts, "seconds": round(seconds, 3)}, sys.stdout, indent=1,
                  ensure_ascii=False)
        print()
    else:
        print(f"{len(records)} claims in {seconds:.2f} s: " + ", ".join(f"{n} {k}" for k, n in counts.items()))
    return worst


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


def run_cached(args: argparse.Namespace) -> int:
    """:func:`run`, or its answer replayed from the disk cache: finished verdicts only (status 0 or 1),
    never one the time budget left undecided."""
    from .replay import cached

    return cached("check", args, run, keep=(0, 1), files=("file",))


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
            if args.claim is None and args.file is None:
                return 0
        if args.file is not None:
            if args.claim is not None:
                raise InvalidInputError(f"--file: expected either a CLAIM or --file, got both (CLAIM {args.claim!r})")
            return _run_file(args, system, given)
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
