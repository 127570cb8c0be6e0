"""Sections 3.3–3.4 and 3.5.3: Euler's equations, free tops, stability, the wobbling plate.

References are independent of the derivations under test: ω̇ = I⁻¹(τ - ω × Iω) with
NumPy's cross product; SciPy's solve_ivp (DOP853, rtol 1e-12) on the compiled equations;
numpy.linalg on finite-difference Jacobians; finite differences of the numeric R(φ, θ, ψ).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from mechderive.core.compile import compile_expressions
from mechderive.core.symbols import state_symbol
from mechderive.errors import InvalidInputError, NonFiniteValueError, ShapeError, UnphysicalInertiaError
from mechderive.kinematics import euler
from mechderive.systems.free_top import model as ft
from mechderive.systems.free_top.stability import (
    instability_growth_rate,
    is_steady_rotation,
    linearised_eigenvalues,
    principal_axis_stability,
)

MOMENTS = [ft.I1, ft.I2, ft.I3]
OMEGA = list(ft.omega_symbols())


def _rhs():
    """The compiled ω̇ of Euler's equations (3.33) with torque: f(ω1, ω2, ω3, I1, I2, I3, τ1, τ2, τ3) -> (3,)."""
    return compile_expressions(list(ft.model().euler_rhs), OMEGA + MOMENTS + list(ft.tau_symbols), name="euler_rhs")


def _free(I):
    f = _rhs()
    return lambda t, w: f(*w, *I, 0.0, 0.0, 0.0)


def _integrate(I, w0, t_end, **kw):
    return solve_ivp(_free(I), (0.0, t_end), w0, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True, **kw)


def _random_moments(rng, n):
    """Distinct moments obeying the triangle inequalities: the principal moments of random point clouds."""
    out = []
    while len(out) < n:
        pts, m = rng.normal(size=(6, 3)) * rng.uniform(0.3, 2.0, size=3), rng.uniform(0.5, 2.0, size=6)
        I = np.einsum("i,ij->j", m, np.sum(pts**2, axis=1, keepdims=True) - pts**2)  # diagonal of Σ m(r²δ - rr)
        if np.min(np.abs(np.diff(np.sort(I)))) > 0.05 * I.max():
            out.append(rng.permutation(I))
    return out


# --- 3.3.1 (3.31)-(3.33): Euler's equations ---------------------------------------------------

def test_3_33_euler_rhs_matches_cross_product_form(rng):
    # Reference: I ω̇ = τ - ω × Iω (L̇ = τ in the rotating frame), with NumPy's cross product.
    f = _rhs()
    for _ in range(20):
        I, w, tau = rng.uniform(1, 2, 3), rng.normal(size=3), rng.normal(size=3)
        want = (tau - np.cross(w, I * w)) / I
        np.testing.assert_allclose(f(*w, *I, *tau), want, rtol=1e-13, atol=1e-14)  # a few roundings


def test_3_31_space_angular_momentum_constant_along_integrated_motion():
    # Integrate ω̇ (3.33) together with Ṙ = ωR (3.5) and check L̃ = Rᵀ I ω stays put.
    I = np.array([1.0, 2.0, 2.5])
    f = _rhs()

    def rhs(t, y):
        w, R = y[:3], y[3:].reshape(3, 3)
        W = np.array([[0, w[2], -w[1]], [-w[2], 0, w[0]], [w[1], -w[0], 0]])  # ω_ab = ε_abc ω_c
        return np.concatenate([f(*w, *I, 0, 0, 0), (W @ R).ravel()])

    sol = solve_ivp(rhs, (0, 20), np.concatenate([[0.3, 1.0, -0.4], np.eye(3).ravel()]), method="DOP853",
                    rtol=1e-12, atol=1e-14, t_eval=np.linspace(0, 20, 50))
    L_space = np.array([y[3:].reshape(3, 3).T @ (I * y[:3]) for y in sol.y.T])
    # rtol 1e-12 per step over ~10³ steps: drift ≲ 1e-9; a wrong sign in (3.33) drifts by O(1).
    assert np.max(np.abs(L_space - L_space[0])) < 1e-9


