"""Section 3.2 (the inertia tensor) and 3.3's (3.29)–(3.30), checked from independent angles.

References: mpmath at 30 digits, scipy quadrature in other coordinates, finite
differences of R(φ, θ, ψ), and a standard table of moments of inertia (values
written here, sourced: Goldstein, Classical Mechanics, and Wikipedia's "List of
moments of inertia" — the same values appear in both).
"""

from __future__ import annotations

import runpy
import sys

import mpmath
import numpy as np
import pytest
import sympy as sp
from scipy import integrate
from scipy.spatial.transform import Rotation

from mechderive.catalog.registry import all_claims, run_claims
from mechderive.errors import InvalidInputError, NonFiniteValueError, ShapeError, UnphysicalInertiaError
from mechderive.inertia import (
    BODIES,
    BodyInertia,
    angular_momentum,
    body_inertia,
    body_inertia_symbolic,
    box,
    check_inertia_tensor,
    check_principal_moments,
    inertia_from_density,
    inertia_tensor,
    inertia_tensor_symbolic,
    kinetic_energy,
    parallel_axis,
    principal_axes,
    principal_axes_symbolic,
    solid_of_revolution,
)
from mechderive.inertia import bodies as bodies_module
from mechderive.inertia.density import density_model
from mechderive.inertia.free_body import free_body_model
from mechderive.inertia.parallel_axis_theorem import parallel_axis_model
from mechderive.inertia.regions import r as r_cyl
from mechderive.inertia.regions import x as x_sym
from mechderive.inertia.regions import z as z_sym
from mechderive.kinematics.euler import angular_velocity_body, rotation_matrix

from .conftest import ROOT

# Rounding: a handful of products and sums of O(1) doubles -> errors ~1e-15; 1e-12 leaves room, yet any
# formula error (a wrong coefficient is >= 1e-3 relative) fails.
RTOL = 1e-12


def _point_cloud(rng, n=7, batch=()):
    masses = rng.uniform(0.2, 2.0, size=batch + (n,))
    positions = rng.normal(size=batch + (n, 3))
    return masses, positions


def _mp_inertia(masses, positions):
    """(3.19) evaluated independently with mpmath at 30 digits."""
    with mpmath.workdps(30):
        I = mpmath.zeros(3, 3)
        for m, p in zip(masses, positions):
            p = [mpmath.mpf(float(v)) for v in p]
            r2 = sum(v * v for v in p)
            for a in range(3):
                for b in range(3):
                    I[a, b] += mpmath.mpf(float(m)) * ((r2 if a == b else 0) - p[a] * p[b])
        return np.array(I.tolist(), dtype=float)


# =====================================================================================================
# 3.2 — point masses: (3.17)–(3.19), (3.27)–(3.28)
# =====================================================================================================

