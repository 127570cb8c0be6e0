"""Section 3.7: deformable bodies — gauge potential (3.87)–(3.92), Wilson loop (3.98)–(3.99), field strength
(3.102)–(3.103), the falling cat.

References are independent of the code under test: angular momentum from its definition Σ m r × ṙ with
ṙ by mpmath's numerical differentiation at 30 digits; the inertia module's (3.19); a cat reduced by hand to
a one-dimensional integral (scipy quad); the measured order of the small-loop remainder.
"""

from __future__ import annotations

import json

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechderive.errors import IntegrationError, InvalidInputError, ShapeError
from mechderive.kinematics.so3 import expm_so3, hat
from mechderive.systems.deformable import (DeformableBody, ShapeLoop, centred_positions, falling_cat,
                                           falling_cat_motion, net_rotation, rotation_along)
from mechderive.systems.deformable import cat as cat_module
from mechderive.systems.deformable import derivation
from mechderive.systems.deformable.examples import BASE_SHAPE, gauge_rotation, shape_symbols, three_mass_body

from .conftest import run_python

S = sp.Symbol("s", real=True)
X0 = np.array([float(v) for v in BASE_SHAPE])


@pytest.fixture(scope="session")
def conn():
    return three_mass_body().numeric()


def _loop(radius=0.4):
    x0, y0 = BASE_SHAPE
    return ShapeLoop.from_expressions(
        [x0 + radius * sp.cos(S), y0 + radius * sp.sin(S) / 2 + radius * sp.sin(2 * S) / 4], S, (0.0, 2 * np.pi))


# ============================================================================ (3.92) against L = Σ m r × ṙ


def _positions_mp(body):
    """The body's masses and positions as given, as mpmath functions of (shape, parameters): lambdified once per body
    (lambdify is the slow part), with common subexpressions taken out (the cat's positions are ~400 operations each)."""
    syms = [*body.coordinates, *body.parameters]
    return (sp.lambdify(syms, list(body.masses), "mpmath"),
            sp.lambdify(syms, [list(r) for r in body.positions], "mpmath", cse=True))


def _space_momentum_mp(body, functions, point, v, R0, sign=1):
    """L at t = 0 of r_i(t) = R0 exp(t hat(±v)) r̃_i(x + t ẋ), computed from Σ m r × ṙ at 50 digits
    (``functions``: :func:`_positions_mp` of the body).

    ṙ by the central difference (r(h) − r(−h))/2h, h = 1e-15: truncation h²|r‴|/6 ~ 1e-30,
    rounding 1e-50/h = 1e-35, far below the 1e-22 tested.
    """
    mass_function, pos = functions
    masses = mass_function(*[point[s] for s in (*body.coordinates, *body.parameters)])
    H = mpmath.matrix(hat_mp(v)) * sign

    def config(t):
        shape = pos(*[point[s] + t * point[d] for s, d in zip(body.coordinates, body.velocities)],
                    *[point[p] for p in body.parameters])
        turn = R0 * mpmath.expm(t * H)
        return [turn * mpmath.matrix(r) for r in shape]

    with mpmath.workdps(50):
        h = mpmath.mpf("1e-15")
        r0, rp, rm = config(0), config(h), config(-h)
        L = mpmath.matrix(3, 1)
        for m, r, a, b in zip(masses, r0, rp, rm):
            rd = (a - b) / (2 * h)
            L += m * mpmath.matrix([r[1] * rd[2] - r[2] * rd[1], r[2] * rd[0] - r[0] * rd[2],
                                    r[0] * rd[1] - r[1] * rd[0]])
    return L


def hat_mp(v):
    return [[0, v[2], -v[1]], [-v[2], 0, v[0]], [v[1], -v[0], 0]]


@pytest.mark.parametrize("which", ["three masses", "cat"])
def test_3_92_omega_makes_the_space_angular_momentum_vanish(which, rng):
    body = three_mass_body() if which == "three masses" else cat_module.cat_body()
    vvec = sp.lambdify([*body.coordinates, *body.velocities, *body.parameters], list(body.angular_velocity_vector),
                       "mpmath")
    values = {p: cat_module.DEFAULTS[p.name] for p in body.parameters}
    numeric = body.numeric(values)
    functions = _positions_mp(body)
    with mpmath.workdps(30):
        for _ in range(3):
            point = {s: mpmath.mpf(float(rng.uniform(-1, 1))) for s in (*body.coordinates, *body.velocities)}
            point.update({p: mpmath.mpf(v) for p, v in values.items()})
            v = vvec(*[point[s] for s in (*body.coordinates, *body.velocities, *body.parameters)])
            q = mpmath.matrix(rng.normal(size=3).tolist())
            R0 = mpmath.expm(mpmath.matrix(hat_mp(q)))  # a random orientation
            L = _space_momentum_mp(body, functions, point, v, R0)
            scale = mpmath.norm(_space_momentum_mp(body, functions, point, [0, 0, 0], R0))  # |L| without the rotation
            assert scale > 1e-12
            # L is computed to ~1e-28 relative; Ω from (3.92) must cancel the shape's own momentum exactly.
            assert mpmath.norm(L) < 1e-22 * scale
            wrong = _space_momentum_mp(body, functions, point, v, R0, sign=-1)  # Ω transposed: the other sign
            assert mpmath.norm(wrong) > 1e-3 * scale
            # the compiled route agrees with the 30-digit one to rounding
            xs = np.array([float(point[s]) for s in body.coordinates])
            xd = np.array([float(point[s]) for s in body.velocities])
            np.testing.assert_allclose(numeric.angular_velocity(xs, xd), [float(c) for c in v], rtol=1e-10, atol=1e-12)