# --- 3.4.1 (3.34)-(3.37): the symmetric top --------------------------------------------------

def test_3_37_symmetric_top_solution_against_solve_ivp():
    I1, I3, w3, w0 = 1.0, 1.6, 2.0, 0.7
    Omega = compile_expressions(ft.model().symmetric_precession_rate, [ft.I1, ft.I3, OMEGA[2]])(I1, I3, w3)
    assert Omega == pytest.approx(w3 * (I1 - I3) / I1, rel=1e-15)  # (3.36), by hand: -1.2
    ts = np.linspace(0, 30, 301)
    sol = _integrate((I1, I1, I3), [0.0, w0, w3], 30.0)
    got = sol.sol(ts)
    want = np.vstack([w0 * np.sin(Omega * ts), w0 * np.cos(Omega * ts), np.full_like(ts, w3)])
    # DOP853 at rtol 1e-12 over ~6 periods: global error ~1e-10.
    np.testing.assert_allclose(got, want, atol=1e-9)


# --- 3.4.2 (3.38)-(3.39): the Earth's wobble -------------------------------------------------

def test_3_39_earth_wobble_period():
    rate = compile_expressions(ft.model().symmetric_precession_rate, [ft.I1, ft.I3, OMEGA[2]])
    I1 = 1.0
    I3 = I1 * (1 + 1 / 300)  # (I1 - I3)/I1 = -1/300 (3.38)
    day = 1.0
    assert 2 * np.pi / abs(rate(I1, I3, 2 * np.pi / day)) == pytest.approx(300.0, rel=1e-13)  # one turn a day
    assert 2 * np.pi / abs(rate(I1, I3, 1 / day)) == pytest.approx(600 * np.pi, rel=1e-13)  # 1 rad/day: ≈ 1885 days
    assert rate(I1, I3, 1.0) < 0  # retrograde in the body frame: the chapter's 1/300 is |Ω|


# --- 3.4.3 (3.40)-(3.45): stability ----------------------------------------------------------

@pytest.mark.parametrize("moments", list(itertools.permutations((2.0, 3.0, 4.0))))
def test_3_45_stability_all_orderings(moments):
    got = principal_axis_stability(*moments)
    order = np.argsort(moments)
    assert got[order[0] + 1] == "stable"  # smallest
    assert got[order[1] + 1] == "unstable"  # intermediate
    assert got[order[2] + 1] == "stable"  # largest
    # (3.45) as printed, for axis 1
    I1, I2, I3 = moments
    assert (got[1] == "unstable") == (I2 < I1 < I3 or I3 < I1 < I2)


@pytest.mark.parametrize("moments, expected", [
    ((3.0, 3.0, 4.0), {1: "neutral", 2: "neutral", 3: "stable"}),  # prolate-ish symmetric top, symmetry axis e3
    ((4.0, 3.0, 4.0), {1: "neutral", 2: "stable", 3: "neutral"}),
    ((3.0, 4.0, 4.0), {1: "stable", 2: "neutral", 3: "neutral"}),
    ((1.0, 1.0, 2.0), {1: "neutral", 2: "neutral", 3: "stable"}),  # disc: I3 = I1 + I2
    ((2.5, 2.5, 2.5), {1: "neutral", 2: "neutral", 3: "neutral"}),  # sphere
])
def test_stability_with_equal_moments(moments, expected):
    assert principal_axis_stability(*moments) == expected


def test_nearly_equal_moments_are_equal_only_with_rtol():
    moments = (3.0, 3.0 * (1 + 1e-12), 4.0)
    assert principal_axis_stability(*moments) == {1: "stable", 2: "unstable", 3: "stable"}  # exact float signs
    assert principal_axis_stability(*moments, rtol=1e-9) == {1: "neutral", 2: "neutral", 3: "stable"}


