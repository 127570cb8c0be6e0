"""The ``mechderive`` command line: ``run``, ``scenes``, ``verify``, ``derive``, ``check``, ``bench``, ``stress``,
``sweep``.

Options may come before, between or after a subcommand's positional arguments
(``mechderive derive heavy_top --format latex lagrangian``): :func:`main` hands
everything after the subcommand's name to that subcommand's parser through
``argparse``'s ``parse_intermixed_args``.

Exit status (the same for every subcommand; some add their own, e.g. ``check``'s 3):

====  =====================================================================================
0     success
1     a check that was run did not pass (``verify``, ``stress``; ``check``: false)
2     bad input: a usage error, or a :class:`~mechderive.errors.MechDeriveError`, printed
      as one line ``mechderive: error: <what was wrong and what is allowed>``; also an output
      that could not be written (``-o`` on a full disk, stdout on a full disk)
70    an internal error (a bug): one line naming the exception (EX_SOFTWARE of sysexits.h)
130   interrupted by Ctrl-C (128 + SIGINT, what a shell reports for a process killed by it)
141   stdout was closed early, e.g. ``mechderive run --json | head -1`` (128 + SIGPIPE)
143   terminated by SIGTERM while an output file was being written (129: SIGHUP); the
      temporary file was removed first (:class:`mechderive.scenes.output.Terminated`).
      At any other moment these signals end the run as they end any process.
====  =====================================================================================

No traceback is printed for any of these unless ``MECHDERIVE_DEBUG=1`` is set in the
environment.  A closed pipe exits silently with 141, as ``cat`` or ``seq`` killed by
SIGPIPE do, rather than 0: the output was cut short, and for ``verify`` or ``stress``
the remaining checks never ran, so success would be a claim the run cannot make
(``set -o pipefail`` scripts treat it as they treat any other Unix tool).  SIGPIPE
is not restored to its default action instead, because a signal would kill the run
before it can remove the temporary file of an output being written.
"""

from __future__ import annotations

import argparse
import errno
import functools
import os
import sys
from typing import Sequence

