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
(two equal moments) m = 0 and they reduce to (3.37); a sphere, or a steady
rotation about a principal axis, is a constant ω.

Orientation: with the "L frame" f_b = S_bc ẽ_c chosen so that f_3 = L/|L|, the
relabelled body's Euler angles relative to the L frame are

    cos θ' = L_z/|L|,   ψ' = atan2(L_x, L_y),
    φ'(t) = φ'0 + (|L|/I_z) t + (c2/λ) [Π(n; am u | m) - Π(n; am u0 | m)],

(c2, n from the partial fractions of φ̇, derived), and the chapter's R is

    R(t) = Πᵀ R(φ', θ', ψ') S.

Accuracy and long times
-----------------------
All constants are computed once, from the exact binary inputs, in mpmath at 40
digits, so 1 - m keeps its digits however close the motion is to the
separatrix.  The phase u = λt + u0 is formed in double-double and reduced by the
period 4K in double-double, giving an exact integer period count j and a
remainder r in [0, 4K); the functions are evaluated at r, and the precession
angle gains j·Δφ (Δφ per period, double-double) reduced modulo 2π in
double-double.  Hence evaluating at 10⁶ periods costs and errs no more than at
one, apart from the rounding of t itself (relative 1.1e-16) which no method can
avoid.  The continuous (unwrapped) angles φ, ψ are returned as plain floats,
whose own rounding (ulp of the angle) grows with t; R and q use the reduced
angles.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import mpmath
import numpy as np

from ...core.codecache import cached_lambdify
from ...core.phase import DD, mod_two_pi, reduce_phase
from ...special.highprec import complete_pi_mp
from ...core.validate import as_finite_array, check_rotation_matrix
from ...errors import DerivationError, InvalidInputError
from ...inertia.validate import check_principal_moments
from ...kinematics.rotations import continuous_euler_angles, euler_angles_from_matrix, rotation_matrix
from ...kinematics.so3 import expm_so3

__all__ = ["FreeTopSolution", "exact_free_top"]

_DPS = 40  # digits for the one-off constants: 1 - m keeps >= 25 digits down to 1 - m ~ 1e-15


_CONSTANT_NAMES = ("P2", "S2", "lambda2", "Q2", "m", "m1")


def _exact_args():
    from . import exact_model as em

    return [em.Ix, em.Iy, em.Iz, em.E2, em.L2]


@functools.cache
def _compiled_constants():
    """The derived constants of ω(t) as mpmath functions of (I_x, I_y, I_z, 2T, L²), compiled once.

    Through the disk cache: a warm process neither imports SymPy nor derives.
    """
    def build_constants():
        from . import exact_model as em

        c = em.model().constants
        return _exact_args(), [c[k] for k in _CONSTANT_NAMES]

    def build_q():
        import sympy as sp

        from . import exact_model as em

        return [*_exact_args(), *sp.symbols("P S lambda", real=True)], [em.model().constants["Q"]]

    consts, _ = cached_lambdify("free_top.elliptic_constants", build_constants, module="mpmath")
    q, _ = cached_lambdify("free_top.elliptic_Q", build_q, module="mpmath")
    funcs = {name: (lambda k: (lambda *a: consts(*a)[k]))(k) for k, name in enumerate(_CONSTANT_NAMES)}
    funcs["Q"] = lambda *a: q(*a)[0]
    return funcs


@functools.cache
def _compiled_precession():
    """(c1, c2, n) of φ̇ = c1 + c2/(1 - n sn²) as an mpmath function of (I_x, I_y, I_z, 2T, L², |L|).

    Derived (and compiled) only when R(t) is asked for.
    """
    def build():
        from . import exact_model as em

        pf = em.model().precession_partial_fractions
        return [*_exact_args(), em.L], [pf["c1"], pf["c2"], pf["n"]]

    return cached_lambdify("free_top.precession_fractions", build, module="mpmath")[0]


@dataclass(frozen=True)
class _Orientation:
    """Constants of the orientation (φ', the L frame), computed on the first request for R(t)."""

    S: np.ndarray
    phi0: float
    c1_over_lam: float
    c2_over_lam: float
    n: float
    pi_u0: float
    dphi: DD | None  # precession per period (None on the separatrix)
    rate_inf: DD | None  # separatrix: the asymptotic precession rate c1 + c2/(1 - n)
    arctan_u0: float  # separatrix: arctan(√(-n) tanh u0)


def _signed_permutation(x: int, y: int, z: int) -> np.ndarray:
    """Rows e_x, e_y, σ e_z with σ = ±1 chosen so that det = +1 (a proper rotation)."""
    Pm = np.zeros((3, 3))
    Pm[0, x] = Pm[1, y] = Pm[2, z] = 1.0
    Pm[2, z] = np.linalg.det(Pm)
    return Pm


def _l_frame(L_space: np.ndarray) -> np.ndarray:
    """A rotation S whose third row is L/|L|; S = 1 when L is already along ẽ3.

    S is the minimal rotation taking ẽ3 to L̂ (rows are the L-frame axes in space
    components); for L̂ = -ẽ3 it is the half turn about ẽ1.
    """
    n = L_space / np.linalg.norm(L_space)
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


@dataclass(frozen=True)
class FreeTopSolution:
    """The exact motion of one free rigid body; call its methods with arrays of times (s).

    Build it with :func:`exact_free_top`.  Attributes describe the motion:
    ``kind`` ('elliptic', 'separatrix' or 'steady'), ``m`` and ``m1`` (elliptic
    parameter and 1 - m), ``polhode_period`` (s; ∞ on the separatrix, nan when
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
    _amp: tuple[float, float, float]
    _lam: DD
    _u0: DD
    _period: DD | None  # 4K in u
    _I_rel: tuple[float, float, float]
    _mp: dict = field(default_factory=dict, repr=False)  # 40-digit setup values for the lazy orientation

    @functools.cached_property
    def _orient(self) -> _Orientation:
        with mpmath.workdps(_DPS):
            return _orientation_setup(self)

    @property
    def _S(self) -> np.ndarray:
        return np.eye(3) if self.kind == "steady" else self._orient.S

    @property
    def precession_per_period(self) -> float:
        """φ' advance per polhode period (rad); nan on the separatrix or for a steady rotation."""
        if self.kind != "elliptic":
            return float("nan")
        return self._orient.dphi.hi

    # --- the phase ---------------------------------------------------------------------------

    def _phase(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(j, r): u(t) = λt + u0 = j·4K + r with integer j and r in [0, 4K) (see :mod:`mechderive.core.phase`)."""
        return reduce_phase(self._lam, self._u0, self._period, t)

    def _pi_series(self):
        """The Fourier series of Π(n; am u | m) of this motion's precession (fitted once), or None."""
        if "pi_series" not in self._mp:
            from ...special import pi_series

            self._mp["pi_series"] = pi_series.fit_pi_series_for_motion(np.array([self._orient.n]), self.m, self.m1,
                                                                       self._period.hi / 4)
        return self._mp["pi_series"]

    def _elliptic(self, t: np.ndarray):
        from ...special.jacobi import jacobi_am, jacobi_sn_cn_dn

        j, r = self._phase(t)
        sn, cn, dn = jacobi_sn_cn_dn(r, self.m, m1=self.m1)
        return j, r, np.asarray(sn), np.asarray(cn), np.asarray(dn), jacobi_am

    # --- angular velocity --------------------------------------------------------------------

    def omega_relabelled(self, t: Any) -> np.ndarray:
        """ω in the relabelled axes (x, y, z), shape (..., 3)."""
        t = as_finite_array(t, "t")
        if self.kind == "steady":
            return np.broadcast_to(self._perm @ np.array(self.omega0), t.shape + (3,)).copy()
        _, _, sn, cn, dn, _ = self._elliptic(t)
        P, Q, S = self._amp
        return np.stack([P * cn, Q * sn, S * dn], axis=-1)

    def omega(self, t: Any) -> np.ndarray:
        """Body components (ω1, ω2, ω3) at times ``t`` (rad/s), shape (..., 3)."""
        return self.omega_relabelled(t) @ self._perm  # ω = Πᵀ ω'  (row-vector form)

    def angular_momentum(self, t: Any) -> np.ndarray:
        """Body components L_a = I_a ω_a (3.28), shape (..., 3)."""
        return self.omega(t) * np.array(self.moments)

    # --- orientation -------------------------------------------------------------------------

    def _angles(self, t: np.ndarray, *, continuous: bool):
        """Euler angles (φ', θ', ψ') of the relabelled body relative to the L frame.

        With ``continuous=False`` φ' and ψ' are reduced modulo 2π exactly (for R);
        otherwise they are unwrapped in time (plain floats).
        """
        from ...special.integrals import pi_of_am

        j, r, sn, cn, dn, jacobi_am = self._elliptic(t)
        P, Q, S = self._amp
        Ix, Iy, Iz = self._I_rel
        Lx, Ly, Lz = Ix * P * cn, Iy * Q * sn, Iz * S * dn
        theta = np.arctan2(np.hypot(Lx, Ly), Lz)
        A = np.asarray(jacobi_am(r, self.m, m1=self.m1))  # am(r) in [0, 2π) for r in [0, 4K)
        a, b, s = Ix * P, Iy * Q, np.sign(Q)
        # ψ' = atan2(L_x, L_y) = π/2 - s·am(u) + a bounded periodic correction (see module docstring)
        corr = np.arctan2((a * s - b) * sn * cn, b * s * sn**2 + a * cn**2)
        psi_red = np.pi / 2 - s * A + corr
        o = self._orient
        if o.dphi is None:
            # Separatrix (m = 1): with s = sn u = tanh u, Π(n; am u | 1) = ∫ ds / ((1 - n s²)(1 - s²))
            # = [atanh s + √(-n) arctan(√(-n) s)] / (1 - n) for n ≤ 0 (partial fractions), and
            # atanh(tanh u) = u exactly.  The linear parts combine into one rate, reduced mod 2π in
            # double-double, so nothing cancels however long the run (Π itself grows like u).
            k = np.sqrt(-o.n)
            bounded = o.c2_over_lam * k / (1 - o.n) * (np.arctan(k * np.tanh(r)) - o.arctan_u0)
            return o.phi0 + mod_two_pi(o.rate_inf, t) + bounded, theta, psi_red
        # Π(n; am r | m) straight from r: by the motion's Fourier series where it converges
        # (special.pi_series, fitted once), else by Carlson from sn, cn, dn of r — through the rounded
        # am(r) the error would be amplified by 1/((1 - n sin²A) dn) ~ 1/√(1 - m) at the saddle
        # passages near the separatrix.
        series = self._pi_series()
        if series is not None:
            pi_r = series(r)[0]
        else:
            pi_r = np.asarray(pi_of_am(o.n, r, self.m, m1=self.m1))
        phi_red = o.phi0 + o.c1_over_lam * (r - self._u0.hi - self._u0.lo) + o.c2_over_lam * (pi_r - o.pi_u0)
        if continuous:
            return phi_red + j * (o.dphi.hi + o.dphi.lo), theta, psi_red - s * 2 * np.pi * j
        return phi_red + mod_two_pi(o.dphi, j), theta, psi_red

    def euler_angles(self, t: Any) -> np.ndarray:
        """Euler angles (φ, θ, ψ) of R(t), continuous in time; shape (..., 3).

        When L lies along ẽ3 (to rounding) and the relabelling is the identity (the common
        case of a body circulating about axis 3 with L vertical) these are the L-frame angles,
        continuous by construction.  Otherwise they are extracted from R(t) and unwrapped
        along ``t`` (a 1-D array, sorted and sampled finely enough that φ and ψ change by
        less than π between samples); at θ = 0 or π, where only φ ± ψ is defined, ψ is
        carried over from the neighbouring sample.
        """
        t = as_finite_array(t, "t")
        # S within rounding of 1: the L-frame angles differ from R's by O(1e-16 / sin θ) at most.
        if self.kind != "steady" and np.allclose(self._S, np.eye(3), rtol=0, atol=4e-16) \
                and np.array_equal(self._perm, np.eye(3)):
            phi, theta, psi = self._angles(t, continuous=True)
            return np.stack([phi, theta, psi], axis=-1)
        return continuous_euler_angles(euler_angles_from_matrix(self.rotation(t)))

    def rotation(self, t: Any) -> np.ndarray:
        """The chapter's R(t) (rows = body axes in space components), shape (..., 3, 3)."""
        t = as_finite_array(t, "t")
        if self.kind == "steady":
            # Ṙ = hat(ω) R with constant ω: R = exp(hat(ω t)) R0.  Reduce |ω| t mod 2π first.
            w = np.array(self.omega0)
            wn = np.linalg.norm(w)
            if wn == 0:
                return np.broadcast_to(self.R0, t.shape + (3, 3)).copy()
            return expm_so3(mod_two_pi(wn, t)[..., None] * (w / wn)) @ self.R0
        phi, theta, psi = self._angles(t, continuous=False)
        RL = rotation_matrix(phi, theta, psi)
        return self._perm.T @ RL @ self._S

    def quaternion(self, t: Any) -> np.ndarray:
        """Unit quaternion (scalar first) of the active rotation Rᵀ, sign kept continuous along t."""
        from ...kinematics.conversions import matrix_to_quaternion

        q = matrix_to_quaternion(self.rotation(t))
        if q.ndim == 2 and len(q) > 1:
            flips = np.cumsum(np.r_[0, np.sum(q[1:] * q[:-1], axis=-1) < 0]) % 2
            q = np.where(flips[:, None] == 1, -q, q)
        return q

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


def exact_free_top(moments: Any, omega0: Any, *, R0: Any = None, strict: bool = True) -> FreeTopSolution:
    """The exact motion of a free rigid body with principal moments ``moments``.

    Parameters
    ----------
    moments : (I1, I2, I3), principal moments about the centre of mass (kg m²), any order.
    omega0 : body components of ω at t = 0 (rad/s).
    R0 : the chapter's R at t = 0 (default identity: body axes along the space axes).
    strict : ``False`` accepts moments that violate the triangle inequalities (no rigid body has
        them, e.g. (3, 3, 9)); positive, finite moments are required all the same.

    >>> sol = exact_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0))
    >>> sol.kind, round(sol.polhode_period, 6)
    ('elliptic', 6.790708)
    >>> bool(abs(sol.omega(0.0) - [1.0, 0.5, 1.0]).max() < 1e-15)
    True
    """
    I = check_principal_moments(*as_finite_array(moments, "moments", shape=(3,)), strict=strict)
    w0 = as_finite_array(omega0, "omega0", shape=(3,))
    R0 = np.eye(3) if R0 is None else check_rotation_matrix(R0, "R0")
    with mpmath.workdps(_DPS):
        return _setup(I, w0, R0)


def _setup(I: np.ndarray, w0: np.ndarray, R0: np.ndarray) -> FreeTopSolution:
    mp = mpmath.mpf
    Im = [mp(float(x)) for x in I]
    wm = [mp(float(x)) for x in w0]
    E2 = sum(Im[a] * wm[a] ** 2 for a in range(3))
    L2 = sum(Im[a] ** 2 * wm[a] ** 2 for a in range(3))
    energy, L_norm = float(E2 / 2), float(mpmath.sqrt(L2))
    order = np.argsort(I, kind="stable")
    lo_ax, mid_ax, hi_ax = (int(k) for k in order)
    common = dict(moments=tuple(map(float, I)), omega0=tuple(map(float, w0)), R0=R0, energy=energy, L_norm=L_norm)

    def steady() -> FreeTopSolution:
        return FreeTopSolution(kind="steady", m=0.0, m1=1.0, polhode_period=float("nan"), _perm=np.eye(3),
                               _amp=(0.0, 0.0, 0.0), _lam=DD(0.0, 0.0), _u0=DD(0.0, 0.0), _period=None,
                               _I_rel=(1.0, 1.0, 1.0), **common)

    if L2 == 0 or I[lo_ax] == I[hi_ax]:
        return steady()  # at rest, or a sphere: ω is constant
    delta = L2 - E2 * Im[mid_ax]  # > 0: ω circulates about the largest-moment axis
    if delta >= 0:
        x, z = lo_ax, hi_ax
    else:
        x, z = hi_ax, lo_ax
    y = mid_ax
    perm = _signed_permutation(x, y, z)
    wr = [mp(float(v)) for v in perm @ w0]  # exact: a signed permutation of floats
    Ix, Iy, Iz = Im[x], Im[y], Im[z]
    f = _compiled_constants()
    args = (Ix, Iy, Iz, E2, L2)
    P2, S2 = f["P2"](*args), f["S2"](*args)
    if P2 <= 0 or S2 <= 0 or wr[2] == 0:
        return steady()  # ω along a principal axis (or in a degenerate plane): steady rotation
    if Iy == Ix or Iy == Iz:
        m, m1 = mp(0), mp(1)  # symmetric body: the (I_x - I_y) factor vanishes exactly
    else:
        m, m1 = f["m"](*args), f["m1"](*args)
    if wr[0] == 0 and wr[1] == 0:
        return steady()
    P = mpmath.sqrt(P2)
    S = mpmath.sign(wr[2]) * mpmath.sqrt(S2)
    lam = mpmath.sqrt(f["lambda2"](*args))
    Q = f["Q"](*args, P, S, lam)
    if Q == 0:
        return steady()
    A0 = mpmath.atan2(wr[1] / Q, wr[0] / P)
    u0 = mpmath.ellipf(A0, m)
    # The ansatz must reproduce ω(0): a check on signs and branches (the derivation is symbolic).
    # sn u0 = sin A0, cn u0 = cos A0, dn u0 = √(1 - m sin²A0) exactly (u0 = F(A0|m), DLMF 22.16.1),
    # so the check tests P, Q, S and m themselves without three 40-digit Jacobi evaluations.
    sn0, cn0 = mpmath.sin(A0), mpmath.cos(A0)
    dn0 = mpmath.sqrt(1 - m * sn0**2)
    err = max(abs(P * cn0 - wr[0]), abs(Q * sn0 - wr[1]), abs(S * dn0 - wr[2])) / mpmath.sqrt(L2 / Im[z] ** 2)
    if err > mp(10) ** -25:
        raise DerivationError(f"elliptic solution does not reproduce ω(0): relative error {mpmath.nstr(err, 3)}")
    separatrix = m1 == 0
    if separatrix:
        period, T = None, float("inf")
    else:
        K = mpmath.ellipk(m)
        period, T = DD.of(4 * K), float(4 * K / lam)
    return FreeTopSolution(
        kind="separatrix" if separatrix else "elliptic", m=float(m), m1=float(m1), polhode_period=T,
        _perm=perm, _amp=(float(P), float(Q), float(S)), _lam=DD.of(lam), _u0=DD.of(u0), _period=period,
        _I_rel=(float(Ix), float(Iy), float(Iz)),
        _mp=dict(args=args, m=m, m1=m1, lam=lam, u0=u0, A0=A0), **common)


def _orientation_setup(sol: FreeTopSolution) -> _Orientation:
    """The precession constants and the L frame (40 digits), for the first R(t) request."""
    v = sol._mp
    args, m, lam, u0, A0 = v["args"], v["m"], v["lam"], v["u0"], v["A0"]
    f = _compiled_precession()
    Lm = mpmath.sqrt(args[4])
    c1, c2, n = f(*args, Lm)
    n = n if m != 0 else mpmath.mpf(0)
    # Π(n; A0 | m): mpmath's ellippi is quasi-periodic in φ and handles m = 1 inside (-π/2, π/2)
    pi_u0 = mpmath.ellippi(n, A0, m)
    dphi = rate_inf = None
    arctan_u0 = 0.0
    if sol._period is None:
        rate_inf = DD.of(c1 + c2 / (1 - n))
        arctan_u0 = float(mpmath.atan(mpmath.sqrt(-n) * mpmath.tanh(u0)))
    else:
        K = mpmath.ellipk(m)
        dphi = DD.of(c1 * 4 * K / lam + c2 / lam * 4 * complete_pi_mp(n, v["m1"]))
    # The L frame and φ'0: L in space components is R0ᵀ L_body.
    L_body = np.array(sol.moments) * np.array(sol.omega0)
    S_frame = _l_frame(sol.R0.T @ L_body)
    ang0 = euler_angles_from_matrix(sol._perm @ sol.R0 @ S_frame.T)
    return _Orientation(S=S_frame, phi0=float(ang0[0]), c1_over_lam=float(c1 / lam), c2_over_lam=float(c2 / lam),
                        n=float(n), pi_u0=float(pi_u0), dphi=dphi, rate_inf=rate_inf, arctan_u0=arctan_u0)
