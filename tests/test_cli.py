"""The command line as a user meets it: options anywhere, exit statuses, no traceback, no partial file.

Issue 11, reproduction 10 and "the CLI never prints a traceback for bad input, a closed pipe
or Ctrl-C, and leaves no partial output file".  Subprocess tests use the suite's disk cache
(conftest), so only the first one derives and compiles the small free-top scene below.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import numpy as np
import pytest

import mechderive.scenes.output as output
import mechderive.scenes.planner as planner
from mechderive.cli import (EXIT_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_PIPE, _subcommand_parsers,
                            build_parser, main, parse_args)
from mechderive.errors import InvalidInputError

from .conftest import ROOT, run_python

# A small free-top scene (ω1 only, 11 samples): derived and compiled once, in this process (``scene``), then
# 0.3 s per subprocess from the suite's disk cache.
SMALL_SCENE = """\
system = "free_top"
[parameters]
I1 = 1.0
I2 = 2.0
I3 = 3.0
[initial]
omega = [1e-6, 1.0, 1e-6]
[time]
t_end = 10.0
samples = 11
[output]
quantities = ["omega1"]
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> str:
    """The small scene's file, its compiled functions put in the suite's disk cache by a run in this process (its
    derivations shared with the other free-top tests here), so no subprocess below derives (~3 s cold)."""
    folder = tmp_path_factory.mktemp("scene")
    path = folder / "small.toml"
    path.write_text(SMALL_SCENE)
    assert main(["run", str(path), "-o", str(folder / "warm.csv")]) == 0
    return str(path)


def _env(*, buffered: bool = True) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env.pop("MECHDERIVE_DEBUG", None)
    # A user's stdout into a pipe is block-buffered: the write that fails may be the final flush.
    env.pop("PYTHONUNBUFFERED", None)
    if not buffered:
        env["PYTHONUNBUFFERED"] = "1"  # every print writes, and fails, at once
    return env


def _run_into_closed_pipe(*args: str, buffered: bool = True) -> subprocess.CompletedProcess:
    """``python -m mechderive *args`` with stdout a pipe nobody reads: every write fails with EPIPE."""
    read_end, write_end = os.pipe()
    os.close(read_end)  # closed before the child starts: deterministic, unlike racing a `head`
    try:
        return subprocess.run([sys.executable, "-m", "mechderive", *args], stdout=write_end, stderr=subprocess.PIPE,
                              cwd=ROOT, env=_env(buffered=buffered), text=True, timeout=120)
    finally:
        os.close(write_end)


# --- python -m mechderive ---------------------------------------------------------------------

def test_python_m_mechderive_runs_the_cli():
    proc = run_python("-m", "mechderive", "--help")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("usage: mechderive ")
    assert "141 output pipe closed" in " ".join(proc.stdout.split())
    version = run_python("-m", "mechderive", "--version")
    assert version.stdout.strip().startswith("mechderive ")


# --- options before, between and after positionals ----------------------------------------------

def test_every_subcommand_parses_intermixed_options():
    # parse_intermixed_args raises TypeError (not a usage error) for a parser it cannot handle.
    parsers = _subcommand_parsers(build_parser())
    assert set(parsers) == {"run", "scenes", "verify", "derive", "check", "bench", "stress", "sweep"}
    for name, parser in parsers.items():
        with pytest.raises(SystemExit) as exc:
            parser.parse_intermixed_args(["--no-such-option"])
        assert exc.value.code == 2, name


def test_a_command_line_builds_the_parser_of_its_own_subcommand_alone():
    from mechderive.cli import COMMANDS

    full = _subcommand_parsers(build_parser())
    assert set(COMMANDS) == set(full)  # the table main dispatches on names every subcommand, no more
    for name in COMMANDS:
        alone = _subcommand_parsers(build_parser(name))
        assert name in alone and set(alone) <= set(full)
        # the same options, help and usage as in the full parser
        assert alone[name].format_help() == full[name].format_help(), name
    # run and scenes come from one module: building `run` does not build `derive`
    assert set(_subcommand_parsers(build_parser("run"))) == {"run", "scenes"}


