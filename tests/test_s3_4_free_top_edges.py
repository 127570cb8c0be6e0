"""Section 3.4: the free top's closed form at its edges (issue 11), against independent 40-digit references.

References: Taylor integration of Euler's equations (3.33) and Ṙ = hat(ω)R (3.11) in mpmath,
each component to its own relative accuracy (tests/_free_top_reference.py); for tilts below
1e-24 the exact linear response about the steady rotation.  Nothing here uses the closed form.

Tolerances, and why
-------------------
* ω(0) = ω0 component by component to 8 ulp of each component (the t = 0 evaluation rounds P, Q,
  S and the Jacobi values: ≤ 5 ulp measured over thousands of draws).
* ω(t) component by component to 16 ulp of max(|ω_a|, 2^-40·A_a), A_a the size of ω_a over the
  motion (the largest of |ω0_a| and the reference's values): a component passing through zero is
  measured against the accuracy its phase allows (the phase is exact to ~|u|·1e-32, so within
  2^-40·A_a of a zero the relative error may grow).
* R(0) = R0 and R(t) to 16·2^-52 absolute in every entry (R is an orthogonal matrix of O(1) entries;
  ≤ 6·2^-52 measured).
* every error is within the solution's own ``error_estimate``.
"""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mechderive.errors import MechDeriveError
from mechderive.kinematics.rotations import rotation_matrix
from mechderive.systems.free_top.exact import exact_free_top

from ._free_top_reference import integrate, near_axis, ulp, ulp_error

EPS = 2.0**-52
OMEGA0_ULP = 8
OMEGA_ULP = 16
R0_ABS = 16 * EPS
R_ABS = 16 * EPS


def check_against(sol, moments, omega0, R0, times, ref) -> None:
    """ω(0), R(0) from the inputs; ω(t), R(t) from the reference ``ref`` (one 12-vector per time)."""
    w0 = np.asarray(omega0, dtype=float)
    w_0 = sol.omega(0.0)
    for a in range(3):
        assert ulp_error(w_0[a], w0[a]) <= OMEGA0_ULP, (moments, omega0, "ω(0)", w_0, w0)
    assert np.max(np.abs(sol.rotation(0.0) - R0)) <= R0_ABS, (moments, omega0, "R(0)")
    times = np.asarray(times, dtype=float)
    w, R = sol.omega(times), sol.rotation(times)
    # the scale of each component over the motion, from the data themselves
    amp = np.max(np.abs(np.array([[float(v) for v in y[:3]] for y in ref] + [list(w0)])), axis=0)
    err_w = err_R = 0.0
    for i in range(len(times)):
        for a in range(3):
            e = ulp_error(w[i, a], ref[i][a], floor=2.0**-40 * amp[a])
            assert e <= OMEGA_ULP, (moments, omega0, times[i], a, w[i, a], float(ref[i][a]), e)
            err_w = max(err_w, abs(float(w[i, a] - ref[i][a])))
        dR = max(abs(float(R[i].ravel()[j] - ref[i][3 + j])) for j in range(9))
        assert dR <= R_ABS, (moments, omega0, times[i], dR)
        err_R = max(err_R, dR)
    # the solution's own measured estimate covers what it got wrong (up to the reference's own
    # error, below 1e-25 at 30 digits: a steady rotation's estimate is exactly 0)
    assert err_w <= (sol.error_estimate(times, ("omega",)) + 1e-25) * np.linalg.norm(w0), (moments, omega0)
    assert err_R <= sol.error_estimate(times, ("R",)) + 1e-25, (moments, omega0)


# --- issue 11, reproductions 1-3 ---------------------------------------------------------------

@pytest.mark.parametrize("omega0", [
    (2.0**-53, 0.0, 0.2),            # the case: L tilted 2.8e-17 rad from ẽ3 (was 90° off)
    (1e-16 * 0.2, 0.0, 0.2), (9e-16 * 0.2, 0.0, 0.2), (4e-16 * 0.2, 3e-16 * 0.2, 0.2),
    (0.2, 1e-16 * 0.2, 0.0), (0.2, 0.0, 9e-16 * 0.2),  # L within 1e-16..9e-16 of axis 1
    (2.0**-60, 2.0**-60, 1.0),       # L = (ε, ε, 1)
])
def test_attitude_is_right_when_L_is_within_rounding_of_an_axis(omega0):
    sol = exact_free_top((2.0, 3.0, 5.0), omega0)
    np.testing.assert_allclose(sol.rotation(0.0), np.eye(3), rtol=0, atol=R0_ABS)
    times = [0.0, 0.7, 10.0]
    check_against(sol, (2.0, 3.0, 5.0), omega0, np.eye(3), times, integrate((2.0, 3.0, 5.0), omega0, times))


