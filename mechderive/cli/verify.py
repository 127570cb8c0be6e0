"""``mechderive verify``: check the chapter's claims against the toolkit's derivations."""

from __future__ import annotations

import argparse
import json
import sys
import textwrap
import time

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
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..catalog.registry import STATUSES, all_claims, run_claims

    claims = all_claims(args.section)
    if not claims:
        sections = sorted({c.section for c in all_claims()}, key=lambda s: tuple(int(x) for x in s.split(".")))
        raise InvalidInputError(f"expected a section among {', '.join(sections)}, got {args.section!r}")
    start = time.perf_counter()
    rows = []
    for claim in claims:
        rows.extend(run_claims(claims=[claim]))
        if not args.json:
            _print_row(rows[-1])
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


_HEADER_DONE = False


def _print_row(r) -> None:
    global _HEADER_DONE
    if not _HEADER_DONE:
        print(f"{'equation':<22} {'section':<7} {'method':<11} {'status':<11} {'sec':>6}  claim")
        print("-" * 102)
        _HEADER_DONE = True
    claim = textwrap.shorten(r.claim, 90, placeholder="…")
    print(f"{r.equation:<22} {r.section:<7} {r.method:<11} {r.status:<11} {r.seconds:6.2f}  {claim}", flush=True)
