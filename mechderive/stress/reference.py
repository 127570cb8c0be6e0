"""Independent high-precision references for the stress cases: a Taylor-series integrator in mpmath.

Nothing here uses the toolkit's derivations or closed forms.  The equations are typed in by hand,
as in ``tests/reference/make_*_reference.py``: the body angular velocity ω and the chapter's R
(e_a = R_ab ẽ_b) with Ṙ = hat(ω) R (3.11), hat(ω)_ab = ε_abc ω_c, and

    free top (3.33):   I1 ω̇1 = (I2 - I3) ω2 ω3  (cyclic),
    heavy top:         I1 ω̇1 = (I1 - I3) ω2 ω3 + M g l R23,   I1 ω̇2 = (I3 - I1) ω3 ω1 - M g l R13,   ω̇3 = 0

(moments about the pivot, gravity torque l e3 × (-M g ẽ3) in body components).

Method.  Both right-hand sides are quadratic polynomials in y = (ω, R), so the Taylor coefficients
of y(t0 + s) = Σ c_k s^k follow exactly from c_{k+1} = F_k / (k + 1), F_k the k-th coefficient of
the right-hand side, each product's coefficient a Cauchy product Σ_i a_i b_{k-i}, summed exactly over
integers in fixed point (:meth:`QuadraticField.fixed_series`; ``mpmath.fdot`` in :meth:`QuadraticField.series_mp`).
The order N = ⌈-ln(tol)/2⌉ + 1 and the step h = ρ/e² with ρ estimated from the last two coefficients
(Jorba & Zou 2005, Exp. Math. 14, 99): the truncation error is then ~e^{-2N} ≤ tol per step.  This
is mpmath.odefun's method (a Taylor series) with the coefficients computed exactly instead of by
finite differences at N-fold precision, which makes it ~30× faster; the test suite checks the two
agree to 1e-24.  Each step's polynomial is kept, so the solution can be evaluated anywhere (dense
output, e.g. at the exact binary value of a float time t, or inside a root search for a period), by
Horner's rule in integers (:class:`StepPolynomial`).

Long times use exact symmetries instead of integrating (see :func:`monodromy_power`).
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass
from typing import Callable, Sequence

import mpmath
import numpy as np

from ..errors import InvalidInputError

__all__ = ["DPS", "TaylorSolution", "RefRun", "free_top_field", "heavy_top_field", "integrate", "heavy_initial_state",
           "free_initial_state", "euler_matrix", "euler_angles", "matrix", "monodromy_power", "free_top_m1",
           "free_top_period", "find_root", "sample", "heavy_reference", "free_reference"]

#: Working digits of every reference (≥ 25 asked; 30 leaves room for the amplification of
#: rounding near a separatrix, where perturbations grow like 1/√(1 - m) per passage).
DPS = 30

mpf = mpmath.mpf


@dataclass(frozen=True)
class QuadraticField:
    """ẏ_i = Σ c y_a y_b + Σ c y_a, a polynomial field of degree 2 (the products are shared)."""

    n: int
    pairs: tuple[tuple[int, int], ...]
    quadratic: tuple[tuple[tuple[mpmath.mpf, int], ...], ...]  # per component: (coefficient, pair index)
    linear: tuple[tuple[tuple[mpmath.mpf, int], ...], ...]  # per component: (coefficient, component)

    @classmethod
    def build(cls, n: int, terms: Sequence[Sequence[tuple]]) -> "QuadraticField":
        """``terms[i]``: tuples (c, a, b) for c·y_a·y_b and (c, a) for c·y_a."""
        pairs: list[tuple[int, int]] = []
        quad, lin = [], []
        for comp in terms:
            q, l_ = [], []
            for term in comp:
                if len(term) == 3:
                    pair = tuple(sorted(term[1:]))
                    if pair not in pairs:
                        pairs.append(pair)
                    q.append((term[0], pairs.index(pair)))
                else:
                    l_.append((term[0], term[1]))
            quad.append(tuple(q))
            lin.append(tuple(l_))
        return cls(n, tuple(pairs), tuple(quad), tuple(lin))

    def series(self, y0: Sequence[mpmath.mpf], order: int, step: mpmath.mpf | None = None) -> list[list[mpmath.mpf]]:
        """Taylor coefficients c[i][0..order] of the solution through y0, at the working precision
        (:meth:`fixed_series`, else :meth:`series_mp`)."""
        fixed = self.fixed_series(y0, order, step)
        return fixed.coefficients() if fixed is not None else self.series_mp(y0, order)

    def fixed_series(self, y0: Sequence[mpmath.mpf], order: int,
                     step: mpmath.mpf | None = None) -> "FixedSeries | None":
        """The Taylor coefficients through y0 in fixed point, or None where :meth:`series_mp` must compute them.

        The series is taken in s/H, d_k = c_k H^k, as integers over 2^P, with H a power of two near the step the
        coefficients will allow (``step``, the previous step, when known).  Those d_k are all of the state's size or
        smaller, so an absolute precision of 2^-P with P = precision + 64 bits + twice the spread of the state's
        nonzero magnitudes keeps every coefficient that matters to the working precision, each component to its
        own relative accuracy; the Cauchy products then run over Python integers (exact) instead of mpf dot
        products: ~5× faster.  If the last coefficients come out with too few bits (H far too small), H is
        enlarged and the series computed again.  None: a state beyond the fixed-point range, or a series whose
        terms past d_1 all vanish (a polynomial).  Tests compare the two routes.
        """
        y0 = [mpf(y) for y in y0]
        nonzero = [abs(y) for y in y0 if y]
        if not nonzero:
            return None
        top, spread, P = _fixed_point_scale(nonzero)
        if P > _MAX_FIXED_BITS:
            return None
        if step is None:
            # the field's time scale at y0, 1/(|quadratic| |y| + |linear|): a step of that order (below, H is adjusted)
            rate = max([abs(c) for comp in self.quadratic for c, _ in comp] or [0]) * mpmath.ldexp(1, top) + \
                max([abs(c) for comp in self.linear for c, _ in comp] or [0])
            step = 1 / rate if rate else mpf(1)
        exponent = int(mpmath.floor(mpmath.log(step, 2)))
        # at the step the coefficients allow, d_N ~ tol·|y| ~ 2^-(prec - 7): about P - prec + 7 bits.  The step
        # control needs ~20 significant bits of d_N in each component, and a component may be 2^-spread of the largest
        target = P - mpmath.mp.prec + 7
        for _ in range(16):
            d = self._scaled_series(y0, order, top, exponent, P)
            if order < 2:
                break
            bits = [max(abs(di[k]).bit_length() for di in d) for k in range(order + 1)]
            if max(bits[order - 1:]) >= 24 + spread:
                break
            # H too small: d_k falls by ~δ bits an order; extrapolate d_N's bits from the last order left nonzero
            # (everything past d_1 zero: a polynomial, or H far too small; mpf decides)
            last = max((k for k in range(2, order + 1) if bits[k]), default=None)
            if last is None:
                return None
            fall = (bits[1] - bits[last]) / (last - 1)
            exponent += max(1, math.ceil((target - (bits[last] - fall * (order - last))) / order))
        else:
            return None
        return FixedSeries(d, top, exponent, P)

    def _scaled_series(self, y0: Sequence[mpmath.mpf], order: int, top: int, exponent: int, P: int) -> list[list[int]]:
        """D[i][k] = round(2^P · c_ik H^k / 2^top), H = 2^exponent, by the recurrence of :meth:`series_mp` in y/2^top
        and s/H: d_{k+1} = H/(k+1)·(2^top Σ q·(d∗d)_k + Σ l·d_k); every rounding is below one unit of 2^-P."""
        scale_q, scale_l = mpmath.ldexp(1, top + exponent), mpmath.ldexp(1, exponent)
        quadratic = [[(_fixed(c * scale_q, P), p) for c, p in comp] for comp in self.quadratic]
        linear = [[(_fixed(c * scale_l, P), a) for c, a in comp] for comp in self.linear]
        d = [[_fixed(mpmath.ldexp(y, -top), P)] for y in y0]
        half = 1 << (P - 1)
        for k in range(order):
            products = [(sum(map(operator.mul, d[a][: k + 1], d[b][k::-1])) + half) >> P for a, b in self.pairs]
            for i in range(self.n):
                acc = 0
                for c, p in quadratic[i]:
                    acc += c * products[p]
                for c, a in linear[i]:
                    acc += c * d[a][k]
                d[i].append(((acc + half) >> P) // (k + 1))
        return d

    def series_mp(self, y0: Sequence[mpmath.mpf], order: int) -> list[list[mpmath.mpf]]:
        """:meth:`series` in mpf arithmetic: c_{k+1} = F_k/(k + 1), each product's coefficient an exact dot product."""
        c = [[mpf(y)] for y in y0]
        fdot = mpmath.fdot
        for k in range(order):
            prods = [fdot(c[a][: k + 1], c[b][k::-1]) for a, b in self.pairs]
            for i in range(self.n):
                s = mpf(0)
                for coef, p in self.quadratic[i]:
                    s += coef * prods[p]
                for coef, a in self.linear[i]:
                    s += coef * c[a][k]
                c[i].append(s / (k + 1))
        return c