class TestPointMasses:
    def test_3_19_tensor_matches_mpmath(self, rng):
        m, r = _point_cloud(rng)
        np.testing.assert_allclose(inertia_tensor(m, r), _mp_inertia(m, r), rtol=RTOL, atol=RTOL)

    def test_3_19_vectorised_over_a_batch(self, rng):
        m, r = _point_cloud(rng, batch=(4, 2))
        I = inertia_tensor(m, r)
        assert I.shape == (4, 2, 3, 3)
        np.testing.assert_allclose(I[3, 1], _mp_inertia(m[3, 1], r[3, 1]), rtol=RTOL, atol=RTOL)

    def test_3_19_symbolic_equals_numeric(self, rng):
        m, r = _point_cloud(rng, n=3)
        exact = inertia_tensor_symbolic([sp.Float(v, 30) for v in m], [[sp.Float(v, 30) for v in p] for p in r])
        np.testing.assert_allclose(np.array(exact, dtype=float), inertia_tensor(m, r), rtol=RTOL, atol=RTOL)

    def test_3_17_3_18_kinetic_energy_equals_sum_of_half_m_omega_cross_r_squared(self, rng):
        m, r = _point_cloud(rng)
        w = rng.normal(size=3)
        reference = 0.5 * np.sum(m * np.sum(np.cross(w, r) ** 2, axis=-1))  # ½ Σ m |ω × r|², by numpy.cross
        assert kinetic_energy(inertia_tensor(m, r), w) == pytest.approx(reference, rel=RTOL)

    def test_3_27_3_28_angular_momentum_equals_sum_of_r_cross_omega_cross_r(self, rng):
        m, r = _point_cloud(rng)
        w = rng.normal(size=3)
        reference = np.sum(m[:, None] * np.cross(r, np.cross(w, r)), axis=0)
        np.testing.assert_allclose(angular_momentum(inertia_tensor(m, r), w), reference, rtol=RTOL, atol=RTOL)

    def test_3_28_spin_and_angular_momentum_differ_in_direction(self):
        # unequal moments: L = Iω is not parallel to ω (the "peculiar" property noted after (3.28))
        I = body_inertia("cuboid", mass=1.0, a=1.0, b=2.0, c=3.0).inertia_cm
        w = np.array([1.0, 1.0, 1.0])
        L = angular_momentum(I, w)
        assert np.linalg.norm(np.cross(L, w)) > 0.1

    def test_rigid_velocity_is_omega_cross_r_in_body_components(self):
        # The derivation's input ṙ = ωᵀ r = ω × r, against finite differences of R(φ, θ, ψ) of (3.54):
        # ṙ̃ = Ṙᵀ r (space components) must equal Rᵀ (ω × r) with ω from (3.58).
        angles, rates = np.array([0.3, 1.1, -0.7]), np.array([0.9, -0.4, 1.3])
        r = np.array([0.2, -1.0, 0.5])
        h = 1e-5  # central difference: error ~ h² |R'''| ~ 1e-10, well under the 1e-8 tolerance
        Rdot = (rotation_matrix(*(angles + h * rates)) - rotation_matrix(*(angles - h * rates))) / (2 * h)
        R = rotation_matrix(*angles)
        w = angular_velocity_body(*angles, *rates)
        np.testing.assert_allclose(Rdot.T @ r, R.T @ np.cross(w, r), atol=1e-8)

    def test_model_derives_each_quantity_once(self):
        from mechderive.inertia.tensor import point_mass_model

        pm = point_mass_model(2)
        pm.angular_momentum
        pm.angular_momentum
        assert pm.derived.count("inertia_tensor") == 1 and pm.derived.count("angular_momentum") == 1


# =====================================================================================================
# 3.2 — continuous bodies (3.20), (3.23), (3.24), against a standard table
# =====================================================================================================

M, l, R, h, a, b, c = sp.symbols("M l R h a b c", positive=True)

# Standard table (Goldstein; Wikipedia "List of moments of inertia"): principal moments about the centre
# of mass, axis 3 the symmetry axis (rod: along axis 3; disc and ring: in the 1-2 plane).
TABLE = {
    "rod": (M * l**2 / 12, M * l**2 / 12, 0),
    "disc": (M * R**2 / 4, M * R**2 / 4, M * R**2 / 2),
    "ring": (M * R**2 / 2, M * R**2 / 2, M * R**2),
    "solid_sphere": (2 * M * R**2 / 5,) * 3,
    "hollow_sphere": (2 * M * R**2 / 3,) * 3,
    "solid_cylinder": (M * (3 * R**2 + h**2) / 12, M * (3 * R**2 + h**2) / 12, M * R**2 / 2),
    "cuboid": (M * (b**2 + c**2) / 12, M * (a**2 + c**2) / 12, M * (a**2 + b**2) / 12),
    "solid_ellipsoid": (M * (b**2 + c**2) / 5, M * (a**2 + c**2) / 5, M * (a**2 + b**2) / 5),
    "solid_cone": (3 * M * R**2 / 20 + 3 * M * h**2 / 80, 3 * M * R**2 / 20 + 3 * M * h**2 / 80,
                   3 * M * R**2 / 10),
}
# Solid cone (same sources): centre of mass 3h/4 from the apex; about the apex I1 = I2 = 3/5 M h² + 3/20 M R².
CONE_APEX = (3 * M * h**2 / 5 + 3 * M * R**2 / 20, 3 * M * h**2 / 5 + 3 * M * R**2 / 20, 3 * M * R**2 / 10)
DIMS = {"rod": {"length": l}, "disc": {"radius": R}, "ring": {"radius": R}, "solid_sphere": {"radius": R},
        "hollow_sphere": {"radius": R}, "solid_cylinder": {"radius": R, "height": h},
        "cuboid": {"a": a, "b": b, "c": c}, "solid_ellipsoid": {"a": a, "b": b, "c": c},
        "solid_cone": {"radius": R, "height": h}}
