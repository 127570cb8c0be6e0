"""Shared fixtures: global numeric state is reset around every test (STYLE.md habit 11)."""

from __future__ import annotations

import atexit
import functools
import gc
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import mpmath
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent

# Compiled code goes to a disk cache; the suite uses its own, never the user's ~/.cache, and removes
# it when the session ends (mkdtemp makes it 0700, as the cache requires of its folders).
if not os.environ.get("MECHDERIVE_CACHE_DIR"):
    os.environ["MECHDERIVE_CACHE_DIR"] = tempfile.mkdtemp(prefix="mechderive-test-cache-")
    atexit.register(shutil.rmtree, os.environ["MECHDERIVE_CACHE_DIR"], ignore_errors=True)


@pytest.fixture(autouse=True)
def _reset_mpmath_precision():
    dps = mpmath.mp.dps
    yield
    mpmath.mp.dps = dps


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator: random cases are reproducible."""
    return np.random.default_rng(20261121)


def run_python(*args: str, timeout: float = 300, env: dict | None = None) -> subprocess.CompletedProcess:
    """Run ``python *args`` from the repository root with the package importable (``env`` adds variables)."""
    env = {**os.environ, **(env or {})}
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return subprocess.run([sys.executable, *args], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=timeout)


def warm_run_report(code: str) -> dict:
    """Run ``code`` twice in fresh processes, the first warming the disk cache; the JSON the second prints last."""
    run_python("-c", code)
    done = run_python("-c", code)
    assert done.returncode == 0, done.stderr
    import json

    return json.loads(done.stdout.strip().splitlines()[-1])


from mechderive.catalog.registry import evaluate as _EVALUATE  # noqa: E402 - the unpatched one


@functools.cache
def verified(claim):
    """The catalog's verdict on ``claim``, checked once per test process (the catalog is verified once per
    session, not once per test that reads it: test_catalog, the derivation scripts, the section files).

    Only for unmodified claims: a test that plants an error calls ``evaluate`` itself."""
    return _EVALUATE(claim)


@pytest.fixture
def claims_checked_once(monkeypatch):
    """Make ``run_claims`` (the derivation scripts', the section tests') read :func:`verified`."""
    from mechderive.catalog import registry

    monkeypatch.setattr(registry, "evaluate", verified)


#: the groups that take longest (measured 2026-11-28, 90 s to 7 s each), started first
LONGEST_GROUPS = ("catalog", "tests.test_s3_6_closed_form", "tests.test_sweep", "tests.test_package",
                  "tests.test_bench", "tests.test_heavy_top_integrate", "tests.test_stress",
                  "tests.test_sweep_plot", "tests.test_lagrangian_system", "tests.test_prefetch")


#: node-id parts of the tests outside the catalog's group that derive the falling cat: test_derive's formats (its
#: LaTeX and code tests loop over every system, the cat's included) and the deformable modules' doctests
_DERIVES_THE_CAT = ("tests/test_derive.py::", "[mechderive.systems.deformable")

#: module -> the group it joins: files that derive the same systems (SymPy, ~1 s each) run in one worker
SHARED_GROUPS = {
    # Kepler's and the precessing orbit's reductions in t and along φ, the cn-form system's (test_central_force_...)
    "tests.test_s3_6_closed_form_in_time": "tests.test_s3_6_closed_form",
    "tests.test_s3_6_closed_form_in_time_bounds": "tests.test_s3_6_closed_form",
    "tests.test_s3_6_closed_form_printed": "tests.test_s3_6_closed_form",
    # the scans of the package's source share its parsed syntax trees (tests/_package_sources.py)
    "tests.test_layers": "tests.test_package",
    "tests.security.test_injection": "tests.test_package",
    # files that derive what the catalog's claims derive (the bodies' inertia, the heavy and free tops' f(u),
    # rates and stability, the kinematics; the docstrings' examples of those modules): derived in one worker,
    # not in both (measured with each test's new derivations, 2026-11-28: ~16 s of derivation they shared)
    "tests.test_s3_2_inertia": "catalog",
    "tests.test_s3_6_heavy_top_derivations": "catalog",
    "tests.test_s3_3_s3_4_free_tops": "catalog",
    "tests.test_s3_1_path_ordered": "catalog",
    "tests.test_doctests": "catalog",
}


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook, which reads the groups
def pytest_collection_modifyitems(config, items):
    # ``--dist loadgroup`` with one group a file: a file's tests run in one worker, so what they derive (a
    # body's inertia, the cat's connection: 40% of the suite's time is SymPy deriving) and their module- or
    # session-scoped references (the bench's --quick run, 30-digit integrations) are built in one process,
    # not in both (measured: 225 → 160 s of derivation in all).  Every test that reads the catalog's
    # verdicts joins test_catalog's group, which checks each claim once (the derivation scripts then replay),
    # and so do the §3.7 tests: the falling cat's connection (~7 s) is derived once, for them and the claims.
    # The tests elsewhere that derive the falling cat (test_derive, its modules' doctests) join them too: the cat
    # is the longest derivation (~7 s), and it was derived in both workers (measured with py-spy).
    group = {}
    for item in items:
        catalog = ("claims_checked_once" in getattr(item, "fixturenames", ())
                   or item.module.__name__ in ("tests.test_catalog", "tests.test_s3_7_deformable")
                   or any(mark in item.nodeid for mark in _DERIVES_THE_CAT))
        group[item] = "catalog" if catalog else SHARED_GROUPS.get(item.module.__name__, item.module.__name__)
        item.add_marker(pytest.mark.xdist_group(group[item]))
    # xdist hands the groups out in collection order: the longest first, so that no long group starts
    # last while the other worker idles (longest-processing-time-first; a stale order costs time, not results)
    items.sort(key=lambda item: LONGEST_GROUPS.index(group[item]) if group[item] in LONGEST_GROUPS
               else len(LONGEST_GROUPS))


class _XdistGroupsOnPytest9:
    """pytest-xdist 3.8 marks a grouped test by appending ``@group`` to ``item._nodeid``; pytest 9 reads a node's id
    from ``item._id`` instead, so the groups never reach the scheduler and ``--dist loadgroup`` acts as ``load``
    (measured: the bench's session fixture built in both workers).  After xdist's hook, carry the suffix over.
    Private attributes of both: on any surprise it does nothing (the tests then run ungrouped, slower, not wrong)."""

    @pytest.hookimpl(trylast=True)
    def pytest_collection_modifyitems(self, config, items):
        try:
            from _pytest.nodeid import NodeId
        except ImportError:  # pytest < 9: xdist's own renaming works
            return
        for item in items:
            legacy = getattr(item, "_nodeid", None)
            if isinstance(legacy, str) and "@" in legacy and "@" not in item.nodeid and hasattr(item, "_id"):
                try:
                    item._id = NodeId.parse(legacy)
                except (AttributeError, TypeError, ValueError):
                    return


def pytest_collection_finish(session):
    # The modules and the collected items (SymPy, SciPy, 3000 tests: most of the heap) live to the end: frozen,
    # the collector never walks them again, and it runs less often (a young generation of 10,000 instead of 700
    # objects).  The suite allocates expression trees by the million; measured on test_catalog + test_s3_2_inertia
    # in one process: 1.7-2.0 s of 46 s in the collector before, 0.7-0.85 s after.
    gc.freeze()
    gc.set_threshold(10_000, 20, 10)


@pytest.hookimpl(hookwrapper=True, tryfirst=True)  # outermost: after xdist has sent the worker's results
def pytest_sessionfinish(session, exitstatus):
    yield
    # An xdist worker has sent its results with "workerfinished" (the controller then ignores how the worker
    # ends).  Freeing the heap of a process that derived half the chapter takes ~1.5 s, and the controller
    # waits for it before printing the summary: the worker leaves at once instead.
    if os.environ.get("PYTEST_XDIST_WORKER") and hasattr(session.config, "workerinput"):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(int(exitstatus))


def pytest_configure(config):
    if hasattr(config, "workerinput"):  # in an xdist worker, where the groups are written into the ids
        config.pluginmanager.register(_XdistGroupsOnPytest9(), "xdist-groups-on-pytest-9")

