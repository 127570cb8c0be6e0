"""The compiled DOP853 (mechderive.solvers.dop853_c) behind integrate_heavy_top / integrate_free_top.

It must be SciPy's DOP853 without the interpreter: the same steps, the same results to rounding, the
same failure modes as clear errors, and a fallback when no C compiler is available.
"""

from __future__ import annotations

import re
import textwrap

import numpy as np
import pytest

from mechderive.core import cbuild
from mechderive.errors import IntegrationError, InvalidInputError
from mechderive.systems.free_top.exact import exact_free_top
from mechderive.systems.free_top.integrate import integrate_free_top
from mechderive.systems.heavy_top.exact import exact_heavy_top
from mechderive.systems.heavy_top.integrate import integrate_heavy_top

from .conftest import run_python

pytestmark = pytest.mark.skipif(not cbuild.c_enabled(), reason="no C compiler on this machine")

HEAVY = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)      # the BASELINE.md top: M g l = 1
LAUNCH = dict(theta=0.5, psi_dot=5.0)


def _blow_up():
    """y' = y², y(0) = 1: y = 1/(1 - t) leaves every bound at t = 1."""
    import sympy as sp

    from mechderive.solvers.dop853_c import compiled_dop853

    y = sp.Symbol("y")
    return compiled_dop853("test_blow_up", lambda: (sp.Matrix([y**2]), [y], []))


# --- 3.6: the heavy top --------------------------------------------------------------------------

def test_heavy_top_compiled_takes_scipys_steps():
    t = np.linspace(0.0, 35.177, 201)  # 10 nutation periods
    c = integrate_heavy_top(HEAVY, LAUNCH, t, rtol=1e-10, estimate_error=False, backend="c")
    s = integrate_heavy_top(HEAVY, LAUNCH, t, rtol=1e-10, estimate_error=False, backend="scipy")
    assert (c.backend, s.backend) == ("c", "scipy")
    # the same tableau, controller and dense output: the evaluation counts agree (SciPy counts a
    # handful of extra calls in its bookkeeping) ...
    assert abs(c.n_evaluations - s.n_evaluations) <= 10
    # ... and the two differ by rounding, far below the tolerance asked for
    assert np.max(np.abs(c.omega - s.omega)) < 1e-10 * 1e-2
    assert np.max(np.abs(c.quaternion - s.quaternion)) < 1e-10 * 1e-2


def test_heavy_top_compiled_against_the_closed_form():
    # the closed form is checked against 30-digit mpmath to 3e-13 (test_s3_6_heavy_top_exact.py)
    top = exact_heavy_top(HEAVY, LAUNCH)
    t = np.linspace(0.0, 10 * top.nutation_period, 401)
    run = integrate_heavy_top(HEAVY, LAUNCH, t, rtol=1e-12)
    exact = top.evaluate(t, ["omega", "R"])
    err_w = np.max(np.abs(run.omega - exact["omega"]))
    err_R = np.max(np.abs(run.R - exact["R"]))
    assert err_w < 1e-9 and err_R < 1e-9           # rtol 1e-12 over 10 periods: ~1e-10 expected
    # the estimate (distance to a run at 1000× tighter rtol) is of the size of the true error
    assert run.angle_error_estimate is not None and err_R < 10 * run.angle_error_estimate + 1e-12
    assert run.n_steps is not None and run.n_steps > 0


def test_heavy_top_compiled_at_the_pole_is_finite():
    # θ = 0 exactly: the (ω, q) state has no singularity there (the Euler-angle RHS returns NaN)
    run = integrate_heavy_top(HEAVY, dict(theta=0.0, theta_dot=0.5, psi_dot=10.0), np.linspace(0, 5, 51),
                              rtol=1e-11, backend="c")
    assert np.all(np.isfinite(run.omega)) and np.all(np.isfinite(run.quaternion))
    assert run.p_psi_drift < 1e-10


# --- 3.4: the free asymmetric top ----------------------------------------------------------------

def test_free_top_compiled_against_the_closed_form():
    sol = exact_free_top([1.0, 2.0, 3.0], [1.0, 0.5, 1.0])
    t = np.linspace(0.0, 10 * sol.polhode_period, 401)
    run = integrate_free_top([1.0, 2.0, 3.0], [1.0, 0.5, 1.0], t, rtol=1e-12, atol=1e-14, backend="c")
    assert run.backend == "c"
    err = np.max(np.abs(run.omega - sol.omega(t)))
    assert err < 1e-9                               # the closed form is within 3e-16 of 30-digit mpmath
    assert err < 10 * run.error_estimate + 1e-13