NUMBERS = {M: 2.5, l: 1.7, R: 0.6, h: 1.3, a: 0.5, b: 0.9, c: 1.4}


class TestBodies:
    def test_table_covers_every_body(self):
        assert set(TABLE) == set(BODIES)

    @pytest.mark.parametrize("name", sorted(TABLE))
    def test_symbolic_inertia_equals_table(self, name):
        body = body_inertia_symbolic(name)
        # the module's symbols have the same names and assumptions as the table's, so they are the same symbols
        assert sp.simplify(body.inertia_cm - sp.diag(*TABLE[name])) == sp.zeros(3, 3)
        assert body.mass == M

    @pytest.mark.parametrize("name", sorted(TABLE))
    def test_numeric_inertia_equals_table(self, name):
        dims = {k: NUMBERS[s] for k, s in DIMS[name].items()}
        body = body_inertia(name, mass=NUMBERS[M], **dims)
        expected = np.diag([float(sp.sympify(v).subs(NUMBERS)) for v in TABLE[name]])
        np.testing.assert_allclose(body.inertia_cm, expected, rtol=RTOL, atol=RTOL)

    def test_centres_of_mass(self):
        for name in BODIES:
            expected = sp.Matrix([0, 0, 3 * h / 4]) if name == "solid_cone" else sp.zeros(3, 1)
            assert body_inertia_symbolic(name).centre_of_mass == expected, name

    def test_cone_about_apex_equals_table_and_direct_integral(self):
        cone = body_inertia_symbolic("solid_cone")
        about_apex = cone.inertia_about((0, 0, 0))  # by the parallel axis theorem (3.25)
        assert sp.simplify(about_apex - sp.diag(*CONE_APEX)) == sp.zeros(3, 3)
        model = bodies_module.body_model("solid_cone")  # integrated directly about the apex, no theorem
        direct = model.inertia_origin.subs(bodies_module.rho, model.uniform_density)
        assert sp.simplify(direct - sp.diag(*CONE_APEX)) == sp.zeros(3, 3)

    def test_cone_about_apex_against_scipy_quadrature(self):
        # Independent: Cartesian tplquad, no Jacobian, no SymPy. quad's default tolerance ~1.5e-8 -> rtol 1e-7.
        Rn, hn, Mn = 0.6, 1.3, 2.5
        rho = Mn / (np.pi * Rn**2 * hn / 3)

        def cone_integral(f):
            val, _ = integrate.tplquad(lambda yy, xx, zz: rho * f(xx, yy, zz), 0, hn,
                                       lambda zz: -Rn * zz / hn, lambda zz: Rn * zz / hn,
                                       lambda zz, xx: -np.sqrt(max((Rn * zz / hn) ** 2 - xx**2, 0.0)),
                                       lambda zz, xx: np.sqrt(max((Rn * zz / hn) ** 2 - xx**2, 0.0)))
            return val

        I11 = cone_integral(lambda xx, yy, zz: yy**2 + zz**2)
        I33 = cone_integral(lambda xx, yy, zz: xx**2 + yy**2)
        numeric = body_inertia("solid_cone", mass=Mn, radius=Rn, height=hn).inertia_about([0.0, 0.0, 0.0])
        np.testing.assert_allclose([numeric[0, 0], numeric[2, 2]], [I11, I33], rtol=1e-7)

    def test_numeric_bodies_broadcast(self):
        body = body_inertia("solid_cylinder", mass=np.array([1.0, 2.0]), radius=0.5, height=np.array([[1.0], [2.0]]))
        assert body.inertia_cm.shape == (2, 2, 3, 3) and body.centre_of_mass.shape == (2, 2, 3)
        np.testing.assert_allclose(body.inertia_cm[1, 0, 2, 2], 0.5 * 1.0 * 0.25, rtol=RTOL)

    def test_each_body_is_integrated_once(self):
        model = bodies_module.body_model("ring")
        body_inertia_symbolic("ring")
        body_inertia("ring", mass=1.0, radius=2.0)
        body_inertia("ring", mass=3.0, radius=1.0)
        assert bodies_module.body_model("ring") is model
        assert model.derived.count("inertia_origin") == 1 and model.derived.count("mass") == 1
        assert model.compiled.count("ring_inertia_cm") == 1

    def test_3_24_disc_jacobian_is_derived(self):
        assert bodies_module.body_model("disc").measure == sp.Symbol("r", positive=True)
        sphere = bodies_module.body_model("solid_sphere").measure
        assert sp.simplify(sphere - sp.Symbol("r", positive=True) ** 2 * sp.sin(sp.Symbol("vartheta", real=True))) == 0


