"""The motions of u̇² = P(u) that do not oscillate (issue 16): degree ≤ 1, the quadratic with no real root, the
cubic with one real root and the quartics escaping through ∞ with complex roots — closed forms in t that are
polynomial, exponential or Jacobian.

The periodic and asymptotic motions are :mod:`mechderive.solvers.quadrature_motion`'s; it hands these here.
Each form below is derived from ü = P'(u)/2 (the derivative of u̇² = P(u) divided by 2u̇) and checked in the tests
against DOP853 on that equation:

* **deg P ≤ 1**, P = c1 u + c0: ü = c1/2, so u = u0 + u̇0 t + (c1/4) t² with u̇0 = ±√P(u0) — uniform motion
  (c1 = 0: a free particle, a free rotor) or uniformly accelerated (a body falling under uniform gravity).  From a
  start on the root r = −c0/c1 (u̇0 = 0) the motion leaves it on the side where P > 0, i.e. the sign of c1.  The
  root is the one turning point (reached at t_r = −2u̇0/c1, in the past or the future); no period.  The form has
  no division by c1, so c1 → 0 loses nothing (only the turning point, −c0/c1, recedes to ∞).
* **a quadratic with no real root**, P = c2((u − α)² + β²), c2 > 0: ü = c2 (u − α), so

      u = α + β sinh(κ t + v_s) = α + p₊ e^{κt} + p₋ e^{−κt},   κ = √c2,   p± = ((u0 − α) ± u̇0/κ)/2,

  (p± = ±β e^{±v_s}/2); u passes through every value, with no turning point.  p₊p₋ = −β²/4, so the smaller of
  the two is taken as −β²/(4·the larger) (no cancellation when β ≪ |u0 − α|); a pair so near the real axis that
  β² is lost at the working precision (a nearly double root) is refused.
* **a cubic with one real root r** and the complex pair α ± iβ, lead c3: P > 0 on the side σ = sign c3 of r,
  where u runs from r out to ∞ and reaches it in a finite time (Byrd & Friedman 239.00 for σ = +1, and its mirror
  u → −u; derived in the docstring of :func:`_cubic_complex_pair`):

      u = r + σ A (1 − cn v)/(1 + cn v),   v = κ t + v_s,   A² = (r − α)² + β²,
      m = 1/2 − σ (r − α)/(2A),   κ² = |c3| A,

  the Möbius form (A + B cn)/(C + D cn) of :class:`~mechderive.solvers.quadrature_motion.EllipticMotionCn`.  u
  is infinite at cn = −1, v = ±2K: the motion exists for (−2K − v_s)/κ < t < (2K − v_s)/κ
  (:attr:`~mechderive.solvers.quadrature_motion.EllipticMotion.escape_times`), and the closed form refuses times
  beyond, as for the cubic's real-root branch u ≥ r3.

* **a quartic with two real roots, a complex pair and a positive lead**, u outside the real roots: from the root on
  u0's side out to ∞ in cn (:func:`complex_pair_quartic_outside`, B&F 260.00), escaping in finite time.
* **a quartic with no real root** (two complex pairs, positive lead): u = α1 + b tan(φ0 + am(κt + v_s)) from
  u = α1 + b tan φ, which turns dt = du/√P into dψ/(κ√(1 − m sin²ψ)) (:func:`two_pair_quartic`); u passes every
  value between its escapes to −∞ and +∞.

A cyclic coordinate's rate ċ = R(u) that is a polynomial in u integrates in closed form on the first two
(:func:`elementary_rate_integral`): on u = u0 + s t + a t², R(u(t)) is a polynomial in t; on u = α + p₊E + p₋/E,
E = e^{κt}, it is Σ_j C_j E^j (j = −deg R … deg R), and ∫₀^t = C_0 t + Σ_{j≠0} C_j (e^{jκt} − 1)/(jκ) — a
projectile's horizontal coordinate, ẏ = p_y − w x with a magnetic-like coupling.

* **a quadratic with a double root r**, P = c2 (u − r)², c2 > 0, from u0 ≠ r: u = r + (u0 − r) e^{±κt}
  (:func:`exponential_double_root`), towards r or away from it, never reaching it.

A rate with poles in u (a rational R) on these forms, and on the m = 0 and m = 1 forms, integrates by partial
fractions in e^{κt} (or t): :mod:`mechderive.solvers.quadrature_rational`; on the cn and tan forms by its Fourier
series in the Jacobi argument, its error measured by a 30-digit refit: :mod:`mechderive.solvers.quadrature_fourier`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .quadrature_motion import DPS, EllipticMotionCn, NotElliptic, _mp, _outside, _split_mp

__all__ = ["ElementaryMotion", "exponential_double_root", "EllipticMotionCubicPair", "EllipticMotionCnEscape", "ElementaryRate", "open_motion",
           "elementary_rate_integral", "complex_pair_quartic_outside", "EllipticMotionTan", "two_pair_quartic"]


@dataclass
class ElementaryMotion:
    """u(t) in elementary functions of t: ``form`` "polynomial" (u = u0 + s t + a t², ``constants`` = (u0, s, a)) or
    "exponential" (u = α + p₊ e^{κt} + p₋ e^{−κt}, ``constants`` = (α, p₊, p₋)); mpmath numbers at 40 digits.

    ``interval`` = (turning point, ±∞) when there is one (the root of a linear P; −∞ or +∞ as the side the
    motion lies on), else (−∞, ∞).  The protocol of :class:`~mechderive.solvers.quadrature_motion.EllipticMotion`
    that :mod:`mechderive.systems.lagrangian.closed` uses, with t itself as the "phase": :meth:`jacobi` returns
    (t,), :meth:`mp_state` u and u̇ at the caller's precision (the estimate's reference).
    """

    coefficients: tuple
    degree: int
    form: str
    constants: tuple
    interval: tuple
    #: the rate of the exponential form (√c2), the time scale's inverse; 1 for the polynomial form
    kappa: Any
    steady: bool = False
    _f: dict = field(default_factory=dict, repr=False)
    #: u tends to a double root of P (as t → ∞ or −∞) and never reaches it: u − r ∝ e^{±κt}
    asymptotic: bool = False

    #: no Jacobi functions: the closed form's estimate and folds take the elementary path
    elementary = True
    escape_times = None
    m = None

    @property
    def u_period(self) -> Any:
        return _mp().inf

    @property
    def turning_point(self) -> Any:
        """The root of P the motion turns at (None if it has none)."""
        a, b = self.interval
        mp = _mp()
        return None if mp.isinf(a) else a

    def _doubles(self) -> tuple:
        if "c" not in self._f:
            with _mp().workdps(DPS):
                self._f["c"] = tuple(float(x) for x in self.constants)
                self._f["k"] = _split_mp(self.kappa)
        return self._f["c"]

    def jacobi(self, t: Any) -> tuple:
        return (np.asarray(t, dtype=float),)

    def _exp(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(e^{κt}, e^{−κt}) with κt in double-double (κ's rounding is not multiplied by t)."""
        from ..special._doubledouble import two_prod

        self._doubles()
        k_hi, k_lo = self._f["k"]
        p, pe = two_prod(np.broadcast_to(k_hi, t.shape).astype(float), t)
        small = pe + k_lo * t
        with np.errstate(over="ignore"):
            return np.exp(p) * (1.0 + small), np.exp(-p) * (1.0 - small)

    def u(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        t = np.asarray(t, dtype=float) if jac is None else jac[0]
        c = self._doubles()
        if self.form == "polynomial":
            return c[0] + t * (c[1] + c[2] * t)
        ep, em = self._exp(t)
        return c[0] + (self._times(c[1], ep) + self._times(c[2], em))

    @staticmethod
    def _times(p: float, e: np.ndarray) -> np.ndarray:
        """p e^{±κt}; 0 where p = 0 (the double root's one-sided form), also where e^{κt} overflows."""
        return p * e if p != 0.0 else np.zeros_like(e)

    def u_dot(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        t = np.asarray(t, dtype=float) if jac is None else jac[0]
        c = self._doubles()
        if self.form == "polynomial":
            return c[1] + 2.0 * c[2] * t
        ep, em = self._exp(t)
        return self._f["k"][0] * (self._times(c[1], ep) - self._times(c[2], em))

    def minus(self, point: Any, t: Any, jac: tuple | None = None) -> np.ndarray:
        """u(t) − ``point`` (the rates offered here have no poles, near which this would need more care)."""
        return self.u(t, jac) - float(point)

    def signed_root(self, end: str, t: Any, jac: tuple | None = None) -> tuple:
        raise NotElliptic("expected no fold of the substitution on a motion without an elliptic closed form "
                          "(a fold at the turning point of an unbounded motion is not covered)")

    def mp_state(self, t: Any) -> tuple:
        """(u, u̇) at t from the 40-digit constants, at the caller's precision (mpmath)."""
        mp = _mp()
        t = mp.mpf(t)
        c0, c1, c2 = self.constants
        if self.form == "polynomial":
            return c0 + t * (c1 + c2 * t), c1 + 2 * c2 * t
        ep, em = mp.exp(self.kappa * t), mp.exp(-self.kappa * t)
        return c0 + c1 * ep + c2 * em, self.kappa * (c1 * ep - c2 * em)

    def u_mp(self, t) -> Any:
        mp = _mp()
        with mp.workdps(DPS):
            return self.mp_state(t)[0]


class EllipticMotionCubicPair(EllipticMotionCn):
    """u = r + σA(1 − cn v)/(1 + cn v) for a cubic with one real root (see the module docstring): the Möbius form
    of :class:`EllipticMotionCn` with (A + B cn)/(C + D cn) = ((r + σA) + (r − σA) cn)/(1 + cn), evaluated in the
    forms that keep their digits at both ends: σ(u − r) = A sn²/(1 + cn)² while cn ≥ 0 (near the root), and
    A (1 − cn)²/sn² while cn < 0 (near the escape at cn = −1, where 1 + cn would cancel)."""

    def _parts(self) -> tuple[float, float]:
        A, B, C, D, det = self._mob()
        return (A + B) / 2.0, (A - B) / 2.0  # r and σA

    def u(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        r, sa = self._parts()
        with np.errstate(all="ignore"):
            return r + sa * np.where(cn >= 0, sn * sn / (1.0 + cn) ** 2, (1.0 - cn) ** 2 / (sn * sn))

    def u_dot(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        """u̇ = 2σAκ sn dn/(1 + cn)² (d cn/dv = −sn dn), with 1/(1 + cn)² = (1 − cn)²/sn⁴ while cn < 0."""
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        r, sa = self._parts()
        kap = float(self.kappa)
        with np.errstate(all="ignore"):
            return 2.0 * sa * kap * dn * np.where(cn >= 0, sn / (1.0 + cn) ** 2, (1.0 - cn) ** 2 / sn**3)

    def minus(self, point: Any, t: Any, jac: tuple | None = None) -> np.ndarray:
        mp = _mp()
        A, B, C, D = self.mobius
        with mp.workdps(DPS):
            shift = float((A + B) / 2 - point)
        r, _ = self._parts()
        return shift + (self.u(t, jac) - r)

    def mp_u(self, sn, cn, dn) -> Any:
        A, B, C, D = self.mobius
        r, sa = (A + B) / 2, (A - B) / 2
        return r + sa * (sn * sn / (1 + cn) ** 2 if cn >= 0 else (1 - cn) ** 2 / (sn * sn))

    def mp_u_dot(self, sn, cn, dn) -> Any:
        A, B, C, D = self.mobius
        sa = (A - B) / 2
        return 2 * sa * self.kappa * dn * (sn / (1 + cn) ** 2 if cn >= 0 else (1 - cn) ** 2 / sn**3)

    @property
    def escape_times(self) -> tuple[float, float]:
        """(t₋, t₊): u is infinite at v = ±2K (cn = −1), before and after the start."""
        mp = _mp()
        with mp.workdps(DPS):
            return float((-2 * self.K - self.v_start) / self.kappa), float((2 * self.K - self.v_start) / self.kappa)

    def u_mp(self, t) -> Any:
        mp = _mp()
        with mp.workdps(DPS):
            v = self.kappa * mp.mpf(t) + self.v_start
            return self.mp_u(*(mp.ellipfun(f, v, m=self.m) for f in ("sn", "cn", "dn")))


class EllipticMotionCnEscape(EllipticMotionCn):
    """u = (A + B cn v)/(C + D cn v) for a quartic with two real roots, a complex pair and a positive lead, u outside
    the real roots (see :func:`complex_pair_quartic_outside`): from the root e on u0's side (cn = 1) out to ∞, which
    it reaches at the pole cn_p = −C/D, v = ±v_p (:attr:`escape_times`)."""

    @property
    def escape_times(self) -> tuple[float, float]:
        mp = _mp()
        A, B, C, D = self.mobius
        with mp.workdps(DPS):
            v_p = mp.ellipf(mp.acos(-C / D), self.m)  # in (0, 2K); v_s in (−v_p, v_p)
            return float((-v_p - self.v_start) / self.kappa), float((v_p - self.v_start) / self.kappa)


def complex_pair_quartic_outside(c: list, roots: list, u0: Any, direction: int) -> EllipticMotionCnEscape:
    """P = c4 (u − a)(u − b)((u − α)² + β²), c4 > 0, u0 outside [a, b]: with e the real root on u0's side, f the other,
    E = |e − z|, F = |f − z| (z = α + iβ),

        u = (eF − fE + (eF + fE) cn v)/(F − E + (F + E) cn v),   m = ((E + F)² − (e − f)²)/(4EF),   κ² = c4 E F,

    u = e at cn = 1, f at cn = −1 and ∞ between, at cn_p = −(F − E)/(F + E): the bounded form of Byrd & Friedman
    259.00 with one distance's sign turned, which moves the pole of the Möbius map onto the arc from e through ∞
    to f (B&F 260.00).  m and κ² are checked against P at two values of cn (the ratio κ² = P/(du/dv)² must be
    constant), and u(t) in the tests against DOP853."""
    mp = _mp()
    e, f = _outside(u0, *roots, "between the real roots")
    pair = [z for z in mp.polyroots(c, maxsteps=400, extraprec=6 * mp.mp.dps) if abs(mp.im(z)) > 0]
    alpha, beta = mp.re(pair[0]), abs(mp.im(pair[0]))
    E, F = mp.sqrt((e - alpha) ** 2 + beta**2), mp.sqrt((f - alpha) ** 2 + beta**2)
    m = ((E + F) ** 2 - (e - f) ** 2) / (4 * E * F)
    m1 = ((e - f) ** 2 - (E - F) ** 2) / (4 * E * F)
    k2 = c[0] * E * F
    A, B, C, D = e * F - f * E, e * F + f * E, F - E, F + E
    P = lambda x: mp.polyval(c, x)  # noqa: E731

    def kappa_sq(cn):
        du = (B * C - A * D) / (C + D * cn) ** 2
        return P((A + B * cn) / (C + D * cn)) / (du**2 * (1 - cn * cn) * (m1 + m * cn * cn))

    for cn in (mp.mpf(9) / 10, mp.mpf(1) / 3):
        if not 0 < m < 1 or abs(kappa_sq(cn) - k2) > mp.mpf(10) ** -8 * abs(k2):
            raise NotElliptic(f"expected the cn form to fit the quartic (κ² constant), got {mp.nstr(k2, 8)} and "
                              f"{mp.nstr(kappa_sq(cn), 8)}: an inconsistent root configuration")
    if m1 < mp.mpf(10) ** -15:
        raise NotElliptic(f"expected the complex pair away from the motion, got 1 − m = {mp.nstr(m1, 3)}: a nearly "
                          "double root, not covered")
    kappa = mp.sqrt(k2)
    K = mp.ellipk(m)
    # cn0 from the inverse Möbius map, taken as 1 − cn0 and acos as 2 asin √((1 − cn0)/2), which keep their digits
    # at the root (cn0 → 1)
    one_minus = (C + D) * (u0 - e) / (D * u0 - B)  # 1 − cn0 without cancellation: ((C + D)u0 − (A + B))/(D u0 − B)
    v0 = mp.ellipf(2 * mp.asin(mp.sqrt(max(min(one_minus / 2, mp.mpf(1)), mp.mpf(0)))), m)
    rising = -(B * C - A * D) > 0  # du/dv = −det sn dn/(C + D cn)² on (0, 2K)
    v_start = mp.mpf(0) if direction == 0 else (v0 if (direction > 0) == rising else -v0)
    return EllipticMotionCnEscape(tuple(c), (e, f), (e, f, mp.mpf("nan"), mp.mpf("nan")), (A, B, C, D), m, m1, kappa,
                                  v_start, K, mp.inf, 4)


class EllipticMotionTan(EllipticMotionCn):
    """u = α1 + b tan(φ0 + am v) for a quartic with two complex pairs and a positive lead (see
    :func:`two_pair_quartic`), written from sn and cn: tan(φ0 + am v) = (s0 cn + c0 sn)/(c0 cn − s0 sn) with
    (s0, c0) = (sin φ0, cos φ0) — ``mobius`` = (α1, b, s0, c0).  u passes every value and is infinite where
    φ0 + am v = ±π/2 (:attr:`escape_times`)."""

    def _tan_parts(self) -> tuple[float, float, float, float]:
        if "tan" not in self._f:
            with _mp().workdps(DPS):
                self._f["tan"] = tuple(float(x) for x in self.mobius)
        return self._f["tan"]

    def u(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        alpha, b, s0, c0 = self._tan_parts()
        with np.errstate(all="ignore"):
            return alpha + b * (s0 * cn + c0 * sn) / (c0 * cn - s0 * sn)

    def u_dot(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        """u̇ = b κ dn / cos²(φ0 + am v) (d am/dv = dn), cos(φ0 + am v) = c0 cn − s0 sn."""
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        alpha, b, s0, c0 = self._tan_parts()
        with np.errstate(all="ignore"):
            return b * float(self.kappa) * dn / (c0 * cn - s0 * sn) ** 2

    def minus(self, point: Any, t: Any, jac: tuple | None = None) -> np.ndarray:
        return self.u(t, jac) - float(point)

    def mp_u(self, sn, cn, dn) -> Any:
        alpha, b, s0, c0 = self.mobius
        return alpha + b * (s0 * cn + c0 * sn) / (c0 * cn - s0 * sn)

    def mp_u_dot(self, sn, cn, dn) -> Any:
        alpha, b, s0, c0 = self.mobius
        return b * self.kappa * dn / (c0 * cn - s0 * sn) ** 2

    def u_mp(self, t) -> Any:
        mp = _mp()
        with mp.workdps(DPS):
            v = self.kappa * mp.mpf(t) + self.v_start
            return self.mp_u(*(mp.ellipfun(f, v, m=self.m) for f in ("sn", "cn", "dn")))

    @property
    def escape_times(self) -> tuple[float, float]:
        """am v = ±π/2 − φ0 around the start: v = F(±π/2 − φ0 | m) (F of any real amplitude)."""
        mp = _mp()
        alpha, b, s0, c0 = self.mobius
        with mp.workdps(DPS):
            phi0 = mp.atan2(s0, c0)
            ahead, behind = (mp.ellipf(x - phi0, self.m) for x in (mp.pi / 2, -mp.pi / 2))
            return float((behind - self.v_start) / self.kappa), float((ahead - self.v_start) / self.kappa)


def two_pair_quartic(c: list, u0: Any, direction: int) -> EllipticMotionTan:
    """P = c4 ((u − α1)² + β1²)((u − α2)² + β2²), c4 > 0: no real root, u passes every value and reaches ±∞ in finite
    time.  Derivation: with u = α1 + b tan φ (b = ±β1 by the direction, so that φ grows with t),
    (u − α1)² + β1² = β1² sec²φ and du = b sec²φ dφ, so

        dt = du/(d·√P) = dφ / (√c4 √Q(φ)),   Q(φ) = ((α1 − α2) cos φ + b sin φ)² + β2² cos²φ,

    a positive quadratic form A cos²φ + 2B sin φ cos φ + C sin²φ (A = (α1 − α2)² + β2², B = (α1 − α2) b, C = β1²)
    = λ1 cos²ψ + λ2 sin²ψ with ψ = φ − φ0, 2φ0 = atan2(B, (A − C)/2), λ1,2 = (A + C)/2 ± R, R = √(((A − C)/2)² + B²),
    λ2 = β1²β2²/λ1.  Hence κ t = F(ψ|m) − F(ψ_s|m) with m = 2R/λ1, 1 − m = λ2/λ1, κ² = c4 λ1: ψ = am(κt + v_s),
    u = α1 + b tan(φ0 + am(κt + v_s)).  Checked in the tests against DOP853 and ∫du/√P.
    """
    mp = _mp()
    pairs = sorted((z for z in mp.polyroots(c, maxsteps=400, extraprec=6 * mp.mp.dps) if mp.im(z) > 0),
                   key=lambda z: -mp.im(z))
    if len(pairs) != 2:
        raise NotElliptic(f"expected two complex pairs of roots, got {len(pairs)}: an inconsistent configuration")
    (alpha1, beta1), (alpha2, beta2) = ((mp.re(z), mp.im(z)) for z in pairs)
    if direction == 0:
        raise NotElliptic("expected u̇0 ≠ 0 where P has no real root (u̇² = P > 0 everywhere), got 0")
    b = direction * beta1
    A, B, C = (alpha1 - alpha2) ** 2 + beta2**2, (alpha1 - alpha2) * b, beta1**2
    R = mp.sqrt(((A - C) / 2) ** 2 + B**2)
    lam1 = (A + C) / 2 + R
    m, m1 = 2 * R / lam1, (beta1 * beta2 / lam1) ** 2
    if m1 < mp.mpf(10) ** -15:
        raise NotElliptic(f"expected complex pairs away from the real axis, got 1 − m = {mp.nstr(m1, 3)}: a nearly "
                          "double root the motion passes, not covered")
    phi0 = mp.atan2(B, (A - C) / 2) / 2
    kappa = mp.sqrt(c[0] * lam1)
    # the check of the derivation: κ² = P/(du/dv)² at two phases (du/dv = b dn / cos²(φ0 + am v))
    for v in (mp.mpf(1) / 3, -mp.mpf(7) / 10):
        sn, cn, dn = (mp.ellipfun(f, v, m=m) for f in ("sn", "cn", "dn"))
        cos = mp.cos(phi0) * cn - mp.sin(phi0) * sn
        u = alpha1 + b * (mp.sin(phi0) * cn + mp.cos(phi0) * sn) / cos
        ratio = mp.polyval(c, u) / (b * dn / cos**2) ** 2
        if abs(ratio - kappa**2) > mp.mpf(10) ** -8 * kappa**2:
            raise NotElliptic(f"expected the tan form to fit the quartic (κ² constant), got {mp.nstr(kappa**2, 8)} and "
                              f"{mp.nstr(ratio, 8)}: an inconsistent root configuration")
    phi_start = mp.atan((u0 - alpha1) / b)
    v_start = mp.ellipf(phi_start - phi0, m)
    return EllipticMotionTan(tuple(c), (-mp.inf, mp.inf), (mp.mpf("nan"),) * 4, (alpha1, b, mp.sin(phi0), mp.cos(phi0)),
                             m, m1, kappa, v_start, mp.ellipk(m), mp.inf, 4)


def open_motion(c: list, roots: list, u0: Any, direction: int) -> Any:
    """The motion of u̇² = P(u) (``c`` P's coefficients, highest first, leading one nonzero unless P ≡ 0; ``roots``
    its real roots) for the configurations of the module docstring, at the caller's working precision; raises
    :class:`NotElliptic` for the others."""
    mp = _mp()
    degree = len(c) - 1
    if degree <= 1:
        return _polynomial(c, u0, direction)
    if degree == 2 and not roots:
        if c[0] < 0:
            raise NotElliptic(f"expected u̇² = P(u0) ≥ 0, got a quadratic P < 0 everywhere (u0 = {mp.nstr(u0, 10)})")
        return _exponential(c, u0, direction)
    if degree == 3 and len(roots) == 1:
        return _cubic_complex_pair(c, roots[0], u0, direction)
    if degree == 4 and not roots:
        if c[0] < 0:
            raise NotElliptic(f"expected u̇² = P(u0) ≥ 0, got a quartic P < 0 everywhere (u0 = {mp.nstr(u0, 10)})")
        return two_pair_quartic(c, u0, direction)
    raise NotElliptic(f"expected a configuration of degree ≤ 1, a quadratic with no real root or a cubic with one, "
                      f"got degree {degree} with {len(roots)} real roots")


def _speed(c: list, u0: Any, direction: int) -> Any:
    """u̇0 = direction·√P(u0) (P(u0) < 0 within the rounding of doubles taken as exact is a start on a root)."""
    mp = _mp()
    value = mp.polyval(c, u0)
    scale = sum(abs(x) * abs(u0) ** (len(c) - 1 - i) for i, x in enumerate(c)) + mp.mpf(10) ** -300
    if value < -mp.mpf(2) ** -40 * scale:
        raise NotElliptic(f"expected u̇² = P(u0) ≥ 0, got P(u0) = {mp.nstr(value, 5)} at u0 = {mp.nstr(u0, 10)}")
    return direction * mp.sqrt(max(value, mp.mpf(0)))


def _polynomial(c: list, u0: Any, direction: int) -> ElementaryMotion:
    """P = c1 u + c0 (c1 = 0 allowed): u = u0 + u̇0 t + (c1/4) t² (ü = P'/2 = c1/2)."""
    mp = _mp()
    c = [mp.mpf(0)] * (2 - len(c)) + list(c)
    c1, c0 = c
    if c1 == 0:
        if c0 < 0:
            raise NotElliptic(f"expected u̇² = P ≥ 0, got the constant P = {mp.nstr(c0, 5)} < 0")
        speed = direction * mp.sqrt(c0)
        interval = (-mp.inf, mp.inf)
        if direction == 0 and c0 > 0:
            raise NotElliptic("expected a direction for a uniform motion (u̇0 ≠ 0), got none")
        steady = c0 == 0
        if steady:  # P ≡ 0: at rest, u ≡ u0
            speed = mp.mpf(0)
            interval = (u0, u0)
        return ElementaryMotion(tuple(c), 0, "polynomial", (u0, speed, mp.mpf(0)), interval, mp.mpf(1), steady=steady)
    speed = _speed(c, u0, direction)
    if direction == 0:
        # a start on the root: u̇ grows as (c1/2) t, towards the side where P > 0 (that of c1) — the form covers it
        speed = mp.mpf(0)
    root = -c0 / c1
    interval = (root, mp.inf if c1 > 0 else -mp.inf)
    return ElementaryMotion(tuple(c), 1, "polynomial", (u0, speed, c1 / 4), interval, mp.mpf(1))


def _exponential(c: list, u0: Any, direction: int) -> ElementaryMotion:
    """P = c2((u − α)² + β²), c2 > 0: u = α + p₊e^{κt} + p₋e^{−κt} (see the module docstring)."""
    mp = _mp()
    c2, c1, c0 = c
    alpha = -c1 / (2 * c2)
    beta_sq = c0 / c2 - alpha**2
    # β² from c0/c2 − α² cancels to ~10^-DPS of α²: a pair nearer the real axis than that is not resolved (it may be
    # a double root, u − α ∝ e^{±κt}: exponential_double_root, when the 40-digit roots are double)
    if not beta_sq > mp.mpf(10) ** (-DPS + 10) * (alpha**2 + abs(c0 / c2)):
        raise NotElliptic(f"expected a complex pair of roots resolved at {DPS} digits, got α ± iβ with β² = "
                          f"{mp.nstr(beta_sq, 3)} beside α = {mp.nstr(alpha, 10)}: a nearly double root, not covered")
    if direction == 0:
        raise NotElliptic("expected u̇0 ≠ 0 where P has no real root (u̇² = P > 0 everywhere), got 0")
    kappa = mp.sqrt(c2)
    x0 = u0 - alpha
    # u̇0/κ = ±√(x0² + β²): the larger of p± = (x0 ± u̇0/κ)/2 directly, the other from p₊p₋ = −β²/4
    half = direction * mp.sqrt(x0**2 + beta_sq)
    if (x0 >= 0) == (half >= 0):
        big = (x0 + half) / 2
        p_plus, p_minus = big, -beta_sq / (4 * big)
    else:
        big = (x0 - half) / 2
        p_plus, p_minus = -beta_sq / (4 * big), big
    return ElementaryMotion(tuple(c), 2, "exponential", (alpha, p_plus, p_minus), (-mp.inf, mp.inf), kappa)


def exponential_double_root(c: list, r: Any, u0: Any, direction: int) -> ElementaryMotion:
    """P = c2 (u − r)², c2 > 0, u0 ≠ r: ü = c2 (u − r), and u̇ = ±κ (u − r) with κ = √c2 at every time, so

        u = r + (u0 − r) e^{sκt},   s = sign(u̇0 (u0 − r)),

    the limit of the exponential form α + p₊e^{κt} + p₋e^{−κt} as β → 0 with one p zero: the motion along the
    separatrix of an inverted oscillator, towards the unstable equilibrium r (s = −1: reached as t → ∞) or away
    from it (s = +1: left as t → −∞).  r is the motion's bound on u0's side, approached and never reached; the
    other side is unbounded.  ``r`` is the double root (P's pair merged at the working precision)."""
    mp = _mp()
    x0 = u0 - r
    if direction == 0 or x0 == 0:
        raise NotElliptic("expected a start off the double root of P = c2 (u − r)² with u̇0 ≠ 0, got u̇0 = 0")
    kappa = mp.sqrt(c[0])
    away = (direction > 0) == (x0 > 0)
    p_plus, p_minus = (x0, mp.mpf(0)) if away else (mp.mpf(0), x0)
    return ElementaryMotion(tuple(c), 2, "exponential", (r, p_plus, p_minus), (r, mp.inf if x0 > 0 else -mp.inf),
                            kappa, asymptotic=True)


def _cubic_complex_pair(c: list, r: Any, u0: Any, direction: int) -> EllipticMotionCubicPair:
    """P = c3 (u − r)((u − α)² + β²), the motion on the side σ = sign c3 of r.

    Derivation (x = σ(u − r) ≥ 0, s = σ(r − α), A² = s² + β²; the mirror u → −u makes σ = −1 the case σ = +1):
    with cn = (A − x)/(A + x), i.e. x = A(1 − cn)/(1 + cn) = A sn²/(1 + cn)²,

        (u − α)² + β² = x² + 2 s x + A² = 2A² [(1 + s/A) + (1 − s/A) cn²]/(1 + cn)² = 4A² dn²/(1 + cn)²

    exactly when m/(1 − m) = (1 − s/A)/(1 + s/A), m = (1 − s/A)/2; and dx/dv = 2A sn dn/(1 + cn)², so that
    (dx/dv)² = P(u)/(|c3| A): u̇² = P(u) with v = κ t + v_s, κ² = |c3| A.  Checked numerically below (κ² at two
    values of cn) and in the tests against DOP853.
    """
    mp = _mp()
    sigma = 1 if c[0] > 0 else -1
    # the pair from P/(u − r): synthetic division, then the quadratic's α and β²
    q2 = c[0]
    q1 = c[1] + r * q2
    q0 = c[2] + r * q1
    alpha = -q1 / (2 * q2)
    beta_sq = q0 / q2 - alpha**2
    if not beta_sq > mp.mpf(10) ** (-DPS + 10) * (alpha**2 + abs(q0 / q2)):
        raise NotElliptic(f"expected a complex pair of roots resolved at {DPS} digits, got α ± iβ with β² = "
                          f"{mp.nstr(beta_sq, 3)} beside α = {mp.nstr(alpha, 10)}: a nearly double root, not covered")
    x0 = sigma * (u0 - r)
    if x0 < -mp.mpf(2) ** -40 * (1 + abs(u0)):
        raise NotElliptic(f"expected u̇² = P(u0) ≥ 0, got u0 = {mp.nstr(u0, 10)} on the side of the root "
                          f"{mp.nstr(r, 10)} where P < 0")
    x0 = max(x0, mp.mpf(0))
    s = sigma * (r - alpha)
    A = mp.sqrt(s**2 + beta_sq)
    # m and 1 − m without cancellation: (A ∓ s)/(2A), the small one as β²/(2A(A ± s))
    if s >= 0:
        m, m1 = beta_sq / (2 * A * (A + s)), (A + s) / (2 * A)
    else:
        m, m1 = (A - s) / (2 * A), beta_sq / (2 * A * (A - s))
    # the pair near the real axis on the motion's side: u passes a near-double root slowly (m → 1); the 30-digit
    # reference would keep too few digits of 1 − m to measure the estimate
    if m1 < mp.mpf(10) ** -15:
        raise NotElliptic(f"expected the complex pair away from the motion, got 1 − m = {mp.nstr(m1, 3)} (β = "
                          f"{mp.nstr(mp.sqrt(beta_sq), 3)}): a nearly double root the motion passes, not covered")
    k2 = abs(c[0]) * A
    mob = (r + sigma * A, r - sigma * A, mp.mpf(1), mp.mpf(1))
    P = lambda x: mp.polyval(c, x)  # noqa: E731

    def kappa_sq(cn):
        sn2 = 1 - cn * cn
        du = 2 * A / (1 + cn) ** 2  # |du/dv| / (sn dn)
        return P(r + sigma * A * (1 - cn) / (1 + cn)) / (du**2 * sn2 * (m1 + m * cn * cn))

    for cn in (mp.mpf(1) / 3, -mp.mpf(2) / 5):
        if abs(kappa_sq(cn) - k2) > mp.mpf(10) ** -8 * abs(k2):
            raise NotElliptic(f"expected the cn form to fit the cubic (κ² constant), got {mp.nstr(k2, 8)} and "
                              f"{mp.nstr(kappa_sq(cn), 8)}: an inconsistent root configuration")
    kappa = mp.sqrt(k2)
    K = mp.ellipk(m)
    # v0 = F(φ0|m), cn v0 = cos φ0 = (A − x0)/(A + x0): φ0 = 2 asin √(x0/(A + x0)) (no cancellation at the root)
    v0 = mp.ellipf(2 * mp.asin(mp.sqrt(x0 / (A + x0))), m)
    # σ du/dv ≥ 0 on (0, 2K): u moves away from r as v grows on the side σ
    v_start = mp.mpf(0) if direction == 0 else (v0 if direction * sigma > 0 else -v0)
    return EllipticMotionCubicPair(tuple(c), (r, sigma * mp.inf), (r, sigma * mp.inf, mp.mpf("nan"), mp.mpf("nan")),
                                   mob, m, m1, kappa, v_start, K, mp.inf, 3)


# --- ∫ R(u(t)) dt for a polynomial R -------------------------------------------------------------------------

def _poly_mul(p: list, q: list) -> list:
    """The product of two coefficient lists (lowest degree first)."""
    out = [0] * (len(p) + len(q) - 1)
    for i, x in enumerate(p):
        for j, y in enumerate(q):
            out[i + j] += x * y
    return out


@dataclass
class ElementaryRate:
    """∫₀^t R(u(t')) dt' on an :class:`ElementaryMotion` for a polynomial R (see the module docstring):
    ``form`` "polynomial" with ``coefficients`` of the integral in t (lowest first, 40 digits: ∫ = Σ c_k t^k), or
    "exponential" with ``coefficients`` {j: C_j} of R(u(t)) = Σ C_j e^{jκt}."""

    motion: ElementaryMotion
    coefficients: Any
    _f: dict = field(default_factory=dict, repr=False)

    @property
    def advance(self) -> Any:
        raise NotElliptic("expected a periodic motion for an advance per period, got an unbounded one (no period)")

    def __call__(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        t = np.asarray(t, dtype=float) if jac is None else jac[0]
        mp = _mp()
        if self.motion.form == "polynomial":
            if "c" not in self._f:
                with mp.workdps(DPS):
                    self._f["c"] = [float(x) for x in self.coefficients]
            return np.polyval(self._f["c"][::-1], t)
        from ..special._doubledouble import two_prod

        if "c" not in self._f:
            with mp.workdps(DPS):
                self._f["c"] = {j: float(x) for j, x in self.coefficients.items()}
        self.motion._doubles()
        k_hi, k_lo = self.motion._f["k"]
        p, pe = two_prod(np.broadcast_to(k_hi, t.shape).astype(float), t)
        small = pe + k_lo * t
        total = self._f["c"].get(0, 0.0) * t
        for j, cj in self._f["c"].items():
            if j == 0:
                continue
            # (e^{jκt} − 1)/(jκ) from expm1 of the rounded phase, its remainder jδ added to first order
            with np.errstate(over="ignore"):
                growth = np.expm1(j * p) + np.exp(j * p) * (j * small)
            total = total + cj * growth / (j * k_hi)
        return total

    def value_mp(self, t) -> Any:
        """The integral at t (mpmath, at the caller's precision): the same sums from the 40-digit coefficients."""
        mp = _mp()
        t = mp.mpf(t)
        if self.motion.form == "polynomial":
            return mp.polyval(list(self.coefficients)[::-1], t)
        kap = self.motion.kappa
        return sum((cj * t if j == 0 else cj * mp.expm1(j * kap * t) / (j * kap)) for j, cj in self.coefficients.items())


def elementary_rate_integral(motion: ElementaryMotion, numerator: Sequence, denominator: Sequence) -> ElementaryRate:
    """∫ R(u) dt along ``motion`` for R = N/D (coefficients in u, highest first) with D a nonzero constant; raises
    :class:`NotElliptic` for a rate with poles in u."""
    mp = _mp()
    with mp.workdps(DPS):
        N = [mp.mpf(x) for x in numerator]
        D = [mp.mpf(x) for x in denominator]
        while len(D) > 1 and D[0] == 0:
            D = D[1:]
        if len(D) != 1 or D[0] == 0:
            raise NotElliptic(f"expected a rate polynomial in u on a motion in elementary functions of t, got a "
                              f"denominator of degree {len(D) - 1} (poles in u: not covered)")
        R = [x / D[0] for x in N][::-1]  # lowest degree first
        if motion.form == "polynomial":
            u = list(motion.constants)  # u0 + s t + a t², lowest first
            in_t, power = [mp.mpf(0)], [mp.mpf(1)]
            for coef in R:
                term = [coef * x for x in power]
                in_t = [a + b for a, b in zip(in_t + [0] * (len(term) - len(in_t)), term + [0] * (len(in_t) - len(term)))]
                power = _poly_mul(power, u)
            # ∫₀^t Σ a_k t^k = Σ a_k t^{k+1}/(k + 1)
            return ElementaryRate(motion, [mp.mpf(0)] + [a / (k + 1) for k, a in enumerate(in_t)])
        alpha, p_plus, p_minus = motion.constants
        # u = p₋E⁻¹ + α + p₊E as a Laurent polynomial {j: coefficient}; its powers by convolution
        u = {-1: p_minus, 0: alpha, 1: p_plus}
        total: dict = {}
        power = {0: mp.mpf(1)}
        for coef in R:
            for j, x in power.items():
                total[j] = total.get(j, 0) + coef * x
            nxt: dict = {}
            for j, x in power.items():
                for i, y in u.items():
                    nxt[i + j] = nxt.get(i + j, 0) + x * y
            power = nxt
        return ElementaryRate(motion, {j: x for j, x in total.items() if x != 0})
