"""Section 3.4: the free top's measured error estimate (issue 11: "error estimates are measured, never a constant").

``FreeTopSolution.error_estimate(t, quantities)`` is built from residuals on the run (ω(0) - ω0,
Euler's equations (3.33), conservation of 2T, L² and of L in space, R(0) - R0, the precession angle
against quadrature of the rate (3.58)).  Checked here against 30-digit Taylor references
(tests/_free_top_reference.py): it covers the true error on ordinary motions without being absurdly
larger, and it catches a wrong constant planted in the closed form.
"""

from __future__ import annotations

import dataclasses
import functools

import mpmath
import numpy as np
import pytest

from mechderive.core.phase import DD
from mechderive.errors import InvalidInputError
from mechderive.kinematics.rotations import rotation_matrix
from mechderive.systems.free_top.exact import exact_free_top

from ._free_top_reference import integrate

R0 = rotation_matrix(0.3, 1.1, -0.4)
T = np.linspace(0.0, 12.0, 241)
CHECKED = T[::30]  # where the true error is measured


@functools.lru_cache(maxsize=None)
def _reference(moments, omega0):
    return integrate(moments, omega0, CHECKED, R0=R0)


def _true_errors(sol, moments, omega0, times=CHECKED):
    """max |ω - ω_ref| / |ω0| and max |R - R_ref| over ``times`` (30-digit reference)."""
    ref = _reference(tuple(moments), tuple(omega0))
    w, R = sol.omega(times), sol.rotation(times)
    ew = max(abs(float(w[i, a] - ref[i][a])) for i in range(len(times)) for a in range(3))
    eR = max(abs(float(R[i].ravel()[j] - ref[i][3 + j])) for i in range(len(times)) for j in range(9))
    return ew / np.linalg.norm(omega0), eR


ORDINARY = [
    ((1.0, 2.0, 3.0), (1.0, 0.5, 1.0)),
    ((3.0, 4.0, 5.0), (-2.0, 1.0, 0.5)),
    ((0.55, 0.89, 1.43), (0.3, -0.2, 0.7)),
    ((2.0, 2.0, 3.0), (0.3, 0.4, 1.0)),            # symmetric
    ((1.0, 2.0, 2.25), (-0.75, 0.5, 1.0)),         # on the separatrix
    ((1.0, 2.0, 2.9), (0.1, 1.0, 1e-7)),           # near the intermediate axis: 1 - m = 0.01
    ((2.0, 3.0, 4.0), (1e-20, 1.0, 1e-20)),        # 1 - m = 1e-40: piecewise separatrix motion
    ((2.0, 3.0, 5.0), (2.0**-53, 0.0, 0.2)),       # L within rounding of ẽ3
    ((1.0, 1e3, 1e3), (1.0, 0.3, 0.2)),            # a thin rod
    ((2.0, 2.0, 2.0), (1.0, 2.0, 3.0)),            # a sphere: steady
]


@pytest.mark.parametrize("moments, omega0", ORDINARY)
def test_estimate_covers_the_true_error_and_is_not_absurd(moments, omega0):
    sol = exact_free_top(moments, omega0, R0=R0)
    sol.rotation(T)
    est_w, est_R = sol.error_estimate(T, ("omega",)), sol.error_estimate(T, ("R",))
    true_w, true_R = _true_errors(sol, moments, omega0)
    assert true_w <= est_w and true_R <= est_R
    # 1e-12: the bound for ordinary motions; measured 1e-16..5e-14 here (12 s, ~2-10 periods)
    assert est_w <= 1e-12 and est_R <= 1e-12
    assert sol.error_estimate(T) == max(est_w, est_R)


def _fresh(sol, **changes):
    """A copy of ``sol`` with some constants replaced, and no cached evaluations."""
    return dataclasses.replace(sol, **changes, _mp={k: sol._mp[k] for k in ("constants", "L")})


