"""The disk cache of ``derive`` and ``check`` answers (issue 14 §5): a warm command replays the stored text
without importing SymPy; the replay is byte-identical to the answer computed; a corrupt entry is
recomputed; undecided verdicts, user systems and standard input are never stored."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mechderive.cli import main

CODE = ("import sys, time; t = time.perf_counter(); from mechderive.cli import main; s = main({argv!r}); "
        "sys.stderr.write(f'{{time.perf_counter() - t}} {{\"sympy\" in sys.modules}}\\n'); sys.exit(s)")


def _run(argv, cache: Path):
    env = {**os.environ, "MECHDERIVE_CACHE_DIR": str(cache)}
    env.pop("MECHDERIVE_NO_DISK_CACHE", None)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CODE.format(argv=argv)], capture_output=True, text=True, env=env)
    seconds, sympy = done.stderr.strip().splitlines()[-1].split()
    return done.stdout, done.returncode, float(seconds), sympy == "True", time.perf_counter() - start


def _run_here(argv, cache: Path, monkeypatch, capsys):
    """The command in this process (its derivations shared with the other tests): (stdout, status)."""
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(cache))
    monkeypatch.delenv("MECHDERIVE_NO_DISK_CACHE", raising=False)
    capsys.readouterr()
    status = main(argv)
    return capsys.readouterr().out, status


@pytest.mark.parametrize("argv, status", [(["derive", "free_top", "euler_equations"], 0),
                                          (["check", "free_top", "dt(T) = 0"], 0)])
def test_a_warm_answer_is_replayed_without_sympy(tmp_path, argv, status, monkeypatch, capsys):
    # computed here (the cold answer need not come from a fresh process: the stored text is the same), then
    # replayed by a fresh process that never imports SymPy
    cold = _run_here(argv, tmp_path, monkeypatch, capsys)
    warm = _run(argv, tmp_path)
    assert cold[1] == warm[1] == status and cold[0] == warm[0] and not warm[3]
    # the replay reads one file: the command itself (timed here, not the interpreter's start) takes ~0.07 s on
    # a quiet machine; the bound is the 0.5 s for the whole process (0.3 s failed once in a fresh venv
    # while the 2-core machine ran another suite)
    assert warm[2] < 0.5


def test_a_cold_process_stores_what_it_computes(tmp_path):
    # the whole path in fresh processes once: a cold one derives (SymPy) and stores, a warm one replays
    argv = ["check", "free_top", "dt(T) = 0"]
    cold, warm = _run(argv, tmp_path), _run(argv, tmp_path)
    assert cold[1] == warm[1] == 0 and cold[0] == warm[0] and cold[3] and not warm[3]


def test_a_corrupt_entry_is_recomputed(tmp_path, monkeypatch, capsys):
    argv = ["derive", "free_top", "euler_equations"]
    first = _run_here(argv, tmp_path, monkeypatch, capsys)
    (entry,) = list(tmp_path.glob("*/text/*.json"))
    good = entry.read_bytes()
    entry.write_bytes(good.replace(b"stdout", b"stdoux"))
    again = _run_here(argv, tmp_path, monkeypatch, capsys)
    assert again == first and entry.read_bytes() == good  # recomputed, the same answer, and stored afresh
    assert _run(argv, tmp_path)[3] is False  # which a fresh process replays without SymPy


def test_what_is_never_stored(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("MECHDERIVE_NO_DISK_CACHE", raising=False)
    # refuted (1) is final and kept; an input error (2) is not
    assert main(["check", "free_top", "dt(T) = 1"]) == 1
    assert main(["check", "free_top", "dt(Q) = 0"]) == 2
    assert len(list(tmp_path.glob("*/text/check-*.json"))) == 1
    capsys.readouterr()
