"""Principle 5, "stable at the edges": the stress cases of ``mechderive stress`` in the test suite.

Every case (mechderive/stress/) compares the toolkit's methods with an independent 30-digit mpmath
integration of hand-written equations.  The ``--quick`` subset runs by default; the rest is
``@pytest.mark.slow`` (``pytest -m slow tests/test_stress.py``).  Cases that reveal a toolkit bug
are ``xfail(strict=True)`` with a one-line reason: when the bug is fixed the test XPASSes, fails,
and the mark is to be removed.
"""

from __future__ import annotations

import json
import math

import mpmath
import numpy as np
import pytest

from mechderive.errors import InvalidInputError
from mechderive.stress import all_cases, run_case, select
from mechderive.stress import reference as ref
from mechderive.stress.core import Case, Collector

# --- known toolkit bugs the cases reveal (see the report of the stress task) ---------------------------

KNOWN_BUGS: dict[str, str] = {}


def _param(case: Case):
    marks = [] if case.quick else [pytest.mark.slow]
    if case.name in KNOWN_BUGS:
        marks.append(pytest.mark.xfail(strict=True, reason=KNOWN_BUGS[case.name]))
    return pytest.param(case, id=case.name, marks=marks)


@pytest.mark.parametrize("case", [_param(c) for c in all_cases()])
def test_stress_case(case):
    result = run_case(case)
    assert result.nan_free, f"NaN/inf in {result.details.get('nan_outputs')}"
    assert result.passed, f"{case.name}: {result.verdict}: {result.reason}"


def test_every_known_bug_names_a_case():
    names = {c.name for c in all_cases()}
    assert set(KNOWN_BUGS) <= names


# --- focused reproductions of bugs (cheap, default run) -------------------------------------------------

def test_heavy_top_theta_dot_at_the_pole_exactly():
    # Regression: the 40-digit root u2 came out as 1 + 4e-40 and 1 - u2 < 0 spoiled θ̇ (7.6e-7 relative).
    from mechderive.systems.heavy_top.exact import exact_heavy_top

    top = exact_heavy_top(dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0), dict(theta=0.0, theta_dot=0.5, psi_dot=10.0))
    # the initial state itself, no reference needed: 1e-13 is the closed form's claimed accuracy
    assert top.theta_dot(0.0) == pytest.approx(0.5, rel=1e-13)


def test_free_top_rotation_at_the_first_saddle_passage():
    # Regression: Π was evaluated through the rounded am u, whose error is amplified by ~1/√(1 - m) here.
    from mechderive.stress.free_cases import SEP_MOMENTS, _R0, separatrix_omega
    from mechderive.systems.free_top.exact import exact_free_top

    w0 = separatrix_omega(-1e-10)  # 1 - m = 1e-10, below (L² < 2T I2); the first saddle is at t ≈ T/4
    sol = exact_free_top(SEP_MOMENTS, w0, R0=np.array(_R0))
    t = np.linspace(0.0, 0.3 * sol.polhode_period, 31)
    reference = ref.free_reference(SEP_MOMENTS, w0, _R0, t)
    np.testing.assert_allclose(sol.omega(t), reference.omega, rtol=0, atol=1e-12)  # ω is fine
    # 1e-12: the closed form's ~1e-13 ×10 (R is well conditioned: Ṙ = hat(ω)R with ω accurate)
    np.testing.assert_allclose(sol.rotation(t), reference.R, rtol=0, atol=1e-12)


# --- the reference itself --------------------------------------------------------------------------------

def _odefun_heavy(y0, p, t):
    """mpmath.odefun (Taylor by finite differences at extra precision) on the same hand-written equations."""
    I1, I3, mgl = mpmath.mpf(p["I1"]), mpmath.mpf(p["I3"]), mpmath.mpf(p["M"]) * p["g"] * p["l"]

    def f(_, y):
        w, R = y[:3], [y[3:6], y[6:9], y[9:12]]
        W = [[0, w[2], -w[1]], [-w[2], 0, w[0]], [w[1], -w[0], 0]]
        dR = [W[i][0] * R[0][j] + W[i][1] * R[1][j] + W[i][2] * R[2][j] for i in range(3) for j in range(3)]
        return [((I1 - I3) * w[1] * w[2] + mgl * R[1][2]) / I1, ((I3 - I1) * w[2] * w[0] - mgl * R[0][2]) / I1,
                mpmath.mpf(0)] + dR

    return mpmath.odefun(f, 0, y0, tol=mpmath.mpf(10) ** -24)(mpmath.mpf(t))


