"""∫ R(u(t)) dt for a rational rate R on the cn and tan forms (issue 16), by the Fourier series of the rate in the
Jacobi argument, with its error measured on the run.

On the cn forms (:class:`~mechderive.solvers.quadrature_motion.EllipticMotionCn`: a quartic with a complex pair, u
between its real roots or escaping outside them; the cubic with one real root) u = (A + B cn v)/(C + D cn v), and on
the tan form (a quartic with no real root) u = α1 + b tan(φ0 + am v); v = κt + v_s.  R(u(v)) is then periodic in v —
period Λ = 4K (cn) or 2K (tan: am grows by π) — and analytic on the real axis wherever R is finite on the whole range
u(v) takes over a period (the formulas run on through ∞ beyond an escape, so R must also be finite at u = ∞ there:
deg N ≤ deg D).  Written homogeneously, R = N(p/q)/D(p/q) with u = p/q, so the escape (q = 0) is no division by zero.

An analytic periodic function is its Fourier series, with coefficients falling geometrically; the trapezoidal rule on
M equispaced samples of a period gives them (the FFT) to an aliasing error ~ the M-th coefficient.  So

    ∫₀^t R dt' = (1/κ)[c₀ (v − v_s) + P(v) − P(v_s)],   P(v) = Σ_{k≥1} Re(2c_k e^{ikωv}/(ikω)),   ω = 2π/Λ,

c₀ the mean: the advance per period of u (4K/κ) is c₀·4K/κ.  M is doubled from 64 until the coefficients have
fallen below 2e-16 of max|R| (the FFT's rounding noise is ~5e-17 of it) within the first M/4 (else the form is refused, naming the slow decay: a pole of R near
the motion, or m near 1).  The secular part uses the phase v = n·4K + r in double-double, the periodic part r.

The error is measured, not assumed: :meth:`FourierRate.value_mp` refits at 30 digits from M/2 samples and keeps
8 terms more than the doubles (aliasing comes from index ≥ M/4, below the cut by the convergence test) — the
difference from the doubles is their rounding plus the truncation of their series, which the closed form's estimate
reports.  (30-digit sn, cn cost ~1 ms a pair; the period's symmetries leave M/8 pairs for the cn forms, M/4 for tan.)

Refused with the reason (:class:`~mechderive.solvers.quadrature_motion.NotElliptic`): a real pole of R on the range
of u over a period (the integral diverges where the motion reaches it, or the series cannot converge), a rate that
grows without bound at an escape (deg N > deg D), and a series that does not converge within 4096 samples.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .quadrature_motion import DPS, REFERENCE_DPS, NotElliptic, _mp, _split_mp, rate_coefficients_mp

__all__ = ["FourierRate", "fourier_rate_integral"]

#: sample counts tried per period (doubling); the fit is accepted when converged within the first quarter
_SAMPLES = (64, 128, 256, 512, 1024, 2048, 4096)
#: a coefficient below this fraction of max|R| counts as converged: the FFT's own rounding leaves every coefficient
#: with noise of ~5e-17 of it (as :mod:`mechderive.special.pi_series`)
_TAIL = 2e-16


def _is_tan(motion: Any) -> bool:
    from .quadrature_open import EllipticMotionTan

    return isinstance(motion, EllipticMotionTan)


def _homogeneous(motion: Any, sn, cn, xp=np):
    """(p, q) with u = p/q on the cn or tan form (numbers or arrays of ``xp``'s kind)."""
    if _is_tan(motion):
        alpha, b, s0, c0 = motion._tan_parts() if xp is np else motion.mobius
        q = c0 * cn - s0 * sn
        return alpha * q + b * (s0 * cn + c0 * sn), q
    A, B, C, D = motion._mob()[:4] if xp is np else motion.mobius
    return A + B * cn, C + D * cn


def _rate(N: Sequence, Dn: Sequence, p, q):
    """R(p/q) = q^{e−d} Σ n_k p^k q^{d−k} / Σ d_k p^k q^{e−k} (coefficients highest first): finite where q = 0 when
    d ≤ e."""
    d, e = len(N) - 1, len(Dn) - 1
    num = sum(c * p ** (d - i) * q**i for i, c in enumerate(N))
    den = sum(c * p ** (e - i) * q**i for i, c in enumerate(Dn))
    return num * q ** (e - d) / den if e >= d else num / (den * q ** (d - e))


@dataclass
class FourierRate:
    """∫₀^t R(u) dt' on a cn or tan form as c₀ v + P(v) (see the module docstring): ``mean`` c₀, ``coefficients``
    2c_k/(ikω) for k = 1.. (doubles), ``period_v`` Λ (40 digits), ``samples`` M."""

    motion: Any
    numerator: tuple
    denominator: tuple
    mean: float
    coefficients: np.ndarray
    period_v: Any
    samples: int
    _f: dict = field(default_factory=dict, repr=False)

    def _periodic(self, r: np.ndarray, coefficients: np.ndarray, omega: float) -> np.ndarray:
        """Re Σ_k a_k z^k, z = e^{iωr}, by Horner (|z| = 1: stable)."""
        z = np.exp(1j * omega * r)
        acc = np.zeros(r.shape, complex)
        for a in coefficients[::-1]:
            acc = (acc + a) * z
        return acc.real

    def __call__(self, t: Any, jac: tuple | None = None) -> np.ndarray:
        mo = self.motion
        t = np.asarray(t, dtype=float)
        _, _, _, n, r = mo.jacobi(t) if jac is None else jac
        n0, r0 = mo.phase(np.zeros(1))
        if "omega" not in self._f:
            mp = _mp()
            with mp.workdps(DPS):
                self._f["omega"] = float(2 * mp.pi / self.period_v)
                self._f["four_K"] = _split_mp(4 * mo.K)
                self._f["kappa"] = float(mo.kappa)
        omega = self._f["omega"]
        fk_hi, fk_lo = self._f["four_K"]
        turns = n - n0[0]
        advance = (r - r0[0]) + turns * fk_hi + turns * fk_lo  # v − v_s, the multiple of 4K kept apart
        periodic = self._periodic(r, self.coefficients, omega) - self._periodic(r0, self.coefficients, omega)[0]
        return (self.mean * advance + periodic) / self._f["kappa"]

    @property
    def advance(self) -> Any:
        """c₀·4K/κ, the increase over one period of u (4K in v) — only where u oscillates (no escape)."""
        if self.motion.escape_times is not None:
            raise NotElliptic("expected a periodic motion for an advance per period, got one that reaches ∞")
        mp = _mp()
        with mp.workdps(DPS):
            mean = self._reference()[0]
            return mean * 4 * self.motion.K / self.motion.kappa

    def _reference(self) -> tuple:
        """(c₀, [a_k], ω) refitted at 30 digits from M/2 samples (mpmath), cached: the reference of the estimate."""
        if "reference" not in self._f:
            mp = _mp()
            mo = self.motion
            with mp.workdps(REFERENCE_DPS):
                count = self.samples // 2
                step = self.period_v / count
                # sn, cn on [0, K] only, the rest by sn(2K − v) = sn v, cn(2K − v) = −cn v and (cn forms, Λ = 4K)
                # sn(v + 2K) = −sn v, cn(v + 2K) = −cn v: a quarter (cn) or half (tan) of the 30-digit evaluations
                half = count // 2 if _is_tan(mo) else count // 4
                base = [(mp.ellipfun("sn", j * step, m=mo.m), mp.ellipfun("cn", j * step, m=mo.m))
                        for j in range(half + 1)]
                pairs = []
                for j in range(count):
                    if j <= half:
                        pairs.append(base[j])
                    elif _is_tan(mo) or j <= 2 * half:
                        sn, cn = base[2 * half - j]
                        pairs.append((sn, -cn))
                    else:
                        sn, cn = pairs[j - 2 * half]
                        pairs.append((-sn, -cn))
                values = [_rate(self.numerator, self.denominator, *_homogeneous(mo, sn, cn, xp=mp)) for sn, cn in pairs]
                omega = 2 * mp.pi / self.period_v
                mean = mp.fsum(values) / count
                coefficients = []
                # the DFT coefficients a few past the doubles' cut (below it by then: their truncation is measured)
                for k in range(1, min(count // 2, len(self.coefficients) + 8) + 1):
                    root = mp.expjpi(-2 * mp.mpf(k) / count)
                    z, total = mp.mpc(1), mp.mpc(0)
                    for value in values:
                        total += value * z
                        z *= root
                    coefficients.append(2 * total / count / (1j * k * omega))
                self._f["reference"] = (mean, coefficients, omega)
        return self._f["reference"]

    def value_mp(self, t) -> Any:
        """The integral at t from the 30-digit refit (see the module docstring), at the caller's precision."""
        mp = _mp()
        mo = self.motion
        mean, coefficients, omega = self._reference()
        v = mo.kappa * mp.mpf(t) + mo.v_start

        def periodic(x):
            z = mp.expj(omega * x)
            acc = mp.mpc(0)
            for a in coefficients[::-1]:
                acc = (acc + a) * z
            return mp.re(acc)

        return (mean * (v - mo.v_start) + periodic(v) - periodic(mo.v_start)) / mo.kappa


def fourier_rate_integral(motion: Any, numerator: Sequence, denominator: Sequence) -> FourierRate:
    """∫ R(u) dt on a cn or tan form for R = N/D (coefficients in u, highest first); raises :class:`NotElliptic` for
    the cases the module docstring lists."""
    from ..special import jacobi_sn_cn_dn

    mp = _mp()
    with mp.workdps(DPS):
        N, Dn = rate_coefficients_mp(numerator, denominator)
        escaping = motion.escape_times is not None
        if escaping and len(N) > len(Dn) and any(x != 0 for x in N):
            raise NotElliptic(f"expected a rate bounded as u → ∞ on a motion that reaches ∞ (deg N ≤ deg D), got deg N = "
                              f"{len(N) - 1} > deg D = {len(Dn) - 1}: its integral diverges at the escape")
        _refuse_real_poles(motion, N, Dn)
        period_v = 2 * motion.K if _is_tan(motion) else 4 * motion.K
        Nf, Df = [float(x) for x in N], [float(x) for x in Dn]
        m, m1 = float(motion.m), float(motion.m1)
    for count in _SAMPLES:
        v = np.arange(count) * (float(period_v) / count)
        sn, cn, _ = (np.asarray(x, float) for x in jacobi_sn_cn_dn(v, m, m1=m1))
        p, q = _homogeneous(motion, sn, cn)
        with np.errstate(all="ignore"):
            values = _rate(Nf, Df, p, q)
        if not np.all(np.isfinite(values)):
            raise NotElliptic("expected the rate finite along the motion's formula, got a non-finite sample")
        c = np.fft.rfft(values) / count
        scale = float(np.max(np.abs(values))) or 1.0
        big = np.nonzero(np.abs(c[1:]) > _TAIL * scale)[0]
        kept = int(big[-1]) + 1 if big.size else 0
        if kept < count // 4 - 4:
            omega = 2 * np.pi / float(period_v)
            k = np.arange(1, kept + 1)
            coefficients = 2 * c[1:kept + 1] / (1j * k * omega)
            return FourierRate(motion, tuple(N), tuple(Dn), float(c[0].real), coefficients, period_v, count)
    tail = float(np.max(np.abs(c[count // 4:]))) / scale
    raise NotElliptic(f"expected the rate's Fourier series in the Jacobi argument to converge within {_SAMPLES[-1]} "
                      f"samples a period, got coefficients past the first quarter still {tail:.1e} of the rate (a pole "
                      f"of the rate near the motion, or m = {m:.6g} near 1): not covered")


def _refuse_real_poles(motion: Any, N: list, Dn: list) -> None:
    """Raise where a real pole of R lies on the range u takes over a period of the formula (see the module
    docstring); a pole cancelled by the numerator is none."""
    mp = _mp()
    if len(Dn) == 1:
        return
    tiny = mp.mpf(10) ** (-DPS // 2)
    for root in mp.polyroots(Dn, maxsteps=400, extraprec=6 * DPS):
        if abs(mp.im(root)) > tiny * (1 + abs(root)):
            continue
        p = mp.re(root)
        if abs(mp.polyval(N, p)) <= tiny * max(abs(x) for x in N + [mp.mpf(1)]) * (1 + abs(p)) ** len(N):
            continue
        if _is_tan(motion):
            reached = True  # u = α1 + b tan(…) takes every real value
        else:
            A, B, C, D = motion.mobius
            denominator = D * p - B
            reached = denominator != 0 and -1 <= (A - C * p) / denominator <= 1  # cn at u = p, inside [−1, 1]
        if reached:
            raise NotElliptic(f"expected the rate finite on the range of u, got a pole at u = {mp.nstr(p, 10)} that u "
                              "reaches over a period of its formula (the integral diverges there, or the series in the "
                              "Jacobi argument cannot converge): not covered on the cn and tan forms")