#: beyond this many bits of fixed point (a state whose components span ~10^2800) the series is computed in mpf
_MAX_FIXED_BITS = 20_000


def _fixed_point_scale(magnitudes: Sequence[mpmath.mpf]) -> tuple[int, int, int]:
    """(top, spread, P) for a state of these nonzero magnitudes: |y| < 2^top, the largest over the smallest below
    2^spread, and P = precision + 64 + 2·spread bits of fixed point in units of 2^top (each component keeps its
    relative accuracy, products of two included)."""
    top = int(mpmath.floor(mpmath.log(max(magnitudes), 2))) + 1
    spread = top - int(mpmath.floor(mpmath.log(min(magnitudes), 2)))
    return top, spread, mpmath.mp.prec + 64 + 2 * spread


def _fixed(x: mpmath.mpf, P: int) -> int:
    """round(x·2^P), exactly from x's mantissa."""
    sign, man, exp, _ = mpf(x)._mpf_
    shift = exp + P
    value = int(man) << shift if shift >= 0 else (int(man) + (1 << (-shift - 1))) >> -shift
    return -value if sign else value


@dataclass(frozen=True)
class FixedSeries:
    """Taylor coefficients in fixed point: c_ik = d[i][k] · 2^(top - P) / H^k, H = 2^exponent."""

    d: list[list[int]]
    top: int
    exponent: int
    P: int

    def coefficients(self) -> list[list[mpmath.mpf]]:
        """The c_ik as mpf at the working precision."""
        make, from_man_exp, prec = mpmath.mp.make_mpf, mpmath.libmp.from_man_exp, mpmath.mp.prec
        base = self.top - self.P
        return [[make(from_man_exp(v, base - self.exponent * k, prec, "n")) for k, v in enumerate(di)] for di in self.d]

    def polynomial(self, h: mpmath.mpf) -> "StepPolynomial":
        """The series over one step of length h, as a polynomial in s/h (e_k = d_k (h/H)^k, integer arithmetic)."""
        P, half = self.P, 1 << (self.P - 1)
        ratio = _fixed(mpmath.ldexp(h, -self.exponent), P)
        powers = [1 << P]
        for _ in range(len(self.d[0]) - 1):
            powers.append((powers[-1] * ratio + half) >> P)
        return StepPolynomial([[(v * w + half) >> P for v, w in zip(di, powers)] for di in self.d], h, self.top, P)


