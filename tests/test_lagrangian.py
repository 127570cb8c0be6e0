"""The generic Lagrangian layer (mechderive.core.lagrangian), on systems with hand-written references.

References are independent of the layer: the equations of motion of the spherical pendulum, the
central-force problem, a charge in a uniform magnetic field (the Lorentz force) and a driven
oscillator, written out by hand; the textbook effective potentials; Kepler's third law; and
conservation checked along SciPy's solve_ivp (DOP853) rather than symbolically.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from mechderive.core.lagrangian import LagrangianModel, from_state_symbols, vanishes
from mechderive.core.symbols import coordinate, state_symbol, t
from mechderive.errors import DerivationError, InvalidInputError

m, g, l, k = sp.symbols("m g l k", positive=True)
qB, Om, F0 = sp.symbols("q_B Omega F0", real=True)
S = state_symbol  # plain state symbols: S("theta_dot") ...


def _pendulum() -> LagrangianModel:
    """Spherical pendulum, θ from the downward vertical: L = ½ml²(θ̇² + sin²θ φ̇²) + mgl cos θ."""
    th, ph = coordinate("theta"), coordinate("phi")
    L = m * l**2 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) / 2 + m * g * l * sp.cos(th)
    return LagrangianModel(L, [th, ph])


def _central(V=None) -> LagrangianModel:
    """Planar motion in a central potential: L = ½m(ṙ² + r²φ̇²) − V(r); V generic unless given."""
    r, ph = coordinate("r"), coordinate("phi")
    V = sp.Function("V")(r) if V is None else V(r)
    return LagrangianModel(m * (r.diff(t) ** 2 + r**2 * ph.diff(t) ** 2) / 2 - V, [r, ph])


# --- Euler–Lagrange equations -------------------------------------------------------------------

def test_spherical_pendulum_accelerations_match_the_hand_derivation():
    # θ̈ = sin θ cos θ φ̇² − (g/l) sin θ,  φ̈ = −2 cot θ θ̇ φ̇
    th, thd, phd = S("theta"), S("theta_dot"), S("phi_dot")
    acc = _pendulum().acceleration_map
    assert list(acc) == [S("theta_ddot"), S("phi_ddot")]
    assert vanishes(acc[S("theta_ddot")] - (sp.sin(th) * sp.cos(th) * phd**2 - g / l * sp.sin(th)))
    assert vanishes(acc[S("phi_ddot")] + 2 * sp.cos(th) / sp.sin(th) * thd * phd)


def test_central_force_accelerations_with_a_generic_potential():
    # r̈ = r φ̇² − V'(r)/m,  φ̈ = −2 ṙ φ̇ / r
    r, rd, phd = S("r"), S("r_dot"), S("phi_dot")
    acc = _central().accelerations
    assert sp.simplify(acc[0] - (r * phd**2 - sp.Function("V")(r).diff(r) / m)) == 0
    assert sp.simplify(acc[1] + 2 * rd * phd / r) == 0


def test_velocity_dependent_lagrangian_gives_the_lorentz_force():
    # L = ½m(ẋ² + ẏ²) + ½qB(xẏ − yẋ): m ẍ = qB ẏ, m ÿ = −qB ẋ (uniform B along z)
    x, y = coordinate("x"), coordinate("y")
    L = m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2 + qB * (x * y.diff(t) - y * x.diff(t)) / 2
    acc = LagrangianModel(L, [x, y]).accelerations
    assert sp.simplify(acc - sp.Matrix([qB * S("y_dot") / m, -qB * S("x_dot") / m])) == sp.zeros(2, 1)


def test_explicit_time_dependence_enters_forcing_and_energy_rate():
    # driven oscillator L = ½mẋ² − ½kx² + F0 x cos Ωt: mẍ = −kx + F0 cos Ωt, and dh/dt = −∂L/∂t
    x = coordinate("x")
    L = m * x.diff(t) ** 2 / 2 - k * x**2 / 2 + F0 * x * sp.cos(Om * t)
    model = LagrangianModel(L, [x])
    xs, xd = S("x"), S("x_dot")
    assert sp.simplify(model.accelerations[0] - (-k * xs + F0 * sp.cos(Om * t)) / m) == 0
    h = model.energy_function
    rate = h.diff(t) + h.diff(xs) * xd + h.diff(xd) * model.accelerations[0]
    assert sp.simplify(rate + model.state_lagrangian.diff(t)) == 0


def test_euler_lagrange_equations_in_functions_of_t():
    # the θ equation of the pendulum: ml²θ̈ − ml² sin θ cos θ φ̇² + mgl sin θ = 0
    th, ph = coordinate("theta"), coordinate("phi")
    eq = _pendulum().euler_lagrange[0]
    ref = m * l**2 * (th.diff(t, 2) - sp.sin(th) * sp.cos(th) * ph.diff(t) ** 2) + m * g * l * sp.sin(th)
    assert sp.expand(eq - ref) == 0


def test_mass_matrix_and_forcing_reproduce_the_equations():
    model = _pendulum()
    acc_syms = sp.Matrix(model.acceleration_symbols)
    residual = model.mass_matrix * acc_syms - model.forcing
    el = from_state_symbols(residual, model.coordinates) - model.euler_lagrange
    assert sp.simplify(el) == sp.zeros(2, 1)


# --- ignorable coordinates, momenta, energy -----------------------------------------------------

def test_cyclic_coordinates_are_detected_exactly():
    assert _pendulum().cyclic_coordinates == (coordinate("phi"),)
    assert _central().cyclic_coordinates == (coordinate("phi"),)
    # ∂L/∂q = ẋ²(−2 sin 2q + 4 sin q cos q)/2 is zero only by a trig identity: q is still ignorable
    q, x = coordinate("q"), coordinate("x")
    L = q.diff(t) ** 2 / 2 + x.diff(t) ** 2 * (sp.cos(2 * q) + 2 * sp.sin(q) ** 2) / 2 - k * x**2 / 2
    assert LagrangianModel(L, [q, x]).cyclic_coordinates == (q,)


def test_momenta_and_energy_function():
    model = _pendulum()
    th, thd, phd = S("theta"), S("theta_dot"), S("phi_dot")
    assert model.conserved_momenta == {coordinate("phi"): m * l**2 * sp.sin(th) ** 2 * phd}
    assert sp.expand(model.momenta[0] - m * l**2 * thd) == 0
    T = m * l**2 * (thd**2 + sp.sin(th) ** 2 * phd**2) / 2
    assert sp.expand(model.energy_function - (T - m * g * l * sp.cos(th))) == 0


# --- Routh reduction ---------------------------------------------------------------------------

def test_spherical_pendulum_effective_potential():
    p = sp.Symbol("p_phi", real=True)
    th = S("theta")
    model = _pendulum()
    ref = p**2 / (2 * m * l**2 * sp.sin(th) ** 2) - m * g * l * sp.cos(th)
    assert vanishes(model.effective_potential - ref)
    assert vanishes(model.cyclic_velocities[S("phi_dot")] - p / (m * l**2 * sp.sin(th) ** 2))


def test_central_force_routhian_effective_potential_and_radial_equation():
    p = sp.Symbol("p_phi", real=True)
    r, rd = S("r"), S("r_dot")
    V = sp.Function("V")(r)
    model = _central()
    assert sp.simplify(model.routhian - (m * rd**2 / 2 - p**2 / (2 * m * r**2) - V)) == 0
    assert sp.simplify(model.effective_potential - (p**2 / (2 * m * r**2) + V)) == 0
    # the Routhian's own E–L equation: m r̈ = p²/(m r³) − V'(r)
    assert sp.simplify(model.reduced_accelerations[0] - (p**2 / (m**2 * r**3) - V.diff(r) / m)) == 0


def test_reduced_energy_equals_the_energy_function():
    model = _central()
    R, rd = model.routhian, S("r_dot")
    p = model.momentum_symbols[coordinate("phi")]
    h_reduced = rd * R.diff(rd) - R
    h = model.energy_function.subs(S("phi_dot"), model.cyclic_velocities[S("phi_dot")])
    assert sp.simplify(h_reduced - h) == 0 and h_reduced.has(p)


def test_routh_reduction_without_cyclic_coordinates_raises():
    x = coordinate("x")
    model = LagrangianModel(x.diff(t) ** 2 / 2 - k * x**2 / 2, [x])
    with pytest.raises(DerivationError, match="expected at least one cyclic coordinate to reduce, got none"):
        model.routhian  # noqa: B018


# --- numbers: conservation along solve_ivp, Kepler's third law ----------------------------------

def test_pendulum_conserves_energy_and_p_phi_along_solve_ivp():
    model = _pendulum()
    rhs = model.ode_rhs([m, g, l])
    vals = (1.3, 9.81, 0.7)
    y0 = [0.9, 0.2, 0.4, 1.7]  # θ, φ, θ̇, φ̇
    sol = solve_ivp(rhs, (0, 20), y0, args=vals, method="DOP853", rtol=1e-12, atol=1e-12)
    args = [*model.positions, *model.velocities, m, g, l]
    h = sp.lambdify(args, model.energy_function)(*sol.y, *vals)
    p = sp.lambdify(args, model.conserved_momenta[coordinate("phi")])(*sol.y, *vals)
    # rtol 1e-12 per step over ~2000 steps: drifts of a few 1e-11 relative are the integrator's own
    assert np.max(np.abs(h - h[0])) < 1e-9 * abs(h[0])
    assert np.max(np.abs(p - p[0])) < 1e-9 * abs(p[0])
    assert "ode_rhs" in model.compiled


def test_kepler_orbit_period_and_invariants():
    # V = −k/r: bound orbit with E < 0 has semi-major axis A = −k/(2E) and period 2π√(m A³/k)
    model = _central(lambda r: -k / r)
    vals = (1.0, 2.0)  # m, k
    y0 = [1.0, 0.0, 0.3, 1.1]  # r, φ, ṙ, φ̇
    args = [*model.positions, *model.velocities, m, k]
    energy = sp.lambdify(args, model.energy_function)
    E0 = energy(*y0, *vals)
    A = -vals[1] / (2 * E0)
    period = 2 * np.pi * np.sqrt(vals[0] * A**3 / vals[1])
    sol = solve_ivp(model.ode_rhs([m, k]), (0, 1.2 * period), y0, args=vals, method="DOP853",
                    rtol=1e-12, atol=1e-12, dense_output=True)
    # after one period the orbit closes: φ advanced by 2π and (r, ṙ) back (1e-8: interpolant + rtol)
    r1, phi1, rd1, _ = sol.sol(period)
    assert abs(phi1 - 2 * np.pi) < 1e-8 and abs(r1 - y0[0]) < 1e-8 and abs(rd1 - y0[2]) < 1e-8
    h = energy(*sol.y, *vals)
    p = sp.lambdify(args, model.conserved_momenta[coordinate("phi")])(*sol.y, *vals)
    assert np.max(np.abs(h - E0)) < 1e-10 and np.max(np.abs(p - p[0])) < 1e-10


# --- laziness ----------------------------------------------------------------------------------

def test_quantities_are_derived_lazily():
    model = _pendulum()
    assert model.derived == []
    _ = model.effective_potential
    for name in ("accelerations", "mass_matrix", "forcing", "euler_lagrange", "energy_function"):
        assert not model.is_derived(name)
    model2 = _pendulum()
    _ = model2.accelerations
    assert not model2.is_derived("routhian") and not model2.is_derived("cyclic_coordinates")


# --- bad input ---------------------------------------------------------------------------------

def test_lagrangian_in_other_coordinates_is_refused():
    x = coordinate("x")
    r, ph = coordinate("r"), coordinate("phi")
    L = (r.diff(t) ** 2 + r**2 * ph.diff(t) ** 2) / 2
    with pytest.raises(InvalidInputError, match=r"expected the Lagrangian to be a function of the coordinates "
                                                r"\(x\(t\)\), their velocities and t, got also .*phi\(t\)"):
        LagrangianModel(L + x.diff(t) ** 2, [x])


def test_lagrangian_in_plain_symbols_is_refused():
    th, thd = sp.symbols("theta theta_dot")
    with pytest.raises(InvalidInputError, match=r"expected the coordinates as functions of t \(coordinate\('theta'\)\), "
                                                r"got the plain symbol theta"):
        LagrangianModel(thd**2 / 2 + sp.cos(th), [coordinate("theta")])


def test_bad_coordinates_and_lagrangians():
    x, y = coordinate("x"), coordinate("y")
    with pytest.raises(InvalidInputError, match="expected each coordinate to be a function of t like coordinate"):
        LagrangianModel(x.diff(t) ** 2, [sp.Symbol("x")])
    with pytest.raises(InvalidInputError, match=r"expected distinct coordinates, got \[x\(t\), x\(t\)\]"):
        LagrangianModel(x.diff(t) ** 2, [x, x])
    with pytest.raises(InvalidInputError, match="expected at least one coordinate, got none"):
        LagrangianModel(x.diff(t) ** 2, [])
    with pytest.raises(InvalidInputError, match="expected a Lagrangian"):
        LagrangianModel(None, [x])
    with pytest.raises(InvalidInputError, match="expected the Lagrangian as a scalar SymPy expression, got"):
        LagrangianModel(sp.Matrix([x.diff(t) ** 2]), [x])
    with pytest.raises(InvalidInputError, match="expected at most first derivatives of the coordinates, got"):
        LagrangianModel(x.diff(t) ** 2 + x * x.diff(t, 2), [x])
    with pytest.raises(InvalidInputError, match=r"expected the Lagrangian to contain the velocity of every "
                                                r"coordinate, got none of Derivative\(y\(t\), t\)"):
        LagrangianModel(x.diff(t) ** 2 / 2 - y**2, [x, y])


def test_singular_lagrangian_has_no_accelerations():
    x, y = coordinate("x"), coordinate("y")
    model = LagrangianModel((x.diff(t) + y.diff(t)) ** 2 / 2 - x**2, [x, y])
    with pytest.raises(InvalidInputError, match=r"expected a regular Lagrangian \(det ∂²L/∂q̇∂q̇ ≠ 0\), got det = 0"):
        model.accelerations  # noqa: B018


def test_ode_rhs_needs_every_parameter():
    with pytest.raises(InvalidInputError, match=r"expected parameters including g, got \[m, l\]"):
        _pendulum().ode_rhs([m, l])


def test_subclass_that_derives_its_lagrangian_refuses_another():
    from mechderive.systems.heavy_top.model import HeavyTopModel

    with pytest.raises(InvalidInputError, match="expected no Lagrangian for HeavyTopModel, which derives its own"):
        HeavyTopModel(coordinate("x").diff(t) ** 2)