class TestUserDensity:
    def test_density_on_a_box_against_scipy(self):
        density = lambda x, y, z: 1 + x + y**2 * z + 0.5 * z  # noqa: E731 - positive on the box below
        body = inertia_from_density(lambda x, y, z: 1 + x + y**2 * z + sp.Rational(1, 2) * z,
                                    box((0, 1), (0, 2), (-1, 1))).as_numeric()

        def q(f):  # nquad default tolerance ~1.5e-8 -> compare at rtol 1e-7
            return integrate.nquad(lambda x, y, z: density(x, y, z) * f(x, y, z), [(0, 1), (0, 2), (-1, 1)])[0]

        mass = q(lambda x, y, z: 1.0)
        com = np.array([q(lambda x, y, z, k=k: (x, y, z)[k]) for k in range(3)]) / mass
        I_O12 = q(lambda x, y, z: -x * y)
        I_O33 = q(lambda x, y, z: x**2 + y**2)
        assert body.mass == pytest.approx(mass, rel=1e-7)
        np.testing.assert_allclose(body.centre_of_mass, com, rtol=1e-7)
        I_O = body.inertia_about([0.0, 0.0, 0.0])
        np.testing.assert_allclose([I_O[0, 1], I_O[2, 2]], [I_O12, I_O33], rtol=1e-7)

    def test_density_on_a_solid_of_revolution_against_cartesian_quadrature(self):
        # ρ(r, z) = 1 + r² z inside r <= 1 - z/2, 0 <= z <= 1; scipy integrates it in Cartesian coordinates.
        body = inertia_from_density(1 + r_cyl**2 * z_sym, solid_of_revolution(1 - z_sym / 2, (0, 1))).as_numeric()

        def q(f):
            Rz = lambda zz: 1 - zz / 2  # noqa: E731
            return integrate.tplquad(
                lambda yy, xx, zz: (1 + (xx**2 + yy**2) * zz) * f(xx, yy, zz), 0, 1,
                lambda zz: -Rz(zz), lambda zz: Rz(zz),
                lambda zz, xx: -np.sqrt(max(Rz(zz) ** 2 - xx**2, 0.0)),
                lambda zz, xx: np.sqrt(max(Rz(zz) ** 2 - xx**2, 0.0)))[0]

        mass = q(lambda xx, yy, zz: 1.0)
        zc = q(lambda xx, yy, zz: zz) / mass
        I_O11 = q(lambda xx, yy, zz: yy**2 + zz**2)
        assert body.mass == pytest.approx(mass, rel=1e-7)
        np.testing.assert_allclose(body.centre_of_mass, [0.0, 0.0, zc], rtol=1e-7, atol=1e-12)
        assert body.inertia_about([0.0, 0.0, 0.0])[0, 0] == pytest.approx(I_O11, rel=1e-7)

    def test_symbolic_density_parameters_stay_symbols(self):
        k = sp.Symbol("k", positive=True)
        body = inertia_from_density(k * x_sym, box((0, 1), (0, 1), (0, 1)))
        assert body.mass == k / 2 and body.centre_of_mass[0] == sp.Rational(2, 3)

    def test_same_density_is_integrated_once(self):
        region = box((0, 1), (0, 3), (0, 1))
        inertia_from_density(1 + x_sym**2, region)
        inertia_from_density(1 + x_sym**2, region)
        assert density_model(sp.sympify(1 + x_sym**2), region).derived.count("inertia_origin") == 1