def _fd_jacobian(I, w, h=1e-5):
    # Central differences are exact for the quadratic ω̇: only rounding, ~1e-16·|ω̇|/h ≈ 1e-11.
    f = _free(I)
    return np.column_stack([(f(0, w + h * e) - f(0, w - h * e)) / (2 * h) for e in np.eye(3)])


def test_linearised_eigenvalues_match_finite_difference_jacobian(rng):
    for I in _random_moments(rng, 8):
        for axis in (1, 2, 3):
            Omega = rng.uniform(0.5, 3.0) * rng.choice([-1, 1])
            w = np.zeros(3)
            w[axis - 1] = Omega
            got = linearised_eigenvalues(*I, w)
            ref = np.linalg.eigvals(_fd_jacobian(I, w))
            key = lambda z: (round(z.real, 6), round(z.imag, 6))  # noqa: E731
            # Eigenvalues O(1) from a Jacobian accurate to ~1e-10: agreement to 1e-8.
            np.testing.assert_allclose(sorted(got, key=key), sorted(ref, key=key), atol=1e-8)
            kind = principal_axis_stability(*I)[axis]
            assert (np.max(np.abs(ref.real)) > 1e-3) == (kind == "unstable")


def test_linearised_eigenvalues_in_a_plane_of_equal_moments(rng):
    # I1 = I2: every ω in the (e1, e2) plane is steady, and J is nilpotent.  Eigenvalues of a
    # nilpotent matrix are ill-conditioned (a 1e-11 error moves them by ~1e-5.5), so compare the
    # characteristic polynomial's coefficients instead: λ³ - sλ with s = 0.
    I = np.array([1.5, 1.5, 2.2])
    for _ in range(5):
        a = rng.uniform(0, 2 * np.pi)
        w = 1.3 * np.array([np.cos(a), np.sin(a), 0.0])
        assert is_steady_rotation(*I, w)
        got = linearised_eigenvalues(*I, w)
        np.testing.assert_allclose(got, 0, atol=1e-12)
        np.testing.assert_allclose(np.poly(_fd_jacobian(I, w)), [1, 0, 0, 0], atol=1e-9)
    # the sphere: any ω at all
    w = rng.normal(size=3)
    np.testing.assert_allclose(linearised_eigenvalues(2.0, 2.0, 2.0, w), 0, atol=1e-12)


def test_3_44_growth_rate_against_integration():
    # Spin about e1 with I2 < I1 < I3 (unstable), perturbed by η2 = 1e-10.  Fit log|η2| while
    # 1e-8 < |η2| < 1e-4: past the initial cosh transient, before η² terms matter (≤ 1e-4 relative).
    I, Omega = (2.0, 1.0, 2.5), 1.3
    rate = instability_growth_rate(*I, Omega, axis=1)
    sol = _integrate(I, [Omega, 1e-10, 0.0], 40.0)
    ts = np.linspace(0, 40, 8001)
    eta2 = np.abs(sol.sol(ts)[1])
    window = (eta2 > 1e-8) & (eta2 < 1e-4)
    assert window.sum() > 1000
    slope = np.polyfit(ts[window], np.log(eta2[window]), 1)[0]
    assert slope == pytest.approx(rate, rel=0.01)  # the 1 %; measured ~1e-6
    assert rate == pytest.approx(np.sqrt(Omega**2 / I[2] * (I[2] - I[0]) * (I[0] - I[1]) / I[1]), rel=1e-14)


