"""mechderive.special against mpmath at 30 digits, identities by DLMF number, and every error message.

References are built with the *exact* parameter: when m1 is given, mpmath gets m = 1 - m1
formed at 30 digits, so the reference is not limited by the rounding of 1 - m1 in double.

Tolerances (EPS = 2.2e-16, one ulp of 1):
* JAC_RTOL = 10 EPS — sn, cn, dn are evaluated to a few ulp *relative* (measured <= 4 ulp,
  including cn near its zeros and dn ≈ √m1); the rest is headroom for libm differences.
* K_ATOL = 4e-32 per unit of |u| — K is carried in double-double (~1e-32 relative, measured
  <= 1.2e-32), so reducing u by j·2K leaves an absolute error ~1e-32·|u|: invisible except in
  relative terms next to a zero of sn or cn at huge u.
* INT_RTOL = 8 EPS — F, E and Π (n <= 0.3) are sums of positive Carlson terms (measured <= 2 ulp).
* PI_RTOL = 16 EPS — for n = 0.99 the R_J term is ~100 K and SciPy's R_J is itself off by up to
  3 ulp on these unbalanced arguments (measured 7.6 ulp overall).
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import scipy.special
from hypothesis import given, settings
from hypothesis import strategies as st

from mechderive.errors import InvalidInputError, NonFiniteValueError
from mechderive.special import (
    ellipk_m1,
    elliptic_e,
    elliptic_e_incomplete,
    elliptic_f,
    elliptic_pi,
    elliptic_pi_incomplete,
    jacobi_am,
    jacobi_sn_cn_dn,
    pi_of_am,
)

EPS = float(np.finfo(float).eps)
JAC_RTOL = 10 * EPS
K_ATOL = 4e-32
INT_RTOL = 8 * EPS
PI_RTOL = 16 * EPS

M1_GRID = [1.0, 0.5, 1e-1, 1e-3, 1e-6, 1e-9, 1e-10, 1e-12, 1e-14, 0.0]
M_GRID = [0.0, 1e-12, 0.38, 0.9]
N_GRID = [-10.0, -0.5, 0.3, 0.99]


# ---------------------------------------------------------------- references (mpmath, 30 digits)

def _param(m1: float | None = None, m: float | None = None):
    """(m passed to mechderive, m1 keyword, exact mpmath m formed at 30 digits)."""
    with mpmath.workdps(30):
        if m1 is not None:
            return 1.0 - m1, m1, 1 - mpmath.mpf(m1)
        return m, None, mpmath.mpf(m)


def _ref_jacobi(u, mm):
    with mpmath.workdps(30):
        x = mpmath.mpf(u) if not isinstance(u, mpmath.mpf) else u
        return [mpmath.ellipfun(f, x, m=mm) for f in ("sn", "cn", "dn")]


def _ref_am(u, mm):
    """am(u|m) = jπ + atan2(sn r, cn r), u = j·2K + r (m < 1); gd(u) at m = 1."""
    with mpmath.workdps(30):
        x = mpmath.mpf(u) if not isinstance(u, mpmath.mpf) else u
        if mm == 1:
            return mpmath.atan(mpmath.sinh(x))
        K = mpmath.ellipk(mm)
        j = mpmath.nint(x / (2 * K))
        r = x - 2 * j * K
        return j * mpmath.pi + mpmath.atan2(mpmath.ellipfun("sn", r, m=mm), mpmath.ellipfun("cn", r, m=mm))


def _real(z):
    """mpmath returns the principal value of Π for n > 1 as the real part of a complex number."""
    return z.real if isinstance(z, mpmath.mpc) else z


def _max_excess(got, refs, rtol, atol):
    """max over points of |got - ref| / (rtol |ref| + atol); <= 1 means within tolerance."""
    got = np.atleast_1d(got)
    atol = np.broadcast_to(atol, got.shape)
    worst = 0.0
    for g, r, a in zip(got, refs, atol):
        err = abs(mpmath.mpf(float(g)) - r)
        worst = max(worst, float(err / (rtol * abs(r) + a)) if (rtol * abs(r) + a) > 0 else float(err > 0) * np.inf)
    return worst


def _jacobi_points(K: float, count: int) -> np.ndarray:
    if not np.isfinite(K):
        return np.concatenate([np.linspace(0.0, 30.0, count), [1e-8, 400.0]])
    base = np.linspace(0.0, 4 * K, count)
    # next to the zeros of cn and sn, and v = K/2, where cn and dn are hardest in relative terms
    near = [K * (1 - 1e-9), K * (1 + 1e-9), 2 * K - 1e-7, 3 * K + 1e-3, 1e-8,
            0.45 * K, 0.5 * K, 0.55 * K, 1.5 * K, 2.5 * K, 3.45 * K]
    return np.concatenate([base, near])


def _check_jacobi(u, m, m1, mm, count_label=""):
    sn, cn, dn = jacobi_sn_cn_dn(u, m, m1=m1)
    with mpmath.workdps(30):
        K = float(mpmath.ellipk(mm)) if mm != 1 else np.inf
    refs = [_ref_jacobi(float(x), mm) for x in u]
    atol = K_ATOL * (np.abs(u) + (K if np.isfinite(K) else 0.0))
    for name, got, column in (("sn", sn, 0), ("cn", cn, 1), ("dn", dn, 2)):
        excess = _max_excess(got, [r[column] for r in refs], JAC_RTOL, atol)
        assert excess <= 1.0, f"{name} {count_label}: error {excess:.2f}× tolerance"


# ---------------------------------------------------------------- Jacobi functions

@pytest.mark.parametrize("m1", M1_GRID)
def test_jacobi_against_mpmath_on_one_period_by_m1(m1):
    m, m1_kw, mm = _param(m1=m1)
    K = float(ellipk_m1(m1))
    _check_jacobi(_jacobi_points(K, 13), m, m1_kw, mm, f"m1={m1:g}")


@pytest.mark.parametrize("m", M_GRID)
def test_jacobi_against_mpmath_on_one_period_by_m(m):
    m_, _, mm = _param(m=m)
    with mpmath.workdps(30):
        K = float(mpmath.ellipk(mm))
    _check_jacobi(_jacobi_points(K, 13), m_, None, mm, f"m={m:g}")


@pytest.mark.parametrize("m1", [0.5, 1e-3, 1e-9, 1e-14])
@pytest.mark.parametrize("periods", [10**4, 10**6])
def test_jacobi_at_many_periods_plain_u_and_periods_form(m1, periods):
    """u = n·4K + r: the plain double u is reduced exactly; ``periods=n`` loses nothing at all."""
    m, m1_kw, mm = _param(m1=m1)
    with mpmath.workdps(30):
        K_mp = mpmath.ellipk(mm)
    K = float(K_mp)
    r = np.array([0.3, 0.77 * K, 2.5 * K])
    # plain u: the reference is at the double u itself
    u = periods * 4 * K + r
    atol = K_ATOL * (np.abs(u) + K)
    got = jacobi_sn_cn_dn(u, m, m1=m1)
    refs = [_ref_jacobi(float(x), mm) for x in u]
    for column in range(3):
        assert _max_excess(got[column], [ref[column] for ref in refs], JAC_RTOL, atol) <= 1.0
    # periods form: the reference is at the exact n·4K + r
    got = jacobi_sn_cn_dn(r, m, m1=m1, periods=periods)
    with mpmath.workdps(30):
        refs = [_ref_jacobi(periods * 4 * K_mp + mpmath.mpf(float(x)), mm) for x in r]
    for column in range(3):
        assert _max_excess(got[column], [ref[column] for ref in refs], JAC_RTOL, 0.0) <= 1.0


def test_plain_u_error_at_1e6_periods_is_the_rounding_of_u_itself():
    """Documented residual: n·4K + r rounded to double moves the phase by <= ulp(u)/2."""
    m1 = 0.62
    K = float(ellipk_m1(m1))
    n, r = 10**6, 0.7
    u = n * 4 * K + r
    exact = jacobi_sn_cn_dn(r, 1 - m1, m1=m1, periods=n)[0]
    plain = jacobi_sn_cn_dn(u, 1 - m1, m1=m1)[0]
    assert abs(plain - exact) <= 0.5 * np.spacing(u) + abs(r - (u - n * 4 * K)) + 4 * EPS
    assert abs(plain - exact) > 0  # and it is not zero: the caller's rounding is real


def test_scipy_ellipj_fails_near_the_separatrix_where_this_module_does_not():
    """Why the module exists: at 1 - m = 1e-12 SciPy's ellipj is wrong by O(1) and more."""
    m = 1 - 1e-12
    m1 = 1.0 - m  # the exact complement of the double m: both codes get the same parameter
    mm = mpmath.mpf(m)  # exact: a double
    K = float(ellipk_m1(m1))
    u = np.linspace(0.1, 4 * K, 9)
    refs = [_ref_jacobi(float(x), mm) for x in u]
    ours = jacobi_sn_cn_dn(u, m, m1=m1)
    theirs = scipy.special.ellipj(u, m)[:3]

    def worst(values):
        return max(float(abs(mpmath.mpf(float(v)) - ref[c])) for c in range(3) for v, ref in zip(values[c], refs))

    assert worst(theirs) > 1e-2
    assert worst(ours) < 1e-15