@pytest.mark.parametrize("tilt", [5e-17, 5e-18, 1e-20, 1e-100, 1e-300, 5e-324])
def test_tiny_tilts_keep_every_constant_exact(tilt):
    # was DerivationError: 2T·I_k - L² lost all its digits to cancellation at 40 digits
    omega0 = (tilt, 0.0, 0.2)
    sol = exact_free_top((2.0, 3.0, 5.0), omega0)
    times = [0.0, 1.0, 10.0]
    check_against(sol, (2.0, 3.0, 5.0), omega0, np.eye(3), times, integrate((2.0, 3.0, 5.0), omega0, times))


def test_symmetric_body_spinning_about_a_transverse_axis_is_a_steady_rotation():
    # was ZeroDivisionError: ω in the equal-moment plane is an eigenvector of I, so ω̇ = 0 (3.33)
    sol = exact_free_top((2.0, 2.0, 3.0), (1.0, 0.0, 0.0))
    assert sol.kind == "steady"
    t = np.array([0.0, 0.5, 3.0, 1e4])
    np.testing.assert_array_equal(sol.omega(t), np.tile([1.0, 0.0, 0.0], (4, 1)))
    # R = exp(hat(ω)t): a rotation by t about e1 (chapter convention R = R1(t))
    c, s = np.cos(t), np.sin(t)
    expected = np.zeros((4, 3, 3))
    expected[:, 0, 0] = 1
    expected[:, 1, 1], expected[:, 1, 2], expected[:, 2, 1], expected[:, 2, 2] = c, s, -s, c
    # |ω| t is reduced mod 2π in double-double, so even t = 1e4 costs nothing beyond rounding
    np.testing.assert_allclose(sol.rotation(t), expected, rtol=0, atol=4 * EPS)
    check_against(sol, (2.0, 2.0, 3.0), (1.0, 0.0, 0.0), np.eye(3), t[:3], integrate((2.0, 2.0, 3.0), (1, 0, 0), t[:3]))


def test_separatrix_with_negative_components_keeps_their_signs():
    # on the separatrix cn = sech u never changes sign, so P must carry the sign of ω_x (was ω ≈ 0)
    for signs in itertools.product((1, -1), repeat=3):
        omega0 = tuple(s * v for s, v in zip(signs, (0.75, 0.5, 1.0)))
        sol = exact_free_top((1.0, 2.0, 2.25), omega0)
        assert sol.kind == "separatrix"
        times = [0.0, 1.5, 4.0]
        check_against(sol, (1.0, 2.0, 2.25), omega0, np.eye(3), times,
                      integrate((1.0, 2.0, 2.25), omega0, times))


# --- every degeneracy ---------------------------------------------------------------------------

DEGENERATE = [
    ((2.0, 2.0, 3.0), (0.3, 0.4, 1.0), "elliptic"),     # I1 = I2: m = 0, (3.37)
    ((2.0, 3.0, 3.0), (1.0, 0.4, -0.3), "elliptic"),    # I2 = I3
    ((3.0, 2.0, 3.0), (0.4, 1.0, 0.3), "elliptic"),     # I1 = I3 (the equal pair in another place)
    ((2.0, 3.0, 3.0), (0.0, 0.4, -0.3), "steady"),      # ω in the equal-moment plane
    ((2.0, 2.0, 2.0), (0.3, -0.4, 1.0), "steady"),      # sphere
    ((1.0, 2.0, 3.0), (0.3, 0.2, 0.5), "elliptic"),     # flat plate I1 + I2 = I3
    ((1.0, 2.0, 3.0), (0.0, 0.0, -2.0), "steady"),      # ω exactly on an axis
    ((1.0, 2.0, 3.0), (0.0, 1.0, 0.0), "steady"),       # exactly on the unstable axis
    ((1.0, 2.0, 3.0), (0.5, 0.0, 1.0), "elliptic"),     # a zero component
    ((1.0, 2.0, 3.0), (0.5, 1.0, 0.0), "elliptic"),     # a zero component (about the other axis)
    ((1.0, 2.0, 2.25), (0.75, 0.0, 1.0), "separatrix"),  # exactly on the separatrix, ω_y = 0
    ((1.0, 2.0, 2.25), (0.75, 0.5, 1.0 + 2**-52), "elliptic"),   # one ulp off it: 1 - m ~ 1e-16
    ((1.0, 2.0, 2.25), (0.75, 0.5, 1.0 - 2**-52), "elliptic"),   # ... on the other side
    ((2.0, 3.0, 3.0 + 2.0**-45), (1.0, 0.0, 1.0), "elliptic"),   # nearly symmetric
    ((1.0, 2.0, 3.0), (0.0, 0.0, 0.0), "steady"),       # at rest
]