@pytest.mark.parametrize("argv, expected", [
    (["derive", "heavy_top", "--format", "latex", "lagrangian", "f_u"],
     {"system": "heavy_top", "quantities": ["lagrangian", "f_u"], "format": "latex"}),
    (["derive", "--format", "c", "inertia", "--pivot=-1", "disc", "inertia_pivot"],
     {"system": "inertia", "quantities": ["disc", "inertia_pivot"], "format": "c", "pivot": "-1"}),
    (["derive", "heavy_top", "--moments", "1", "1", "2", "lagrangian"],
     {"moments": ["1", "1", "2"], "quantities": ["lagrangian"]}),
    (["check", "heavy_top", "--json", "dt(E) = 0"], {"system": "heavy_top", "claim": "dt(E) = 0", "json": True}),
    (["check", "--given", "I2 = I1", "free_top", "--json", "--", "-omega1 = 0"],
     {"system": "free_top", "claim": "-omega1 = 0", "given": ["I2 = I1"]}),
    (["run", "-o", "x.csv", "default", "--json"], {"scene": "default", "output": "x.csv", "json": True}),
    (["scenes", "default"], {"name": "default"}),
    (["stress", "--case", "pole", "--quick"], {"case": ["pole"], "quick": True}),
])
def test_options_among_positionals(argv, expected):
    args = parse_args(build_parser(), argv)
    assert args.command == argv[0]
    assert {k: getattr(args, k) for k in expected} == expected


def test_derive_option_among_positionals_prints_the_same(capsys):
    # The issue's `derive heavy_top --format latex lagrangian` is parsed above; printed here with
    # rotation, whose derivation is cheap.
    assert main(["derive", "rotation", "--format", "latex", "R1", "R3"]) == 0
    before = capsys.readouterr().out
    assert main(["derive", "rotation", "R1", "--format", "latex", "R3"]) == 0
    assert capsys.readouterr().out == before
    assert before.count("\\begin{equation}") == 2


def test_top_level_usage_errors_stay_argparse_errors(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["nope"])
    assert exc.value.code == 2
    assert "invalid choice: 'nope'" in capsys.readouterr().err
    assert main([]) == 0
    assert capsys.readouterr().out.startswith("usage: mechderive ")


# --- a closed pipe ----------------------------------------------------------------------------

def test_closed_pipe_exits_141_without_traceback(scene):
    for args, buffered in ((["scenes"], True), (["scenes"], False), (["run", scene, "--json"], True)):
        proc = _run_into_closed_pipe(*args, buffered=buffered)
        assert proc.returncode == EXIT_PIPE, (args, proc.stderr)
        assert proc.stderr == "", (args, proc.stderr)  # not even "Exception ignored ... BrokenPipeError"


