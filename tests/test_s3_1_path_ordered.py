"""Section 3.1.2, path-ordered exponentials (3.11)–(3.16): the Magnus integrator and the catalog claims.

References used: known Euler-angle trajectories R(φ(t), θ(t), ψ(t)) (3.54) with ω from (3.58);
an mpmath ODE solution at 30 digits; SciPy's DOP853; a symbolic Dyson series with
non-commuting symbols (for the sign of the Magnus commutator).
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechderive.catalog.registry import all_claims, evaluate
from mechderive.errors import InvalidInputError, NonFiniteValueError, NotARotationError, ShapeError
from mechderive.kinematics.euler import angular_velocity_body, angular_velocity_space, rotation_matrix
from mechderive.kinematics.magnus import gauss_nodes, magnus_exponent, magnus_exponent_from_nodes, magnus_step
from mechderive.kinematics.path_ordered import (
    naive_exponential,
    path_ordered_exponential,
    sampled_angular_velocity,
)
from mechderive.kinematics.so3 import expm_so3, hat

from .conftest import verified

# ----------------------------------------------------------------------------- test trajectories

T_END = 2.0


def euler_path(t):
    """A smooth Euler-angle path (φ, θ, ψ) and its rates, away from gimbal lock (θ ∈ [0.4, 1.2])."""
    t = np.asarray(t, dtype=float)
    phi, phi_dot = 0.3 + 1.1 * t + 0.2 * t**2, 1.1 + 0.4 * t
    theta, theta_dot = 0.8 + 0.4 * np.sin(1.3 * t), 0.52 * np.cos(1.3 * t)
    psi, psi_dot = -0.2 + 2.0 * t - 0.1 * t**3, 2.0 - 0.3 * t**2
    return phi, theta, psi, phi_dot, theta_dot, psi_dot


def omega_body(t):
    """Body components of ω along the path, (3.58): the input of Ṙ = ωR."""
    return angular_velocity_body(*euler_path(t))


def omega_space(t):
    """Space components ω̃ = Rᵀω; hat(ω̃) = Rᵀ hat(ω) R is the convective Ω = R⁻¹Ṙ of (3.10)."""
    return angular_velocity_space(*euler_path(t))


def exact_R(t):
    return rotation_matrix(*euler_path(t)[:3])


R0 = exact_R(0.0)


def max_err(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


def fitted_order(hs, errors) -> float:
    return float(np.polyfit(np.log(hs), np.log(errors), 1)[0])


# ----------------------------------------------------------------------------- (3.11) Ṙ = ωR, the integrator

class TestMagnusIntegrator_3_11:
    def test_fixed_axis_cubic_rate_is_exact(self):
        # ω = (1 + t²) n̂: the commutators vanish and 2-point Gauss is exact for polynomials of
        # degree ≤ 3, so the result is exp(n̂ ∫ω) to rounding (≈1e-15 per step; 1e-13 leaves room).
        n = np.array([1.0, 2.0, 2.0]) / 3
        res = path_ordered_exponential(lambda s: np.outer(1 + s**2, n), (0.0, 1.5), steps=3)
        assert max_err(res.R[-1], expm_so3(n * (1.5 + 1.5**3 / 3))) < 1e-13

    @pytest.mark.parametrize("order, steps, tol", [(4, 200, 1e-8), (6, 60, 1e-10)])
    def test_reproduces_euler_angle_trajectory(self, order, steps, tol):
        # Errors ~ C h^order, worst over the grid: measured 8e-10 (order 4, h = 0.01), 1.6e-11 (order 6, h = 1/30).
        res = path_ordered_exponential(omega_body, (0.0, T_END), steps=steps, order=order, R0=R0)
        assert max_err(res.R, exact_R(res.t)) < tol

    @pytest.mark.parametrize("order, steps", [(4, [8, 16, 32, 64, 128]), (6, [4, 8, 16, 32, 64])])
    def test_measured_order_of_convergence(self, order, steps):
        # The error at t = 2 is fitted as C h^p over h = 0.25 … 0.016 (order 4), 0.5 … 0.031 (order 6),
        # all far above rounding (smallest errors ≈ 5e-9, 1e-11). Measured p: 3.999 and 5.996.
        hs = T_END / np.array(steps)
        errors = [max_err(path_ordered_exponential(omega_body, (0.0, T_END), steps=n, order=order, R0=R0).R[-1],
                          exact_R(T_END)) for n in steps]
        assert fitted_order(hs, errors) == pytest.approx(order, abs=0.3)

    def test_rotation_after_1e5_steps(self):
        # No projection anywhere: each product of rotations adds O(ε) to |RᵀR − 1|, so after n = 1e5 steps
        # the bound is between √n ε ≈ 7e-14 (random walk) and n ε ≈ 2e-11 (worst case); measured 2e-14.
        res = path_ordered_exponential(omega_body, (0.0, T_END), steps=100_000, R0=R0)
        R = res.R[-1]
        assert max_err(R.T @ R, np.eye(3)) < 1e-12
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
        assert max_err(R, exact_R(T_END)) < 1e-12

    def test_vectorised_and_scalar_omega_agree(self):
        scalar = lambda s: omega_body(float(s))  # noqa: E731 - a callable that only takes a scalar
        a = path_ordered_exponential(omega_body, (0.0, 1.0), steps=20, R0=R0)
        b = path_ordered_exponential(scalar, (0.0, 1.0), steps=20, R0=R0)
        assert max_err(a.R, b.R) < 1e-15

    def test_t_eval_off_grid_keeps_the_order(self):
        # Off-grid times are reached by a partial Magnus step, so they are as accurate as grid points.
        te = np.array([0.0, 0.123, 0.777, 1.5, 1.999, 2.0])
        res = path_ordered_exponential(omega_body, (0.0, T_END), steps=64, order=6, t_eval=te, R0=R0)
        assert res.t.shape == (6,) and res.R.shape == (6, 3, 3)
        assert max_err(res.R, exact_R(te)) < 1e-9

    def test_magnus_step_is_one_step_of_the_integrator(self):
        res = path_ordered_exponential(omega_body, (0.0, 0.1), steps=1, R0=R0)
        assert max_err(magnus_step(omega_body, 0.0, 0.1, R0), res.R[-1]) < 1e-15

    def test_sampled_omega_is_limited_by_the_spline(self):
        # Cubic-spline samples every Δ = 0.01: the O(Δ⁴) interpolation error dominates (measured 1.4e-10).
        times = np.linspace(0.0, T_END, 201)
        res = path_ordered_exponential((times, omega_body(times)), (0.0, T_END), steps=400, R0=R0)
        assert max_err(res.R[-1], exact_R(T_END)) < 1e-7


class TestCommutatorSign_3_16:
    """The sign of the Magnus-4 commutator, derived from the ordered Dyson series (3.16)."""

    @staticmethod
    def _integrate(expr, var, lo, hi):
        # SymPy cannot integrate non-commutative expressions: integrate the commutative factor of each term.
        total = sp.Integer(0)
        for term in sp.Add.make_args(sp.expand(expr)):
            c, nc = term.args_cnc()
            total += sp.integrate(sp.Mul(*c), (var, lo, hi)) * sp.Mul(*nc)
        return sp.expand(total)

    @staticmethod
    def _truncate(expr, h, degree):
        return sp.Add(*[term for term in sp.Add.make_args(sp.expand(expr))
                        if sp.degree(sp.Mul(*term.args_cnc()[0]), h) <= degree])

    @pytest.mark.parametrize("later_on_left, sign", [(True, +1), (False, -1)])
    def test_gauss_magnus4_coefficient(self, later_on_left, sign):
        a, b = sp.symbols("a b", commutative=False)
        h, s1, s2, s3 = sp.symbols("h s1 s2 s3", positive=True)
        A = lambda s: a + b * s  # noqa: E731 - ω(t) = a + b t, the simplest non-commuting case
        order = (lambda *m: sp.Mul(*m)) if later_on_left else (lambda *m: sp.Mul(*reversed(m)))
        integ = self._integrate
        d1 = integ(A(s1), s1, 0, h)
        d2 = integ(integ(order(A(s1), A(s2)), s2, 0, s1), s1, 0, h)  # s2 < s1: s1 is later
        d3 = integ(integ(integ(order(A(s1), A(s2), A(s3)), s3, 0, s2), s2, 0, s1), s1, 0, h)
        x = d1 + d2 + d3  # d_k is O(h^k): through h³, X² is d1² + d1 d2 + d2 d1 and X³ is d1³
        x2, x3 = d1 * d1 + d1 * d2 + d2 * d1, d1 * d1 * d1
        log_series = self._truncate(x - x2 / 2 + x3 / 3, h, 3)  # log(1 + X) through h³
        k = sp.Symbol("k")
        c1, c2 = sp.Rational(1, 2) - sp.sqrt(3) / 6, sp.Rational(1, 2) + sp.sqrt(3) / 6
        a1, a2 = A(c1 * h), A(c2 * h)
        magnus = h / 2 * (a1 + a2) + k * h**2 * (a2 * a1 - a1 * a2)
        diff = sp.expand(magnus - log_series)
        # Through h³ the difference is only k-dependent multiples of [b, a]; solve for k.
        coeff = sp.expand(diff).coeff(h, 3).coeff(b * a)
        solution = sp.solve(coeff, k)
        assert solution == [sign * sp.sqrt(3) / 12]
        assert sp.expand(diff.subs(k, solution[0])) == 0

    def test_local_error_against_tiny_steps(self):
        # A step of length h against 4096 sub-steps (≈ exact): local error O(h⁵) for the right
        # sign; flipping the commutator leaves O(h³). Fitted exponents 5.0 vs 3.0, ±0.3.
        def one_step(h, sign):
            nodes = omega_body(gauss_nodes(4) * h)
            a1, a2 = hat(nodes[0]), hat(nodes[1])
            c = sign * np.sqrt(3) / 12 * h**2 * (a2 @ a1 - a1 @ a2)
            from mechderive.kinematics.so3 import vee
            return expm_so3(vee(h / 2 * (a1 + a2) + c))

        hs = np.array([0.2, 0.1, 0.05])
        ref = [path_ordered_exponential(omega_body, (0.0, h), steps=4096, order=6).R[-1] for h in hs]
        good = [max_err(one_step(h, +1), r) for h, r in zip(hs, ref)]
        flipped = [max_err(one_step(h, -1), r) for h, r in zip(hs, ref)]
        assert fitted_order(hs, good) == pytest.approx(5, abs=0.3)
        assert fitted_order(hs, flipped) == pytest.approx(3, abs=0.3)
        assert np.allclose([max_err(one_step(h, +1), expm_so3(magnus_exponent(omega_body, 0.0, h)))
                            for h in hs], 0, atol=1e-15)


class TestMpmathReference_3_11:
    """An independent solution of Ṙ = ωR: mpmath's Taylor-series ODE solver at 30 digits."""

    T = 1.0

    @staticmethod
    def w_numpy(s):
        s = np.asarray(s, dtype=float)
        return np.stack(np.broadcast_arrays(np.sin(s) + 0.5, 0.7 * np.cos(2 * s), 0.3 + s**2), axis=-1)

    @pytest.fixture(scope="class")
    @classmethod
    def reference(cls):
        with mpmath.workdps(30):
            def rhs(s, y):
                w1, w2, w3 = mpmath.sin(s) + 0.5, 0.7 * mpmath.cos(2 * s), 0.3 + s * s
                W = [[0, w3, -w2], [-w3, 0, w1], [w2, -w1, 0]]  # ω_ab = ε_abc ω_c
                return [sum(W[i][k] * y[3 * k + j] for k in range(3)) for i in range(3) for j in range(3)]

            sol = mpmath.odefun(rhs, 0, [1, 0, 0, 0, 1, 0, 0, 0, 1])
            return {s: np.array([float(v) for v in sol(mpmath.mpf(s))]).reshape(3, 3) for s in (0.5, cls.T)}

    def test_fixed_step_order6_matches_mpmath(self, reference):
        # 100 order-6 steps of 0.01: truncation ≈ 1e-16, so only rounding (~1e-15) remains.
        res = path_ordered_exponential(self.w_numpy, (0.0, self.T), steps=100, order=6, t_eval=[0.5, self.T])
        assert max_err(res.R[0], reference[0.5]) < 1e-13
        assert max_err(res.R[1], reference[self.T]) < 1e-13

    @pytest.mark.parametrize("order", [4, 6])
    @pytest.mark.parametrize("rtol", [1e-6, 1e-10])
    def test_adaptive_error_estimate_is_honest(self, reference, order, rtol):
        res = path_ordered_exponential(self.w_numpy, (0.0, self.T), rtol=rtol, order=order)
        actual = max_err(res.R[-1], reference[self.T])
        # The estimate is a sum of local step-doubling estimates (a first-order bound): it stays within
        # rtol and does not undersell the true error by more than a factor 3 (measured actual/estimate 0.64-0.78).
        assert res.error_estimate <= rtol
        assert actual <= 3 * res.error_estimate
        assert res.t[0] == 0.0 and res.t[-1] == self.T

    def test_adaptive_order6_needs_fewer_steps(self):
        n4 = path_ordered_exponential(self.w_numpy, (0.0, self.T), rtol=1e-10, order=4).steps
        n6 = path_ordered_exponential(self.w_numpy, (0.0, self.T), rtol=1e-10, order=6).steps
        assert n6 < n4

    def test_adaptive_lands_on_t_eval(self, reference):
        res = path_ordered_exponential(self.w_numpy, (0.0, self.T), rtol=1e-11, order=6, t_eval=[0.0, 0.5])
        np.testing.assert_array_equal(res.t, [0.0, 0.5])
        assert max_err(res.R[0], np.eye(3)) == 0.0
        assert max_err(res.R[1], reference[0.5]) < 1e-10


