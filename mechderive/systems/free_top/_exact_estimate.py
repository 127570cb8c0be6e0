"""A measured error estimate for the free top's closed form (private; see ``FreeTopSolution.error_estimate``).

Nothing here is a constant: every term is a residual computed on the run, at the very
values that were output (the evaluations at the sample times are re-used), and converted
to an error in the output — ω relative to |ω|, R entries absolute (radians).

ω (section 3.4, Euler's equations (3.33)):

* **initial value**: |ω(0) - ω0| / |ω0|, the formula evaluated at t = 0;
* **Euler's equations** at the samples, with the analytic derivative of the ansatz
  (sn' = cn dn, cn' = -sn dn, dn' = -m sn cn): a residual ρ (rad/s²) is a rate error, so it is
  counted as ρ/|ω| · (|t|max + 1/ν) — a phase drift growing with time, ν the fastest rate;
* **conservation** of 2T and L² at the samples (relative), which the Jacobi values satisfy only
  if they lie on the right polhode with the right parameter m;
* **the period** used to reduce the phase against an independent computation of K(m)
  (AGM in double-double, or ln(4/k') for 1 - m < 1e-34), times the number of quarter periods
  — a wrong period would shift the phase by that much per quarter.

R (sections 3.5–3.6, (3.54), (3.58)):

* **initial value**: max |R(0) - R0|;
* **conservation of L in space** at the samples: |R(t)ᵀ L_body(t) - R0ᵀ L_body(0)| / |L|,
  which checks θ', ψ', the L frame and the relabelling;
* **the precession angle**: φ'(b) - φ'(a) from the formula against Gauss–Legendre quadrature
  of the physical rate φ̇ = |L|(I_x ω_x² + I_y ω_y²)/(I_x² ω_x² + I_y² ω_y²) (solved from (3.58))
  over one polhode period (or the whole run if shorter) at the start and at the end of the
  run; a mismatch δ over a span τ is counted as δ·(1 + |t|max/τ) (a rate error);
* plus the ω estimate, since θ', ψ' and the phase of φ' come from ω.

The extra points (t = 0 unless it is a sample, the quadrature nodes — about 12 per unit of
phase over half a polhode period, fixed by the motion, not by the number of samples) are
evaluated in one call; the samples themselves are re-used from the evaluation being checked.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ...errors import InvalidInputError

if TYPE_CHECKING:
    from .exact import FreeTopSolution

_QUANTITIES = ("omega", "R", "euler_angles")
_GL_NODES = 12  # per panel of width δ (the distance of the integrand's nearest pole): error ~ (2 + √5)^-24
_MAX_NODES = 2400  # the precession check is shortened rather than made to cost more than this


@functools.cache
def _gauss_legendre() -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(_GL_NODES)


def error_estimate(sol: "FreeTopSolution", t: Any, quantities: Sequence[str]) -> float:
    """The largest requested estimate: ω relative to |ω0|, R absolute."""
    if isinstance(quantities, str):
        quantities = (quantities,)
    bad = [q for q in quantities if q not in _QUANTITIES]
    if bad or not quantities:
        raise InvalidInputError(f"expected quantities among {_QUANTITIES}, got {tuple(quantities)!r}")
    t = sol._times(t)
    if "euler_angles" in quantities:
        rest = tuple(q for q in quantities if q != "euler_angles")
        e_R = error_estimate(sol, t, ("R",))
        return max(_euler_estimate(sol, t, e_R), error_estimate(sol, t, rest) if rest else 0.0)
    want_R = "R" in quantities
    if sol.kind == "steady":
        return _steady(sol, t) if want_R else 0.0
    J = sol._jacobi(t)
    # the extra points, in one evaluation: t = 0 (unless it is a sample), and for R the ends and
    # quadrature nodes of the precession check
    zero = np.flatnonzero(t.ravel() == 0.0)
    k = 0 if zero.size else 1
    probe = [np.zeros(k)]
    plan = _precession_plan(sol, t) if want_R else None
    if plan is not None:
        probe += [plan["ends"], plan["nodes"]]
    probe = np.concatenate(probe)
    P = sol._jacobi(probe, keep=False) if probe.size else None
    J0 = J.__class__(*(np.ravel(getattr(J, f))[zero[:1]] for f in ("q", "v", "sn", "cn", "dn", "s", "c", "d"))) \
        if zero.size else P[:1]
    e_omega = _omega_estimate(sol, t, J, J0)
    if not want_R:
        return float(e_omega)
    e_R = _rotation_estimate(sol, t, J, J0)
    if plan is not None:
        n_ends = plan["ends"].size
        e_R += _precession_estimate(sol, t, plan, P[k:k + n_ends], P[k + n_ends:])
    return float(max(e_omega if "omega" in quantities else 0.0, e_omega + e_R))


def _euler_estimate(sol: "FreeTopSolution", t: np.ndarray, e_R: float) -> float:
    """The Euler angles' error from R's: φ ± ψ are twice the arguments of z_A = q0 + i q3 and
    z_B = q1 + i q2 (|z_A| = cos θ/2, |z_B| = sin θ/2), whose errors are ≲ e_R/|z| — the conditioning
    of φ and ψ near θ = 0 and π, at every sample but t = 0 (R0's own angles); plus 2π for every
    passage of the tracked path closer to either than PASSAGE_MARGIN·e_R (the side it passed on is
    then not determined); plus the rounding of the angles themselves (4 ulp)."""
    from ...solvers.half_angles import DECADES, PASSAGE_MARGIN, passages_within

    kept = sol._cached("euler_angles", t)
    if kept is None:
        sol.euler_angles(t)
        kept = sol._cached("euler_angles", t)
    angles, tracking = kept
    angles = angles.reshape(-1, 3)
    later = t.ravel() != 0.0
    half = 0.5 * angles[later, 1]
    with np.errstate(divide="ignore"):
        cond = float(np.max(1.0 / np.abs(np.cos(half)) + 1.0 / np.abs(np.sin(half)), initial=0.0))
    biggest = float(np.max(np.abs(angles[:, [0, 2]]), initial=0.0))
    estimate = e_R * cond + 4.0 * float(np.spacing(biggest))
    if tracking is not None:
        near, start = tracking
        distance = PASSAGE_MARGIN * e_R
        # the start is among the counts wherever it lies below the decade passages_within reads
        decade = 10.0 ** -min(max(int(np.floor(-np.log10(distance))), 0), DECADES - 1) if distance > 0 else 0.0
        passages = passages_within(near, distance) - sum(z < decade for z in start)
        if passages > 0:
            estimate = max(estimate, 2 * np.pi * passages)
    return float(estimate)


def _steady(sol: "FreeTopSolution", t: np.ndarray) -> float:
    """ω is exact (the input, ω̇ = 0 decided exactly); R = exp(hat(ω) t) R0 with |ω|t reduced mod 2π in
    double-double: check R(0) = R0 and that ω̃ = Rᵀω stays constant (Ṙ = hat(ω)R), plus R's rounding."""
    w = np.array(sol.omega0)
    R = sol.rotation(t)
    R_at_0 = sol._rotation(np.zeros(1), keep=False)[0]
    scale = np.max(np.abs(w))
    drift = 0.0 if scale == 0 else float(np.max(np.abs(np.einsum("...ab,a->...b", R, w / scale)
                                                       - sol.R0.T @ (w / scale)), initial=0.0))
    return 4 * float(np.spacing(1.0)) + float(np.max(np.abs(R_at_0 - sol.R0))) + drift


def _omega_at(sol: "FreeTopSolution", J) -> np.ndarray:
    """ω at the Jacobi values J, divided by 2^e (the amplitudes' scale): never denormal."""
    (P, Q, S), _ = sol._amp_scaled
    return (np.stack([P * J.cn, Q * J.sn, S * J.dn], axis=-1)) @ sol._perm


def _omega_estimate(sol: "FreeTopSolution", t: np.ndarray, J, J0) -> float:
    # everything in units of 2^e, the amplitudes' power-of-two scale (exact, and never denormal),
    # and time in units of 2^-e s, so that Euler's equations keep their form (λ scales like ω)
    (P, Q, S), e = sol._amp_scaled
    w0s = np.ldexp(np.array(sol.omega0), -e)
    norm = np.linalg.norm(w0s)
    lam = np.ldexp(sol._lam.hi + sol._lam.lo, sol._lam.exp - e)
    Ix, Iy, Iz = np.array(sol._I_rel) / max(sol.moments)  # only ratios of moments enter
    m = 1.0 if (sol._tiny or sol._quarter is None) else sol.m
    # ω(0) - ω0.  Within 8 ulp of each component it is the rounding of the evaluation (the Jacobi
    # values and amplitudes: ≤ 5 ulp measured) and counts as such; beyond, it is evidence of a wrong
    # phase or constant: read as a phase error δu = |Δω|/|dω/du(0)| and propagated to the worst point
    # of the orbit, |dω/du| ≤ max(|P|, |Q|, m|S|) (|dω/du| > 0: sn, cn never vanish together).
    diff = np.abs(_omega_at(sol, J0)[0] - w0s)
    rounding = 8 * np.spacing(np.abs(w0s))
    excess = float(np.linalg.norm(np.maximum(diff - rounding, 0.0)))
    top = max(abs(P), abs(Q), m * abs(S))
    slope0 = float(np.hypot(np.hypot(P / top * J0.sn * J0.dn, Q / top * J0.cn * J0.dn),
                            m * S / top * J0.sn * J0.cn)[0]) if top > 0 else 0.0
    reach = 1.0 / slope0 if slope0 > 0 else np.inf
    e_init = float(np.linalg.norm(np.minimum(diff, rounding))) / norm
    if excess > 0:
        e_init += excess / norm * max(1.0, reach)
    wx, wy, wz = P * J.cn, Q * J.sn, S * J.dn
    # the rounding of the output itself: 4 ulp of its largest component (the Jacobi functions'
    # own error, measured against mpmath in the special module's tests, is within that)
    e_round = 4 * float(np.max(np.spacing(np.maximum(np.abs(wx), np.maximum(np.abs(wy), np.abs(wz)))),
                               initial=0.0)) / norm
    # Euler's equations (3.33) in the relabelled axes (a proper rotation keeps their cyclic form)
    rho = np.max(np.abs(np.stack([
        -lam * P * J.sn * J.dn - (Iy - Iz) / Ix * wy * wz,
        lam * Q * J.cn * J.dn - (Iz - Ix) / Iy * wz * wx,
        -lam * m * S * J.sn * J.cn - (Ix - Iy) / Iz * wx * wy])), initial=0.0)
    # conservation of 2T and L² (relative), against their values at t = 0 from the inputs
    moments = np.array(sol.moments) / max(sol.moments)
    two_T0 = float(np.sum(moments * w0s**2))
    L20 = float(np.sum((moments * w0s) ** 2))
    two_T = Ix * wx**2 + Iy * wy**2 + Iz * wz**2
    L2 = (Ix * wx) ** 2 + (Iy * wy) ** 2 + (Iz * wz) ** 2
    e_cons = float(np.max(np.abs(two_T - two_T0), initial=0.0)) / two_T0 + \
        float(np.max(np.abs(L2 - L20), initial=0.0)) / L20
    nu = max(lam, np.max(np.abs(w0s)) * max(Ix, Iy, Iz) / min(Ix, Iy, Iz))  # |ω̇|/|ω| ≤ this
    t_span = np.ldexp(float(np.max(np.abs(t), initial=0.0)), e)
    e_euler = rho / norm * (t_span + 1.0 / nu)
    e_period = _period_estimate(sol, J) * max(abs(P), abs(Q), abs(S)) / norm
    return e_round + e_init + e_cons + e_euler + e_period


def _period_estimate(sol: "FreeTopSolution", J) -> float:
    """|K used - K(m) by another algorithm| · (largest quarter count): the phase error a wrong period makes."""
    if sol._quarter is None:
        return 0.0
    K = sol._quarter.hi + sol._quarter.lo
    mant, ex = sol._kc
    if sol._tiny:
        # K = ln(4/k') + O(m1 ln m1) (DLMF 19.12.1): below 1e-34 the correction is below 1e-32
        independent = np.log(4.0) - np.log(mant) - ex * np.log(2.0)
    else:
        from ...special._parameter import quarter_period

        independent = float(quarter_period(np.asarray(sol.m1), np.asarray(0.0))[0])
    dK = max(abs(K - independent) - 4 * np.spacing(K), 0.0)  # within its own rounding it is no evidence
    return dK * float(np.max(np.abs(J.q), initial=0.0) + 1)


def _rotation_estimate(sol: "FreeTopSolution", t: np.ndarray, J, J0) -> float:
    R = sol.rotation(t)
    e_round = 4 * float(np.spacing(1.0))  # 4 ulp of an entry of size 1: the rounding of R itself
    e_R0 = float(np.max(np.abs(sol._rotation_at(J0, np.zeros(1))[0] - sol.R0)))
    I = np.array(sol.moments) / max(sol.moments)
    _, e = sol._amp_scaled
    L0 = sol.R0.T @ (I * np.ldexp(np.array(sol.omega0), -e))
    Ln = np.linalg.norm(L0)
    L_space = np.einsum("...ab,...a->...b", R, I * _omega_at(sol, J))
    e_L = float(np.max(np.abs(L_space - L0), initial=0.0)) / Ln
    # A rotation by δ changes R by δ[n]×R, whose largest entry is at least δ·√2/3 (its Frobenius
    # norm is δ√2); a direction error of L by δ changes some component by at least δ/√3.  So
    # each residual, read as a rotation, is at most 3 times its largest entry.
    return e_round + 3 * (e_R0 + e_L)


def _precession_plan(sol: "FreeTopSolution", t: np.ndarray) -> dict | None:
    """Where to compare φ' increments with quadrature: [a, a + τ] at the start and at the end of the run.

    τ is half a polhode period (the integrand's period: then the quadrature is one number for
    both intervals) or the whole run if shorter, cut down so that the nodes stay below a budget.
    """
    t_span = float(np.max(np.abs(t), initial=0.0))
    if t_span == 0.0:
        return None
    o = sol._orient
    lam = (sol._lam.hi + sol._lam.lo) * 2.0**sol._lam.exp
    # panel width in u: the nearest complex pole of 1/(1 - n sn²) is at least atan(1/√-n) from the real axis
    delta = np.arctan(1.0 / np.sqrt(-o.n)) if o.n < 0 else np.pi / 2
    half_period = 0.5 * sol.polhode_period if np.isfinite(sol.polhode_period) else np.inf
    tau = min(half_period, t_span)
    panels = int(np.ceil(lam * tau / delta))
    if panels * _GL_NODES > _MAX_NODES // 2:
        panels = _MAX_NODES // (2 * _GL_NODES)
        tau = panels * delta / lam
    sign = 1.0 if np.max(t) >= -np.min(t) else -1.0
    same = tau == half_period or tau == t_span
    # the end interval: over a whole number of half periods from 0 the integrand repeats, so the
    # same quadrature serves both ends
    starts = [0.0, sign * tau * np.floor((t_span - tau) / tau) if same else sign * (t_span - tau)]
    x, wts = _gauss_legendre()
    nodes, weights, edges = [], [], []
    for a in (starts[:1] if same else starts):
        e = np.linspace(a, a + sign * tau, panels + 1)
        mid, half = 0.5 * (e[1:] + e[:-1]), 0.5 * (e[1:] - e[:-1])
        nodes.append((mid[:, None] + half[:, None] * x[None, :]).ravel())
        weights.append((half[:, None] * wts[None, :]))
        edges.append(e)
    ends = np.concatenate([edges[0], edges[-1] + (starts[1] - starts[0] if same else 0.0)])
    return dict(t_span=t_span, tau=tau, panels=panels, ends=ends, nodes=np.concatenate(nodes), weights=weights)


def _precession_estimate(sol: "FreeTopSolution", t: np.ndarray, plan: dict, J_ends, J_nodes) -> float:
    """φ'(b) - φ'(a) of the formula, ν (b - a) + (c2/λ)(p(u_b) - p(u_a)), against ∫_a^b φ̇ dt.

    φ̇ = |L| (I_x ω_x² + I_y ω_y²)/(I_x² ω_x² + I_y² ω_y²) is solved from (3.58) with L along the
    L frame's third axis: it depends on ω alone.  The comparison is made at every panel edge of
    the quadrature (cumulative sums), at the start and at the end of the run.  Its mismatch over
    the whole span τ is a rate error and counts as δ (1 + |t|max/τ); what remains at the interior
    edges after removing that linear drift is a bounded error of φ' and counts once.
    """
    o = sol._orient
    Ix, Iy, _ = np.array(sol._I_rel) / max(sol.moments)
    a_hat, b_hat = sol._ab_unit  # (I_x P, I_y Q) / max: L_x, L_y up to a common factor
    Lx2, Ly2 = (a_hat * J_nodes.cn) ** 2, (b_hat * J_nodes.sn) ** 2
    rate = (sol.L_norm / max(sol.moments)) * (Lx2 / Ix + Ly2 / Iy) / (Lx2 + Ly2)
    per_run = plan["weights"][0].size
    cumulative = [np.concatenate([[0.0], np.cumsum(np.sum(w * rate[k * per_run:(k + 1) * per_run].reshape(w.shape),
                                                          axis=1))]) for k, w in enumerate(plan["weights"])]
    p = sol._periodic_pi(J_ends, o)
    nu = (o.nu.hi + o.nu.lo) * 2.0**o.nu.exp
    n_edges = plan["panels"] + 1
    drift = interior = 0.0
    for k in range(2):
        edges, pk = plan["ends"][k * n_edges:(k + 1) * n_edges], p[k * n_edges:(k + 1) * n_edges]
        formula = nu * (edges - edges[0]) + o.c2_over_lam * (pk - pk[0])
        d = formula - cumulative[min(k, len(cumulative) - 1)]
        d = (d + np.pi) % (2 * np.pi) - np.pi
        frac = np.linspace(0.0, 1.0, n_edges)
        drift = max(drift, abs(d[-1]))
        interior = max(interior, float(np.max(np.abs(d - frac * d[-1]))))
    return drift * (1.0 + plan["t_span"] / plan["tau"]) + interior
