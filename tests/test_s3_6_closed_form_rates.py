"""§3.6 generalised (issue 16): cyclic rates with poles on the motions whose u is rational in an exponential of t
(m = 0, m = 1, the exponential and polynomial forms), and the time along an orbit — Kepler's t(φ).

References, each independent of the partial fractions under test: Kepler's equation M = E − e sin E (and the
hyperbolic M = e sinh H − H) written here by hand and evaluated at 30 digits; 2π a^{3/2}/√(GM) for the orbital
period; mpmath's quadrature at 30 digits of the rate along u(τ) written here from the form's definition
(u = M(sin²v), M(tanh²v), α + p₊e^{κt} + p₋e^{−κt}, u0 + s t + a t²); SymPy for the identities the forms rest on.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechderive.solvers.quadrature_motion import NotElliptic, elliptic_motion, rate_integral

KEPLER = "m/2*(r_dot**2 + r**2*phi_dot**2) + k/r"


# --- the forms' identities, by SymPy ------------------------------------------------------------------------

def test_the_forms_of_u_in_x_are_identities():
    """w = sin²v = −(x − 1)²/(4x) at x = e^{2iv}; tanh²v = (x − 1)²/(x + 1)² at x = e^{2v}; α + p₊e^{κt} + p₋e^{−κt}
    = (p₊x² + αx + p₋)/x at x = e^{κt} — the U(x)/S(x) of mechderive.solvers.quadrature_rational, by difference."""
    v, t, kappa, alpha, pp, pm, y = sp.symbols("v t kappa alpha p_plus p_minus y", real=True)

    def identity(lhs, rhs, exponential, symbol):
        # both sides rational in y = the exponential once rewritten: their difference cancels to 0
        difference = (lhs - rhs).rewrite(sp.exp).subs(exponential, y)
        return sp.cancel(sp.together(difference)) == 0 and not difference.has(symbol)

    x = sp.exp(2 * sp.I * v)
    assert identity(sp.sin(v) ** 2, -(x - 1) ** 2 / (4 * x), sp.exp(sp.I * v), v)
    X = sp.exp(2 * v)
    assert identity(sp.tanh(v) ** 2, (X - 1) ** 2 / (X + 1) ** 2, sp.exp(v), v)
    E = sp.exp(kappa * t)
    assert identity(alpha + pp * E + pm / E, (pp * E**2 + alpha * E + pm) / E, E, t)


def _F_and_parts(integral, x):
    """F(x) = R(u(x))·dτ/dx and the sum of its partial fractions, at a complex x (working precision)."""
    from mechderive.solvers.quadrature_rational import _u_of_x

    U, S = _u_of_x(integral.motion, integral.path)
    parts = sum(q * x**k for k, q in enumerate(integral.quotient))
    for rho, _, coefs in integral.poles:
        parts += sum(c / (x - rho) ** k for k, c in enumerate(coefs, start=1))
    return U, S, parts


def test_partial_fractions_reproduce_the_rate_at_random_points():
    """Kepler's dt/dφ = 1/(ℓu²) on the circle (a double pole at u = 0 → two double poles in x, and x = 0) and a rate
    with a complex pair and a real pole on the ray (a separatrix): F(x) against Σ principal parts + polynomial at
    random complex x, 40 digits — the decomposition is the formula, so it must hold to the working precision."""
    rng = np.random.default_rng(7)
    ell = 1.2
    circle = elliptic_motion([-1.0, 2 / ell**2, -0.4 / ell**2], 1.0, 1)
    ray = elliptic_motion(2.0 * np.poly((-1.0, 1.0, 1.0)), 0.0, 1)  # a separatrix, u from −1 towards 1
    cases = [(circle, [1.0], [ell, 0.0, 0.0], 2j), (ray, [1.0, 0.5], [1.0, 0.0, 0.3, 3.0], 2)]
    with mpmath.workdps(40):
        for motion, num, den, gamma in cases:
            integral = rate_integral(motion, num, den)
            for _ in range(4):
                x = mpmath.mpc(*rng.normal(size=2))
                U, S, parts = _F_and_parts(integral, x)
                u = mpmath.polyval(U[::-1], x) / mpmath.polyval(S[::-1], x)
                F = mpmath.polyval(num, u) / mpmath.polyval(den, u) / (motion.kappa * gamma * x)
                assert abs(F - parts) <= mpmath.mpf(10) ** -30 * abs(F)


# --- Kepler: the time along the orbit ------------------------------------------------------------------------

def _orbit(initial):
    from mechderive.systems.lagrangian import from_lagrangian
    from mechderive.systems.lagrangian.closed import closed_orbit

    system = from_lagrangian(KEPLER, ["r", "phi"], ["m", "k"])
    return closed_orbit(system, "phi", dict(m=1.0, k=1.0), initial)


def _elements(initial):
    """(ℓ, E, e, f0) of the orbit (GM = m = 1), by hand: ℓ = r²φ̇, e² = 1 + 2Eℓ², r = ℓ²/(1 + e cos f) and ṙ = (e/ℓ)
    sin f give the true anomaly at the start, f0."""
    mp = mpmath.mp
    r, rd, pd = (mp.mpf(initial[k]) for k in ("r", "r_dot", "phi_dot"))
    ell = r * r * pd
    E = (rd**2 + (r * pd) ** 2) / 2 - 1 / r
    e = mp.sqrt(1 + 2 * E * ell**2)
    return ell, E, e, mp.atan2(rd * ell / e, (ell**2 / r - 1) / e)


def _mean_anomaly(f, e):
    """M = E − e sin E at the true anomaly f (mpmath), tan(E/2) = √((1 − e)/(1 + e)) tan(f/2), E unwrapped by f's turns."""
    turns = mpmath.nint(f / (2 * mpmath.pi))
    ecc = 2 * mpmath.atan(mpmath.sqrt((1 - e) / (1 + e)) * mpmath.tan(f / 2)) + 2 * mpmath.pi * turns
    return ecc - e * mpmath.sin(ecc)