def test_taylor_reference_agrees_with_mpmath_odefun():
    p = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)
    with mpmath.workdps(26):
        y0 = ref.heavy_initial_state(dict(theta=0.5, phi=0.2, psi=-0.3, theta_dot=0.4, phi_dot=0.7, psi_dot=5.0))
        taylor = ref.integrate(ref.heavy_top_field(1.0, 0.5, mpmath.mpf(0.1) * 10 * 1), y0)(1.3)
        other = _odefun_heavy(y0, p, 1.3)
        # two integrators at 26 digits, tolerances 1e-24: agreement to 1e-22 shows neither is off
        assert max(abs(a - b) for a, b in zip(taylor, other)) < mpmath.mpf(10) ** -22


@pytest.mark.parametrize("omega", [(0.3, 1.1, -0.4), (3e5, -1.1e6, 4e5), (1e-30, 0.0, 2.0), (1e-9, 1e-9, 1e-9)],
                         ids=["ordinary", "huge spin", "tilt 1e-30", "slow"])
def test_fixed_point_series_equals_the_mpf_recurrence(omega):
    """The Taylor coefficients in fixed point (integers over 2^P) against the same recurrence in mpf, and the step's
    dense output (Horner in integers) against Horner in mpf: to 1e-30 of the state in the step's units
    (c_k h^k), and to 1e-28 relative in every coefficient of order ≤ 2 (the step rule's, per component)."""
    with mpmath.workdps(ref.DPS):
        field = ref.free_top_field((1.0, 2.0, 3.5))
        y0 = ref.free_initial_state(omega, [[0.6, 0.8, 0.0], [-0.8, 0.6, 0.0], [0.0, 0.0, 1.0]])
        fixed = field.fixed_series(y0, 34)
        assert fixed is not None
        got, want = fixed.coefficients(), field.series_mp(y0, 34)
        sol = ref.TaylorSolution(field, y0)
        sol.extend(0)
        h = sol.steps[0][0]
        scale = max(abs(v) for v in y0)
        assert max(abs(a - b) * h**k for ci, wi in zip(got, want) for k, (a, b) in enumerate(zip(ci, wi))) \
            < mpmath.mpf(10) ** -30 * scale
        assert max(abs(a - b) / abs(b) for ci, wi in zip(got, want) for a, b in zip(ci[:3], wi[:3]) if b) \
            < mpmath.mpf(10) ** -28
        for fraction in ("0", "0.37", "1"):
            s = h * mpmath.mpf(fraction)
            dense = sol.polynomials[0].at(s)
            assert max(abs(a - ref._horner(ci, s)) for a, ci in zip(dense, want)) < mpmath.mpf(10) ** -30 * scale
        # the check can fail: R11's equation dropped changes its rate, as the comparison above would see
        wrong = ref.QuadraticField(field.n, field.pairs, field.quadratic[:3] + ((),) + field.quadratic[4:], field.linear)
        assert abs(wrong.series(y0, 34)[3][1] - want[3][1]) > 1e-6 * abs(want[3][1]) > 0


def test_a_polynomial_series_takes_the_mpf_route():
    """ω = 0: every coefficient past the first vanishes, which fixed point cannot tell from underflow; mpf decides."""
    with mpmath.workdps(ref.DPS):
        field = ref.free_top_field((1.0, 2.0, 3.5))
        y0 = ref.free_initial_state((0.0, 0.0, 0.0))
        assert field.fixed_series(y0, 34) is None
        assert field.series(y0, 34) == field.series_mp(y0, 34)


def test_taylor_reference_free_top_conserves_energy_and_orthogonality():
    I = (1.0, 2.0, 3.0)
    with mpmath.workdps(ref.DPS):
        sol = ref.integrate(ref.free_top_field(I), ref.free_initial_state((1.0, 0.5, 1.0)))
        y = sol(5.0)
        E = lambda v: sum(mpmath.mpf(i) * w**2 for i, w in zip(I, v[:3]))  # noqa: E731
        R = ref.matrix(y)
        assert abs(E(y) - E(sol(0))) < mpmath.mpf(10) ** -26
        assert mpmath.mnorm(R * R.T - mpmath.eye(3), 1) < mpmath.mpf(10) ** -26