def test_3_93_inertia_equals_the_inertia_modules_point_mass_tensor(conn, rng):
    from mechderive.inertia import inertia_tensor

    for x in rng.uniform(-1, 1, size=(4, 2)):
        np.testing.assert_allclose(conn.inertia(x), inertia_tensor(conn.masses, conn.positions(x)), atol=1e-13)


def test_3_87_connection_contracts_to_omega(conn, rng):
    x, xd = rng.uniform(-1, 1, size=(2, 5, 2))
    by_parts = np.einsum("nA,nAa->na", xd, conn.connection(x))
    np.testing.assert_allclose(conn.angular_velocity(x, xd), by_parts, rtol=1e-12, atol=1e-13)


# ============================================================================ the polynomial twins and the forms of Ω


def _tidy_reference(expr):
    """The former ``_tidy``, kept as the reference: expand, sin/cos → c/s, ``sympy.reduced`` by c² + s² − 1 (lex),
    back, ``factor_terms``."""
    e = sp.expand(expr)
    args = sorted({f.args[0] for f in e.atoms(sp.sin, sp.cos)}, key=sp.default_sort_key)
    fwd, back, gens, basis = {}, {}, [], []
    for i, a in enumerate(args):
        c, s = sp.Dummy(f"c{i}"), sp.Dummy(f"s{i}")
        fwd[sp.cos(a)], fwd[sp.sin(a)] = c, s
        back[c], back[s] = sp.cos(a), sp.sin(a)
        gens += [c, s]
        basis.append(c**2 + s**2 - 1)
    if not gens:
        return e
    _, rem = sp.reduced(sp.expand(e.xreplace(fwd)), basis, *gens, order="lex")
    return sp.factor_terms(sp.expand(rem).xreplace(back))


def _several_angles_body():
    """Three angles x, 2x, x + y, which the twins treat as independent: Ω is kept factored there."""
    return DeformableBody([1, 1, 1], centred_positions([1, 1, 1], [(sp.cos(2 * x_), sp.sin(x_), 0),
                                                                  (0, sp.cos(x_)**3, y_), (x_ * y_, 0, sp.sin(x_ + y_))]),
                          [x_, y_])


def test_tidy_is_the_normal_form_sympy_reduced_computes():
    from mechderive.systems.deformable.model import _tidy

    m, a = sp.symbols("m a", positive=True)
    cat = cat_module.cat_body()
    exprs = [c for r in cat.positions for c in r]  # long centred sums with 1/half_mass
    exprs += [c for r in three_mass_body().regauged(gauge_rotation()).positions for c in r]
    exprs += [sp.sin(x_)**4 + sp.cos(x_)**4 * y_ / m, sp.cos(2 * x_)**3 * sp.sin(x_) - 1 / m**2 * sp.cos(x_)**3,
              (sp.cos(x_) + sp.sin(y_))**5 * a - sp.Rational(1, 3), x_**2 * (1 + y_) / 7, sp.Integer(0),
              sp.cos(y_ * (x_ + sp.Rational(1, 2))) ** 2 + sp.sin(x_ * y_ + y_ / 2) ** 2,  # one angle, two spellings
              sp.cos(x_)**2 + sp.sin(x_)**2 - 1 + x_ * sp.sin(y_) - sp.sin(y_) * x_,
              sp.Float(0.5) * sp.cos(x_)**3, sp.sqrt(2) * sp.cos(x_)**2, sp.cos(x_)**2 / (1 + m)]
    for e in exprs:
        assert _tidy(e) == _tidy_reference(e), e


