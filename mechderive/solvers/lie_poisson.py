"""Explicit Lie–Poisson splitting of the free rigid body (McLachlan 1993; Touma & Wisdom 1994).

The free body's Hamiltonian in body angular momentum L_a = I_a ω_a (3.28) is

    H = L1²/(2 I1) + L2²/(2 I2) + L3²/(2 I3)            (3.46 with L_a = I_a ω_a)

and Euler's equations (3.33) are the Lie–Poisson equations L̇ = L × ∇H = L × ω.
Each piece H_a = L_a²/(2 I_a) alone generates ω = (L_a / I_a) e_a: a uniform
rotation about the *fixed body axis* a by the angle θ = h L_a / I_a in time h,
which is exactly integrable:

* L_a is constant, and (L_b, L_c), with (a, b, c) a cyclic permutation of (1, 2, 3),
  turns by -θ: L_b ← L_b cos θ + L_c sin θ,  L_c ← L_c cos θ - L_b sin θ
  (solving L̇_b = L_c ω_a, L̇_c = -L_b ω_a);
* the orientation obeys Ȧ = A [ω]× (see :mod:`mechderive.solvers.quaternion`) with
  constant ω, so A ← A exp(θ [e_a]×) exactly, i.e. q ← q ⊗ (cos θ/2, sin θ/2 e_a):
  q0 ← c q0 - s q_a,  q_a ← c q_a + s q0,  q_b ← c q_b + s q_c,  q_c ← c q_c - s q_b
  with c, s = cos θ/2, sin θ/2.

Every sub-flow is an exact flow of a Hamiltonian piece on the coadjoint orbit
|L| = const, so the composition is a Poisson (symplectic on the sphere) map: |L| is
kept to rounding, the space angular momentum A L too (each sub-flow turns L by -θ
and A by +θ about the same axis), and the energy error stays bounded — it
oscillates without drift over exponentially long times (backward error analysis).
Strang composition φ1(h/2) φ2(h/2) φ3(h) φ2(h/2) φ1(h/2) gives order 2; the weights of
:mod:`mechderive.solvers.composition` raise it to 4 and 6.

Two kernels: :func:`propagate` (one body, pure-Python floats: for a single
trajectory NumPy's per-call overhead would dominate) and :func:`propagate_ensemble`
(M bodies at once, NumPy arrays of shape (M,), processed in cache-sized chunks).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..errors import DerivationError
from .composition import merged_sequence
from .limits import nonfinite_state

__all__ = ["step_schedule", "propagate", "propagate_ensemble", "subflows_per_step"]

_CYCLIC = ((0, 1, 2), (1, 2, 0), (2, 0, 1))  # (a, b, c) for each body axis a (0-based)


def step_schedule(weights: Sequence[float]) -> tuple[list[tuple[int, float]], list[tuple[int, float]], float]:
    """The merged sub-flows of one composed step as (head coefficient, body, tail coefficient).

    One step is φ_axis0(head) · body · φ_axis0(tail) in application order, with
    head = tail; consecutive steps apply φ_axis0(tail + head) between their bodies.
    Coefficients are fractions of the step h.

    >>> step_schedule((1.0,))
    (0.5, [(1, 0.5), (2, 1.0), (1, 0.5)], 0.5)
    """
    seq = merged_sequence(tuple(weights), 3)
    (a0, head), (a1, tail) = seq[0], seq[-1]
    if a0 != 0 or a1 != 0:  # pragma: no cover - guaranteed by merged_sequence
        raise DerivationError("expected the composed step to start and end with axis 0")
    return head, seq[1:-1], tail  # type: ignore[return-value]


def subflows_per_step(weights: Sequence[float]) -> int:
    """Exact sub-flows per step when steps are chained (the junction flows merged).

    >>> subflows_per_step((1.0,))
    4
    """
    _, body, _ = step_schedule(weights)
    return len(body) + 1


def propagate(L: list[float], q: list[float], inertia: Sequence[float], step: float, n_steps: int,
              weights: Sequence[float], record: list | None = None, *,
              t0: float = 0.0) -> tuple[list[float], list[float]]:
    """Advance one body by ``n_steps`` composed steps of size ``step``; returns new (L, q) lists.

    ``L``: body angular momentum (3 floats); ``q``: quaternion of A = Rᵀ (4 floats,
    scalar first; not renormalised — its norm changes only by rounding).  ``record``: a list to
    which (L1, L2, L3, q0, q1, q2, q3) is appended between consecutive steps (n_steps - 1 entries;
    each is the step's end followed by the next step's first sub-flow, which the chaining merges).
    An infinite L (``math.cos(inf)``) raises :class:`~mechderive.errors.IntegrationError` naming the time
    (``t0``: the time of ``L``, ``q``); a NaN passes through silently, for the caller to check.
    """
    if n_steps <= 0:
        return list(L), list(q)
    head, body, tail = step_schedule(weights)
    inv = [step / float(i) for i in inertia]
    # (axis, half-angle per unit L_axis) for every sub-flow
    body_k = [(a, 0.5 * c * inv[a]) for a, c in body]
    head_k = (0, 0.5 * head * inv[0])
    junction = [(0, 0.5 * (head + tail) * inv[0])]
    tail_k = (0, 0.5 * tail * inv[0])
    loop = body_k + junction
    last = body_k + [tail_k]
    L1, L2, L3 = (float(x) for x in L)
    q0, q1, q2, q3 = (float(x) for x in q)
    cos, sin = math.cos, math.sin

    def run(flows: list[tuple[int, float]]) -> None:
        nonlocal L1, L2, L3, q0, q1, q2, q3
        for a, k in flows:
            if a == 0:
                h = k * L1
                c, s = cos(h), sin(h)
                vs, ss = 2.0 * s * s, 2.0 * s * c
                L2, L3 = L2 + (L3 * ss - L2 * vs), L3 - (L2 * ss + L3 * vs)
                q0, q1, q2, q3 = c * q0 - s * q1, c * q1 + s * q0, c * q2 + s * q3, c * q3 - s * q2
            elif a == 1:
                h = k * L2
                c, s = cos(h), sin(h)
                vs, ss = 2.0 * s * s, 2.0 * s * c
                L3, L1 = L3 + (L1 * ss - L3 * vs), L1 - (L3 * ss + L1 * vs)
                q0, q2, q3, q1 = c * q0 - s * q2, c * q2 + s * q0, c * q3 + s * q1, c * q1 - s * q3
            else:
                h = k * L3
                c, s = cos(h), sin(h)
                vs, ss = 2.0 * s * s, 2.0 * s * c
                L1, L2 = L1 + (L2 * ss - L1 * vs), L2 - (L1 * ss + L2 * vs)
                q0, q3, q1, q2 = c * q0 - s * q3, c * q3 + s * q0, c * q1 + s * q2, c * q2 - s * q1

    done = 0
    try:
        run([head_k])
        if record is None:
            for done in range(n_steps - 1):
                run(loop)
        else:
            for done in range(n_steps - 1):
                run(loop)
                record.append((L1, L2, L3, q0, q1, q2, q3))
        done = n_steps - 1
        run(last)
    except (ArithmeticError, ValueError) as exc:  # math.cos(inf): "math domain error"
        raise nonfinite_state("the Lie–Poisson splitting", t=t0 + done * step, steps=done, cause=exc) from exc
    return [L1, L2, L3], [q0, q1, q2, q3]


def propagate_ensemble(L: np.ndarray, q: np.ndarray, inertia: np.ndarray, step: float, n_steps: int,
                       weights: Sequence[float], *, chunk: int = 4096) -> None:
    """Advance M bodies in place: ``L`` shape (3, M), ``q`` shape (4, M), ``inertia`` shape (3,) or (3, M).

    Members are processed in chunks of ``chunk`` so that the working set stays in cache.
    """
    if n_steps <= 0:
        return
    head, body, tail = step_schedule(weights)
    M = L.shape[1]
    inv = np.broadcast_to(step / np.asarray(inertia, dtype=float).reshape(3, -1), (3, M))
    loop = body + [(0, head + tail)]
    last = body + [(0, tail)]
    for lo in range(0, M, chunk):
        sl = slice(lo, min(M, lo + chunk))
        Lc, qc = L[:, sl].copy(), q[:, sl].copy()
        half = [0.5 * inv[a, sl] for a in range(3)]
        _apply(Lc, qc, half, [(0, head)])
        for _ in range(n_steps - 1):
            _apply(Lc, qc, half, loop)
        _apply(Lc, qc, half, last)
        L[:, sl], q[:, sl] = Lc, qc


def _apply(L: np.ndarray, q: np.ndarray, half: list[np.ndarray], flows: list[tuple[int, float]]) -> None:
    """Apply exact axis sub-flows to arrays in place (see the module docstring for the formulas)."""
    for a, coef in flows:
        _, b, c_ = _CYCLIC[a]
        h = L[a] * (coef * half[a])
        c, s = np.cos(h), np.sin(h)
        vs = 2.0 * s * s
        ss = 2.0 * s * c
        Lb, Lc = L[b], L[c_]
        dLb = Lc * ss - Lb * vs
        Lc -= Lb * ss + Lc * vs
        Lb += dLb
        q0, qa, qb, qc = q[0], q[1 + a], q[1 + b], q[1 + c_]
        q0_old, qb_old = q0.copy(), qb.copy()
        q0 *= c
        q0 -= s * qa
        qa *= c
        qa += s * q0_old
        qb *= c
        qb += s * qc
        qc *= c
        qc -= s * qb_old
