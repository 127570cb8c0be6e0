"""The ``mechderive`` command line: ``run``, ``scenes``, ``verify``, ``derive``, ``check``, ``bench``, ``stress``."""

from __future__ import annotations

import argparse
import sys
from typing import Sequence

from .. import __version__
from ..errors import MechDeriveError

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mechderive",
        description="Derive, verify and simulate the motion of rigid bodies.",
    )
    parser.add_argument("--version", action="version", version=f"mechderive {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    # Each subcommand module registers itself; imported here, not at package import, so that
    # `import mechderive.cli` stays light.
    from . import bench, check, derive, run, stress, verify

    run.add_parsers(sub)  # run, scenes
    verify.add_parser(sub)
    derive.add_parser(sub)
    check.add_parser(sub)
    bench.add_parser(sub)
    stress.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mechderive`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return int(args.run(args) or 0)
    except MechDeriveError as exc:
        print(f"mechderive: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
