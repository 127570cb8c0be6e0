"""Closed forms found (issue 16, first step): reduction to q̇² = F(q) and the substitution that makes it a
polynomial, against the chapter's f(u) (3.73) and hand-written quadratures; and the refusals."""

from __future__ import annotations

import pytest
import sympy as sp

from mechderive.core.lagrangian import LagrangianModel
from mechderive.core.quadrature import NoQuadrature, NoSubstitution, find_substitution, reduce_to_quadrature
from mechderive.core.symbols import coordinate, t

m, g, l, k = sp.symbols("m g l k", positive=True)
I1, I3, M = sp.symbols("I1 I3 M", positive=True)
E = sp.Symbol("E", real=True)
th, ph, ps, r = coordinate("theta"), coordinate("phi"), coordinate("psi"), coordinate("r")


def _found(L, qs):
    return find_substitution(reduce_to_quadrature(LagrangianModel(L, qs)))


def _same(p, expected, u):
    return sp.expand(p.as_expr() - expected.subs(sp.Symbol("u", real=True), u)) == 0


def test_3_73_heavy_top_given_as_a_lagrangian_reduces_to_the_chapters_cubic():
    """L = ½I1(θ̇² + sin²θ φ̇²) + ½I3(ψ̇ + cos θ φ̇)² − Mgl cos θ: u = cos θ, and u̇² is (3.73)'s
    f(u) = (α − βu)(1 − u²) − (b − au)² with a = p_ψ/I1, b = p_φ/I1 (3.66), α = 2E'/I1, E' = E − p_ψ²/(2 I3),
    β = 2Mgl/I1 (3.72) — written here by hand from the chapter, not taken from the toolkit's heavy top."""
    L = I1 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) / 2 \
        + I3 * (ps.diff(t) + sp.cos(th) * ph.diff(t)) ** 2 / 2 - M * g * l * sp.cos(th)
    found = _found(L, [ph, th, ps])
    assert (found.name, found.degree) == ("u = cos q", 3)
    u = found.variable
    p_phi, p_psi = sp.Symbol("p_phi", real=True), sp.Symbol("p_psi", real=True)
    a, b = p_psi / I1, p_phi / I1
    alpha, beta = 2 * (E - p_psi**2 / (2 * I3)) / I1, 2 * M * g * l / I1
    assert sp.expand(found.polynomial.as_expr() - ((alpha - beta * u) * (1 - u**2) - (b - a * u) ** 2)) == 0


def test_spherical_pendulum_is_a_cubic_in_cos_theta():
    """u̇² = (1 − u²)(2E/(ml²) + 2(g/l)u) − p_φ²/(m²l⁴) for L = ½ml²(θ̇² + sin²θ φ̇²) + mgl cos θ (by hand)."""
    L = m * l**2 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) / 2 + m * g * l * sp.cos(th)
    found = _found(L, [th, ph])
    u, p = found.variable, sp.Symbol("p_phi", real=True)
    assert (found.name, found.degree) == ("u = cos q", 3)
    assert sp.expand(found.polynomial.as_expr()
                     - ((1 - u**2) * (2 * E / (m * l**2) + 2 * g / l * u) - p**2 / (m**2 * l**4))) == 0


def test_the_simple_pendulum_and_the_oscillator():
    """Pendulum: u̇² = (1 − u²)·2(E + mgl u)/(ml²) with u = cos θ; oscillator: ẋ² = 2E/m − k x²/m (u = x)."""
    pendulum = _found(m * l**2 * th.diff(t) ** 2 / 2 + m * g * l * sp.cos(th), [th])
    u = pendulum.variable
    assert (pendulum.name, pendulum.degree) == ("u = cos q", 3)
    assert sp.expand(pendulum.polynomial.as_expr() - (1 - u**2) * 2 * (E + m * g * l * u) / (m * l**2)) == 0
    oscillator = _found(m * r.diff(t) ** 2 / 2 - k * r**2 / 2, [r])
    assert (oscillator.name, oscillator.degree) == ("u = q", 2)
    assert sp.expand(oscillator.polynomial.as_expr() - (2 * E / m - k * u**2 / m)) == 0