def test_passing_m1_keeps_digits_that_m_alone_has_lost():
    """m = 1 - 1e-14 rounds m1 to 9.99e-15: dn near K then differs by ~1e-3 relative."""
    m1 = 1e-14
    K = float(ellipk_m1(m1))
    ref = _ref_jacobi(K, _param(m1=m1)[2])[2]
    with_m1 = jacobi_sn_cn_dn(K, 1 - m1, m1=m1)[2]
    without = jacobi_sn_cn_dn(K, 1 - m1)[2]
    assert abs(with_m1 - ref) / ref < JAC_RTOL
    assert abs(without - ref) / ref > 1e-5


def test_special_cases_m0_and_m1():
    u = np.linspace(-20, 20, 41)
    sn, cn, dn = jacobi_sn_cn_dn(u, 0.0)
    np.testing.assert_allclose(sn, np.sin(u), rtol=0, atol=4 * EPS)
    np.testing.assert_allclose(cn, np.cos(u), rtol=0, atol=4 * EPS)
    np.testing.assert_array_equal(dn, 1.0)
    np.testing.assert_allclose(jacobi_am(u, 0.0), u, rtol=2 * EPS, atol=0)
    sn, cn, dn = jacobi_sn_cn_dn(u, 1.0)
    np.testing.assert_allclose(sn, np.tanh(u), rtol=2 * EPS)
    np.testing.assert_allclose(cn, 1 / np.cosh(u), rtol=4 * EPS)
    np.testing.assert_allclose(dn, 1 / np.cosh(u), rtol=4 * EPS)
    np.testing.assert_allclose(jacobi_am(u, 1.0), np.arctan(np.sinh(u)), rtol=4 * EPS)