def test_kepler_ellipse_time_along_phi_is_keplers_equation_over_a_hundred_orbits():
    """t(φ) of the ellipse along φ against M = E − e sin E, n t = M(f) − M(f0), tan(E/2) = √((1 − e)/(1 + e)) tan(f/2)
    (E unwrapped by whole turns of f), at 30 digits; the period against 2π a^{3/2}; dt/dφ's quadrature over one orbit."""
    initial = dict(r=1.0, phi=0.0, r_dot=0.1, phi_dot=1.2)
    orbit = _orbit(initial)
    assert orbit.kind == "oscillation between turning points" and "t" in orbit.cyclic
    phi = np.concatenate([np.linspace(0.0, 7.0, 15), 2 * np.pi * np.array([100.3, 101.77, 137.5])])
    got = orbit.columns(phi, ["t", "t_dot"])
    with mpmath.workdps(30):
        ell, E, e, f0 = _elements(initial)
        a = -1 / (2 * E)


        want = [float((_mean_anomaly(f0 + mpmath.mpf(p), e) - _mean_anomaly(f0, e)) * a**1.5) for p in phi]
        period = 2 * mpmath.pi * a**1.5
        one_orbit = mpmath.quad(lambda p: (1 + e * mpmath.cos(f0 + p)) ** -2 * ell**3, [0, mpmath.pi, 2 * mpmath.pi])
        assert abs(one_orbit - period) <= mpmath.mpf(10) ** -25 * period  # the two references agree
    # the partial fractions in doubles: measured 4e-16 of t after 137 orbits; 1e-14 of max(1, t) is the bound
    err = np.abs(got["t"] - want)
    assert np.all(err <= 1e-14 * np.maximum(1.0, np.abs(want))), err.max()
    estimate = orbit.estimate(phi, ["t"])[1]["t"]
    assert err.max() <= 4 * estimate and estimate <= 1e-14 * max(want)
    # dt/dφ = r²/ℓ from the same closed form's r
    r = orbit.columns(phi, ["r"])["r"]
    assert np.max(np.abs(got["t_dot"] - r**2 / float(ell))) <= 1e-14 * np.max(r**2 / float(ell))
    assert abs(orbit.summary("t_per_period") - float(period)) <= 2e-15 * float(period)


