"""Section 3.6 at its edges: uniform-precession rates without cancellation, the closed form's edge sweep,
and its measured error estimate (issue 11).

References are independent of the toolkit's derivations: (3.80)–(3.81) typed in by hand and solved by
mpmath at 120 digits (so that the textbook quadratic formula, which cancels, still leaves > 30 digits),
and the hand-written Newton–Euler equations integrated by mpmath's Taylor series at 30 digits
(:func:`mechderive.stress.reference.heavy_reference`).
"""

from __future__ import annotations

import functools
import warnings

import mpmath
import numpy as np
import pytest

# The horizontal gyroscope of the issue (reproduction 4): I1, I3 about the pivot, M, g, l.
GYRO = (0.010625, 0.00125, 1.0, 9.81, 0.1)


# --- (3.80)-(3.81): uniform precession ---------------------------------------------------------------

@functools.cache
def _generated_functions() -> dict:
    """What ``mechderive derive heavy_top precession_rates minimum_spin --format python`` prints, exec'd (once: the
    tests only call the functions)."""
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


# --- the closed form at its edges (issue 11): every draw right to its estimate, or refused ---------

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from mechderive.errors import InvalidInputError, MechDeriveError  # noqa: E402
from mechderive.stress.reference import euler_matrix, heavy_reference  # noqa: E402
from mechderive.systems.heavy_top.exact import exact_heavy_top  # noqa: E402

TOP = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)  # the chapter's example top (about the pivot), M g l = 1
KEYS = ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")
OUTPUTS = ["theta", "theta_dot", "phi", "psi", "phi_dot", "psi_dot", "R", "apex", "omega"]
EPS = 2.0**-52


def _wrap(x):
    return (np.asarray(x) + np.pi) % (2 * np.pi) - np.pi


def _rates_scale(params: dict, init: dict) -> float:
    """A natural scale of the rates: |ω(0)|, the derived a, b of (3.66) (≤ 2|ω|·I3/I1), √(M g l/I1)."""
    w = np.hypot(np.hypot(init["phi_dot"], init["theta_dot"]), init["psi_dot"]) * max(1.0, params["I3"] / params["I1"])
    return max(2 * w, np.sqrt(params["M"] * params["g"] * params["l"] / params["I1"]))


def _window(top, init: dict, n: int) -> np.ndarray:
    T = top.nutation_period
    span = 1.5 * T if np.isfinite(T) and T < 40 else 6.0
    # the reference's Taylor steps scale with the fastest rate: keep its cost bounded
    fastest = max(abs(init["psi_dot"]), abs(init["phi_dot"]), abs(init["theta_dot"]), 1.0)
    return np.linspace(0.0, min(span, 200.0 / fastest), n)


def check_motion(params: dict, initial: dict, *, n: int = 9, ordinary: bool = False) -> dict | None:
    """exact_heavy_top against the 30-digit reference: the start to a few ulp, every output against the
    reference *and* within the solution's own error estimate; None if refused with a MechDeriveError."""
    init = {k: float(initial.get(k, 0.0)) for k in KEYS}
    try:
        top = exact_heavy_top(params, init)
    except MechDeriveError as exc:  # any other exception type fails the test
        assert isinstance(exc, InvalidInputError) and "expected" in str(exc), exc
        return None
    t = _window(top, init, n)
    out = top.evaluate(t, OUTPUTS)
    for k, v in out.items():
        assert np.all(np.isfinite(v)), (k, init)
    scale = _rates_scale(params, init)
    # the start: θ, R and ω to a few ulp (4: one rounding each of half a dozen operations, with margin)
    assert abs(out["theta"][0] - init["theta"]) <= 4 * np.spacing(max(init["theta"], 1.0)), init
    with mpmath.workdps(30):
        R0 = np.array(euler_matrix(init["phi"], init["theta"], init["psi"]).tolist(), dtype=float)
    np.testing.assert_allclose(out["R"][0], R0, rtol=0, atol=8 * EPS, err_msg=str(init))
    if init["theta"] > 0:
        for k in ("phi", "psi"):
            assert abs(out[k][0] - init[k]) <= 4 * np.spacing(max(abs(init[k]), np.pi)), (k, init)
        # rates: partial fractions of size |a|, |b| cancel to φ̇: ulp of the rates' scale, not of φ̇
        for k in ("theta_dot", "phi_dot", "psi_dot"):
            assert abs(out[k][0] - init[k]) <= 16 * EPS * scale, (k, init)
    else:  # on the pole only φ + ψ (and φ̇ + ψ̇) are defined
        assert abs(_wrap(out["phi"][0] + out["psi"][0] - init["phi"] - init["psi"])) <= 8 * EPS * np.pi
        assert abs(out["phi_dot"][0] + out["psi_dot"][0] - init["phi_dot"] - init["psi_dot"]) <= 16 * EPS * scale
    ref = heavy_reference(params, init, t)
    err = {"theta": np.max(np.abs(out["theta"] - ref.angles[:, 1])),
           "R": np.max(np.abs(out["R"] - ref.R)),
           "apex": np.max(np.abs(out["apex"] - ref.R[:, 2, :])),
           "omega": np.max(np.abs(out["omega"] - ref.omega))}
    # φ, ψ each where the reference defines them well (sin θ > 1e-3: R31, R13 ≥ 1e-3, 30 digits)
    well = np.sin(ref.angles[:, 1]) > 1e-3
    if np.any(well):
        for k, col in (("phi", 0), ("psi", 2)):
            err[k] = np.max(np.abs(_wrap(out[k] - ref.angles[:, col]))[well])
    for q, e in err.items():
        estimate = top.error_estimate(t, [q])
        assert np.isfinite(estimate) and e <= estimate, (q, e, estimate, init)
        if ordinary:
            assert estimate <= (1e-11 * scale if q == "omega" else 1e-11), (q, estimate, init)
    return err