def test_head_reading_one_line(scene):
    # `mechderive run --json | head -1`: the reader may close before or after the last write;
    # either way no traceback (0 if everything fit in the pipe before it closed, else 141).
    proc = subprocess.Popen([sys.executable, "-m", "mechderive", "run", scene, "--json"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=ROOT, env=_env())
    assert proc.stdout.readline().strip() == b"{"
    proc.stdout.close()
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.wait(timeout=120) in (0, EXIT_PIPE), err
    assert "Traceback" not in err and "BrokenPipeError" not in err, err


def test_broken_pipe_in_process(monkeypatch, capsys):
    def closed(*_args, **_kw):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr("mechderive.cli.run.scenes", closed)  # bound by build_parser, inside main
    assert main(["scenes"]) == EXIT_PIPE
    assert capsys.readouterr().err == ""


# --- Ctrl-C, internal errors, bad input: one line, the right status, no file ------------------------

def _fail_in_solve(monkeypatch, exc: BaseException) -> None:
    def run_scene(*_args, **_kw):
        raise exc

    monkeypatch.setattr(planner, "run_scene", run_scene)


def test_ctrl_c_while_solving(monkeypatch, capsys, tmp_path, scene):
    _fail_in_solve(monkeypatch, KeyboardInterrupt())
    assert main(["run", scene, "-o", str(tmp_path / "out.csv")]) == EXIT_INTERRUPTED
    assert capsys.readouterr().err == "mechderive: interrupted\n"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_ctrl_c_while_writing_leaves_no_file(monkeypatch, capsys, tmp_path, suffix, scene):
    """Interrupted halfway through the table: no file, no temporary file; an old table survives intact."""
    real_write = output._write_atomically

    def interrupted(path, write, *rest):
        def half(f):
            f.write(b"t,omega1\n0.0,")  # some bytes reach the temporary file first
            raise KeyboardInterrupt

        real_write(path, half, *rest)

    monkeypatch.setattr(output, "_write_atomically", interrupted)
    target = tmp_path / f"out{suffix}"
    assert main(["run", scene, "-o", str(target)]) == EXIT_INTERRUPTED
    assert capsys.readouterr().err.endswith("mechderive: interrupted\n")
    assert list(tmp_path.iterdir()) == []
    target.write_bytes(b"old table")
    assert main(["run", scene, "-o", str(target)]) == EXIT_INTERRUPTED
    assert [p.name for p in tmp_path.iterdir()] == [target.name]
    assert target.read_bytes() == b"old table"


def test_internal_error_is_one_line(monkeypatch, capsys, tmp_path, scene):
    _fail_in_solve(monkeypatch, ZeroDivisionError("float division by zero"))
    assert main(["run", scene, "-o", str(tmp_path / "out.npz")]) == EXIT_INTERNAL
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("mechderive: internal error: ZeroDivisionError: float division by zero -- this is a bug")
    assert "MECHDERIVE_DEBUG=1" in err
    assert list(tmp_path.iterdir()) == []


def test_debug_variable_prints_the_traceback(monkeypatch, capsys, scene):
    _fail_in_solve(monkeypatch, ZeroDivisionError("float division by zero"))
    monkeypatch.setenv("MECHDERIVE_DEBUG", "1")
    assert main(["run", scene]) == EXIT_INTERNAL
    err = capsys.readouterr().err
    assert err.startswith("Traceback (most recent call last):")
    assert err.splitlines()[-1].startswith("mechderive: internal error: ZeroDivisionError")


@pytest.mark.parametrize("argv, message", [
    (["-o", "{tmp}/missing/out.csv"],
     r"-o '.*missing/out\.csv': expected an existing directory, got '.*missing'"),
    (["-o", "{tmp}/out.txt"], r"-o '.*out\.txt': expected a suffix \.csv or \.npz, got '\.txt'"),
    (["-o", "{tmp}/dir.csv"], r"-o '.*dir\.csv': expected a file name, got a directory"),
    (["--plot", "{tmp}/out.jpg"], r"--plot '.*out\.jpg': expected a suffix \.png, \.pdf, \.svg, got '\.jpg'"),
    (["--plot", "{tmp}/missing/out.png"], r"--plot '.*out\.png': expected an existing directory"),
])
def test_bad_output_target_refused_before_solving(monkeypatch, capsys, tmp_path, argv, message, scene):
    import re

    _fail_in_solve(monkeypatch, AssertionError("solved before checking the output target"))
    (tmp_path / "dir.csv").mkdir()
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(["run", scene, *argv]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert err.startswith("mechderive: error: ") and err.count("\n") == 1, err
    assert re.search(message, err), err


def test_unwritable_directory_refused(tmp_path, monkeypatch):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    if os.name != "posix" or os.geteuid() == 0:
        # root (as in CI) writes anywhere: the permission check is then shown a directory it may not write
        real_access = os.access
        monkeypatch.setattr(os, "access", lambda path, mode, *a, **k: False if os.fspath(path) == os.fspath(locked)
                            and mode & os.W_OK else real_access(path, mode, *a, **k))
    with pytest.raises(InvalidInputError, match=r"expected a directory you may write to, got '.*locked'"):
        output.check_output_path(locked / "out.csv", output.TABLE_SUFFIXES)


# --- the files themselves ---------------------------------------------------------------------

def test_table_gets_the_mode_a_plain_write_would(tmp_path):
    # mkstemp's 0o600 used to make every table private; the umask decides, as for open(..., "w").
    plain = tmp_path / "plain.csv"
    plain.write_text("")
    written = output.write_table(tmp_path / "t.csv", np.arange(3.0), {"x": np.ones(3)})
    assert written.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777


def test_write_failure_names_the_file(tmp_path, monkeypatch):
    def full(*_args, **_kw):
        raise OSError(28, "No space left on device")

    with pytest.raises(InvalidInputError, match=r"output file '.*t\.npz': could not write it: No space left on device"):
        with output.atomic_output(tmp_path / "t.npz") as tmp:
            tmp.write_bytes(b"partial")
            full()
    assert list(tmp_path.iterdir()) == []


def test_plot_interrupted_leaves_no_file(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    from mechderive.scenes.plot import plot_scene

    def half(self, fname, **_kw):
        with open(fname, "wb") as f:
            f.write(b"\x89PNG partial")
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", half)
    t = np.linspace(0.0, 1.0, 5)
    with pytest.raises(KeyboardInterrupt):
        plot_scene("falling_cat", {"t": t, "flip_angle": t}, tmp_path / "cat.png")
    assert list(tmp_path.iterdir()) == []


def test_namespace_carries_the_command():
    args = parse_args(build_parser(), ["scenes"])
    assert isinstance(args, argparse.Namespace) and args.command == "scenes" and args.name is None


@pytest.mark.parametrize("argv,named", [
    (["check", "heavy_top", "E = E", "--budget", "abc"], "check: argument --budget"),
    (["run", "--bogus"], "run: unrecognized arguments: --bogus"),
    (["frob"], "invalid choice: 'frob'"),
    (["derive", "heavy_top", "--pivot"], "derive: argument --pivot"),
])
def test_usage_errors_are_one_line_naming_the_argument(argv, named, capsys):
    """argparse's own errors (usage text plus a line) are one line like every other input error: exit 2."""
    from mechderive.cli import main

    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert err.count("\n") == 1 and err.startswith("mechderive: error: ") and named in err, err
