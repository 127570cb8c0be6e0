"""Continuous Euler angles along an integration, from the integrator's own steps (not from its samples).

The unit quaternion of A = Rᵀ in the chapter's Euler angles (3.54) is
(:func:`~mechderive.kinematics.conversions.euler_to_quaternion`)

    q = (c cos σ, s cos δ, s sin δ, c sin σ),   σ = (φ + ψ)/2,  δ = (φ - ψ)/2,
    s = sin(θ/2), c = cos(θ/2),

so σ is the argument of z_A = q0 + i q3 and δ that of z_B = q1 + i q2.  φ = σ + δ and ψ = σ - δ
are continuous functions of time as long as z_A and z_B stay away from 0 — z_B vanishes at the
pole θ = 0 (only φ + ψ is defined there), z_A at the bottom θ = π (only φ - ψ).  Unwrapping the
*output samples* cannot count the turns made between them (a top spinning at 20 rad/s sampled
every second turns ~3 times in between); this module follows the arguments of z_A and z_B along
every accepted step of the integrator instead, refining a step with its dense output where needed.

Refinement.  On a piece [x_a, x_b] of a step of length h, with |ż| ≤ v (v: 1.5 × the largest
|ż| among the step's stages), the path of z has length L ≤ v h (x_b - x_a) and stays at
|z| ≥ ρ = (|z_a| + |z_b| - L)/2 from 0, so its argument changes by at most L/ρ.  The change is
therefore the wrapped difference d ∈ [-π, π] of the end arguments whenever ρ > 0 and
L < (2π - |d|) ρ; otherwise the piece is halved (dense output), at most :data:`MAX_DEPTH` times,
and at most :data:`MAX_REFINEMENTS` times in one step.

Passages.  Near the pole φ and ψ each turn by about ±π in a short time, the sign depending on
the side on which the apex passes; an error in q of size e can change the side only if the path
comes within e of z = 0.  The tracker keeps ``closest``, the smallest ρ met on any piece (a lower
bound of min |z_A| = min cos(θ/2) and min |z_B| = min sin(θ/2) along the path), and ``near``, how
many times the path entered |z| < 10⁻ᵏ, k = 0 … 16; a piece that could not be resolved (at the
depth limit, or touching z = 0 exactly) counts as ρ = 0.  :func:`output_error_estimates` reads
``near`` at the error of q: each passage closer than that adds 2π to the error of φ and ψ.
A path that *starts* at z = 0 (θ0 = 0 or π) leaves it along ż(0): the argument there is taken as
that of ż(0) (the limit t → 0⁺: only φ ± ψ was given), and its first step is not counted as a
passage.  A path that stays at z = 0 exactly (the sleeping top) keeps the given argument.

The same algorithm is compiled into the C stepper (:mod:`.dop853_c`); :class:`HalfAngleTracker`
is its Python twin, driven by SciPy's DOP853 in :mod:`.dop853`; :class:`SampleTracker` applies it
to fixed-step integrators (the splittings), with a cubic Hermite interpolant as dense output.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np

__all__ = ["HalfAngleTracker", "SampleTracker", "MAX_DEPTH", "MAX_REFINEMENTS", "SPEED_MARGIN", "DECADES", "DECADE_THRESHOLDS",
           "PASSAGE_MARGIN", "CHUNK", "follow_fixed_steps",
           "euler_angles_from_half_angles", "initial_half_angles", "half_angles_of_quaternion", "sleeping_split",
           "rotation_angle_between", "passages_within", "output_error_estimates"]

#: At most this many halvings of a step (2⁻⁴⁸ of a step is below the resolution of t).
MAX_DEPTH = 48
#: At most this many halvings in one step (a few dozen are the most the tests' motions need, near a
#: pole): a step that would need more — a path whose length bound is infinite or NaN (a state beyond
#: the floating-point range), or a spin of ~10²⁰ turns per step — leaves the rest of its pieces
#: unresolved (counted as passages through z = 0), in bounded time instead of up to 2⁴⁸ halvings.
MAX_REFINEMENTS = 1 << 12
#: The bound of |ż| on a step: this factor times the largest |ż| among the step's stages.
SPEED_MARGIN = 1.5
#: Approaches to z = 0 are counted below each of the thresholds 10⁰, 10⁻¹, …, 10⁻¹⁶.
DECADES = 17

_EPS = float(np.finfo(float).eps)
_TWO_PI = 2.0 * math.pi
#: The thresholds 10⁻ᵏ (printed exactly into the C twin).
DECADE_THRESHOLDS = 10.0 ** -np.arange(DECADES)
_ASCENDING = DECADE_THRESHOLDS[::-1].copy()


def _wrap(x: float) -> float:
    """x reduced to [-π, π]."""
    return x - _TWO_PI * round(x / _TWO_PI)


def _pairs(y: Sequence[float], qoff: int) -> tuple[tuple[float, float], tuple[float, float]]:
    return (float(y[qoff]), float(y[qoff + 3])), (float(y[qoff + 1]), float(y[qoff + 2]))


def _below(y: float) -> bool:
    """Below the real axis as atan2 sees it: atan2(-0.0, x < 0) = -π."""
    return math.copysign(1.0, y) < 0.0


def _crossing(za: Sequence[float], zb: Sequence[float]) -> float:
    """2π k that keeps atan2(z) + 2π k continuous along the chord from za to zb (its negative-axis crossing).

    The chord meets y = 0 at x = (za × zb)/(y_b - y_a), negative iff the cross product and y_b - y_a
    have opposite signs; crossing it downwards atan2 jumps by -2π, upwards by +2π.
    """
    below_a, below_b = _below(za[1]), _below(zb[1])
    if below_a == below_b:
        return 0.0
    cross = za[0] * zb[1] - za[1] * zb[0]
    if not below_a and cross > 0.0:
        return _TWO_PI
    if below_a and cross < 0.0:
        return -_TWO_PI
    return 0.0


class HalfAngleTracker:
    """Continuous arguments of z_A = q0 + i q3 and z_B = q1 + i q2 along accepted steps.

    ``qoff`` is the index of q0 in the state; ``args0`` the arguments (σ0, δ0) at the start (any
    representatives of the arguments of z(0), except where z(0) = 0).  The continuous argument is
    kept as atan2(z) + ``offset`` (``offset`` − its start a multiple of 2π: no rounding accumulates
    over the steps), or ``held`` while z = 0 exactly.
    """

    def __init__(self, y0: Sequence[float], f0: Sequence[float], qoff: int, args0: Sequence[float]) -> None:
        self.qoff = qoff
        self.offset = [0.0, 0.0]
        self.held = [float(args0[0]), float(args0[1])]
        self.closest = [math.inf, math.inf]
        self.near = np.zeros((2, DECADES), dtype=np.int64)
        self._depth = [0, 0]  # the path is below 10⁻ᵏ for k < depth
        self.departing = [False, False]
        for p, (z, zdot) in enumerate(zip(_pairs(y0, qoff), _pairs(f0, qoff))):
            if z[0] * z[0] + z[1] * z[1] != 0.0:
                self.offset[p] = self.held[p] - math.atan2(z[1], z[0])
            elif zdot != (0.0, 0.0):  # leaving z = 0 along ż(0): its direction, nearest the given argument
                self.held[p] += _wrap(math.atan2(zdot[1], zdot[0]) - self.held[p])
                self.departing[p] = True
        self.speed = [0.0, 0.0]
        self._h = 0.0
        self._dense: Callable[[float], np.ndarray] | None = None

    def args_at(self, y: Sequence[float]) -> tuple[float, float]:
        """(σ, δ) at the state y, the current point of the tracking."""
        out = []
        for p, z in enumerate(_pairs(y, self.qoff)):
            zero = z[0] * z[0] + z[1] * z[1] == 0.0
            out.append(self.held[p] if zero else math.atan2(z[1], z[0]) + self.offset[p])
        return out[0], out[1]

    def step(self, y_old: Sequence[float], h: float, stages: np.ndarray | None,
             points: Sequence[tuple[float, Sequence[float]]], dense: Callable[[float], np.ndarray], *,
             speed: Sequence[float] | None = None) -> list[tuple[float, float]]:
        """Advance over one accepted step of length ``h``.

        ``stages``: the step's stage derivatives (rows); ``points``: (x, y(x)) in increasing x ∈ (0, 1],
        the last at x = 1 (the step's end); ``dense(x)``: y at x ∈ (0, 1) (called only when a piece
        must be refined); ``speed``: bounds of |ż_A|, |ż_B| on the step, in place of the one from
        ``stages``.  Returns the arguments (σ, δ) at each point.
        """
        o = self.qoff
        if speed is not None:
            self.speed = [float(speed[0]), float(speed[1])]
        else:  # plain floats: for 13 rows NumPy's per-call cost would dominate
            rows = stages[:, o:o + 4].tolist()
            self.speed = [SPEED_MARGIN * math.sqrt(max(r[0] * r[0] + r[3] * r[3] for r in rows)),
                          SPEED_MARGIN * math.sqrt(max(r[1] * r[1] + r[2] * r[2] for r in rows))]
        self._h, self._dense = h, dense
        self._refinements = MAX_REFINEMENTS
        out = []
        xa, za = 0.0, _pairs(y_old, o)
        for xb, yb in points:
            zb = _pairs(yb, o)
            self._piece(xa, za, xb, zb, 0)
            out.append(self.args_at(yb))
            xa, za = xb, zb
        self.departing = [False, False]
        return out

    def _piece(self, xa: float, za: tuple, xb: float, zb: tuple, depth: int) -> None:
        # touch: 0 ordinary, 1 leaving z = 0 exactly, 2 arriving at z = 0 exactly, 3 at z = 0 throughout
        rho, ok, touch = [0.0, 0.0], [True, True], [0, 0]
        halving_helps = True  # not with an infinite or NaN length: half of it is as long
        for p in (0, 1):
            # as the C twin: a |z| below 1e-154 squares to 0 and counts as z = 0
            ra2 = za[p][0] * za[p][0] + za[p][1] * za[p][1]
            rb2 = zb[p][0] * zb[p][0] + zb[p][1] * zb[p][1]
            if ra2 == 0.0 or rb2 == 0.0:
                touch[p] = 3 if ra2 == rb2 else (1 if ra2 == 0.0 else 2)
                ok[p] = touch[p] == 3
            else:
                length = self.speed[p] * self._h * (xb - xa)
                halving_helps = halving_helps and math.isfinite(length)
                rho[p] = 0.5 * (math.sqrt(ra2) + math.sqrt(rb2) - length)
                # the path stays at |z| ≥ rho, so turns by ≤ length/rho < π: the chord's turn
                ok[p] = rho[p] > 0.0 and length < math.pi * rho[p]
        if not (ok[0] and ok[1]) and depth < MAX_DEPTH and halving_helps and self._refinements > 0:
            self._refinements -= 1
            xm = 0.5 * (xa + xb)
            zm = _pairs(self._dense(xm), self.qoff)
            self._piece(xa, za, xm, zm, depth + 1)
            self._piece(xm, zm, xb, zb, depth + 1)
            return
        for p in (0, 1):
            if touch[p] == 1:  # leaving z = 0: the turn from the held argument, wrapped
                a = math.atan2(zb[p][1], zb[p][0])
                self.offset[p] = self.held[p] + _wrap(a - self.held[p]) - a
            elif touch[p] == 2:
                self.held[p] = math.atan2(za[p][1], za[p][0]) + self.offset[p]
            elif touch[p] == 0:
                self.offset[p] += _crossing(za[p], zb[p])
            if touch[p] == 3 or (touch[p] == 1 and self.departing[p]):
                pass  # held at z = 0, or leaving it at the start along ż(0): not a passage
            elif not self.departing[p]:
                # not ok: unresolved (MAX_DEPTH, MAX_REFINEMENTS), or touching z = 0: as if through z = 0
                self._approach(p, rho[p] if ok[p] else 0.0)

    def _approach(self, p: int, rho: float) -> None:
        """Record a piece staying at |z| ≥ rho: ``closest``, and entries below each 10⁻ᵏ in ``near``."""
        self.closest[p] = min(self.closest[p], rho)
        d = self._depth[p]
        while d < DECADES and rho < DECADE_THRESHOLDS[d]:  # entering
            self.near[p][d] += 1
            d += 1
        while d > 0 and not rho < DECADE_THRESHOLDS[d - 1]:  # leaving
            d -= 1
        self._depth[p] = d


def initial_half_angles(phi: float, psi: float) -> tuple[float, float]:
    """(σ, δ) = ((φ + ψ)/2, (φ - ψ)/2)."""
    return 0.5 * (phi + psi), 0.5 * (phi - psi)


def half_angles_of_quaternion(q0: np.ndarray) -> tuple[np.ndarray, tuple[float, float]]:
    """(q0 with the sign of euler_to_quaternion(φ0, θ0, ψ0), (σ0, δ0)) for the Euler angles (3.54) of R(q0).

    The angles are those of :func:`~mechderive.kinematics.rotations.euler_angles_from_matrix`; q0 and
    -q0 are the same rotation, and the tracked arguments are those of the sign
    :func:`~mechderive.kinematics.conversions.euler_to_quaternion` gives.
    """
    from ..kinematics.conversions import euler_to_quaternion, quaternion_to_matrix
    from ..kinematics.rotations import euler_angles_from_matrix

    phi, theta, psi = (float(v) for v in euler_angles_from_matrix(quaternion_to_matrix(q0)))
    if float(np.dot(euler_to_quaternion(phi, theta, psi), q0)) < 0.0:
        q0 = -q0
    return q0, initial_half_angles(phi, psi)


def sleeping_split(q: np.ndarray, args: np.ndarray, rates: tuple[float, float]) -> np.ndarray:
    """(σ, δ) with the turning split between φ and ψ as the initial rates split it, where only their sum exists.

    A body that stays exactly at θ = 0 (q1 = q2 = 0 throughout: a sleeping top) turns by φ + ψ only:
    the tracker holds δ = (φ - ψ)/2 and φ, ψ would share the turning equally.  With the initial rates
    ``rates`` = (φ̇0, ψ̇0) (as a closed form or a scene file gives them: φ = φ0 + φ̇0 t, ψ = ψ0 + ψ̇0 t),
    δ - δ0 = κ (σ - σ0), κ = (φ̇0 - ψ̇0)/(φ̇0 + ψ̇0); at θ = π (q0 = q3 = 0 throughout) likewise
    σ - σ0 = κ' (δ - δ0), κ' = (φ̇0 + ψ̇0)/(φ̇0 - ψ̇0).  Elsewhere ``args`` unchanged.
    """
    phi_dot, psi_dot = rates
    out = args.copy()
    if not np.any(q[:, 1:3]) and phi_dot + psi_dot != 0.0:
        out[:, 1] = args[0, 1] + (phi_dot - psi_dot) / (phi_dot + psi_dot) * (args[:, 0] - args[0, 0])
    elif not np.any(q[:, [0, 3]]) and phi_dot - psi_dot != 0.0:
        out[:, 0] = args[0, 0] + (phi_dot + psi_dot) / (phi_dot - psi_dot) * (args[:, 1] - args[0, 1])
    return out


def euler_angles_from_half_angles(q: np.ndarray, args: np.ndarray) -> np.ndarray:
    """(N, 3) Euler angles (φ, θ, ψ) (3.54) from unit quaternions q (N, 4) and tracked (σ, δ) (N, 2).

    φ = σ + δ and ψ = σ - δ; θ = 2 atan2(|z_B|, |z_A|) ∈ [0, π], accurate at both poles.
    """
    theta = 2.0 * np.arctan2(np.hypot(q[:, 1], q[:, 2]), np.hypot(q[:, 0], q[:, 3]))
    sigma, delta = args[:, 0], args[:, 1]
    return np.stack([sigma + delta, theta, sigma - delta], axis=-1)


def rotation_angle_between(q: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
    """The angle (rad) of the relative rotation between unit quaternions, accurate for small angles."""
    dot = np.abs(np.sum(q * q_ref, axis=-1))
    cross = np.linalg.norm(q_ref[..., :1] * q[..., 1:] - q[..., :1] * q_ref[..., 1:]
                           - np.cross(q_ref[..., 1:], q[..., 1:]), axis=-1)
    return 2.0 * np.arctan2(cross, dot)


#: A passage closer to z = 0 than this many times the estimated error of q is not resolved.
PASSAGE_MARGIN = 10.0


def passages_within(near: np.ndarray, distance: float) -> int:
    """How many times the path came within ``distance`` of the pole or the bottom (|z_B| or |z_A|), from
    the counts ``near`` (2, :data:`DECADES`) of entries below 10⁻ᵏ, read at the smallest 10⁻ᵏ ≥ distance."""
    k = DECADES - 1 if distance <= 0.0 else int(np.clip(math.floor(-math.log10(distance)), 0, DECADES - 1))
    return int(near[0][k] + near[1][k])


def output_error_estimates(run: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None],
                           ref: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None],
                           factor: float, steps: int | None = 0) -> dict[str, Any]:
    """Estimated max_t errors of everything an integration outputs, from its distance to a reference run.

    ``run`` and ``ref`` are (ω (N, 3), unit q (N, 4), Euler angles (N, 3), ``near`` counts (2, DECADES)
    or None) at the same times; ``factor`` scales the distances (the rerun's or Richardson's).  Returns

    * ``omega``: max |ω - ω_ref| (rad/s);
    * ``rotation``: α (1 + α/2) with α the largest rotation angle between R and R_ref (rad) — it
      bounds every |ΔR_ij| (R' - R = R(E - 1), |(E - 1)_ij| ≤ sin α + 1 - cos α) and |Δq| ≤ α/2;
    * ``euler``: max |Δφ|, |Δθ|, |Δψ| (rad) plus 4 ulp of the largest angle (the continuous angles'
      own rounding); at least 2π n when the path came n times closer to the pole or the bottom than
      :data:`PASSAGE_MARGIN` × α: the side it passed on — hence φ and ψ, to ±2π each time — is then
      not determined by the integration (φ ± ψ and R are);
    * ``unresolved_passages``: that n.

    Each figure also carries a rounding floor of 4 √``steps`` ε (× max |ω|, × 1 rad, × the largest
    angle): the reference run is rounded like the run itself, so their distance (and Richardson's
    extrapolation of it) does not see the rounding accumulated over many steps — measured ~1e-12
    against the closed form where a splitting's distance said ~1e-13.  Rounding errors of the
    steps are unbiased, so they add as a random walk (√steps); 4 is the margin of that model,
    checked against the closed form in the tests.
    """
    w, q, ang, near = run
    w_ref, q_ref, ang_ref, near_ref = ref
    rounding = 4.0 * math.sqrt(float(steps or 0)) * _EPS
    w_err = float(np.max(np.abs(w - w_ref))) * factor + rounding * float(np.max(np.abs(w)))
    alpha = float(np.max(rotation_angle_between(q, q_ref))) * factor + rounding
    rot_err = alpha * (1.0 + alpha / 2.0)
    biggest = float(np.max(np.abs(ang[:, [0, 2]])))
    euler = (float(np.max(np.abs(ang - ang_ref))) * factor + 4.0 * float(np.spacing(biggest))
             + rounding * max(1.0, biggest))
    n = max([passages_within(c, PASSAGE_MARGIN * alpha) for c in (near, near_ref) if c is not None], default=0)
    if n:
        euler = max(euler, _TWO_PI * n)
    return dict(omega=w_err, rotation=rot_err, euler=euler, unresolved_passages=n)


class SampleTracker(HalfAngleTracker):
    """:class:`HalfAngleTracker` along the states of a fixed-step integrator, which has no dense output.

    The state is (L1, L2, L3, q0, …, q3) with ω = L / I.  Between two recorded states q(t) is taken
    as the cubic Hermite interpolant H of q and q̇ = ½ q ⊗ (0, ω) there (error O(h⁴ |q⁗|) — as small
    relative to |z| as the rotation per step is small: z_B near the pole turns with the spin, its
    size does not change the ratio); |ż| is bounded on the step by the triangle inequality on the
    coefficients of H' (× :data:`SPEED_MARGIN`).  Steps whose change is certain are summed at once;
    the others are halved as in :class:`HalfAngleTracker`, on the interpolant.
    """

    def __init__(self, y0: np.ndarray, inertia: np.ndarray, args0: Sequence[float]) -> None:
        y0 = np.asarray(y0, dtype=float)
        self.inertia = np.asarray(inertia, dtype=float)
        super().__init__(y0, np.concatenate([np.zeros(3), self._qdot(y0[None, :])[0]]), 3, args0)

    def _qdot(self, states: np.ndarray) -> np.ndarray:
        """q̇ = ½ q ⊗ (0, ω) (:func:`~mechderive.solvers.quaternion.quaternion_rate`, written out) per state."""
        w1, w2, w3 = (states[:, a] / self.inertia[a] for a in range(3))
        q0, q1, q2, q3 = (states[:, 3 + a] for a in range(4))
        return 0.5 * np.stack([-(q1 * w1 + q2 * w2 + q3 * w3), q0 * w1 + q2 * w3 - q3 * w2,
                               q0 * w2 + q3 * w1 - q1 * w3, q0 * w3 + q1 * w2 - q2 * w1], axis=1)

    def feed(self, states: np.ndarray, h: Any) -> np.ndarray:
        """Advance along ``states`` (M + 1, 7), consecutive states ``h`` (a number or M numbers) apart, the
        first one where the last chunk ended.  Returns (σ, δ) at every one of them, shape (M + 1, 2)."""
        h = np.broadcast_to(np.asarray(h, dtype=float), (len(states) - 1,))
        q = states[:, 3:]
        qdot = self._qdot(states)
        qa, qb = q[:-1], q[1:]
        da, db = qdot[:-1] * h[:, None], qdot[1:] * h[:, None]  # dq/dτ, τ = (t - t_a)/h
        # H'(τ) = da + (6 (qb - qa) - 4 da - 2 db) τ + (6 (qa - qb) + 3 da + 3 db) τ²
        c1, c2 = 6.0 * (qb - qa) - 4.0 * da - 2.0 * db, 6.0 * (qa - qb) + 3.0 * da + 3.0 * db
        jumps, rho, good, held, speed, r2s = [], [], np.ones(len(qa), dtype=bool), [], [], []
        for i, j in ((0, 3), (1, 2)):
            # |H'(τ)| ≤ |da| + |c1| τ + |c2| τ² on [0, 1], per pair: small where that pair moves little
            length = SPEED_MARGIN * (np.sqrt(da[:, i] ** 2 + da[:, j] ** 2) + np.sqrt(c1[:, i] ** 2 + c1[:, j] ** 2)
                                     + np.sqrt(c2[:, i] ** 2 + c2[:, j] ** 2))
            r2 = q[:, i] ** 2 + q[:, j] ** 2
            rp = 0.5 * (np.sqrt(r2[:-1]) + np.sqrt(r2[1:]) - length)
            hp = (r2[:-1] == 0.0) & (r2[1:] == 0.0)
            good &= hp | ((r2[:-1] != 0.0) & (r2[1:] != 0.0) & (rp > 0.0) & (length < np.pi * rp))
            below = np.signbit(q[:, j])
            cross = q[:-1, i] * q[1:, j] - q[:-1, j] * q[1:, i]
            down = ~below[:-1] & below[1:] & (cross > 0.0)  # atan2 jumps by -2π: the offset gains 2π
            up = below[:-1] & ~below[1:] & (cross < 0.0)
            jumps.append(_TWO_PI * (down.view(np.int8) - up.view(np.int8)))
            rho.append(rp)
            held.append(hp)
            speed.append(length / h)
            r2s.append(r2)
        if self.departing[0] or self.departing[1]:
            good[0] = False  # the first step, leaving z = 0: by the rule of HalfAngleTracker
        offset, held_arg = np.empty((len(q), 2)), np.empty((len(q), 2))
        offset[0], held_arg[0] = self.offset, self.held
        k = 0
        for bad in [*np.flatnonzero(~good), len(good)]:
            if bad > k:  # steps k .. bad - 1: every change certain
                for p in (0, 1):
                    self._approaches(p, rho[p][k:bad][~held[p][k:bad]])
                    offset[k + 1:bad + 1, p] = self.offset[p] + np.cumsum(jumps[p][k:bad])
                    held_arg[k + 1:bad + 1, p] = self.held[p]
                    self.offset[p] = float(offset[bad, p])
            if bad < len(good):
                dense = self._hermite(states[bad], qa[bad], qb[bad], da[bad], db[bad])
                self.step(states[bad], h[bad], None, [(1.0, states[bad + 1])], dense,
                          speed=(speed[0][bad], speed[1][bad]))
                offset[bad + 1], held_arg[bad + 1] = self.offset, self.held
            k = bad + 1
        out = np.empty((len(q), 2))
        for p, (i, j) in enumerate(((0, 3), (1, 2))):
            out[:, p] = np.where(r2s[p] == 0.0, held_arg[:, p], np.arctan2(q[:, j], q[:, i]) + offset[:, p])
        return out

    @staticmethod
    def _hermite(y_a: np.ndarray, qa: np.ndarray, qb: np.ndarray, da: np.ndarray,
                 db: np.ndarray) -> Callable[[float], np.ndarray]:
        """x ↦ a state holding the cubic Hermite interpolant of q at x ∈ (0, 1) (ω unused)."""
        def at(x: float) -> np.ndarray:
            x2, x3 = x * x, x * x * x
            y = y_a.copy()
            y[3:] = (2 * x3 - 3 * x2 + 1) * qa + (x3 - 2 * x2 + x) * da + (3 * x2 - 2 * x3) * qb + (x3 - x2) * db
            return y
        return at

    def _approaches(self, p: int, rho: np.ndarray) -> None:
        """:meth:`_approach` for many consecutive pieces at once."""
        if rho.size == 0:
            return
        self.closest[p] = min(self.closest[p], float(np.min(rho)))
        # depth: how many thresholds (decreasing) lie above rho; each rise enters decades before .. depth - 1
        if rho.min() >= DECADE_THRESHOLDS[1]:  # the common case, far from both poles: below 1 at most
            depth = (rho < 1.0).view(np.int8).astype(np.intp)
        else:
            depth = DECADES - np.searchsorted(_ASCENDING, rho, side="right")
        before = np.concatenate([[self._depth[p]], depth[:-1]])
        rise = depth > before
        if np.any(rise):
            marks = np.bincount(before[rise], minlength=DECADES + 1) - np.bincount(depth[rise], minlength=DECADES + 1)
            self.near[p] += np.cumsum(marks)[:DECADES]
        self._depth[p] = int(depth[-1])


#: A fixed-step integration is recorded and tracked this many steps at a time (memory: 56 bytes a step).
CHUNK = 1 << 16


def follow_fixed_steps(y0: np.ndarray, inertia: np.ndarray, args0: Sequence[float],
                       intervals: Sequence[tuple[int, float]],
                       advance: Callable[[np.ndarray, list[tuple[int, float]]], np.ndarray],
                       ) -> tuple[np.ndarray, np.ndarray, SampleTracker]:
    """Run a fixed-step integrator over output ``intervals`` ((steps, step size) each) and track (σ, δ).

    ``advance(y, pieces)`` runs the pieces ((steps, step size) each) from the state y and returns the
    state after every step, row 0 y (:meth:`.kick_drift_c.CompiledSplitting.propagate_recorded`).
    Pieces are batched up to :data:`CHUNK` steps (an interval longer than that is cut, which only
    moves the chaining of the steps at the cut).  Returns (states at the interval ends (len(intervals), 7),
    (σ, δ) at the start and the interval ends (len(intervals) + 1, 2), the tracker).
    """
    tracker = SampleTracker(y0, inertia, args0)
    pieces = []  # (steps, step size, whether it ends an output interval)
    for n, h in intervals:
        while n > CHUNK:
            pieces.append((CHUNK, h, False))
            n -= CHUNK
        pieces.append((n, h, True))
    y = np.asarray(y0, dtype=float)
    ends, args = [], [tracker.args_at(y)]
    batch: list[tuple[int, float, bool]] = []

    def flush() -> None:
        nonlocal y
        states = advance(y, [(n, h) for n, h, _ in batch])
        tracked = tracker.feed(states, np.repeat([h for _, h, _ in batch], [n for n, _, _ in batch]))
        rows = np.cumsum([n for n, _, _ in batch])
        for row, (_, _, last) in zip(rows, batch):
            if last:
                ends.append(states[row])
                args.append(tracked[row])
        y = states[-1]
        batch.clear()

    total = 0
    for piece in pieces:
        if batch and total + piece[0] > CHUNK:
            flush()
            total = 0
        batch.append(piece)
        total += piece[0]
    if batch:
        flush()
    return np.array(ends), np.array(args), tracker