def _uniform(theta0: float, spin: float, which: int) -> dict:
    """A uniform precession: θ̇ = 0, φ̇ a root of (3.80) from the derived, cancellation-free rates."""
    rates = _generated_functions()["heavy_top_precession_rates"]
    rate = float(rates(*(TOP[k] for k in ("I1", "I3", "M", "g", "l")), spin, theta0).ravel()[which])
    return dict(theta=theta0, phi_dot=rate, psi_dot=spin - rate * np.cos(theta0))


def _p_phi_zero(theta0: float, spin_rate: float, theta_dot: float) -> dict:
    """p_φ = I1 φ̇ sin²θ + I3 (ψ̇ + φ̇ cos θ) cos θ = 0 (3.64), solved for φ̇."""
    c, s = np.cos(theta0), np.sin(theta0)
    phi_dot = -TOP["I3"] * spin_rate * c / (TOP["I1"] * s * s + TOP["I3"] * c * c)
    return dict(theta=theta0, theta_dot=theta_dot, phi_dot=phi_dot, psi_dot=spin_rate)


# Each a different edge, kept cheap for the default run (≈0.3 s of reference each).
QUICK = {
    "general": (dict(theta=1.0, phi=0.3, psi=-0.2, theta_dot=0.4, phi_dot=0.7, psi_dot=3.0), True),
    "near-pole-passage-1e-7": (dict(theta=1e-7, theta_dot=0.5, psi_dot=10.0), False),
    "near-pole-passage-1e-30": (dict(theta=1e-30, theta_dot=0.5, psi_dot=10.0), False),
    "hanging-through-the-bottom": (dict(theta=np.pi, theta_dot=0.3), False),
    "on-the-pole-looping": (dict(theta=0.0, theta_dot=3.0, psi_dot=1.0), False),
    "p_psi-0": (dict(theta=1.0, theta_dot=0.7, phi_dot=0.8, psi_dot=-0.8 * np.cos(1.0)), True),
}


@pytest.mark.parametrize("name", list(QUICK))
def test_edge_motion_against_30_digit_reference(name):
    init, ordinary = QUICK[name]
    assert check_motion(TOP, init, n=7, ordinary=ordinary) is not None


def test_uniform_precession_and_p_phi_zero_against_reference():
    check_motion(TOP, _uniform(1.0, 5.0, 0), n=5, ordinary=True)  # a double root of f(u)
    check_motion(TOP, _p_phi_zero(2.0, 2.0, 0.7), n=5, ordinary=True)


@settings(max_examples=4, deadline=None, derandomize=True)
@given(theta=st.floats(0.0, np.pi), theta_dot=st.floats(0.0, 3.0), phi_dot=st.floats(-3.0, 3.0),
       psi_dot=st.floats(-20.0, 20.0))
def test_random_motions_against_reference(theta, theta_dot, phi_dot, psi_dot):
    check_motion(TOP, dict(theta=theta, theta_dot=theta_dot, phi_dot=phi_dot, psi_dot=psi_dot), n=5)