def test_the_double_pendulum_is_refused_two_coordinates_remain():
    a1, a2 = coordinate("a1"), coordinate("a2")
    L = m * l**2 * (a1.diff(t) ** 2 + a2.diff(t) ** 2 / 2 + a1.diff(t) * a2.diff(t) * sp.cos(a1 - a2)) \
        + m * g * l * (2 * sp.cos(a1) + sp.cos(a2))
    with pytest.raises(NoQuadrature, match="one coordinate left.*got 2"):
        reduce_to_quadrature(LagrangianModel(L, [a1, a2]))


def test_a_quintic_potential_is_refused_naming_the_degree():
    with pytest.raises(NoSubstitution, match="u = q: degree 5"):
        _found(m * r.diff(t) ** 2 / 2 - k * r**5, [r])


def test_kepler_in_time_is_not_a_quartic_in_one_over_r():
    """ṙ² = 2E/m + 2k/(m r) − p_φ²/(m² r²): u = 1/r gives u̇² = u⁴(...) of degree 6 (the orbit u(φ) is the
    elliptic one, a change of the independent variable this step does not make); u = q gives no polynomial."""
    with pytest.raises(NoSubstitution, match="u = 1/q: degree 6"):
        _found(m * (r.diff(t) ** 2 + r**2 * th.diff(t) ** 2) / 2 + k / r, [r, th])


def test_an_explicitly_time_dependent_lagrangian_has_no_conserved_energy():
    with pytest.raises(NoQuadrature, match="explicit time"):
        reduce_to_quadrature(LagrangianModel(m * r.diff(t) ** 2 / 2 - k * r**2 * sp.cos(t) / 2, [r]))


# --- one motion: turning points and period against independent references ---------------------------

import mpmath  # noqa: E402

from mechderive.core.quadrature import oscillation  # noqa: E402


def _period_by_quadrature(P, a, b):
    """2∫_a^b du/√P(u) by mpmath's tanh-sinh at 50 digits, with u = (a + b)/2 + (b − a)/2 sin φ taking out the
    endpoints' 1/√ singularities (the integrand (b − a)/2 cos φ / √P(u) stays finite)."""
    with mpmath.workdps(50):
        c, h = (a + b) / 2, (b - a) / 2
        # (the 40-digit roots leave P ~ -1e-40 at the very ends: the real part)
        return mpmath.re(2 * mpmath.quad(lambda f: h * mpmath.cos(f) / mpmath.sqrt(P(c + h * mpmath.sin(f))),
                                         [-mpmath.pi / 2, mpmath.pi / 2]))


def _pendulum():
    return find_substitution(reduce_to_quadrature(LagrangianModel(
        m * l**2 * th.diff(t) ** 2 / 2 + m * g * l * sp.cos(th), [th])))


@pytest.mark.parametrize("th0, thd0, kind", [(1.0, 0.0, "libration"), (0.3, 2.0, "libration"), (3.0, 0.1, "libration"),
                                             (0.0, 7.0, "rotation"), (2.0, 5.0, "rotation")])
def test_pendulum_period_libration_and_rotation(th0, thd0, kind):
    """u = cos θ folds at θ = 0 and π.  Libration: T = 4K(sin²(θmax/2))/√(g/l) (the textbook formula); rotation:
    T = 2∫₀^π dθ/θ̇(θ) by mpmath's quadrature of the energy equation in θ itself (30 digits)."""
    with mpmath.workdps(40):  # the constants as exact as the recipe's own 40 digits
        g0 = mpmath.mpf("9.81")
        E0 = mpmath.mpf(thd0) ** 2 / 2 - g0 * mpmath.cos(th0)
    o = oscillation(_pendulum(), {m: 1, g: g0, l: 1, E: E0}, th0)
    with mpmath.workdps(30):
        if kind == "libration":
            ref = 4 * mpmath.ellipk(mpmath.sin(mpmath.acos(-E0 / g0) / 2) ** 2) / mpmath.sqrt(g0)
        else:
            ref = 2 * mpmath.quad(lambda x: 1 / mpmath.sqrt(2 * (E0 + g0 * mpmath.cos(x))), [0, mpmath.pi])
    assert o.kind.startswith(kind)
    assert abs(o.period - ref) <= mpmath.mpf(10) ** -25 * ref