def test_kepler_time_minus_a_target_keeps_its_digits_after_a_thousand_orbits():
    """t(φ) − t, as the inversion of t(φ) forms it (RationalRate.minus), against Kepler's equation at 30 digits after
    1000 orbits (t ≈ 15400, ulp 1.8e-12), t the double nearest t(φ): within the integral's own rounding bound
    (first-order, measured ≤ 0.27 of it), which is below 1/16 ulp of t — the secular part in double-double, the
    target taken from it exactly.  The value alone is t rounded (to half an ulp), as before."""
    initial = dict(r=1.0, phi=0.0, r_dot=0.1, phi_dot=1.2)
    integral = _orbit(initial).rate("t")[0]
    phi = 2 * np.pi * np.array([1000.0, 1000.13, 1000.5, 1000.87]) + 0.3
    with mpmath.workdps(30):
        ell, E, e, f0 = _elements(initial)
        a = -1 / (2 * E)


        exact = [(_mean_anomaly(f0 + mpmath.mpf(float(p)), e) - _mean_anomaly(f0, e)) * a**1.5 for p in phi]
        target = np.array([float(x) for x in exact])
        got = integral.minus(phi, target)
        error = np.array([float(abs(mpmath.mpf(float(g)) - (x - mpmath.mpf(float(y))))) for g, x, y in
                          zip(got, exact, target)])
    bound = integral.rounding(phi)
    assert np.all(error <= bound), (error, bound)
    assert np.all(bound <= np.spacing(target) / 16), bound / np.spacing(target)
    value = integral(phi)
    assert np.all(np.abs(value - target) <= 0.5 * np.spacing(target))


def test_reference_radius_is_refined_to_30_digits_far_along_the_asymptote():
    """At r ≈ 3e12 on a hyperbola along φ (u = 1/r ≈ 3e-13, the doubles' r off by 1e-3 relative from u's rounding) the
    30-digit reference r = 1/u of ClosedMotion.reference_values, Newton from the double r, reaches 1/u to 25 digits
    (two fixed steps left 1e-12, and the estimate took that for the doubles' error of ṙ)."""
    initial = dict(r=1.0, phi=-0.302, r_dot=-0.274, phi_dot=3.8586)
    orbit = _orbit(initial)
    lo, hi = orbit.rate("t")[0].singular_times
    s = np.array([hi * (1 - 2.0**-40)])
    got = orbit.columns(s, ["r", "r_dot"])
    ref = orbit.reference_values(s, got)[0]
    with mpmath.workdps(30):
        v = orbit.motion.kappa * mpmath.mpf(float(s[0])) + orbit.motion.v_start
        sn, cn, dn = (mpmath.ellipfun(f, v, m=orbit.motion.m) for f in ("sn", "cn", "dn"))
        u = orbit.motion.mp_u(sn, cn, dn)
        assert abs(ref["r"] * u - 1) <= mpmath.mpf(10) ** -25
        assert ref["r"] > 1e11 and abs(float(got["r"][0]) / float(ref["r"]) - 1) > 1e-9  # the doubles' r is off


def test_kepler_hyperbola_time_along_phi_is_the_hyperbolic_keplers_equation():
    """t(φ) of the hyperbola against M = e sinh H − H, tanh(H/2) = √((e − 1)/(e + 1)) tan(f/2), up to 0.999 of the
    way to the asymptote on both sides; at the asymptote dt/dφ = 1/(ℓu²) is infinite (u = 1/r = 0): refused there."""
    initial = dict(r=1.0, phi=0.0, r_dot=0.2, phi_dot=1.6)
    orbit = _orbit(initial)
    with mpmath.workdps(30):
        ell, E, e, f0 = _elements(initial)
        f_inf = mpmath.acos(-1 / e)
        a = 1 / (2 * E)

        def mean_anomaly(f):
            H = 2 * mpmath.atanh(mpmath.sqrt((e - 1) / (e + 1)) * mpmath.tan(f / 2))
            return e * mpmath.sinh(H) - H

        ahead, behind = float(f_inf - f0), float(-f_inf - f0)
        phi = np.concatenate([np.linspace(0.999 * behind, 0.0, 8), np.linspace(0.0, 0.999 * ahead, 12)[1:]])
        want = np.array([float((mean_anomaly(f0 + mpmath.mpf(p)) - mean_anomaly(f0)) * a**1.5) for p in phi])
    got = orbit.columns(phi, ["t", "t_dot"])
    # near the asymptote t is ill-conditioned in φ (dt/dφ ~ 10⁶ at 0.999): the bound adds dt/dφ·ulp(φ)
    err = np.abs(got["t"] - want)
    bound = 1e-14 * np.maximum(1.0, np.abs(want)) + 8 * np.abs(got["t_dot"]) * np.spacing(np.abs(phi) + 1)
    assert np.all(err <= bound), (err / bound).max()
    with pytest.raises(Exception, match="pole the motion reaches at phi = 2.04739"):
        orbit.columns(np.array([0.0, 1.01 * ahead]), ["t"])
    with pytest.raises(Exception, match="no period"):
        orbit.summary("t_per_period")