class TestRightOrdering_3_98:
    """Ṙ = RΩ with Ω = R⁻¹Ṙ (3.10), later times on the right (3.98), used in section 3.7."""

    @pytest.mark.parametrize("order, steps", [(4, [16, 32, 64]), (6, [8, 16, 32])])
    def test_convective_angular_velocity_reproduces_the_path(self, order, steps):
        # hat(ω̃) = Rᵀ hat(ω) R = R⁻¹Ṙ, so integrating the space components from the right gives R(t).
        errors = [max_err(path_ordered_exponential(omega_space, (0.0, T_END), steps=n, order=order,
                                                   ordering="right", R0=R0).R[-1], exact_R(T_END)) for n in steps]
        assert errors[-1] < 1e-7
        assert fitted_order(T_END / np.array(steps), errors) == pytest.approx(order, abs=0.3)

    def test_left_ordering_of_the_convective_velocity_is_wrong(self):
        res = path_ordered_exponential(omega_space, (0.0, T_END), steps=64, ordering="left", R0=R0)
        assert max_err(res.R[-1], exact_R(T_END)) > 0.1

    def test_right_is_the_inverse_of_left_with_reversed_sign(self):
        # Ṙ = RΩ ⇔ d(R⁻¹)/dt = −Ω R⁻¹: the right-ordered solution is the transpose of a left-ordered one.
        right = path_ordered_exponential(omega_body, (0.0, 1.0), steps=30, ordering="right").R[-1]
        left = path_ordered_exponential(lambda s: -omega_body(s), (0.0, 1.0), steps=30, ordering="left").R[-1]
        assert max_err(right, left.T) < 1e-14

    def test_exponent_commutator_sign_flips(self):
        nodes = np.array([[1.0, 0.2, 0.0], [0.1, 1.0, 0.5]])
        left = magnus_exponent_from_nodes(nodes, 0.3, ordering="left")
        right = magnus_exponent_from_nodes(nodes, 0.3, ordering="right")
        average = 0.15 * nodes.sum(axis=0)
        assert max_err(left - average, -(right - average)) < 1e-16
        assert max_err(left, right) > 1e-3