def test_euler_matrix_and_angles_round_trip():
    with mpmath.workdps(30):
        y = [0, 0, 0] + [v for row in ref.euler_matrix(0.3, 1.2, -2.0).tolist() for v in row]
        assert [float(a) for a in ref.euler_angles(y)] == pytest.approx([0.3, 1.2, -2.0], abs=1e-28)


def test_monodromy_power_is_repeated_multiplication():
    with mpmath.workdps(30):
        C = ref.euler_matrix(0.1, 0.2, 0.3)
        direct = C * C * C * C * C
        assert mpmath.mnorm(ref.monodromy_power(C, 5) - direct, 1) < mpmath.mpf(10) ** -27


def test_free_top_m1_sign_and_size():
    with mpmath.workdps(40):
        assert ref.free_top_m1((1.0, 2.0, 2.25), (0.75, 0.5, 1.0)) == 0
        above, below = ref.free_top_m1((1.0, 2.0, 3.0), (1.0, 0.5, 1.0)), ref.free_top_m1((1, 2, 3), (1, 0.5, 0.1))
    assert float(above) == pytest.approx(1 - 0.38461538461538464, rel=1e-12)  # BASELINE: m = 0.38 (5/13)
    assert below < 0


# --- verdicts, selection, command line -------------------------------------------------------------------

def _case(run, name="synthetic") -> Case:
    return Case(name=name, family="0 test", description="d", system="s", inputs="i", methods=("m",),
                reference="r", tolerance="t", run=run)


def test_verdicts():
    def good(col: Collector):
        col.compare("m", "x", [1.0, 2.0], [1.0, 2.0 + 1e-14], 1e-12)

    def silent_nan(col: Collector):
        col.compare("m", "x", [1.0, math.nan], [1.0, 2.0], 1e-12)

    def inaccurate(col: Collector):
        col.compare("m", "x", [1.0], [1.1], 1e-12)

    def refused(col: Collector):
        col.attempt("m", "solve", lambda: (_ for _ in ()).throw(InvalidInputError("expected X, got Y")))

    def declared(col: Collector):
        col.said_so("m", "x", 1e-13, 1e-15, "requested rtol not attainable")

    def crash(col: Collector):
        raise ZeroDivisionError("boom")

    assert run_case(_case(good)).verdict == "met"
    r = run_case(_case(silent_nan))
    assert (r.verdict, r.nan_free) == ("not met", False)
    assert run_case(_case(inaccurate)).reason.startswith("m x: 0.1 > 1e-12")
    assert "valid input refused: InvalidInputError" in run_case(_case(refused)).reason
    r = run_case(_case(declared))
    assert (r.verdict, r.passed) == ("said so", True)
    r = run_case(_case(crash))
    assert (r.verdict, r.reason) == ("not met", "crashed: ZeroDivisionError: boom")


def test_select_by_name_and_prefix():
    assert [c.name for c in select("huge-spin")] == ["huge-spin"]
    assert {c.family for c in select("separatrix")} == {"1 free-top separatrix"}
    assert all(c.quick for c in select(None, quick=True))
    with pytest.raises(InvalidInputError, match="stress case 'nope': expected a case name or prefix"):
        select("nope")


def test_quick_subset_covers_every_family():
    assert {c.family for c in select(None, quick=True)} == {c.family for c in all_cases()}


def test_cli_prints_a_row_and_exits_by_verdict(monkeypatch, capsys):
    import mechderive.stress as stress
    from mechderive.cli import main

    def ok(col):
        col.compare("m", "x", 1.0, 1.0, 1e-12)

    def bad(col):
        col.compare("m", "x", 1.0, 2.0, 1e-12)

    monkeypatch.setattr(stress, "all_cases", lambda: [_case(ok, "fine"), _case(bad, "broken")])
    assert main(["stress", "--case", "fine"]) == 0
    out = capsys.readouterr().out
    assert "fine" in out and "met" in out and "1 cases: 1 met" in out
    assert main(["stress"]) == 1
    assert main(["stress", "--case", "broken", "--json"]) == 1
    assert main(["stress", "--case", "nope"]) == 2  # an InvalidInputError: the CLI's error exit


def test_cli_json_rows(monkeypatch, capsys):
    import mechderive.stress as stress
    from mechderive.cli import main

    monkeypatch.setattr(stress, "all_cases", lambda: [_case(lambda col: col.compare("m", "x", 1.0, 1.0, 1e-12))])
    assert main(["stress", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert rows[0]["name"] == "synthetic" and rows[0]["verdict"] == "met" and rows[0]["passed"] is True