@pytest.mark.parametrize("make", [cat_module.cat_body, _several_angles_body], ids=["cat", "several angles"])
def test_twins_give_the_expressions_of_the_expression_route(make):
    """Reduced positions, Jacobians, Ĩ (3.93) and L̃ (3.94) computed on the polynomial twins are the very
    expressions the route on SymPy expressions gives (the former one, with the reference _tidy)."""
    body = make()
    assert body._ring is not None and body._ring.ring is not None
    reduced = tuple(r.applyfunc(_tidy_reference) for r in body.positions)
    assert body.reduced_positions == reduced
    xs = sp.Matrix(body.coordinates)
    jacobians = tuple(r.jacobian(xs).applyfunc(_tidy_reference) for r in reduced)
    assert body.position_jacobians == jacobians
    d = derivation.model()
    assert body.inertia_tensor == body._per_mass(d.inertia_per_mass).applyfunc(_tidy_reference)
    total = sp.zeros(3, 1)
    for A, xdot in enumerate(body.velocities):
        total += body._per_mass(d.apparent_angular_momentum, [J.col(A) for J in jacobians]).applyfunc(_tidy_reference) * xdot
    assert body.apparent_angular_momentum == total


def _numeric_connection(body, functions, point):
    """Ω_A at ``point`` by solving Ĩ v = L̃_A at 30 digits: Ĩ = Σ m (|r̃|² 1 − r̃ r̃ᵀ), L̃_A = Σ m r̃ × ∂_A r̃, from the
    positions as given (``functions``: the masses and positions lambdified), not from the body's derived Ĩ, L̃.

    ∂_A r̃ by the central difference (r̃(x + h e_A) − r̃(x − h e_A))/2h at 60 digits, h = 1e-25: truncation
    h²|r̃‴|/6 ~ 1e-50, rounding 1e-60/h = 1e-35, far below the 1e-24 tested."""
    syms = [*body.coordinates, *body.parameters]
    mass_function, pos = functions
    with mpmath.workdps(60):
        masses = mass_function(*[point[s] for s in syms])
        x0 = [point[s] for s in body.coordinates]

        def positions(xs):
            return [mpmath.matrix(r) for r in pos(*xs, *[point[p] for p in body.parameters])]

        r0 = positions(x0)
        inertia = mpmath.zeros(3, 3)
        for m, r in zip(masses, r0):
            inertia += m * ((r.T * r)[0] * mpmath.eye(3) - r * r.T)
        h = mpmath.mpf("1e-25")
        rows = []
        for A in range(body.dimension):
            plus = positions([x + (h if B == A else 0) for B, x in enumerate(x0)])
            minus = positions([x - (h if B == A else 0) for B, x in enumerate(x0)])
            L = mpmath.matrix(3, 1)
            for m, r, rp, rm in zip(masses, r0, plus, minus):
                rd = (rp - rm) / (2 * h)
                L += m * mpmath.matrix([r[1] * rd[2] - r[2] * rd[1], r[2] * rd[0] - r[0] * rd[2],
                                        r[0] * rd[1] - r[1] * rd[0]])
            rows.append(mpmath.lu_solve(inertia, L))
    return rows




@pytest.mark.parametrize("make, form", [
    (three_mass_body, "expanded"), (lambda: three_mass_body().regauged(gauge_rotation()), "expanded"),
    (cat_module.cat_body, "expanded"), (_several_angles_body, "factored")],
    ids=["three masses", "regauged", "cat", "several angles"])
def test_connection_equals_a_30_digit_solve_of_L_equal_0(make, form):
    """Ω_A (3.87) and Ω (3.92) of the derivation (Ĩ⁻¹ L̃ on the twins, common factors cancelled or kept factored)
    against solving Ĩ v = L̃_A numerically at 30 digits, at 20 random rational shapes, velocities and parameters."""
    import random

    body = make()
    rows, v = body.connection_vectors, body.angular_velocity_vector
    assert form in {f for f, *_ in body._twin["angular_velocity_vector"]}  # the route taken (both are tested)
    rnd = random.Random(92)
    worst = mpmath.mpf(0)
    functions = _positions_mp(body)
    # the derivation's expressions, evaluated at 45 digits (mpmath lambdify prints rationals as quotients of mpf)
    arguments = [*body.coordinates, *body.velocities, *body.parameters]
    derived = sp.lambdify(arguments, [list(rows), list(v)], "mpmath", cse=True)
    with mpmath.workdps(30):
        for _ in range(20):
            point = {s: sp.Rational(rnd.randint(-90, 90), 97) for s in (*body.coordinates, *body.velocities)}
            point.update({p: sp.Rational(rnd.randint(30, 130), 100) for p in body.parameters})
            mp_point = {s: mpmath.mpf(q.p) / q.q for s, q in point.items()}
            want = _numeric_connection(body, functions, mp_point)
            total = [sum(want[A][a] * mp_point[xd] for A, xd in enumerate(body.velocities)) for a in range(3)]
            with mpmath.workdps(45):
                got_rows, got_v = derived(*[mpmath.mpf(point[s].p) / point[s].q for s in arguments])
            for A in range(body.dimension):
                for a in range(3):
                    worst = max(worst, abs(mpmath.re(got_rows[3 * A + a]) - want[A][a]) / (1 + abs(want[A][a])))
            for a in range(3):
                worst = max(worst, abs(mpmath.re(got_v[a]) - total[a]) / (1 + abs(total[a])))
    assert worst < 1e-24, worst