class StepPolynomial:
    """y(t0 + s) = Σ_k e_k (s/h)^k for 0 ≤ s ≤ h, each e_k an integer over 2^P in units of 2^top.

    In s/h ≤ 1 the terms e_k fall like e^(-2k) (the step rule below), so Horner's rule in integers loses at most
    one unit of 2^-P a term: ~100 times faster than Horner in mpf, for the dense output at every sample time.
    """

    def __init__(self, e: list[list[int]], h: mpmath.mpf, top: int, P: int) -> None:
        self.e, self.h, self.top, self.P = e, h, top, P

    @classmethod
    def from_coefficients(cls, c: Sequence[Sequence[mpmath.mpf]], h: mpmath.mpf) -> "StepPolynomial":
        """From mpf coefficients c_ik (the :meth:`QuadraticField.series_mp` route)."""
        top, _, P = _fixed_point_scale([abs(v) for ci in c for v in ci[:1] if v] or [mpf(1)])
        hk = [mpmath.ldexp(h ** k, -top) for k in range(len(c[0]))]
        return cls([[_fixed(v * w, P) for v, w in zip(ci, hk)] for ci in c], h, top, P)

    def at(self, s: mpmath.mpf) -> list[mpmath.mpf]:
        """y(t0 + s), 0 ≤ s ≤ h."""
        P = self.P
        u = _fixed(s / self.h, P)
        make, from_man_exp, prec = mpmath.mp.make_mpf, mpmath.libmp.from_man_exp, mpmath.mp.prec
        out = []
        for ei in self.e:
            acc = 0
            for v in reversed(ei):
                acc = ((acc * u) >> P) + v
            out.append(make(from_man_exp(acc, self.top - P, prec, "n")))
        return out

    def end(self) -> list[mpmath.mpf]:
        """y(t0 + h): the sum of the terms."""
        make, from_man_exp, prec = mpmath.mp.make_mpf, mpmath.libmp.from_man_exp, mpmath.mp.prec
        return [make(from_man_exp(sum(ei), self.top - self.P, prec, "n")) for ei in self.e]