@pytest.mark.parametrize("moments, omega0, kind", DEGENERATE)
def test_degenerate_bodies_and_motions(moments, omega0, kind):
    R0 = rotation_matrix(0.4, 1.1, -0.7)
    sol = exact_free_top(moments, omega0, R0=R0)
    assert sol.kind == kind
    times = [0.0, 0.9, 4.2]
    check_against(sol, moments, omega0, R0, times, integrate(moments, omega0, times, R0=R0))


# --- the sweep: near every axis, at tilts 10^-k, every ordering and degeneracy ------------------

MOMENTS = [tuple(p) for p in itertools.permutations((3.0, 4.0, 5.0))] + [
    (2.0, 2.0, 3.0), (2.0, 3.0, 2.0), (3.0, 2.0, 2.0), (2.0, 3.0, 3.0), (3.0, 2.0, 3.0), (3.0, 3.0, 2.0),
    (2.0, 2.0, 2.0), (1.0, 2.0, 3.0), (0.25, 0.5, 0.75)]
SIGNS = [(1.0, 1.0, -1.0), (-1.0, -1.0, 1.0)]  # (big component, first tilt, second tilt)


def _near_axis_case(moments, axis, signs, k):
    """ω = ±0.8 along ``axis`` plus tilts ±10^-k·(0.6, 0.35) in the other two components."""
    w = np.zeros(3)
    w[axis] = 0.8 * signs[0]
    others = [b for b in range(3) if b != axis]
    w[others[0]] = signs[1] * 0.6 * 10.0**-k
    w[others[1]] = signs[2] * 0.35 * 10.0**-k
    return tuple(float(x) for x in w)


def _sweep(ks, moment_sets, times=(0.0, 0.8, 2.7)) -> int:
    n = 0
    for moments in moment_sets:
        R0 = rotation_matrix(0.3, 0.8, -1.3)
        for axis, signs in itertools.product(range(3), SIGNS):
            linear = [k for k in ks if k >= 24]
            direct = [k for k in ks if k < 24]
            for k in direct:
                w = _near_axis_case(moments, axis, signs, k)
                check_against(exact_free_top(moments, w, R0=R0), moments, w, R0, times,
                              integrate(moments, w, times, R0=R0))
                n += 1
            if linear:
                # one linear response serves every tilt below 1e-24 (its ε² is invisible)
                reference = near_axis(moments, 0.8 * signs[0], axis, times, R0=R0)
                for k in linear:
                    w = _near_axis_case(moments, axis, signs, k)
                    check_against(exact_free_top(moments, w, R0=R0), moments, w, R0, times, reference(w))
                    n += 1
    return n


def test_sweep_near_axes_sample():
    # a bounded deterministic sample of the full sweep below: every moment set once, the axis, the
    # signs and the tilt (1, 1e-8, 1e-17: L within rounding of an axis, 1e-160, 1e-320: a denormal)
    # taken in turn
    times = (0.0, 0.8, 2.7)
    for i, moments in enumerate(MOMENTS):
        R0 = rotation_matrix(0.3, 0.8, -1.3)
        w = _near_axis_case(moments, i % 3, SIGNS[i % 2], (0, 8, 17, 160, 320)[i % 5])
        check_against(exact_free_top(moments, w, R0=R0), moments, w, R0, times,
                      integrate(moments, w, times, R0=R0))