# --- each path, against a quadrature of the rate along u(τ) written from the form --------------------------------

def _u_by_hand(motion, path):
    """u(τ) at the caller's precision from the form's definition (not from the rate's partial fractions)."""
    mp = mpmath.mp
    if path == "line":
        u0, s, a = motion.constants
        return lambda tau: u0 + s * tau + a * tau**2
    if path == "exp":
        alpha, pp, pm = motion.constants
        return lambda tau: alpha + pp * mp.exp(motion.kappa * tau) + pm * mp.exp(-motion.kappa * tau)
    A, B, C, D = motion.mobius
    w = mp.sin if path == "circle" else mp.tanh

    def u(tau):
        ww = w(motion.kappa * tau + motion.v_start) ** 2
        return (A + B * ww) / (C + D * ww)

    return u


PATHS = [
    # (name, P's coefficients, u0, direction, N, D, path, times)
    # (u − 1.5)²(u² − u + 0.5), its coefficients exact in binary: a double root the doubles do not split
    pytest.param("circle, a complex pair and a double real pole", [-1.0, 0.0, 1.0], 0.2, 1, [1.0, 0.0, 2.0],
                 [1.0, -4.0, 5.75, -3.75, 1.125], "circle", (0.7, 9.0, 250.0), marks=pytest.mark.slow),
    ("ray: a separatrix, a pole beyond its double root", 2.0 * np.poly((-1.0, 1.0, 1.0)), 0.0, 1, [1.0, -0.2],
     [1.0, -1.3], "ray", (0.5, 3.0, 40.0)),
    pytest.param("ray: the hyperbolic quadratic, complex poles", [4.0, 0.0, -4.0], 1.5, -1, [1.0],
                 [1.0, 0.0, 0.0, 2.0], "ray", (-2.0, 0.4, 3.0), marks=pytest.mark.slow),
    pytest.param("exp: no real root, a double pole off the path", [1.0, -1.0, 2.5], 0.3, 1, [1.0, 0.0],
                 np.poly((0.5 + 1j, 0.5 - 1j, 0.5 + 1j, 0.5 - 1j)).real, "exp", (-3.0, 0.8, 6.0), marks=pytest.mark.slow),
    ("exp: a double root, towards it", [1.0, -2.0, 1.0], 3.0, -1, [2.0], [1.0, 0.0, 1.0], "exp", (0.5, 5.0, 60.0)),
    ("line: accelerated, complex poles", [-2.0, 1.0], 0.0, 1, [1.0, 0.0, 0.0], [1.0, 0.0, 0.25], "line",
     (0.3, 1.0, 4.0)),
]


@pytest.mark.parametrize("name, coeffs, u0, direction, num, den, path, times", PATHS,
                         ids=[(c.values if hasattr(c, "values") else c)[0] for c in PATHS])