@pytest.mark.parametrize("m1", [1.0, 0.5, 1e-3, 1e-9, 1e-14, 0.0])
def test_am_against_mpmath_and_unwrapped(m1):
    m, m1_kw, mm = _param(m1=m1)
    K = float(ellipk_m1(m1))
    u = _jacobi_points(K, 9)
    if np.isfinite(K):
        u = np.concatenate([u, -u, [10**4 * 4 * K + 0.3]])
    got = jacobi_am(u, m, m1=m1_kw)
    refs = [_ref_am(float(x), mm) for x in u]
    # am is O(|u|): a few ulp of the result plus the reduction's ~1e-32·(|u| + K)
    assert _max_excess(got, refs, JAC_RTOL, K_ATOL * (np.abs(u) + (K if np.isfinite(K) else 1.0))) <= 1.0
    if np.isfinite(K):
        # am(u + 2K) = am(u) + π (DLMF 22.16.2) and periods add 2π each
        v = np.array([0.1, 0.9 * K])
        np.testing.assert_allclose(jacobi_am(v, m, m1=m1_kw, periods=3) - jacobi_am(v, m, m1=m1_kw),
                                   6 * np.pi, rtol=4 * EPS)
        t = np.linspace(-3 * K, 3 * K, 301)
        assert np.all(np.diff(jacobi_am(t, m, m1=m1_kw)) > 0)  # continuous and increasing


def test_broadcasting_and_scalars():
    """A column of parameters (mixing the Gauss and the sech-series paths) equals row-by-row calls."""
    u = np.linspace(0, 3, 4)
    m = np.array([[0.1], [0.5], [0.99], [1 - 1e-6], [1.0]])
    sn, cn, dn = jacobi_sn_cn_dn(u, m)
    assert sn.shape == cn.shape == dn.shape == (5, 4)
    for row, m_row in enumerate(m[:, 0]):
        for got, alone in zip((sn, cn, dn), jacobi_sn_cn_dn(u, m_row)):
            np.testing.assert_array_equal(got[row], alone)
    assert isinstance(jacobi_sn_cn_dn(0.5, 0.3)[0], np.floating)
    assert elliptic_pi_incomplete(np.array([[0.3], [-2.0]]), u, 0.5).shape == (2, 4)
    assert pi_of_am(0.3, u, m).shape == (5, 4)