def test_cat_connection_is_ltilde_over_itilde_11():
    """The cat's Ĩ is block-diagonal and its L̃ along e1: the cancelled Ω_swivel is L̃_1,swivel / Ĩ_11, Ω_bend = 0."""
    from mechderive.systems.deformable.model import _tidy

    body = cat_module.cat_body()
    rows = body.connection_vectors
    bend_dot, swivel_dot = body.velocities
    assert list(rows.row(0)) == [0, 0, 0] and list(rows.row(1))[1:] == [0, 0]
    expected = body.apparent_angular_momentum[0].coeff(swivel_dot) / body.inertia_tensor[0, 0]
    assert _tidy(sp.fraction(sp.together(rows[1, 0] - expected))[0]) == 0
    assert sp.count_ops(rows[1, 0]) < 40


# ============================================================================ (3.98) speed independence, arrays


def test_3_98_net_rotation_is_independent_of_the_traversal_speed(conn):
    loop = _loop()
    base = net_rotation(conn, loop, rtol=1e-12)
    assert np.max(np.abs(base.R - np.eye(3))) > 0.05  # a non-trivial net rotation
    for T, wobble in [(1.0, 0.6), (7.0, -0.9), (0.2, 0.3)]:
        k = 2 * np.pi / T
        other = loop.reparametrised(lambda u: k * u + wobble * np.sin(k * u),
                                    lambda u: k * (1 + wobble * np.cos(k * u)), (0, T))
        res = net_rotation(conn, other, rtol=1e-12)
        # both at rtol 1e-12; their estimates are reported and bounded
        assert res.error_estimate < 1e-11
        np.testing.assert_allclose(res.R, base.R, atol=1e-10)


def test_3_98_loop_given_as_arrays(conn):
    loop = _loop()
    times = np.linspace(0, 2 * np.pi, 801)
    sampled = net_rotation(conn, (times, loop.shape(times)), rtol=1e-12)
    exact = net_rotation(conn, loop, rtol=1e-12)
    # periodic cubic spline: O(h⁴) with h = 2π/800 → ~1e-9 in ẋ, so ~1e-9 in R
    np.testing.assert_allclose(sampled.R, exact.R, atol=1e-7)


def test_3_98_later_times_to_the_right(conn):
    """Ṙ = RΩ (later on the right) keeps the body's L zero; the left ordering (Ṙ = ΩR) does not give R⁻¹Ṙ = Ω."""
    loop = _loop()
    t = np.linspace(1.0, 1.0 + 8e-3, 9)
    run = rotation_along(conn, loop, rtol=1e-13, t_eval=t)
    fd = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
    Rdot = np.einsum("k,kab->ab", fd, run.rotations) / 1e-3
    R = run.rotations[4]
    Omega = hat(np.einsum("A,Aa->a", loop.velocity(t[4:5])[0], conn.connection(loop.shape(t[4:5]))[0]))
    np.testing.assert_allclose(R.T @ Rdot, Omega, atol=1e-9)  # (3.86)
    assert np.max(np.abs(Rdot @ R.T - Omega)) > 1e-2  # ṘR⁻¹ is not Ω here


# ============================================================================ (3.89), (3.99) gauge


def test_3_99_net_rotation_conjugated_by_the_gauge_change(conn):
    body = three_mass_body().regauged(gauge_rotation())
    # kept per S (the catalog's (3.89) derives the same body): asked again, the same body, nothing derived anew
    derived = list(body.derived)
    assert three_mass_body().regauged(sp.Matrix(gauge_rotation())) is body and body.derived == derived
    new = body.numeric()
    for radius in (0.4, 0.2):
        loop = _loop(radius)
        R = net_rotation(conn, loop, rtol=1e-12).R
        R_new = net_rotation(new, loop, rtol=1e-12).R
        x0 = loop.shape(np.array([0.0]))[0]
        S0 = np.array(gauge_rotation().subs(dict(zip(shape_symbols(), x0))).evalf(), dtype=float)
        assert np.max(np.abs(R_new - R)) > 1e-2  # the gauge change is not trivial …
        np.testing.assert_allclose(R_new, S0 @ R @ S0.T, atol=1e-10)  # … but only conjugates R (3.99)


@pytest.mark.slow
def test_field_strength_is_gauge_covariant_only_as_corrected():
    """F' = S F S⁻¹ under (3.89) for the derived F (both derived from scratch); the printed (3.103) is not."""
    body = three_mass_body()
    old, new = body.numeric(), body.regauged(gauge_rotation()).numeric()
    x0 = np.array([0.2, -0.4])
    S0 = np.array(gauge_rotation().subs(dict(zip(shape_symbols(), x0))).evalf(), dtype=float)

    def printed(conn):
        d, O = conn.connection_derivatives(x0), conn.connection(x0)
        return hat(d[0, 1]) - hat(d[1, 0]) + hat(O[0]) @ hat(O[1]) - hat(O[1]) @ hat(O[0])

    F, F_new = hat(old.field_strength(x0)[0, 1]), hat(new.field_strength(x0)[0, 1])
    np.testing.assert_allclose(F_new, S0 @ F @ S0.T, atol=1e-11)
    assert np.max(np.abs(printed(new) - S0 @ printed(old) @ S0.T)) > 1e-2


