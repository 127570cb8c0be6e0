"""Bulirsch's cel for the complete Π at 40 digits, against mpmath.ellippi (an independent algorithm)."""

import mpmath
import pytest

from mechderive.special.highprec import complete_pi_mp


@pytest.mark.parametrize("n, m1", [(0.55, 0.91), (-0.0875, 0.91), (-3.0, 0.6153846), (0.99, 1e-12),
                                   (-10.0, 0.5), (0.3, 0.5), (0.0, 0.3), (0.999999, 1.0), (-1e6, 1e-14)])
def test_complete_pi_matches_mpmath_to_38_digits(n, m1):
    with mpmath.workdps(40):
        got = complete_pi_mp(mpmath.mpf(n), mpmath.mpf(m1))
        ref = mpmath.ellippi(mpmath.mpf(n), 1 - mpmath.mpf(m1))
        # 38 of 40 digits: cel's last two iterations are at full precision; mpmath's own result ~1e-40
        assert abs(got - ref) <= mpmath.mpf(10) ** -38 * abs(ref)


def test_complete_pi_refuses_outside_its_domain():
    with pytest.raises(ValueError, match="expected n < 1"):
        complete_pi_mp(1.5, 0.5)
