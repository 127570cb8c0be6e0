"""``mechderive.rotation_matrix`` in NumPy: without SymPy, and equal to R(φ, θ, ψ) (3.54) at 40 digits.

(The derived symbolic R is checked against the chapter's (3.54) in :mod:`mechderive.catalog`.)
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

import mechderive
from mechderive.errors import NonFiniteValueError

from .conftest import run_python


def test_rotation_matrix_imports_no_sympy(tmp_path):
    # a fresh process and an empty cache dir: nothing compiled or cached can stand in for SymPy
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    proc = run_python("-c", "import mechderive, sys; mechderive.rotation_matrix(0.1, 0.2, 0.3); "
                            "assert 'sympy' not in sys.modules, 'sympy imported'", timeout=60,
                      env={"MECHDERIVE_CACHE_DIR": str(cache)})
    assert proc.returncode == 0, proc.stderr


def _reference(phi: float, theta: float, psi: float) -> np.ndarray:
    """R3(ψ) R1(θ) R3(φ) by hand at 40 digits, the chapter's passive R3(α) = [[c, s, 0], [−s, c, 0],
    [0, 0, 1]] (3.51) and R1(α) = [[1, 0, 0], [0, c, s], [0, −s, c]] (3.52)."""
    with mpmath.workdps(40):
        def r3(a):
            c, s = mpmath.cos(a), mpmath.sin(a)
            return mpmath.matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])

        def r1(a):
            c, s = mpmath.cos(a), mpmath.sin(a)
            return mpmath.matrix([[1, 0, 0], [0, c, s], [0, -s, c]])

        m = r3(mpmath.mpf(psi)) * r1(mpmath.mpf(theta)) * r3(mpmath.mpf(phi))
        return np.array(m.tolist(), dtype=float)


def test_rotation_matrix_agrees_with_40_digit_reference_and_the_derivation():
    rng = np.random.default_rng(20261121)
    angles = rng.uniform(-7.0, 7.0, (40, 3))
    got = mechderive.rotation_matrix(angles[:, 0], angles[:, 1], angles[:, 2])
    assert got.shape == (40, 3, 3)
    ref = np.array([_reference(*a) for a in angles])
    # each entry sums at most 4 products of 3 rounded factors: a few ulps of 1, so 1e-15
    assert np.max(np.abs(got - ref)) < 1e-15
    assert mechderive.rotation_matrix(0.1, 0.2, 0.3).shape == (3, 3)
    assert mechderive.rotation_matrix([0.1, 0.2], 0.3, [[0.0], [1.0]]).shape == (2, 2, 3, 3)


def test_rotation_matrix_refuses_non_finite_angles():
    with pytest.raises(NonFiniteValueError, match="theta"):
        mechderive.rotation_matrix(0.0, float("nan"), 0.0)