def test_rates_with_poles_integrate_on_every_rational_path(name, coeffs, u0, direction, num, den, path, times):
    motion = elliptic_motion(coeffs, u0, direction)
    integral = rate_integral(motion, num, den)
    assert integral.path == path and integral.singular_times is None
    got = integral(np.array(times))
    with mpmath.workdps(30):
        u = _u_by_hand(motion, path)
        rate = lambda tau: mpmath.polyval(list(num), u(tau)) / mpmath.polyval(list(den), u(tau))  # noqa: E731
        if path == "circle":  # periodic: whole periods by the quadrature over one (also the advance's reference)
            period = motion.u_period
            per_period = mpmath.quad(rate, mpmath.linspace(0, period, 5))
            assert abs(float(integral.advance) - float(per_period)) <= 1e-14 * abs(float(per_period))
        for tau, value in zip(times, got):
            whole = mpmath.floor(tau / period) if path == "circle" else 0
            rest = tau - whole * period if path == "circle" else mpmath.mpf(tau)
            want = (whole * per_period if whole else 0) + mpmath.quad(rate, mpmath.linspace(0, rest, 4))
            # doubles: measured ≤ 3e-15 of max(1, |∫|); the 30-digit value of the same sums agrees to rounding
            assert abs(value - float(want)) <= 1e-14 * max(1.0, abs(float(want))), (tau, value, want)
            assert abs(float(integral.value_mp(tau)) - float(want)) <= 1e-25 * max(1.0, abs(float(want)))


def test_a_pole_the_motion_reaches_bounds_the_integral():
    """R = 1/u on u = 0.1 + √0.8 t − t²/2 (P = 1 − 2u, the line path) reaches u = 0 at t = √0.8 ± √(0.8 + 0.2): the
    integral exists strictly between the crossings (it diverges logarithmically at them), and a start on the pole is
    refused."""
    motion = elliptic_motion([-2.0, 1.0], 0.1, 1)  # u = 0.1 + √0.8 t − t²/2
    integral = rate_integral(motion, [1.0], [1.0, 0.0])
    lo, hi = integral.singular_times
    s = float(mpmath.sqrt(0.8))
    assert hi == pytest.approx(s + np.sqrt(s * s + 0.2), rel=1e-14) and lo == pytest.approx(s - np.sqrt(s * s + 0.2),
                                                                                            rel=1e-14)
    t = np.array([0.5 * lo, 0.5 * hi, 0.99 * hi])
    with mpmath.workdps(30):
        want = [mpmath.quad(lambda x: 1 / (0.1 + mpmath.sqrt(0.8) * x - x * x / 2), [0, x]) for x in t]
    # |∫| ≤ 8 here (log|t − t₊| at 1% from the crossing): 1e-14 of 10 is ample (measured 1.8e-15)
    assert np.max(np.abs(integral(t) - np.array(want, float))) <= 1e-14 * 10
    with pytest.raises(NotElliptic, match="start on one"):
        rate_integral(elliptic_motion([-2.0, 1.0], 0.0, 1), [1.0], [1.0, 0.0])


# --- the cn and tan forms: the rate's Fourier series in the Jacobi argument ------------------------------------

def _u_cn_by_hand(motion):
    """u(τ) from the cn or tan form's definition, Jacobi functions by mpmath at the caller's precision."""
    mp = mpmath.mp
    from mechderive.solvers.quadrature_open import EllipticMotionTan

    def u(tau):
        v = motion.kappa * tau + motion.v_start
        sn, cn = mp.ellipfun("sn", v, m=motion.m), mp.ellipfun("cn", v, m=motion.m)
        if isinstance(motion, EllipticMotionTan):
            alpha, b, s0, c0 = motion.mobius
            return alpha + b * (s0 * cn + c0 * sn) / (c0 * cn - s0 * sn)
        A, B, C, D = motion.mobius
        return (A + B * cn) / (C + D * cn)

    return u