# ---------------------------------------------------------------- identities (hypothesis)

_m1s = st.one_of(st.sampled_from([0.0, 1.0, 1e-14, 1e-10]), st.floats(-15, 0).map(lambda e: 10.0**e))
_dyadic = st.integers(-2**26, 2**26).map(lambda k: k * 2.0**-20)  # |u| <= 64, u + v exact


@settings(max_examples=150, deadline=None, derandomize=True)
@given(u=_dyadic, v=_dyadic, m1=_m1s)
def test_pythagorean_and_addition_identities(u, v, m1):
    """sn² + cn² = 1, dn² + m sn² = 1 (DLMF 22.6.1); addition theorems (DLMF 22.8.1-3)."""
    m = 1.0 - m1
    (su, sv, sw), (cu, cv, cw), (du, dv, dw) = jacobi_sn_cn_dn(np.array([u, v, u + v]), m, m1=m1)
    assert abs(su * su + cu * cu - 1) <= 4 * EPS
    assert abs(du * du + m * su * su - 1) <= 4 * EPS
    den = du * du + m * su * su * cv * cv  # = 1 - m sn²u sn²v, without cancellation
    terms = (abs(su * cv * dv) + abs(sv * cu * du), abs(cu * cv) + abs(su * sv * du * dv),
             abs(du * dv) + m * abs(su * sv * cu * cv))
    rhs = ((su * cv * dv + sv * cu * du) / den, (cu * cv - su * sv * du * dv) / den,
           (du * dv - m * su * sv * cu * cv) / den)
    for lhs, r, size in zip((sw, cw, dw), rhs, terms):
        assert abs(lhs - r) <= 16 * EPS * (size / den + 1)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(u=st.floats(-200, 200), m1=st.floats(-6, 0).map(lambda e: 10.0**e))
def test_f_of_am_is_the_identity(u, m1):
    """F(am(u|m)|m) = u (DLMF 22.16.1); dF/dφ = 1/Δ <= 1/√m1 amplifies am's rounding."""
    got = elliptic_f(jacobi_am(u, 1 - m1, m1=m1), 1 - m1, m1=m1)
    assert abs(got - u) <= 8 * EPS * (abs(u) + 1) / np.sqrt(m1)


# ---------------------------------------------------------------- integrals

_PHIS = np.array([0.1, 1.3, np.pi / 2, 2.0, -4.0, 1e4 + 0.3])


@pytest.mark.parametrize("m1", M1_GRID[:-1])
def test_f_e_and_k_against_mpmath(m1):
    m, m1_kw, mm = _param(m1=m1)
    with mpmath.workdps(30):
        assert _max_excess(ellipk_m1(m1), [mpmath.ellipk(mm)], EPS, 0) <= 1.0  # correctly rounded
        assert _max_excess(elliptic_e(m, m1=m1_kw), [mpmath.ellipe(mm)], INT_RTOL, 0) <= 1.0
        f_ref = [mpmath.ellipf(mpmath.mpf(float(p)), mm) for p in _PHIS]
        e_ref = [mpmath.ellipe(mpmath.mpf(float(p)), mm) for p in _PHIS]
    assert _max_excess(elliptic_f(_PHIS, m, m1=m1_kw), f_ref, INT_RTOL, 0) <= 1.0
    assert _max_excess(elliptic_e_incomplete(_PHIS, m, m1=m1_kw), e_ref, INT_RTOL, 0) <= 1.0




@pytest.mark.parametrize("dtype", [np.float64, np.longdouble])
def test_carlson_of_one_point_is_the_arrays_bit_for_bit(dtype):
    """R_F (DLMF 19.16.1) and R_J (19.16.2) of one point run Carlson's steps on Python floats or longdouble scalars
    (the closed forms' setups): the same operations as the array code, so the same bits — checked against the
    array code on points of every size, with a zero argument, and far from order one."""
    from mechderive.special import _carlson

    rng = np.random.default_rng(16)
    for trial in range(400):
        v = [rng.uniform(0, 2, 4), 10.0 ** rng.uniform(-30, 30, 4), 10.0 ** rng.uniform(-300, 300, 4)][trial % 3]
        if trial % 5 == 0:
            v[trial % 3] = 0.0
        x, y, z, p = (np.asarray(a, dtype=dtype) for a in v)
        with np.errstate(all="ignore"):
            pair = [np.stack([a, a]) for a in (x, y, z)]  # an array of two: the array code
            for args, ref in (((x, y, z), _carlson.elliprf(*pair)[0]), ((x, y, z, p), _carlson._rj_positive(x, y, z, p))):
                call = _carlson.elliprf if len(args) == 3 else _carlson.elliprj
                for shaped in (args, tuple(a.reshape(1) for a in args)):
                    got = call(*shaped)
                    assert got.dtype == dtype and np.shape(got) == np.shape(shaped[0])
                    assert np.asarray(got).reshape(-1)[0] == ref or (np.isnan(got).all() and np.isnan(ref)), (v, call)