def test_spherical_pendulum_period_against_quadrature_in_theta():
    """2∫ dθ/√F(θ) between the turning angles, F = 2(E + g cos θ) − p²/sin²θ (unit m, l), by mpmath.quad."""
    found = find_substitution(reduce_to_quadrature(LagrangianModel(
        m * l**2 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) / 2 + m * g * l * sp.cos(th), [th, ph])))
    p = sp.Symbol("p_phi", real=True)
    with mpmath.workdps(40):
        th0, phd0, g0 = mpmath.mpf(0.8), mpmath.mpf(1.5), mpmath.mpf("9.81")  # the start in doubles, exactly
        pv = mpmath.sin(th0) ** 2 * phd0
        E0 = (mpmath.sin(th0) * phd0) ** 2 / 2 - g0 * mpmath.cos(th0)
    o = oscillation(found, {m: 1, g: g0, l: 1, E: E0, p: pv}, float(th0))
    assert o.kind == "oscillation between turning points" and o.folds == (False, False)
    with mpmath.workdps(50):
        lo, hi = sorted(mpmath.acos(x) for x in o.u_range)
    ref = _period_by_quadrature(lambda x: 2 * (E0 + g0 * mpmath.cos(x)) - pv**2 / mpmath.sin(x) ** 2, lo, hi)
    assert abs(o.period - ref) <= 1e-18 * ref


def test_heavy_top_nutation_period_from_the_generic_recipe_equals_the_built_in_closed_form():
    """The Lagrangian written out, reduced and solved generically, against exact_heavy_top (hand-built, 40 digits)."""
    from mechderive import exact_heavy_top

    L = I1 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) / 2 \
        + I3 * (ps.diff(t) + sp.cos(th) * ph.diff(t)) ** 2 / 2 - M * g * l * sp.cos(th)
    found = find_substitution(reduce_to_quadrature(LagrangianModel(L, [ph, th, ps])))
    with mpmath.workdps(40):  # the start's doubles, exactly, and the constants (3.63)-(3.65) at 40 digits
        i1, i3, mgl, th0, thd0, phd0, psd0 = (mpmath.mpf(x) for x in (1.0, 0.5, 0.981, 0.5, 0.3, 0.2, 20.0))
        w3 = psd0 + phd0 * mpmath.cos(th0)
        values = {I1: 1, I3: sp.Rational(1, 2), M: 1, g: mgl, l: 1,
                  sp.Symbol("p_psi", real=True): i3 * w3,
                  sp.Symbol("p_phi", real=True): i1 * mpmath.sin(th0) ** 2 * phd0 + i3 * mpmath.cos(th0) * w3,
                  E: (i1 * (thd0**2 + (mpmath.sin(th0) * phd0) ** 2) + i3 * w3**2) / 2 + mgl * mpmath.cos(th0)}
    o = oscillation(found, values, float(th0))
    top = exact_heavy_top(dict(I1=1.0, I3=0.5, Mgl=0.981),
                          dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.3, phi_dot=0.2, psi_dot=20.0))
    assert abs(float(o.period) - top.nutation_period) <= 1e-13 * top.nutation_period


def test_anharmonic_oscillator_two_real_roots_and_a_complex_pair():
    """ẋ² = 2E − x² − x⁴/2 (L = ½ẋ² − ½x² − x⁴/4): a quartic in x with two real roots and a complex pair, a
    cubic in x²; the period by mpmath's quadrature in x."""
    x = coordinate("x")
    found = find_substitution(reduce_to_quadrature(LagrangianModel(x.diff(t) ** 2 / 2 - x**2 / 2 - x**4 / 4, [x])))
    # u = x² makes it a cubic (lower than x's quartic); x passes through the fold x = 0 of u = x²
    assert (found.name, found.degree) == ("u = q²", 3)
    with mpmath.workdps(40):
        E0 = mpmath.mpf(7) / 10
    o = oscillation(found, {E: E0}, 0.0)
    assert o.folds == (True, False) and o.kind.startswith("libration")
    with mpmath.workdps(50):  # the turning points in x, at the roots' precision (−amp too: mpmath rounds it)
        amp = mpmath.sqrt(o.u_range[1])
        ends = (-amp, amp)
    ref = _period_by_quadrature(lambda v: 2 * E0 - v**2 - v**4 / 2, *ends)
    assert abs(o.period - ref) <= 1e-18 * o.period


