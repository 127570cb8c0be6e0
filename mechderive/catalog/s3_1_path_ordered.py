"""Catalog, section 3.1.2: path-ordered exponentials, (3.11)–(3.16).

Each printed formula is transcribed only here, to be checked against
:mod:`mechderive.kinematics.dyson` (symbolic derivations from Ṙ = ωR) or against
numerical solutions (:mod:`mechderive.kinematics.path_ordered`, SciPy, mpmath).

Notes on what is claimed
------------------------
* (3.12) is claimed twice: it *is* the solution for a fixed axis, and it is *not* for
  a turning axis.  The second claim is made falsifiable by checking the text's
  reason: the residual Ṙ − ωR of (3.12) is, at second order in ω, the misordered
  second term of (3.14) minus its properly ordered partner, ½(Mω − ωM) ≠ 0.
* (3.16): the printed limits "∫_0^{t''} ∫_{t'}^t ω(t'')ω(t') dt' dt''" bind each
  integration variable to a limit containing itself, so read literally (innermost
  sign with the first differential, as SymPy does) the result depends on t' and t''.
  The text's own sentence gives the region 0 < t' < t'' < t, i.e.
  ∫_0^t dt'' ∫_0^{t''} dt' ω(t'')ω(t'), registered as the correction.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import sympy as sp

from ..core.compile import compile_expressions
from ..core.symbols import t
from ..kinematics import dyson
from ..kinematics.dyson import eps, so3_matrix, t1, t2
from .checks import all_pass, same
from .registry import Claim, Outcome, register

SECTION = "3.1.2"

# ----------------------------------------------------------------------------- (3.11)

_R = sp.MatrixSymbol("R", 3, 3)
_RDOT = sp.MatrixSymbol("Rdot", 3, 3)
# A non-commuting numeric test angular velocity (body components, rad/s).
_W_EXPR = sp.Matrix([sp.sin(t) + sp.Rational(1, 2), sp.Rational(7, 10) * sp.cos(2 * t), sp.Rational(3, 10) + t**2])


def _w_numeric(times: np.ndarray) -> np.ndarray:
    return compile_expressions(list(_W_EXPR), [t], name="path_ordered_test_omega")(np.asarray(times, dtype=float))


def _inverse(m: sp.MatrixSymbol) -> sp.Matrix:
    a = m.as_explicit()
    return a.adjugate() / a.det()  # R⁻¹ entry by entry, so that perturbing one entry is possible


def _check_3_11(formula: Any) -> Outcome:
    """Evaluate the formula on Ṙ, R of the integrator's solution of Ṙ = ωR; it must return ω."""
    from ..kinematics.path_ordered import path_ordered_exponential

    # The formula under test is lambdified directly: perturbed copies must not fill the compile cache.
    f = sp.lambdify([_RDOT, _R], sp.Matrix(formula), "numpy")
    delta = 5e-3
    worst = 0.0
    for tc in (0.5, 1.0):
        stencil = tc + delta * np.array([-2.0, -1.0, 1.0, 2.0])
        res = path_ordered_exponential(_w_numeric, (0.0, 1.5), steps=400, order=6, t_eval=np.sort(np.append(stencil, tc)))
        Rm2, Rm1, Rc, Rp1, Rp2 = res.R
        # 5-point derivative: truncation δ⁴|R⁽⁵⁾|/30 ~ 1e-9 (3e-9 measured), rounding ≈ 1.5·1e-14/δ ≈ 3e-12.
        Rdot = (Rm2 - 8 * Rm1 + 8 * Rp1 - Rp2) / (12 * delta)
        got = np.asarray(f(Rdot, Rc), dtype=float)
        want = so3_matrix(_W_EXPR.subs(t, tc)).evalf()
        err = float(np.max(np.abs(got - np.array(want, dtype=float))))
        worst = max(worst, err)
    # 1e-7 is ~30× the finite-difference error above; a 1 % change of ω moves it by ≳ 5e-3.
    if worst > 1e-7:
        return Outcome(False, f"Ṙ R⁻¹ of the integrated R differs from ω by {worst:.3g}")
    return Outcome(True, f"Ṙ R⁻¹ of the Magnus solution reproduces ω to {worst:.1e} at t = 0.5, 1.0")


register(Claim(
    equation="3.11", section=SECTION,
    statement="the rotation obtained by integrating ω satisfies ω = Ṙ R⁻¹",
    method="integration",
    printed=lambda: _RDOT.as_explicit() * _inverse(_R),
    check=_check_3_11,
    perturbed=lambda: _inverse(_R) * _RDOT.as_explicit(),  # the convective Ω = R⁻¹Ṙ of (3.10): a different matrix
))

# ----------------------------------------------------------------------------- (3.12)

_AXIS = sp.Matrix([1, 2, 2]) / 3
_RATE = 1 + t**2  # ω(t) = (1 + t²) n̂, a fixed axis with a varying rate