# ----------------------------------------------------------------------------- (3.12) the naive exponential

class TestNaiveExponential_3_12:
    def test_fixed_axis_is_right(self):
        # Quadrature to 1e-13, Rodrigues to rounding: agreement to 1e-12 with the Magnus solution.
        n = np.array([0.0, 0.6, 0.8])
        w = lambda s: np.outer(np.cos(s) + 2, n)  # noqa: E731 - fixed axis, varying rate
        ts = np.array([0.5, 1.0, 3.0])
        naive = naive_exponential(w, ts)
        res = path_ordered_exponential(w, (0.0, 3.0), steps=200, order=6, t_eval=ts)
        assert naive.shape == (3, 3, 3)
        assert max_err(naive, res.R) < 1e-12
        assert max_err(naive, expm_so3(np.outer(np.sin(ts) + 2 * ts, n))) < 1e-12

    def test_turning_axis_is_wrong(self):
        ts = np.array([0.5, 1.0, T_END])
        naive = naive_exponential(omega_body, ts) @ R0  # exp(∫ω) R0, the naive guess from R(0) = R0
        assert max_err(naive, exact_R(ts)) > 0.05

    def test_turning_axis_error_starts_at_third_order(self):
        # exp(M) − P exp(∫ω) = ½∫∫[ω(t''), ω(t')] + … = O(t³) when ω is smooth: fitted exponent 3 ± 0.3.
        ts = np.array([0.01, 0.02, 0.04])
        naive = naive_exponential(omega_body, ts)
        exact = path_ordered_exponential(omega_body, (0.0, 0.04), steps=40, order=6, t_eval=ts).R
        errors = [max_err(a, b) for a, b in zip(naive, exact)]
        assert fitted_order(ts, errors) == pytest.approx(3, abs=0.3)