CN_FORMS = [
    # (name, P's coefficients, u0, direction, N, D, times as fractions of the escape times, or absolute)
    ("cn: a quartic with a complex pair, u between its real roots", -np.real(np.poly((-1.0, 2.0, 1 + 2j, 1 - 2j))),
     0.3, 1, [1.0, 0.5], [1.0, 0.0, 4.0], (0.8,)),
    pytest.param("cn: the same over ten periods, and its advance", -np.real(np.poly((-1.0, 2.0, 1 + 2j, 1 - 2j))), 0.3, 1,
                 [1.0, 0.5], [1.0, 0.0, 4.0], (41.3,), marks=pytest.mark.slow),
    ("tan: a quartic with no real root", np.real(np.poly((1j, -1j, 0.5 + 2j, 0.5 - 2j))), 0.3, 1,
     [1.0, 0.0], [1.0, 0.0, 9.0], (0.9,)),
    pytest.param("tan: m = 0.99 (1024 samples a period)", np.real(np.poly((1j, -1j, 2 + 0.5j, 2 - 0.5j))), 0.3, 1,
                 [1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 1.0, 1.0], (-0.5, 0.9), marks=pytest.mark.slow),
    pytest.param("cn: a cubic with one real root", np.real(np.poly((0.5, 1 + 1j, 1 - 1j))), 1.0, 1, [1.0, 0.0],
                 [1.0, 0.0, 3.0], (-0.5, 0.9), marks=pytest.mark.slow),
    pytest.param("cn: a quartic outside its real roots", [1.0, 0.0, -2.0, 0.0, -0.5], 1.8, 1, [2.0], [1.0, 0.0, 1.0],
                 (-0.5, 0.9), marks=pytest.mark.slow),
]


@pytest.mark.parametrize("name, coeffs, u0, direction, num, den, times", CN_FORMS,
                         ids=[(c.values if hasattr(c, "values") else c)[0] for c in CN_FORMS])
def test_rates_on_the_cn_and_tan_forms_against_a_quadrature(name, coeffs, u0, direction, num, den, times):
    """∫ R dt by the Fourier series of R(u(v)) against mpmath's quadrature of R along u(τ) written from the form, at
    30 digits; the escaping forms within their escape times; the estimate (doubles against the 30-digit refit)
    bounds the error actually made."""
    motion = elliptic_motion(coeffs, u0, direction)
    integral = rate_integral(motion, num, den)
    if motion.escape_times is not None:
        times = tuple(f * motion.escape_times[0 if f < 0 else 1] * (-1 if f < 0 else 1) for f in times)
    got = integral(np.array(times))
    with mpmath.workdps(30):
        u = _u_cn_by_hand(motion)
        rate = lambda tau: mpmath.polyval(num, u(tau)) / mpmath.polyval(den, u(tau))  # noqa: E731
        period = motion.u_period
        if motion.escape_times is None and max(times) > period:  # whole periods from the advance's own quadrature
            per_period = mpmath.quad(rate, mpmath.linspace(0, period, 3))
            assert abs(float(integral.advance) - float(per_period)) <= 1e-14 * abs(float(per_period))
        for tau, value in zip(times, got):
            whole = mpmath.floor(tau / period) if motion.escape_times is None and tau > period else 0
            want = (whole * per_period if whole else 0) + mpmath.quad(rate, [0, tau - (whole * period if whole else 0)])
            error = abs(value - float(want))
            # measured ≤ 2e-16 of max(1, |∫|) here
            assert error <= 1e-14 * max(1.0, abs(float(want))), (tau, value, want)
            estimate = abs(value - float(integral.value_mp(tau))) + 2.0**-52 * abs(value)
            assert error <= 4 * estimate, (error, estimate)


def test_rates_the_cn_and_tan_forms_cannot_integrate_are_refused_with_the_reason():
    tan = elliptic_motion(np.real(np.poly((1j, -1j, 2 + 0.5j, 2 - 0.5j))), 0.3, 1)
    with pytest.raises(NotElliptic, match="pole at u = 0.5 that u reaches"):
        rate_integral(tan, [1.0], [1.0, -0.5])  # u takes every real value: it passes the pole
    with pytest.raises(NotElliptic, match="deg N = 1 > deg D = 0"):
        rate_integral(tan, [1.0, 0.0], [1.0])  # ċ = u grows without bound at the escape
    cn = elliptic_motion(-np.real(np.poly((-1.0, 2.0, 1 + 2j, 1 - 2j))), 0.3, 1)
    with pytest.raises(NotElliptic, match="pole at u = 1.5"):
        rate_integral(cn, [1.0], [1.0, -1.5])  # u oscillates on (−1, 2) through 1.5
    rate_integral(cn, [1.0], [1.0, -2.5])  # a pole beyond the motion's range: integrated