def test_leaving_the_pole_along_the_separatrix():
    # Regression (found by the random sweep): from the pole with θ̇0 = 4e-38 and a spin below the
    # sleeping threshold, u3 - u2 ~ 1e-76 was found at 40 digits as 1e-21 (a near double root solved to
    # the square root of the precision): θ came out 1e-8 instead of 1e-36, with an estimate of 9e-16.
    params = dict(TOP, I3=0.125)
    err = check_motion(params, dict(theta=0.0, theta_dot=4.17616425727919e-38, psi_dot=2.0), n=5)
    assert err is not None
    with pytest.raises(InvalidInputError, match="separatrix"):  # 1 - m = 3e-161: beyond a double
        exact_heavy_top(params, dict(theta=0.0, theta_dot=1e-80, psi_dot=2.0))


def test_negligible_gravity_puts_a_root_of_f_beyond_the_doubles():
    # Regression (issue 12): M g l / I1 = 1e-200 s⁻² against rates of order one (a scene in the units of a
    # fast motion, θ̇ = 1e300 rad/s in SI) makes β = 2 M g l / I1 = 2e-200, and f(u)'s third root
    # u3 ≈ α/β ~ 1e200: np.roots of the double coefficients saw a quadratic (LinAlgError, then two roots).
    # The far root by Newton, the other two from the quotient; the motion against the 30-digit reference.
    params = dict(TOP, M=1e-201)
    assert check_motion(params, dict(theta=1.0, phi=0.3, theta_dot=0.4, phi_dot=0.7, psi_dot=3.0), n=5,
                        ordinary=True) is not None


def test_refusals_say_why():
    # θ̇ < 0 on the pole leaves θ's range [0, π]; an apex within 1e-75 rad of the pole (not through it)
    # is beyond double precision's Carlson integrals.  Both: InvalidInputError, "expected …, got …".
    for init in (dict(theta=0.0, theta_dot=-0.3), dict(theta=1e-80, theta_dot=0.5, psi_dot=10.0),
                 dict(theta=1e-100, psi_dot=1.0)):
        with pytest.raises(InvalidInputError, match="expected .*got"):
            exact_heavy_top(TOP, init)


# The full sweep (slow): the poles at 10^-k, the bottom, double roots, the sleeping top, zero spin,
# p_φ = 0, p_ψ = 0, huge spins, the separatrix; and many random draws.

def _sweep_cases() -> list[tuple[str, dict]]:
    cases = []
    for k in (1, 3, 6, 9, 12, 16, 20, 40, 60, 74, 76, 150, 300):
        th = 10.0**-k
        cases += [(f"pole-rest-{k}", dict(theta=th, psi_dot=10.0)), (f"pole-pass-{k}", dict(theta=th, theta_dot=0.5, psi_dot=10.0)),
                  (f"pole-prec-{k}", dict(theta=th, phi_dot=0.3, psi_dot=10.0)), (f"pole-nospin-{k}", dict(theta=th, theta_dot=0.3)),
                  (f"pole-falling-{k}", dict(theta=th, psi_dot=1.0))]
    cases.append(("pole-denormal", dict(theta=5e-324, theta_dot=0.5, psi_dot=10.0)))
    for k in (1, 3, 6, 9, 12, 15, 16):
        th = np.pi - 10.0**-k
        cases += [(f"bottom-rest-{k}", dict(theta=th, psi_dot=3.0)), (f"bottom-pass-{k}", dict(theta=th, theta_dot=0.3, psi_dot=3.0)),
                  (f"bottom-prec-{k}", dict(theta=th, phi_dot=0.3, psi_dot=3.0)), (f"bottom-swing-{k}", dict(theta=th, theta_dot=0.3)),
                  (f"bottom-still-{k}", dict(theta=th))]
    for th in (1e-6, 0.3, 1.0, np.pi / 2, 2.0, 3.0, np.pi - 1e-6):
        for spin in (0.5, 5.0, 50.0, 1e4):
            # real rates (discriminant of (3.80) ≥ 0), and the fast one not beyond 1e6 rad/s
            c = np.cos(th)
            if (TOP["I3"] * spin) ** 2 >= 4 * TOP["I1"] * c and TOP["I3"] * spin / (TOP["I1"] * abs(c)) < 1e6:
                cases += [(f"uniform-{which}-{th:.3g}-{spin:g}", ("uniform", th, spin, which)) for which in (0, 1)]
    for w in (0.0, 1.0, 3.99, 4.0, 4.01, 10.0, 1e3):
        cases += [(f"sleeping-{w}", dict(theta=0.0, psi_dot=w)), (f"sleeping-prec-{w}", dict(theta=0.0, psi_dot=w, phi_dot=1.0))]
    for th in (0.3, 1.0, 2.0, 3.0):
        for thd in (0.0, 0.7):
            cases += [(f"p_psi-0-{th}-{thd}", dict(theta=th, theta_dot=thd, phi_dot=0.8, psi_dot=-0.8 * np.cos(th))),
                      (f"p_phi-0-{th}-{thd}", _p_phi_zero(th, 2.0, thd)),
                      (f"no-spin-{th}-{thd}", dict(theta=th, theta_dot=thd, phi_dot=0.8)),
                      (f"at-rest-{th}-{thd}", dict(theta=th, theta_dot=thd))]
    for w in (1e2, 1e4, 1e6, 1e8, 1e12, 1e15):
        cases += [(f"huge-{w:g}", dict(theta=0.5, psi_dot=w)), (f"huge-hanging-{w:g}", dict(theta=2.5, theta_dot=0.1, psi_dot=w))]
    beta = 2 * TOP["M"] * TOP["g"] * TOP["l"] / TOP["I1"]
    for k in (2, 4, 8, 12):
        for sgn in (1, -1):  # a pendulum whose energy is 10^-k from reaching the top
            cases.append((f"separatrix-{sgn}-{k}", dict(theta=np.pi / 2, theta_dot=np.sqrt(beta * (1 + sgn * 10.0**-k)))))
    return cases