def _rotation_terms() -> list[list[tuple]]:
    """Ṙ = hat(ω) R with y = (ω1, ω2, ω3, R11, R12, ..., R33): Ṙ_0j = ω3 R_1j - ω2 R_2j, cyclically."""
    R = lambda i, j: 3 + 3 * i + j  # noqa: E731
    one = mpf(1)
    terms = []
    for i in range(3):
        for j in range(3):
            if i == 0:
                terms.append([(one, 2, R(1, j)), (-one, 1, R(2, j))])
            elif i == 1:
                terms.append([(-one, 2, R(0, j)), (one, 0, R(2, j))])
            else:
                terms.append([(one, 1, R(0, j)), (-one, 0, R(1, j))])
    return terms


def free_top_field(moments: Sequence[float]) -> QuadraticField:
    """Euler's equations (3.33) and Ṙ = hat(ω) R, at the current mpmath precision."""
    I1, I2, I3 = (mpf(x) for x in moments)
    euler = [[((I2 - I3) / I1, 1, 2)], [((I3 - I1) / I2, 2, 0)], [((I1 - I2) / I3, 0, 1)]]
    return QuadraticField.build(12, euler + _rotation_terms())


def heavy_top_field(I1: float, I3: float, mgl: mpmath.mpf) -> QuadraticField:
    """The heavy top's Newton–Euler equations (moments about the pivot) and Ṙ = hat(ω) R."""
    I1, I3 = mpf(I1), mpf(I3)
    euler = [[((I1 - I3) / I1, 1, 2), (mgl / I1, 3 + 5)],     # + M g l R23 / I1
             [((I3 - I1) / I1, 2, 0), (-mgl / I1, 3 + 2)],    # - M g l R13 / I1
             []]
    return QuadraticField.build(12, euler + _rotation_terms())


