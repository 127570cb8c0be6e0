"""∫ R(u(τ)) dτ for a rational rate R = N/D on the motions whose u is a rational function of an exponential of τ
(issue 16): partial fractions in that exponential, with any poles — simple, multiple or complex.

Four forms of u̇² = P(u) (:mod:`.quadrature_motion`, :mod:`.quadrature_open`) have u = U(x)/S(x), U and S of
degree ≤ 2 in a variable x whose logarithm is linear in τ (dτ = dx/(κγx)), or x = τ itself:

=========  ===========================================  =======================  =================================
path       motion                                       x                        U(x) / S(x)
=========  ===========================================  =======================  =================================
circle     m = 0: u = M(sin² v), a bounded quadratic    e^{2iv}, v = κτ + v_s    w = sin² v = −(x − 1)²/(4x)
ray        m = 1: u = M(tanh² v) (separatrix, the       e^{2v}                   w = tanh² v = (x − 1)²/(x + 1)²
           hyperbolic quadratic)
exp        u = α + p₊e^{κt} + p₋e^{−κt}                 e^{κt}                   (p₊x² + αx + p₋)/x
line       u = u0 + s t + a t²                          t                        u0 + s t + a t² (S = 1)
=========  ===========================================  =======================  =================================

with M(w) = (A + Bw)/(C + Dw) the motion's Möbius map, so that U = A·S_w + B·N_w, S = C·S_w + D·N_w for
w = N_w/S_w.  The identities w(x) are checked with SymPy in the tests (the exponential forms of sin² and tanh²,
and of the Laurent form, by difference).

Then R(u(x))·dτ/dx = F(x) is a rational function of x whose poles are known factor by factor: for each pole u_j of R
(multiplicity μ_j, from D's roots at 40 digits) the two roots of U(x) − u_j S(x); the roots of S where N has the
higher degree (u = ∞ there); and x = 0 (from dτ = dx/(κγx)).  Partial fractions at 40 digits, each pole's
principal part from the Taylor series of the rest of F at it, and the polynomial part by division, give

    G(x) = Σ_k q_k x^{k+1}/(k + 1) + Σ_ρ [c_{ρ,1} L_ρ(x) + Σ_{k≥2} c_{ρ,k} (x − ρ)^{1−k}/(1 − k)],

∫₀^τ R dτ = Re[G(x(τ)) − G(x(0))], with L_ρ a logarithm of x − ρ continuous along the path x(τ): log x = iγφ or
γφ exactly (the phase φ in double-double: the secular part does not lose digits with time); log x + log(1 − ρ/x)
for |ρ| < |x| and log(−ρ) + log(1 − x/ρ) otherwise (the principal logarithms are continuous along the circle and
the positive ray for ρ off them; the constant between the two forms on the ray is fixed once at |x| = |ρ|); log|x − ρ|
for a pole on the path itself.

On the circle the motion is periodic (u has period π in v): G less its secular part Σ c_{ρ,1}·iγφ (over ρ = 0
and the poles inside the unit circle, whose L_ρ carry log x) is a function of x alone, so the advance over one period
of u is that secular rate times π — 2πi times the residues of F inside the circle (:attr:`RationalRate.advance`).
The secular part is evaluated from φ in double-double (its rate, too, a double-double) and the rest from x of the
phase reduced by π, so long times keep their digits (Kepler's t(φ) after 137 orbits: 4e-16 of t);
:meth:`RationalRate.minus` gives the integral less a target without the integral's own final rounding (t(φ) − t
near a root, to ~1e-3 ulp of t after 1000 orbits), and :meth:`RationalRate.rounding` a first-order bound of the
doubles' rounding at each time (the terms' sizes, and their sensitivity to x's and x − ρ's rounding).

A real pole of R that the motion reaches (a root ρ on the path: the circle, the positive ray, the real line) makes
the integral diverge there; the integral exists between the crossings around τ = 0 (:attr:`RationalRate.singular_times`)
— Kepler's hyperbola along φ, whose time dt/dφ = m/(ℓu²) is infinite where u = 1/r reaches 0 (r = ∞) — and the
caller refuses times beyond.  A start on such a pole is refused.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .quadrature_motion import DPS, NotElliptic, _mp, _split_mp, rate_coefficients_mp

__all__ = ["RationalRate", "rational_rate_integral", "rational_path"]

#: the roundings one term of G carries, counted in :meth:`RationalRate.rounding`: its coefficient's rounding to a
#: double, the function's (log, power), the complex product, and its share of the sum
TERM = 4.0


def rational_path(motion: Any) -> str | None:
    """The path (see the module docstring) on which ``motion``'s u is U(x)/S(x), or None (an elliptic m in (0, 1),
    a steady motion, the cn and tan forms)."""
    if getattr(motion, "elementary", False):
        return "line" if motion.form == "polynomial" else "exp"
    from .quadrature_motion import EllipticMotionCn

    if isinstance(motion, EllipticMotionCn) or motion.steady:
        return None
    if motion.m == 0:
        return "circle"
    if motion.asymptotic:
        return "ray"
    return None


def _u_of_x(motion: Any, path: str) -> tuple[list, list]:
    """(U, S): u = U(x)/S(x), coefficients lowest degree first, at the working precision."""
    mp = _mp()
    if path == "line":
        u0, s, a = motion.constants
        return [u0, s, a], [mp.mpf(1)]
    if path == "exp":
        alpha, p_plus, p_minus = motion.constants
        return [p_minus, alpha, p_plus], [mp.mpf(0), mp.mpf(1)]
    A, B, C, D = motion.mobius
    if path == "circle":  # w = −(x − 1)²/(4x): N_w = −(1 − 2x + x²), S_w = 4x
        n_w, s_w = [-1, 2, -1], [0, 4, 0]
    else:  # ray: w = (x − 1)²/(x + 1)²
        n_w, s_w = [1, -2, 1], [1, 2, 1]
    U = [A * s + B * n for s, n in zip(s_w, n_w)]
    S = [C * s + D * n for s, n in zip(s_w, n_w)]
    return U, S


# --- polynomial helpers (coefficients lowest degree first, mpmath numbers) ------------------------------------

def _trim(p: list) -> list:
    p = list(p)
    while len(p) > 1 and p[-1] == 0:
        p.pop()
    return p


def _mul(p: list, q: list) -> list:
    out = [0] * (len(p) + len(q) - 1)
    for i, x in enumerate(p):
        if x == 0:
            continue
        for j, y in enumerate(q):
            out[i + j] += x * y
    return out


def _pow(p: list, e: int) -> list:
    out = [1]
    for _ in range(e):
        out = _mul(out, p)
    return out


def _add(p: list, q: list) -> list:
    n = max(len(p), len(q))
    return [(p[i] if i < len(p) else 0) + (q[i] if i < len(q) else 0) for i in range(n)]


def _compose(coeffs_high_first: list, U: list, S: list) -> list:
    """Σ c_k U^k S^{d−k} (d = deg of the given polynomial in u): its value at u = U/S times S^d."""
    d = len(coeffs_high_first) - 1
    total: list = [0]
    for i, c in enumerate(coeffs_high_first):
        k = d - i
        total = _add(total, [c * y for y in _mul(_pow(U, k), _pow(S, d - k))])
    return total


def _roots_with_multiplicity(p_low_first: list) -> list:
    """[(root, multiplicity)] of a polynomial (lowest first) of degree ≤ 2 exactly, else by polyroots clustered at
    10^(−DPS/2) (a multiple root comes out split by about 10^(−DPS/μ))."""
    mp = _mp()
    p = _trim(p_low_first)
    deg = len(p) - 1
    if deg <= 0:
        return []
    if deg == 1:
        return [(-p[0] / p[1], 1)]
    if deg == 2:
        c, b, a = p
        disc = b * b - 4 * a * c
        scale = abs(b) ** 2 + abs(4 * a * c)
        if abs(disc) <= mp.mpf(10) ** (-DPS + 5) * scale:
            return [(-b / (2 * a), 2)]
        sq = mp.sqrt(disc)  # complex for a negative or complex discriminant
        # the root of larger size first, the other from the product c/a (no cancellation)
        big = (-b - sq) / (2 * a) if abs(-b - sq) >= abs(-b + sq) else (-b + sq) / (2 * a)
        return [(big, 1), (c / (a * big), 1)] if big != 0 else [(mp.mpf(0), 2)]
    roots = mp.polyroots(p[::-1], maxsteps=400, extraprec=6 * DPS)
    tiny = mp.mpf(10) ** (-DPS // 3)
    out: list = []
    for r in roots:
        for i, (q, k) in enumerate(out):
            if abs(r - q) <= tiny * (1 + abs(q)):
                out[i] = ((q * k + r) / (k + 1), k + 1)
                break
        else:
            out.append((r, 1))
    return out


def _taylor_shift(p: list, rho: Any, order: int) -> list:
    """The first ``order`` Taylor coefficients of p at rho: p(rho + h) = Σ a_i h^i."""
    out = []
    work = list(p)
    for _ in range(order):
        # synthetic division by (x − rho): remainder is the value, the quotient's Taylor coefficients follow
        acc = 0
        quotient = [0] * max(len(work) - 1, 0)
        for i in range(len(work) - 1, -1, -1):
            acc = acc * rho + work[i]
            if i > 0:
                quotient[i - 1] = acc
        out.append(acc)
        work = quotient if quotient else [0]
    return out


def _series_mul(a: list, b: list, order: int) -> list:
    return [sum(a[i] * b[k - i] for i in range(k + 1)) for k in range(order)]


def _inverse_power_series(delta: Any, power: int, order: int) -> list:
    """Taylor coefficients in h of (delta + h)^(−power)."""
    out = []
    coef = delta ** (-power)
    for i in range(order):
        out.append(coef)
        coef = coef * (-(power + i)) / ((i + 1) * delta)
    return out


@dataclass
class RationalRate:
    """∫₀^τ R(u(τ')) dτ' by partial fractions in x (see the module docstring).  ``quotient``: the polynomial part's
    coefficients (lowest first); ``poles``: ((ρ, on_path, (c_1, …, c_μ)), …); ``gamma``: x = e^{γφ} (None on the
    line); the phase φ = κτ + φ_s.  Values at 40 digits; the doubles are taken once."""

    motion: Any
    path: str
    quotient: list
    poles: tuple
    gamma: Any
    kappa: Any
    phase_start: Any
    #: (τ₋, τ₊): the motion meets a pole of R there (the integral diverges); None if it never does
    singular_times: tuple | None = None
    _f: dict = field(default_factory=dict, repr=False)

    # --- the phase --------------------------------------------------------------------------------

    def _phase(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """φ(t) = κt + φ_s as (hi, lo) in double-double; on the circle reduced by the period 2π of x (the multiple
        of 2π kept apart, in the secular part, by :meth:`__call__`)."""
        from ..special._doubledouble import two_prod, two_sum

        if "k" not in self._f:
            self._f["k"] = _split_mp(self.kappa)
            self._f["s"] = _split_mp(self.phase_start)
        k_hi, k_lo = self._f["k"]
        s_hi, s_lo = self._f["s"]
        p, pe = two_prod(np.broadcast_to(k_hi, t.shape).astype(float), t)
        hi, e = two_sum(p, np.broadcast_to(s_hi, t.shape).astype(float))
        lo = e + pe + k_lo * t + s_lo
        hi, lo = two_sum(hi, lo)
        return hi, lo

    def _doubles(self) -> dict:
        if "poles" not in self._f:
            mp = _mp()
            with mp.workdps(DPS):
                self._f["quotient"] = [complex(q) for q in self.quotient]
                poles = []
                for rho, on_path, coefs in self.poles:
                    offset = complex(self._offset(rho)) if self.path in ("ray", "exp") and not on_path and rho != 0 \
                        else 0j
                    poles.append((complex(rho), on_path, [complex(c) for c in coefs], offset))
                self._f["poles"] = poles
                self._f["gamma"] = None if self.gamma is None else complex(self.gamma)
                if self.path == "circle":
                    # the secular rate Re(γ Σ c_{ρ,1}) over ρ = 0 and the poles inside the circle, in double-double:
                    # rounded to a double it would put an error of ε·|t| into t after many periods
                    inside = sum((coefs[0] for rho, on_path, coefs in self.poles
                                  if rho == 0 or (abs(rho) < 1 and not on_path)), mp.mpc(0))
                    self._f["secular"] = _split_mp(mp.re(inside * self.gamma))
        return self._f

    def _offset(self, rho: Any) -> Any:
        """On the ray: the multiple of 2πi between the two forms of log(x − ρ) (x ≥ |ρ|: log x + log(1 − ρ/x); below:
        log(−ρ) + log(1 − x/ρ)), fixed at x = |ρ| so that L_ρ is continuous."""
        mp = _mp()
        x = abs(rho)
        above = mp.log(x) + mp.log(1 - rho / x)
        below = mp.log(-rho) + mp.log(1 - x / rho)
        k = mp.nint(mp.im(above - below) / (2 * mp.pi))
        return mp.mpc(0, 2 * mp.pi * k)

    # --- evaluation in doubles ---------------------------------------------------------------------------

    def __call__(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        """∫₀^t R dt' at the times t (``jac`` is not needed: x is taken from the phase)."""
        return self.minus(t, 0.0)

    def minus(self, t: Any, target: Any) -> np.ndarray:
        """∫₀^t R dt' − ``target`` (arrays of the same shape, or a scalar target), formed without the integral's own
        rounding: on the circle the secular part S = Re(γΣc)·φ is a double-double product and target is subtracted
        from it exactly, so that the difference (a residual near a root, when t(c) is inverted) keeps its digits
        however large the integral has grown; the rest is rounded as :meth:`rounding` bounds."""
        from ..special._doubledouble import two_sum

        t = np.asarray(t, dtype=float)
        periodic, s_hi, s_lo, _ = self._parts(t, sized=False)
        p0, s0_hi, s0_lo, _ = self._start()
        # (S − target − S(0)) by two exact sums of the leading parts (exactly 0 at t = 0, target = 0)
        head, tail = two_sum(s_hi, -np.asarray(target, dtype=float))
        head, tail2 = two_sum(head, -s0_hi)
        return head + ((tail + tail2) + (s_lo - s0_lo) + (periodic - p0))

    def rounding(self, t: Any) -> np.ndarray:
        """A bound scale for the rounding of :meth:`minus` (and of the value, less its final rounding to a double)
        at the times t: ε·(M(t) + M(0)), M the sum over the terms of G of |term| and of |d term/dx| times the
        absolute rounding of x and of x − ρ (x from the phase: ε(2 + |γφ_r|)|x|, φ_r the reduced phase); the secular
        part is exact to ~ε²|S|.  The first-order rounding bound of the sum, each term carrying a few roundings:
        the caller scales it by a small factor and checks it against 30 digits at some times."""
        t = np.asarray(t, dtype=float)
        _, _, _, magnitude = self._parts(t)
        return 2.0**-52 * (magnitude + self._start()[3])

    def _start(self) -> tuple[float, float, float, float]:
        """(P, S_hi, S_lo, M) at τ = 0 (see :meth:`_parts`)."""
        if "start" not in self._f:
            self._f["start"] = tuple(float(x[0]) for x in self._parts(np.zeros(1)))
        return self._f["start"]

    def _parts(self, t: np.ndarray, sized: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(P, S_hi, S_lo, M): Re G(x(t)) = P + S, S the secular part (see the module docstring) in double-double
        (zero but on the circle), and M the magnitude that bounds the rounding of P (see :meth:`rounding`; not
        accumulated unless ``sized``: the values alone do not pay for it)."""
        f = self._doubles()
        zero = np.zeros(t.shape)
        if self.path == "line":
            x = t.astype(complex)
            total = np.zeros(t.shape, complex)
            size = np.zeros(t.shape)
            ax = np.abs(t)
            for k, q in enumerate(f["quotient"]):
                term = q * x ** (k + 1) / (k + 1)
                total = total + term
                if sized:
                    size = size + TERM * np.abs(term)
            for rho, on_path, coefs, _ in f["poles"]:
                d = x - rho
                with np.errstate(all="ignore"):
                    ad = np.abs(d)
                    dx = (0.5 * ax + abs(rho)) / ad  # x − ρ's relative error, over ε (ρ rounded, the difference)
                    log = np.log(ad) if on_path else np.log(d)
                    total = total + coefs[0] * log
                    if sized:
                        size = size + abs(coefs[0]) * (TERM * np.abs(log) + dx)
                    for k, c in enumerate(coefs[1:], start=2):
                        term = c * d ** (1 - k) / (1 - k)
                        total = total + term
                        if sized:
                            size = size + np.abs(term) * (TERM + (k - 1) * dx)
            return total.real, zero, zero, size
        hi, lo = self._phase(t)
        gamma = f["gamma"]
        if self.path == "circle":
            # x = e^{iγφ} has period 2π/|γ| in φ: reduce φ (the secular part below takes the multiple back)
            # (γ = 2i: period π, reduced in double-double so that long times keep the phase of x)
            from ..special._doubledouble import PI_HI, PI_LO, two_prod, two_sum

            n = np.floor(hi / np.pi + 0.5)
            h, he = two_prod(n, np.broadcast_to(PI_HI, n.shape).astype(float))
            dd, de = two_sum(hi, -h)
            red = dd + (de - he + lo - n * PI_LO)
            x = np.exp(gamma * red)
            inv_x = np.conj(x)
            # x's absolute rounding (|x| = 1), over ε: exp of an argument γ·red rounded to ε|γ·red|
            dx = 1.0 + abs(gamma) * np.abs(red)
            total = np.zeros(t.shape, complex)
            size = np.zeros(t.shape)
            for k, q in enumerate(f["quotient"]):
                term = q * x ** (k + 1) / (k + 1)
                total = total + term
                if sized:
                    size = size + TERM * np.abs(term) + abs(q) * (k + 1) * dx
            for rho, on_path, coefs, _ in f["poles"]:
                if sized:
                    with np.errstate(all="ignore"):
                        # (x − ρ)'s relative error, over ε: x's, and ρ's rounding to a double
                        near = (dx + abs(rho)) / np.abs(x - rho)
                if rho == 0:
                    log = 0.0
                elif abs(rho) < 1 and not on_path:
                    log = np.log1p(-rho * inv_x)
                else:
                    log = np.log1p(-x / rho)
                total = total + coefs[0] * log
                if sized:
                    size = size + abs(coefs[0]) * (TERM * np.abs(log) + (0.0 if rho == 0 else near))
                for k, c in enumerate(coefs[1:], start=2):
                    with np.errstate(all="ignore"):
                        term = c * (x - rho) ** (1 - k) / (1 - k)
                    total = total + term
                    if sized:
                        size = size + np.abs(term) * (TERM + (k - 1) * near)
            # φ = red + n·period: the secular part Re(γΣc)·φ with φ unreduced (hi + lo), in double-double
            from ..special._doubledouble import dd_mul

            c_hi, c_lo = f["secular"]
            s_hi, s_lo = dd_mul(np.broadcast_to(c_hi, t.shape).astype(float), np.full(t.shape, c_lo), hi, lo)
            # (the double-double product's own error, ~ε²|S|, counted generously)
            return total.real, s_hi, s_lo, size + 4.0 * 2.0**-52 * np.abs(s_hi)
        # the ray and exp paths: x = e^{γφ} > 0, or its inverse y where x is large
        g = gamma.real
        with np.errstate(over="ignore", under="ignore"):
            x = np.exp(g * hi) * (1.0 + g * lo)
            y = np.exp(-g * hi) * (1.0 - g * lo)
        dx = 1.0 + np.abs(g * hi)  # x's relative error, over ε: exp of an argument rounded to ε|γφ|
        total = np.zeros(t.shape, complex)
        size = np.zeros(t.shape)
        phase = g * hi + g * lo  # log x
        for k, q in enumerate(f["quotient"]):
            with np.errstate(over="ignore"):
                term = q * np.exp((k + 1) * g * hi) * (1.0 + (k + 1) * g * lo) / (k + 1)
            total = total + term
            if sized:
                size = size + np.abs(term) * (TERM + (k + 1) * dx)
        for rho, on_path, coefs, offset in f["poles"]:
            if rho == 0:
                total = total + coefs[0] * phase
                if sized:
                    size = size + abs(coefs[0]) * np.abs(phase) * TERM
                for k, c in enumerate(coefs[1:], start=2):
                    with np.errstate(over="ignore"):
                        term = c * np.exp((k - 1) * g * -hi) * (1.0 - (k - 1) * g * lo) / (1 - k)
                    total = total + term
                    if sized:
                        size = size + np.abs(term) * (TERM + (k - 1) * dx)
                continue
            r = abs(rho)
            above = x >= r
            with np.errstate(all="ignore"):
                # (x − ρ)'s relative rounding, over ε: (|x|·dx + |ρ|)/|x − ρ|, from y where x is large
                near = np.where(above, (dx + r * y) / np.abs(1.0 - rho * y), (x * dx + r) / np.abs(x - rho))
                if on_path:  # ρ > 0 on the ray: log|x − ρ|, from the nearer form
                    log = np.where(above, phase + np.log(np.abs(1.0 - rho.real * y)),
                                   np.log(r) + np.log(np.abs(1.0 - x / rho.real)))
                else:
                    log = np.where(above, phase + np.log1p(-rho * y), np.log(-rho) + np.log1p(-x / rho) + offset)
                total = total + coefs[0] * log
                if sized:
                    size = size + abs(coefs[0]) * (TERM * (np.abs(log) + np.abs(phase)) + near)
                for k, c in enumerate(coefs[1:], start=2):
                    # (x − ρ)^{1−k}: from y where x is large (x^{1−k} (1 − ρy)^{1−k})
                    far = y ** (k - 1) * (1.0 - rho * y) ** (1 - k)
                    near_value = (x - rho) ** (1 - k)
                    term = c * np.where(above, far, near_value) / (1 - k)
                    total = total + term
                    if sized:
                        size = size + np.abs(term) * (TERM + (k - 1) * near)
        return total.real, zero, zero, size

    # --- 30-digit reference ---------------------------------------------------------------------------------

    def value_mp(self, t) -> Any:
        """The integral at t from the 40-digit constants, at the caller's precision (mpmath): the same sums, with
        log(x − ρ) continued as in the doubles."""
        mp = _mp()
        return self._g_mp(mp.mpf(t)) - self._g_mp(mp.mpf(0))

    def _g_mp(self, t) -> Any:
        mp = _mp()
        if self.path == "line":
            total = sum(q * t ** (k + 1) / (k + 1) for k, q in enumerate(self.quotient))
            for rho, on_path, coefs in self.poles:
                d = t - rho
                total += coefs[0] * (mp.log(abs(d)) if on_path else mp.log(d))
                total += sum(c * d ** (1 - k) / (1 - k) for k, c in enumerate(coefs[1:], start=2))
            return mp.re(total)
        phi = self.kappa * t + self.phase_start
        x = mp.exp(self.gamma * phi)
        total = sum(q * x ** (k + 1) / (k + 1) for k, q in enumerate(self.quotient))
        for rho, on_path, coefs in self.poles:
            if rho == 0:
                log = self.gamma * phi
            elif self.path == "circle":
                log = (self.gamma * phi + mp.log(1 - rho / x)) if abs(rho) < 1 and not on_path else mp.log(1 - x / rho)
            elif on_path:
                log = mp.log(abs(x - rho))
            elif abs(x) >= abs(rho):
                log = self.gamma * phi + mp.log(1 - rho / x)
            else:
                log = mp.log(-rho) + mp.log(1 - x / rho) + self._offset(rho)
            total += coefs[0] * log
            total += sum(c * (x - rho) ** (1 - k) / (1 - k) for k, c in enumerate(coefs[1:], start=2))
        return mp.re(total)

    @property
    def advance(self) -> Any:
        """The increase over one period of u (π in v: x once round the circle), 2π·Re(Σ c_{ρ,1}·iγ)/|γ| over ρ = 0 and
        the poles inside the circle (the residue theorem); only on the circle (a periodic motion)."""
        if self.path != "circle":
            raise NotElliptic("expected a periodic motion for an advance per period, got one that does not return "
                              f"({'m = 1' if self.path == 'ray' else 'no period'})")
        mp = _mp()
        with mp.workdps(DPS):
            inside = sum((coefs[0] for rho, on_path, coefs in self.poles if rho == 0 or (abs(rho) < 1 and not on_path)),
                         mp.mpc(0))
            return mp.re(inside * self.gamma) * 2 * mp.pi / abs(self.gamma)


def rational_rate_integral(motion: Any, numerator: Sequence, denominator: Sequence) -> RationalRate:
    """∫ R(u) dτ along ``motion`` (a form of :func:`rational_path`) for R = N/D, N and D by their coefficients in u
    (highest first); raises :class:`NotElliptic` where the motion is not one of these forms or starts on a pole."""
    mp = _mp()
    path = rational_path(motion)
    if path is None:
        raise NotElliptic("expected u a rational function of e^{κt}, e^{2iv} or t (m = 0 or 1, or an elementary form)")
    with mp.workdps(DPS):
        N, Dn = rate_coefficients_mp(numerator, denominator)
        if Dn[0] == 0:
            raise NotElliptic("expected a rate with a nonzero denominator, got D ≡ 0")
        U, S = _u_of_x(motion, path)
        U, S = _trim(U), _trim(S)
        d, e = len(N) - 1, len(Dn) - 1
        # F = R(U/S)·dτ/dx = Ñ S^{e−d} / D̃ · 1/(κγx): numerator and the denominator's factors
        num = _compose(N, U, S)
        if e > d:
            num = _mul(num, _pow(S, e - d))
        factors: list = []  # (polynomial lowest first, multiplicity)
        lead = Dn[0]
        u_poles = _roots_with_multiplicity(Dn[::-1])
        for u_j, mu in u_poles:
            factors.append((_trim(_add(U, [-u_j * s for s in S])), mu))
        if d > e:
            factors.append((S, d - e))
        if path == "line":
            scale = mp.mpf(1)
        else:
            gamma = mp.mpc(0, 2) if path == "circle" else mp.mpf(2) if path == "ray" else mp.mpf(1)
            kappa = motion.kappa
            factors.append(([mp.mpf(0), mp.mpf(1)], 1))
            scale = kappa * gamma
        # the distinct roots in x, multiplicities summed over factors
        roots: list = []
        lead_total = lead * scale
        for poly, mu in factors:
            lead_total *= poly[-1] ** mu
            for rho, k in _roots_with_multiplicity(poly):
                for i, (sigma, j) in enumerate(roots):
                    if abs(rho - sigma) <= mp.mpf(10) ** (-DPS // 2) * (1 + abs(sigma)):
                        roots[i] = (sigma, j + k * mu)
                        break
                else:
                    roots.append((rho, k * mu))
        den: list = [lead_total]
        for rho, mu in roots:
            den = _mul(den, _pow([-rho, 1], mu))
        # the polynomial part: num = quotient·den + remainder
        quotient: list = []
        rem = list(num)
        while len(rem) >= len(den):
            f = rem[-1] / den[-1]
            quotient.append(f)
            shift = len(rem) - len(den)
            rem = [r - f * (den[i - shift] if 0 <= i - shift < len(den) else 0) for i, r in enumerate(rem)][:-1]
        quotient = quotient[::-1]
        poles = []
        on_path_any = []
        for rho, mu in roots:
            rest_series = [mp.mpf(1)] + [mp.mpf(0)] * (mu - 1)
            for sigma, nu in roots:
                if sigma is rho:
                    continue
                rest_series = _series_mul(rest_series, _inverse_power_series(rho - sigma, nu, mu), mu)
            h = _series_mul(_taylor_shift(num, rho, mu), rest_series, mu)
            coefs = [h[mu - k] / lead_total for k in range(1, mu + 1)]
            on_path = _on_path(path, rho)
            if on_path and any(abs(c) > 0 for c in coefs):
                on_path_any.append(rho)
            poles.append((rho, on_path, tuple(coefs)))
        phase_start = mp.mpf(0) if path in ("line", "exp") else motion.v_start
        rate = RationalRate(motion, path, quotient, tuple(poles), None if path == "line" else gamma,
                            mp.mpf(1) if path == "line" else motion.kappa, phase_start)
        if on_path_any:
            rate.singular_times = _singular_times(rate, on_path_any)
        return rate


def _on_path(path: str, rho: Any) -> bool:
    """Whether x = ρ lies on the path x(τ) (the unit circle, the positive ray, the real line), to 10^(−DPS/2)."""
    mp = _mp()
    tiny = mp.mpf(10) ** (-DPS // 2)
    if path == "circle":
        return abs(abs(rho) - 1) <= tiny
    if path == "line":
        return abs(mp.im(rho)) <= tiny * (1 + abs(rho))
    return abs(mp.im(rho)) <= tiny * (1 + abs(rho)) and mp.re(rho) > 0


def _singular_times(rate: RationalRate, on_path: list) -> tuple:
    """(τ₋, τ₊): the nearest times before and after τ = 0 where x(τ) reaches a pole on the path (±inf if none)."""
    mp = _mp()
    times = []
    for rho in on_path:
        if rate.path == "line":
            times.append(mp.re(rho))
            continue
        if rate.path == "circle":
            # e^{iγφ} = ρ: φ = arg ρ/|γ| + k·2π/|γ|
            g = abs(rate.gamma)
            base = mp.arg(rho) / g
            period = 2 * mp.pi / g
            k0 = mp.floor((rate.phase_start - base) / period)
            phis = [base + (k0 + j) * period for j in (-1, 0, 1, 2)]
        else:
            phis = [mp.log(mp.re(rho)) / mp.re(rate.gamma)]
        times += [(phi - rate.phase_start) / rate.kappa for phi in phis]
    tiny = mp.mpf(10) ** (-DPS // 2)
    if any(abs(x) <= tiny for x in times):
        raise NotElliptic("expected the start away from the rate's poles, got a start on one (the rate is infinite "
                          "there)")
    before = max((x for x in times if x < 0), default=-mp.inf)
    after = min((x for x in times if x > 0), default=mp.inf)
    return float(before), float(after)