# ----------------------------------------------------------------------------- the catalog, section 3.1.2

CLAIMS = all_claims("3.1.2")


def test_catalog_covers_3_11_to_3_16():
    assert {c.equation.split()[0] for c in CLAIMS} == {"3.11", "3.12", "3.13", "3.14", "3.15", "3.16"}


@pytest.mark.parametrize("claim", CLAIMS, ids=[c.equation for c in CLAIMS])
def test_claim_status(claim, claims_checked_once):
    result = verified(claim)
    expected = "misprint" if claim.equation == "3.16" else "verified"
    assert result.status == expected, result.detail


# The generic perturbation of each member of the passing form is test_catalog's
# test_check_fails_when_a_member_is_perturbed; here, each claim's own hand-made wrong form.
PERTURBED = [c for c in CLAIMS if c.perturbed is not None]


@pytest.mark.parametrize("claim", PERTURBED, ids=[c.equation for c in PERTURBED])
def test_perturbed_formula_fails(claim):
    assert not claim.check(claim.perturbed()).passed


def _claim(equation):
    return next(c for c in CLAIMS if c.equation == equation)


def test_3_15_opposite_ordering_fails():
    from mechderive.catalog.s3_1_path_ordered import dyson_second_order

    outcome = _claim("3.15").check(dyson_second_order(later_on_left=False))
    assert not outcome.passed and "ε^2" in outcome.detail  # the misordered series is only first-order right


