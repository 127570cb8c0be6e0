"""The exact motion of a free rigid body: ω(t) by Jacobi elliptic functions, R(t) in closed form.

What is evaluated (derivation in :mod:`.exact_model`)
-----------------------------------------------------
Body axes are relabelled by a proper signed permutation Π (rows e_x, e_y, ±e_z)
so that y is the intermediate principal axis and z the axis ω circulates about
(the largest-moment axis when L² > 2T·I_y, the smallest when L² < 2T·I_y).  Then

    ω_x = P cn(u|m),   ω_y = Q sn(u|m),   ω_z = S dn(u|m),   u = λ t + u0,

with P², Q², S², λ², m, 1 - m functions of (I_x, I_y, I_z, 2T, L²) derived by
SymPy.  The polhode period is 4K(m)/λ.  On the separatrix (L² = 2T·I_y, m = 1)
the same formulas give the hyperbolic (tanh/sech) motion; for a symmetric body
(two equal moments) m = 0 and they reduce to (3.37).  When ω is an eigenvector of
the inertia tensor (a sphere, ω along a principal axis, or a symmetric body spinning
about any axis of its equal-moment plane) Euler's equations (3.33) give ω̇ = 0: a
steady rotation, R(t) = exp(hat(ω) t) R0.

Orientation: with the "L frame" f_b = S_bc ẽ_c chosen so that f_3 = L/|L|, the
relabelled body's Euler angles relative to the L frame are

    cos θ' = L_z/|L|,   ψ' = atan2(L_x, L_y),
    φ'(t) = φ'0 + (|L|/I_z) t + (c2/λ) [Π(n; am u | m) - Π(n; am u0 | m)],

(c2, n from the partial fractions of φ̇, derived), and the chapter's R is

    R(t) = Πᵀ R(φ', θ', ψ') S.

φ'0 is read from R_L(0) = Π R0 Sᵀ = R3(ψ'0) R1(θ'0) R3(φ'0) with θ'0, ψ'0 known
from L, which is valid at every θ' (reading all three angles off the matrix is not,
at θ' = 0).

Accuracy and long times
-----------------------
The constants are computed once, at 40 digits, from the exact binary inputs
(:mod:`._exact_setup`: through the gaps G_k = 2T·I_k - L², which are exact sums, so a
tilt of 1e-320 from an axis or a motion 1e-60 from the separatrix keeps every digit).
The phase u = λt + u0 is formed in double-double and reduced to the *nearest*
multiple of the quarter period, u = q·K + v with |v| ≤ K/2, and sn, cn, dn are taken
at v and shifted by q quarter periods (DLMF 22.4.iii).  As sn and cn vanish exactly at
the multiples of K, every component of ω keeps its *relative* accuracy — a component
of 1e-300 at t = 0, or passing through zero, is right to a few ulp of itself.  For
1 - m < 1e-34 the functions at v are tanh v, sech v (exact to double precision there),
so even 1 - m = 1e-600 (a tilt of 1e-300 from the intermediate axis) is evaluated with
its true period.  Evaluating at 10⁶ periods costs and errs no more than at one; the
continuous (unwrapped) angles φ, ψ are plain floats whose own rounding grows with t;
R and q use angles reduced modulo 2π in double-double.

The error of a run is measured by :meth:`FreeTopSolution.error_estimate`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ...core.phase import DD, mod_two_pi, reduce_phase_nearest
from ...core.validate import as_finite_array, check_rotation_matrix
from ...errors import InvalidInputError
from ...inertia.validate import check_principal_moments
from ...kinematics.rotations import euler_angles_from_matrix, rotation_matrix
from ...kinematics.so3 import expm_so3

__all__ = ["FreeTopSolution", "exact_free_top"]

#: Rotation (rad) per step of the grid on which the continuous Euler angles are tracked.
TRACKING_STEP = 0.25
#: The largest grid :meth:`FreeTopSolution.euler_angles` tracks on (~0.1 s of work per 10⁵ points).
MAX_TRACKING_POINTS = 4_000_000
_TRACKING_CHUNK = 1 << 16

#: |t| is refused beyond 2^50 quarter periods or turns: past it the count is no longer exact.
_MAX_COUNT = 2.0**50


@dataclass(frozen=True)
class _Orientation:
    """Constants of the orientation (φ', the L frame), computed on the first request for R(t).

    φ'(t) = φ'0 + ν t + (c2/λ) [p(u) - p(u0)], where Π(n; am u | m) = (Π(n|m)/K) u + p(u) splits
    the elliptic integral into its mean and its bounded 2K-periodic part p (on the separatrix
    Π(n|m)/K → 1/(1 - n)).  ν = c1 + c2 Π(n|m)/K is the mean precession rate; ν t is reduced
    modulo 2π in double-double, and p never grows, so no term loses digits at long times.
    """

    S: np.ndarray
    phi0: float
    nu: DD  # the mean precession rate c1 + c2·Π(n|m)/K
    c2_over_lam: float
    n: float
    slope: float  # tiny 1 - m: 1/(1 - n) - Π(n|m)/K, the small slope left in p on each quarter period
    pi_c_over_K: float  # Π(n|m)/K (the Carlson fallback subtracts it)
    p0: float  # p(u0) as evaluated in double (so φ'(0) = φ'0 exactly)
    dphi: DD | None  # precession per polhode period


def _nearest_arguments(q: np.ndarray, near: tuple[float, float]) -> tuple[float, float]:
    """The arguments of q0 + i q3 and q1 + i q2 nearest ``near`` (a zero pair keeps its ``near``)."""
    out = []
    for (x, y), a in zip(((q[0], q[3]), (q[1], q[2])), near):
        if x == 0.0 and y == 0.0:
            out.append(a)
        else:
            out.append(a + float(np.remainder(np.arctan2(y, x) - a + np.pi, 2 * np.pi) - np.pi))
    return out[0], out[1]


def _l_frame(L_space: np.ndarray) -> np.ndarray:
    """A rotation S whose third row is L/|L|; S = 1 when L is already along ẽ3.

    S is the minimal rotation taking ẽ3 to L̂ (rows are the L-frame axes in space
    components); for L̂ = -ẽ3 it is the half turn about ẽ1.  L may be of any size
    (it is scaled before it is normalised, so 1e-200 does not underflow).
    """
    L_space = np.asarray(L_space, dtype=float)
    n = L_space / np.max(np.abs(L_space))
    n = n / np.linalg.norm(n)
    c = n[2]
    if c > -0.5:
        # Rodrigues for the rotation about ẽ3 × n̂ by the angle between them, written without
        # dividing by sin: active A = c·1 + [v]× + v vᵀ/(1 + c), v = ẽ3 × n̂.  S = Aᵀ.
        v = np.array([-n[1], n[0], 0.0])
        vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
        A = c * np.eye(3) + vx + np.outer(v, v) / (1 + c)
    else:
        flip = np.diag([1.0, -1.0, -1.0])  # half turn about ẽ1 maps ẽ3 to -ẽ3
        A = flip @ _l_frame(flip @ n).T
    S = A.T
    S[2] = n  # exactly the unit L (A ẽ3 = n̂ up to rounding)
    return S


def _ldexp(x: np.ndarray, scaled: tuple[float, int]) -> np.ndarray:
    """x · (mantissa · 2^exp), rounded once (a tiny k' = √(1 - m) must not be a denormal first)."""
    return np.ldexp(scaled[0] * x, scaled[1])


@dataclass(frozen=True)
class _Jacobi:
    """sn, cn, dn at u = q·K + v (q an integer-valued float), and the values s, c, d at v."""

    q: np.ndarray
    v: np.ndarray
    sn: np.ndarray
    cn: np.ndarray
    dn: np.ndarray
    s: np.ndarray
    c: np.ndarray
    d: np.ndarray

    def __getitem__(self, index) -> "_Jacobi":
        return _Jacobi(*(getattr(self, f)[index] for f in ("q", "v", "sn", "cn", "dn", "s", "c", "d")))


@dataclass(frozen=True)
class FreeTopSolution:
    """The exact motion of one free rigid body; call its methods with arrays of times (s).

    Build it with :func:`exact_free_top`.  Attributes describe the motion:
    ``kind`` ('elliptic', 'separatrix' or 'steady'), ``m`` and ``m1`` (elliptic
    parameter and 1 - m, as floats: m1 underflows to 0 below 1e-308 although the
    motion stays periodic), ``polhode_period`` (s; ∞ on the separatrix, nan when
    steady), ``precession_per_period`` (rad of φ' per polhode period), ``energy``
    T and ``L_norm`` |L|.
    """

    moments: tuple[float, float, float]
    omega0: tuple[float, float, float]
    R0: np.ndarray
    kind: str
    m: float
    m1: float
    energy: float
    L_norm: float
    polhode_period: float
    _perm: np.ndarray
    _amp: tuple[float, float, float]  # P, Q, S
    _lam: DD
    _u0: DD  # the phase at t = 0, q0·K + v0
    _period: DD | None  # 4K in u
    _I_rel: tuple[float, float, float]
    _quarter: DD | None = None  # K
    _q0: int = 0
    _v0: DD = DD(0.0, 0.0)
    _kc: tuple[float, int] = (1.0, 0)  # k' = √(1 - m) as mantissa·2^exp
    _tiny: bool = False  # 1 - m < 1e-34: v-values are tanh, sech, sech
    _L_unit: tuple[float, float, float] = (0.0, 0.0, 1.0)  # (I_x P, I_y Q, I_z S)/|L|
    _ab_unit: tuple[float, float] = (1.0, 1.0)  # (I_x P, I_y Q)/max(|I_x P|, |I_y Q|): their ratio, never denormal
    _amp_scaled: tuple = ((0.0, 0.0, 0.0), 0)  # (P, Q, S)·2^-e and e, so that 1/2 ≤ max < 1: never denormal
    _t_max: float = float("inf")
    _spin: tuple = (None, None)  # steady: (|ω| as DD, unit ω)
    _mp: dict = field(default_factory=dict, repr=False)  # 40-digit setup values, caches

    # --- construction helpers --------------------------------------------------------------

    @functools.cached_property
    def _orient(self) -> _Orientation:
        if "extended" in self._mp:  # set up in extended precision: the orientation too, where its errors allow
            from .exact_extended import orientation

            o = orientation(self)
            if o is not None:
                return o
        import mpmath

        from . import _exact_setup as setup

        with mpmath.workdps(setup.DPS):
            return _orientation_setup(self)

    @property
    def _S(self) -> np.ndarray:
        return np.eye(3) if self.kind == "steady" else self._orient.S

    @property
    def t_max(self) -> float:
        """The largest |t| (s) evaluated: 2^50 quarter periods or turns of this motion (inf at rest).

        Beyond it the count of quarter periods (or of turns, reduced mod 2π) is no longer an exact
        integer in double precision; later times are refused.
        """
        return self._t_max

    @property
    def precession_per_period(self) -> float:
        """φ' advance per polhode period (rad); nan on the separatrix or for a steady rotation."""
        if self.kind != "elliptic":
            return float("nan")
        return self._orient.dphi.hi

    def _times(self, t: Any) -> np.ndarray:
        t = as_finite_array(t, "t")
        big = np.abs(t) > self._t_max
        if np.any(big):
            raise InvalidInputError(
                f"expected |t| <= {self._t_max:.6g} s (2^50 quarter periods or turns of this motion: beyond, "
                f"the count is no longer an exact integer), got t = {float(t[big].ravel()[0])!r}")
        return t

    # --- the phase and the Jacobi functions --------------------------------------------------

    def _jacobi(self, t: np.ndarray, *, keep: bool = True) -> _Jacobi:
        """sn, cn, dn at u(t) = λt + u0, reduced to the nearest quarter period.

        The last evaluation is kept (``keep``) for :meth:`error_estimate`, which checks exactly
        what was output; its own extra points (t = 0, quadrature nodes) pass ``keep=False``.
        """
        hit = self._cached("jacobi", t)
        if hit is not None:
            return hit
        q, v, v_lo = reduce_phase_nearest(self._lam, self._v0, self._quarter, t)
        q = q + self._q0
        if self._quarter is None or self._tiny:
            with np.errstate(over="ignore"):
                s, c = np.tanh(v), 1.0 / np.cosh(v)  # sech underflows to 0 far out: right to the last bit
            d = c
            m = 1.0
        else:
            from ...special.jacobi import jacobi_sn_cn_dn

            s, c, d = (np.asarray(x) for x in jacobi_sn_cn_dn(v, self.m, m1=self.m1))
            m = self.m
        # the low word of v to first order (sn' = cn dn, cn' = -sn dn, dn' = -m sn cn): for a large
        # |v| near the separatrix its rounding, ulp(v), would otherwise cost |v|/2 ulp of cn and dn
        s, c, d = s + c * d * v_lo, c - s * d * v_lo, d - m * s * c * v_lo
        qm = np.mod(q, 4.0)
        odd = (qm == 1.0) | (qm == 3.0)
        # even q: (±s, ±c, d); odd q: sn = ±cd v, cn = ∓k' sd v, dn = k' nd v (DLMF 22.4.iii)
        sign = np.where((qm == 0.0) | (qm == 1.0), 1.0, -1.0)
        sn = sign * np.where(odd, c / d, s)
        cn = np.where(odd, -sign * _ldexp(s / d, self._kc), sign * c)
        dn = np.where(odd, _ldexp(1.0 / d, self._kc), d)
        out = _Jacobi(q, v, sn, cn, dn, s, c, d)
        return self._store("jacobi", t, out) if keep else out

    def _cached(self, what: str, t: np.ndarray):
        """The last evaluation of ``what`` at exactly these times, if kept (for :meth:`error_estimate`)."""
        hit = self._mp.get(what)
        return hit[1] if hit is not None and hit[0] == (t.shape, t.tobytes()) else None

    def _store(self, what: str, t: np.ndarray, value):
        # one entry per quantity, keyed by the exact times: the estimate re-uses what was output
        self._mp[what] = ((t.shape, t.tobytes()), value)
        return value

    # --- angular velocity --------------------------------------------------------------------

    def omega_relabelled(self, t: Any) -> np.ndarray:
        """ω in the relabelled axes (x, y, z), shape (..., 3)."""
        t = self._times(t)
        if self.kind == "steady":
            return np.broadcast_to(self._perm @ np.array(self.omega0), t.shape + (3,)).copy()
        J = self._jacobi(t)
        (P, Q, S), e = self._amp_scaled
        # scaled by a power of two: exactly P·cn etc. in the normal range, rounded once if denormal
        return np.ldexp(np.stack([P * J.cn, Q * J.sn, S * J.dn], axis=-1), e)

    def omega(self, t: Any) -> np.ndarray:
        """Body components (ω1, ω2, ω3) at times ``t`` (rad/s), shape (..., 3)."""
        return self.omega_relabelled(t) @ self._perm  # ω = Πᵀ ω'  (row-vector form)

    def angular_momentum(self, t: Any) -> np.ndarray:
        """Body components L_a = I_a ω_a (3.28), shape (..., 3)."""
        return self.omega(t) * np.array(self.moments)

    # --- orientation -------------------------------------------------------------------------

    def _pi_series(self, n: float):
        """The Fourier series of Π(n; am u | m) of this motion's precession (fitted once), or None."""
        if "pi_series" not in self._mp:
            from ...special import pi_series

            self._mp["pi_series"] = None if self._tiny else pi_series.fit_pi_series_for_motion(
                np.array([n]), self.m, self.m1, self._quarter.hi)
        return self._mp["pi_series"]

    def _pi_panels(self, o: _Orientation):
        """p by Chebyshev panels from the quarter periods (fitted once), where the series declines."""
        if "pi_panels" not in self._mp:
            from ...special import pi_series

            self._mp["pi_panels"] = pi_series.fit_pi_panels(o.n, self.m, self.m1, self._quarter.hi,
                                                            o.pi_c_over_K)
        return self._mp["pi_panels"]

    def _periodic_pi(self, J: _Jacobi, o: _Orientation) -> np.ndarray:
        """p(u) = Π(n; am u | m) - (Π(n|m)/K) u, bounded and 2K-periodic, at u = q·K + v.

        Four regimes.  Separatrix and 1 - m < 1e-34: closed forms (below).  Otherwise the
        motion's Fourier series of Π (special.pi_series), whose coefficients fall like
        e^{-πδ/K} (δ the distance of the integrand's pole from the real axis); where it declines,
        near the separatrix, Chebyshev panels measured from the nearest quarter period, which keep
        p to ~1e-16 although Π ≈ u/(1 - n) is as large as K there.  Last resort, Carlson's R_J
        from sn, cn, dn of r (not from a rounded am(r), which would amplify the error by
        1/((1 - n sin²A) dn) ~ 1/√(1 - m) at the saddle passages), with rounding ulp(Π) ~ ulp(K).
        """
        if o.n == 0:
            return np.zeros_like(J.v)
        odd = np.mod(J.q, 2.0) == 1.0
        if self._quarter is None or self._tiny:
            # Separatrix (m = 1): Π(n; am u | 1) = [u + √-n arctan(√-n tanh u)]/(1 - n) (partial
            # fractions, with atanh(tanh u) = u exactly), and Π(n|m)/K → 1/(1 - n).  For 1 - m < 1e-34,
            # piecewise separatrix motion: on an even quarter the same integral; past K,
            # 1/(1 - n cd² w) = 1/(1 - n) to O(k').  So p = slope·v (+ the arctan on even quarters).
            k = np.sqrt(-o.n)
            atan_part = k * np.arctan(k * np.tanh(J.v)) / (1 - o.n)
            if self._quarter is None:
                return atan_part
            return o.slope * J.v + np.where(odd, 0.0, atan_part)
        series = self._pi_series(o.n)
        if series is not None:
            return series.periodic(np.where(odd, self._quarter.hi, 0.0) + J.v)[0]
        panels = self._pi_panels(o)
        if panels is not None:
            return panels(odd.astype(float), J.v)
        from ...special.integrals import pi_of_am

        r = np.where(odd, self._quarter.hi, 0.0) + J.v
        return np.asarray(pi_of_am(o.n, r, self.m, m1=self.m1)) - o.pi_c_over_K * r

    def _angles(self, t: np.ndarray, *, continuous: bool, keep: bool = True):
        """Euler angles (φ', θ', ψ') of the relabelled body relative to the L frame.

        With ``continuous=False`` φ' and ψ' are reduced modulo 2π exactly (for R);
        otherwise they are unwrapped in time (plain floats).
        """
        return self._angles_at(self._jacobi(t, keep=keep), t, continuous=continuous)

    def _rotation_at(self, J: _Jacobi, t: np.ndarray) -> np.ndarray:
        """R from the Jacobi values J at the times t."""
        phi, theta, psi = self._angles_at(J, t, continuous=False)
        return self._perm.T @ rotation_matrix(phi, theta, psi) @ self._S

    def _angles_at(self, J: _Jacobi, t: np.ndarray, *, continuous: bool):
        o = self._orient
        a, b, c = self._L_unit
        theta = np.arctan2(np.hypot(a * J.cn, b * J.sn), c * J.dn)
        a, b = self._ab_unit
        # am(u) = q·π/2 + δ: δ = am(v) for even q, and for odd q, from sn(K + v) = cd v and
        # cn(K + v) = -k' sd v, δ = atan2(k' sn v, cn v)
        qm = np.mod(J.q, 4.0)
        odd = (qm == 1.0) | (qm == 3.0)
        delta = np.where(odd, np.arctan2(_ldexp(J.s, self._kc), J.c), np.arctan2(J.s, J.c))
        # ψ' = atan2(a cn, b sn) = s_a·π/2 - s_a s_b·am u + a bounded periodic correction
        sa, sb = (1.0 if a >= 0 else -1.0), (1.0 if b >= 0 else -1.0)
        corr = np.arctan2(sa * sb * (abs(a) - abs(b)) * J.sn * J.cn, abs(b) * J.sn**2 + abs(a) * J.cn**2)
        quarters = J.q if continuous else qm
        psi = sa * np.pi / 2 - sa * sb * (quarters * (np.pi / 2) + delta) + corr
        periodic = o.c2_over_lam * (self._periodic_pi(J, o) - o.p0)
        if continuous:
            return o.phi0 + (o.nu.hi + o.nu.lo) * np.ldexp(t, o.nu.exp) + periodic, theta, psi
        return o.phi0 + mod_two_pi(o.nu, t) + periodic, theta, psi

    def euler_angles(self, t: Any) -> np.ndarray:
        """Euler angles (φ, θ, ψ) of R(t) (3.54), continued from t = 0 along the motion; shape (..., 3).

        When L lies along ẽ3 (to rounding) and the relabelling is the identity (the common
        case of a body circulating about axis 3 with L vertical) these are the L-frame angles,
        continuous by construction.  Otherwise (φ ± ψ)/2 — the arguments of the quaternion's
        pairs (q0, q3) and (q1, q2) — are followed from t = 0 along the motion itself, on a
        grid of at most :data:`TRACKING_STEP` rad of rotation a step (halved by the tracker where
        a step's change is not certain; :class:`~mechderive.solvers.half_angles.SampleTracker`),
        so the turns counted do not depend on how coarsely ``t`` samples the motion.  At θ = 0
        or π only φ ± ψ is defined; how near the path came to either is kept for
        :meth:`error_estimate` (``"euler_angles"``).  A run needing more than
        :data:`MAX_TRACKING_POINTS` grid points is refused.
        """
        t = self._times(t)
        # S within rounding of 1: the L-frame angles differ from R's by O(1e-16 / sin θ) at most.
        if self.kind != "steady" and np.allclose(self._S, np.eye(3), rtol=0, atol=4e-16) \
                and np.array_equal(self._perm, np.eye(3)):
            phi, theta, psi = self._angles(t, continuous=True)
            out = np.stack([phi, theta, psi], axis=-1)
            self._store("euler_angles", t, (out, None))
            return out
        return self._tracked_euler_angles(t)

    def _tracked_euler_angles(self, t: np.ndarray) -> np.ndarray:
        from ...kinematics.conversions import matrix_to_quaternion
        from ...solvers.half_angles import SampleTracker, euler_angles_from_half_angles, initial_half_angles

        flat = t.ravel()
        inertia = np.array(self.moments)
        # |ω|² = Σ ω_a² ≤ Σ I_a ω_a² / I_min = 2T / I_min: the fastest the body can turn
        w_max = float(np.sqrt(2.0 * self.energy / inertia.min()))
        h = TRACKING_STEP / w_max if w_max > 0 else np.inf
        # the start from R0 itself (the grid starts at t = 0), so that an exact pole start (R0 = 1, say)
        # is exactly one and the tracker takes φ - ψ from the direction the path leaves it in
        q0 = matrix_to_quaternion(self.R0)
        phi0, _, psi0 = euler_angles_from_matrix(self.R0)
        args0 = _nearest_arguments(q0, initial_half_angles(phi0, psi0))
        out = np.empty((flat.size, 3))
        near = None
        for side in (1.0, -1.0):
            sel = np.flatnonzero(side * flat >= 0.0)
            if sel.size == 0:
                continue
            span = float(np.max(side * flat[sel]))
            n = int(np.ceil(span / h)) if span > 0 else 0
            if n + sel.size > MAX_TRACKING_POINTS:
                raise InvalidInputError(
                    f"expected at most {MAX_TRACKING_POINTS} tracking points for continuous Euler angles, got "
                    f"{n + sel.size} (|t| up to {span:.6g} s at up to {w_max:.6g} rad/s): ask for R or the "
                    "quaternion instead, which need no tracking, or a shorter time")
            grid = np.union1d(np.linspace(0.0, span, n + 1), side * flat[sel])
            R = self._rotation(side * grid, keep=False)
            q = matrix_to_quaternion(R)
            flips = np.cumsum(np.r_[0, np.sum(q[1:] * q[:-1], axis=-1) < 0]) % 2  # q and -q: one rotation
            q = np.where(flips[:, None] == 1, -q, q)
            q[0] = q0 if np.dot(q0, q[0]) >= 0 else -q0
            # samples closer than MIN_TRACKED_TURN of rotation to the last tracked point are not tracked
            # through: R's rounding would be all their difference (a run of 1e-300 s), and the tracker
            # would refine noise.  Their half-angle arguments continue the tracked one's, nearest branch.
            kept = _tracked_points(grid, w_max)
            w = self._omega_values(side * grid[kept])
            states = np.concatenate([w * inertia, q[kept]], axis=-1)
            tracker = SampleTracker(states[0], inertia, args0 if np.dot(q0, q[0]) > 0 else (args0[0] + np.pi,
                                                                                             args0[1] + np.pi))
            tracked = np.empty((len(states), 2))
            tracked[0] = tracker.args_at(states[0])
            times = grid[kept]
            for a in range(0, len(states) - 1, _TRACKING_CHUNK):
                b = min(a + _TRACKING_CHUNK, len(states) - 1)
                tracked[a:b + 1] = tracker.feed(states[a:b + 1], side * np.diff(times[a:b + 1]))
            args = _continued_arguments(q, kept, tracked)
            angles = euler_angles_from_half_angles(q, args)
            out[sel] = angles[np.searchsorted(grid, side * flat[sel])]
            near = tracker.near.copy() if near is None else near + tracker.near
        # how near the path came to θ = 0 and π, less the start itself (given exactly by R0): a
        # passage closer than the error of R leaves the side it passed on, hence φ and ψ to ±2π, open
        start = (float(np.hypot(q0[0], q0[3])), float(np.hypot(q0[1], q0[2])))
        out = out.reshape(t.shape + (3,))
        self._store("euler_angles", t, (out, (near, start)))
        return out

    def _omega_values(self, t: np.ndarray) -> np.ndarray:
        """Body ω at ``t`` without replacing the kept evaluation (see :meth:`_jacobi`)."""
        if self.kind == "steady":
            return np.broadcast_to(np.array(self.omega0), t.shape + (3,))
        J = self._jacobi(t, keep=False)
        (P, Q, S), e = self._amp_scaled
        return np.ldexp(np.stack([P * J.cn, Q * J.sn, S * J.dn], axis=-1), e) @ self._perm

    def rotation(self, t: Any) -> np.ndarray:
        """The chapter's R(t) (rows = body axes in space components), shape (..., 3, 3)."""
        return self._rotation(self._times(t), keep=True)

    def _rotation(self, t: np.ndarray, *, keep: bool) -> np.ndarray:
        if self.kind == "steady":
            # Ṙ = hat(ω) R with constant ω: R = exp(hat(ω t)) R0.  Reduce |ω| t mod 2π first.
            rate, axis = self._spin
            if rate is None:
                return np.broadcast_to(self.R0, t.shape + (3, 3)).copy()
            return expm_so3(mod_two_pi(rate, t)[..., None] * axis) @ self.R0
        hit = self._cached("R", t)
        if hit is not None:
            return hit.copy()
        R = self._rotation_at(self._jacobi(t, keep=keep), t)
        return self._store("R", t, R).copy() if keep else R

    def quaternion(self, t: Any) -> np.ndarray:
        """Unit quaternion (scalar first) of the active rotation Rᵀ, sign kept continuous along t."""
        from ...kinematics.conversions import matrix_to_quaternion

        q = matrix_to_quaternion(self.rotation(t))
        if q.ndim == 2 and len(q) > 1:
            flips = np.cumsum(np.r_[0, np.sum(q[1:] * q[:-1], axis=-1) < 0]) % 2
            q = np.where(flips[:, None] == 1, -q, q)
        return q

    # --- the measured error ----------------------------------------------------------------------

    def error_estimate(self, t: Any, quantities: Sequence[str] = ("omega", "R")) -> float:
        """A bound on the error of :meth:`omega` / :meth:`rotation` at the times ``t``, measured on the run.

        Nothing in it is a constant: it is made of residuals at the very values output at ``t``
        (re-used, not recomputed, when ``omega(t)`` / ``rotation(t)`` were called with the same
        array), each converted to an error in the output — ω(0) - ω0 (as a phase error carried
        over the orbit), Euler's equations (3.33) with the analytic derivative of the ansatz (a
        rate error, times |t|max), conservation of 2T and L², the reduction period against an
        independent K(m); for R also R(0) - R0, conservation of L in space, and the increments of
        the precession angle φ' against Gauss–Legendre quadrature of the physical rate (3.58).
        Details: :mod:`mechderive.systems.free_top._exact_estimate`.

        ``quantities``: ``"omega"`` (then: error of ω relative to |ω0|) and/or ``"R"`` (absolute, in
        the entries of R, i.e. radians; includes the ω part, from which R's angles come); the result
        is the largest requested.  Asking only for ω evaluates nothing of the orientation.  Cost: the
        residual arithmetic on the samples plus, for R, one evaluation of a few hundred extra phases.

        >>> sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0))
        >>> t = np.linspace(0.0, 20.0, 201)
        >>> bool(sol.error_estimate(t) < 1e-12)
        True
        """
        from ._exact_estimate import error_estimate

        return error_estimate(self, t, quantities)

    # --- curves for plots ----------------------------------------------------------------------

    def polhode(self, samples: int = 400) -> np.ndarray:
        """ω over one polhode period (closed curve on the inertia ellipsoid), shape (samples, 3)."""
        if self.kind != "elliptic":
            raise InvalidInputError(f"expected a periodic (elliptic) motion for a polhode, got kind {self.kind!r}")
        return self.omega(np.linspace(0.0, self.polhode_period, samples))

    def herpolhode(self, t: Any) -> np.ndarray:
        """ω in L-frame components (f1, f2) — its trace on the invariable plane — shape (..., 2)."""
        w_space = np.einsum("...ab,...a->...b", self.rotation(t), self.omega(t))  # ω̃ = Rᵀ ω
        return (w_space @ self._S.T)[..., :2]


def exact_free_top(moments: Any, omega0: Any, *, R0: Any = None, strict: bool = True,
                   horizon: float | None = None) -> FreeTopSolution:
    """The exact motion of a free rigid body with principal moments ``moments``.

    Parameters
    ----------
    moments : (I1, I2, I3), principal moments about the centre of mass (kg m²), any order.
    omega0 : body components of ω at t = 0 (rad/s), any finite floats (denormals included).
    R0 : the chapter's R at t = 0 (default identity: body axes along the space axes).
    strict : ``False`` accepts moments that violate the triangle inequalities (no rigid body has
        them, e.g. (3, 3, 9)); positive, finite moments are required all the same.
    horizon : the largest |t| (s) the motion will be evaluated at, if known: the constants are then set up
        in extended precision where their measured errors over that span allow (:mod:`.exact_extended`,
        no mpmath), else at 40 digits as without it.

    >>> sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0))
    >>> sol.kind, round(sol.polhode_period, 6)
    ('elliptic', 6.790708)
    >>> bool(abs(sol.omega(0.0) - [1.0, 0.5, 1.0]).max() < 1e-15)
    True
    >>> exact_free_top((2.0, 2.0, 3.0), (1.0, 0.0, 0.0)).kind   # tumbling end over end: steady
    'steady'

    Every evaluation's error is measured by :meth:`FreeTopSolution.error_estimate`.  Refused with
    a :class:`~mechderive.errors.MechDeriveError`: moments no body can have (3.22), a non-rotation
    R0, non-finite input, and times beyond 2^50 turns or quarter periods of the motion.
    """
    I = check_principal_moments(*as_finite_array(moments, "moments", shape=(3,)), strict=strict)
    w0 = as_finite_array(omega0, "omega0", shape=(3,))
    R0 = np.eye(3) if R0 is None else check_rotation_matrix(R0, "R0")
    if horizon is not None:
        from .exact_extended import setup as extended

        sol = extended(I, w0, R0, float(horizon))
        if sol is not None:
            return sol
    import mpmath

    from . import _exact_setup as setup

    with mpmath.workdps(setup.DPS):
        return _setup(I, w0, R0)


def _setup(I: np.ndarray, w0: np.ndarray, R0: np.ndarray) -> FreeTopSolution:
    import mpmath

    from . import _exact_setup as setup

    mp = mpmath.mpf
    two_T, L2, _ = setup.gaps(I, w0)
    L_norm = mpmath.sqrt(setup.mpf_of(L2))
    common = dict(moments=tuple(map(float, I)), omega0=tuple(map(float, w0)), R0=R0,
                  energy=float(setup.mpf_of(two_T) / 2), L_norm=float(L_norm))
    nu = L_norm / mp(float(np.min(I)))  # every angular rate of the motion is at most |L|/I_min
    if setup.is_steady(I, w0):
        wm = [mp(float(x)) for x in w0]
        wn = mpmath.sqrt(sum(x * x for x in wm))
        spin = (None, None) if wn == 0 else (DD.scaled(wn), np.array([float(x / wn) for x in wm]))
        return FreeTopSolution(kind="steady", m=0.0, m1=1.0, polhode_period=float("nan"), _perm=np.eye(3),
                               _amp=(0.0, 0.0, 0.0), _lam=DD(0.0, 0.0), _u0=DD(0.0, 0.0), _period=None,
                               _I_rel=(1.0, 1.0, 1.0), _t_max=_t_max(nu), _spin=spin, **common)
    e = setup.elliptic_constants(I, w0)
    Ix, Iy, Iz = e.I_rel
    L_unit = tuple(float(i * amp / L_norm) for i, amp in zip(e.I_rel, (e.P, e.Q, e.S)))
    _, amp_exp = mpmath.frexp(max(abs(e.P), abs(e.Q), abs(e.S)))
    amp_scaled = (tuple(float(mpmath.ldexp(a, -int(amp_exp))) for a in (e.P, e.Q, e.S)), int(amp_exp))
    ab = (e.I_rel[0] * e.P, e.I_rel[1] * e.Q)
    ab_unit = tuple(float(x / max(abs(ab[0]), abs(ab[1]))) for x in ab)
    if e.K is None:
        kind, period, T, quarter, kc = "separatrix", None, float("inf"), None, (0.0, 0)
        nu = max(nu, e.lam)
    else:
        kind, period, T, quarter = "elliptic", DD.of(4 * e.K), float(4 * e.K / e.lam), DD.of(e.K)
        mant, ex = mpmath.frexp(mpmath.sqrt(e.m1))
        kc = (float(mant), int(ex))
        nu = max(nu, e.lam / e.K)
    return FreeTopSolution(
        kind=kind, m=float(e.m), m1=float(e.m1), polhode_period=T, _perm=e.perm,
        _amp=(float(e.P), float(e.Q), float(e.S)), _lam=DD.scaled(e.lam), _u0=DD.of(e.u0), _period=period,
        _I_rel=(float(Ix), float(Iy), float(Iz)), _quarter=quarter, _q0=e.q0, _v0=DD.of(e.v0), _kc=kc,
        _tiny=bool(e.K is not None and e.m1 < setup.TINY_M1), _L_unit=L_unit, _ab_unit=ab_unit,
        _amp_scaled=amp_scaled, _t_max=_t_max(nu),
        _mp=dict(constants=e, L=L_norm), **common)


#: Samples whose rotation from the last tracked point is below this (rad) continue its half-angle
#: arguments instead of being tracked through (see :meth:`FreeTopSolution._tracked_euler_angles`).
MIN_TRACKED_TURN = 2.0**-20


def _tracked_points(grid: np.ndarray, w_max: float) -> np.ndarray:
    """Indices into the increasing ``grid`` to track through: the first point of each span of
    :data:`MIN_TRACKED_TURN`/w_max (the first point always)."""
    if w_max <= 0 or len(grid) < 2:
        return np.arange(len(grid))
    cell = np.floor(grid * (w_max / MIN_TRACKED_TURN))
    return np.flatnonzero(np.r_[True, cell[1:] != cell[:-1]])


def _continued_arguments(q: np.ndarray, kept: np.ndarray, tracked: np.ndarray) -> np.ndarray:
    """The half-angle arguments (σ, δ) at every point: tracked at ``kept``, elsewhere the argument of
    q's pair (q0, q3) and (q1, q2) on the branch nearest the last tracked one (held where the pair is 0)."""
    if len(kept) == len(q):
        return tracked
    last = np.searchsorted(kept, np.arange(len(q)), side="right") - 1
    ref = tracked[last]
    out = np.empty_like(ref)
    for p, (i, j) in enumerate(((0, 3), (1, 2))):
        raw = np.arctan2(q[:, j], q[:, i])
        zero = (q[:, i] == 0) & (q[:, j] == 0)
        out[:, p] = np.where(zero, ref[:, p], raw + 2 * np.pi * np.round((ref[:, p] - raw) / (2 * np.pi)))
    out[kept] = tracked
    return out


def _t_max(rate) -> float:
    """The largest |t| at which 2^50 turns (or quarter periods) at ``rate`` are not exceeded."""
    return float("inf") if rate == 0 else float(_MAX_COUNT / rate)


def _orientation_setup(sol: FreeTopSolution) -> _Orientation:
    """The precession constants, the L frame and φ'0 (40 digits), for the first R(t) request (inside
    ``mpmath.workdps``); a motion set up in extended precision gets its 40-digit constants here."""
    import mpmath

    from . import _exact_setup as setup

    if "constants" not in sol._mp:  # the extended setup's orientation did not pass its checks
        I, w0 = np.array(sol.moments), np.array(sol.omega0)
        sol._mp["constants"] = setup.elliptic_constants(I, w0)
        sol._mp["L"] = mpmath.sqrt(setup.mpf_of(setup.gaps(I, w0)[1]))
    e = sol._mp["constants"]
    Lm = sol._mp["L"]
    c1, c2, n = setup.compiled_precession()(*e.I_rel, e.two_T, e.L2, Lm)
    n = n if e.m != 0 else mpmath.mpf(0)
    # The L frame and φ'0: L in space components is R0ᵀ L_body (its direction, formed at 40 digits
    # so that no component underflows).
    L_dir = np.array([float(mpmath.mpf(i) * mpmath.mpf(w) / Lm) for i, w in zip(sol.moments, sol.omega0)])
    S_frame = _l_frame(sol.R0.T @ L_dir)
    theta0, psi0 = setup.lframe_angles(e)
    phi0 = setup.initial_precession_angle(sol._perm @ sol.R0 @ S_frame.T, theta0, psi0)
    if e.K is None:
        pi_c_over_K, dphi = 1 / (1 - n), None
    else:
        from ...special.highprec import complete_pi_mp

        pi_c_over_K = complete_pi_mp(n, e.m1) / e.K
        dphi = DD.of((c1 + c2 * pi_c_over_K) * 4 * e.K / e.lam)
    # n = 0 (a symmetric body, m = 0): Π(0; am u | 0) = u, p ≡ 0, and c2/λ (which may overflow when
    # λ ∝ ω_z is tiny) is not needed
    c2_over_lam = 0.0 if n == 0 else float(c2 / e.lam)
    o = _Orientation(S=S_frame, phi0=phi0, nu=DD.scaled(c1 + c2 * pi_c_over_K), c2_over_lam=c2_over_lam,
                     n=float(n), slope=float(1 / (1 - n) - pi_c_over_K), pi_c_over_K=float(pi_c_over_K), p0=0.0,
                     dphi=dphi)
    # p(u0) through the very evaluation used at every t: φ'(0) = φ'0 exactly.
    p0 = float(sol._periodic_pi(sol._jacobi(np.zeros(1), keep=False), o)[0])
    return _Orientation(**{**o.__dict__, "p0": p0})
