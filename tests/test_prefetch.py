"""Deriving on a second core during a cold start (:func:`mechderive.core.codecache.prefetch`, issue 14 §5):
the same answer as one core, the work logged as done in parallel, and a failing child harmless."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from mechderive.core import codecache


def _cold_run(tmp_path, name: str, **env: str) -> dict:
    environment = {**os.environ, "MECHDERIVE_CACHE_DIR": str(tmp_path / name), **env}
    environment.pop("MECHDERIVE_NO_DISK_CACHE", None)
    out = subprocess.run([sys.executable, "-m", "mechderive.cli", "run", "--json", "-o", str(tmp_path / f"{name}.csv")],
                         capture_output=True, text=True, env=environment, check=True).stdout
    return json.loads(out)


@pytest.mark.skipif(not hasattr(os, "fork") or (os.cpu_count() or 1) < 2, reason="needs fork and two cores")
def test_a_cold_start_on_two_cores_gives_the_one_core_answer(tmp_path, capsys):
    two = _cold_run(tmp_path, "two")
    # the one-core answer: this process's, derived here (or by this session's processes, on one core each)
    from mechderive.cli import main

    assert main(["run", "--json", "-o", str(tmp_path / "one.csv")]) == 0
    one = json.loads(capsys.readouterr().out)
    from mechderive.systems.heavy_top.exact_extended import EXTENDED

    # b ∓ a in the half angle for the extended-precision setup (where longdouble is wider than a double), φ̇ and
    # ψ̇'s partial fractions and rates, the invariants of the drift check
    assert [c for c in two["compiled"] if c.endswith("(parallel)")] == [
        *(["heavy_top.passage_factors (parallel)"] if EXTENDED else []), "heavy_top.precession_fractions (parallel)",
        "heavy_top.spin_fractions (parallel)", "heavy_top.rates_near_poles (parallel)",
        "heavy_top.invariants (parallel)"]
    # the same functions, derived in another process: the same table to the last bit
    assert (tmp_path / "two.csv").read_bytes() == (tmp_path / "one.csv").read_bytes()
    assert two["error_estimate"] == one["error_estimate"]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_a_failing_child_leaves_the_work_to_the_parent(tmp_path, monkeypatch):
    import sympy as sp

    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("MECHDERIVE_NO_DISK_CACHE", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    monkeypatch.setattr("threading.active_count", lambda: 1)  # pytest's own threads: this test forks anyway
    parent = os.getpid()
    x = sp.Symbol("x")

    def build():
        if os.getpid() != parent:
            raise RuntimeError("the child fails")
        return [x], x**2 + 1

    name = f"test.prefetch_failing_{parent}"
    assert codecache.prefetch([(name, build, "numpy")])
    func, _ = codecache.cached_lambdify(name, build)
    assert func(3.0) == [10.0]
    assert codecache.compile_log()[-1][:2] == (name, "compiled")  # built here: the child left no file


def test_parallel_off_derives_in_this_process_alone(tmp_path, monkeypatch):
    import sympy as sp

    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("MECHDERIVE_NO_DISK_CACHE", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    monkeypatch.setattr("threading.active_count", lambda: 1)
    monkeypatch.setenv("MECHDERIVE_PARALLEL", "0")
    x = sp.Symbol("x")
    name = f"test.prefetch_off_{os.getpid()}"
    assert not codecache.prefetch([(name, lambda: ([x], x + 1), "numpy")])  # no child forked
    func, _ = codecache.cached_lambdify(name, lambda: ([x], x + 1))
    assert func(1.0) == [2.0] and codecache.compile_log()[-1][:2] == (name, "compiled")