class TaylorSolution:
    """A dense solution: the Taylor polynomial of every step, evaluable at any t in [0, t_end]."""

    def __init__(self, field: QuadraticField, y0: Sequence, *, tol: mpmath.mpf | None = None) -> None:
        self.field = field
        self.tol = tol if tol is not None else mpf(10) ** (-(mpmath.mp.dps - 2))
        self.order = int(math.ceil(-float(mpmath.log(self.tol)) / 2)) + 1
        self.starts: list[mpmath.mpf] = [mpf(0)]
        self.steps: list[tuple[mpmath.mpf, list[list[mpmath.mpf]]]] = []
        self.polynomials: list[StepPolynomial] = []
        self._y = [mpf(v) for v in y0]
        self.n_steps = 0

    @property
    def t_end(self) -> mpmath.mpf:
        return self.starts[-1]

    def _step(self) -> None:
        N = self.order
        fixed = self.field.fixed_series(self._y, N, self.steps[-1][0] if self.steps else None)  # last step: H's guess
        c = fixed.coefficients() if fixed is not None else self.field.series_mp(self._y, N)
        h = self._step_size(c)
        polynomial = fixed.polynomial(h) if fixed is not None else StepPolynomial.from_coefficients(c, h)
        self.steps.append((h, c))
        self.polynomials.append(polynomial)
        self._y = polynomial.end()
        self.starts.append(self.starts[-1] + h)
        self.n_steps += 1

    def _step_size(self, c: list[list[mpmath.mpf]]) -> mpmath.mpf:
        """h = ρ/e², ρ from the last two coefficients against the state's largest component (Jorba & Zou)."""
        N = self.order
        scale = max(mpf(1), max(abs(ci[0]) for ci in c))
        rho = mpmath.inf
        for j in (N - 1, N):
            size = max(abs(ci[j]) for ci in c)
            if size != 0:
                rho = min(rho, (scale / size) ** (mpf(1) / j))
        if rho == mpmath.inf:  # a polynomial of degree < N - 1: the series is exact (steady motion)
            rho = mpf(1e3)
        return rho / mpmath.e ** 2

    def extend(self, t: mpmath.mpf) -> None:
        """Integrate on until t_end ≥ t."""
        while self.starts[-1] < t or not self.steps:
            self._step()

    def __call__(self, t) -> list[mpmath.mpf]:
        """y(t) (t ≥ 0, an mpf or a float taken exactly), integrating on if needed."""
        t = mpf(t)
        if t < 0:
            raise InvalidInputError(f"expected t >= 0, got {t}")
        self.extend(t)
        k = _bisect(self.starts, t)
        return self.polynomials[k].at(t - self.starts[k])

    def derivative(self, t, component: int) -> mpmath.mpf:
        """dy_component/dt at t (from the step's polynomial)."""
        t = mpf(t)
        self.extend(t)
        k = _bisect(self.starts, t)
        _, c = self.steps[k]
        s = t - self.starts[k]
        ci = c[component]
        return _horner([j * ci[j] for j in range(1, len(ci))], s)


def _horner(c: Sequence[mpmath.mpf], s: mpmath.mpf) -> mpmath.mpf:
    acc = mpf(0)
    for v in reversed(c):
        acc = acc * s + v
    return acc


def _bisect(starts: list, t) -> int:
    """Index k of the step with starts[k] <= t <= starts[k+1]."""
    lo, hi = 0, len(starts) - 2
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if starts[mid] <= t:
            lo = mid
        else:
            hi = mid - 1
    return lo


def integrate(field: QuadraticField, y0: Sequence, t_end=None) -> TaylorSolution:
    """A :class:`TaylorSolution` from y0 (extended lazily; to t_end at once if given)."""
    sol = TaylorSolution(field, y0)
    if t_end is not None:
        sol.extend(mpf(t_end))
    return sol


# --- conversions, written out (the chapter's conventions) -------------------------------------------

def _R3(a):
    c, s = mpmath.cos(a), mpmath.sin(a)
    return mpmath.matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def _R1(a):
    c, s = mpmath.cos(a), mpmath.sin(a)
    return mpmath.matrix([[1, 0, 0], [0, c, s], [0, -s, c]])


def euler_matrix(phi, theta, psi) -> mpmath.matrix:
    """R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ) (3.54)."""
    return _R3(mpf(psi)) * _R1(mpf(theta)) * _R3(mpf(phi))