def test_quarter_period_of_one_value_is_the_arrays_bit_for_bit_and_32_digit():
    """K(m) = π/(2 M(1, √m1)) (DLMF 19.8.5): one value runs the double-double AGM on Python floats, arrays on
    NumPy — the same IEEE operations, so the same bits; both against mpmath at 40 digits to 2e-31 relative
    (double-double's ~106 bits, with the AGM's ~6 steps of rounding)."""
    from mechderive.special import _parameter

    rng = np.random.default_rng(15)
    m1 = np.concatenate([rng.uniform(0, 1, 60), 10.0 ** rng.uniform(-300, 0, 60), [1.0, 0.5, 2.0**-900, 5e-324]])
    lo = np.concatenate([m1[:-4] * rng.uniform(-1, 1, len(m1) - 4) * 1e-17, np.zeros(4)])
    _parameter._quarter_period_scalar.cache_clear()
    for i in range(len(m1)):
        # (an array of one: an array's AGM runs to its slowest element's convergence, which can move the last bit)
        arr_hi, arr_lo = _parameter._quarter_period(m1[i:i + 1], lo[i:i + 1])
        one_hi, one_lo = _parameter.quarter_period(np.array([m1[i]]), np.array([lo[i]]))
        assert (one_hi[0], one_lo[0]) == (arr_hi[0], arr_lo[0]), m1[i]
        with mpmath.workdps(40 + max(0, int(-np.log10(m1[i])))):  # 40 digits of m = 1 - m1 past m1's own
            ref = mpmath.ellipk(1 - (mpmath.mpf(float(m1[i])) + mpmath.mpf(float(lo[i]))))
            assert abs((mpmath.mpf(float(one_hi[0])) + mpmath.mpf(float(one_lo[0]))) / ref - 1) < 2e-31, m1[i]

@pytest.mark.parametrize("m1", M1_GRID[:-1])
@pytest.mark.parametrize("n", N_GRID)
def test_pi_against_mpmath(m1, n):
    m, m1_kw, mm = _param(m1=m1)
    rtol = PI_RTOL if n > 0.5 else INT_RTOL
    with mpmath.workdps(30):
        refs = [mpmath.ellippi(n, mpmath.mpf(float(p)), mm) for p in _PHIS]
        ref_c = mpmath.ellippi(n, mm)
    assert _max_excess(elliptic_pi_incomplete(n, _PHIS, m, m1=m1_kw), refs, rtol, 0) <= 1.0
    assert _max_excess(elliptic_pi(n, m, m1=m1_kw), [ref_c], rtol, 0) <= 1.0


def _ref_pi_principal_value(n, phi, mm):
    """Π(n; φ|m) for n > 1 without mpmath's slow complex path past π/2.

    Complete: Π(n|m) = K(m) - Π(m/n|m) (DLMF 19.6.5, an identity independent of R_J's
    principal value); incomplete: mpmath directly on |ψ| < π/2 (its real part) plus 2jΠ(n|m).
    """
    with mpmath.workdps(30):
        complete = mpmath.ellipk(mm) - mpmath.ellippi(mm / n, mm)
        x = mpmath.mpf(float(phi))
        j = mpmath.nint(x / mpmath.pi)
        return 2 * j * complete + _real(mpmath.ellippi(n, x - j * mpmath.pi, mm)), complete


@pytest.mark.parametrize("m", [0.0, 0.38, 0.9])
def test_pi_principal_value_for_n_above_one(m):
    """n = 2: Cauchy principal value through sin²θ = 1/2 (the pole at φ = π/4 and 3π/4).

    Tolerance relative to the integral's scale max(|Π|, K): Π(2; φ|m) crosses zero.
    """
    mm = mpmath.mpf(m)  # exact: a double
    phis = np.array([0.3, 1.0, 2.0])
    refs = [_ref_pi_principal_value(2, p, mm)[0] for p in phis]
    ref_c = _ref_pi_principal_value(2, 0.0, mm)[1]
    K = float(ellipk_m1(1 - m))
    got = elliptic_pi_incomplete(2.0, phis, m)
    assert _max_excess(got, refs, PI_RTOL, PI_RTOL * K) <= 1.0
    assert _max_excess(elliptic_pi(2.0, m), [ref_c], PI_RTOL, PI_RTOL * K) <= 1.0