# ============================================================================ (3.101)–(3.103) small loops


def test_3_103_field_strength_is_antisymmetric_and_compiled(conn, rng):
    for x in rng.uniform(-1, 1, size=(3, 2)):
        F = conn.field_strength(x)
        np.testing.assert_allclose(F, -np.swapaxes(F, 0, 1), atol=1e-14)
        d, O = conn.connection_derivatives(x), conn.connection(x)
        comm = hat(O[0]) @ hat(O[1]) - hat(O[1]) @ hat(O[0])
        np.testing.assert_allclose(hat(F[0, 1]), hat(d[1, 0]) - hat(d[0, 1]) + comm, atol=1e-12)
        assert np.max(np.abs(comm)) > 1e-2 and np.max(np.abs(d[1, 0] - d[0, 1])) > 1e-2  # both parts matter


def _small_loop_errors(conn, F12, sizes):
    errors = []
    unit = [sp.cos(S) - 1, sp.sin(S) + sp.sin(2 * S) / 2]  # the loop's shape, scaled by e below
    M12_unit = float(sp.integrate(unit[0] * sp.diff(unit[1], S), (S, 0, 2 * sp.pi)))  # ∮ a¹ da² ∝ e²
    for e in sizes:
        a = [e * unit[0], e * unit[1]]
        loop = ShapeLoop.from_expressions([BASE_SHAPE[0] + a[0], BASE_SHAPE[1] + a[1]], S, (0.0, 2 * np.pi))
        M12 = e**2 * M12_unit
        R = net_rotation(conn, loop, rtol=1e-13).R
        errors.append(np.max(np.abs(R - (np.eye(3) + hat(F12) * M12))))  # ½(F12 M12 + F21 M21) = F12 M12
    return np.array(errors)


def test_3_102_small_loop_remainder_is_third_order(conn):
    sizes = np.array([0.08, 0.04, 0.02, 0.01, 0.005])
    F = conn.field_strength(X0)
    order = np.polyfit(np.log(sizes), np.log(_small_loop_errors(conn, F[0, 1], sizes)), 1)[0]
    assert abs(order - 3) < 0.15, order
    d = conn.connection_derivatives(X0)
    printed = -(d[1, 0] - d[0, 1]) + (F[0, 1] - (d[1, 0] - d[0, 1]))  # (3.103) as printed: derivatives swapped
    order_printed = np.polyfit(np.log(sizes), np.log(_small_loop_errors(conn, printed, sizes)), 1)[0]
    assert abs(order_printed - 2) < 0.15, order_printed


def test_3_102_derivation_gives_the_standard_curvature():
    form = derivation.model().field_strength_form
    nc = {n: sp.Symbol(n, commutative=False) for n in ("Omega_1", "Omega_2", "dOmega_1_2", "dOmega_2_1")}
    want = nc["dOmega_2_1"] - nc["dOmega_1_2"] + nc["Omega_1"] * nc["Omega_2"] - nc["Omega_2"] * nc["Omega_1"]
    assert sp.expand(form[(1, 2)] - want) == 0


# ============================================================================ the falling cat


@pytest.fixture(scope="session")
def flip():
    return falling_cat(samples=61)


def test_cat_turns_over_by_pi_with_zero_angular_momentum(flip):
    assert abs(flip.flip_angle[-1] - np.pi) < 1e-8
    assert np.max(np.abs(flip.angular_momentum)) < 1e-10
    R = flip.R[-1]
    np.testing.assert_allclose(R, np.diag([1.0, -1.0, -1.0]), atol=1e-10)  # a half turn about the long axis e1
    np.testing.assert_allclose(flip.shapes[[0, -1]], [[0, 0], [0, -2 * np.pi]], atol=1e-12)  # straight → straight
    assert flip.error_estimate < 1e-11
    assert 0.5 < flip.peak_bend < 2.5


