"""The heavy symmetric top's motion in closed form (section 3.6).

What is evaluated (derivation in :mod:`.exact_model` and :mod:`.model`)
----------------------------------------------------------------------
With u = cos θ, the derived cubic u̇² = f(u) = β (u - u1)(u - u2)(u - u3) has
u1 ≤ u(t) ≤ u2 ≤ 1 ≤ u3, and

    u(t) = u1 + (u2 - u1) sn²(v | m),    v = κ t + v0,
    κ² = β (u3 - u1) / 4,   m = (u2 - u1)/(u3 - u1),   1 - m = (u3 - u2)/(u3 - u1),

so the nutation period is 2K(m)/κ.  θ is formed without cancellation from
1 - u = (1 - u2) + (u2 - u1) cn² and 1 + u = (1 + u1) + (u2 - u1) sn².
The precession and spin angles integrate the partial fractions of φ̇(u) and
ψ̇(u) (3.74)–(3.75):

    φ(t) - φ0 = (c0/κ)(v - v0) + Σ_i (c_i/κ) [Π(n_i; am v | m) - Π(n_i; am v0 | m)],

with the characteristics n₊ = (u2 - u1)/(1 - u1) and n₋ = -(u2 - u1)/(1 + u1).

Long times: every constant is computed once at 40 digits from the exact binary
inputs; v is formed and reduced by the period 2K in double-double, giving an exact
count j of nutation periods, and φ, ψ gain j·Δφ, j·Δψ (double-double, reduced
mod 2π for R).  Evaluating at 10⁶ nutation periods therefore costs and errs as at
one, apart from the rounding of t itself.

Boundary cases: a double root u1 = u2 (uniform precession, including the sleeping
top at θ = 0) is a steady motion with constant rates; near it the amplitude u2 - u1
and m are small but the formulas hold.  When the apex passes exactly through the
pole (u2 = 1, so b = a) the n₊ term has a zero coefficient and is dropped; when it
passes *near* the pole, n₊ → 1 and φ turns by almost π in a short time — correct,
but φ, ψ are then ill-conditioned functions of time (their sum stays accurate); the
``conditioning`` attribute reports 1/(1 - n₊), the factor by which errors in t are
amplified in φ there (near the bottom likewise 1 - n₋, with φ - ψ accurate).  R, the apex
and ω are well conditioned through such passages and are formed so: from the half sums and
differences (φ ± ψ)/2, their rates, and (sin θ/2, cos θ/2); 1 - u2, 1 + u1 and the advance per
period are computed with as many extra digits as the passage needs, and Π(n₊) from 1 - n₊ itself.

Edges (issue 11; tests/test_s3_6_heavy_top_edges.py sweeps them against 30-digit references).
sn, cn, dn are taken at the distance of the phase from the nearest turning point, formed in
double-double (and from δ0 = v0 − turning point at the setup's precision near the start), so
that 1 ∓ u keeps its digits next to the pole and the bottom; b ∓ a comes from the state in half
angles (so θ0 = 1e-30 is not mistaken for a passage through the pole); φ̇ and ψ̇ are output from
(3.74)–(3.75) in 1 ∓ u; Π(n; am r0) at the start is evaluated by the path every sample takes, so
φ(0) = φ0.  Refused, with an :class:`~mechderive.errors.InvalidInputError` saying why: θ̇ < 0 at
θ = 0 (θ cannot leave [0, π]; the same motion has θ̇ > 0 and φ, ψ turned by π), and motions whose
apex comes within ~1e-75 rad of the pole or the bottom without passing through it (1 ∓ cos θ
below 1e-150: Carlson's integrals of the passage under- or overflow in double precision).  On
the pole (θ0 = 0) only φ + ψ and φ̇ + ψ̇ are defined; φ̇(0), ψ̇(0) are then the motion's limits.
:meth:`HeavyTopSolution.error_estimate` measures each run's error (:mod:`.estimate`).
"""

from __future__ import annotations

import functools
import math
from typing import Any, Mapping

import numpy as np

from ...core.validate import as_finite_array
from ...errors import DerivationError, InvalidInputError
from ...core.codecache import cached_lambdify
from ...core.phase import DD, mod_two_pi
from ...special._doubledouble import dd_add, two_prod
from .parameters import check_initial, check_params

__all__ = ["HeavyTopSolution", "exact_heavy_top"]

_DPS = 40


def _build_state():
    from . import model as hm

    cfs = hm.model().constants_from_state
    return [*hm.PARAMETERS, *hm.STATE], [cfs[k] for k in (hm.a, hm.b, hm.alpha, hm.beta)]


def _build_f():
    from . import model as hm

    return [hm.a, hm.b, hm.alpha, hm.beta], list(hm.model().f_coefficients)


def _build_nutation():
    from . import exact_model as em
    from . import model as hm

    nut = em.model().nutation_constants
    return [hm.beta, em.u1, em.u2, em.u3], [nut["kappa2"], nut["m"], nut["m1"]]


def _build_gaps():
    from . import model as hm

    return [*hm.PARAMETERS, *hm.STATE], list(hm.model().passage_factors)


#: (label, build) of u(t)'s derived constants; compiled for mpmath here, for NumPy by :mod:`.batch`
NUTATION_BUILDS = (("heavy_top.constants_from_state", _build_state), ("heavy_top.passage_factors", _build_gaps),
                   ("heavy_top.f_coefficients", _build_f), ("heavy_top.nutation_constants", _build_nutation))


@functools.cache
def _nutation_functions():
    """The derived constants of u(t) as mpmath functions, compiled once (through the disk cache)."""
    import mpmath  # noqa: F401 - the compiled functions run in its namespace

    state, gaps, cubic, nutation = (cached_lambdify(label, build, module="mpmath")[0]
                                    for label, build in NUTATION_BUILDS)
    return {"state": state, "f": cubic, "nutation": nutation, "gaps": gaps}


def angle_function_jobs(*, angles: bool = True, rates: bool = True) -> list[tuple]:
    """(name, build, module) of what φ and ψ need beyond u(t): the partial fractions of φ̇ and ψ̇
    (:func:`_angle_functions`, with ``angles``) and the rates near the poles (:func:`_derived_rates`, with
    ``rates``: φ̇, ψ̇ and the angles' error estimate), for :func:`mechderive.core.codecache.prefetch`: a cold
    start derives them on a second core while this one derives u(t)'s constants."""
    from .exact_extended import fraction_jobs

    # the partial fractions as the extended-precision setup takes them (:mod:`.exact_extended`, the warm
    # run's path); the 40-digit path compiles its mpmath ones when it is taken
    jobs = fraction_jobs() if angles else []
    return jobs + ([("heavy_top.rates_near_poles", _rates_build, "numpy")] if rates else [])


def _fraction_build(which: str):
    def inner():
        from . import exact_model as em
        from . import model as hm

        fr = getattr(em.model(), which)
        flat = [fr["c0"]] + [x for c, n in fr["terms"] for x in (c, n)]
        return [hm.I1, hm.I3, hm.a, hm.b, em.u1, em.u2, em.u3], flat
    return inner