SWEEP = _sweep_cases()


@pytest.mark.slow
@pytest.mark.parametrize("name,init", SWEEP, ids=[c[0] for c in SWEEP])
def test_sweep_against_reference(name, init):
    if isinstance(init, tuple):  # a uniform precession, from the derived rates
        init = _uniform(*init[1:])
    check_motion(TOP, init, n=9)


@pytest.mark.slow
@settings(max_examples=300, deadline=None, derandomize=True)
@given(theta=st.one_of(st.floats(0.0, np.pi), st.floats(0.0, 1e-6), st.floats(np.pi - 1e-6, np.pi)),
       theta_dot=st.one_of(st.floats(0.0, 5.0), st.floats(0.0, 1e-20)),
       phi_dot=st.one_of(st.floats(-5.0, 5.0), st.floats(-1e-20, 1e-20)),
       psi_dot=st.one_of(st.floats(-50.0, 50.0), st.floats(-1e6, 1e6)), I3=st.floats(0.05, 1.9))
def test_random_sweep_against_reference(theta, theta_dot, phi_dot, psi_dot, I3):
    check_motion(dict(TOP, I3=I3), dict(theta=theta, theta_dot=theta_dot, phi_dot=phi_dot, psi_dot=psi_dot), n=7)


# --- the error estimate: measured, lazy, and it catches a wrong constant ----------------------------

GENERAL = dict(theta=1.0, phi=0.3, psi=-0.2, theta_dot=0.4, phi_dot=0.7, psi_dot=3.0)


def _plant(top, what: str) -> None:
    """Make one constant of the closed form wrong (relative 1e-9 .. 1e-10), after it is computed."""
    from mechderive.core.phase import DD
    from mechderive.systems.heavy_top.exact import _Angle

    def replace(spec: _Angle, **changes) -> _Angle:
        return _Angle(**{k: changes.get(k, getattr(spec, k)) for k in _Angle.__slots__})

    if what == "phase rate κ":
        k = top._kappa
        object.__setattr__(top, "_kappa", DD(k.hi * (1 + 1e-10), k.lo))
        return
    angles = dict(top._angles)
    spec = angles["phi"]
    (c, n, pi0), *rest = spec.terms
    if what == "Π coefficient":
        spec = replace(spec, terms=((c * (1 + 1e-9), n, pi0), *rest))
    elif what == "Π at the start":
        spec = replace(spec, terms=((c, n, pi0 * (1 + 1e-9)), *rest))
    elif what == "advance per period":
        spec = replace(spec, per_period=DD(spec.per_period.hi * (1 + 1e-9), 0.0))
    angles["phi"] = spec
    top.__dict__["_angles"] = angles


@functools.cache
def _general_run() -> tuple:
    """Times past the first nutation period (the advance per period enters), the honest estimate, the reference."""
    top = exact_heavy_top(TOP, GENERAL)
    t = np.linspace(0.0, 2.5 * top.nutation_period, 9)
    return t, top.error_estimate(t, ["phi", "R"]), heavy_reference(TOP, GENERAL, t)