# One BLAS thread unless the user chose: NumPy's OpenBLAS starts its thread pool when NumPy is imported
# (`import numpy` 280–325 ms with it, 185–255 ms with one thread, min–median of 10 on the loaded 2-core
# machine; a warm `mechderive run` 495–510 → 391–434 ms), and nothing here multiplies matrices larger than
# a few rows — sweeps spread over processes (--workers), whose BLAS threads would only contend.  Set before
# anything below imports NumPy; the library (`import mechderive`) leaves the environment alone.
if not any(name in os.environ for name in ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")):
    os.environ["OPENBLAS_NUM_THREADS"] = "1"

from .. import __version__  # noqa: E402 - after the BLAS threads are set
from ..errors import MechDeriveError  # noqa: E402
from ..scenes.output import Terminated  # noqa: E402

__all__ = ["main", "build_parser", "parse_args", "EXIT_INPUT", "EXIT_INTERNAL", "EXIT_INTERRUPTED", "EXIT_PIPE"]

EXIT_INPUT = 2
EXIT_INTERNAL = 70
EXIT_INTERRUPTED = 130
EXIT_PIPE = 141

_DEBUG_VARIABLE = "MECHDERIVE_DEBUG"
# Errors of a write that found no room: the output is lost, but mechderive did nothing wrong.
_DISK_FULL = frozenset(getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EFBIG") if hasattr(errno, name))


class _Parser(argparse.ArgumentParser):
    """argparse's parser, except that help and version text that cannot be written is an error
    and a usage error is one line ``mechderive: error: COMMAND: what was wrong (see … --help)``.

    argparse drops an :class:`OSError` while printing (``mechderive --help | head -1``,
    ``--help > /dev/full``) and exits 0; on stdout it now reaches :func:`main`, which
    answers 141 or status 2 as for any other output.  Subcommand parsers inherit the class.
    """

    def error(self, message: str):  # type: ignore[override]
        """A usage error as one line, like every other input error (argparse prints the usage too)."""
        command = self.prog.removeprefix("mechderive").strip()
        where = f"{command}: " if command else ""
        _say(f"mechderive: error: {where}{message} (see `{self.prog} --help`)")
        self.exit(EXIT_INPUT)

    def _print_message(self, message: str, file=None) -> None:  # type: ignore[override]
        if message and file is sys.stdout:
            sys.stdout.write(message)
        else:
            super()._print_message(message, file)

    def _get_formatter(self) -> argparse.HelpFormatter:
        # the width argparse would take from shutil.get_terminal_size (COLUMNS, else the terminal, else 80,
        # less 2): every add_argument makes a formatter, and importing shutil for it cost ~5 ms of each run
        return self.formatter_class(prog=self.prog, width=_columns() - 2)


@functools.cache
def _columns() -> int:
    """The terminal's width in columns as :func:`shutil.get_terminal_size` gives it, without importing shutil
    (once per process: argparse asks at every argument it adds)."""
    try:
        columns = int(os.environ["COLUMNS"])
        if columns > 0:
            return columns
    except (KeyError, ValueError):
        pass
    try:
        return os.get_terminal_size(sys.__stdout__.fileno()).columns or 80
    except (AttributeError, ValueError, OSError):
        return 80


#: each subcommand's name -> the module of this package that registers it (``run`` registers two)
COMMANDS = {"run": "run", "scenes": "run", "verify": "verify", "derive": "derive", "check": "check",
            "bench": "bench", "stress": "stress", "sweep": "sweep"}


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser; with ``only`` (a name of :data:`COMMANDS`), just the subcommands its
    module registers.

    :func:`main` builds the one subcommand a command line names: importing the other modules and building
    their parsers (~8 ms) was waste in every ``mechderive run``.  ``mechderive --help``, ``--version`` and
    an unknown command get the full parser (the list of commands, argparse's "invalid choice" with them).
    """
    parser = _Parser(
        prog="mechderive",
        description="Derive, verify and simulate the motion of rigid bodies.",
        epilog=f"Exit status: 0 success, 1 a check did not pass, 2 bad input, 70 internal error, "
               f"130 interrupted, 141 output pipe closed, 143 terminated.  {_DEBUG_VARIABLE}=1 prints tracebacks.",
    )
    parser.add_argument("--version", action="version", version=f"mechderive {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    # Each subcommand module registers itself; imported here, not at package import, so that
    # `import mechderive.cli` stays light.
    import importlib

    for name in dict.fromkeys(COMMANDS.values()) if only is None else (COMMANDS[only],):
        module = importlib.import_module(f".{name}", __name__)
        (module.add_parsers if name == "run" else module.add_parser)(sub)  # run adds run and scenes
    return parser


def _subcommand_parsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The parser of each subcommand of ``parser``, by name."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def parse_args(parser: argparse.ArgumentParser, argv: Sequence[str]) -> argparse.Namespace:
    """Parse ``argv`` with options allowed anywhere among a subcommand's positionals.

    argparse's own subcommand dispatch parses the rest of the line in one pass, which
    fills all positionals from the first run of them (``derive heavy_top --format latex
    lagrangian`` leaves ``lagrangian`` unrecognised).  So the subcommand's parser is
    called directly with ``parse_intermixed_args``; top-level options (``--help``,
    ``--version``) and unknown commands go through ``parser`` as usual.
    """
    argv = list(argv)
    commands = _subcommand_parsers(parser)
    if argv and argv[0] in commands:
        return commands[argv[0]].parse_intermixed_args(argv[1:], argparse.Namespace(command=argv[0]))
    return parser.parse_args(argv)


def _debug() -> bool:
    return os.environ.get(_DEBUG_VARIABLE, "") not in ("", "0")


def _say(line: str) -> None:
    """One line on stderr, which may itself be closed."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def _traceback_if_debugging() -> None:
    if _debug():
        import traceback

        traceback.print_exc()


def _stdout_to_devnull() -> None:
    """Point stdout's file descriptor at /dev/null, so that the flush at exit cannot fail again.

    The recipe of the Python documentation ("Note on SIGPIPE", module signal).  When stdout
    is not a real file (a test capturing it), there is nothing to redirect.
    """
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
    finally:
        os.close(devnull)


def _flush_stdout_quietly() -> None:
    """Flush what an interrupted or failed command left in stdout's buffer; a closed pipe is no error here."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _stdout_to_devnull()
    except (OSError, ValueError):
        pass


def _stdout_unwritable() -> BaseException | None:
    """The error that flushing stdout raises now, if any (a full disk keeps failing)."""
    try:
        sys.stdout.flush()
    except (OSError, ValueError) as exc:
        return exc
    return None


def _internal_error(exc: BaseException) -> int:
    _flush_stdout_quietly()
    _traceback_if_debugging()
    message = str(exc).strip().splitlines()[0] if str(exc).strip() else "(no message)"
    hint = "" if _debug() else f"; {_DEBUG_VARIABLE}=1 shows the traceback"
    _say(f"mechderive: internal error: {type(exc).__name__}: {message} -- this is a bug in mechderive, "
         f"please report it to its maintainers with the command line{hint}")
    return EXIT_INTERNAL


def _output_failed(exc: OSError) -> int:
    """Standard output could not be written (a full disk, a quota): one line, status 2."""
    _traceback_if_debugging()
    _stdout_to_devnull()  # or the interpreter's final flush fails once more
    _say(f"mechderive: error: standard output: could not write it: {exc.strerror or exc}")
    return EXIT_INPUT


def _skip_final_collection() -> None:
    """Move every object to the collector's permanent generation, which the interpreter's final collections
    skip: after a cold start they walked the SymPy expressions of every derivation, ~0.5 s between the last
    line printed and the exit (measured; 0.04 s frozen).  The process ends right after; what it wrote is
    flushed and closed by then, atexit handlers still run, and the memory goes back to the system anyway."""
    import gc

    gc.freeze()


def _collect_less() -> None:
    """Run the cyclic garbage collector less often (a young generation of 10,000 objects instead of 700): a
    cold start's derivations allocate SymPy expressions by the hundred thousand, nearly all alive to the end
    or freed by reference counting, and the collector's passes over them took 0.11-0.16 s of a one-process
    cold ``run`` (0.07-0.10 s so).  Only for the console script's own process, never for a program that
    imports the package."""
    import gc

    gc.set_threshold(10_000, 20, 10)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``mechderive`` console script; returns the exit status (module docstring).

    argparse's own exits (``--help``, ``--version``, usage errors) still raise
    :class:`SystemExit`, after their output has been flushed; if that output met a closed
    pipe the status is 141 instead.
    """
    try:
        if argv is None:  # the process is this command's alone (see _collect_less)
            _collect_less()
        words = sys.argv[1:] if argv is None else list(argv)
        parser = build_parser(words[0] if words and words[0] in COMMANDS else None)
        args = parse_args(parser, words)
        if args.command is None:
            parser.print_help()
            status = 0
        else:
            args.own_process = argv is None  # the process ends with this command (the console script, python -m)
            status = int(args.run(args) or 0)
        # A reader that went away shows here rather than in the interpreter's final flush,
        # where it could only be reported as "Exception ignored" with exit status 120.
        sys.stdout.flush()
        if argv is None:  # the process ends with this command (the console script, python -m)
            _skip_final_collection()
        return status
    except MechDeriveError as exc:
        _flush_stdout_quietly()
        _traceback_if_debugging()
        _say(f"mechderive: error: {exc}")
        return EXIT_INPUT
    except KeyboardInterrupt:
        _flush_stdout_quietly()
        _traceback_if_debugging()
        _say("mechderive: interrupted")
        return EXIT_INTERRUPTED
    except Terminated as exc:
        _flush_stdout_quietly()
        _traceback_if_debugging()
        _say("mechderive: terminated; the output file being written was removed")
        return int(exc.code)
    except SystemExit:
        # argparse printed help, a version or a usage error and exits: flush here, where a
        # closed pipe or a full disk can still be reported, not in the interpreter's last flush.
        failed = _stdout_unwritable()
        if isinstance(failed, BrokenPipeError):
            _stdout_to_devnull()
            return EXIT_PIPE
        if isinstance(failed, OSError):
            return _output_failed(failed)
        raise
    except BrokenPipeError:
        _traceback_if_debugging()
        _stdout_to_devnull()
        return EXIT_PIPE
    except OSError as exc:
        # Writing stdout failed if it still cannot be flushed; ENOSPC and its kin with nothing
        # left to flush (unbuffered stdout) are the same failure.
        failed = _stdout_unwritable()
        if isinstance(failed, OSError) or exc.errno in _DISK_FULL:
            return _output_failed(failed if isinstance(failed, OSError) else exc)
        return _internal_error(exc)
    except Exception as exc:  # noqa: BLE001 - the last resort: a bug, said in one line
        return _internal_error(exc)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