@functools.cache
def _angle_functions():
    """Partial fractions of φ̇ and ψ̇ along u(t) — derived only when φ or ψ is asked for.

    Each is an mpmath function of (I1, I3, a, b, u1, u2, u3) returning [c0, c_1, n_1, c_2, n_2, ...].
    """
    return {name: cached_lambdify(f"heavy_top.{which}", _fraction_build(which), module="mpmath")[0]
            for name, which in (("phi", "precession_fractions"), ("psi", "spin_fractions"))}


@functools.cache
def _omega_half_angles():
    """Body ω (3.58) as a function of (σ, δ, s, c, σ̇, δ̇, θ̇), derived from the chapter's form.

    σ = (φ + ψ)/2, δ = (φ - ψ)/2 and (s, c) ∝ (sin θ/2, cos θ/2) with any common factor, so that
    sin θ = 2sc/(s² + c²), cos θ = (c² - s²)/(s² + c²).  This is what R is built from: near the
    pole φ̇ and ψ̇ grow like 1/(1 - n₊ sn²) and φ̇ cos θ + ψ̇ cancels (near the bottom φ̇ sin θ
    from a θ rounded next to π loses digits); here ω3 = 2(σ̇ c² - δ̇ s²)/(s² + c²), where the
    large part of δ̇ (σ̇) comes multiplied by s² (c²), with nothing cancelling.
    """
    def build():
        import sympy as sp

        from ...core.symbols import state_symbol
        from ...kinematics import euler

        sig, dlt, s, c, sd, dd, thd = sp.symbols("sigma delta s c sigma_dot delta_dot theta_dot", real=True)
        th = state_symbol("theta")
        w = euler.model().state_angular_velocity_body.subs({
            state_symbol("phi"): sig + dlt, state_symbol("psi"): sig - dlt, state_symbol("phi_dot"): sd + dd,
            state_symbol("psi_dot"): sd - dd, state_symbol("theta_dot"): thd})
        w = w.subs({sp.sin(th): 2 * s * c / (s**2 + c**2), sp.cos(th): (c**2 - s**2) / (s**2 + c**2)})
        if th in w.free_symbols:
            raise DerivationError(f"expected ω (3.58) in sin θ and cos θ only, got {w}")
        return [sig, dlt, s, c, sd, dd, thd], w.applyfunc(lambda e: sp.factor(sp.together(e)))

    return cached_lambdify("heavy_top.omega_half_angles", build, module="numpy")[0]


@functools.cache
def _derived_rates():
    """[φ̇, ψ̇, (φ̇ + ψ̇)/2, (φ̇ − ψ̇)/2] (3.74)–(3.75) in (I1, I3, b − a, b + a, 1 − u, 1 + u), derived.

    The rates the solution outputs (:meth:`_Pass.derived_rates`): 1 ∓ u and b ∓ a enter with full
    relative accuracy, so nothing cancels near the pole or the bottom (the partial fractions in
    sn² have terms ~1/(1 − n₊) that cancel there).  The half sum and difference are simplified
    symbolically, so the 1/(1 − u) spike of a near pole passage (1/(1 + u) near the bottom) is
    absent from the one it cancels in, not cancelled in floating point.
    """
    return cached_lambdify("heavy_top.rates_near_poles", _rates_build, module="numpy")[0]


def _rates_build():
    import sympy as sp

    from ...core.simplify import factor
    from . import model as hm

    phi_dot, psi_dot = hm.model().rates_near_poles
    x, y = sp.symbols("x_pole y_bottom", real=True)
    # each coefficient by the project's factor: sympy.factor's expression (checked against it, tests/test_core.py),
    # without proving small polynomials irreducible by Wang's algorithm (most of this job's time in the child)
    half = [sp.collect(sp.expand((phi_dot + s * psi_dot) / 2), [x, y], factor) for s in (1, -1)]
    dm, dp = sp.symbols("d_minus d_plus", real=True)
    return [hm.I1, hm.I3, dm, dp, x, y], [phi_dot, psi_dot, *half]


class _Angle:
    """The closed form of one precession-type angle: start, linear part, Π terms, advance per period.

    A plain record (a frozen dataclass's generated methods, or a named tuple's, cost ~1 ms and ~0.2 ms of every
    warm run's imports)."""

    __slots__ = ("name", "start", "c0_over_kappa", "terms", "per_period", "rate")

    def __init__(self, name: str, start: float, c0_over_kappa: float,
                 terms: tuple[tuple[float, float, float], ...], per_period: DD | None, rate: float) -> None:
        self.name, self.start, self.c0_over_kappa = name, start, c0_over_kappa
        self.terms = terms  # (c_i/κ, n_i, Π(n_i; am v0 | m))
        self.per_period = per_period
        self.rate = rate  # for steady motion: the constant rate