def test_free_top_torque_needs_the_python_backend():
    with pytest.raises(IntegrationError, match="torque"):
        integrate_free_top([1.0, 2.0, 3.0], [1.0, 0.5, 1.0], [0.0, 1.0], torque=lambda t, w, R: np.zeros(3),
                           backend="c")
    run = integrate_free_top([1.0, 2.0, 3.0], [1.0, 0.5, 1.0], [0.0, 1.0], torque=lambda t, w, R: np.zeros(3))
    assert run.backend == "scipy"


# --- failures are errors, never NaN ----------------------------------------------------------------

def test_blow_up_is_an_integration_error():
    ode = _blow_up()
    y, stats = ode.solve(np.array([0.0, 0.5]), np.array([1.0]), [], 1e-12, 1e-14)
    assert y[-1, 0] == pytest.approx(2.0, rel=1e-10)  # 1/(1 - 0.5)
    with pytest.raises(IntegrationError, match="step size fell below|NaN or infinity"):
        ode.solve(np.array([0.0, 2.0]), np.array([1.0]), [], 1e-10, 1e-12)


def test_step_limit_is_an_integration_error():
    with pytest.raises(IntegrationError, match=r"reach t = 0.9 within max_steps = 5 steps, got to t = 0\.\d+ after "
                                                r"5 steps: .*raise max_steps"):
        _blow_up().solve(np.array([0.0, 0.9]), np.array([1.0]), [], 1e-12, 1e-14, max_steps=5)


# --- a batch of runs: each the single run, bit for bit, with its own status ------------------------------

def test_a_batch_takes_each_points_own_steps_bit_for_bit():
    from mechderive.systems.heavy_top.integrate import _compiled_dop853

    ode = _compiled_dop853()
    rng = np.random.default_rng(15)
    m = 6
    t = np.linspace(0.0, 3.0, 61)
    q = rng.normal(size=(m, 4))
    y0 = np.hstack([rng.normal(size=(m, 3)) * [1, 1, 10], q / np.linalg.norm(q, axis=1, keepdims=True)])
    y0[2, 3:] = [1.0, 0.0, 0.0, 0.0]  # θ = 0 exactly: tracked from z_B = 0
    par = np.array([[HEAVY["I1"] * (1 + 0.5 * rng.random()), HEAVY["I3"], HEAVY["M"], HEAVY["g"], HEAVY["l"]]
                    for _ in range(m)])[:, :ode.n_par]
    rtol = 10.0 ** rng.uniform(-12, -6, m)           # each point its own tolerances, as a rerun asks
    args0 = rng.uniform(-3, 3, (m, 2))
    # small chunks: every point stops and resumes in several calls, which must not change a bit
    batch = ode.solve_batch(t, y0, par, rtol, rtol * 1e-3, track=(3, args0), chunk_evaluations=500)
    assert list(batch.status) == [0] * m and batch.errors == [None] * m
    for i in range(m):
        y, info = ode.solve(t, y0[i], par[i], rtol[i], rtol[i] * 1e-3, track=(3, args0[i]))
        assert y.tobytes() == batch.y[i].tobytes()
        assert info["args"].tobytes() == batch.args[i].tobytes()
        assert (info["nfev"], info["steps"], info["rejected"]) == (batch.nfev[i], batch.steps[i], batch.rejected[i])
        assert np.array_equal(info["near"], batch.near[i]) and np.array_equal(info["closest"], batch.closest[i])


def test_a_point_that_fails_ends_alone_with_the_single_runs_error():
    ode = _blow_up()
    t = np.array([0.0, 0.5, 2.0])
    y0 = np.array([[0.1], [1.0], [np.nan], [0.2], [0.6]])   # 1/(1/y0 - t): 1.0 and 0.6 blow up before t = 2
    batch = ode.solve_batch(t, y0, np.zeros((5, 0)), 1e-12, 1e-14, max_steps=10_000)
    done = [i for i in range(5) if batch.errors[i] is None]
    assert done == [0, 3]
    for i in done:  # y = y0/(1 - y0 t)
        assert batch.y[i, -1, 0] == pytest.approx(y0[i, 0] / (1 - 2 * y0[i, 0]), rel=1e-10)
    for i in (1, 2, 4):
        with pytest.raises(IntegrationError) as single:
            ode.solve(t, y0[i], [], 1e-12, 1e-14, max_steps=10_000)
        assert str(batch.errors[i]) == str(single.value) and batch.status[i] != 0
    steps = ode.solve_batch(t, y0[[0, 4]], np.zeros((2, 0)), 1e-12, 1e-14, max_steps=5)
    assert "within max_steps = 5 steps" in str(steps.errors[1])


