"""Section 3.1 and 3.5: rotations, Euler angles, angular velocity, conversions.

References are independent of the code under test: SciPy's Rotation, scipy.linalg.expm,
and mpmath numerical differentiation of R(t) at 30 digits.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import scipy.linalg
from scipy.spatial.transform import Rotation

from mechderive.errors import InvalidInputError, NonFiniteValueError, NotARotationError, ShapeError
from mechderive.kinematics import conversions as conv
from mechderive.kinematics import euler
from mechderive.kinematics.so3 import expm_so3, hat, logm_so3, vee


# --- (3.51)-(3.54): R(φ, θ, ψ) ------------------------------------------------------------

def test_3_54_matches_scipy_intrinsic_ZXZ_transposed(rng):
    # SciPy's intrinsic "ZXZ" is Rz(φ)Rx(θ)Rz(ψ) (active) = R3(φ)ᵀR1(θ)ᵀR3(ψ)ᵀ = R(φ,θ,ψ)ᵀ.
    angles = rng.uniform([-np.pi, 0, -np.pi], [np.pi, np.pi, np.pi], size=(500, 3))
    R = euler.rotation_matrix(angles[:, 0], angles[:, 1], angles[:, 2])
    A = Rotation.from_euler("ZXZ", angles).as_matrix()
    assert R.shape == (500, 3, 3)
    np.testing.assert_allclose(R, np.swapaxes(A, 1, 2), atol=2e-15)  # rounding of a few products


def test_3_54_rows_are_body_axes_orthonormal_det_one(rng):
    angles = rng.uniform(-4, 4, size=(200, 3))
    R = euler.rotation_matrix(*angles.T)
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)


def test_3_51_3_52_axis_rotations_are_exponentials_of_generators():
    for axis, gen in ((1, np.array([[0, 0, 0], [0, 0, 1], [0, -1, 0.0]])),
                      (3, np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 0.0]]))):
        for a in (0.3, -2.0, 3.1):
            got = np.array(euler.axis_rotation(axis, a), dtype=float)
            np.testing.assert_allclose(got, scipy.linalg.expm(a * gen), atol=1e-15)


def test_euler_angles_round_trip_including_gimbal_lock(rng):
    angles = rng.uniform([-3, 1e-7, -3], [3, np.pi - 1e-7, 3], size=(300, 3))
    back = euler.euler_angles_from_matrix(euler.rotation_matrix(*angles.T))
    np.testing.assert_allclose(euler.rotation_matrix(*back.T), euler.rotation_matrix(*angles.T), atol=1e-14)
    np.testing.assert_allclose(back[:, 1], angles[:, 1], rtol=1e-8, atol=1e-15)
    # At θ = 0 only φ + ψ is defined: ψ = 0 is chosen and φ carries the sum.
    lock = euler.euler_angles_from_matrix(euler.rotation_matrix(0.4, 0.0, 0.5))
    np.testing.assert_allclose(lock, [0.9, 0.0, 0.0], atol=1e-15)
    lock_pi = euler.euler_angles_from_matrix(euler.rotation_matrix(0.4, np.pi, 0.0))
    np.testing.assert_allclose(euler.rotation_matrix(*lock_pi), euler.rotation_matrix(0.4, np.pi, 0.0), atol=1e-15)


def test_theta_recovered_to_full_relative_accuracy_near_zero():
    # arccos(R33) would lose half the digits at θ = 1e-9; atan2(sin θ, cos θ) does not.
    for th in (1e-9, 1e-5, np.pi - 1e-9):
        back = euler.euler_angles_from_matrix(euler.rotation_matrix(0.2, th, -0.7))
        assert back[1] == pytest.approx(th, rel=1e-7, abs=0)


# --- (3.5)-(3.6), (3.58): angular velocity -----------------------------------------------------

def _mp_rotation(phi, theta, psi):
    c, s = mpmath.cos, mpmath.sin
    R3 = lambda a: mpmath.matrix([[c(a), s(a), 0], [-s(a), c(a), 0], [0, 0, 1]])
    R1 = lambda a: mpmath.matrix([[1, 0, 0], [0, c(a), s(a)], [0, -s(a), c(a)]])
    return R3(psi) * R1(theta) * R3(phi)


def test_3_58_body_angular_velocity_against_mpmath_derivative_of_R():
    # Reference: ω = Ṙ Rᵀ with Ṙ by mpmath.diff at 30 digits along a straight line in angle space.
    mpmath.mp.dps = 30
    q0 = [mpmath.mpf("0.7"), mpmath.mpf("1.1"), mpmath.mpf("-0.4")]
    qd = [mpmath.mpf("0.3"), mpmath.mpf("-1.2"), mpmath.mpf("2.5")]
    path = lambda s: _mp_rotation(*(q + s * d for q, d in zip(q0, qd)))
    Rdot = mpmath.matrix(3, 3)
    for i in range(3):
        for j in range(3):
            Rdot[i, j] = mpmath.diff(lambda s: path(s)[i, j], 0)
    W = Rdot * path(0).T
    ref_body = np.array([float(W[1, 2]), float(W[2, 0]), float(W[0, 1])])
    got = euler.angular_velocity_body(*[float(x) for x in q0 + qd])
    np.testing.assert_allclose(got, ref_body, rtol=0, atol=1e-15)
    # Space components: Rᵀ ω
    ref_space = np.array(path(0).T.tolist(), dtype=float) @ ref_body
    np.testing.assert_allclose(euler.angular_velocity_space(*[float(x) for x in q0 + qd]), ref_space, atol=1e-15)


def test_angular_velocity_vectorised_shapes(rng):
    q = rng.normal(size=(6, 7))
    assert euler.angular_velocity_body(*q).shape == (7, 3)
    assert euler.angular_velocity_body(0.1, 0.2, 0.3, 0.0, 0.0, 1.0).shape == (3,)


# --- so(3) in the chapter's convention --------------------------------------------------------

def test_hat_is_the_chapter_convention_and_vee_inverts_it(rng):
    w = rng.normal(size=(50, 3))
    W = hat(w)
    # ω_ab = ε_abc ω_c
    eps = np.zeros((3, 3, 3))
    eps[0, 1, 2] = eps[1, 2, 0] = eps[2, 0, 1] = 1
    eps[0, 2, 1] = eps[2, 1, 0] = eps[1, 0, 2] = -1
    np.testing.assert_allclose(W, np.einsum("abc,nc->nab", eps, w), atol=0)
    np.testing.assert_allclose(vee(W), w, atol=0)


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 0.5, 3.0, np.pi - 1e-9])
def test_expm_so3_against_scipy_expm_and_log_inverts(rng, scale):
    for _ in range(20):
        n = rng.normal(size=3)
        w = scale * n / np.linalg.norm(n)
        E = expm_so3(w)
        np.testing.assert_allclose(E, scipy.linalg.expm(hat(w)), atol=2e-15)
        np.testing.assert_allclose(logm_so3(E), w, rtol=1e-8, atol=1e-15)


# --- conversions (documented in kinematics/conversions.py) -------------------------------------

def test_scipy_round_trip_and_documented_relation(rng):
    angles = rng.uniform(-3, 3, size=(100, 3))
    R = euler.rotation_matrix(*angles.T)
    rot = conv.to_scipy_rotation(R)
    np.testing.assert_allclose(rot.as_matrix(), np.swapaxes(R, 1, 2), atol=1e-15)
    np.testing.assert_allclose(conv.from_scipy_rotation(rot), R, atol=1e-15)
    # The body axis e3 (row 3 of R) is where the active rotation sends ẽ3.
    np.testing.assert_allclose(rot.apply([0, 0, 1.0]), R[:, 2, :], atol=1e-15)


@pytest.mark.parametrize("theta", [0.0, 1e-12, 1e-6, 0.4, np.pi / 2, np.pi - 1e-9, np.pi])
def test_quaternion_round_trips_including_near_theta_zero(rng, theta):
    phi, psi = rng.uniform(-3, 3, size=2)
    q = conv.euler_to_quaternion(phi, theta, psi)
    R = euler.rotation_matrix(phi, theta, psi)
    np.testing.assert_allclose(conv.quaternion_to_matrix(q), R, atol=2e-16 * 8)
    q_back = conv.matrix_to_quaternion(R)
    q_ref = q if q[0] >= 0 else -q
    np.testing.assert_allclose(q_back, q_ref, atol=4e-16 * 8)
    # SciPy agrees (scalar last there)
    np.testing.assert_allclose(Rotation.from_quat(np.roll(q, -1)).as_matrix(), R.T, atol=1e-15)


def test_quaternion_at_half_turns():
    # 180° rotations are where naive trace-based extraction divides by ~0.
    for axis in np.eye(3):
        A = Rotation.from_rotvec(np.pi * axis).as_matrix()
        q = conv.matrix_to_quaternion(A.T)
        np.testing.assert_allclose(np.abs(q[1:]), np.abs(axis), atol=1e-15)


# --- bad input ---------------------------------------------------------------------------------

def test_rotation_matrix_refuses_nonfinite_angles():
    with pytest.raises(NonFiniteValueError, match="expected `theta` to be finite, got nan"):
        euler.rotation_matrix(0.0, np.nan, 0.0)


def test_non_orthogonal_and_improper_matrices_refused():
    with pytest.raises(NotARotationError, match=r"expected `R` orthogonal .*got max \|RᵀR - 1\| = 0.21"):
        euler.euler_angles_from_matrix(np.diag([1.1, 1, 1]))
    with pytest.raises(NotARotationError, match=r"expected `R` to have det \+1.*got det = -1"):
        conv.to_scipy_rotation(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ShapeError, match=r"expected `R` to have shape \(3, 3\) or \(\.\.\., 3, 3\), got \(2, 2\)"):
        conv.matrix_to_quaternion(np.eye(2))


def test_non_unit_quaternion_refused():
    with pytest.raises(InvalidInputError, match=r"expected a unit quaternion .*got \|q\| = 2"):
        conv.quaternion_to_matrix([2.0, 0, 0, 0])
    with pytest.raises(ShapeError, match=r"expected `q` to have shape \(\.\.\., 4\), got \(3,\)"):
        conv.quaternion_to_matrix([1.0, 0, 0])


def test_bad_axis_refused():
    with pytest.raises(InvalidInputError, match="expected axis 1, 2 or 3, got 4"):
        euler.generator(4)