def heavy_initial_state(initial: dict) -> list[mpmath.mpf]:
    """(ω, R) at t = 0 from Euler angles and rates (exact binary inputs), ω by (3.58)."""
    th, ph, ps, thd, phd, psd = (mpf(initial.get(k, 0.0)) for k in
                                 ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot"))
    c, s = mpmath.cos, mpmath.sin
    R = euler_matrix(ph, th, ps)
    w = [phd * s(th) * s(ps) + thd * c(ps), phd * s(th) * c(ps) - thd * s(ps), psd + phd * c(th)]
    return w + [R[i, j] for i in range(3) for j in range(3)]


def free_initial_state(omega0: Sequence[float], R0=None) -> list[mpmath.mpf]:
    R = [[1, 0, 0], [0, 1, 0], [0, 0, 1]] if R0 is None else R0
    return [mpf(float(x)) for x in omega0] + [mpf(float(R[i][j])) for i in range(3) for j in range(3)]


def matrix(y: Sequence) -> mpmath.matrix:
    """R from a state y = (ω, R)."""
    return mpmath.matrix([[y[3 + 3 * i + j] for j in range(3)] for i in range(3)])


def euler_angles(y: Sequence) -> tuple:
    """(φ, θ, ψ) of R in (-π, π], [0, π], (-π, π] (meaningful individually only away from θ = 0, π)."""
    R = lambda i, j: y[3 + 3 * (i - 1) + (j - 1)]  # noqa: E731
    return (mpmath.atan2(R(3, 1), -R(3, 2)), mpmath.atan2(mpmath.sqrt(R(1, 3) ** 2 + R(2, 3) ** 2), R(3, 3)),
            mpmath.atan2(R(1, 3), R(2, 3)))


def monodromy_power(C: mpmath.matrix, N: int) -> mpmath.matrix:
    """Cᴺ for a rotation C, from its axis and angle (Rodrigues) at the working precision.

    Used for long times: R(NT + τ) = R(τ) Cᴺ with C = R(0)⁻¹ R(T), because R(t + T) and R(t)
    solve the same linear equation Ṙ = hat(ω) R when ω has period T.
    """
    tr = C[0, 0] + C[1, 1] + C[2, 2]
    v = mpmath.matrix([C[2, 1] - C[1, 2], C[0, 2] - C[2, 0], C[1, 0] - C[0, 1]])
    s = mpmath.norm(v) / 2
    if s == 0:
        return mpmath.eye(3)
    angle = mpmath.atan2(s, (tr - 1) / 2)
    axis = v / (2 * s)
    a = N * angle
    K = mpmath.matrix([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return mpmath.eye(3) + mpmath.sin(a) * K + (1 - mpmath.cos(a)) * K * K


def free_top_m1(moments: Sequence[float], omega0: Sequence[float]) -> mpmath.mpf:
    """1 - m of the free top's motion from the textbook formula (Landau & Lifshitz §37), signed:

    with I_x < I_y < I_z, D = L² - 2T I_y, k² = (I_y - I_x)(2T I_z - L²) / ((I_z - I_y)(L² - 2T I_x))
    for D > 0 (and x ↔ z for D < 0), 1 - k² = (I_z - I_x) D / ((I_z - I_y)(L² - 2T I_x)).
    Returned with the sign of D (0 on the separatrix): how far, and on which side.
    """
    I = sorted(zip((mpf(x) for x in moments), (mpf(float(w)) for w in omega0)))
    (Ix, wx), (Iy, wy), (Iz, wz) = I
    E2 = Ix * wx ** 2 + Iy * wy ** 2 + Iz * wz ** 2
    L2 = (Ix * wx) ** 2 + (Iy * wy) ** 2 + (Iz * wz) ** 2
    D = L2 - E2 * Iy
    if D == 0:
        return mpf(0)
    if D > 0:
        return (Iz - Ix) * D / ((Iz - Iy) * (L2 - E2 * Ix))
    return (Iz - Ix) * D / ((Iy - Ix) * (E2 * Iz - L2))


def find_root(f: Callable[[mpmath.mpf], mpmath.mpf], guess) -> mpmath.mpf:
    """A simple root of f near ``guess`` (secant method at the working precision)."""
    return mpmath.findroot(f, mpf(guess), tol=mpf(10) ** (-(mpmath.mp.dps - 4)))


# --- reference runs at float sample times -------------------------------------------------------

@dataclass
class RefRun:
    """A reference sampled at float times (taken exactly): ω, R, Euler angles, φ ± ψ (floats)."""

    t: np.ndarray
    omega: np.ndarray  # (N, 3)
    R: np.ndarray  # (N, 3, 3)
    angles: np.ndarray  # (N, 3): φ, θ, ψ, each in its principal range
    phi_plus_psi: np.ndarray  # atan2(R12 - R21, R11 + R22): well defined at θ = 0
    phi_minus_psi: np.ndarray  # atan2(R12 + R21, R11 - R22): well defined at θ = π
    solution: TaylorSolution
    seconds: float


def sample(sol: TaylorSolution, times) -> RefRun:
    """Evaluate a reference solution at float times (call inside ``mpmath.workdps(DPS)``)."""
    import time as _time

    start = _time.perf_counter()
    ys = [sol(float(t)) for t in np.asarray(times, dtype=float)]
    omega = np.array([[float(v) for v in y[:3]] for y in ys])
    R = np.array([[float(v) for v in y[3:]] for y in ys]).reshape(-1, 3, 3)
    ang = np.array([[float(a) for a in euler_angles(y)] for y in ys])
    plus = np.array([float(mpmath.atan2(y[3 + 1] - y[3 + 3], y[3 + 0] + y[3 + 4])) for y in ys])
    minus = np.array([float(mpmath.atan2(y[3 + 1] + y[3 + 3], y[3 + 0] - y[3 + 4])) for y in ys])
    return RefRun(np.asarray(times, dtype=float), omega, R, ang, plus, minus, sol, _time.perf_counter() - start)


def heavy_reference(params: dict, initial: dict, times) -> RefRun:
    """The heavy top's reference at ``times`` (an independent mpmath integration at :data:`DPS` digits)."""
    import time as _time

    start = _time.perf_counter()
    with mpmath.workdps(DPS):
        mgl = mpf(params["M"]) * mpf(params["g"]) * mpf(params["l"])
        sol = integrate(heavy_top_field(params["I1"], params["I3"], mgl), heavy_initial_state(initial))
        run = sample(sol, times)
    run.seconds = _time.perf_counter() - start
    return run


def free_reference(moments, omega0, R0, times) -> RefRun:
    """The free top's reference at ``times``."""
    import time as _time

    start = _time.perf_counter()
    with mpmath.workdps(DPS):
        R0l = None if R0 is None else [[float(x) for x in row] for row in R0]
        sol = integrate(free_top_field(moments), free_initial_state(omega0, R0l))
        run = sample(sol, times)
    run.seconds = _time.perf_counter() - start
    return run


def free_top_period(moments: Sequence[float], omega0: Sequence[float]) -> mpmath.mpf:
    """The polhode period 4K(m)/λ from the textbook formulas (Landau & Lifshitz §37), a root-search start.

    I_x < I_y < I_z, D = L² - 2T I_y.  D > 0: λ² = (I_z - I_y)(L² - 2T I_x)/(I_x I_y I_z),
    m = (I_y - I_x)(2T I_z - L²)/((I_z - I_y)(L² - 2T I_x)); D < 0: x and z exchange roles.
    """
    I = sorted(zip((mpf(x) for x in moments), (mpf(float(w)) for w in omega0)))
    (Ix, wx), (Iy, wy), (Iz, wz) = I
    E2 = Ix * wx ** 2 + Iy * wy ** 2 + Iz * wz ** 2
    L2 = (Ix * wx) ** 2 + (Iy * wy) ** 2 + (Iz * wz) ** 2
    if L2 - E2 * Iy < 0:
        (Ix, Iz), (E2, L2) = (Iz, Ix), (E2, L2)
    lam2 = (Iz - Iy) * (L2 - E2 * Ix) / (Ix * Iy * Iz)
    m = (Iy - Ix) * (E2 * Iz - L2) / ((Iz - Iy) * (L2 - E2 * Ix))
    return 4 * mpmath.ellipk(m) / mpmath.sqrt(abs(lam2))
