"""Section 3.6 at its edges: uniform-precession rates without cancellation, the closed form's edge sweep,
and its measured error estimate (issue 11).

References are independent of the toolkit's derivations: (3.80)–(3.81) typed in by hand and solved by
mpmath at 120 digits (so that the textbook quadratic formula, which cancels, still leaves > 30 digits),
and the hand-written Newton–Euler equations integrated by mpmath's Taylor series at 30 digits
(:func:`mechderive.stress.reference.heavy_reference`).
"""

from __future__ import annotations

import warnings

import mpmath
import numpy as np
import pytest

# The horizontal gyroscope of the issue (reproduction 4): I1, I3 about the pivot, M, g, l.
GYRO = (0.010625, 0.00125, 1.0, 9.81, 0.1)


# --- (3.80)-(3.81): uniform precession ---------------------------------------------------------------

def _generated_functions() -> dict:
    """What ``mechderive derive heavy_top precession_rates minimum_spin --format python`` prints, exec'd."""
    from mechderive.derive import derive_entries, render

    src = render(derive_entries("heavy_top", ["precession_rates", "minimum_spin"]), "python", system="heavy_top")
    ns: dict = {}
    exec(compile(src, "<derived>", "exec"), ns)
    return ns


def _reference_rates(params, spin: float, theta0: float) -> list[float] | None:
    """(slow, fast) by |φ̇| from (3.80) typed in: M g l = φ̇ (I3 ω3 − I1 φ̇ cos θ0), at 120 digits.

    The textbook formula (B ± √disc)/(2 I1 cos θ0) loses up to ~30 digits to cancellation on this
    grid (I3ω3 = 1e5 at cos θ0 = 6e-17); 120 digits leave more than 80.  None: no real rates.
    """
    with mpmath.workdps(120):
        I1, I3, M, g, l = (mpmath.mpf(x) for x in params)
        c = mpmath.cos(mpmath.mpf(theta0))  # the exact binary θ0
        B, mgl = I3 * mpmath.mpf(spin), M * g * l
        if c == 0:
            return [float(mgl / B), float("inf")]
        disc = B * B - 4 * I1 * mgl * c
        if disc < 0:
            return None
        roots = sorted(((B + s * mpmath.sqrt(disc)) / (2 * I1 * c) for s in (1, -1)), key=abs)
        return [float(r) for r in roots]


THETAS = [1e-8, 0.1, 0.6, 1.0, np.pi / 2 - 1e-4, np.pi / 2 - 1e-9, np.pi / 2, np.nextafter(np.pi / 2, 4.0),
          np.pi / 2 + 1e-9, 2.0, 3.0, np.pi - 1e-8, np.pi]
SPINS = [1e-8, 1e-3, 1.0, 300.0, 1e5, 1e8, -1e-3, -300.0, -1e8]


def test_horizontal_gyroscope_slow_rate_is_mgl_over_spin():
    # Reproduction 4: the generated code gave 0 (the textbook formula cancels completely at cos θ0 = 6e-17).
    rates = _generated_functions()["heavy_top_precession_rates"]
    I1, I3, M, g, l = GYRO
    slow, fast = rates(*GYRO, 300.0, np.pi / 2).ravel()
    # to leading order M g l/(I3 ω3) = 2.616; the next term is relative I1 M g l cos θ0/(I3ω3)² ~ 5e-19
    assert slow == pytest.approx(M * g * l / (I3 * 300.0), rel=4e-16)
    assert fast == pytest.approx(_reference_rates(GYRO, 300.0, np.pi / 2)[1], rel=4e-16)


def test_precession_rates_against_120_digit_roots_over_a_grid():
    # Every (θ0, ω3) of the grid with real roots, including θ0 = π/2 and its float neighbours, hanging
    # tops, spins from 1e-8 to 1e8 of both signs.  4 ulp: each root is a handful of correctly rounded
    # operations on one sum of like-signed terms (measured worst: 1.1 ulp).
    ns = _generated_functions()
    rates = ns["heavy_top_precession_rates"]
    checked = 0
    for th in THETAS:
        for w in SPINS:
            want = _reference_rates(GYRO, w, th)
            if want is None:
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # no overflow, no invalid value, no division by zero
                got = rates(*GYRO, w, th).ravel()
            np.testing.assert_allclose(got, want, rtol=4 * 2.0**-52, atol=0, err_msg=f"theta0={th!r}, omega3={w!r}")
            checked += 1
    assert checked > 70


def test_precession_rates_compiled_from_the_model_are_the_generated_ones():
    # The numeric path (compile_expressions of the model's rates) and `derive --format python` print the
    # same derivation: both right at the horizontal gyroscope (to rounding).
    from mechderive.core.compile import compile_expressions
    from mechderive.systems.heavy_top import model as ht

    f = compile_expressions(list(ht.model().precession_rates), [*ht.PARAMETERS, ht.omega3, ht.theta0], name="rates")
    got = np.asarray(f(*GYRO, np.array([300.0, -300.0]), np.pi / 2), dtype=float)
    want = np.array([_reference_rates(GYRO, w, np.pi / 2) for w in (300.0, -300.0)])
    np.testing.assert_allclose(got, want, rtol=4 * 2.0**-52)


def test_minimum_spin_is_zero_below_the_horizontal_and_the_textbook_root_above():
    wmin = _generated_functions()["heavy_top_minimum_spin"]
    I1, I3, M, g, l = GYRO
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # it used to be NaN with "invalid value in sqrt"
        below = wmin(*GYRO, np.array([np.nextafter(np.pi / 2, 4.0), 2.0, 3.0, np.pi]))
        above = wmin(*GYRO, np.array([1e-8, 0.6, 1.5, np.pi / 2]))
    assert np.all(below == 0.0)
    for th in (np.nextafter(np.pi / 2, 4.0), 2.0, 3.0, np.pi):
        # any spin is enough there: at ω3 = 0 (and so for all ω3) the discriminant is ≥ 0
        with mpmath.workdps(30):
            assert -4 * mpmath.mpf(I1) * M * g * l * mpmath.cos(mpmath.mpf(th)) >= 0
        assert _reference_rates(GYRO, 1e-300, th) is not None
    # (3.81) typed in: (2/I3)√(I1 M g l cos θ0), 30 digits; 4 ulp for a product of square roots
    with mpmath.workdps(30):
        want = [float(2 / mpmath.mpf(I3) * mpmath.sqrt(mpmath.mpf(I1) * M * g * l * mpmath.cos(mpmath.mpf(th))))
                for th in (1e-8, 0.6, 1.5, np.pi / 2)]
    np.testing.assert_allclose(above, want, rtol=4 * 2.0**-52)
    # and it is where the rates stop being real: 1e-6 below, the reference has none
    for th in (0.6, 1.5):
        w = float(wmin(*GYRO, th))
        assert _reference_rates(GYRO, w * (1 - 1e-6), th) is None
        assert _reference_rates(GYRO, w * (1 + 1e-6), th) is not None