def test_a_quartic_well_with_four_real_roots():
    """ẋ² = 2E − (x² − 1)² (a double well below its barrier, E < 1/2): motion in one well, between the middle
    pair of roots of the well's side; period by mpmath.quad."""
    x = coordinate("x")
    found = find_substitution(reduce_to_quadrature(LagrangianModel(x.diff(t) ** 2 / 2 - (x**2 - 1) ** 2 / 2, [x])))
    with mpmath.workdps(40):
        E0 = mpmath.mpf(3) / 10
    o = oscillation(found, {E: E0}, 1.0)
    assert found.name == "u = q²" and o.u_range[0] > 0 and o.folds == (False, False)  # the right-hand well
    with mpmath.workdps(50):
        ends = [mpmath.sqrt(x) for x in o.u_range]  # the turning points in x, at the roots' precision
    ref = _period_by_quadrature(lambda v: 2 * E0 - (v**2 - 1) ** 2, *ends)
    assert abs(o.period - ref) <= 1e-18 * o.period


def test_motions_without_a_period_are_said_so():
    """A free particle (ẋ² = 2E/m, no root: unbounded) and a pendulum at rest at the bottom (a double root)."""
    x = coordinate("x")
    free = find_substitution(reduce_to_quadrature(LagrangianModel(m * x.diff(t) ** 2 / 2 - k * x, [x])))
    with pytest.raises(NoSubstitution, match="unbounded"):
        oscillation(free, {m: 1, k: -1, E: 1}, 0.0)  # pushed away forever: V = −x
    with pytest.raises(NoSubstitution, match="steady"):
        oscillation(_pendulum(), {m: 1, g: 1, l: 1, E: -1}, 0.0)


@pytest.mark.parametrize("theta0, theta_dot0", [(1.0, 0.0), (0.0, 7.0)])
def test_a_lagrangian_scenes_period_comes_from_the_closed_form(theta0, theta_dot0):
    """`system = "lagrangian"` with the pendulum's L: `period` is the recipe's (≤ 1e-14 from 4K(k²)/ω0 for the
    libration, from the 30-digit quadrature in θ for the rotation), its estimate measured and covering that."""
    from mechderive.scenes.planner import run_scene
    from mechderive.scenes.schema import parse_scene

    scene = parse_scene({"system": "lagrangian", "coordinates": ["theta"],
                         "lagrangian": "l**2*theta_dot**2/2 + g*l*cos(theta)",
                         "parameters": {"g": 9.81, "l": 1.0}, "initial": {"theta": theta0, "theta_dot": theta_dot0},
                         "time": {"t_end": 5.0, "samples": 501},
                         "output": {"quantities": ["theta"], "summary": ["period"]}})
    report = run_scene(scene).report
    value, estimate = report["summary"]["period"], report["summary_error"]["period"]
    with mpmath.workdps(30):
        g0, E0 = mpmath.mpf(9.81), mpmath.mpf(theta_dot0) ** 2 / 2 - mpmath.mpf(9.81) * mpmath.cos(theta0)
        if E0 < g0:
            ref = 4 * mpmath.ellipk(mpmath.sin(mpmath.acos(-E0 / g0) / 2) ** 2) / mpmath.sqrt(g0)
        else:
            ref = 2 * mpmath.quad(lambda x: 1 / mpmath.sqrt(2 * (E0 + g0 * mpmath.cos(x))), [0, mpmath.pi])
    assert abs(value - float(ref)) <= max(estimate, 2e-16 * value) <= 1e-14 * value


def test_derive_closed_form_prints_the_reduction_or_why_not(tmp_path, capsys):
    """`mechderive derive SCENE closed_form`: (d cos θ/dt)² = P(cos θ) for the spherical pendulum (the cubic of the
    test above, printed in θ(t)); the double pendulum refused with the reason, exit status 2."""
    from mechderive.cli import main

    scene = tmp_path / "spherical.toml"
    scene.write_text('system = "lagrangian"\ncoordinates = ["theta", "phi"]\n'
                     'lagrangian = "m*l**2/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + m*g*l*cos(theta)"\n'
                     "[parameters]\nm = 1.0\nl = 1.0\ng = 9.81\n"
                     "[initial]\ntheta = 1.0\nphi = 0.0\ntheta_dot = 0.0\nphi_dot = 1.0\n"
                     '[time]\nt_end = 1.0\nsamples = 11\n[output]\nquantities = ["theta"]\n', encoding="utf-8")
    assert main(["derive", str(scene), "closed_form", "--format", "latex"]) == 0
    out = capsys.readouterr().out
    assert r"\left(\frac{d}{d t} \cos{\left(\theta{\left(t \right)} \right)}\right)^{2} =" in out
    assert r"\cos^{3}{\left(\theta \right)}" in out  # the cubic, in the plain coordinate (code can be generated)
    double = tmp_path / "double.toml"
    double.write_text('system = "lagrangian"\ncoordinates = ["a1", "a2"]\n'
                      'lagrangian = "a1_dot**2 + a2_dot**2/2 + a1_dot*a2_dot*cos(a1 - a2) + 2*cos(a1) + cos(a2)"\n'
                      "[initial]\na1 = 1.0\na2 = 0.0\na1_dot = 0.0\na2_dot = 0.0\n"
                      '[time]\nt_end = 1.0\nsamples = 11\n[output]\nquantities = ["a1"]\n', encoding="utf-8")
    assert main(["derive", str(double), "closed_form"]) == 2
    assert "one coordinate left" in capsys.readouterr().err