# =====================================================================================================
# 3.2 — principal axes (3.21)
# =====================================================================================================

def _physical_moments(rng, n):
    # moments of random point clouds: physical by construction (positive, triangle inequalities)
    m, r = _point_cloud(rng, batch=(n,))
    return np.linalg.eigvalsh(inertia_tensor(m, r))


class TestPrincipalAxes:
    def test_random_rotated_tensors(self, rng):
        moments = _physical_moments(rng, 20)
        O_true = Rotation.random(20, random_state=12345).as_matrix()
        I = np.einsum("nji,nj,njk->nik", O_true, moments, O_true)  # Oᵀ diag O
        got, O = principal_axes(I)
        scale = moments.max()
        np.testing.assert_allclose(got, moments, rtol=RTOL, atol=RTOL * scale)
        np.testing.assert_allclose(O @ I @ np.swapaxes(O, -1, -2), np.eye(3) * got[:, None, :],
                                   atol=RTOL * scale * 10)
        np.testing.assert_allclose(np.linalg.det(O), 1.0, rtol=RTOL)

    def test_moments_match_mpmath_eigensolver(self, rng):
        m, r = _point_cloud(rng)
        I = inertia_tensor(m, r)
        with mpmath.workdps(30):
            ev, _ = mpmath.eigsy(mpmath.matrix(I.tolist()))
            reference = sorted(float(v) for v in ev)
        np.testing.assert_allclose(principal_axes(I)[0], reference, rtol=RTOL)

    @pytest.mark.parametrize("diag", [(1.0, 1.0, 2.0), (2.0, 3.0, 3.0), (2.0, 2.0, 2.0)])
    def test_repeated_moments_give_a_proper_orthonormal_basis(self, diag):
        Q = Rotation.from_euler("zxz", [0.4, 1.0, -0.3]).as_matrix()
        I = Q.T @ np.diag(diag) @ Q
        moments, O = principal_axes(I)
        np.testing.assert_allclose(moments, sorted(diag), rtol=RTOL)
        np.testing.assert_allclose(O @ O.T, np.eye(3), atol=RTOL)
        assert np.linalg.det(O) == pytest.approx(1.0, rel=RTOL)
        np.testing.assert_allclose(O @ I @ O.T, np.diag(sorted(diag)), atol=10 * RTOL)

    def test_rows_are_the_text_R_of_a_principal_body_frame(self):
        # If Ĩ = Rᵀ diag R for the R of (3.54) (rows of R = body axes), the returned rows are ± R's rows.
        R = rotation_matrix(0.3, 1.2, -0.5)
        I = R.T @ np.diag([1.0, 2.0, 2.5]) @ R
        _, O = principal_axes(I)
        np.testing.assert_allclose(np.abs(O @ R.T), np.eye(3), atol=1e-12)

    def test_line_body(self):
        rod = body_inertia("rod", mass=1.0, length=1.0).inertia_cm
        moments, _ = principal_axes(rod, line_body=True)
        np.testing.assert_allclose(moments, [0.0, 1 / 12, 1 / 12], atol=RTOL)

    def test_symbolic_block_and_diagonal(self):
        A, B, C = sp.symbols("A B C", positive=True)
        for I in (sp.diag(A, A, C), sp.Matrix([[A, B, 0], [B, A, 0], [0, 0, C]])):
            moments, O = principal_axes_symbolic(I)
            assert sp.simplify(O * I * O.T - sp.diag(*moments)) == sp.zeros(3, 3)
            assert sp.simplify(O.det()) == 1