def test_cat_flip_matches_the_hand_reduced_integral(flip):
    """By symmetry Ω stays along e1: v₁ = ψ̇ (1 − I_a cos(β/2) / (I_a cos²(β/2) + I_t sin²(β/2))),
    with I_a = (2/3) m ρ², I_t = (1/3) m (ρ² + ℓ²) of each half (derived by hand from the halves' spins,
    the spun-representative gauge and (3.89)); its integral is the rotation angle."""
    p, beta0 = flip.parameters, mpmath.mpf(flip.peak_bend)
    Ia = mpmath.mpf(2) / 3 * p["half_mass"] * p["radius"] ** 2
    It = mpmath.mpf(p["half_mass"]) * (p["radius"] ** 2 + p["half_length"] ** 2) / 3

    def v1(t):
        beta, psidot = beta0 * mpmath.sin(mpmath.pi * t) ** 2, -2 * mpmath.pi * (1 - mpmath.cos(2 * mpmath.pi * t))
        c, s = mpmath.cos(beta / 2), mpmath.sin(beta / 2)
        return psidot * (1 - Ia * c / (Ia * c**2 + It * s**2))

    mid = len(flip.t) // 2
    with mpmath.workdps(25):  # Gauss–Legendre on an analytic integrand: exact to ~1e-25
        theta, theta_mid = (float(mpmath.quad(v1, [0, end])) for end in (1, mpmath.mpf(flip.t[mid])))
    np.testing.assert_allclose(flip.R[-1], expm_so3([theta, 0, 0]), atol=1e-11)
    np.testing.assert_allclose(flip.R[mid], expm_so3([theta_mid, 0, 0]), atol=1e-11)


def test_cat_flip_does_not_depend_on_the_duration(flip):
    slow = falling_cat({"peak_bend": flip.peak_bend}, duration=3.0, samples=5)
    np.testing.assert_allclose(slow.R[-1], flip.R[-1], atol=1e-11)
    assert np.max(np.abs(slow.angular_momentum)) < 1e-10


def test_falling_cat_motion_scene_series(flip):
    out = falling_cat_motion({"peak_bend": flip.peak_bend}, t_end=2.0, samples=31)
    names = {"t", "flip_angle", "shape_bend", "shape_swivel", "L1", "L2", "L3"} | {f"q{k}" for k in range(4)} \
        | {f"R{a}{b}" for a in (1, 2, 3) for b in (1, 2, 3)}
    assert set(out) == names and all(v.shape == (31,) for v in out.values())
    R31 = np.stack([[out[f"R{a}{b}"] for b in (1, 2, 3)] for a in (1, 2, 3)]).transpose(2, 0, 1)
    from mechderive.kinematics.conversions import quaternion_to_matrix

    q = np.stack([out[f"q{k}"] for k in range(4)], axis=-1)
    np.testing.assert_allclose(quaternion_to_matrix(q), R31, atol=1e-12)  # q is of the active R(3.7) = R(3.1)ᵀ
    assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0) and q[0, 0] == pytest.approx(1.0)  # continuous sign
    np.testing.assert_allclose(R31[-1], np.diag([1.0, -1.0, -1.0]), atol=1e-10)
    assert out["flip_angle"][0] == pytest.approx(0, abs=1e-14)
    assert abs(out["flip_angle"][-1] - np.pi) < 1e-8
    assert np.max(np.abs([out["L1"], out["L2"], out["L3"]])) < 1e-10
    assert out["shape_bend"].max() == pytest.approx(flip.peak_bend, rel=1e-3)


def test_cat_with_other_proportions_still_flips():
    res = falling_cat({"radius": 0.04, "half_length": 0.13, "half_mass": 1.5}, samples=11)
    assert abs(res.flip_angle[-1] - np.pi) < 1e-8 and np.max(np.abs(res.angular_momentum)) < 1e-10


def test_cat_compiled_and_magnus_backends_agree(flip):
    """DOP853 compiled to C on the derived Ṙ = RΩ and the Magnus steps on the compiled Ω_A: the same flip."""
    if flip.backend != "c":
        pytest.skip("no C compiler: only the Magnus backend runs")
    magnus = falling_cat(samples=61, backend="magnus")
    assert magnus.backend == "magnus"
    # both roots of sin θ(β₀) = 0 with θ to ~1e-14; dθ/dβ₀ ~ 3
    assert abs(magnus.peak_bend - flip.peak_bend) < 1e-12
    np.testing.assert_allclose(flip.R, magnus.R, atol=1e-12)
    np.testing.assert_allclose(flip.angular_momentum, magnus.angular_momentum, atol=1e-13)


def test_cat_without_a_c_compiler_uses_magnus_steps(flip):
    from mechderive.core import cbuild

    cbuild.set_c_enabled(False)
    try:
        with pytest.raises(IntegrationError, match=r"expected a C compiler for backend='c'"):
            falling_cat({"peak_bend": flip.peak_bend}, samples=3, backend="c")
        res = falling_cat({"peak_bend": flip.peak_bend}, samples=5)
        assert res.backend == "magnus" and abs(res.flip_angle[-1] - np.pi) < 1e-8
    finally:
        cbuild.set_c_enabled(None)
    with pytest.raises(InvalidInputError, match=r"expected backend one of 'auto', 'c', 'magnus', got 'rk4'"):
        falling_cat(samples=3, backend="rk4")