@pytest.mark.slow
def test_sweep_near_axes_full():
    # the linear-response reference itself agrees with direct integration where both apply
    import mpmath

    times = (0.0, 0.8, 2.7)
    w = _near_axis_case((3.0, 4.0, 5.0), 1, SIGNS[0], 25)
    linear, direct = near_axis((3.0, 4.0, 5.0), w[1], 1, times)(w), integrate((3.0, 4.0, 5.0), w, times, dps=40)
    # the neglected O(ε) e^{σt} ≈ 1e-25·1.8 relative, and 40-digit rounding of O(1) entries
    for a, b in zip(linear, direct):
        for x, y in zip(a, b):
            assert abs(x - y) <= mpmath.mpf(10) ** -22 * abs(y) + mpmath.mpf(10) ** -38
    start = time.perf_counter()
    n = _sweep(list(range(0, 321)), MOMENTS)
    print(f"free-top edge sweep: {n} cases in {time.perf_counter() - start:.0f} s")


SEPARATRIX_OFFSETS = [0.0] + [10.0**-k for k in range(1, 16)]


def _separatrix_cases(offsets):
    # (1, 2, 2.25) with ω = (0.75, ω_y, 1) is exactly on the separatrix: Σ I_a (I_a - I_2) ω_a² = 0;
    # ω_x (1 + δ) puts it 2δ·0.56 relative off, on the side of the sign of δ
    for d, wy, sx in itertools.product(offsets, (0.0, 0.5, -3.0), (1.0, -1.0)):
        for side in (1.0, -1.0):
            yield (1.0, 2.0, 2.25), (sx * 0.75 * (1 + side * d), wy, 1.0)


def test_separatrix_sample():
    times = (0.0, 1.1, 3.7)
    R0 = rotation_matrix(-0.2, 0.5, 2.0)
    for moments, w in list(_separatrix_cases([1e-5, 1e-15]))[::5]:
        check_against(exact_free_top(moments, w, R0=R0), moments, w, R0, times,
                      integrate(moments, w, times, R0=R0))


@pytest.mark.slow
def test_separatrix_full():
    times = (0.0, 1.1, 3.7, 9.0)
    R0 = rotation_matrix(-0.2, 0.5, 2.0)
    for moments, w in _separatrix_cases(SEPARATRIX_OFFSETS):
        check_against(exact_free_top(moments, w, R0=R0), moments, w, R0, times, integrate(moments, w, times, R0=R0))
    # 1 - m far below 1e-16: a nearly symmetric body (I3 = I2(1 + 2^-j)) on its separatrix to rounding
    for j in (20, 40, 60):
        moments = (1.0, 2.0, 2.0 * (1 + 2.0**-j))
        import mpmath

        with mpmath.workdps(60):
            wx = float(mpmath.sqrt(mpmath.mpf(moments[2]) * (mpmath.mpf(moments[2]) - moments[1]) / (moments[1] - 1)))
        w = (wx, 0.3, 1.0)
        sol = exact_free_top(moments, w, R0=R0)
        check_against(sol, moments, w, R0, times, integrate(moments, w, times, R0=R0))


# --- property-based: any body, any ω, tilts down to denormals ----------------------------------

@st.composite
def _bodies_and_omegas(draw):
    a = draw(st.floats(0.05, 10.0))
    b = draw(st.floats(0.05, 10.0))
    c = draw(st.floats(abs(a - b) + 1e-3, a + b))  # the triangle inequality (3.22)
    moments = draw(st.permutations([a, b, c]))
    axis = draw(st.integers(0, 2))
    k = draw(st.integers(0, 330))
    big = draw(st.floats(0.1, 5.0)) * draw(st.sampled_from([1.0, -1.0]))
    tilts = [draw(st.floats(-1.0, 1.0)) * 10.0**-k for _ in range(2)]
    w = [0.0, 0.0, 0.0]
    w[axis] = big
    for slot, tilt in zip([x for x in range(3) if x != axis], tilts):
        w[slot] = tilt
    return tuple(moments), tuple(w)