class _Pass:
    """One evaluation at an array of times: shared intermediates computed at most once, on demand.

    ``computed`` lists what was evaluated, in order (the laziness tests read it).
    """

    def __init__(self, sol: "HeavyTopSolution", t: np.ndarray) -> None:
        self.sol, self.t = sol, t
        self.computed: list[str] = []
        self._cache: dict[str, Any] = {}

    def _get(self, key: str, make):
        if key not in self._cache:
            self._cache[key] = make()
            self.computed.append(key)
        return self._cache[key]

    def phase(self):
        """(j, r): v = j·2K + r, r in [0, 2K) (r rounded to a double)."""
        return self.phase_dd()[:2]

    def phase_dd(self):
        """(j, r_hi, r_lo): the reduced phase as a double-double."""
        return self._get("phase", lambda: self.sol._phase_dd(self.t))

    def jacobi(self):
        """sn, cn, dn of the reduced phase r."""
        return self.reduced_jacobi()[:3]

    def reduced_jacobi(self):
        """sn, cn, dn of r and the half-period count j' of r = j'·2K + r', |r'| <= K, shared by θ and Π.

        Each to a few ulp *relative*, also next to the turning points: sn, cn, dn are taken at the
        distance δ of r from the nearest of 0, K, 2K (:meth:`turning`), with DLMF 22.4.iii:
        sn(K + δ) = cd δ, cn(K + δ) = -k' sd δ, dn(K + δ) = k' nd δ; sn(2K + δ) = -sn δ,
        cn(2K + δ) = -cn δ.  Next to the pole u2 ≈ 1, 1 - u = (1 - u2) + (u2 - u1) cn² then keeps
        its digits; from r rounded to a double, cn near K would carry an absolute error ulp(K) — a
        relative error 1e-16/|cn| in cn, and in φ̇, ψ̇ ∝ 1/(1 - u) (at θ0 = 1e-16 φ̇(0) came out
        0.75 rad/s off).
        """
        from ...special._sncndn import reduced_sn_cn_dn

        def make():
            p = self.sol._jacobi_parameter
            if self.sol._period is None:  # m = 1: no period, r is the phase itself
                _, rh, rl = self.phase_dd()
                return reduced_sn_cn_dn(np.asarray(rh + rl, dtype=float), p)[:4]
            kind, xh, xl = self.turning()
            sx, cx, dx = reduced_sn_cn_dn(xh + xl, p)[:3]
            kc = np.sqrt(p.m1 + p.m1_lo)
            at0, atK = kind == 0, kind == 1
            sn = np.where(at0, sx, np.where(atK, cx / dx, -sx))
            cn = np.where(at0, cx, np.where(atK, -kc * sx / dx, -cx))
            dn = np.where(at0, dx, np.where(atK, kc / dx, dx))
            past_K = (kind == 2) | (atK & ((xh > 0) | ((xh == 0) & (xl > 0))))  # r = 2K + r', r' in (-K, 0]
            return sn, cn, dn, past_K.astype(float)
        return self._get("jacobi", make)

    def turning(self):
        """(kind, x_hi, x_lo): r = kind·K + x with kind 0, 1, 2 the nearest of 0, K, 2K, x in double-double.

        From the double-double phase, x is known to ~1e-32·|v| absolutely.  Near the start that is
        not enough when θ0 is within ~1e-30 of a turning point (1 - u0 ~ 1e-60 next to the pole):
        there x comes from w = κt + δ0, δ0 = v0 - (the turning point next to v0) computed at the
        setup's precision with its full relative accuracy, so that x(0) = δ0 (and θ̇(0), φ̇(0)
        are reproduced); the two agree to ~1e-32 wherever both apply.
        """
        def make():
            sol = self.sol
            j, rh, rl = self.phase_dd()
            per = sol._period
            Kh, Kl = 0.5 * per.hi, 0.5 * per.lo
            kind = np.where(rh <= 0.5 * Kh, 0, np.where(rh >= 1.5 * Kh, 2, 1))
            xh, xl = dd_add(rh, rl, -kind * Kh, -kind * Kl)
            anchor, dv0 = sol._mp.get("anchor"), sol._mp.get("dv0")
            if anchor is not None:
                k = sol._kappa
                wh, wl = two_prod(k.hi, self.t)
                wl = wl + k.lo * self.t
                wh, wl = dd_add(wh, wl, dv0.hi, dv0.lo)
                small = np.abs(wh) <= 0.25 * Kh
                w_kind = np.full(np.shape(wh), 1) if anchor else np.where((wh > 0) | ((wh == 0) & (wl >= 0)), 0, 2)
                kind = np.where(small, w_kind, kind)
                xh, xl = np.where(small, wh, xh), np.where(small, wl, xl)
            return kind, xh, xl
        # part of the Jacobi step (not listed in ``computed`` on its own)
        if "turning" not in self._cache:
            self._cache["turning"] = make()
        return self._cache["turning"]

    def amplitude(self):
        from ...special.jacobi import jacobi_am

        return self._get("am", lambda: np.asarray(jacobi_am(self.phase()[1], self.sol.m, m1=self.sol.m1)))

    def pi(self, n: float):
        """Π(n; am r | m) for the characteristic ``n`` (after :meth:`pis`, which batches them)."""
        self.pis([n])
        return self._cache[f"pi({n!r})"]

    def pis(self, ns) -> None:
        """Π(n; am r | m) for every n in ``ns`` not yet computed, straight from the phase r.

        Usually from the motion's Fourier series of Π (:mod:`mechderive.special.pi_series`, fitted
        once per motion, ~6× cheaper at thousands of phases); where that series converges too
        slowly (a passage near the pole, m near 1), by Carlson's form, one call for all n sharing
        sn, cn, dn of r — going through am(r) would amplify its rounding by 1/dn near the turning
        points when m → 1.
        """
        one_minus_n = self.sol._mp.get("one_minus_n", {})
        batch = []
        for n in ns:
            if f"pi({n!r})" in self._cache:
                continue
            n1 = one_minus_n.get(n)
            if n1 is not None and n1 < 1e-3 and self.sol._period is not None:
                self._get(f"pi({n!r})", lambda: self._pi_near_one(n, n1))
            else:
                batch.append(n)
        series = self.sol._pi_series() if batch else None
        if series is not None and all(n in series.n for n in batch):
            shape = np.shape(self.phase()[1])
            values = series(np.reshape(self.phase()[1], (-1,)))
            for n, value in zip(series.n.tolist(), values):
                if n in batch:
                    self._get(f"pi({n!r})", lambda: value.reshape(shape))
        elif batch:
            from ...special.integrals import pi_of_am  # (here: the series' motions never load the integrals)

            shape = np.shape(self.phase()[1])
            flat = [np.reshape(x, (1, -1)) for x in self.reduced_jacobi()]
            values = np.asarray(pi_of_am(np.array(batch)[:, None], np.reshape(self.phase()[1], (1, -1)),
                                         self.sol.m, m1=self.sol.m1, jacobi=tuple(flat)))
            for n, value in zip(batch, values):
                self._get(f"pi({n!r})", lambda: value.reshape(shape))

    def _pi_near_one(self, n: float, n1: float) -> np.ndarray:
        """Π(n; am r | m) for n close to 1 with 1 - n = ``n1`` known to full relative accuracy.

        Near a pole passage 1 - n₊ = (1 - u2)/(1 - u1) is tiny; forming it as 1 - float(n) would
        lose its digits (1e-16/(1 - n) relative).  DLMF 19.25.14 in Carlson's form with
        1 - n sn² = cn² + (1 - n) sn², and Π(n; π - A) = 2Π(n) - Π(n; A) past r = K.
        """
        from ...special._carlson import elliprj

        sn, cn, dn, past = self.reduced_jacobi()
        kind, xh, xl = self.turning()
        per = self.sol._period
        K = per.hi / 2
        sn3 = np.abs(sn) ** 3
        # which side of K, and r or 2K - r, from r = kind·K + x: within ulp(K) of the passage a
        # rounded r would pick the wrong branch (an error of the whole jump 2Π(n), ~π in φ)
        r_hi, r_lo = dd_add(kind * K, kind * 0.5 * per.lo, xh, xl)
        rest_hi, rest_lo = dd_add(per.hi, per.lo, -r_hi, -r_lo)
        with np.errstate(all="ignore"):
            half = n / 3 * sn3 * elliprj(cn * cn, dn * dn, 1.0, cn * cn + n1 * sn * sn)
            complete = K + n / 3 * float(elliprj(0.0, self.sol.m1, 1.0, n1))
        return np.where(past == 0, (r_hi + r_lo) + half, 2 * complete - ((rest_hi + rest_lo) + half))

    def half_theta(self):
        """(sin θ/2, cos θ/2) up to a common positive factor, *signed* through exact passages.

        When the apex passes exactly through the pole (u2 = 1) or the bottom (u1 = -1),
        √(1 - u) = √(u2 - u1)|cn| (resp. √(1 + u) = √(u2 - u1)|sn|); keeping the sign of cn (sn)
        continues the motion through the passage (θ → -θ), instead of bouncing back.
        """
        def make():
            sn, cn, _ = self.jacobi()
            one_minus, one_plus = self.one_minus_plus_u()
            s, c = np.sqrt(one_minus), np.sqrt(one_plus)
            # sn, cn are of r = v - j·2K; sn(v) = (-1)^j sn(r), cn(v) = (-1)^j cn(r)
            parity = 1.0 - 2.0 * np.mod(self.phase()[0], 2.0)
            if self.sol._one_minus_u2 == 0.0:
                s = self.sol._mp["pole_sign"] * np.sqrt(self.sol._amp) * cn * parity
            if self.sol._one_plus_u1 == 0.0:
                c = self.sol._mp["bottom_sign"] * np.sqrt(self.sol._amp) * sn * parity
            return s, c
        return self._get("half_theta", make)

    def passages(self):
        """Exact passages through the pole or the bottom since t = 0 (each turns φ and ψ by π for θ ≥ 0)."""
        def make():
            sol = self.sol
            if sol._one_minus_u2 != 0.0 and sol._one_plus_u1 != 0.0:
                return np.zeros(self.t.shape)
            j, r = self.phase()
            half = sol._period.hi / 2  # K: the pole at v = K (mod 2K), the bottom at v = 0 (mod 2K)
            # the phase at t = 0 by the same arithmetic: v0 = F(A0|m) lies in [-K, K], so its period
            # count j0 is -1 when the start is just before a bottom passage (v0 < 0)
            j0, r0 = (float(x[0]) for x in sol._at_start.phase())
            count = np.zeros(self.t.shape)
            if sol._one_minus_u2 == 0.0:
                count = count + (j + (r >= half)) - (j0 + (r0 >= half))
            if sol._one_plus_u1 == 0.0:
                count = count + (j + (r > 0)) - (j0 + (r0 > 0))
            return count
        return self._get("passages", make)

    def one_minus_plus_u(self):
        def make():
            sn, cn, _ = self.jacobi()
            return self.sol._one_minus_u2 + self.sol._amp * cn**2, self.sol._one_plus_u1 + self.sol._amp * sn**2
        return self._get("1-u,1+u", make)

    def angle(self, spec: _Angle, *, reduced: bool) -> np.ndarray:
        """φ or ψ (``spec``) at the pass's times, continuous or (``reduced``) with its whole periods reduced
        modulo 2π; computed once per pass (read-only): the output and the error estimate's angle checks,
        which check the very values output, share it.  (Not listed in ``computed``: a combination of what is.)"""
        key = f"angle({spec.name},{reduced})"
        if key not in self._cache:
            value = self._angle(spec, reduced)
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            self._cache[key] = value
        return self._cache[key]

    def _angle(self, spec: _Angle, reduced: bool) -> np.ndarray:
        sol, t = self.sol, self.t
        if sol.kind == "steady":
            return spec.start + (mod_two_pi(spec.rate, t) if reduced else spec.rate * t)
        j, rh, rl = self.phase_dd()
        j0, r0h, r0l = sol._phase0
        j = j - j0  # periods since t = 0; Π(n; am r0) is the terms' pi0
        # r - r0 from the double-double phases (rh - r0h exact when close): r ~ K, whose ulp would
        # otherwise show at t = 0 (R(0) was 18 ulp off at K = 140)
        value = spec.start + spec.c0_over_kappa * ((rh - r0h) + (rl - r0l))
        self.pis([n for _, n, _ in spec.terms])
        for c, n, pi0 in spec.terms:
            value = value + c * (self.pi(n) - pi0)
        if spec.per_period is None:
            return value
        per = spec.per_period  # at 40 digits: j·Δ must not carry j·ulp(Δ) far out
        if reduced:
            return value + mod_two_pi(per, j)
        return value + j * (per.hi + per.lo)

    def half_angle(self, a: _Angle, b: _Angle, sign: int) -> np.ndarray:
        """(a ± b)/2, reduced modulo 2π in double-double; terms with a common characteristic combined
        first, so that a term cancelling in the sum (n₊ in φ + ψ, n₋ in φ - ψ) is never evaluated."""
        return self._get(f"half({a.name},{b.name},{sign})", lambda: self._half_angle(a, b, sign))

    @staticmethod
    def _combined(a: _Angle, b: _Angle, sign: int) -> tuple[float, dict, dict]:
        """c0/κ and the Π coefficients of (a ± b)/2 by characteristic (and Π(n; am v0) per n)."""
        coeffs: dict[float, float] = {}
        pi0s: dict[float, float] = {}
        for spec, w in ((a, 0.5), (b, 0.5 * sign)):
            for c, n, pi0 in spec.terms:
                coeffs[n] = coeffs.get(n, 0.0) + w * c
                pi0s[n] = pi0
        return 0.5 * (a.c0_over_kappa + sign * b.c0_over_kappa), coeffs, pi0s

    def _half_angle(self, a: _Angle, b: _Angle, sign: int) -> np.ndarray:
        sol = self.sol
        j, rh, rl = self.phase_dd()
        j0, r0h, r0l = sol._phase0
        j = j - j0
        c0, coeffs, pi0s = self._combined(a, b, sign)
        value = 0.5 * (a.start + sign * b.start) + c0 * ((rh - r0h) + (rl - r0l))
        self.pis([n for n, c in coeffs.items() if c != 0.0])
        for n, c in coeffs.items():
            if c != 0.0:
                value = value + c * (self.pi(n) - pi0s[n])
        if a.per_period is not None:
            per_a, per_b = a.per_period, b.per_period
            hi, lo = dd_add(per_a.hi, per_a.lo, sign * per_b.hi, sign * per_b.lo)  # exact sum, then exact halving
            per = DD(0.5 * float(hi), 0.5 * float(lo))
            value = value + mod_two_pi(per, j)
        return value

    def rate(self, spec: _Angle) -> np.ndarray:
        """φ̇ or ψ̇: the derivative of :meth:`angle`, κ(c0/κ + Σ (c_i/κ)/(1 - n_i sn²))."""
        sol = self.sol
        if sol.kind == "steady":
            return np.full(self.t.shape, spec.rate)
        kappa = sol._kappa.hi + sol._kappa.lo
        value = np.full(self.t.shape, spec.c0_over_kappa * kappa)
        for c, n, _ in spec.terms:
            value = value + c * self._kappa_over_q(n)
        return value

    def derived_rates(self) -> list[np.ndarray]:
        """[φ̇, ψ̇, (φ̇ + ψ̇)/2, (φ̇ − ψ̇)/2] from u(t) by (3.74)–(3.75) (:func:`_derived_rates`).

        At an exact passage b ∓ a = 0 and its term is absent (1 ∓ u may be 0 there).
        """
        def make():
            v = self.sol._mp
            x, y = self.one_minus_plus_u()
            dm, dp = v["d_minus"], v["d_plus"]
            x = np.where(x == 0, 1.0, x) if dm == 0 else x
            y = np.where(y == 0, 1.0, y) if dp == 0 else y
            with np.errstate(divide="ignore", invalid="ignore"):
                out = _derived_rates()(float(v["I1"]), float(v["I3"]), dm, dp, x, y)
            return [np.broadcast_to(np.asarray(r, dtype=float), np.shape(x)) for r in out]
        return self._get("rates", make)

    def half_rate(self, a: _Angle, b: _Angle, sign: int) -> np.ndarray:
        """d/dt of :meth:`half_angle`: its combined terms, so (φ̇ + ψ̇)/2 has no n₊ term, (φ̇ - ψ̇)/2 no n₋."""
        c0, coeffs, _ = self._combined(a, b, sign)
        value = np.full(self.t.shape, c0 * (self.sol._kappa.hi + self.sol._kappa.lo))
        for n, c in coeffs.items():
            if c != 0.0:
                value = value + c * self._kappa_over_q(n)
        return value

    def _kappa_over_q(self, n: float) -> np.ndarray:
        """κ/(1 - n sn²), the rate of Π(n; am v | m) in t."""
        def make():
            sn, cn, _ = self.jacobi()
            n1 = self.sol._mp.get("one_minus_n", {}).get(n, 1.0)
            # near the pole 1 - n₊ sn² = cn² + (1 - n₊) sn² keeps the digits 1 - float(n₊) has lost
            q = cn**2 + n1 * sn**2 if n1 < 1e-3 else 1 - n * sn**2
            return (self.sol._kappa.hi + self.sol._kappa.lo) / q
        return self._get(f"kappa/q({n!r})", make)