def test_the_closed_form_period_is_cross_checked_against_the_measured_one():
    """Agreeing within their estimates: the closed form's; disagreeing: the measured period, its estimate the
    disagreement (the recipe's assumptions did not hold), never the closed form with its small estimate."""
    from mechderive.systems.lagrangian.system import _checked

    assert _checked((2.0, 1e-15), (2.0 + 1e-10, 1e-9)) == (2.0, 1e-15)
    assert _checked((2.0, 1e-15), (3.0, 1e-9)) == (3.0, 1.0)
    assert _checked((2.0, 1e-15), (None, "not periodic within the run")) == (2.0, 1e-15)


def test_the_generic_reduction_equals_the_built_in_heavy_tops_f_of_u_symbolically():
    """Issue 16: the heavy top's hand-built derivation (systems/heavy_top/model.py, f(u) in a, b, α, β) and the
    generic recipe on its Lagrangian give the same polynomial, identically, once a = p_ψ/I1, b = p_φ/I1,
    α = 2(E − p_ψ²/(2 I3))/I1, β = 2Mgl/I1 (3.66), (3.72)."""
    from mechderive.systems.heavy_top import model as hm

    L = I1 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) / 2 \
        + I3 * (ps.diff(t) + sp.cos(th) * ph.diff(t)) ** 2 / 2 - M * g * l * sp.cos(th)
    found = _found(L, [ph, th, ps])
    p_phi, p_psi = sp.Symbol("p_phi", real=True), sp.Symbol("p_psi", real=True)
    built_in = hm.model().f_u.subs({hm.a: p_psi / I1, hm.b: p_phi / I1, hm.alpha: 2 * (E - p_psi**2 / (2 * I3)) / I1,
                                    hm.beta: 2 * M * g * l / I1, hm.u: found.variable})
    assert sp.expand(found.polynomial.as_expr() - built_in) == 0


def test_kepler_orbits_along_phi_are_quadratics_in_one_over_r_and_close():
    """Binet: (du/dφ)² = 2mE/p² + 2mk u/p² − u² with u = 1/r (a quadratic, by hand): the orbit's period in φ is
    2π — it closes; with an extra attraction β/r² it is 2π/√(1 − 2mβ/p²) — the orbit precesses (both by hand)."""
    kepler = m * (r.diff(t) ** 2 + r**2 * ph.diff(t) ** 2) / 2 + k / r
    found = find_substitution(reduce_to_quadrature(LagrangianModel(kepler, [r, ph]), along="phi"))
    p = sp.Symbol("p_phi", real=True)
    u = found.variable
    assert (found.name, found.degree, found.independent) == ("u = 1/q", 2, "phi")
    assert sp.expand(found.polynomial.as_expr() - (2 * m * E / p**2 + 2 * m * k * u / p**2 - u**2)) == 0
    with mpmath.workdps(40):
        values = {m: 1, k: 1, p: 1, E: mpmath.mpf(-3) / 10}  # bound: E < 0
        assert abs(oscillation(found, values, 1.0).period - 2 * mpmath.pi) <= 1e-30
        beta = sp.Symbol("beta", positive=True)
        extra = find_substitution(reduce_to_quadrature(LagrangianModel(kepler + beta / r**2, [r, ph]), along="phi"))
        o = oscillation(extra, {**values, beta: mpmath.mpf(1) / 10}, 1.0)
        assert abs(o.period - 2 * mpmath.pi / mpmath.sqrt(1 - mpmath.mpf(2) / 10)) <= 1e-30
    with pytest.raises(NoQuadrature, match="cyclic coordinate to measure the orbit along"):
        reduce_to_quadrature(LagrangianModel(kepler, [r, ph]), along="r")
