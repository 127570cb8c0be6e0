"""The one-off constants of the free top's closed form, at 40 digits from the exact binary inputs (private).

Everything here runs once per motion, in mpmath; :mod:`.exact` evaluates the result in
double precision.  What makes the constants exact however close the motion is to an axis or
to the separatrix:

* **Gaps, not differences.**  Every constant (P², Q², S², λ², m, 1 - m, derived in
  :mod:`.exact_model`) is a product of moments, moment differences and the gaps
  G_k = 2T·I_k - L² = Σ_a I_a ω_a² (I_k - I_a) (:attr:`.exact_model.FreeTopExactModel.gap_constants`).
  The gaps are formed in exact rational arithmetic from the float inputs, so a tilt of 1e-320
  from an axis, or a motion 1e-60 from the separatrix (G_y ≈ 0), keeps all 40 digits; a
  difference of the rounded 2T·I_k and L² would keep none.  The separatrix is G_y = 0 exactly.
* **The initial phase from its nearest quarter period.**  u0 = q0·K + v0 with q0 the nearest
  multiple of K (where sn or cn vanish) and v0 = F(φ|m) computed by Carlson's R_F with
  Δ² = cos²φ + m1 sin²φ (DLMF 19.25.5), from the small one of the ratios ω_x/P, ω_y/Q, so a
  component of 1e-300 at t = 0 is reproduced to its last bit.  Near the separatrix only
  m1 = 1 - m is used (m itself rounds to 1).
* **A steady rotation is decided exactly:** ω is an eigenvector of the inertia tensor iff for
  every pair of axes the moments are equal or one of the components is zero; then Euler's
  equations (3.33) give ω̇ = 0 identically.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from fractions import Fraction

import mpmath
import numpy as np

from ...core.codecache import cached_lambdify
from ...core.phase import DD
from ...errors import DerivationError
from ...special.jacobi import shift_by_quarter_periods
from ._exact_gaps import TINY_M1, gaps, is_steady, relabelling, signed_permutation  # noqa: F401 - re-exported
from ._exact_gaps import build_gap_constants, build_precession, build_q

DPS = 40  # digits of every one-off constant
#: The relative tolerance of the t = 0 self-check at 40 digits (what survives ~15 digits of
#: amplification in the worst conditioned relabelling, with room to spare).
SELF_CHECK = mpmath.mpf(10) ** -25


@functools.cache
def _compiled_gap_constants():
    """(P², S², λ², Q², m, m1) as an mpmath function of (I_x, I_y, I_z, G_x, G_y, G_z), compiled once."""
    return cached_lambdify("free_top.gap_constants", build_gap_constants, module="mpmath")[0]


@functools.cache
def _compiled_q():
    """Q(I_x, I_y, I_z, P, S, λ) as an mpmath function (:func:`._exact_gaps.build_q`), compiled once."""
    return cached_lambdify("free_top.elliptic_Q_of_PS", build_q, module="mpmath")[0]


@functools.cache
def compiled_precession():
    """(c1, c2, n) of φ̇ = c1 + c2/(1 - n sn²) as an mpmath function of (I_x, I_y, I_z, 2T, L², |L|)."""
    return cached_lambdify("free_top.precession_fractions", build_precession, module="mpmath")[0]


def mpf_of(x: Fraction) -> mpmath.mpf:
    """A rational with a power-of-two denominator (a combination of floats) at the working precision."""
    return mpmath.mpf(x.numerator) / x.denominator


def _F(s, c, m1):
    """F(φ|m) for |φ| ≤ π/2 from s = sin φ, c = cos φ ≥ 0: s R_F(c², c² + m1 s², 1) (DLMF 19.25.5)."""
    return s * mpmath.elliprf(c * c, c * c + m1 * s * s, 1)


@dataclass(frozen=True)
class Elliptic:
    """The 40-digit constants of ω = (P cn u, Q sn u, S dn u) in the relabelled axes, u = λt + q0 K + v0."""

    perm: np.ndarray
    I_rel: tuple  # mpf moments (I_x, I_y, I_z)
    w_rel: tuple  # mpf ω0 in the relabelled axes (exact)
    two_T: mpmath.mpf
    L2: mpmath.mpf
    P: mpmath.mpf
    Q: mpmath.mpf
    S: mpmath.mpf
    lam: mpmath.mpf
    m: mpmath.mpf
    m1: mpmath.mpf
    K: mpmath.mpf | None  # None on the separatrix
    q0: int
    v0: mpmath.mpf
    A0: mpmath.mpf  # am(u0) in (-π, π]

    @property
    def u0(self) -> mpmath.mpf:
        return self.v0 if self.K is None else self.q0 * self.K + self.v0


def elliptic_constants(I: np.ndarray, w: np.ndarray) -> Elliptic:
    """The constants of a non-steady motion (call inside ``mpmath.workdps(DPS)``)."""
    two_T, L2, G = gaps(I, w)
    x, y, z = relabelling(I, G)
    perm = signed_permutation(x, y, z)
    wr = [mpmath.mpf(float(v)) for v in perm @ w]  # exact: a signed permutation of floats
    Im = tuple(mpmath.mpf(float(I[k])) for k in (x, y, z))
    P2, S2, lam2, _, m, m1 = _compiled_gap_constants()(*Im, *(mpf_of(G[k]) for k in (x, y, z)))
    separatrix = G[y] == 0
    if separatrix:
        m, m1 = mpmath.mpf(1), mpmath.mpf(0)
    elif m <= m1:  # the smaller of m, 1 - m keeps its relative digits; the other follows exactly
        m1 = 1 - m
    else:
        m = 1 - m1
    # On the separatrix cn = sech u > 0 never changes sign, so P carries the sign of ω_x.
    P = mpmath.sqrt(P2) * (mpmath.sign(wr[0]) if separatrix else 1)
    S = mpmath.sign(wr[2]) * mpmath.sqrt(S2)
    lam = mpmath.sqrt(lam2)
    Q = _compiled_q()(*Im, P, S, lam)[0]
    c0, s0, d0 = wr[0] / P, wr[1] / Q, wr[2] / S
    if separatrix:
        K, q0 = None, 0
        v0 = mpmath.asinh(s0 / c0)  # sinh u = sn/cn = tanh/sech
        h = mpmath.hypot(s0, c0)
        recon = (c0 / h, s0 / h, c0 / h)  # (cn, sn, dn) at u0 = (sech, tanh, sech)
        A0 = mpmath.atan2(s0, c0)
    else:
        kc = mpmath.sqrt(m1)
        K = mpmath.elliprf(0, m1, 1)
        # the nearest quarter period q0·K: rotate (cn, sn) by -q0·π/2 exactly (sign changes only)
        if abs(s0) <= abs(c0):
            q0 = 0 if c0 > 0 else (2 if s0 >= 0 else -2)
        else:
            q0 = 1 if s0 > 0 else -1
        cp, sp_ = {0: (c0, s0), 1: (s0, -c0), -1: (-s0, c0), 2: (-c0, -s0), -2: (-c0, -s0)}[q0]
        # am(v0): tan am(v0) = tan B for even q0, = tan B / k' for odd q0 (sn(K + v) = cd v, cn(K + v) = -k' sd v)
        ca = cp if q0 % 2 == 0 else kc * cp
        h = mpmath.hypot(sp_, ca)
        sv, cv = sp_ / h, ca / h
        dv = mpmath.sqrt(cv * cv + m1 * sv * sv)
        v0 = _F(sv, cv, m1)
        sn, cn, dn = shift_by_quarter_periods(q0, sv, cv, dv, kc)
        recon = (cn, sn, dn)
        A0 = mpmath.atan2(s0, c0)
    # The ansatz must reproduce ω(0) component by component, and satisfy Euler's equations (3.33):
    # a check on signs, branches and the constants themselves (the derivation is symbolic).
    amp = (abs(P), abs(Q), abs(S))
    floor = max(abs(v) for v in wr) * mpmath.mpf(10) ** -35
    err = max(abs(amp_k * sgn * f - wk) / max(abs(wk), floor)
              for amp_k, sgn, f, wk in zip(amp, (mpmath.sign(P), mpmath.sign(Q), mpmath.sign(S)), recon, wr))
    Ix, Iy, Iz = Im
    # relation 1 relative to its terms; relation 3 relative to λ S I_z, i.e. as an absolute error in m
    euler = max(abs(lam * P * Ix - (Iz - Iy) * Q * S) / abs(lam * P * Ix),
                abs(lam * m * S * Iz - (Iy - Ix) * P * Q) / abs(lam * S * Iz))
    if err > SELF_CHECK or euler > SELF_CHECK:
        raise DerivationError(f"elliptic solution does not reproduce ω(0) and Euler's equations (3.33): relative "
                              f"errors {mpmath.nstr(err, 3)}, {mpmath.nstr(euler, 3)} (expected < 1e-25)")
    if K is not None and abs(v0) > K / 2:  # keep |v0| <= K/2: the phase at t = 0 then reduces to (q0, v0) itself
        step = 1 if v0 > 0 else -1
        q0, v0 = q0 + step, v0 - step * K
    return Elliptic(perm=perm, I_rel=Im, w_rel=tuple(wr), two_T=mpf_of(two_T), L2=mpf_of(L2), P=P, Q=Q, S=S,
                    lam=lam, m=m, m1=m1, K=K, q0=q0, v0=v0, A0=A0)


def pi_amplitude(n, s, c, m1, Pi_complete):
    """Π(n; A|m) for A in (-π, π] from s = sin A, c = cos A (quasi-periodic, DLMF 19.2.10, 19.25.14)."""
    shift = 0
    if c < 0:  # A = ±π + ψ with |ψ| <= π/2
        shift = 2 if s >= 0 else -2
        s, c = -s, -c
    d2 = c * c + m1 * s * s
    return shift * Pi_complete + s * mpmath.elliprf(c * c, d2, 1) + n / 3 * s**3 * mpmath.elliprj(c * c, d2, 1,
                                                                                                   1 - n * s * s)


def lframe_angles(e: Elliptic) -> tuple[mpmath.mpf, mpmath.mpf]:
    """(θ'0, ψ'0) of the relabelled body relative to the L frame: cos θ' = L_z/|L|, ψ' = atan2(L_x, L_y)."""
    Lx, Ly, Lz = (i * w for i, w in zip(e.I_rel, e.w_rel))
    return mpmath.atan2(mpmath.hypot(Lx, Ly), Lz), mpmath.atan2(Lx, Ly)


def initial_precession_angle(M: np.ndarray, theta0, psi0) -> float:
    """φ'0 from R_L(0) = M = R3(ψ'0) R1(θ'0) R3(φ'0) (3.54), with θ'0 and ψ'0 known.

    R3(φ'0) = R1(θ'0)ᵀ R3(ψ'0)ᵀ M, whose first row is (cos φ'0, sin φ'0, 0): valid at every θ',
    including θ' = 0 where reading φ' and ψ' off M alone is impossible (gimbal lock).
    """
    Mm = mpmath.matrix([[mpmath.mpf(float(v)) for v in row] for row in M])
    c, s = mpmath.cos(theta0), mpmath.sin(theta0)
    R1 = mpmath.matrix([[1, 0, 0], [0, c, s], [0, -s, c]])
    c, s = mpmath.cos(psi0), mpmath.sin(psi0)
    R3 = mpmath.matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    X = R1.T * R3.T * Mm
    return float(mpmath.atan2(X[0, 1], X[0, 0]))