def test_3_16_opposite_ordering_fails():
    from mechderive.catalog.s3_1_path_ordered import _ordered_double_integral

    assert not _claim("3.16").check(_ordered_double_integral(later_on_left=False)).passed


def test_3_16_printed_limits_leave_free_variables():
    detail = evaluate(_claim("3.16")).detail
    assert "depends on t', t''" in detail


# ----------------------------------------------------------------------------- bad input

def w_ok(s):
    return np.tile([0.0, 0.0, 1.0], (np.size(s), 1))


class TestBadInput:
    def test_non_finite_omega(self):
        with pytest.raises(NonFiniteValueError, match=r"expected `omega\(t\)` to be finite, got nan"):
            path_ordered_exponential(lambda s: np.full((len(s), 3), np.nan), (0, 1), steps=2)

    def test_non_finite_scalar_omega(self):
        with pytest.raises(NonFiniteValueError, match=r"expected `omega\(t\)` to be finite, got inf"):
            path_ordered_exponential(lambda s: [float(s), np.inf, 0.0], (0, 1), steps=2)

    def test_omega_wrong_shape(self):
        with pytest.raises(ShapeError, match=r"expected `omega\(t\)` to have shape \(3,\), got \(2,\)"):
            path_ordered_exponential(lambda s: np.array([1.0, 2.0]), (0, 1), steps=2)

    def test_omega_transposed(self):
        with pytest.raises(ShapeError, match=r"expected omega\(t\) of shape \(N, 3\) .* got \(3, N\)"):
            path_ordered_exponential(lambda s: np.array([s, s, s]), (0, 1), steps=2)

    def test_omega_not_callable(self):
        with pytest.raises(InvalidInputError, match="expected `omega` to be a callable .* got ndarray"):
            path_ordered_exponential(np.zeros(3), (0, 1), steps=2)

    def test_t_end_before_t0(self):
        with pytest.raises(InvalidInputError, match="expected t_end > t0 in `t_span`, got t0=1.0, t_end=0.5"):
            path_ordered_exponential(w_ok, (1.0, 0.5), steps=2)

    def test_t_span_shape_and_finiteness(self):
        with pytest.raises(ShapeError, match=r"expected `t_span` to have shape \(2,\), got \(3,\)"):
            path_ordered_exponential(w_ok, (0, 1, 2), steps=2)
        with pytest.raises(NonFiniteValueError, match="expected `t_span` to be finite, got inf"):
            path_ordered_exponential(w_ok, (0, np.inf), steps=2)

    @pytest.mark.parametrize("steps", [0, -3, 2.5, True])
    def test_steps_below_one_or_not_integer(self, steps):
        with pytest.raises(InvalidInputError, match=r"expected `steps` to be an integer >= 1, got"):
            path_ordered_exponential(w_ok, (0, 1), steps=steps)

    def test_steps_and_rtol_exclusive(self):
        with pytest.raises(InvalidInputError, match="expected exactly one of `steps`.*got steps=None, rtol=None"):
            path_ordered_exponential(w_ok, (0, 1))
        with pytest.raises(InvalidInputError, match="expected exactly one of `steps`.*got steps=3, rtol=0.001"):
            path_ordered_exponential(w_ok, (0, 1), steps=3, rtol=1e-3)

    def test_rtol(self):
        with pytest.raises(InvalidInputError, match=r"expected `rtol` > 0, got -1.0"):
            path_ordered_exponential(w_ok, (0, 1), rtol=-1.0)
        with pytest.raises(InvalidInputError, match=r"expected `rtol` >= 1e-13 \(double rounding\), got 1e-16"):
            path_ordered_exponential(w_ok, (0, 1), rtol=1e-16)

    def test_max_steps_exceeded(self):
        with pytest.raises(InvalidInputError, match="expected at most max_steps=5 steps"):
            path_ordered_exponential(lambda s: np.outer(np.ones_like(s), [50.0, 0, 3]) * np.sin(40 * s)[:, None],
                                     (0, 1), rtol=1e-10, max_steps=5)

    def test_order_and_ordering(self):
        with pytest.raises(InvalidInputError, match="expected `order` 4 or 6, got 5"):
            path_ordered_exponential(w_ok, (0, 1), steps=2, order=5)
        with pytest.raises(InvalidInputError, match="expected `ordering` 'left' .* or 'right' .*, got 'middle'"):
            path_ordered_exponential(w_ok, (0, 1), steps=2, ordering="middle")

    def test_R0_not_a_rotation(self):
        with pytest.raises(NotARotationError, match=r"expected `R0` orthogonal"):
            path_ordered_exponential(w_ok, (0, 1), steps=2, R0=2 * np.eye(3))
        with pytest.raises(NotARotationError, match=r"expected `R0` to have det \+1"):
            path_ordered_exponential(w_ok, (0, 1), steps=2, R0=np.diag([1.0, 1.0, -1.0]))
        with pytest.raises(ShapeError, match=r"expected `R0` to have shape \(3, 3\), got \(2, 3, 3\)"):
            path_ordered_exponential(w_ok, (0, 1), steps=2, R0=np.stack([np.eye(3)] * 2))

    def test_t_eval(self):
        with pytest.raises(InvalidInputError, match=r"expected `t_eval` within t_span \[0.0, 1.0\], got values in"):
            path_ordered_exponential(w_ok, (0, 1), steps=2, t_eval=[0.5, 1.5])
        with pytest.raises(InvalidInputError, match="expected strictly increasing `t_eval`"):
            path_ordered_exponential(w_ok, (0, 1), steps=2, t_eval=[0.5, 0.2])

    def test_samples(self):
        times = np.linspace(0, 1, 5)
        with pytest.raises(InvalidInputError, match="expected strictly increasing `times`"):
            sampled_angular_velocity(times[::-1], np.zeros((5, 3)))
        with pytest.raises(InvalidInputError, match="expected at least 4 samples for a cubic spline, got 3"):
            sampled_angular_velocity(times[:3], np.zeros((3, 3)))
        with pytest.raises(ShapeError, match=r"expected `values` of shape \(5, 3\) to match `times`, got \(4, 3\)"):
            sampled_angular_velocity(times, np.zeros((4, 3)))
        with pytest.raises(InvalidInputError, match=r"expected the time span within the samples \[0.0, 1.0\]"):
            path_ordered_exponential((times, np.zeros((5, 3))), (0, 2), steps=2)

    def test_naive_exponential_non_finite_time(self):
        with pytest.raises(NonFiniteValueError, match="expected `t` to be finite, got nan"):
            naive_exponential(w_ok, [0.5, np.nan])