# =====================================================================================================
# 3.2 — validation: symmetric, positive (3.22), triangle inequalities
# =====================================================================================================

class TestValidation:
    def test_triangle_inequality_message(self):
        with pytest.raises(UnphysicalInertiaError,
                           match=r"^expected I1 \+ I2 >= I3 \(triangle inequality\), got I1 \+ I2 = 1.5 < I3 = 3$"):
            check_principal_moments(1.0, 0.5, 3.0)

    def test_triangle_inequality_cyclic(self):
        with pytest.raises(UnphysicalInertiaError, match=r"expected I2 \+ I3 >= I1 .* got I2 \+ I3 = 2 < I1 = 3"):
            check_principal_moments(3.0, 1.0, 1.0)

    def test_negative_moment(self):
        with pytest.raises(UnphysicalInertiaError, match=r"^expected principal moments > 0 \(3.22\), got I2 = -1$"):
            check_principal_moments(2.0, -1.0, 2.0)

    def test_zero_moment_needs_line_body(self):
        with pytest.raises(UnphysicalInertiaError,
                           match=r"got I3 = 0; a zero moment is allowed only for a line body \(line_body=True\)"):
            check_principal_moments(1.0, 1.0, 0.0)
        np.testing.assert_array_equal(check_principal_moments(1.0, 1.0, 0.0, line_body=True), [1.0, 1.0, 0.0])

    def test_line_body_still_needs_equal_other_moments(self):
        with pytest.raises(UnphysicalInertiaError, match=r"expected I3 \+ I1 >= I2 .* got I3 \+ I1 = 1 < I2 = 2"):
            check_principal_moments(1.0, 2.0, 0.0, line_body=True)
        with pytest.raises(UnphysicalInertiaError, match=r"^expected principal moments >= 0 \(3.22\), got I1 = -1$"):
            check_principal_moments(-1.0, 1.0, 1.0, line_body=True)

    def test_plane_body_passes_within_rounding(self):
        Q = Rotation.from_euler("xyz", [0.3, 0.2, 1.1]).as_matrix()
        disc = Q.T @ np.diag([0.1, 0.2, 0.3]) @ Q  # I1 + I2 = I3 exactly, up to rounding
        check_inertia_tensor(disc)

    def test_asymmetric_tensor(self):
        with pytest.raises(UnphysicalInertiaError,
                           match=r"^expected a symmetric inertia tensor \(I_ab = I_ba\), got I_12 = 1 but I_21 = 0$"):
            check_inertia_tensor([[2.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]])

    def test_unphysical_tensor(self):
        with pytest.raises(UnphysicalInertiaError, match=r"triangle inequality"):
            check_inertia_tensor(np.diag([1.0, 1.0, 5.0]))

    def test_non_finite_and_shape(self):
        with pytest.raises(NonFiniteValueError, match=r"expected `inertia` to be finite, got nan"):
            check_inertia_tensor([[np.nan, 0, 0], [0, 1, 0], [0, 0, 1]])
        with pytest.raises(ShapeError,
                           match=r"expected `inertia` to have shape \(3, 3\) or \(\.\.\., 3, 3\), got \(2, 2\)"):
            check_inertia_tensor(np.eye(2))

    def test_kinetic_energy_refuses_unphysical_tensor(self):
        with pytest.raises(UnphysicalInertiaError, match=r"expected I1 \+ I2 >= I3"):
            kinetic_energy(np.diag([1.0, 1.0, 5.0]), [1.0, 0.0, 0.0])
        with pytest.raises(ShapeError, match=r"expected `omega` to have shape \(\.\.\., 3\), got \(2,\)"):
            kinetic_energy(np.eye(3), [1.0, 0.0])

    def test_point_mass_input(self):
        with pytest.raises(InvalidInputError, match=r"^expected masses >= 0, got -1.0$"):
            inertia_tensor([1.0, -1.0], [[1, 0, 0], [0, 1, 0]])
        with pytest.raises(ShapeError, match=r"expected `masses` of shape \(\.\.\., N\) and `positions` of shape "
                                             r"\(\.\.\., N, 3\), got \(2,\) and \(3, 3\)"):
            inertia_tensor([1.0, 1.0], np.zeros((3, 3)))

    def test_body_input(self):
        with pytest.raises(InvalidInputError, match=r"expected a body name among 'rod', .*, got 'cube'"):
            body_inertia("cube", mass=1.0, a=1.0)
        with pytest.raises(InvalidInputError, match=r"^expected dimensions \(radius, height\) for 'solid_cone', "
                                                    r"got \(radius\)$"):
            body_inertia("solid_cone", mass=1.0, radius=1.0)
        with pytest.raises(InvalidInputError, match=r"^expected `radius` > 0, got -2.0$"):
            body_inertia("disc", mass=1.0, radius=-2.0)
        with pytest.raises(InvalidInputError, match=r"^expected `mass` > 0, got 0.0$"):
            BodyInertia(0.0, [0, 0, 0], np.eye(3))
        with pytest.raises(UnphysicalInertiaError, match=r"a zero moment is allowed only for a line body"):
            BodyInertia(1.0, [0, 0, 0], np.diag([1.0, 1.0, 0.0]))  # a rod, but line_body not set

    def test_region_and_density_input(self):
        with pytest.raises(InvalidInputError, match=r"^expected lower < upper limit for x, got 1 and 0$"):
            box((1, 0), (0, 1), (0, 1))
        with pytest.raises(InvalidInputError, match=r"expected `x_range` as a pair \(lower, upper\), got 3"):
            box(3, (0, 1), (0, 1))
        with pytest.raises(InvalidInputError, match=r"expected the density in the region's coordinates"):
            inertia_from_density(sp.Symbol("x") + 1, box((0, 1), (0, 1), (0, 1)))
        with pytest.raises(InvalidInputError, match=r"^expected no free symbols to make numbers, got M, R$"):
            body_inertia_symbolic("disc").as_numeric()

    def test_parallel_axis_input(self):
        with pytest.raises(InvalidInputError, match=r"^expected `mass` > 0, got -1.0$"):
            parallel_axis(np.eye(3), -1.0, [0, 0, 1])
        with pytest.raises(ShapeError, match=r"^expected `c` to have shape \(\.\.\., 3\), got \(2,\)$"):
            parallel_axis(np.eye(3), 1.0, [0, 1])