@pytest.mark.parametrize("moments, axis", [((1.0, 2.0, 2.5), 2), ((2.5, 1.0, 2.0), 3)])
def test_growth_rate_other_axes_against_integration(moments, axis):
    Omega = 0.9
    rate = instability_growth_rate(*moments, Omega, axis=axis)
    w0 = np.zeros(3)
    w0[axis - 1] = Omega
    w0[axis % 3] = 1e-10  # perturb the next axis
    sol = _integrate(moments, w0, 60.0)
    ts = np.linspace(0, 60, 6001)
    eta = np.linalg.norm(np.delete(sol.sol(ts), axis - 1, axis=0), axis=0)
    window = (eta > 1e-8) & (eta < 1e-4)
    slope = np.polyfit(ts[window], np.log(eta[window]), 1)[0]
    assert slope == pytest.approx(rate, rel=0.01)


def test_stable_axis_oscillates_at_the_derived_frequency():
    I, Omega = (1.0, 2.0, 3.0), 1.0  # e1 is the smallest axis: stable
    freq = linearised_eigenvalues(*I, [Omega, 0, 0])[1].imag
    sol = _integrate(I, [Omega, 1e-6, 0.0], 200.0)
    ts = np.linspace(0, 200, 200001)
    eta2 = sol.sol(ts)[1]
    assert np.max(np.abs(eta2)) < 1e-5  # bounded: no growth
    crossings = ts[1:][np.sign(eta2[1:]) != np.sign(eta2[:-1])]
    measured = np.pi / np.mean(np.diff(crossings))
    assert measured == pytest.approx(freq, rel=1e-4)  # crossing times resolved to 1e-3 over ~30 half-periods


# --- 3.4.4 (3.46)-(3.49): Poinsot ------------------------------------------------------------

def test_3_46_3_47_conserved_along_integration():
    I = np.array([1.0, 1.7, 2.4])
    sol = _integrate(I, [0.4, 1.1, -0.6], 50.0)
    w = sol.sol(np.linspace(0, 50, 500))
    two_T = np.einsum("a,an->n", I, w**2)
    L2 = np.einsum("a,an->n", I**2, w**2)
    # rtol 1e-12 per step: drift ≲ 1e-10 relative over the run.
    assert np.ptp(two_T) / two_T[0] < 1e-10 and np.ptp(L2) / L2[0] < 1e-10


# --- 3.5.3 (3.59)-(3.61): the free symmetric top in Euler angles ----------------------------

def _euler_rates():
    m = ft.model()
    r = m.symmetric_top_euler_rates_spin
    names = [state_symbol(n) for n in ("phi_dot", "theta_dot", "psi_dot")]
    return compile_expressions([r[n] for n in names], [ft.I1, ft.I3, OMEGA[2], state_symbol("theta")])


@pytest.mark.parametrize("I1, I3", [(1.0, 2.0), (1.0, 0.4)])
def test_3_60_rates_keep_L_fixed_along_e3(I1, I3):
    # Reference: R(t) from the numeric (3.54) at φ = φ̇t, θ fixed, ψ = ψ̇t; ω from ṘRᵀ by central
    # differences; then L̃ = Rᵀ I ω must be constant and along ẽ3.
    theta0, w3 = 0.4, 1.7
    phi_dot, theta_dot, psi_dot = _euler_rates()(I1, I3, w3, theta0)
    assert theta_dot == 0.0
    I = np.array([I1, I1, I3])
    h = 1e-5
    for tc in (0.0, 0.8, 2.1):
        R = lambda s: euler.rotation_matrix(phi_dot * s, theta0, psi_dot * s)  # noqa: E731
        W = (R(tc + h) - R(tc - h)) / (2 * h) @ R(tc).T  # ω_ab = ε_abc ω_c; error ~h² ≈ 1e-10
        w = np.array([W[1, 2], W[2, 0], W[0, 1]])
        L_space = R(tc).T @ (I * w)
        np.testing.assert_allclose(L_space[:2], 0, atol=1e-9)
        assert L_space[2] == pytest.approx(I3 * w3 / np.cos(theta0), rel=1e-9)  # L = I3ω3/cos θ
        assert w[2] == pytest.approx(w3, rel=1e-9)