def _printed_3_12_fixed_axis() -> sp.Matrix:
    angle = sp.integrate(_RATE.subs(t, t1), (t1, 0, t))
    # exp(s n̂·J) for a plain symbol s, then s = ∫ω: SymPy's eigen-decomposition carrying t³/3 + t took 2.3 s, this 1 s
    s = sp.Dummy("s", real=True)
    rotation = (s * so3_matrix(_AXIS)).exp().xreplace({s: angle})
    return rotation.applyfunc(lambda e: sp.expand(e.rewrite(sp.cos)))


def _check_3_12_fixed_axis(formula: Any) -> Outcome:
    R = sp.Matrix(formula)
    w = _RATE * so3_matrix(_AXIS)
    return all_pass([same(R.diff(t), w * R, "Ṙ = ωR"), same(R.subs(t, 0), sp.eye(3), "R(0) = 1")])


register(Claim(
    equation="3.12", section=SECTION,
    statement="for a fixed axis, ω = (1 + t²) n̂, R = exp(∫_0^t ω dt') solves (3.11) with R(0) = 1",
    method="symbolic",
    printed=_printed_3_12_fixed_axis,
    check=_check_3_12_fixed_axis,
))


def _printed_3_12_residual() -> sp.Matrix:
    # (3.14)'s second term ½Mω, less the ½ωM that ωR's expansion would need in its place.
    m = dyson.model()
    M, w = m.generic_integral, m.generic_omega
    return M * w / 2 - w * M / 2


def _check_3_12_residual(formula: Any) -> Outcome:
    derived = dyson.model().naive_residual
    if all(sp.expand(e) == 0 for e in derived):
        return Outcome(False, "derived residual vanishes: no failure of (3.12) to show")
    return same(formula, derived, "ε² part of d/dt exp(εM) − εω exp(εM)")


register(Claim(
    equation="3.12 (turning axis)", section=SECTION,
    statement="for non-commuting ω, exp(∫ω) is not a solution: at O(ω²) it misses Ṙ = ωR by ½(Mω − ωM) ≠ 0",
    method="symbolic",
    printed=_printed_3_12_residual,
    check=_check_3_12_residual,
))

# ----------------------------------------------------------------------------- (3.13)

_K = sp.Symbol("k", integer=True, nonnegative=True)


def _check_3_13(formula: Any) -> Outcome:
    """Sum the series Σ c(k) M^k at 30 digits; compare with mpmath's Padé expm and the toolkit's Rodrigues."""
    import mpmath

    from ..kinematics.so3 import expm_so3

    coeff = sp.lambdify(_K, formula, "mpmath")
    rng = np.random.default_rng(31)
    vectors = [rng.normal(size=3) for _ in range(4)]
    vectors += [np.array([0.0, 0.0, 3.1]), np.array([1e-7, -2e-7, 3e-7])]  # near π, and tiny
    worst_mp = worst_rod = 0.0
    with mpmath.workdps(30):
        for v in vectors:
            M = mpmath.matrix(so3_matrix(sp.Matrix(v)).tolist())
            total, power = mpmath.zeros(3, 3), mpmath.eye(3)
            # |M|^k/k! < 1e-40 for k ≥ 80 when |M| ≤ 4: the truncation is invisible at 30 digits.
            for k in range(80):
                total += coeff(k) * power
                power = power * M
            ref = mpmath.expm(M, method="pade")
            worst_mp = max(worst_mp, float(mpmath.mnorm(total - ref, 1)))
            rod = expm_so3(v)
            worst_rod = max(worst_rod, float(np.max(np.abs(np.array(total.tolist(), dtype=float) - rod))))
    # 1e-25: Padé vs series at 30 digits; 1e-13: Rodrigues in double is good to a few ulp (~1e-15).
    if worst_mp > 1e-25 or worst_rod > 1e-13:
        return Outcome(False, f"series differs from Padé expm by {worst_mp:.2g}, from Rodrigues by {worst_rod:.2g}")
    return Outcome(True, f"series = Padé expm to {worst_mp:.0e} (30 digits), = Rodrigues to {worst_rod:.0e}")


register(Claim(
    equation="3.13", section=SECTION,
    statement="exp(M) = Σ M^k/k!, which for M ∈ so(3) is the Rodrigues rotation (the k-th coefficient is 1/k!)",
    method="numeric",
    printed=lambda: 1 / sp.factorial(_K),
    check=_check_3_13,
))

# ----------------------------------------------------------------------------- (3.14)


def _printed_3_14() -> sp.Matrix:
    m = dyson.model()
    M, w = m.generic_integral, m.generic_omega
    return w * M / 2 + M * w / 2


register(Claim(
    equation="3.14", section=SECTION,
    statement="d/dt ½(∫_0^t ω)² = ½ ω(t) ∫ω + ½ (∫ω) ω(t), two differently ordered terms",
    method="symbolic",
    printed=_printed_3_14,
    check=lambda formula: same(formula, dyson.model().half_square_derivative, "d/dt ½M²"),
))

# ----------------------------------------------------------------------------- (3.15)


