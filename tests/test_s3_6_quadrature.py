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