def test_3_61_plate_ratio():
    I1 = 1.0
    for theta0 in (1e-4, 0.1, 0.5, 1.0):
        phi_dot, _, psi_dot = _euler_rates()(I1, 2 * I1, 1.0, theta0)
        ratio = phi_dot / psi_dot
        assert ratio == pytest.approx(-2 / np.cos(theta0), rel=1e-14)
        # φ̇ ≈ -2ψ̇ only for slight θ: relative excess 1/cos θ - 1 ≈ θ²/2
        assert ratio / -2 - 1 == pytest.approx(theta0**2 / 2, rel=theta0**2, abs=1e-13)  # next term (5/12)θ²; rounding
    gen = _euler_rates()(1.0, 0.4, 1.0, 0.3)
    assert gen[0] / gen[2] == pytest.approx(0.4 / ((1.0 - 0.4) * np.cos(0.3)), rel=1e-14)


# --- bad input --------------------------------------------------------------------------------

def test_non_positive_moments_refused():
    with pytest.raises(UnphysicalInertiaError, match=r"expected principal moments > 0 \(3.22\), got I2 = -1"):
        principal_axis_stability(1.0, -1.0, 1.0)
    with pytest.raises(UnphysicalInertiaError, match="expected principal moments > 0 .*got I3 = 0"):
        instability_growth_rate(1.0, 1.0, 0.0, 1.0)
    with pytest.raises(UnphysicalInertiaError, match=r"expected I1 \+ I2 >= I3 \(triangle inequality\), got I1 \+ I2 = 3"):
        linearised_eigenvalues(1.0, 2.0, 4.0, [0.0, 0.0, 1.0])
    with pytest.raises(NonFiniteValueError, match="expected `I1` to be finite, got nan"):
        principal_axis_stability(float("nan"), 1.0, 1.0)


def test_non_steady_rotation_refused():
    with pytest.raises(InvalidInputError, match=r"expected a steady rotation .*got ω = \[1.0, 0.0, 0.001\]"):
        linearised_eigenvalues(1.0, 2.0, 2.5, [1.0, 0.0, 1e-3])
    assert not is_steady_rotation(1.0, 2.0, 2.5, [1.0, 0.0, 1e-3])
    with pytest.raises(ShapeError, match=r"expected `omega` to have shape \(3,\), got \(2,\)"):
        linearised_eigenvalues(1.0, 2.0, 2.5, [1.0, 0.0])


def test_growth_rate_refuses_stable_axis_bad_axis_and_zero_spin():
    with pytest.raises(InvalidInputError, match=r"expected spin about the intermediate axis \(A > 0 in \(3.44\)\), "
                                                r"got axis 3 with A/I1 = .* < 0: stable"):
        instability_growth_rate(1.0, 2.0, 2.5, 1.0, axis=3)
    with pytest.raises(InvalidInputError, match="got axis 1 with A/I2 = 0 = 0: neutral"):
        instability_growth_rate(2.0, 2.0, 2.5, 1.0, axis=1)
    with pytest.raises(InvalidInputError, match="expected axis 1, 2 or 3, got 4"):
        instability_growth_rate(1.0, 2.0, 2.5, 1.0, axis=4)
    with pytest.raises(InvalidInputError, match="expected axis 1, 2 or 3, got True"):
        instability_growth_rate(1.0, 2.0, 2.5, 1.0, axis=True)
    with pytest.raises(InvalidInputError, match="expected a nonzero spin Omega, got 0.0"):
        instability_growth_rate(1.0, 2.0, 2.5, 0.0, axis=2)


# --- laziness ------------------------------------------------------------------------------------

def test_stability_derivations_are_lazy():
    m = ft.FreeTopModel()
    _ = m.stability_coefficient
    assert "stability_coefficient" in m.derived and "linearised_axis1" in m.derived
    assert not m.is_derived("symmetric_top_euler_rates") and not m.is_derived("characteristic_polynomial")
    assert sp.simplify(m.stability_coefficient - m.axis_stability_coefficients[0]) == 0