def test_pi_with_n_one_below_the_double_pole():
    """Π(1; φ|m) is finite for |φ| < π/2 (DLMF 19.6.13: F - (E - Δ tan φ)/m)."""
    with mpmath.workdps(30):
        ref = mpmath.ellippi(1, mpmath.mpf(1.2), mpmath.mpf(0.5))
    assert _max_excess(elliptic_pi_incomplete(1.0, 1.2, 0.5), [ref], INT_RTOL, 0) <= 1.0


@pytest.mark.parametrize("m1", [1.0, 0.5, 1e-3, 1e-9, 1e-14])
@pytest.mark.parametrize("n", N_GRID)
def test_pi_of_am_against_mpmath(m1, n):
    m, m1_kw, mm = _param(m1=m1)
    with mpmath.workdps(30):
        K_mp = mpmath.ellipk(mm)
    K = float(K_mp)
    u = np.array([0.3, 0.9 * K, 1.7 * K, -3.3 * K, 4e4 * K + 0.3, 4e6 * K + 1.1])
    rtol = PI_RTOL if n > 0.5 else INT_RTOL
    with mpmath.workdps(30):
        refs = [mpmath.ellippi(n, _ref_am(float(x), mm), mm) for x in u]
        ref_periods = mpmath.ellippi(n, _ref_am(4 * 10**6 * K_mp + mpmath.mpf(0.7), mm), mm)
    assert _max_excess(pi_of_am(n, u, m, m1=m1_kw), refs, rtol, 0) <= 1.0
    got = pi_of_am(n, 0.7, m, m1=m1_kw, periods=10**6)
    assert _max_excess(got, [ref_periods], rtol, 0) <= 1.0


def test_integral_special_cases():
    phi = np.linspace(-1.5, 1.5, 13)
    np.testing.assert_allclose(elliptic_f(phi, 0.0), phi, rtol=2 * EPS)
    np.testing.assert_allclose(elliptic_e_incomplete(phi, 0.0), phi, rtol=2 * EPS)
    np.testing.assert_allclose(elliptic_f(phi, 1.0), np.arctanh(np.sin(phi)), rtol=4 * EPS)
    np.testing.assert_allclose(elliptic_e_incomplete(phi, 1.0), np.sin(phi), rtol=2 * EPS)
    np.testing.assert_allclose(elliptic_e_incomplete(phi + 3 * np.pi, 1.0), np.sin(phi) + 6, rtol=4 * EPS)
    # Π(0; φ|m) = F(φ|m); Π(n; φ|0) = atan(√(1-n) tan φ)/√(1-n) (DLMF 19.6.12, 19.6.13)
    np.testing.assert_allclose(elliptic_pi_incomplete(0.0, phi, 0.7), elliptic_f(phi, 0.7), rtol=2 * EPS)
    for n in (-10.0, 0.3):
        a = np.sqrt(1 - n)
        np.testing.assert_allclose(elliptic_pi_incomplete(n, phi, 0.0), np.arctan(a * np.tan(phi)) / a,
                                   rtol=4 * EPS)
    # quasi-periodicity F(φ + jπ) = F(φ) + 2jK (DLMF 19.2.10); φ + 1000π is rounded to
    # double (<= ulp(3142)/2) and dF/dφ = 1/Δ <= 1/√m1, which sets the tolerance
    K = ellipk_m1(0.1)
    np.testing.assert_allclose(elliptic_f(phi + 1000 * np.pi, 0.9) - 2000 * K, elliptic_f(phi, 0.9),
                               rtol=0, atol=2 * np.spacing(3200.0) / np.sqrt(0.1))
    # pi_of_am at m = 1: [u - √n artanh(√n tanh u)]/(1 - n); n = 1: (u + sinh u cosh u)/2
    for u in (0.5, 3.0, 50.0, -400.0):
        n = 0.3
        expect = (u - np.sqrt(n) * np.arctanh(np.sqrt(n) * np.tanh(u))) / (1 - n)
        assert abs(pi_of_am(n, u, 1.0) - expect) <= 4 * EPS * abs(expect)
    assert abs(pi_of_am(1.0, 3.0, 1.0) - (3 + np.sinh(3) * np.cosh(3)) / 2) <= 4 * EPS * 104
    assert pi_of_am(0.0, 12.5, 0.3) == 12.5