def _ordered_double_integral(later_on_left: bool = True) -> sp.Matrix:
    """∫_0^t dt'' ∫_0^{t''} dt' of ω(t'')ω(t') (later on the left) or ω(t')ω(t''), for the test ω."""
    w = dyson.model().test_omega
    prod = w.subs(t, t2) * w.subs(t, t1) if later_on_left else w.subs(t, t1) * w.subs(t, t2)
    return prod.applyfunc(lambda e: sp.Integral(sp.expand(e), (t1, 0, t2), (t2, 0, t)))


def dyson_second_order(*, later_on_left: bool = True) -> sp.Matrix:
    """1 + ε∫_0^t ω + ε² ∫∫_{0<t'<t''<t} ω ω, ordered as asked, for the polynomial test ω; a Matrix in t, ε."""
    w = dyson.model().test_omega
    first = w.subs(t, t1).applyfunc(lambda e: sp.integrate(e, (t1, 0, t)))
    return (sp.eye(3) + eps * first + eps**2 * _ordered_double_integral(later_on_left).doit()).applyfunc(sp.expand)


_AMPLITUDES = np.array([0.2, 0.1, 0.05, 0.025])


@functools.cache
def _reference_3_15() -> tuple[np.ndarray, ...]:
    """R(1) solving Ṙ = εωR (DOP853, rtol 1e-13) for each ε of ``_AMPLITUDES``: computed once per session."""
    from scipy.integrate import solve_ivp

    w = dyson.model().compile("test_omega", dyson.model().test_omega, [t])
    out = []
    for a in _AMPLITUDES:
        sol = solve_ivp(lambda s, y: (a * np.asarray(w(s), dtype=float) @ y.reshape(3, 3)).ravel(),
                        (0.0, 1.0), np.eye(3).ravel(), method="DOP853", rtol=1e-13, atol=1e-14)
        out.append(sol.y[:, -1].reshape(3, 3))
    return tuple(out)


def _check_3_15(formula: Any) -> Outcome:
    """The truncated series must differ from the solution of Ṙ = εωR by O(ε³): fit the exponent."""
    f = sp.lambdify([t, eps], sp.Matrix(formula), "numpy")
    amplitudes = _AMPLITUDES
    errors = [np.max(np.abs(np.asarray(f(1.0, a), dtype=float) - R)) for a, R in zip(amplitudes, _reference_3_15())]
    slope = float(np.polyfit(np.log(amplitudes), np.log(errors), 1)[0])
    # Truncation after ε² leaves ε³·|D₃| ≳ 1e-6 here, far above DOP853's 1e-13: the slope is 3 ± 0.1;
    # a misordered ε² term leaves an ε² error (slope 2), a wrong constant term slope ≈ 0.
    if abs(slope - 3) > 0.3:
        return Outcome(False, f"error scales as ε^{slope:.2f}, not ε³ (errors {', '.join(f'{e:.1e}' for e in errors)})")
    return Outcome(True, f"error vs DOP853 scales as ε^{slope:.2f} (ε = 0.2 … 0.025)")


register(Claim(
    equation="3.15", section=SECTION,
    statement="P-ordering (later times on the left) makes 1 + ∫ω + ∫∫ω(t'')ω(t') the solution of Ṙ = ωR to second order in ω",
    method="integration",
    printed=dyson_second_order,
    check=_check_3_15,
))

# ----------------------------------------------------------------------------- (3.16)


def _printed_3_16_literal() -> sp.Matrix:
    w = dyson.model().test_omega
    prod = w.subs(t, t2) * w.subs(t, t1)
    # As printed: ∫_0^{t''} ∫_{t'}^{t} ω(t'')ω(t') dt' dt'' (inner sign ↔ dt', outer ↔ dt'').
    return prod.applyfunc(lambda e: sp.Integral(sp.expand(e), (t1, t1, t), (t2, 0, t2)))


def _check_3_16(formula: Any) -> Outcome:
    value = sp.Matrix(formula).doit().applyfunc(sp.expand)
    stray = value.free_symbols - {t}
    if stray:
        return Outcome(False, f"the double integral still depends on {', '.join(sorted(map(str, stray)))}")
    return same(value, dyson.model().dyson_terms[2], "second Dyson term D₂ (from Ḋ₂ = ωD₁)")


register(Claim(
    equation="3.16", section=SECTION,
    statement="the ε² term of R is the double integral of ω(t'')ω(t') over 0 < t' < t'' < t",
    method="symbolic",
    printed=_printed_3_16_literal,
    corrected=lambda: _ordered_double_integral(later_on_left=True),
    check=_check_3_16,
))


def _printed_3_16_derivative() -> sp.Matrix:
    w = dyson.model().test_omega
    return w * w.subs(t, t1).applyfunc(lambda e: sp.integrate(e, (t1, 0, t)))


register(Claim(
    equation="3.16 (derivative)", section=SECTION,
    statement="d/dt of the ordered double integral is the single term ω(t) ∫_0^t ω(t') dt'",
    method="symbolic",
    printed=_printed_3_16_derivative,
    check=lambda formula: same(formula, dyson.model().dyson_terms[2].diff(t), "d/dt D₂"),
))