def _planted_orientation(sol, **changes):
    out = _fresh(sol)
    out.__dict__["_orient"] = dataclasses.replace(sol._orient, **changes)
    return out


def _scaled(d: DD, factor: float) -> DD:
    return DD.scaled(mpmath.ldexp(mpmath.mpf(d.hi) + d.lo, d.exp) * factor)


PLANTS = {
    "precession angle at t = 0, φ'0 + 1e-9": lambda s, o: _planted_orientation(s, phi0=o.phi0 + 1e-9),
    "mean precession rate × (1 + 1e-10)": lambda s, o: _planted_orientation(s, nu=_scaled(o.nu, 1 + 1e-10)),
    "precession constant c2/λ × (1 + 1e-8)":
        lambda s, o: _planted_orientation(s, c2_over_lam=o.c2_over_lam * (1 + 1e-8)),
    "Π(n; am u0 | m) + 1e-9": lambda s, o: _planted_orientation(s, p0=o.p0 + 1e-9),
    "L frame tilted by 1e-9": lambda s, o: _planted_orientation(s, S=rotation_matrix(1e-9, 0.0, 0.0) @ o.S),
    "parameter m + 1e-8": lambda s, o: _fresh(s, m=s.m + 1e-8, m1=s.m1 - 1e-8),
    "rate λ × (1 + 1e-10)": lambda s, o: _fresh(s, _lam=_scaled(s._lam, 1 + 1e-10)),
    "quarter period K × (1 + 1e-12)": lambda s, o: _fresh(s, _quarter=DD(s._quarter.hi * (1 + 1e-12), 0.0)),
    "amplitude P × (1 + 1e-10)": lambda s, o: _fresh(s, _amp_scaled=((s._amp_scaled[0][0] * (1 + 1e-10),
                                                                        *s._amp_scaled[0][1:]), s._amp_scaled[1])),
    "initial phase v0 + 1e-10": lambda s, o: _fresh(s, _v0=DD(s._v0.hi + 1e-10, 0.0)),
}


@pytest.mark.parametrize("plant", list(PLANTS))
@pytest.mark.parametrize("moments, omega0", [((1.0, 2.0, 3.0), (1.0, 0.5, 1.0)), ((1.0, 2.0, 2.9), (0.1, 1.0, 1e-7))])
def test_a_planted_wrong_constant_is_caught(plant, moments, omega0):
    base = exact_free_top(moments, omega0, R0=R0)
    base.rotation(0.0)
    sol = PLANTS[plant](base, base._orient)
    sol.rotation(T)
    est = sol.error_estimate(T)
    true_w, true_R = _true_errors(sol, moments, omega0)
    true = max(true_w, true_R)
    assert true > 1e-12  # the plant does make the motion wrong
    assert est >= true and est > 1e-12, (plant, est, true)


def test_asking_for_omega_evaluates_nothing_of_the_orientation():
    sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0))
    est = sol.error_estimate(T, ("omega",))
    assert 0 < est < 1e-12 and "_orient" not in sol.__dict__


def test_cost_is_a_few_hundred_extra_jacobi_values_whatever_the_samples(monkeypatch):
    import mechderive.special.jacobi as jacobi

    sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0), R0=R0)
    t = np.linspace(0.0, 1000.0, 100001)
    sol.rotation(t)
    counted = []
    real = jacobi.jacobi_sn_cn_dn
    monkeypatch.setattr(jacobi, "jacobi_sn_cn_dn", lambda u, *a, **k: counted.append(np.size(u)) or real(u, *a, **k))
    sol.error_estimate(t)
    # the samples' own values are re-used: only t = 0 (here a sample), the ends and the quadrature
    # nodes over half a polhode period are evaluated, in one call
    assert len(counted) == 1 and counted[0] < 300


def test_bad_quantities_are_refused():
    sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0))
    with pytest.raises(InvalidInputError, match=r"expected quantities among \('omega', 'R', 'euler_angles'\), got \('q',\)"):
        sol.error_estimate(T, ("q",))