def test_second_falling_cat_run_derives_nothing_and_never_imports_sympy(tmp_path, capsys):
    """A warm scene run loads the cat's connection, loop and compiled stepper from the disk cache.

    The first run is this process's (its derivations are shared with the §3.7 tests and the catalog, and it
    writes the compiled functions to the suite's disk cache, if no earlier test did); the second is a fresh
    process on that cache.  (A fresh cold process would derive the cat again: ~7 s.)"""
    from mechderive.cli import main

    assert main(["run", "falling_cat", "-o", str(tmp_path / "first.csv"), "--json"]) == 0
    capsys.readouterr()
    code = ("import sys\nfrom mechderive.cli import main\n"
            f"main(['run', 'falling_cat', '-o', {str(tmp_path / 'warm.csv')!r}, '--json'])\n"
            "print('SYMPY', 'sympy' in sys.modules)\n")
    proc = run_python("-c", code)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.rstrip().endswith("SYMPY False")
    warm = json.loads(proc.stdout[: proc.stdout.rindex("SYMPY")])
    assert warm["derived"] == []
    names = {c.rsplit(" (", 1)[0] for c in warm["compiled"]}
    assert {"deformable.cat.connection", "deformable.cat.loop", "deformable.cat.positions"} <= names
    assert warm["compiled"] and all(c.endswith("(disk)") for c in warm["compiled"])
    a, b = (np.genfromtxt(tmp_path / f, delimiter=",", names=True) for f in ("first.csv", "warm.csv"))
    assert a.dtype.names == b.dtype.names and len(a) == 201
    for q in a.dtype.names:
        np.testing.assert_allclose(b[q], a[q], rtol=0, atol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("samples", [401, 2001])
def test_cat_angular_momentum_for_dense_sampling(samples):
    res = falling_cat(samples=samples)
    assert np.max(np.abs(res.angular_momentum)) < 1e-10


# ============================================================================ laziness


def test_asking_for_one_quantity_derives_nothing_unrelated():
    x, y = sp.symbols("x y", real=True)
    body = DeformableBody([1, 2, 3], centred_positions([1, 2, 3], [(1, x, 0), (0, 1, y), (x, 0, 1)]), [x, y])
    _ = body.inertia_tensor
    assert body.derived == ["reduced_positions", "inertia_tensor"]
    _ = body.connection
    assert "connection" in body.derived and not body.is_derived("field_strength")
    assert not body.is_derived("connection_derivatives")
    fresh = derivation.ConnectionDerivation()
    _ = fresh.apparent_angular_momentum
    assert not fresh.is_derived("angular_velocity_solution") and not fresh.is_derived("small_loop_second_order")
    assert not fresh.is_derived("epsilon_contracted_momentum")


# ============================================================================ bad input

x_, y_ = sp.symbols("x y", real=True)


@pytest.mark.parametrize("args, kwargs, error, match", [
    ((["1"], [(x_, 0, 0)], [x_]), {}, InvalidInputError, r"expected each mass to be a SymPy expression or a real number, got str"),
    (([1, 1], [(x_, 0), (-x_, 0, 0)], [x_]), {}, ShapeError, r"expected position 1 to have 3 components, got 2"),
    (([1, 1], [(x_, 0, 0)], [x_]), {}, ShapeError, r"expected as many positions as masses \(2\), got 1"),
    (([1, 1], [(x_, 0, 0), (-x_, 0, 0)], ["x"]), {}, InvalidInputError, r"expected shape coordinates to be SymPy symbols, got str"),
    (([1, 1], [(x_, y_, 0), (-x_, -y_, 0)], [x_]), {}, InvalidInputError, r"got undeclared symbols \['y'\]"),
    (([1, 1], [(x_, 0, 0), (x_, 0, 1)], [x_]), {}, InvalidInputError, r"expected the centre of mass at the origin"),
    (([-1, 1], [(x_, 0, 0), (x_, 0, 0)], [x_]), {}, InvalidInputError, r"expected mass 1 > 0, got -1"),
    (([1, 1], [(x_, 0, 0), (-x_, 0, 0)], []), {}, InvalidInputError, r"expected at least one of the shape coordinates, got none"),
    (([1, 1], [(x_, 0, 0), (-x_, 0, 0)], [x_]), {"parameters": [x_]}, InvalidInputError, r"expected parameters distinct"),
])
def test_bad_bodies_are_refused(args, kwargs, error, match):
    with pytest.raises(error, match=match):
        DeformableBody(*args, **kwargs)


def test_bad_numeric_parameters_and_gauges():
    a = sp.Symbol("a", positive=True)
    body = DeformableBody([1, 1, 1, 1], [(a, x_, 0), (-a, -x_, 0), (0, 0, 1), (0, 0, -1)], [x_], parameters=[a])
    with pytest.raises(InvalidInputError, match=r"unknown parameter 'b': expected one of a"):
        body.numeric({"b": 1.0})
    with pytest.raises(InvalidInputError, match=r"missing parameter 'a': expected values for all of a"):
        body.numeric({})
    with pytest.raises(InvalidInputError, match=r"expected S to be a rotation"):
        body.regauged(sp.diag(1, 1, 2))
    with pytest.raises(ShapeError, match=r"expected `x` to have shape \(\.\.\., 1\), got \(2,\)"):
        body.numeric({"a": 1.0}).connection([0.1, 0.2])


def test_singular_inertia_is_reported():
    line = DeformableBody([1, 1], [(1 + x_, 0, 0), (-1 - x_, 0, 0)], [x_])  # all masses on one line, always
    with pytest.raises(InvalidInputError, match=r"expected an inertia tensor Ĩ\(x\) invertible for generic shapes"):
        line.connection
    flat_at_zero = DeformableBody([1, 1, 1, 1], [(1, 0, x_), (-1, 0, -x_), (0, x_, 0), (0, -x_, 0)], [x_]).numeric()
    with pytest.raises(InvalidInputError, match=r"expected shapes with an invertible inertia tensor .* got det Ĩ = 0"):
        flat_at_zero.connection([0.0])  # at x = 0 all masses lie on the e1 axis


def test_singular_shapes_are_refused_also_where_cancelling_made_omega_finite():
    """At x = 0 all masses of this body lie on e1: L̃_1 ≡ 0, so the cancelled Ω_A has no 1/det Ĩ left and is finite
    there; the numeric connection checks Ĩ itself.  The three-mass body keeps det Ĩ as its denominator (no check
    needed where Ω_A is finite)."""
    body = DeformableBody([1, 1, 1, 1], [(1, 0, x_), (-1, 0, -x_), (0, x_, 0), (0, -x_, 0)], [x_])
    assert body.cancels_singular_factors  # before Ω is derived: assume so
    _ = body.connection_vectors
    assert body.cancels_singular_factors and body.connection_vectors[0, 0] == 0
    with pytest.raises(InvalidInputError, match=r"got det Ĩ = 0"):
        body.numeric().connection(np.array([[0.5], [0.0]]))
    assert body.numeric().connection([0.5]).shape == (1, 3)
    three = three_mass_body()
    _ = three.connection_vectors
    assert not three.cancels_singular_factors


def test_bad_loops_are_refused(conn):
    open_path = ShapeLoop.from_expressions([X0[0] + S, X0[1] + 0 * S], S, (0.0, 1.0))
    with pytest.raises(InvalidInputError, match=r"expected a closed loop in shape space .* got a mismatch of"):
        net_rotation(conn, open_path)
    assert rotation_along(conn, open_path).closure > 0.5  # an open path is fine for rotation_along
    with pytest.raises(InvalidInputError, match=r"expected at least 4 samples for a cubic spline, got 3"):
        net_rotation(conn, (np.arange(3.0), np.zeros((3, 2))))
    with pytest.raises(InvalidInputError, match=r"expected strictly increasing `times`"):
        net_rotation(conn, (np.array([0, 1, 1, 2.0]), np.zeros((4, 2))))
    with pytest.raises(ShapeError, match=r"expected a loop in 2 shape coordinates, got 1"):
        net_rotation(conn, ShapeLoop.from_expressions([sp.sin(S)], S, (0.0, 2 * np.pi)))
    with pytest.raises(InvalidInputError, match=r"expected a ShapeLoop or a \(times, shapes\) pair of arrays, got list"):
        net_rotation(conn, [1, 2])
    with pytest.raises(InvalidInputError, match=r"expected expressions of s only, got the symbols \['x'\]"):
        ShapeLoop.from_expressions([x_ * S], S, (0, 1))
    with pytest.raises(InvalidInputError, match=r"expected span \(t0, t1\) with t1 > t0, got \(1.0, 0.0\)"):
        ShapeLoop.from_expressions([S], S, (1, 0))


@pytest.mark.parametrize("params, kwargs, match", [
    ({"tail": 0.3}, {}, r"unknown parameter 'tail': expected one of half_mass, joint_offset, radius, half_length, peak_bend"),
    ({"radius": -0.1}, {}, r"expected `radius` finite and > 0, got -0.1"),
    ({"radius": "big"}, {}, r"expected `radius` to be a number, got 'big'"),
    ({"peak_bend": 3.5}, {}, r"expected `peak_bend` in \(0, π\)"),
    (None, {"t_end": 0.0, "samples": 5}, r"expected `duration` \(t_end\) finite and > 0, got 0.0"),
    (None, {"t_end": 1.0, "samples": 1}, r"expected `samples` to be an integer >= 2, got 1"),
])
def test_bad_cat_parameters_are_refused(params, kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        falling_cat_motion(params, **{"t_end": 1.0, "samples": 5, **kwargs})