# =====================================================================================================
# 3.2.1 — parallel axis theorem (3.25)–(3.26)
# =====================================================================================================

class TestParallelAxis:
    def test_3_25_against_direct_sum(self, rng):
        m, r = _point_cloud(rng, n=9)
        r_cm = r - (m[:, None] * r).sum(axis=0) / m.sum()
        c = rng.normal(size=3)
        direct = inertia_tensor(m, r_cm - c)  # (3.19) about the displaced point, no theorem
        np.testing.assert_allclose(parallel_axis(inertia_tensor(m, r_cm), m.sum(), c), direct,
                                   rtol=RTOL, atol=RTOL * np.abs(direct).max())

    def test_3_25_needs_the_centre_of_mass(self, rng):
        m, r = _point_cloud(rng, n=9)
        r_off = r - (m[:, None] * r).sum(axis=0) / m.sum() + np.array([0.5, 0.0, 0.0])  # not about the c.o.m.
        c = np.array([0.0, 1.0, 0.0])
        assert not np.allclose(parallel_axis(inertia_tensor(m, r_off), m.sum(), c), inertia_tensor(m, r_off - c))

    def test_3_26_symbolic_linear_terms_vanish(self):
        model = parallel_axis_model(3)
        assert any(e != 0 for e in model.linear_terms)
        assert model.linear_terms_at_centre_of_mass == sp.zeros(3, 3)

    def test_rod_about_its_end(self):
        rod = body_inertia("rod", mass=3.0, length=2.0)
        np.testing.assert_allclose(rod.inertia_about([0.0, 0.0, 1.0]), np.diag([4.0, 4.0, 0.0]), rtol=RTOL)  # ⅓Ml²

    def test_disc_displaced(self):
        disc = body_inertia("disc", mass=2.0, radius=1.0)
        cx = 0.7
        expected = 2.0 * np.diag([0.25, 0.25 + cx**2, 0.5 + cx**2])  # the chapter's example (3.2.1)
        np.testing.assert_allclose(disc.inertia_about([cx, 0.0, 0.0]), expected, rtol=RTOL)

    def test_vectorised(self, rng):
        I = np.broadcast_to(np.eye(3), (5, 3, 3))
        c = rng.normal(size=(5, 3))
        out = parallel_axis(I, np.ones(5), c)
        np.testing.assert_allclose(out[2], np.eye(3) + c[2] @ c[2] * np.eye(3) - np.outer(c[2], c[2]), rtol=RTOL)


