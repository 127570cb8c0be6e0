"""Small oscillations and stability through the generic path (mechderive.core.linearize), issue 13 §5.

References, each independent of the path under test:

- the chapter's (3.44)–(3.45) (A and the intermediate-axis rule) and (3.83) (the sleeping top's
  second root u2 = a²/α − 1 and its threshold), typed here from the text, and the numbers of
  systems/free_top/stability.py (derived by its own route: the Jacobian of Euler's equations);
- the spherical pendulum's known ω² = Ω²(1 + 3cos²θ0) about conical motion, and the frequency
  measured on a numerical integration (SciPy DOP853) of hand-written equations of motion;
- the heavy top's nutation about uniform precession measured on an integration of the full
  three-coordinate Euler–Lagrange equations (no Routhian, no expansion);
- eigenvalues of hand-built state matrices by NumPy (gyroscopic and coupled oscillators).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from mechderive.core.linearize import LAMBDA, linearization_derivation, linearize_first_order, linearize_lagrangian
from mechderive.errors import InvalidInputError
from mechderive.systems.base import System

m, g, l = sp.symbols("m g l", positive=True)
th, ph, thd, phd = sp.symbols("theta phi theta_dot phi_dot", real=True)
Omega = sp.Symbol("Omega", positive=True)
theta0 = sp.Symbol("theta0", real=True)


def _spherical() -> sp.Expr:
    """Spherical pendulum, θ from the downward vertical."""
    return m * l**2 * (thd**2 + sp.sin(th) ** 2 * phd**2) / 2 + m * g * l * sp.cos(th)


def _period_from_turning_points(rhs, y0, rate_index: int, t_end: float) -> float:
    """Period of a small oscillation: twice the mean spacing of the zeros of the oscillating rate."""
    event = lambda t, y: y[rate_index]  # noqa: E731
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-12, atol=1e-14, events=event)
    times = sol.t_events[0]
    assert len(times) >= 10
    return 2 * (times[-1] - times[0]) / (len(times) - 1)


# --- the free top: A of (3.44), the rule (3.45) -----------------------------------------------------

def _free_top():
    from mechderive.systems.free_top import model as fm

    return fm, fm.model().free_rhs, fm.omega_symbols()


def test_free_top_stability_coefficient_is_the_chapters_A():
    fm, rhs, w = _free_top()
    I1, I2, I3, Om = fm.I1, fm.I2, fm.I3, fm.Omega
    lin = linearize_first_order(rhs, w, {w[0]: Om, w[1]: 0, w[2]: 0})
    A = Om**2 / I3 * (I3 - I1) * (I1 - I2)  # (3.44), from the chapter
    # det(λ − J) = λ(λ² − A/I2): (3.42)–(3.44) as one polynomial
    assert sp.cancel(lin.characteristic_polynomial.as_expr() - LAMBDA * (LAMBDA**2 - A / I2)) == 0
    assert len(lin.squared_frequencies) == 1 and sp.cancel(lin.squared_frequencies[0] + A / I2) == 0
    assert lin.stable is None  # the sign of A depends on the moments
    # its condition is A < 0 (3.45 negated): checked on every strict ordering of three moments
    for moments in itertools.permutations((2, 3, 4)):
        values = dict(zip((I1, I2, I3), moments))
        intermediate = sorted(moments)[1] == moments[0]
        assert bool(lin.condition.subs(values).subs(Om, 1)) is not intermediate


@pytest.mark.parametrize("moments", [(1, 2, 3), (3, 1, 2), (2, 3, 4), (4, 2, 3), (2, 2, 3), (3, 2, 2),
                                     (1.5, 1, 1), (1, 1, 1)])
def test_free_top_principal_axes_agree_with_stability_module(moments):
    from mechderive.systems.free_top.stability import instability_growth_rate, principal_axis_stability

    fm, rhs, w = _free_top()
    params = dict(zip((fm.I1, fm.I2, fm.I3), moments))
    expected = principal_axis_stability(*moments)
    for axis in (1, 2, 3):
        spin = 1.5
        lin = linearize_first_order(rhs, w, {w[b]: (spin if b == axis - 1 else 0) for b in range(3)}, params)
        verdict = expected[axis]
        if verdict == "unstable":
            assert lin.stable is False and len(lin.growth_rates) == 1
            # same e-folding rate as (3.44)'s √(A/I2), to rounding of the module's float evaluation
            assert float(lin.growth_rates[0]) == pytest.approx(instability_growth_rate(*moments, spin, axis=axis),
                                                               rel=1e-14)
        elif verdict == "stable":
            assert lin.stable is True and len(lin.frequencies) == 1 and not lin.growth_rates
        else:  # neutral: every linearized eigenvalue is zero
            assert not lin.growth_rates and not lin.frequencies
            assert all(e == 0 for e in lin.eigenvalues)
            equal_pair = len(set(moments)) == 2
            # symmetric top in its plane of equal moments: nilpotent J, a linear drift (not stable);
            # a sphere (J = 0) or the symmetry axis: semisimple
            assert lin.stable is (not (equal_pair and moments[axis - 1] in
                                        [x for x in moments if list(moments).count(x) == 2]))


# --- the heavy top: the sleeping top (3.83) -------------------------------------------------------

def _heavy():
    from mechderive.systems.heavy_top import model as hm

    h = hm.model()
    return hm, h.state_lagrangian, (hm.phi, hm.theta, hm.psi), (hm.phi_dot, hm.theta_dot, hm.psi_dot)


def test_sleeping_top_criterion_is_the_chapters_3_83():
    hm, L, q, v = _heavy()
    I1, I3, M, g_, l_, w3 = hm.I1, hm.I3, hm.M, hm.g, hm.l, hm.omega3
    # θ = 0 is singular in Euler angles; the Routhian at p_φ = p_ψ is smooth there (series path)
    lin = linearize_lagrangian(L, q, v, {hm.theta: 0, hm.phi_dot: 0, hm.psi_dot: w3})
    assert lin.variables == (hm.theta,) and lin.cyclic == (hm.phi, hm.psi)
    assert lin.momenta == {sp.Symbol("p_phi", real=True): I3 * w3, sp.Symbol("p_psi", real=True): I3 * w3}
    (w2,) = lin.squared_frequencies
    # chapter: f(u) = (1 − u)²(α(1 + u) − a²), u2 = a²/α − 1 with a = I3ω3/I1, α = β = 2Mgl/I1
    a, alpha = I3 * w3 / I1, 2 * M * g_ * l_ / I1
    u2 = a**2 / alpha - 1
    # ω² is a positive multiple of u2 − 1: stable (oscillating) iff u2 > 1, i.e. ω3² > 4 I1 M g l / I3²
    ratio = sp.simplify(w2 / (u2 - 1))
    assert ratio.is_positive and not ratio.has(w3)
    assert lin.stable is None
    threshold = 2 * sp.sqrt(I1 * M * g_ * l_) / I3  # the chapter: I3 ω3 = 2 √(I1 M g l)
    for factor, stable in ((sp.Rational(999, 1000), False), (sp.Rational(1001, 1000), True)):
        values = {I1: 3, I3: 2, M: 1, g_: sp.Rational(981, 100), l_: sp.Rational(1, 2)}
        spin = (threshold * factor).subs(values)
        assert bool(lin.condition.subs(values).subs(w3, spin)) is stable
        numeric = linearize_lagrangian(L, q, v, {"theta": 0, "phi_dot": 0, "psi_dot": spin}, values)
        assert numeric.stable is stable and bool(numeric.growth_rates) is not stable


def test_heavy_top_nutation_about_uniform_precession_matches_integration():
    hm, L, q, v = _heavy()
    values = {hm.I1: 1, hm.I3: sp.Rational(1, 2), hm.M: 1, hm.g: 10, hm.l: sp.Rational(1, 10)}
    t0, w3 = sp.Rational(3, 5), 10
    # slow root of (3.80), M g l = φ̇ (I3 ω3 − I1 φ̇ cos θ0), solved exactly here
    rate = sp.Symbol("rate")
    roots = sp.solve(sp.Eq(1, rate * (sp.Rational(1, 2) * w3 - rate * sp.cos(t0))), rate)
    slow = min(roots, key=lambda r: abs(float(r)))
    at = {"theta": t0, "phi_dot": slow, "psi_dot": w3 - slow * sp.cos(t0)}
    lin = linearize_lagrangian(L, q, v, at, values)
    assert lin.stable is True and len(lin.frequencies) == 1
    omega = float(lin.frequencies[0])
    # reference: the full equations (φ, θ, ψ), θ̇ nudged (which keeps p_φ, p_ψ: they do not involve θ̇)
    h = hm.model()
    acc = sp.lambdify([*h.positions, *h.velocities], list(h.accelerations.subs(values)), "math")
    rhs = lambda t, y: [y[3], y[4], y[5], *acc(*y)]  # noqa: E731
    y0 = [0.0, float(t0), 0.0, float(slow), 1e-6, float(at["psi_dot"])]
    period = _period_from_turning_points(rhs, y0, 4, 12 * 2 * math.pi / omega)
    # amplitude ~2e-7 rad: nonlinear shift ~1e-13; event timing with DOP853 at rtol 1e-12 over 12 periods
    # measured 2e-9 → 1e-8
    assert 2 * math.pi / period == pytest.approx(omega, rel=1e-8)
    # and the error message for a rate that is not the steady one names the θ equation
    with pytest.raises(InvalidInputError, match=r"∂R/∂theta .* ≠ 0 \(relative"):
        linearize_lagrangian(L, q, v, {**at, "phi_dot": float(slow) * 1.001}, values)


# --- the spherical pendulum about conical motion -----------------------------------------------------

def test_spherical_pendulum_conical_motion_known_result():
    lin = linearize_lagrangian(_spherical(), [th, ph], [thd, phd], {th: theta0, phd: Omega},
                               {g: Omega**2 * l * sp.cos(theta0)})  # g/l = Ω² cos θ0: the cone is steady
    (w2,) = lin.squared_frequencies
    assert sp.simplify(w2 - Omega**2 * (1 + 3 * sp.cos(theta0) ** 2)) == 0  # the known result
    assert lin.stable is True and len(lin.frequencies) == 1
    assert sp.simplify(lin.frequencies[0] ** 2 - w2) == 0


def test_spherical_pendulum_frequency_matches_integration():
    t0, rate = 0.7, 2.0
    params = {m: 1, l: 1, g: sp.Rational(4) * sp.cos(sp.Rational(7, 10))}  # g/l = Ω² cos θ0 exactly
    lin = linearize_lagrangian(_spherical(), [th, ph], [thd, phd], {"theta": t0, "phi_dot": rate}, params)
    omega = float(lin.frequencies[0])
    assert omega == pytest.approx(rate * math.sqrt(1 + 3 * math.cos(t0) ** 2), rel=1e-15)
    G = 4 * math.cos(t0)

    def rhs(t, y):  # hand-written: θ̈ = sin θ cos θ φ̇² − (g/l) sin θ, φ̈ = −2 θ̇ φ̇ cot θ
        s, c = math.sin(y[0]), math.cos(y[0])
        return [y[2], y[3], s * c * y[3] ** 2 - G * s, -2 * y[2] * y[3] * c / s]

    period = _period_from_turning_points(rhs, [t0, 0.0, 1e-6, rate], 2, 12 * 2 * math.pi / omega)
    # amplitude 3e-7 rad: nonlinear shift ~1e-13; event timing with DOP853 at rtol 1e-12 over 12 periods
    # measured 1.6e-9 → 1e-8
    assert 2 * math.pi / period == pytest.approx(omega, rel=1e-8)


# --- the simple pendulum -------------------------------------------------------------------------------

def test_simple_pendulum_bottom_and_top():
    L = m * l**2 * thd**2 / 2 + m * g * l * sp.cos(th)
    bottom = linearize_lagrangian(L, [th], [thd], {th: 0})
    assert bottom.cyclic == () and bottom.stable is True
    assert sp.simplify(bottom.frequencies[0] - sp.sqrt(g / l)) == 0 and bottom.growth_rates == ()
    top = linearize_lagrangian(L, [th], [thd], {th: sp.pi})
    assert top.stable is False and top.frequencies == ()
    assert sp.simplify(top.growth_rates[0] - sp.sqrt(g / l)) == 0
    with pytest.raises(InvalidInputError, match=r"expected an equilibrium .*∂L/∂theta .*g\*l\*m\*sin\(3/10\)"):
        linearize_lagrangian(L, [th], [thd], {th: sp.Rational(3, 10)})
    with pytest.raises(InvalidInputError, match=r"relative 1 of its terms' size"):
        linearize_lagrangian(L, [th], [thd], {th: 0.3}, {g: 9.81, l: 1, m: 1})


# --- gyroscopic and numeric spectra against NumPy --------------------------------------------------

def test_rotating_saddle_gyroscopic_terms_against_numpy():
    # a particle in a frame turning at Ω about z, springs k1 (x) and k2 (y): G = 2Ω J from the Coriolis term
    x, y, xd, yd = sp.symbols("x y x_dot y_dot", real=True)
    W, k1, k2 = sp.symbols("W k1 k2", real=True)
    L = (xd**2 + yd**2) / 2 + W * (x * yd - y * xd) + W**2 * (x**2 + y**2) / 2 - (k1 * x**2 + k2 * y**2) / 2
    lin = linearize_lagrangian(L, [x, y], [xd, yd], {x: 0, y: 0})
    assert lin.G == sp.Matrix([[0, -2 * W], [2 * W, 0]])
    for values in ({W: 1, k1: 3, k2: -sp.Rational(1, 2)}, {W: 2, k1: 3, k2: -sp.Rational(1, 2)},
                   {W: sp.Rational(1, 3), k1: 2, k2: 5}):
        num = linearize_lagrangian(L, [x, y], [xd, yd], {x: 0, y: 0}, values)
        w, a, b = (float(values[s]) for s in (W, k1, k2))
        # hand-built state matrix of ẍ − 2Ωẏ + (k1 − Ω²)x = 0, ÿ + 2Ωẋ + (k2 − Ω²)y = 0
        A = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [w * w - a, 0, 0, 2 * w], [0, w * w - b, -2 * w, 0]])
        ref = np.linalg.eigvals(A)
        got = np.array(num.numeric_eigenvalues)
        assert np.allclose(np.sort_complex(np.round(got, 12)), np.sort_complex(np.round(ref, 12)), atol=1e-10)
        assert num.stable is bool(np.max(ref.real) < 1e-9)


def test_three_coupled_oscillators_numeric_roots_against_numpy():
    # a chain wall–m1–m2–m3–wall with unequal springs: the cubic in λ² has no rational roots
    q = sp.symbols("q1:4", real=True)
    qd = sp.symbols("q1:4_dot", real=True)
    masses, springs = (1, 2, 3), (5, 7, 11, 13)
    ext = [0, *q, 0]
    L = sum(mi * v**2 for mi, v in zip(masses, qd)) / 2 - sum(k * (ext[i + 1] - ext[i]) ** 2
                                                              for i, k in enumerate(springs)) / 2
    lin = linearize_lagrangian(L, q, qd, {qi: 0 for qi in q})
    assert lin.stable is True and len(lin.frequencies) == 3
    Mn = np.diag(masses).astype(float)
    Kn = np.array(lin.K.tolist(), dtype=float)
    ref = np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(Mn, Kn)).real))
    # 40-digit roots against NumPy's double-precision eigensolver (condition ~1): 1e-12
    assert np.allclose(np.sort([float(f) for f in lin.frequencies]), ref, rtol=1e-12)


# --- input errors ---------------------------------------------------------------------------------------

def test_input_errors_name_what_is_wrong():
    L = _spherical()
    with pytest.raises(InvalidInputError, match=r"expected the point `at` to give values of theta, phi_dot, p_phi, got 'psi'"):
        linearize_lagrangian(L, [th, ph], [thd, phd], {"psi": 0})
    with pytest.raises(InvalidInputError, match=r"expected a value of theta"):
        linearize_lagrangian(L, [th, ph], [thd, phd], {phd: 1})
    with pytest.raises(InvalidInputError, match=r"expected theta_dot = 0"):
        linearize_lagrangian(L, [th, ph], [thd, phd], {th: 0, thd: 1})
    with pytest.raises(InvalidInputError, match=r"phi_dot or p_phi in `at`, not both"):
        linearize_lagrangian(L, [th, ph], [thd, phd], {th: 1, phd: 1, "p_phi": 1})
    with pytest.raises(InvalidInputError, match=r"smooth at theta = 0"):  # p_φ ≠ 0 at the pole: singular
        linearize_lagrangian(L, [th, ph], [thd, phd], {th: 0, "p_phi": 1})
    with pytest.raises(InvalidInputError, match=r"expected parameters among the equations' symbols"):
        linearize_lagrangian(L, [th, ph], [thd, phd], {th: 0}, {"k": 1})
    w = sp.symbols("omega1:4", real=True)
    F = [w[1] * w[2], -2 * w[2] * w[0], w[0] * w[1]]
    with pytest.raises(InvalidInputError, match=r"steady point .*domega1/dt = 1"):
        linearize_first_order(F, w, {"omega1": 1, "omega2": 1, "omega3": 1})
    with pytest.raises(InvalidInputError, match=r"none for omega3"):
        linearize_first_order(F, w, {"omega1": 1, "omega2": 0})


# --- the derive hook: a System with a Lagrangian, the --at text -------------------------------------

class _Spherical(System):
    name = "test_spherical_pendulum"

    def lagrangian_model(self):
        return _spherical(), (th, ph), (thd, phd), (m, g, l)


def test_linearization_derivation_parses_at_with_the_whitelist():
    equations, text, lin = linearization_derivation(
        _Spherical(), "theta=0.7, phi_dot=sqrt(g/(l*cos(0.7)))", {"m": 1.0, "g": 9.81, "l": 2.0})
    rate = math.sqrt(9.81 / (2.0 * math.cos(0.7)))
    assert float(lin.frequencies[0]) == pytest.approx(rate * math.sqrt(1 + 3 * math.cos(0.7) ** 2), rel=1e-14)
    assert "frequencies (rad/s)" in text and "stable in the linear approximation" in text
    assert equations.shape == (1, 1) and equations[0].has(sp.Symbol("delta_theta_ddot", real=True))
    assert r"\delta \ddot{\theta}" in lin.latex()
    # a scene parameter the Lagrangian does not use (an output expression's) is accepted and left out
    _, _, again = linearization_derivation(_Spherical(), "theta=0, phi_dot=0", {"m": 1, "g": 9.81, "l": 2.0})
    assert float(again.frequencies[0]) == pytest.approx(math.sqrt(9.81 / 2.0), rel=1e-15)
    for bad, match in (("theta=__import__('os')", "call of '__import__'"), ("theta=0.7, theta=1", "twice"),
                       ("omega=1", "expected a name among"), ("theta", "name=value"),
                       ("theta=0.7, phi_dot=2.6", r"∂R/∂theta .*≠ 0 .*steady motions at this point have "
                                                  rf"phi_dot = -{str(rate)[:12]}\d* or {str(rate)[:12]}")):
        with pytest.raises(InvalidInputError, match=match):
            linearization_derivation(_Spherical(), bad, {"m": 1.0, "g": 9.81, "l": 2.0})
    with pytest.raises(InvalidInputError, match="offers no Lagrangian or first-order model"):
        linearization_derivation(System(), "x=0")


def test_repeated_eigenvalues_semisimple_or_drifting():
    x, y, xd, yd = sp.symbols("x y x_dot y_dot", real=True)
    k = sp.Symbol("k", positive=True)
    # isotropic oscillator: λ = ±i√k twice, two eigenvectors each — stable, no secular term
    iso = linearize_lagrangian((xd**2 + yd**2) / 2 - k * (x**2 + y**2) / 2, [x, y], [xd, yd], {x: 0, y: 0})
    assert iso.stable is True and iso.frequencies == (sp.sqrt(k), sp.sqrt(k))
    # a spring between two free masses: the centre of mass moves uniformly, δx = δy = a + b t (λ = 0 defective)
    pair = linearize_lagrangian((xd**2 + yd**2) / 2 - k * (x - y) ** 2 / 2, [x, y], [xd, yd], {x: 0, y: 0})
    assert pair.stable is False and not pair.growth_rates and pair.verdict.startswith("neutral")
    assert pair.frequencies == (sp.sqrt(2) * sp.sqrt(k),)