@pytest.mark.filterwarnings("error")  # not even a RuntimeWarning (an overflow or a NaN on the way)
@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(_bodies_and_omegas())
def test_any_body_reproduces_its_initial_state_or_refuses_clearly(case):
    moments, omega0 = case
    try:
        sol = exact_free_top(moments, omega0)
    except MechDeriveError:
        return  # a refusal must be a MechDeriveError (any other exception fails the test)
    w = sol.omega(0.0)
    for a in range(3):
        assert ulp_error(w[a], omega0[a]) <= OMEGA0_ULP
    np.testing.assert_allclose(sol.rotation(0.0), np.eye(3), rtol=0, atol=R0_ABS)
    t = np.linspace(0.0, 5.0, 6)
    assert np.all(np.isfinite(sol.omega(t))) and np.all(np.isfinite(sol.rotation(t)))
    est = sol.error_estimate(t)
    assert np.isfinite(est) and est < 1e-12


@settings(max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(_bodies_and_omegas())
def test_any_body_matches_the_reference(case):
    moments, omega0 = case
    times = (0.0, 1.3)
    check_against(exact_free_top(moments, omega0), moments, omega0, np.eye(3), times,
                  integrate(moments, omega0, times))


def test_published_short_fat_symmetric_top_with_strict_false():
    # Principia's euler_solver_test (from ETH lecture 19): I = (3, 3, 9), L0 = (0, 5, 7), and
    # L_body(t) = (5 sin Ωt, 5 cos Ωt, 7) with Ω = L3 (I1 - I3)/(I1 I3).  3 + 3 < 9: no body has
    # these moments, so they are refused unless strict=False.
    from mechderive.errors import UnphysicalInertiaError

    moments, omega0 = (3.0, 3.0, 9.0), (0.0, 5.0 / 3.0, 7.0 / 9.0)
    with pytest.raises(UnphysicalInertiaError, match="triangle inequality"):
        exact_free_top(moments, omega0)
    sol = exact_free_top(moments, omega0, strict=False)
    t = np.arange(0.0, 5.0, 0.1)
    Omega = 7.0 * (3.0 - 9.0) / (3.0 * 9.0)
    expected = np.stack([5 * np.sin(Omega * t), 5 * np.cos(Omega * t), np.full_like(t, 7.0)], axis=-1)
    np.testing.assert_allclose(sol.angular_momentum(t), expected, rtol=0, atol=8 * 7.0 * EPS)
    assert sol.error_estimate(t) < 1e-13
    with pytest.raises(UnphysicalInertiaError, match=r"expected principal moments > 0 .* got I1 = -3"):
        exact_free_top((-3.0, 3.0, 9.0), omega0, strict=False)


def test_times_beyond_the_exact_phase_count_are_refused():
    sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0))
    with pytest.raises(MechDeriveError, match=r"expected \|t\| <= .* got t = 1e\+300"):
        sol.omega([0.0, 1e300])
    assert ulp(1.0) == EPS


@pytest.mark.parametrize("span, samples", [(1e-300, 101), (1e-17, 1001), (1e-6, 20001)])
def test_euler_angles_of_very_short_or_dense_runs(span, samples):
    # Regression (issue 12): with samples closer than R's rounding can tell apart (a run of 1e-300 s from
    # the pole, R0 = 1, never returned), the tracker refined the noise of R for ever; such samples now
    # continue the last tracked point's half-angle arguments.  Reference: over less than 1e-5 rad of
    # turning no angle can wrap, so the angles read off R(t) directly (euler_angles_from_matrix) are the
    # continuous ones; away from the poles (θ0 = 0.5) they are conditioned to ~ε/sin θ: 64 ε.
    from mechderive.kinematics.rotations import euler_angles_from_matrix

    t = np.linspace(0.0, span, samples)
    sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0), R0=rotation_matrix(0.3, 0.5, -0.2))
    angles = sol.euler_angles(t)
    direct = euler_angles_from_matrix(sol.rotation(t))
    assert np.max(np.abs(angles - direct)) <= 64 * EPS
    assert sol.error_estimate(t, ["euler_angles"]) <= 1e-12
    # from the pole (R0 = 1) only φ + ψ is defined while θ ~ |ω| t: it stays 0 to the rounding of R
    # (R(t) is right to a few ε absolutely, not relative to a turn of 1e-300: θ reads up to ~1e-16)
    pole = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0)).euler_angles(t)
    assert np.all(np.isfinite(pole)) and np.max(pole[:, 1]) <= 2 * span + 64 * EPS
    assert np.max(np.abs(np.remainder(pole[:, 0] + pole[:, 2] + np.pi, 2 * np.pi) - np.pi)) <= 2 * span + 8 * EPS