@pytest.mark.parametrize("what", ["phase rate κ", "Π coefficient", "Π at the start", "advance per period"])
def test_estimate_catches_a_planted_wrong_constant(what):
    t, honest, ref = _general_run()
    top = exact_heavy_top(TOP, GENERAL)
    _plant(top, what)
    out = top.evaluate(t, ["phi", "R", "theta"])
    actual = {"phi": np.max(np.abs(_wrap(out["phi"] - ref.angles[:, 0]))), "R": np.max(np.abs(out["R"] - ref.R)),
              "theta": np.max(np.abs(out["theta"] - ref.angles[:, 1]))}
    worst = max(actual.values())
    # the plant is felt (an error far above the closed form's ~1e-15) and the estimate says so
    assert worst > max(1e-11, 30 * honest), (worst, honest)
    for q, e in actual.items():
        if e > 1e-13:
            assert top.error_estimate(t, [q]) >= e, (what, q, e)


def test_estimate_for_theta_evaluates_no_angle():
    # principle 3: θ needs sn, cn of the phase; its estimate (the residual of u̇² = f(u), the start)
    # must not derive or evaluate the partial fractions and Π of φ and ψ.
    top = exact_heavy_top(TOP, dict(theta=0.5, psi_dot=5.0))
    t = np.linspace(0.0, 10.0, 50)
    top.evaluate(t, ["theta"])
    estimate = top.error_estimate(t, ["theta"])
    assert "_angles" not in top.__dict__ and "_angle_fractions" not in top.__dict__
    assert not any(k.startswith(("pi(", "half", "kappa/q")) for k in top._mp["last_pass"]._cache)
    # measured on the run, not a constant: θ to a few ulp here (rounding of sn², 1 ∓ u, the arctangent)
    assert 0 < estimate < 1e-14
    # asking for φ brings in the angle constants (and only then)
    assert top.error_estimate(t, ["phi"]) < 1e-12 and "_angles" in top.__dict__


def test_estimate_grows_with_the_size_of_the_continuous_angles():
    # ψ after ~1000 nutation periods is ~1.6e4 rad: its own ulp (3.6e-12) must be in the estimate.
    # The wrapped ψ is reduced in double-double (error ~1e-15), but the check can only confirm the
    # advance per period to the quadrature's rounding, ~4ε·|Δψ per period| × 1000 periods ≈ 1.4e-11.
    top = exact_heavy_top(TOP, dict(theta=0.5, psi_dot=5.0))
    t = np.array([0.0, 1000.3 * top.nutation_period])
    psi = top.evaluate(t, ["psi"])["psi"]
    assert top.error_estimate(t, ["psi"]) >= 4 * np.spacing(abs(psi[-1]))
    assert top.error_estimate(t, ["psi_wrapped"]) < 1e-10


def test_the_written_out_gauss_legendre_rule_is_the_derived_one():
    """The error estimate's panel rule (written out) against its derivation: the eigenvalues of the Jacobi
    matrix (Golub and Welsch 1969), then Newton's method on P_n by the three-term recurrence (DLMF 18.9.1),
    and at 40 digits: the nodes to an ulp, the weights to 2e-14 relative."""
    from mechderive.systems.heavy_top.estimate import _NODES, _gauss_legendre

    def recurrence(x):
        p0, p1 = np.ones_like(x), x
        for k in range(2, _NODES + 1):
            p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
        return p1, _NODES * (x * p1 - p0) / (x * x - 1)  # P_n, P_n'

    k = np.arange(1, _NODES)
    off = k / np.sqrt(4.0 * k * k - 1.0)
    x = np.linalg.eigvalsh(np.diag(off, 1) + np.diag(off, -1))[::-1]
    for _ in range(10):
        p, dp = recurrence(x)
        step = p / dp
        x = x - step
        if np.max(np.abs(step)) <= 1e-15:
            break
    _, dp = recurrence(x)
    nodes, weights = _gauss_legendre()
    # (to a few ulp, not bit for bit: LAPACK's eigenvalues, Newton's start, may differ by an ulp between builds)
    assert np.max(np.abs(nodes - x[::-1])) <= 4 * np.spacing(1.0)
    assert np.max(np.abs(weights / (2 / ((1 - x[::-1] ** 2) * dp[::-1] ** 2)) - 1)) <= 2e-14
    with mpmath.workdps(40):  # the same Newton iteration at 40 digits
        for x0, w0 in zip(nodes.tolist(), weights.tolist()):
            xm = mpmath.mpf(x0)
            for _ in range(4):
                p0, p1 = mpmath.mpf(1), xm
                for k in range(2, _NODES + 1):
                    p0, p1 = p1, ((2 * k - 1) * xm * p1 - (k - 1) * p0) / k
                dp = _NODES * (xm * p1 - p0) / (xm * xm - 1)
                xm = xm - p1 / dp
            assert abs(x0 - xm) <= 1e-16 and abs(w0 / (2 / ((1 - xm * xm) * dp * dp)) - 1) <= 2e-14