#: The quantities :meth:`HeavyTopSolution.evaluate` knows (each an array over t; R is (..., 3, 3),
#: apex and omega (..., 3)).
QUANTITIES = ("u", "u_dot", "theta", "theta_dot", "phi", "psi", "phi_wrapped", "psi_wrapped", "phi_dot", "psi_dot",
              "R", "apex", "omega")


class HeavyTopSolution:
    """The closed-form motion of one heavy symmetric top; methods take arrays of times (s).

    Attributes: ``kind`` ('nutating' or 'steady'), ``roots`` (u1, u2, u3), ``m``, ``m1``,
    ``nutation_period`` (s; nan when steady), ``motion_class`` (see :func:`classify`),
    ``energy``, ``p_phi``, ``p_psi`` (the conserved quantities, from the initial state),
    ``conditioning`` (1/(1 - n₊): error amplification in φ, ψ near the pole).

    Only what is asked for is computed: θ(t) needs sn, cn of the reduced phase; φ(t) and ψ(t)
    need the amplitude and Π, and their constants (including the partial fractions of φ̇, ψ̇)
    are derived and computed on the first request for either.

    Immutable, with the ``__init__``, ``repr`` and ``==`` a frozen dataclass would have: written out,
    because generating those methods (one ``exec`` each) took ~3 ms of every warm ``mechderive run``.
    """

    parameters: dict
    initial: dict
    kind: str
    roots: tuple[float, float, float]
    m: float
    m1: float
    nutation_period: float
    conditioning: float
    motion_class: str
    energy: float
    p_phi: float
    p_psi: float
    f_coefficients: tuple[float, float, float, float]  # of u³, u², u, 1 in f(u) (3.73)
    _kappa: DD
    _v0: DD
    _period: DD | None  # 2K in v
    _u1: float
    _amp: float  # u2 - u1
    _one_minus_u2: float
    _one_plus_u1: float
    _theta_const: float
    _mp: dict  # 40-digit (or extended-precision) setup values for the lazy angle constants; not in the repr

    #: the fields, in the order ``__init__`` takes them
    _FIELDS = ("parameters", "initial", "kind", "roots", "m", "m1", "nutation_period", "conditioning", "motion_class",
               "energy", "p_phi", "p_psi", "f_coefficients", "_kappa", "_v0", "_period", "_u1", "_amp",
               "_one_minus_u2", "_one_plus_u1", "_theta_const", "_mp")

    def __init__(self, parameters: dict, initial: dict, kind: str, roots: tuple[float, float, float], m: float,
                 m1: float, nutation_period: float, conditioning: float, motion_class: str, energy: float,
                 p_phi: float, p_psi: float, f_coefficients: tuple[float, float, float, float], _kappa: DD, _v0: DD,
                 _period: DD | None, _u1: float, _amp: float, _one_minus_u2: float, _one_plus_u1: float,
                 _theta_const: float, _mp: dict | None = None) -> None:
        self.__dict__.update(
            parameters=parameters, initial=initial, kind=kind, roots=roots, m=m, m1=m1,
            nutation_period=nutation_period, conditioning=conditioning, motion_class=motion_class, energy=energy,
            p_phi=p_phi, p_psi=p_psi, f_coefficients=f_coefficients, _kappa=_kappa, _v0=_v0, _period=_period,
            _u1=_u1, _amp=_amp, _one_minus_u2=_one_minus_u2, _one_plus_u1=_one_plus_u1, _theta_const=_theta_const,
            _mp={} if _mp is None else _mp)

    def __setattr__(self, name: str, value: Any) -> None:
        from dataclasses import FrozenInstanceError

        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        from dataclasses import FrozenInstanceError

        raise FrozenInstanceError(f"cannot delete field {name!r}")

    def _values(self) -> tuple:
        return tuple(self.__dict__[k] for k in self._FIELDS)

    def __repr__(self) -> str:
        shown = ", ".join(f"{k}={self.__dict__[k]!r}" for k in self._FIELDS if k != "_mp")
        return f"{type(self).__qualname__}({shown})"

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return self._values() == other._values()  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash(self._values())

    @property
    def t_max(self) -> float:
        """The largest t (s) evaluated: |κt + v0| ≤ 2^52·K(m), 2^51 nutation periods (inf when steady).

        Beyond it adjacent doubles of the phase are more than a quarter period apart and the period
        count is no longer an exact integer; later times are refused (by the Jacobi functions).
        """
        if self._period is None:
            return float("inf")
        K = self._period.hi / 2
        return float((2.0**52 * K - abs(self._v0.hi)) / math.ldexp(self._kappa.hi, self._kappa.exp))

    @functools.cached_property
    def _at_start(self) -> _Pass:
        """One pass at t = 0, by the path every time goes through, shared by all that needs the start: its
        phase (:attr:`_phase0`, the passages' count), Π(n; am v0) of the angles' constants and the error
        estimate's checks of the start (each had made its own single-point pass, the phase four times)."""
        return _Pass(self, np.zeros(1))

    @functools.cached_property
    def _phase0(self) -> tuple[float, float, float]:
        """(j0, r0_hi, r0_lo): the reduced phase at t = 0, by the arithmetic every time goes through."""
        j, rh, rl = self._at_start.phase_dd()
        return float(j[0]), float(rh[0]), float(rl[0])

    @functools.cached_property
    def _jacobi_parameter(self) -> Any:
        """m, 1 − m and K(m) as the Jacobi functions take them (:func:`mechderive.special._parameter.parameter`):
        validated once per motion, not again by every pass (the samples, the start, the quadrature nodes)."""
        from ...special._parameter import parameter

        return parameter(self.m, self.m1)

    @functools.cached_property
    def _angles(self) -> dict[str, _Angle]:
        if "extended" in self._mp:
            # set up in extended precision (:mod:`.exact_extended`): φ and ψ's constants too, where their
            # measured errors allow; else the 40-digit motion's (its phase agrees with this one's to 1e-14·K)
            from .exact_extended import angle_constants

            got = angle_constants(self)
            if got is not None:
                return _angle_setup(self, *got)
            precise = self.precise()
            angles = precise._angles
            self._mp["one_minus_n"] = precise._mp.get("one_minus_n", {})
            return angles
        import mpmath

        with mpmath.workdps(self._mp.get("dps", _DPS)):
            return _angle_setup(self)

    @functools.cached_property
    def _per_period_precise(self) -> dict[str, DD]:
        """The advance of φ and ψ per nutation period at 40 digits (double-double)."""
        import mpmath

        with mpmath.workdps(self._mp.get("dps", _DPS)):
            from ._exact_setup import precise_advance

            return precise_advance(self)

    def precise(self) -> "HeavyTopSolution":
        """This motion set up at 40 digits: itself, unless it was set up in extended precision
        (:mod:`.exact_extended`; then the 40-digit setup is made on the first call, and kept)."""
        if "extended" not in self._mp:
            return self
        if "precise" not in self._mp:
            import mpmath

            with mpmath.workdps(_DPS):
                from ._exact_setup import setup

                self._mp["precise"] = setup(self.parameters, self.initial)
        return self._mp["precise"]

    def _pi_series(self) -> Any:
        """The Fourier series of Π(n; am u | m) for the characteristics n± not close to 1 (fitted once
        per motion, after :func:`_angle_setup`), or None where it would converge too slowly."""
        if "pi_series" not in self._mp:
            from ...special import pi_series

            ns = sorted(n for n, n1 in self._mp.get("one_minus_n", {}).items() if n1 >= 1e-3)
            self._mp["pi_series"] = None if not ns or self._period is None else pi_series.fit_pi_series_for_motion(
                np.array(ns), self.m, self.m1, self._period.hi / 2, parameter=self._jacobi_parameter)
        return self._mp["pi_series"]

    @functools.cached_property
    def _angle_fractions(self) -> dict[str, tuple]:
        """Per angle: (c0, [(c_i, n_i) kept]) of the partial fractions of φ̇, ψ̇ at 40 digits."""
        import mpmath

        with mpmath.workdps(self._mp.get("dps", _DPS)):
            from ._exact_setup import kept_fractions

            return kept_fractions(self)

    # --- the phase ----------------------------------------------------------------------------

    def _phase(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(j, r): v(t) = κt + v0 = j·2K + r with integer j and r in [0, 2K) (see :mod:`mechderive.core.phase`)."""
        j, rh, rl = self._phase_dd(t)
        return j, rh + rl

    def _phase_dd(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(j, r_hi, r_lo): as :meth:`_phase` with r kept as a double-double (Dekker/Knuth
        transformations as in :func:`mechderive.core.phase.reduce_phase`), so that the distance of
        r to a turning point (0, K, 2K) is known to ~1e-32·|v| absolutely, not to ulp(K)."""
        t = np.asarray(t, dtype=float)
        k = self._kappa
        hi, lo = two_prod(k.hi, t)
        lo = lo + k.lo * t
        hi, lo = dd_add(hi, lo, self._v0.hi, self._v0.lo)
        per = self._period
        if per is None:
            return np.zeros_like(t), hi, lo
        j = np.floor(hi / per.hi)
        ph, pl = two_prod(j, per.hi)  # exact: j is an integer below 2**53
        pl = pl + j * per.lo
        rh, rl = dd_add(hi, lo, -ph, -pl)
        # the floor of the rounded hi part can be off by one at a period boundary: correct it (where it is: at
        # most a few samples, usually none — a correction nowhere needed is not computed)
        for low in (rh < 0, (rh == 0) & (rl < 0)):
            if low.any():
                ah, al = dd_add(rh, rl, per.hi, per.lo)
                rh, rl, j = np.where(low, ah, rh), np.where(low, al, rl), np.where(low, j - 1, j)
        high = (rh > per.hi) | ((rh == per.hi) & (rl >= per.lo))
        if high.any():
            ah, al = dd_add(rh, rl, -per.hi, -per.lo)
            rh, rl, j = np.where(high, ah, rh), np.where(high, al, rl), np.where(high, j + 1, j)
        return j, rh, rl

    # --- one pass over many quantities ---------------------------------------------------------

    def evaluate(self, t: Any, quantities: Any) -> dict[str, np.ndarray]:
        """The requested quantities (names from :data:`QUANTITIES`) at times ``t``, sharing intermediates.

        >>> top = exact_heavy_top(dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0),
        ...                       dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0))
        >>> out = top.evaluate([0.0, 1.0], ["theta"])
        >>> round(float(out["theta"][0]), 12)
        0.5
        """
        return self._evaluate(as_finite_array(t, "t"), quantities)[0]

    def _evaluate(self, t: np.ndarray, quantities: Any) -> tuple[dict[str, np.ndarray], _Pass]:
        names = list(quantities)
        unknown = [q for q in names if q not in QUANTITIES]
        if unknown:
            raise InvalidInputError(f"unknown quantity {unknown[0]!r}: expected one of {', '.join(QUANTITIES)}")
        ps = _Pass(self, t)
        out: dict[str, np.ndarray] = {}
        for q in names:
            out[q] = self._quantity(ps, q)
        self._mp["last_pass"] = ps  # error_estimate at the same times reuses its intermediates
        return out, ps

    def error_estimate(self, t: Any, quantities: Any) -> float:
        """The largest estimated absolute error of ``quantities`` at times ``t``, measured on this motion.

        ``quantities``: names from :data:`QUANTITIES` (``u``, ``theta``, ``theta_dot``, ``phi``,
        ``psi``, ``phi_dot``, ``psi_dot``, ``R``, ``apex``, ``omega``, …).  The value is in each
        quantity's own units (rad, rad/s, or 1 for u, R and the apex) — the largest of them.
        Nothing is a constant: residuals of the derived equations at the samples, the initial
        state reproduced, the angles' increments against Gauss–Legendre quadrature of the derived
        rates (3.74)–(3.75) along u(t), and the rounding of what is output (see
        :mod:`.estimate`).  Only what the requested quantities need is computed: asking for θ
        neither evaluates nor checks φ or ψ.  After :meth:`evaluate` at the same ``t`` its
        intermediates are reused.

        >>> top = exact_heavy_top(dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0), dict(theta=0.5, psi_dot=5.0))
        >>> top.error_estimate([0.0, 1.0, 2.0], ["theta"]) < 1e-14
        True
        """
        from .estimate import estimate

        arr = as_finite_array(t, "t")
        names = list(quantities)
        unknown = [q for q in names if q not in QUANTITIES]
        if unknown:
            raise InvalidInputError(f"unknown quantity {unknown[0]!r}: expected one of {', '.join(QUANTITIES)}")
        last = self._mp.get("last_pass")
        ps = last if last is not None and last.t.shape == arr.shape and np.array_equal(last.t, arr) else _Pass(self, arr)
        return estimate(self, ps, names)

    def _quantity(self, ps: _Pass, q: str) -> np.ndarray:
        t = ps.t
        steady = self.kind == "steady"
        if q == "u":
            if steady:
                return np.full(t.shape, np.cos(self._theta_const))
            return self._u1 + self._amp * ps.jacobi()[0] ** 2
        if q == "u_dot":
            if steady:
                return np.zeros(t.shape)
            sn, cn, dn = ps.jacobi()
            return 2 * (self._kappa.hi + self._kappa.lo) * self._amp * sn * cn * dn
        if q == "theta":
            if steady:
                return np.full(t.shape, self._theta_const)
            one_minus, one_plus = ps.one_minus_plus_u()
            return 2 * np.arctan2(np.sqrt(one_minus), np.sqrt(one_plus))
        if q == "_theta_signed":
            s, c = ps.half_theta()
            return 2 * np.arctan2(s, c)
        if q == "theta_dot":
            if steady:
                return np.zeros(t.shape)
            if self._one_minus_u2 == 0.0 or self._one_plus_u1 == 0.0:
                # θ = |signed θ| folded into [0, π]: θ̇ = ±(signed θ̇), the sign flipping at each
                # exact passage; at the passage instant itself the value just after it (the passage
                # counts as made, as in :meth:`_Pass.passages`): away from the pole, towards the bottom
                s, c = ps.half_theta()
                rate = self._signed_theta_dot(ps)
                return np.where(s == 0, np.abs(rate), np.where(c == 0, -np.abs(rate), np.sign(s) * np.sign(c) * rate))
            sn, cn, dn = ps.jacobi()
            one_minus, one_plus = ps.one_minus_plus_u()
            kappa = self._kappa.hi + self._kappa.lo
            return -2 * kappa * self._amp * sn * cn * dn / np.sqrt(one_minus * one_plus)
        if q in ("phi", "psi", "phi_wrapped", "psi_wrapped"):
            spec = self._angles[q[:3]]
            if q.endswith("wrapped"):
                x = ps.angle(spec, reduced=True) + (np.pi * ps.passages() if not steady else 0.0)
                return x - 2 * np.pi * np.round(x / (2 * np.pi))
            return ps.angle(spec, reduced=False) + (np.pi * ps.passages() if not steady else 0.0)
        if q in ("phi_dot", "psi_dot"):
            if steady:
                return np.full(t.shape, self.initial[q])
            return ps.derived_rates()[0 if q == "phi_dot" else 1]
        if q == "R":
            if steady:  # (imported here: a nutating top's R is built from the half angles, without the module)
                from ...kinematics.rotations import rotation_matrix

                return rotation_matrix(ps.angle(self._angles["phi"], reduced=True), self._theta_const,
                                       ps.angle(self._angles["psi"], reduced=True))
            return self._rotation(ps)
        if q == "apex":
            th = self._quantity(ps, "theta" if steady else "_theta_signed")
            ph = ps.angle(self._angles["phi"], reduced=True)
            return np.stack([np.sin(th) * np.sin(ph), -np.sin(th) * np.cos(ph), np.cos(th)], axis=-1)
        if q == "omega":
            if steady:
                from ...kinematics.rotations import angular_velocity_body

                return angular_velocity_body(ps.angle(self._angles["phi"], reduced=True), self._theta_const,
                                             ps.angle(self._angles["psi"], reduced=True),
                                             self._quantity(ps, "phi_dot"), 0.0, self._quantity(ps, "psi_dot"))
            # from what R is built of: the half sums/differences and the signed (sin θ/2, cos θ/2),
            # continuous through exact passages (φ, ψ without their π jumps)
            phi, psi = self._angles["phi"], self._angles["psi"]
            s, c = ps.half_theta()
            w = _omega_half_angles()(ps.half_angle(phi, psi, +1), ps.half_angle(phi, psi, -1), s, c,
                                     ps.derived_rates()[2], ps.derived_rates()[3],
                                     self._signed_theta_dot(ps))
            return np.stack(np.broadcast_arrays(*w), axis=-1)
        raise InvalidInputError(f"unknown quantity {q!r}: expected one of {', '.join(QUANTITIES)}")

    def _signed_theta_dot(self, ps: _Pass) -> np.ndarray:
        """d/dt of the signed θ: -u̇/sin θ, and at exact passages the form that stays finite there.

        Through the pole (u2 = 1): sin(θ/2) = ±√(amp/2) cn, so θ̇ = ∓κ√(2 amp) sn dn / cos(θ/2);
        through the bottom (u1 = -1): cos(θ/2) = ±√(amp/2) sn, so θ̇ = ∓κ√(2 amp) cn dn / sin(θ/2) likewise.
        """
        sn, cn, dn = ps.jacobi()
        s, c = ps.half_theta()
        kappa = self._kappa.hi + self._kappa.lo
        parity = 1.0 - 2.0 * np.mod(ps.phase()[0], 2.0)
        k = kappa * np.sqrt(2 * self._amp) * parity
        norm = np.hypot(s, c)
        if self._one_minus_u2 == 0.0 and self._one_plus_u1 == 0.0:
            # through both (u1 = -1, u2 = 1: sin θ/2 ∝ cn, cos θ/2 ∝ sn): θ̇ = -2κ dn, with the signs
            return -self._mp["pole_sign"] * self._mp["bottom_sign"] * 2 * kappa * dn
        if self._one_minus_u2 == 0.0:
            return -self._mp["pole_sign"] * k * sn * dn * norm / c
        if self._one_plus_u1 == 0.0:
            return -self._mp["bottom_sign"] * k * cn * dn * norm / s
        u_dot = self._quantity(ps, "u_dot")
        # sin θ = 2sc/(s² + c²): np.sin of a θ rounded next to π would lose ulp(π)/(π - θ) relative
        with np.errstate(divide="ignore", invalid="ignore"):
            return -u_dot * (s * s + c * c) / (2 * s * c)

    def _rotation(self, ps: _Pass) -> np.ndarray:
        """R from the quaternion of Rᵀ built on (φ + ψ)/2 and (φ - ψ)/2 (see conversions.euler_to_quaternion).

        Near the pole φ and ψ are individually ill-conditioned but φ + ψ is not, and φ - ψ enters
        multiplied by sin(θ/2) (near the bottom: the other way round); forming R from φ and ψ
        separately would multiply their rounding by 1/(1 - n±).  The half sums and differences
        are reduced mod 2π in double-double (their advances per period halved exactly).
        """
        from ...kinematics.conversions import quaternion_to_matrix

        sigma = ps.half_angle(self._angles["phi"], self._angles["psi"], +1)
        delta = ps.half_angle(self._angles["phi"], self._angles["psi"], -1)
        s, c = ps.half_theta()
        norm = np.hypot(s, c)
        s, c = s / norm, c / norm
        q = np.stack([c * np.cos(sigma), s * np.cos(delta), s * np.sin(delta), c * np.sin(sigma)], axis=-1)
        return quaternion_to_matrix(q / np.linalg.norm(q, axis=-1, keepdims=True))

    # --- single quantities ------------------------------------------------------------------------

    def theta(self, t: Any) -> np.ndarray:
        """The nutation angle θ(t) (rad), from u(t) without cancellation near θ = 0 or π."""
        return self.evaluate(t, ["theta"])["theta"]

    def u(self, t: Any) -> np.ndarray:
        """u(t) = cos θ(t) = u1 + (u2 - u1) sn²(κt + v0 | m) (3.71)."""
        return self.evaluate(t, ["u"])["u"]

    def theta_dot(self, t: Any) -> np.ndarray:
        """θ̇ = -u̇ / sin θ, with u̇ = 2κ(u2 - u1) sn cn dn (rad/s)."""
        return self.evaluate(t, ["theta_dot"])["theta_dot"]

    def phi(self, t: Any, *, wrapped: bool = False) -> np.ndarray:
        """The precession angle φ(t) (rad): continuous (not wrapped), or in (-π, π] with ``wrapped=True``.

        The continuous angle is a float of size ~|φ̇| t, so its own rounding (ulp) grows with t
        (2.3e-13 at |φ| ~ 2000); the wrapped angle is reduced in double-double and keeps ~1e-15.
        """
        name = "phi_wrapped" if wrapped else "phi"
        return self.evaluate(t, [name])[name]

    def psi(self, t: Any, *, wrapped: bool = False) -> np.ndarray:
        """The spin angle ψ(t) (rad): continuous, or in (-π, π] with ``wrapped=True`` (see :meth:`phi`)."""
        name = "psi_wrapped" if wrapped else "psi"
        return self.evaluate(t, [name])[name]

    def phi_dot(self, t: Any) -> np.ndarray:
        """φ̇(t) = (b - a u)/(1 - u²) (3.74), from its partial fractions (rad/s)."""
        return self.evaluate(t, ["phi_dot"])["phi_dot"]

    def psi_dot(self, t: Any) -> np.ndarray:
        """ψ̇(t) (3.75), from its partial fractions (rad/s)."""
        return self.evaluate(t, ["psi_dot"])["psi_dot"]

    def rotation(self, t: Any) -> np.ndarray:
        """The chapter's R(φ, θ, ψ) at times t (φ, ψ reduced mod 2π exactly), shape (..., 3, 3)."""
        return self.evaluate(t, ["R"])["R"]

    def apex(self, t: Any) -> np.ndarray:
        """The symmetry axis e3 in space components (a point on the unit sphere), shape (..., 3)."""
        return self.evaluate(t, ["apex"])["apex"]


def classify(u1: float, u2: float, a: float, b: float, *, rtol: float = 1e-12) -> str:
    """The chapter's motion classes (figure 44) from the sign of φ̇ ∝ b - a u at the turning points.

    Returns ``'uniform precession'`` (u1 = u2), ``'monotonic precession'`` (φ̇ keeps its sign),
    ``'looping'`` (φ̇ changes sign), or ``'cusps'`` (φ̇ = 0 at a turning point).
    """
    if u2 - u1 <= rtol:
        return "uniform precession"
    g1, g2 = b - a * u1, b - a * u2
    scale = max(abs(a), abs(b), 1e-300)
    if min(abs(g1), abs(g2)) <= rtol * scale:
        return "cusps"
    return "monotonic precession" if g1 * g2 > 0 else "looping"


def exact_heavy_top(parameters: Mapping[str, float], initial: Mapping[str, float], *,
                    strict: bool = True, horizon: float | None = None) -> HeavyTopSolution:
    """The closed-form motion of a heavy symmetric top.

    Parameters
    ----------
    parameters : ``I1 I3 M g l`` — I1 = I2 and I3 principal moments about the pivot (kg m²),
        mass (kg), gravity (m/s²), pivot-to-centre-of-mass distance (m); or ``I1 I3 Mgl`` (M g l > 0).
    initial : ``theta phi psi theta_dot phi_dot psi_dot`` (rad, rad/s) at t = 0.
    strict : ``False`` accepts a top no rigid body is (I1 - M l² < I3/2); see
        :func:`~mechderive.systems.heavy_top.parameters.check_params`.
    horizon : the largest |t| (s) the motion will be evaluated at, if known: the constants are then set up
        in extended precision where their measured errors over that span allow (:mod:`.exact_extended`,
        no mpmath), else at 40 digits as without it.

    >>> top = exact_heavy_top(dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0),
    ...                       dict(theta=0.5, phi=0.0, psi=0.0, theta_dot=0.0, phi_dot=0.0, psi_dot=5.0))
    >>> round(top.nutation_period, 4), top.motion_class
    (3.5177, 'cusps')
    """
    params = check_params(parameters, strict=strict)
    init = check_initial(initial)
    if not np.ndim(init["theta"]) and init["theta"] == 0 and init["theta_dot"] < 0:
        raise InvalidInputError(
            f"expected theta_dot >= 0 at theta = 0 (θ in [0, π] cannot decrease from the pole; the same motion "
            f"is theta_dot = {-init['theta_dot']:g} with phi and psi each turned by π), got theta_dot = "
            f"{init['theta_dot']:g}")
    # (check_params realises Mgl as M = 1, g = Mgl, l = 1)
    for k, v in (("Mgl", params["g"]),) if "Mgl" in parameters else (("g", params["g"]), ("l", params["l"])):
        if not np.all(v > 0):
            raise InvalidInputError(f"expected params['{k}'] > 0 for the heavy top's closed form (with M g l = 0 "
                                    f"the top is free: use the free_top system), got {float(np.min(v)):g}")
    if any(np.ndim(v) for v in (*params.values(), *init.values())):
        raise InvalidInputError("expected scalar parameters and initial values for one closed-form motion, got arrays")
    if horizon is not None:
        from .exact_extended import setup

        top = setup(params, init, horizon, strict=strict, mgl="Mgl" in parameters)
        if top is not None:
            return top
    import mpmath

    from ._exact_setup import setup as setup_40_digits

    with mpmath.workdps(_DPS):
        return setup_40_digits(params, init)


def _passage_sign(value, slope, theta_dot) -> float:
    """The sign making √(amp)·value (sin θ/2 at a pole passage, cos θ/2 at a bottom passage) start
    with the sign of the initial state: positive where value ≠ 0; at a start on the pole/bottom
    itself, the sign that makes θ move as θ̇0 says (value changes like ``slope``)."""
    if value != 0 and abs(value) > 10.0 ** (-_DPS // 2):
        return 1.0 if value > 0 else -1.0
    if theta_dot == 0 or slope == 0:
        return 1.0
    return 1.0 if (slope > 0) == (theta_dot > 0) else -1.0


def _angle_setup(sol: HeavyTopSolution, fractions: dict | None = None, one_minus_n: dict | None = None,
                 advances: dict | None = None) -> dict[str, _Angle]:
    """Constants of φ(t) and ψ(t), for the first request of either.

    The partial-fraction coefficients and the advance per nutation period come from 40-digit
    arithmetic (more near a passage, see :func:`._exact_setup.setup`): the advance multiplies the period count
    j, so its double rounding would grow like j·ulp.  Π(n; am r0 | m) at the start is evaluated as
    every sample's Π is (double precision, from the phase at t = 0).  ``fractions``, ``one_minus_n`` (1 − n
    per n) and ``advances`` (per angle): given by the extended-precision setup (:mod:`.exact_extended`).
    """
    if sol.kind == "steady":
        return {k: _Angle(k, sol.initial[k], 0.0, (), None, sol.initial[k + "_dot"]) for k in ("phi", "psi")}
    v = sol._mp
    kappa = v["kappa"]
    fractions = sol._angle_fractions if fractions is None else fractions
    # φ and ψ share their characteristics n±: one vectorised Π call for all of them
    ns = sorted({n for _, kept in fractions.values() for _, n in kept})
    for n in ns:
        # to full relative accuracy
        sol._mp.setdefault("one_minus_n", {})[float(n)] = float(1 - n if one_minus_n is None else one_minus_n[n])
    # Π(n; am r0 | m) at the phase of t = 0 by the very path every sample takes: φ(0) = φ0 and
    # ψ(0) = ψ0 to rounding, also where Π is huge (n → 1 near the pole, ~1/√(1 - n)) or
    # ill-conditioned in the amplitude (m → 1: Π(n; A | m) from a rounded A0 next to π/2 erred
    # 7e-12 at m1 = 3e-13, and φ(0) with it)
    at_start = sol._at_start
    at_start.pis([float(n) for n in ns])
    pi0 = {n: float(at_start.pi(float(n))[0]) for n in ns}
    out = {}
    for name in ("phi", "psi"):
        c0, kept = fractions[name]
        terms = tuple((float(c / kappa), float(n), pi0[n]) for c, n in kept)
        advance = None if sol._period is None else (sol._per_period_precise if advances is None else advances)[name]
        out[name] = _Angle(name, float(sol.initial[name]), float(c0 / kappa), terms, advance, 0.0)
    return out