def test_backend_names_are_checked():
    with pytest.raises(InvalidInputError, match="backend one of 'auto', 'c', 'scipy'"):
        integrate_heavy_top(HEAVY, LAUNCH, [0.0, 1.0], backend="fortran")
    with pytest.raises(InvalidInputError, match="backend one of 'auto', 'c', 'python' with method='splitting'"):
        integrate_heavy_top(HEAVY, LAUNCH, [0.0, 1.0], method="splitting", step=0.1, backend="scipy")


def test_without_a_compiler_auto_falls_back_and_c_refuses():
    cbuild.set_c_enabled(False)
    try:
        assert integrate_heavy_top(HEAVY, LAUNCH, [0.0, 1.0], estimate_error=False).backend == "scipy"
        with pytest.raises(IntegrationError, match="expected a C compiler"):
            integrate_heavy_top(HEAVY, LAUNCH, [0.0, 1.0], backend="c")
    finally:
        cbuild.set_c_enabled(None)


# --- generated source and cache ----------------------------------------------------------------------

def test_the_tableau_is_printed_exactly():
    from scipy.integrate._ivp import dop853_coefficients as coef

    from mechderive.solvers.dop853_c import _c_array

    for name, values in (("A", coef.A), ("B", coef.B), ("E3", coef.E3), ("E5", coef.E5), ("D", coef.D)):
        text = _c_array(name, values)
        numbers = [float(x) for x in re.findall(r"[-+]?\d[\d.]*(?:e[-+]?\d+)?", text.split("=", 1)[1])]
        assert np.array_equal(np.array(numbers), np.ravel(values)), name  # bit for bit


def test_a_warm_process_neither_derives_nor_compiles(tmp_path):
    code = textwrap.dedent("""
        import sys, numpy as np
        from mechderive.core import cbuild
        from mechderive.systems.heavy_top.integrate import integrate_heavy_top
        run = integrate_heavy_top(dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0), dict(theta=0.5, psi_dot=5.0),
                                  np.linspace(0.0, 10.0, 11), rtol=1e-10)
        print(run.backend, [how for _, how, _ in cbuild.build_log()], "sympy" in sys.modules, "scipy" in sys.modules)
    """)
    env = dict(MECHDERIVE_CACHE_DIR=str(tmp_path), MECHDERIVE_NO_DISK_CACHE="0")
    first = run_python("-c", code, env=env)
    second = run_python("-c", code, env=env)
    assert first.returncode == 0 and second.returncode == 0, first.stderr + second.stderr
    assert first.stdout.split()[:3] == ["c", "['built',", "'built']"]  # the right-hand side, the stepper
    assert second.stdout.split() == ["c", "['disk',", "'disk']", "False", "False"]


def test_an_unwritable_cache_folder_builds_privately(tmp_path, monkeypatch):
    from mechderive.core import codecache
    from mechderive.solvers.dop853_c import compiled_dop853

    blocked = tmp_path / "cache"
    blocked.write_text("a file where the cache folder should be")  # mkdir under it fails
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(blocked))
    codecache.set_disk_cache(True)
    try:
        import sympy as sp

        y = sp.Symbol("y")
        ode = compiled_dop853("test_private_build", lambda: (sp.Matrix([-y]), [y], []))
        out, _ = ode.solve(np.array([0.0, 1.0]), np.array([1.0]), [], 1e-12, 1e-14)
        assert out[-1, 0] == pytest.approx(np.exp(-1.0), rel=1e-11)   # y = e^-t
    finally:
        codecache.set_disk_cache(None)


def test_a_failing_compiler_falls_back_and_says_why(tmp_path, monkeypatch):
    from mechderive.solvers import dop853_c

    fake = tmp_path / "cc"
    fake.write_text("#!/bin/sh\necho 'fake compiler: refusing' >&2\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setenv("CC", str(fake))
    monkeypatch.setenv("MECHDERIVE_NO_DISK_CACHE", "1")  # build privately, so no cached library is found

    import sympy as sp

    y = sp.Symbol("y")
    assert dop853_c.compiled_dop853("test_failing_cc", lambda: (sp.Matrix([-y]), [y], [])) is None
    err = dop853_c.unavailable_error("test_failing_cc")
    assert "fake compiler: refusing" in str(err) and "backend='auto' or 'scipy'" in str(err)