# ---------------------------------------------------------------- errors

@pytest.mark.parametrize(("call", "error", "match"), [
    (lambda: jacobi_sn_cn_dn(0.1, 1.5), InvalidInputError, r"expected `m` in \[0, 1\], got 1\.5"),
    (lambda: jacobi_sn_cn_dn(0.1, -0.1), InvalidInputError, r"expected `m` in \[0, 1\], got -0\.1"),
    (lambda: jacobi_am(0.1, 0.5, m1=1.2), InvalidInputError, r"expected `m1` in \[0, 1\], got 1\.2"),
    (lambda: jacobi_sn_cn_dn(0.1, 0.5, m1=0.4), InvalidInputError,
     r"expected `m1` = 1 - `m` \(\|m \+ m1 - 1\| <= 1e-15\), got m = 0\.5, m1 = 0\.4"),
    (lambda: jacobi_sn_cn_dn(0.1, 1 - 1e-12, m1=1.1e-12), InvalidInputError, r"expected `m1` = 1 - `m`"),
    (lambda: jacobi_sn_cn_dn(np.nan, 0.5), NonFiniteValueError, r"expected `u` to be finite, got nan"),
    (lambda: elliptic_f(np.inf, 0.5), NonFiniteValueError, r"expected `phi` to be finite, got inf"),
    (lambda: jacobi_sn_cn_dn(0.1, "x"), InvalidInputError, r"expected `m` to be numeric"),
    (lambda: jacobi_sn_cn_dn(0.1, 0.5, periods=0.5), InvalidInputError,
     r"expected `periods` to be integers, got 0\.5"),
    (lambda: ellipk_m1(2.0), InvalidInputError, r"expected `m1` in \[0, 1\], got 2\.0"),
    (lambda: elliptic_pi(1.0, 0.5), InvalidInputError, r"expected `n` != 1 \(Π\(1\|m\) diverges\)"),
    (lambda: elliptic_pi(0.3, 1.0), InvalidInputError, r"expected `m` < 1 \(Π\(n\|1\) diverges\)"),
    (lambda: elliptic_pi_incomplete(1.0, 2.0, 0.5), InvalidInputError,
     r"expected \|phi\| < pi/2 when n = 1 .* got phi = 2\.0"),
    (lambda: elliptic_pi_incomplete(2.0, np.pi / 4, 0.5), InvalidInputError,
     r"expected 1 - n sin²φ != 0 \(a pole of the integrand\), got n = 2\.0, phi = 0\.785"),
    (lambda: pi_of_am(2.0, float(elliptic_f(np.pi / 4, 0.5)), 0.5), InvalidInputError,
     r"expected 1 - n sin²φ != 0 .* got n = 2\.0, u = "),
    (lambda: elliptic_f(2.0, 1.0), InvalidInputError, r"expected \|phi\| < pi/2 when m = 1 .* got phi = 2\.0"),
    (lambda: pi_of_am(1.0, 2 * ellipk_m1(0.5), 0.5), InvalidInputError, r"expected \|u\| < K\(m\) when n = 1"),
    (lambda: pi_of_am(0.3, 1.0, 1.0, periods=2), InvalidInputError, r"expected m < 1 and n != 1 with `periods`"),
    (lambda: jacobi_sn_cn_dn(1e17, 0.5), InvalidInputError, r"expected \|u\| <= 2\*\*52·K\(m\) = 8\.35.*e\+15"),
])
def test_errors(call, error, match):
    with pytest.raises(error, match=match):
        call()


# ---------------------------------------------------------------- heavier sweeps

@pytest.mark.slow
@pytest.mark.parametrize("m1", M1_GRID)
def test_jacobi_dense_sweep(m1):
    m, m1_kw, mm = _param(m1=m1)
    K = float(ellipk_m1(m1))
    _check_jacobi(_jacobi_points(K, 401), m, m1_kw, mm, f"dense m1={m1:g}")


@pytest.mark.slow
@pytest.mark.parametrize("m1", [0.5, 1e-6, 1e-12])
def test_jacobi_random_huge_arguments(m1, rng):
    m, m1_kw, mm = _param(m1=m1)
    u = rng.uniform(0, 4e7 * float(ellipk_m1(m1)), 200)
    sn, cn, dn = jacobi_sn_cn_dn(u, m, m1=m1_kw)
    refs = [_ref_jacobi(float(x), mm) for x in u]
    for column, got in enumerate((sn, cn, dn)):
        assert _max_excess(got, [r[column] for r in refs], JAC_RTOL, K_ATOL * np.abs(u)) <= 1.0


