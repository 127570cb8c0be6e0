"""``mechderive verify``: check the chapter's claims against the toolkit's derivations."""

from __future__ import annotations

import argparse
import json
import os
import sys
import textwrap
import time
from typing import Iterator

from ..errors import InvalidInputError


def add_parser(sub: "argparse._SubParsersAction") -> None:
    p = sub.add_parser(
        "verify",
        help="check the chapter's equations against the toolkit's derivations",
        description="Run every catalog check (or those of one section) and print a table; "
        "exit status 1 if any check fails.  Statuses: verified (the printed formula agrees with the "
        "derivation), misprint (it does not, and the entry's corrected formula does), constructed (the "
        "claim holds by construction, e.g. a parameter root-found to make it true; the check passes on "
        "independent evidence from the same run, and the row's note says what was constructed — not a "
        "failure), failed (anything else).",
    )
    p.add_argument("--section", metavar="S", help="only this section and its subsections, e.g. 3.2 or 3.5.2")
    p.add_argument("--json", action="store_true", help="print the rows as a JSON list instead of a table")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="check the claims in N processes, one section at a time each (default: the number of "
                        "cores, at most 8; 1 runs them in this process); the rows and verdicts are the same "
                        "and in the same order whatever N")
    p.add_argument("--fresh", action="store_true",
                   help="run every check even if this package (same source, same SymPy, NumPy, mpmath) has "
                        "verified the same claims before; by default such a table is replayed from the disk cache")
    p.set_defaults(run=run_cached)


def run_cached(args: argparse.Namespace) -> int:
    """:func:`run`, or its table replayed: the verdicts are a function of the package's source and the versions
    of its dependencies (the disk cache's fingerprint), so an unchanged package need not check again;
    ``--fresh`` does, and a table with a failed claim is never stored."""
    if args.fresh:
        return run(args)
    from ..catalog.registry import all_claims
    from .replay import cached

    # the claims themselves are part of the key: a catalog changed at run time (a test's) is not replayed
    claims = [(c.equation, c.section, c.statement, c.method) for c in all_claims(args.section)]
    return cached("verify", args, run, ignore=("jobs", "fresh"), parts=(claims,),
                  replayed="mechderive: verify: this table was computed by this very package before (same source "
                           "and dependencies) and is replayed from the disk cache; --fresh checks again")


def run(args: argparse.Namespace) -> int:
    from ..catalog.registry import STATUSES, all_claims

    claims = all_claims(args.section)
    if not claims:
        sections = sorted({c.section for c in all_claims()}, key=lambda s: tuple(int(x) for x in s.split(".")))
        raise InvalidInputError(f"expected a section among {', '.join(sections)}, got {args.section!r}")
    jobs = _jobs(args.jobs)
    start = time.perf_counter()
    rows = []
    for row in (_in_process(claims) if jobs == 1 else _in_parallel(claims, jobs, args.section)):
        rows.append(row)
        if not args.json:
            _print_row(row)
    total = time.perf_counter() - start
    failed = sum(r.status == "failed" for r in rows)
    if args.json:
        json.dump([r.as_dict() for r in rows], sys.stdout, indent=1, ensure_ascii=False)
        print()
    else:
        counts = ", ".join(f"{sum(r.status == s for r in rows)} {s}" for s in STATUSES)
        print(f"\n{len(rows)} claims: {counts} in {total:.1f} s")
        for r in rows:
            if r.status != "verified":
                head = f"{r.status} — {r.note};" if r.note else f"{r.status}:"
                print(f"  ({r.equation}) {head} {r.detail}")
    return 1 if failed else 0


def _jobs(given: int | None) -> int:
    if given is None:
        return max(1, min(os.cpu_count() or 1, 8))
    if not 1 <= given <= 64:
        raise InvalidInputError(f"--jobs: expected an integer in [1, 64], got {given}")
    return given


def _in_process(claims: list) -> Iterator:
    from ..catalog.registry import run_claims

    for claim in claims:
        yield from run_claims(claims=[claim])


def _section_rows(section: str | None, indices: list[int]) -> list:
    """The rows of the claims at ``indices`` of the catalog (``section``'s): one worker's share."""
    from ..catalog.registry import all_claims, run_claims

    claims = all_claims(section)
    return run_claims(claims=[claims[i] for i in indices])


def _in_parallel(claims: list, jobs: int, section: str | None) -> Iterator:
    """The rows in catalog order, computed in ``jobs`` processes: the claims of one section go to one
    process (they share its derivations), the largest sections first; each row is yielded as soon as it
    and every row before it are done."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    groups: dict[str, list[int]] = {}
    for i, claim in enumerate(claims):
        groups.setdefault(".".join(claim.section.split(".")[:2]), []).append(i)
    order = sorted(groups.values(), key=len, reverse=True)
    done: dict[int, object] = {}
    next_row = 0
    context = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    with ProcessPoolExecutor(max_workers=min(jobs, len(order)), mp_context=context) as pool:
        futures = {pool.submit(_section_rows, section, indices): indices for indices in order}
        from concurrent.futures import as_completed

        for future in as_completed(futures):
            for i, row in zip(futures[future], future.result()):
                done[i] = row
            while next_row in done:
                yield done.pop(next_row)
                next_row += 1


_HEADER_DONE = False


def _print_row(r) -> None:
    global _HEADER_DONE
    if not _HEADER_DONE:
        print(f"{'equation':<22} {'section':<7} {'method':<11} {'status':<11} {'sec':>6}  claim")
        print("-" * 102)
        _HEADER_DONE = True
    claim = textwrap.shorten(r.claim, 90, placeholder="…")
    print(f"{r.equation:<22} {r.section:<7} {r.method:<11} {r.status:<11} {r.seconds:6.2f}  {claim}", flush=True)