# =====================================================================================================
# 3.3 — a free body: centre-of-mass motion + rotation (3.29)–(3.30)
# =====================================================================================================

class TestFreeBody:
    def test_3_30_separation_symbolic(self):
        fb = free_body_model(3)
        assert fb.cross_term != 0 and fb.cross_term_at_cm == 0
        assert sp.simplify(fb.translational_energy - fb.M * fb.V.dot(fb.V) / 2) == 0

    def test_3_30_against_finite_differences(self, rng):
        # r̃_i(t) = X(t) + R(t)ᵀ Δr_i, with R(t) = R(φ(t), θ(t), ψ(t)); T = ½Σm|ṙ̃|² by central differences
        m, r = _point_cloud(rng, n=5)
        dr = r - (m[:, None] * r).sum(axis=0) / m.sum()
        angles0, rates = np.array([0.4, 0.9, -1.2]), np.array([0.7, -0.3, 1.1])
        X = lambda t: np.array([1.0 + 0.3 * t, -0.2 * t**2, np.sin(t)])  # noqa: E731 - centre-of-mass path
        pos = lambda t: X(t) + dr @ rotation_matrix(*(angles0 + rates * t))  # noqa: E731 - rows: Rᵀ Δr_i
        hh = 1e-5  # error ~ hh² ~ 1e-10
        v = (pos(hh) - pos(-hh)) / (2 * hh)
        T_direct = 0.5 * np.sum(m * np.sum(v**2, axis=-1))
        V = (X(hh) - X(-hh)) / (2 * hh)
        w = angular_velocity_body(*angles0, *rates)
        T_split = 0.5 * m.sum() * V @ V + kinetic_energy(inertia_tensor(m, dr), w)
        assert T_split == pytest.approx(T_direct, rel=1e-8)


# =====================================================================================================
# The catalog (3.17)–(3.30) and the derivation script
# =====================================================================================================

# this file's claims: registered by the two modules below (other modules may add 3.3.x claims)
MY_CLAIMS = [c for c in all_claims("3.2") + all_claims("3.3")
             if c.check.__module__ in ("mechderive.catalog.s3_2_inertia", "mechderive.catalog.s3_3_rigid_motion")]


class TestCatalog:
    def test_every_claim_is_verified(self, claims_checked_once):
        results = run_claims(claims=MY_CLAIMS)
        assert {r.equation for r in results} >= {"3.17", "3.18", "3.19", "3.20", "3.21", "3.22", "3.23", "3.24",
                                                   "3.25", "3.26", "3.27", "3.28", "3.30"}
        bad = [(r.equation, r.detail) for r in results if r.status != "verified"]
        assert not bad

    # that each printed part matters (perturbed, the check fails) is test_catalog's
    # test_check_fails_when_a_member_is_perturbed, member by member, for these claims as for every other


def test_derivation_script_runs_with_latex(monkeypatch, capsys, claims_checked_once):
    # in-process, as tests/test_package.py runs every script (sharing this session's derivations)
    monkeypatch.setattr(sys, "argv", ["derivations/s3_2_inertia.py", "--latex"])
    runpy.run_path(str(ROOT / "derivations" / "s3_2_inertia.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "\\begin{equation}" in out and "(3.30) verified" in out