@pytest.mark.slow
@pytest.mark.parametrize("m1", [1e-1, 1e-6, 1e-12])
@pytest.mark.parametrize("n", [-100.0, -1.0, -0.3, -0.2, 0.5, 0.9])
def test_pi_more_n(m1, n):
    m, m1_kw, mm = _param(m1=m1)
    phis = np.linspace(-3.0, 3.0, 25)
    with mpmath.workdps(30):
        refs = [mpmath.ellippi(n, mpmath.mpf(float(p)), mm) for p in phis]
    assert _max_excess(elliptic_pi_incomplete(n, phis, m, m1=m1_kw), refs, PI_RTOL, 0) <= 1.0


@pytest.mark.slow
@pytest.mark.parametrize("m", [0.38, 0.9])
@pytest.mark.parametrize("n", [1.5, 2.0, 10.0])
def test_pi_principal_value_direct_mpmath(m, n):
    """mpmath's own principal value (real part) past π/2: seconds per point, hence slow."""
    mm = mpmath.mpf(m)
    phis = np.array([1.4, 2.0, 7.0])
    with mpmath.workdps(30):
        refs = [_real(mpmath.ellippi(n, mpmath.mpf(float(p)), mm)) for p in phis]
    K = float(ellipk_m1(1 - m))
    assert _max_excess(elliptic_pi_incomplete(n, phis, m), refs, PI_RTOL, PI_RTOL * K) <= 1.0


# --- Π(n; am u | m) by its Fourier series (special/pi_series.py) -------------------------------------

@pytest.mark.parametrize("m, ns", [(0.0903793566, (0.5524676, -0.0875324)),   # the BASELINE top's n±
                                   (0.5, (0.9, -3.0)), (0.999, (0.5, -0.5)), (0.0, (0.3, -1.0))])
def test_pi_series_matches_30_digit_mpmath(m, ns):
    from mechderive.special import ellipk_m1, jacobi_sn_cn_dn
    from mechderive.special.pi_series import fit_pi_series

    K = float(ellipk_m1(1.0 - m))
    series = fit_pi_series(np.array(ns), lambda u: jacobi_sn_cn_dn(u, m)[0] ** 2, K)
    assert series is not None
    u = np.array([0.0, 0.3, K - 1e-9, K, 1.7 * K, 2 * K, 7.25 * K, -3.1])  # Π is defined for every real u
    values = series(u)
    with mpmath.workdps(30):
        Kmp = mpmath.ellipk(m)
        for i, n in enumerate(ns):
            for x, v in zip(u, values[i]):
                # Π(n; am u | m) by mpmath's ellippi (Carlson's R_F, R_J) at the amplitude: with x = 2jK + r, |r| ≤ K,
                # am x = jπ + atan2(sn r, cn r) (am(u + 2K) = am u + π), within one half period of the angle
                j = int(mpmath.nint(mpmath.mpf(float(x)) / (2 * Kmp)))
                r = mpmath.mpf(float(x)) - 2 * j * Kmp
                amplitude = j * mpmath.pi + mpmath.atan2(mpmath.ellipfun("sn", r, m=m), mpmath.ellipfun("cn", r, m=m))
                ref = mpmath.ellippi(n, amplitude, m)
                # a few ulp of the largest value over the points (the series' rounding is absolute)
                assert abs(v - float(ref)) <= 8e-16 * max(1.0, float(np.max(np.abs(values[i])))), (n, x)


def test_pi_series_declines_slow_convergence():
    from mechderive.special import ellipk_m1, jacobi_sn_cn_dn
    from mechderive.special.pi_series import fit_pi_series

    K = float(ellipk_m1(0.7))
    # n → 1: the integrand's pole approaches the real axis (an apex passing near the pole)
    assert fit_pi_series(np.array([0.99999]), lambda u: jacobi_sn_cn_dn(u, 0.3)[0] ** 2, K) is None
    K = float(ellipk_m1(1e-30))
    # m → 1: the period grows (K ≈ 36) and the series of a near-separatrix motion needs too many terms
    assert fit_pi_series(np.array([0.5]), lambda u: jacobi_sn_cn_dn(u, 1 - 1e-30, m1=1e-30)[0] ** 2, K) is None
