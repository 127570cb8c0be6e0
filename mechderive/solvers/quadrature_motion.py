"""The motion u(t) solving u̇² = P(u), P a real polynomial of degree 2, 3 or 4, in Jacobi elliptic functions.

This is the numeric half of the generic closed form (issue 16; the symbolic half, which finds u = g(q)
and P, is :mod:`mechderive.core.quadrature`).  One formula covers every real-root configuration: with
w = sn²(v|m), v = κ t + v_s,

    u = M(w) = (A + B w) / (C + D w),          M(0) = a,  M(1) = b,  M(1/m) = c,  M(∞) = d,

where (a, b) is the interval of motion (P > 0 between two adjacent roots, a the end the labels start
from) and c, d are the next two branch points of √P in the cyclic order of the projective line — the
other roots, and ∞ when the degree is odd (for a quadratic c = d = ∞ and m = 0).  M maps the four
branch points of ẇ² = 4κ² w(1 − w)(1 − m w) onto those of u̇² = P(u), so m is their cross-ratio and κ
the constant ratio of the two sides; the chapter's u = u1 + (u2 − u1) sn²(…) for the heavy top (3.76) is
the cubic case (d = ∞, B/C = u2 − u1), and Byrd & Friedman's 236.00, 254.00-257.00 and 238.00 are the
others (oscillation between adjacent roots, and the cubic's unbounded branch u ≥ r3 through d = ∞; with a
negative lead, u ≤ r1 is its mirror image under u → −u).

A rational function R(u) of the motion (a cyclic coordinate's rate ċ = R(u)) integrates in closed
form the same way: R(M(w)) = Q0 + Q1 w + Σ_j c_j / (1 − n_j w) by partial fractions in w, and

    ∫ R dt = (1/κ) [Q0 v + Q1 (v − E(am v|m))/m + Σ c_j Π(n_j; am v|m)]   (DLMF 19.2.7, 22.16.1),

with the per-period advance from the complete integrals.  The constants (roots, M, m, κ, v_s, n_j,
c_j) are computed at 40 digits with mpmath and rounded once; the functions are then evaluated in
NumPy by :mod:`mechderive.special` (phase reduced by 4K in double-double, so long times keep their
digits).

A start on a double root u_s of P with P''(u_s) < 0 is a steady motion: u ≡ u_s, and the rates integrate to
R(u_s)·t (the degenerate M(w) = u_s).

A quartic with two real roots and a complex pair oscillates between the real ones in cn
(:class:`EllipticMotionCn`, Byrd & Friedman 259.00); its cyclic rates, and those of the other cn and tan forms, are
integrated by the rate's Fourier series in v with a measured error (:mod:`mechderive.solvers.quadrature_fourier`).

m = 1 (``EllipticMotion.asymptotic``): from its turning point a the motion goes towards b in infinite time
and never returns, with sn = tanh and cn = dn = sech — a separatrix, where b is a double root of P (the
pendulum launched with exactly the speed to reach the top, θ = 2 gd(ω0 t); a homoclinic orbit,
x = sech t), or the unbounded quadratic P = c0 (u − r1)(u − r2), c0 > 0, whose double branch point is ∞
(u = r + (r − r') sinh²(κt + v_s), κ² = c0/4: the bead on a turning rod, r̈ = ω² r).  No period; the phase
is not reduced (K = ∞).

Degree ≤ 1 — uniform motion (a free particle, a free rotor) and uniformly accelerated motion (a body under
uniform gravity), u = u0 + u̇0 t + (c1/4) t² —, the quadratic with no real root, u = α + β sinh(κt + v_s)
(no turning point: over the top of an inverted parabola), the cubic with one real root r, u = r +
σA(1 − cn)/(1 + cn) (from r out to ∞, reached in finite time), the quartic with two real roots, a complex pair
and a positive lead outside its real roots (in cn, B&F 260.00) and the quartic with no real root, u = α1 +
b tan(φ0 + am v), are solved in :mod:`mechderive.solvers.quadrature_open`, to which :func:`elliptic_motion` hands
them.  A cyclic rate ċ = R(u) polynomial in u integrates on the degree ≤ 1 and exponential forms to a polynomial
in t or a sum of e^{jκt} (:func:`rate_integral` hands them to :func:`~.quadrature_open.elementary_rate_integral`).

A quartic with four real roots and a positive lead, started outside them (u ≥ r4 or u ≤ r1), runs through ∞
along the arc (r4, ∞, r1): the Möbius form above with its pole inside (0, 1), a the root on u0's side.

Where u reaches ∞ in finite time — the cubic's unbounded branch u ≥ r3 at v = ±K (w = 1), the quartic's arc
through ∞ at its pole, the cn and tan forms at theirs — ``escape_times`` gives the two times around t = 0;
beyond them the formulas continue through ∞ (u̇² = P(u) still holds) but describe no motion, and the caller
refuses them.

Not covered (the caller integrates instead; :class:`NotElliptic` says why): a complex pair so near the real
axis on the motion that 1 − m < 1e-15 (a nearly double root the motion passes slowly), a quadratic whose two
roots are too near each other or the real axis to resolve at 40 digits (one double to the working precision is
solved: :func:`~mechderive.solvers.quadrature_open.exponential_double_root`), an unstable equilibrium (a start
on a double root with P'' > 0), rates on the cn and tan forms with a real pole on u's range or growing at an escape
(:mod:`~mechderive.solvers.quadrature_fourier` says which), and, for 0 < m < 1, rates with complex
poles, poles on the motion, or a polynomial part of degree > 1 in w.  At m = 0 (u = M(sin²v), a bounded quadratic)
and m = 1 (u = M(tanh²v)) u is rational in e^{2iv} or e^{2v}, and any rational rate — multiple and complex poles
included — integrates by partial fractions in that variable (:mod:`mechderive.solvers.quadrature_rational`, to which
:func:`rate_integral` hands them, with the elementary forms' rates that have poles).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..errors import InvalidInputError

__all__ = ["NotElliptic", "EllipticMotion", "EllipticMotionCn", "RateIntegral", "elliptic_motion", "rate_integral", "DPS", "REFERENCE_DPS"]

#: working precision of the constants (decimal digits)
DPS = 40
#: precision of the reference evaluation an estimate compares the doubles with (ample for double rounding)
REFERENCE_DPS = 30


class NotElliptic(InvalidInputError):
    """u̇² = P(u) from this start is not one of the configurations solved here (the message says why)."""


def _mp():
    import mpmath

    return mpmath



def rate_coefficients_mp(numerator: Sequence, denominator: Sequence) -> tuple[list, list]:
    """A rate N(u)/D(u)'s coefficients (highest first) as mpmath numbers at the working precision, leading
    zeros dropped (a constant stays): call inside ``mp.workdps``."""
    mp = _mp()
    N = [mp.mpf(x) for x in numerator]
    Dn = [mp.mpf(x) for x in denominator]
    while len(N) > 1 and N[0] == 0:
        N = N[1:]
    while len(Dn) > 1 and Dn[0] == 0:
        Dn = Dn[1:]
    return N, Dn

def _split_mp(x) -> tuple[float, float]:
    """x (mpf) as a double-double (hi, lo), the difference taken at the working precision (at mpmath's default
    53 bits it would be rounded away: a test over 1000 periods caught a phase error of n·ulp(4K))."""
    mp = _mp()
    with mp.workdps(DPS):
        hi = float(x)
        return hi, float(x - mp.mpf(hi))


@dataclass
class EllipticMotion:
    """u(t) = M(sn²(κ t + v_s | m)) from :func:`elliptic_motion` (see the module docstring).

    ``interval`` = (a, b), ``branch_points`` = (a, b, c, d) (mpmath numbers, ±inf allowed),
    ``mobius`` = (A, B, C, D), ``m``, ``m1`` = 1 − m, ``kappa``, ``v_start`` and ``K`` at 40 digits;
    ``u_period`` = 2K/κ the period of u (u is even about each turning point: w has period 2K in v).
    """

    coefficients: tuple
    interval: tuple
    branch_points: tuple
    mobius: tuple
    m: Any
    m1: Any
    kappa: Any
    v_start: Any
    K: Any
    u_period: Any
    degree: int
    #: u ≡ a double root of P (a stable steady motion): u and its distances are constant
    steady: bool = False
    _f: dict = field(default_factory=dict, repr=False)

    @property
    def asymptotic(self) -> bool:
        """m = 1: the motion goes from its turning point a towards b in infinite time and never returns (b a
        double root of P: a separatrix; or b = ∞, a double point of the quadratic's P: hyperbolic escape);
        sn = tanh, cn = dn = sech, K = ∞ and no period."""
        return not self.steady and self.m == 1

    def _den(self, w: np.ndarray, cn: np.ndarray) -> np.ndarray:
        """C + D w; at m = 1 as C cn² + (C + D) w (1 − w = cn²), which keeps its digits as w → 1 (M(1) = ∞
        for the hyperbolic quadratic: C + D = 0)."""
        A, B, C, D, det = self._mob()
        return C * (cn * cn) + (C + D) * w if self.asymptotic else C + D * w

    # --- the phase ---------------------------------------------------------------------------

    def phase(self, t: Any) -> tuple[np.ndarray, np.ndarray]:
        """(n, r): v(t) = κ t + v_s = n·4K + r with |r| ≲ 4K, r in double-double arithmetic so that v's
        rounding does not grow with t (the reduction the Jacobi functions' ``periods`` argument takes)."""
        from ..special._doubledouble import two_prod, two_sum

        t = np.asarray(t, dtype=float)
        k_hi, k_lo = self._doubles("kappa")
        s_hi, s_lo = self._doubles("v_start")
        if self.asymptotic:  # m = 1: K = ∞, nothing to reduce; v in double-double all the same
            p, pe = two_prod(np.broadcast_to(k_hi, t.shape).astype(float), t)
            return np.zeros(t.shape), p + (pe + k_lo * t + s_hi + s_lo)
        f_hi, f_lo = self._doubles("four_K")
        v = k_hi * t + s_hi
        n = np.floor(v / f_hi + 0.5)
        p, pe = two_prod(np.broadcast_to(k_hi, t.shape).astype(float), t)
        h, he = two_prod(n, np.broadcast_to(f_hi, n.shape).astype(float))
        d, de = two_sum(p, -h)
        r = d + (de + pe - he + k_lo * t + s_hi + s_lo - n * f_lo)
        return n, r

    def _doubles(self, name: str) -> tuple[float, float]:
        if name not in self._f:
            with _mp().workdps(DPS):
                value = 4 * self.K if name == "four_K" else getattr(self, name)
                self._f[name] = _split_mp(value)
        return self._f[name]

    def jacobi(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(sn, cn, dn, n, r) at v(t) (see :meth:`phase`)."""
        from ..special import jacobi_sn_cn_dn

        n, r = self.phase(t)
        sn, cn, dn = jacobi_sn_cn_dn(r, float(self.m), m1=float(self.m1))
        return (np.asarray(sn, float), np.asarray(cn, float), np.asarray(dn, float), n, r)

    # --- u and its distances to the ends -------------------------------------------------------

    def _mob(self) -> tuple[float, float, float, float, float]:
        if "mob" not in self._f:
            A, B, C, D = self.mobius
            with _mp().workdps(DPS):
                self._f["mob"] = (float(A), float(B), float(C), float(D), float(B * C - A * D))
        return self._f["mob"]

    def u(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        """u(t), evaluated from the nearer end of the interval (u − a ∝ sn², b − u ∝ cn²: each to a few
        ulp relative near its own end)."""
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        A, B, C, D, det = self._mob()
        w = sn * sn
        den = self._den(w, cn)
        a, b = self.interval
        near_a = w <= 0.5
        with np.errstate(all="ignore"):
            from_a = (float(a) if np.isfinite(float(a)) else 0.0) + det * w / (C * den)
            from_b = (float(b) if np.isfinite(float(b)) else 0.0) - det * (cn * cn) / ((C + D) * den)
            plain = (A + B * w) / den
        use_a = near_a & np.isfinite(float(a)) & (C != 0)
        use_b = ~near_a & np.isfinite(float(b)) & (C + D != 0)
        return np.where(use_a, from_a, np.where(use_b, from_b, plain))

    def minus(self, point: Any, t: Any, jac: tuple | None = None) -> np.ndarray:
        """u(t) − ``point`` (a number at the working precision, e.g. a pole of a rate) without the cancellation
        of u − p near p: (u − a) + (a − p) from the a end, or (b − p) − (b − u) from the b end, each distance to
        an end from sn² or cn² (the rates of a spherical pendulum passing near its pole keep their digits)."""
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        A, B, C, D, det = self._mob()
        w = sn * sn
        den = self._den(w, cn)
        a, b = self.interval
        mp = _mp()
        with mp.workdps(DPS):
            a_p = float(a - point) if not mp.isinf(a) else None
            b_p = float(b - point) if not mp.isinf(b) else None
        with np.errstate(all="ignore"):
            out = self.u(t, jac) - float(point)
            if a_p is not None and C != 0:
                out = np.where(w <= 0.5, a_p + det * w / (C * den), out)
            if b_p is not None and C + D != 0:
                out = np.where(w > 0.5, b_p - det * (cn * cn) / ((C + D) * den), out)
        return out

    def signed_root(self, end: str, t: Any, jac: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(σ, σ̇): σ = ±√|u − e| at the end e = a (``end="a"``, sign of sn) or b (sign of cn), and its
        time derivative — the coordinate in which a fold of the substitution is smooth."""
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        A, B, C, D, det = self._mob()
        w = sn * sn
        den = self._den(w, cn)
        kap = float(self.kappa)
        scale = abs(det / C) if end == "a" else abs(det / (C + D))
        rho = np.sqrt(scale / np.abs(den))
        drho_dw = -0.5 * rho * D / den
        w_dot = 2.0 * kap * sn * cn * dn
        if end == "a":
            return sn * rho, kap * cn * dn * rho + sn * drho_dw * w_dot
        return cn * rho, -kap * sn * dn * rho + cn * drho_dw * w_dot

    def u_dot(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        """u̇ = M'(w) ẇ with ẇ = 2κ sn cn dn."""
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        A, B, C, D, det = self._mob()
        w = sn * sn
        return det / self._den(w, cn) ** 2 * 2.0 * float(self.kappa) * sn * cn * dn

    def amplitude(self, t: Any) -> np.ndarray:
        """am(v(t)|m), continuous in t (a rotation's angle is affine in it)."""
        from ..special import jacobi_am

        n, r = self.phase(t)
        return np.asarray(jacobi_am(r, float(self.m), m1=float(self.m1)), float) + 2.0 * np.pi * n

    # --- 40-digit evaluation, for the estimate -------------------------------------------------

    def mp_den(self, sn, cn) -> Any:
        """C + D w (mpmath numbers) as C cn² + (C + D) sn²: equal (cn² = 1 − sn²), and exact as w → 1 where
        C + D = 0 (the hyperbolic quadratic, M(1) = ∞)."""
        A, B, C, D = self.mobius
        return C * cn * cn + (C + D) * sn * sn

    def mp_u(self, sn, cn, dn) -> Any:
        """u from the Jacobi functions (mpmath numbers), at the caller's precision."""
        A, B, C, D = self.mobius
        return (A + B * sn * sn) / self.mp_den(sn, cn)

    def mp_u_dot(self, sn, cn, dn) -> Any:
        """u̇ from the Jacobi functions (mpmath numbers): M'(w) ẇ."""
        A, B, C, D = self.mobius
        return (B * C - A * D) / self.mp_den(sn, cn) ** 2 * 2 * self.kappa * sn * cn * dn

    @property
    def escape_times(self) -> tuple[float, float] | None:
        """(t₋, t₊): where M has its pole on the motion u reaches ∞ in finite time, before and after t = 0 — at w = 1
        (v = ±K) for the cubic's unbounded branch u ≥ r3 (B&F 238.00, M(1) = ∞), at w_p = −C/D inside (0, 1) for a
        quartic with positive lead outside its roots.  None where u stays finite (a bounded motion, or m = 1 where
        ∞ is approached in infinite time)."""
        mp = _mp()
        if self.steady or self.asymptotic:
            return None
        A, B, C, D = self.mobius
        with mp.workdps(DPS):
            # the pole of M, C + D w_p = 0: in (0, 1] the motion reaches it (w_p = 1: the cubic's d = ∞ listing; inside:
            # a quartic whose arc of motion runs through ∞, r4 → ∞ or r1 → −∞), at sn²(v) = w_p, v = ±v_p + 2Kn
            if D == 0 or not 0 < -C / D <= 1:
                return None
            w_p = -C / D
            v_p = self.K if w_p == 1 else mp.ellipf(mp.asin(mp.sqrt(w_p)), self.m)
            v_s = self.v_start
            ahead = v_p if v_p > v_s else 2 * self.K - v_p
            behind = -v_p if -v_p < v_s else -2 * self.K + v_p
            return float((behind - v_s) / self.kappa), float((ahead - v_s) / self.kappa)

    def u_mp(self, t) -> Any:
        """u(t) at the working precision (mpmath), as a reference for the doubles."""
        mp = _mp()
        with mp.workdps(DPS):
            v = self.kappa * mp.mpf(t) + self.v_start
            sn, cn = mp.ellipfun("sn", v, m=self.m), mp.ellipfun("cn", v, m=self.m)
            return self.mp_u(sn, cn, None)


class EllipticMotionCn(EllipticMotion):
    """u(t) = (A + B cn v)/(C + D cn v), v = κ t + v_s: a quartic with two real roots a < b and a complex pair,
    u oscillating between them (Byrd & Friedman 259.00: cn v = ((b − u)A − (u − a)B)/((b − u)A + (u − a)B) with
    A, B the distances from b and a to the complex roots, m = ((b − a)² − (A − B)²)/(4AB), κ² = |lead|·A·B).
    The period of u is 4K/κ.  Folds and rotations are not offered on this form; the cyclic rates integrate by their
    Fourier series in v (:mod:`mechderive.solvers.quadrature_fourier`), not by Π."""

    def u(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        A, B, C, D, det = self._mob()
        return (A + B * cn) / (C + D * cn)

    def u_dot(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        sn, cn, dn, _, _ = self.jacobi(t) if jac is None else jac
        A, B, C, D, det = self._mob()
        return -det / (C + D * cn) ** 2 * float(self.kappa) * sn * dn

    def minus(self, point: Any, t: Any, jac: tuple | None = None) -> np.ndarray:
        return self.u(t, jac) - float(point)

    @property
    def escape_times(self) -> None:
        """None: u stays between its two real roots (the Möbius form here is in cn, not sn²)."""
        return None

    def signed_root(self, end: str, t: Any, jac: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
        raise NotElliptic("expected no fold of the substitution on a quartic with complex roots (not covered)")

    def mp_u(self, sn, cn, dn) -> Any:
        A, B, C, D = self.mobius
        return (A + B * cn) / (C + D * cn)

    def mp_u_dot(self, sn, cn, dn) -> Any:
        A, B, C, D = self.mobius
        return -(B * C - A * D) / (C + D * cn) ** 2 * self.kappa * sn * dn

    def u_mp(self, t) -> Any:
        mp = _mp()
        with mp.workdps(DPS):
            v = self.kappa * mp.mpf(t) + self.v_start
            return self.mp_u(None, mp.ellipfun("cn", v, m=self.m), None)


def _complex_pair_quartic(c: list, roots: list, u0: Any, direction: int) -> EllipticMotion:
    """The :class:`EllipticMotionCn` of a quartic with two real roots and a complex pair (see there)."""
    mp = _mp()
    if c[0] > 0:  # outside the real roots, escaping through ∞ (quadrature_open)
        from .quadrature_open import complex_pair_quartic_outside

        return complex_pair_quartic_outside(c, roots, u0, direction)
    a, b = roots
    if not a - mp.mpf(2) ** -40 * (1 + abs(u0)) <= u0 <= b + mp.mpf(2) ** -40 * (1 + abs(u0)):
        raise NotElliptic(f"expected the start between the real roots {mp.nstr(a, 10)} and {mp.nstr(b, 10)}, "
                          f"got u0 = {mp.nstr(u0, 10)}")
    pair = [z for z in mp.polyroots(c, maxsteps=400, extraprec=6 * mp.mp.dps) if abs(mp.im(z)) > 0]
    b1, a1 = mp.re(pair[0]), abs(mp.im(pair[0]))
    dist_b, dist_a = mp.sqrt((b - b1) ** 2 + a1**2), mp.sqrt((a - b1) ** 2 + a1**2)
    m = ((b - a) ** 2 - (dist_a - dist_b) ** 2) / (4 * dist_a * dist_b)
    k2 = -c[0] * dist_a * dist_b
    # cn = 1 at u = a, cn = −1 at u = b:  u = (a·A_b... ) written as (A + B cn)/(C + D cn)
    A, B = a * dist_b + b * dist_a, a * dist_b - b * dist_a
    C, D = dist_b + dist_a, dist_b - dist_a
    P = lambda x: mp.polyval(c, x)  # noqa: E731

    def kappa_sq(cn):
        du = (B * C - A * D) / (C + D * cn) ** 2
        return P((A + B * cn) / (C + D * cn)) / (du**2 * (1 - cn * cn) * (1 - m + m * cn * cn))

    for cn in (mp.mpf(1) / 3, -mp.mpf(2) / 5):
        if abs(kappa_sq(cn) - k2) > mp.mpf(10) ** -8 * abs(k2):
            raise NotElliptic(f"expected the cn form to fit the quartic (κ² constant), got {mp.nstr(k2, 8)} and "
                              f"{mp.nstr(kappa_sq(cn), 8)}: an inconsistent root configuration")
    kappa = mp.sqrt(k2)
    K = mp.ellipk(m)
    cn0 = min(max((A - C * u0) / (D * u0 - B), mp.mpf(-1)), mp.mpf(1))
    v0 = mp.ellipf(mp.acos(cn0), m)  # in [0, 2K]: u runs from a to b as v does (sign of du/dv = −det·sn)
    rising = -(B * C - A * D) > 0
    v_start = v0 if (direction >= 0) == rising else -v0
    if direction == 0:
        v_start = mp.mpf(0) if cn0 > 0 else 2 * K
    return EllipticMotionCn(tuple(c), (a, b), (a, b, mp.mpf("nan"), mp.mpf("nan")), (A, B, C, D), m, 1 - m, kappa,
                            v_start, K, 4 * K / kappa, 4)


def _real_roots(coeffs: Sequence) -> list:
    mp = _mp()
    roots = mp.polyroots(list(coeffs), maxsteps=400, extraprec=6 * mp.mp.dps)
    tiny = mp.mpf(10) ** (-mp.mp.dps // 2)
    real = sorted(mp.re(r) for r in roots if abs(mp.im(r)) <= tiny * (1 + abs(r)))
    return real


def _projective(x) -> tuple:
    mp = _mp()
    return (mp.mpf(1), mp.mpf(0)) if mp.isinf(x) else (x, mp.mpf(1))


def _mobius(a, b, d) -> tuple:
    """(A, B, C, D) with (A + B w)/(C + D w) = a, b, d at w = 0, 1, ∞ (any of them may be ∞)."""
    (a1, a0), (b1, b0), (d1, d0) = _projective(a), _projective(b), _projective(d)
    lam = d0 * b1 - d1 * b0
    mu = a1 * b0 - a0 * b1
    return lam * a1, mu * d1, lam * a0, mu * d0


def _inverse(mobius: tuple, x) -> Any:
    """w with M(w) = x (x may be ∞; the result may be ∞)."""
    mp = _mp()
    A, B, C, D = mobius
    x1, x0 = _projective(x)
    num, den = A * x0 - C * x1, D * x1 - B * x0
    return mp.inf if den == 0 else num / den


def elliptic_motion(coefficients: Sequence, u0: Any, direction: int, *, dps: int = DPS) -> EllipticMotion:
    """u(t) with u̇² = P(u) (``coefficients`` highest first, as numbers mpmath reads at ``dps`` digits),
    u(0) = ``u0`` and u̇(0) of sign ``direction`` (0 at a turning point).

    Two roots closer than 10⁻¹⁰ (a motion near a steady one: their distance is the amplitude) lose digits
    as 10^-dps / distance; the constants are then recomputed with as many more digits as the inputs carry
    (give them to ~60 digits: a conical pendulum whose roots are 1.5e-17 apart keeps its amplitude to 1e-28).
    Raises :class:`NotElliptic` for the configurations listed in the module docstring.
    """
    mp = _mp()
    motion = _elliptic_motion(coefficients, u0, direction, dps)
    a, b = motion.interval
    if not motion.steady and not (mp.isinf(a) or mp.isinf(b)):
        with mp.workdps(dps):
            width = abs(b - a) / (1 + abs(a))
        if width < mp.mpf(10) ** -10:
            lost = int(-mp.log10(width)) + 1
            motion = _elliptic_motion(coefficients, u0, direction, min(dps + 2 * lost, 3 * dps))
    return motion


def _elliptic_motion(coefficients: Sequence, u0: Any, direction: int, dps: int) -> EllipticMotion:
    mp = _mp()
    with mp.workdps(dps):
        c = [mp.mpf(x) for x in coefficients]
        while len(c) > 1 and c[0] == 0:
            c = c[1:]
        degree = len(c) - 1
        if degree > 4:
            raise NotElliptic(f"expected u̇² = P(u) of degree ≤ 4, got degree {degree}")
        u0 = mp.mpf(u0)
        if degree < 2:  # uniform or uniformly accelerated: polynomial in t (quadrature_open)
            from .quadrature_open import open_motion

            return open_motion(c, [], u0, direction)
        P = lambda x: mp.polyval(c, x)  # noqa: E731
        roots = _real_roots(c)
        if degree == 2 and not roots or degree == 3 and len(roots) == 1 or degree == 4 and not roots:
            # no turning point: u = α + β sinh(κt + v_s); or one, and an escape to ∞ in cn (quadrature_open)
            from .quadrature_open import open_motion

            return open_motion(c, roots, u0, direction)
        if degree == 3 and c[0] < 0 and len(roots) == 3 and u0 <= roots[0] + mp.mpf(2) ** -40 * (1 + abs(u0)):
            # u ≤ r1 of a cubic with negative lead: the mirror image ũ = −u of the branch ũ ≥ r̃3 of P̃(ũ) = P(−ũ),
            # whose lead −c3 is positive (B&F 238.00 reflected); M's numerator and the branch points change sign
            mirrored = _elliptic_motion([x * (-1) ** (degree - i) for i, x in enumerate(c)], -u0, -direction, dps)
            A, B, C, D = mirrored.mobius
            return dataclasses.replace(mirrored, coefficients=tuple(c), interval=tuple(-x for x in mirrored.interval),
                                       branch_points=tuple(-x for x in mirrored.branch_points), mobius=(-A, -B, C, D),
                                       _f={})
        if degree == 4 and len(roots) == 2:
            return _complex_pair_quartic(c, roots, u0, direction)
        if degree == 4 and len(roots) < 4 or degree == 3 and len(roots) < 3 or degree == 2 and len(roots) < 2:
            raise NotElliptic(f"expected {degree} real roots of P (degree {degree}), got {len(roots)}: a "
                              "configuration with complex roots, not covered by this closed form")
        close = [(x, y) for x, y in zip(roots, roots[1:]) if abs(x - y) <= mp.mpf(10) ** (-DPS // 2) * (1 + abs(x))]
        if close:
            x, y = close[0]
            double = (x + y) / 2
            curvature = mp.polyval([ci * (degree - i) * (degree - i - 1) for i, ci in enumerate(c[:-2])], double)
            if abs(u0 - double) <= mp.mpf(2) ** -40 * (1 + abs(u0)):
                if curvature < 0:
                    return _steady(c, degree, double, curvature)
                raise NotElliptic("expected simple roots of P, got a double root at u = "
                                  f"{mp.nstr(double, 10)} that the motion starts on: an unstable equilibrium "
                                  "(the separatrix's end), not periodic")
            if degree == 2 and c[0] > 0 and abs(x - y) <= mp.mpf(10) ** (-DPS + 5) * (1 + abs(double)):
                # P = c2 (u − r)² (double to the working precision, as a separatrix's below): u − r ∝ e^{±κt}
                from .quadrature_open import exponential_double_root

                return exponential_double_root(c, double, u0, direction)
            if len(close) > 1 or degree == 2:
                raise NotElliptic("expected at most one double root of P, away from the start, got "
                                  f"{len(close)} (a degenerate P)")
            # a separatrix only if the root is double to the working precision (polyroots, with its extra digits,
            # returns an exact double root's pair ~10^-DPS apart): roots 1e-25 apart are a periodic motion whose
            # period (~ln(1/δ)/κ) a separatrix would get wrong after t ~ ln(1/δ)/κ, with a small estimate
            if abs(x - y) > mp.mpf(10) ** (-DPS + 5) * (1 + abs(double)):
                raise NotElliptic(f"expected a double root of P or roots the 40-digit constants resolve, got two roots "
                                  f"{mp.nstr(abs(x - y), 3)} apart near u = {mp.nstr(double, 10)}: a motion this near "
                                  "a separatrix is not covered")
            # a separatrix: the motion runs from its turning point towards the double root in infinite time;
            # the double root is two coincident branch points, so m = 1 below (sn = tanh)
            roots = [double if r in (x, y) else r for r in roots]
        if degree == 2 and c[0] > 0:
            return _hyperbolic(c, roots, u0, direction)
        # the branch points in the cyclic order of the projective line; ∞ is one when the degree is odd
        points = list(roots) + ([mp.inf] if degree % 2 else [])
        slack = mp.mpf(2) ** -40 * (1 + abs(u0))
        found = None
        count = len(points)
        for i in range(count):
            lo, hi = points[i], points[(i + 1) % count]
            if degree == 2 and i == 1:
                break  # the quadratic's outside (through ∞) is unbounded
            if mp.isinf(lo):
                continue
            wraps = not mp.isinf(hi) and hi < lo  # through ∞ (a quartic with a negative... leading coefficient)
            if mp.isinf(hi):
                mid = lo + 1 + abs(lo)
                inside = u0 >= lo - slack
            elif wraps:
                mid = hi - 1 - abs(hi)
                inside = u0 >= lo - slack or u0 <= hi + slack
            else:
                mid = (lo + hi) / 2
                inside = lo - slack <= u0 <= hi + slack
            if inside and P(mid) > 0:
                found = i
                break
        if found is None:
            raise NotElliptic(f"expected u̇² = P(u0) ≥ 0 inside an interval of motion, got P(u0) = "
                              f"{mp.nstr(P(u0), 5)} at u0 = {mp.nstr(u0, 10)} (roots {[mp.nstr(r, 10) for r in roots]})")
        if degree == 2:
            a, b, cc, d = points[0], points[1], mp.inf, mp.inf
            if c[0] > 0:
                raise NotElliptic("expected a bounded quadratic (negative leading coefficient), got an unbounded one")
        else:
            # (lo, hi, X, Y) in the circle's order, or reversed (hi, lo, Y, X): both give the same m; take the
            # one with d = ∞ when ∞ is a branch point, so that M is affine (u = a + (b − a) w, the chapter's form)
            a, b, cc, d = (points[(found + k) % count] for k in range(4))
            # the reversed listing too when the double root of a separatrix is at the start (d = a): it must be
            # b = c, the end approached (m = 1), not d = a (a degenerate M)
            if mp.isinf(cc) or (not mp.isinf(a) and not mp.isinf(d) and a == d):
                a, b, cc, d = b, a, d, cc
        if degree == 4 and (mp.isinf(a) or mp.isinf(b)):
            raise NotElliptic("expected a finite interval of motion")
        lo, hi = points[found], points[(found + 1) % count]
        if degree == 4 and not mp.isinf(hi) and hi < lo and u0 <= hi + slack:
            # the arc from r4 through ∞ to r1 (positive lead): the motion leaves from the root on u0's side and escapes
            # to ∞ in finite time (a pole of M inside (0, 1): escape_times); a = that root, the listing reversed if
            # u0 ≤ r1 (the same m)
            a, b, cc, d = b, a, d, cc
        mob = _mobius(a, b, d)
        winv = _inverse(mob, cc)
        m = mp.mpf(0) if mp.isinf(winv) else 1 / winv
        if abs(m - 1) <= mp.mpf(10) ** (-DPS + 5):
            m = mp.mpf(1)  # a double root at the far end: a separatrix
        if not 0 <= m <= 1:
            raise NotElliptic(f"expected a parameter 0 ≤ m < 1 from the cross-ratio of the roots, got {mp.nstr(m, 8)}")
        A, B, C, D = mob
        det = B * C - A * D

        def kappa_sq(w):
            deriv = det / (C + D * w) ** 2
            return P((A + B * w) / (C + D * w)) / (4 * deriv**2 * w * (1 - w) * (1 - m * w))

        # κ² from the roots (no cancellation, even for nearly double roots): the ratio of the two sides of
        # u̇² = P(u) under u = M(w), checked against that ratio evaluated at two w (a wrong configuration is O(1) off)
        if degree == 2:
            k2 = -c[0] / 4
        elif degree == 3:
            # the quartic's −lead₄(c − a)(d − b)/4 with one branch point X → ∞ and lead₃ = −lead₄ X
            k2 = (c[0] * (cc - a) / 4 if mp.isinf(d) else -c[0] * (cc - a) / 4 if mp.isinf(b) else
                  -c[0] * (d - b) / 4 if mp.isinf(a) else c[0] * (d - b) / 4)
        else:
            k2 = -c[0] * (cc - a) * (d - b) / 4
        # the evaluation through P cancels to ~10^-DPS of its terms, i.e. relative (10^-DPS/(b − a))² near a double
        # root; a wrong configuration is off by O(1) whatever the tolerance
        width = abs(b - a) if not (mp.isinf(a) or mp.isinf(b)) else mp.mpf(1)
        tolerance = mp.mpf(10) ** -8 + mp.mpf(10) ** (-DPS + 2) * (1 + abs(a if not mp.isinf(a) else b)) ** 2 / width**2
        for w_check in (mp.mpf(1) / 2, mp.mpf(3) / 10):
            check = kappa_sq(w_check)
            if not k2 > 0 or abs(check - k2) > tolerance * abs(k2):
                raise NotElliptic("expected the substitution w = sn² to fit u̇² = P(u) (κ² constant), got "
                                  f"{mp.nstr(k2, 8)} and {mp.nstr(check, 8)}: an inconsistent root configuration")
        kappa = mp.sqrt(k2)
        m1 = 1 - m
        K = mp.ellipk(m)
        v_start = _start(mob, u0, direction, m, K)
        return EllipticMotion(tuple(c), (a, b), (a, b, cc, d), mob, m, m1, kappa, v_start, K, 2 * K / kappa, degree)


def _outside(u0: Any, low: Any, high: Any, where: str) -> tuple:
    """(the root on u0's side, the other) for a start outside the roots ``low`` < ``high`` of P, where P > 0 (a start
    on a root, to 2⁻⁴⁰ relative, counts as outside); between them P < 0 and there is no motion: NotElliptic."""
    mp = _mp()
    slack = mp.mpf(2) ** -40 * (1 + abs(u0))
    if u0 >= high - slack:
        return high, low
    if u0 <= low + slack:
        return low, high
    raise NotElliptic(f"expected u̇² = P(u0) ≥ 0, got P(u0) < 0 at u0 = {mp.nstr(u0, 10)} {where}")


def _hyperbolic(c: list, roots: list, u0: Any, direction: int) -> EllipticMotion:
    """P = c0 (u − r1)(u − r2) with c0 > 0: u runs from its turning point (r2 for u ≥ r2, r1 for u ≤ r1) to ∞,
    u = M(tanh²(κ t + v_s)) = r + (r − r') sinh²(κ t + v_s) with κ² = c0/4: the m = 1 case of the Möbius form,
    ∞ being the quadratic's double branch point (b = c = ∞, d = the other root)."""
    mp = _mp()
    if len(roots) < 2:
        raise NotElliptic("expected real roots of an unbounded quadratic P, got none: u passes through every "
                          "value (a motion with no turning point), not covered")
    a, d = _outside(u0, roots[0], roots[-1], "between the roots")
    mob = _mobius(a, mp.inf, d)
    kappa = mp.sqrt(c[0] / 4)
    v_start = _start(mob, u0, direction, mp.mpf(1), mp.inf)
    return EllipticMotion(tuple(c), (a, mp.inf), (a, mp.inf, mp.inf, d), mob, mp.mpf(1), mp.mpf(0), kappa, v_start,
                          mp.inf, mp.inf, 2)


def _start(mob: tuple, u0: Any, direction: int, m: Any, K: Any) -> Any:
    """v_s: w0 = M⁻¹(u0) in [0, 1], v0 = F(asin √w0 | m), v_s = ±v0 by the sign of ẇ = u̇/M'(w)."""
    mp = _mp()
    A, B, C, D = mob
    w0 = _inverse(mob, u0)
    w0 = min(max(w0, mp.mpf(0)), mp.mpf(1))
    if direction == 0:
        # u̇(0) = 0: u starts at a turning point (q̇ = 0, or q on a fold of g), whatever rounding put u0
        # a hair inside the interval (√ of it would shift the phase by ~1e-8); at m = 1 only a is one
        return mp.mpf(0) if w0 <= mp.mpf(1) / 2 or m == 1 else K
    v0 = mp.ellipf(mp.asin(mp.sqrt(w0)), m)
    w_direction = direction * (1 if (B * C - A * D) / (C + D * w0) ** 2 > 0 else -1)
    return -v0 if w_direction < 0 else v0


def _steady(c: list, degree: int, double: Any, curvature: Any) -> EllipticMotion:
    """u(t) ≡ the double root u_s of P where the motion starts on it with P''(u_s) < 0 (a stable steady motion:
    uniform precession, a conical pendulum): the degenerate M(w) = u_s, m = 0, and κ² = −P''(u_s)/8, the limit of
    κ² as the two roots merge, so that u_period = π/κ is the period of small oscillations about it."""
    mp = _mp()
    kappa = mp.sqrt(-curvature / 8)
    K = mp.pi / 2
    return EllipticMotion(tuple(c), (double, double), (double, double, mp.inf, mp.inf), (double, mp.mpf(0),
                          mp.mpf(1), mp.mpf(0)), mp.mpf(0), mp.mpf(1), kappa, mp.mpf(0), K, 2 * K / kappa, degree,
                          steady=True)


# --- ∫ R(u(t)) dt for a rational R ---------------------------------------------------------------

@dataclass
class RateIntegral:
    """∫₀^t R(u(t')) dt' = (1/κ)[Q0 (v − v_s) + Q1 (I(v) − I(v_s)) + Σ c_j (Π(n_j; v) − Π(n_j; v_s))],
    I(v) = ∫₀^v sn² — see the module docstring.  ``advance``: the increase per period of u (2K in v)."""

    motion: EllipticMotion
    q0: Any
    q1: Any
    terms: tuple  # ((c_j, n_j), ...) at the working precision
    start: tuple = ()
    _mp_cache: dict = field(default_factory=dict, repr=False)

    @property
    def advance(self) -> Any:
        """The increase over one period of u (2K in v), from the complete integrals at the working precision
        (computed on first request: a run that does not ask for it does not pay for 40-digit Π(n|m))."""
        if "advance" not in self._mp_cache:
            mp = _mp()
            mo = self.motion
            with mp.workdps(DPS):
                m, K = mo.m, mo.K
                total = self.q0 * 2 * K + (self.q1 * 2 * (K - mp.ellipe(m)) / m if self.q1 != 0 else 0) \
                    + sum(cj * 2 * mp.ellippi(nj, m) for cj, nj in self.terms)
                self._mp_cache["advance"] = total / mo.kappa
        return self._mp_cache["advance"]

    def __call__(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        from ..special import elliptic_e_incomplete, pi_of_am

        mo = self.motion
        sn, cn, dn, n, r = mo.jacobi(t) if jac is None else jac
        m, m1 = float(mo.m), float(mo.m1)
        kap = float(mo.kappa)
        n4 = n  # v = n·4K + r
        total = float(self.q0) * (r - float(mo.v_start)) + float(self.q0) * 4.0 * n4 * float(mo.K)
        if self.q1 != 0:
            am = mo.amplitude(t)
            # I(v) = (v − E(am v))/m, with E quasi-periodic in am (E(φ + π) = E(φ) + 2E)
            e_inc = np.asarray(elliptic_e_incomplete(am, m, m1=m1), float)
            v_full = r + 4.0 * n4 * float(mo.K)
            total = total + float(self.q1) * ((v_full - e_inc) / m - float(self._i_start))
        series = self._series()
        if series is not None and self.terms:
            # Π(n_j; am v) = a₀(r + 4K·n) + periodic(r): the series fitted once per motion (the heavy top's,
            # :mod:`mechderive.special.pi_series`), ~6× faster than Carlson's R_J at each sample
            values = series.mean[:, None] * (r + 4.0 * n4 * float(mo.K))[None, :] + series.periodic(r)
            for j, ((coef, _), start) in enumerate(zip(self.terms, self.start)):
                total = total + float(coef) * (values[j] - float(start))
            return total / kap
        for (coef, nj), start in zip(self.terms, self.start):
            pi = np.asarray(pi_of_am(float(nj), r, m, m1=m1, periods=n4.astype(np.int64)), float)
            total = total + float(coef) * (pi - float(start))
        return total / kap

    def _series(self) -> Any:
        """Π's Fourier series in the Jacobi argument for every n_j (None where it does not converge: a pole near
        the real axis, m → 1)."""
        if "series" not in self._mp_cache:
            from ..special.pi_series import fit_pi_series_for_motion

            mo = self.motion
            fitted = None
            if self.terms:
                fitted = fit_pi_series_for_motion(np.array([float(nj) for _, nj in self.terms]), float(mo.m),
                                                  float(mo.m1), float(mo.K))
            self._mp_cache["series"] = fitted
        return self._mp_cache["series"]

    @property
    def _i_start(self) -> Any:
        mp = _mp()
        mo = self.motion
        with mp.workdps(DPS):
            if self.q1 == 0:
                return mp.mpf(0)
            am = _am_mp(mo.v_start, mo.m)
            return (mo.v_start - mp.ellipe(am, mo.m)) / mo.m

    def value_mp(self, t) -> Any:
        """The integral at t at :data:`REFERENCE_DPS` digits (mpmath), a reference for the doubles."""
        mp = _mp()
        mo = self.motion
        with mp.workdps(REFERENCE_DPS):
            if "start" not in self._mp_cache:
                am_s = _am_mp(mo.v_start, mo.m)
                self._mp_cache["start"] = (mo.v_start - mp.ellipe(am_s, mo.m) if self.q1 != 0 else 0,
                                           [_pi_mp(nj, am_s, mo.m) for _, nj in self.terms])
            i_s, pi_s = self._mp_cache["start"]
            v = mo.kappa * mp.mpf(t) + mo.v_start
            am = _am_mp(v, mo.m)
            total = self.q0 * (v - mo.v_start)
            if self.q1 != 0:
                total += self.q1 * ((v - mp.ellipe(am, mo.m)) - i_s) / mo.m
            for (coef, nj), start in zip(self.terms, pi_s):
                total += coef * (_pi_mp(nj, am, mo.m) - start)
            return total / mo.kappa


def _am_mp(v, m) -> Any:
    """am(v|m), continuous (mpmath has sn, cn but no am)."""
    mp = _mp()
    K = mp.ellipk(m)
    j = mp.nint(v / (2 * K))
    r = v - 2 * K * j
    return mp.atan2(mp.ellipfun("sn", r, m=m), mp.ellipfun("cn", r, m=m)) + mp.pi * j


def _pi_mp(n, phi, m) -> Any:
    """Π(n; φ|m) for any real φ: 2jΠ(n|m) + Π(n; φ − jπ|m)."""
    mp = _mp()
    j = mp.nint(phi / mp.pi)
    rest = phi - mp.pi * j
    return (2 * j * _complete_pi_mp(n, m, mp.mp.prec) if j else 0) + mp.ellippi(n, rest, m)


@functools.lru_cache(maxsize=64)
def _complete_pi_mp(n, m, prec: int) -> Any:
    """mpmath's Π(n|m) at the caller's working precision ``prec`` (bits: part of the key, as the value depends on
    it).  An estimate asks for the same few at each of its times past the first half-period, and each costs as
    much as the incomplete integral."""
    return _mp().ellippi(n, m)


def rate_integral(motion: EllipticMotion, numerator: Sequence, denominator: Sequence) -> RateIntegral:
    """∫ R(u) dt along ``motion`` for R = N/D with N, D given by their coefficients in u (highest first, numbers
    mpmath reads); raises :class:`NotElliptic` where the partial fractions in w are not the simple kind the
    module docstring lists."""
    mp = _mp()
    from .quadrature_rational import rational_path, rational_rate_integral

    path = rational_path(motion)
    polynomial = all(mp.mpf(x) == 0 for x in list(denominator)[:-1])
    if getattr(motion, "elementary", False) and polynomial:  # polynomial or exponential in t: Σ C_j e^{jκt}
        from .quadrature_open import elementary_rate_integral

        return elementary_rate_integral(motion, numerator, denominator)
    if path is not None:
        # u rational in e^{κt}, e^{2iv} (m = 0), e^{2v} (m = 1) or t: partial fractions in that variable, any poles
        return rational_rate_integral(motion, numerator, denominator)
    if isinstance(motion, EllipticMotionCn):
        # u Möbius in cn (or a tangent of am): the rate's Fourier series in v, its error measured by a 30-digit refit
        from .quadrature_fourier import fourier_rate_integral

        return fourier_rate_integral(motion, numerator, denominator)
    with mp.workdps(DPS):
        N = [mp.mpf(x) for x in numerator]
        Dn = [mp.mpf(x) for x in denominator]
        A, B, C, D = motion.mobius
        k = max(len(N), len(Dn)) - 1
        lin_a, lin_c = [B, A], [D, C]  # A + B w and C + D w, highest first

        def poly_mul(p, q):
            out = [mp.mpf(0)] * (len(p) + len(q) - 1)
            for i, x in enumerate(p):
                for j, y in enumerate(q):
                    out[i + j] += x * y
            return out

        def poly_pow(p, e):
            out = [mp.mpf(1)]
            for _ in range(e):
                out = poly_mul(out, p)
            return out

        def in_w(coeffs):
            deg = len(coeffs) - 1
            total = [mp.mpf(0)]
            for i, x in enumerate(coeffs):
                power = deg - i
                term = poly_mul(poly_pow(lin_a, power), poly_pow(lin_c, k - power))
                term = [x * y for y in term]
                if len(term) > len(total):
                    total = [mp.mpf(0)] * (len(term) - len(total)) + total
                total = [s + y for s, y in zip(total, [mp.mpf(0)] * (len(total) - len(term)) + term)]
            return total

        num, den = in_w(N), in_w(Dn)
        # strip (numerically) zero leading coefficients: a Möbius with D = 0 lowers the degrees
        scale = max(abs(x) for x in den)
        while len(den) > 1 and abs(den[0]) <= mp.mpf(10) ** (-DPS + 5) * scale:
            den = den[1:]
        nscale = max([abs(x) for x in num] + [mp.mpf(0)])
        while len(num) > 1 and abs(num[0]) <= mp.mpf(10) ** (-DPS + 5) * max(nscale, scale):
            num = num[1:]
        # polynomial division num = quot·den + rem
        quot: list = []
        rem = list(num)
        while len(rem) >= len(den):
            f = rem[0] / den[0]
            quot.append(f)
            rem = [x - f * y for x, y in zip(rem, den + [mp.mpf(0)] * (len(rem) - len(den)))][1:]
        if len(quot) > 2:
            raise NotElliptic(f"expected the rate's polynomial part in w = sn² of degree ≤ 1, got {len(quot) - 1}")
        q1 = quot[-2] if len(quot) == 2 else mp.mpf(0)
        q0 = quot[-1] if quot else mp.mpf(0)
        terms = []
        if len(den) > 1:
            poles = mp.polyroots(den, maxsteps=400, extraprec=6 * DPS)
            dden = [x * (len(den) - 1 - i) for i, x in enumerate(den[:-1])]
            tiny = mp.mpf(10) ** (-DPS // 2)
            rscale = max([abs(x) for x in rem] + [mp.mpf(0)])
            for wj in poles:
                dval = mp.polyval(dden, wj)
                residue = mp.polyval(rem, wj) / dval if rem and dval != 0 else mp.mpf(0)
                if rscale == 0 or abs(residue) * abs(dval) <= tiny * rscale * (1 + abs(wj)) ** len(rem):
                    continue  # a removable pole (a zero numerator: no rate, e.g. p_c = 0)
                if abs(mp.im(wj)) > tiny * (1 + abs(wj)):
                    raise NotElliptic("expected the rate's poles real in w = sn², got a complex pole (not covered)")
                wj = mp.re(wj)
                residue = mp.re(residue)
                if -tiny <= wj <= 1 + tiny:
                    raise NotElliptic(f"expected the rate finite on the motion, got a pole at w = {mp.nstr(wj, 8)} "
                                      "(the motion passes through a pole of the rate)")
                if abs(dval) <= tiny * scale:
                    raise NotElliptic("expected simple poles of the rate, got a multiple pole")
                # r/(w − w_j) = (−r/w_j) / (1 − w/w_j)
                terms.append((-residue / wj, 1 / wj))
        integral = RateIntegral(motion, q0, q1, tuple(terms))
        # the start's Π by the route later times take (series or R_J), so the difference at t = 0 is exactly zero
        n0, r0 = motion.phase(np.zeros(1))
        series = integral._series()
        if series is not None and terms:
            at = series.mean * (r0[0] + 4.0 * n0[0] * float(motion.K)) + series.periodic(r0)[:, 0]
            integral.start = tuple(float(x) for x in at)
        else:
            integral.start = tuple(_pi_split_start(nj, motion) for _, nj in terms)
        return integral


def _pi_split_start(nj, motion: EllipticMotion) -> float:
    """Π(n_j; am v_s|m) as evaluated in doubles by the same routine as later times (so the difference at t = 0
    is exactly zero, and rounding is common to both ends)."""
    from ..special import pi_of_am

    n, r = motion.phase(np.zeros(1))
    return float(np.asarray(pi_of_am(float(nj), r, float(motion.m), m1=float(motion.m1),
                                     periods=n.astype(np.int64)), float)[0])
