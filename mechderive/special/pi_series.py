"""Π(n; am u | m) at many points of one motion, as a Fourier series fitted once per motion.

The heavy top's precession and spin angles need Π(n; am u | m) = ∫₀^u du' / (1 - n sn²u') at
thousands of phases u for two characteristics n.  The integrand is even, 2K-periodic and
analytic in a strip around the real axis, so

    1 / (1 - n sn²u) = a₀ + Σ_{k≥1} a_k cos(kπu/K),
    Π(n; am u | m)   = a₀ u + Σ_{k≥1} a_k K/(kπ) sin(kπu/K)        (any real u),

with a₀ = Π(n|m)/K and |a_k| falling like ρᵏ, ρ = exp(-π v/K) where ±iv is the distance of the
integrand's nearest pole (sn²u = 1/n) from the real axis.  The coefficients come from the
trapezoidal rule on M equally spaced points of one period — exact for a trigonometric
polynomial, and for an analytic periodic integrand in error by ~ρ^M (aliasing) — the M/4 + 1
coefficients that can be kept: at M = 128, as one product with a table of cosines (an FFT would compute all
M/2 of them, and importing ``numpy.fft`` cost more instructions than the product: ~6 M, 2 ms of a warm run);
at M = 512 by the FFT, whose rounding grows like log M where the product's grows like √M (see
:data:`_PRODUCT_UP_TO`); the series is summed by Clenshaw's recurrence (about 3 array operations a term).

For the usual top (ρ ≈ 0.25, 27 terms) this costs ~0.5 ms for 2001 phases and two
characteristics, against ~3 ms by Carlson's R_J (:func:`mechderive.special.integrals.pi_of_am`).
When the coefficients do not fall below the rounding level within the first M/4 — a pole near
the real axis, i.e. n → 1 near a pole passage of the apex, or m → 1 near the separatrix —
:func:`fit_pi_series` returns None and the caller uses Carlson's form.  Agreement of the two is
tested to a few ulp of Π over one period.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["PiSeries", "fit_pi_series", "fit_pi_series_for_motion"]

#: Samples per period tried for the fit; a series is accepted only if it has converged within M/4 terms.
_SAMPLES = (128, 512)
#: A coefficient counts as negligible below this fraction of max|integrand|: the cosine sums' own rounding
#: leaves every coefficient with noise of up to ~1.2e-16 of it (measured at M = 512 on 60 random motions;
#: the FFT's was 3e-17 to 1.7e-16), so the series is cut where the true coefficients sink into that noise.
_TAIL = 2e-16
#: the largest M whose coefficients come from the product with a table of cosines; above it, from the FFT. The
#: product spares the import of ``numpy.fft`` (~6 M instructions, 2 ms of a warm run) for the usual top (M = 128),
#: but its rounding grows with M: near the separatrix (M = 512) a free top's R came out 7e-15 off a 30-digit
#: integration where the FFT's coefficients give 2.4e-15 (tests/test_s3_4_free_top_edges.py::test_separatrix_full)
_PRODUCT_UP_TO = 128


class PiSeries:
    """Π(n_i; am u | m) for characteristics n_i, as ``mean[i]·u + Σ_k sine[i, k-1] sin(kπu/K)``.

    A plain class (a frozen dataclass's generated methods took ~1 ms of every warm run's imports; its ``==``
    and hash were of no use on arrays)."""

    __slots__ = ("n", "mean", "sine", "K")

    def __init__(self, n: np.ndarray, mean: np.ndarray, sine: np.ndarray, K: float) -> None:
        self.n = n        # (k,) the characteristics
        self.mean = mean  # (k,) a₀ = Π(n|m)/K
        self.sine = sine  # (k, N) the sine coefficients a_k K/(kπ), k = 1..N
        self.K = K

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """Π(n_i; am u | m) at u (any shape): shape (k, *u.shape)."""
        u = np.asarray(u, dtype=float)
        shape = (len(self.n),) + (1,) * u.ndim
        return self.mean.reshape(shape) * u + self.periodic(u)

    def periodic(self, u: np.ndarray) -> np.ndarray:
        """Π(n_i; am u | m) - a₀u, the bounded 2K-periodic part, shape (k, *u.shape).

        Summed directly, so it does not lose ulp(a₀u) to cancellation as ``self(u) - a₀u`` would.
        """
        u = np.asarray(u, dtype=float)
        theta = (np.pi / self.K) * u
        c2 = 2.0 * np.cos(theta)
        # Clenshaw for Σ_{k=1}^{N} s_k sin(kθ): y_k = s_k + 2cos θ y_{k+1} - y_{k+2}, sum = y_1 sin θ; one
        # characteristic at a time, its coefficients as numbers (all at once, each step broadcast a column of
        # them over the (k, *u.shape) arrays: ~60 % more instructions for the same values)
        sums = np.empty((len(self.n),) + u.shape)
        for i, coefficients in enumerate(self.sine.tolist()):
            y1 = np.zeros(u.shape)
            y2 = np.zeros(u.shape)
            for s_k in reversed(coefficients):
                y1, y2 = s_k + c2 * y1 - y2, y1
            sums[i] = y1
        return sums * np.sin(theta)


def fit_pi_series(n: np.ndarray, sn_squared, K: float) -> PiSeries | None:
    """Fit :class:`PiSeries` for characteristics ``n`` (k,), or None if it does not converge.

    ``sn_squared(u)`` returns sn²(u|m) at an array of u (the caller's accurate Jacobi function);
    ``K`` is K(m).  n must be < 1 and the motion periodic (m < 1).  Tries 128 samples per period,
    then 512; accepts a series whose coefficients are negligible (see :data:`_TAIL`) from some
    index N < M/4 - 4 on, so that aliasing (~ρ^M) is far below the truncation (~ρ^N).
    """
    n = np.atleast_1d(np.asarray(n, dtype=float))
    for samples in _SAMPLES:
        u = (2.0 * K / samples) * np.arange(samples)
        g = 1.0 / (1.0 - n[:, None] * sn_squared(u)[None, :])       # (k, M), one period, even in u
        # a₀ and a_k/2 = (1/M) Σ_j g_j cos(2πjk/M) for k ≤ M/4, the angles reduced exactly (jk mod M): the
        # table's entries are the M values cos(2πi/M), looked up (not its (M/4 + 1)·M cosines evaluated)
        if samples <= _PRODUCT_UP_TO:
            k = np.arange(samples // 4 + 1)
            cosines = np.cos((2.0 * np.pi / samples) * np.arange(samples))[np.outer(np.arange(samples), k) % samples]
            spectrum = (g @ cosines) / samples
        else:  # the FFT's rounding grows like log M, the product's like √M: at M = 512 the product lost R's last bits
            spectrum = np.fft.rfft(g, axis=1).real[:, :samples // 4 + 1] / samples
        a = 2.0 * spectrum[:, 1: samples // 4 + 1]
        small = np.all(np.abs(a) <= _TAIL * np.max(np.abs(g), axis=1)[:, None], axis=0)
        # N: the number of terms kept — every coefficient after it is negligible for every n
        later_all_small = np.flip(np.cumprod(np.flip(small))).astype(bool)
        if not later_all_small.any():
            continue
        N = int(np.argmax(later_all_small))
        if N >= a.shape[1] - 4:
            continue
        k = np.arange(1, N + 1)
        return PiSeries(n=n, mean=spectrum[:, 0], sine=a[:, :N] * (K / (np.pi * k))[None, :], K=float(K))
    return None


def fit_pi_series_for_motion(n: np.ndarray, m: float, m1: float, K: float, *, parameter: Any = None
                             ) -> PiSeries | None:
    """:func:`fit_pi_series` with sn² as :func:`mechderive.special.jacobi.jacobi_sn_cn_dn` gives it at
    parameter m (complement ``m1``, given as exactly as known) — what the closed-form tops use.

    ``parameter``: (m, m1) already validated (:func:`mechderive.special._parameter.parameter`), if the caller
    has it: not validated again (the samples are finite doubles, so sn is the same).
    """
    from ._parameter import parameter as validated
    from ._sncndn import reduced_sn_cn_dn

    p = validated(m, m1) if parameter is None else parameter
    return fit_pi_series(n, lambda u: reduced_sn_cn_dn(u, p)[0] ** 2, K)


#: Chebyshev degree per panel, and panel width as a fraction of the distance δ of the integrand's
#: nearest pole: with h = δ/2 the Bernstein ellipse through the pole has ρ = 4 + √17 ≈ 8.1, and
#: ρ^-18 ≈ 4e-17.
_PANEL_DEGREE = 18
_PANEL_WIDTH = 0.5
#: panels beyond this count (a pole very near the real axis) are not worth their setup
_MAX_PANELS = 4000


class PiPanels:
    """p(u) = Π(n; am u | m) - (Π(n|m)/K) u, the bounded part of Π, by panels from the quarter periods.

    p is odd about 0 and about K and vanishes at every multiple of K, so two functions on
    [0, K/2] give it everywhere: p₀(y) = p(y) and p₁(y) = p(K - y), each ∫₀^y of a bounded
    integrand, 1/(1 - n sn² s) - Π(n|m)/K and (with a minus sign) 1/(1 - n cd² s) - Π(n|m)/K
    (sn(K - s) = cd s), tabulated as piecewise Chebyshev interpolants integrated exactly.  At
    u = e·K + v (e = 0, 1 the parity of the nearest quarter period, |v| ≤ K/2)
    p = sign(v)·p₀(|v|) or -sign(v)·p₁(|v|).  Unlike Π itself (≈ u/(1 - n), as large as K near
    the separatrix) nothing here is large, so p keeps an absolute accuracy of ~1e-16.

    A plain class, as :class:`PiSeries` is.
    """

    __slots__ = ("width", "coef")

    def __init__(self, width: float, coef: np.ndarray) -> None:
        self.width = width
        self.coef = coef  # (2, panels, degree + 2): p₀ and p₁ on each panel, in x ∈ [-1, 1]

    def __call__(self, e: np.ndarray, v: np.ndarray) -> np.ndarray:
        y = np.abs(v)
        k = np.minimum((y / self.width).astype(int), self.coef.shape[1] - 1)
        x = 2.0 * (y - k * self.width) / self.width - 1.0
        c = self.coef[np.asarray(e, dtype=int), k]  # (..., degree + 2)
        b1 = np.zeros_like(x)
        b2 = np.zeros_like(x)
        for j in range(c.shape[-1] - 1, 0, -1):  # Clenshaw for Σ c_j T_j(x)
            b1, b2 = c[..., j] + 2.0 * x * b1 - b2, b1
        value = c[..., 0] + x * b1 - b2
        return np.sign(v) * np.where(np.asarray(e) == 1, -value, value)


def fit_pi_panels(n: float, m: float, m1: float, K: float, pi_c_over_K: float) -> PiPanels | None:
    """:class:`PiPanels` for characteristic n ≤ 0 (or None if too many panels would be needed).

    ``pi_c_over_K`` is Π(n|m)/K, known to more digits than a double evaluation would give.  The
    two cumulative integrals must meet at K/2 (p₀(K/2) = p₁(K/2)): a built-in check of the fit;
    None if they do not agree to 1e-14.
    """
    from numpy.polynomial import chebyshev as C

    from .jacobi import jacobi_sn_cn_dn

    delta = np.arctan(1.0 / np.sqrt(-n)) if n < 0 else np.pi / 2  # nearest pole: sn² = 1/n
    width = _PANEL_WIDTH * min(delta, np.pi / 2)
    panels = int(np.ceil(0.5 * K / width))
    if panels > _MAX_PANELS:
        return None
    x = C.chebpts1(_PANEL_DEGREE + 1)
    starts = width * np.arange(panels)
    s = (starts[:, None] + 0.5 * width * (x[None, :] + 1.0)).ravel()
    sn, cn, dn = (np.asarray(f) for f in jacobi_sn_cn_dn(s, m, m1=m1))
    g = np.stack([1.0 / (1.0 - n * sn**2), 1.0 / (1.0 - n * (cn / dn) ** 2)]) - pi_c_over_K
    g = g.reshape(2, panels, _PANEL_DEGREE + 1)
    V = C.chebvander(x, _PANEL_DEGREE)
    c = g @ V * (2.0 / (_PANEL_DEGREE + 1))  # discrete orthogonality at the first-kind points
    c[..., 0] *= 0.5
    integral = C.chebint(c, lbnd=-1, scl=0.5 * width, axis=-1)  # ∫ from the panel's start
    whole = C.chebval(1.0, np.moveaxis(integral, -1, 0))  # each panel's integral, (2, panels)
    before = np.concatenate([np.zeros((2, 1)), np.cumsum(whole, axis=1)[:, :-1]], axis=1)
    integral[..., 0] += before
    integral[1] *= -1.0  # p₁(y) = p(K - y) = -∫₀^y (1/(1 - n cd² s) - Π/K) ds
    coef = integral
    half = 0.5 * K
    ends = PiPanels(width, coef)
    p0, p1 = (float(ends(np.array(e), np.array(half))) for e in (0, 1))
    if abs(p0 + p1) > 1e-14:  # p₀(K/2) = p(K/2) and -p₁(K/2) evaluates as -p(K/2) through __call__
        return None
    return ends
