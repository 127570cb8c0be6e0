"""The free top's per-motion quantities for N motions at once (a sweep's chunk), section 3.5.

:func:`summarize_batch` is :meth:`System.summarize_batch <mechderive.systems.base.System.summarize_batch>` of
the free top: the setup of the Jacobi solution ω = (P cn u, Q sn u, S dn u), u = λt + u0 (:mod:`.exact`), in
double precision and vectorised in NumPy/SciPy, for the quantities that are plain numbers (or a table of
numbers reproduced operation for operation):

* ``polhode_period`` = ``period`` = 4K(m)/λ and ``flip_interval`` = 2K(m)/λ (half of it), from the gaps
  G_k = 2T·I_k - L² = Σ_a I_a ω_a² (I_k - I_a) and the derived constants (:attr:`.exact_model.
  FreeTopExactModel.gap_constants`): λ² = G_x (I_y - I_z)/(I_x I_y I_z), m = -G_z (I_x - I_y)/(G_x (I_y - I_z)),
  1 - m = G_y (I_x - I_z)/(G_x (I_y - I_z));
* ``energy`` T (3.46) and ``angular_momentum`` |L| (3.47) at t = 0;
* ``stability`` per principal axis (3.44)-(3.45), from the same derived s(ω) the single path evaluates
  (:func:`.stability.linearised_eigenvalues`), evaluated on arrays;
* ``precession_rate`` of a symmetric top: Ω of (3.36) (the same derived expression) and φ̇ = |L|/I⊥ (3.60).

The single path (:func:`.summary.summarize`) computes the period from 40-digit constants, so it is the
correctly rounded 4K/λ.  Here each point carries a rounding *bound* of its own double evaluation, from
the condition numbers computed for that point (below); a point whose bound exceeds :data:`BOUND` — so that
it could differ from the single path by more than 1e-12 relative — is marked ``fallback``, as are points the
single path refuses or answers otherwise (a steady rotation, the separatrix, a symmetric top's flip, the
precession rate of a body that is not a symmetric top, a scene the planner would solve in units of its own
motion for a table of numbers).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
from scipy import special

from ...errors import InvalidInputError
from .. import scaling as _scaling
from ..base import BatchSummary

__all__ = ["summarize_batch", "BOUND"]

_EPS = float(np.finfo(float).eps)
#: The largest rounding bound (relative) a batched value may have.  The contract is agreement with the
#: single path to 1e-12 relative; the single path is correctly rounded (40-digit constants), so a bound of
#: 1e-13 leaves a factor of ten for what the bound assumes (SciPy's ellipk/ellipkm1 within a few ulp, which
#: the measured Carlson comparison checks point by point: it enters the decision too).
BOUND = 1e-13
#: Exponents within 2^±64 of one: the planner solves the scene as given; beyond, a table of rates
#: (``stability``) or a quantity without a power of two (``angular_momentum``) comes back None from the
#: single path, so such points fall back.  The planner's own constant, so the two cannot drift apart.
_COMFORTABLE = _scaling._COMFORTABLE
#: Scaled magnitudes below this (2^-900) are kept away from the subnormal range: every product of the
#: setup then rounds with a relative error of one unit, which the bounds below assume.
_TINY = 2.0**-900


def _refused(I: np.ndarray, w: np.ndarray, strict: bool) -> np.ndarray:
    """Points :meth:`FreeTop.check_parameters` / ``check_initial`` refuse: non-finite input, a moment ≤ 0 (or
    ≤ 1e-9 of the largest unless ``strict`` is False), a broken triangle inequality (3.22) when ``strict``."""
    finite = np.all(np.isfinite(I), axis=1) & np.all(np.isfinite(w), axis=1)
    Ic = np.where(finite[:, None], I, 1.0)
    bad = ~finite | np.any(Ic <= 0, axis=1)
    if strict:
        # check_principal_moments: tolerance 1e-9 × the largest moment (its default rtol)
        tol = 1e-9 * np.max(np.abs(Ic), axis=1)
        bad |= np.any(Ic <= tol[:, None], axis=1)
        with np.errstate(over="ignore"):
            for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
                bad |= Ic[:, a] + Ic[:, b] < Ic[:, c] - tol
    return bad


def _exponent(x: np.ndarray) -> np.ndarray:
    """frexp's exponent, 0 for 0 (:func:`mechderive.systems.scaling.exponent`)."""
    return np.where(x == 0, 0, np.frexp(x)[1])


def _comfortable(I: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Where the planner solves the scene as given (no conversion to units of its own motion), as
    :func:`.system._units` decides: the moments' unit, ω's largest exponent and each moment within 2^±64."""
    eI = _exponent(I)
    k = np.minimum(_exponent(np.max(I, axis=1)), _exponent(np.min(I, axis=1)) + 1021)
    ew = np.where(w != 0, _exponent(w), np.iinfo(np.int64).min)
    j = np.max(ew, axis=1)
    j = np.where(np.all(w == 0, axis=1), 0, j)
    return (np.abs(k) <= _COMFORTABLE) & (np.abs(j) <= _COMFORTABLE) & np.all(np.abs(eI) <= _COMFORTABLE, axis=1)


def _take(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
    return np.take_along_axis(x, idx[:, None], axis=1)[:, 0]


def _period(Is: np.ndarray, ws: np.ndarray) -> dict[str, np.ndarray]:
    """4K/λ in the scaled units, its rounding bound, the Carlson difference, and where it is not answered.

    ``Is`` (max in [1/2, 1)) and ``ws`` (max |ω| in [1/2, 1)) are the inputs scaled by exact powers of two.
    The bound of each step (u = eps/2, the unit roundoff; every operation rounds once, no subnormals):

    * a_j = I_j ω_j ω_j: 2u; a difference of two moments: u (one rounding of an exact difference); a term
      a_j (I_k - I_j): 4u.  G_x and G_z are sums of two terms of one sign (z is the axis ω circulates about,
      x the other extreme one): 5u relative.  G_y's two terms have opposite signs: 5u κ_y, with
      κ_y = (|t1| + |t2|)/|G_y| its condition number, which grows without bound at the separatrix (G_y = 0).
    * m: G_z, G_x, two differences and three operations: (5 + 5 + 1 + 1 + 3)u = 15u; 1 - m: (5κ_y + 10)u;
      λ² likewise 11u, so λ: 6u (half, plus the square root's rounding).
    * K = ellipk(m) where m ≤ 1/2, else ellipkm1(1 - m) (each argument the one known to its relative digits,
      as the single path chooses, :func:`._exact_setup.elliptic_constants`); its sensitivity is
      dlnK/dln m = (E - m' K)/(2 m' K), dlnK/dln m' = -(E - m' K)/(2 m K) (DLMF 19.4.1), at most ~0.5 and
      1/(2K): so near the separatrix K forgives most of 1 - m's error, and the threshold is on the product.
    * 4K/λ: one more rounding.  The algorithm's own error of K is *measured*: the difference of ellipk/ellipkm1
      and Carlson's R_F(0, 1 - m, 1) (DLMF 19.25.1), a different algorithm.
    """
    u = _EPS / 2
    order = np.argsort(Is, axis=1, kind="stable")  # lo, mid, hi as the single path's relabelling
    lo, mid, hi = order[:, 0], order[:, 1], order[:, 2]
    I_lo, I_mid, I_hi = _take(Is, lo), _take(Is, mid), _take(Is, hi)
    a = Is * ws * ws
    a_lo, a_mid, a_hi = _take(a, lo), _take(a, mid), _take(a, hi)
    d_ml, d_hl, d_hm = I_mid - I_lo, I_hi - I_lo, I_hi - I_mid  # all ≥ 0
    # G_k = Σ_a a_a (I_k - I_a) (the gaps of :func:`._exact_setup.gaps`), each term's sign known
    G_lo = -(a_mid * d_ml + a_hi * d_hl)
    G_hi = a_lo * d_hl + a_mid * d_hm
    t1, t2 = a_lo * d_ml, -(a_hi * d_hm)
    G_mid = t1 + t2
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = (np.abs(t1) + np.abs(t2)) / np.abs(G_mid)
    # the relabelling (:func:`._exact_setup.relabelling`): z the largest moment when G_y ≤ 0 (or a symmetric
    # body whose equal moments are the two smaller), else the smallest; x the other extreme
    z_hi = np.where(I_lo == I_mid, True, np.where(I_mid == I_hi, False, G_mid <= 0))
    Ix, Iz = np.where(z_hi, I_lo, I_hi), np.where(z_hi, I_hi, I_lo)
    Iy = I_mid
    Gx, Gz, Gy = np.where(z_hi, G_lo, G_hi), np.where(z_hi, G_hi, G_lo), G_mid
    with np.errstate(all="ignore"):
        lam2 = Gx * (Iy - Iz) / (Ix * Iy * Iz)
        lam = np.sqrt(lam2)
        m = -Gz * (Ix - Iy) / (Gx * (Iy - Iz))
        m1 = Gy * (Ix - Iz) / (Gx * (Iy - Iz))
        small_m = m <= 0.5
        mc = np.where(small_m, m, 0.5)
        m1c = np.where(small_m, 0.5, m1)
        K = np.where(small_m, special.ellipk(mc), special.ellipkm1(m1c))
        K_carlson = special.elliprf(0.0, np.where(small_m, 1.0 - mc, m1c), 1.0)
        E = special.ellipe(np.where(small_m, mc, 1.0 - m1c))
        mm1 = np.where(small_m, 1.0 - mc, m1c)  # m' = 1 - m where it is only used as a factor
        mm = np.where(small_m, mc, 1.0 - m1c)
        sens = np.where(small_m, (E - mm1 * K) / (2 * mm1 * K), (E - mm1 * K) / (2 * mm * K))
        dm = np.where(small_m, 15 * u, (5 * kappa + 10) * u)
        bound = np.abs(sens) * dm + 6 * u + 2 * u
        measured = np.abs(K - K_carlson) / K
        P = 4 * K / lam
    # not answered here: non-finite steps, subnormal-range values (the bounds assume single roundings),
    # the sign of G_y not certain (then even the relabelling may differ), or a bound above BOUND
    mags = np.concatenate([Is, a, np.stack([d_ml, d_hl, d_hm, np.abs(Gx), np.abs(Gz), np.abs(Gy), lam2, mm, mm1], 1)],
                          axis=1)
    tiny = np.any((mags != 0) & (mags < _TINY), axis=1)
    unsure = ~(5 * kappa * u < 0.5)  # includes G_y = 0 (κ = inf) and nan
    out_of_reach = tiny | unsure | ~np.isfinite(P) | ~(P > 0) | ~(bound + measured <= BOUND) | ~(m >= 0) \
        | ~(m1 >= 0)
    return {"P": P, "bound": bound, "measured": measured, "fallback": out_of_reach}


def _steady(I: np.ndarray, w: np.ndarray) -> np.ndarray:
    """ω × Iω = 0 exactly (:func:`._exact_setup.is_steady`): a steady rotation, no polhode period."""
    out = np.ones(len(I), dtype=bool)
    for b, c in ((0, 1), (1, 2), (2, 0)):
        out &= (I[:, b] == I[:, c]) | (w[:, b] == 0) | (w[:, c] == 0)
    return out


def _stability(I: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The per-axis table of :func:`.summary._stability`, {"axisN": {"kind": ..., rate}}, as an object array.

    The same derived s(ω) (``growth_squared``, compiled from the model) at ω = |ω| e_a, evaluated on arrays:
    elementwise, the very operations the single path does on one point.  The estimate is measured: the
    difference from the second derived form A_a/I_b of (3.44) (``axis_growth_rate_squared``), plus the
    rounding of the square root.
    """
    from .stability import _compiled

    n = len(I)
    spin = np.sqrt(w[:, 0] * w[:, 0] + w[:, 1] * w[:, 1] + w[:, 2] * w[:, 2])
    # the single path's np.linalg.norm of one vector is sqrt(dot(x, x)): the same sum (to an ulp's order)
    unit = np.where(spin == 0, 1.0, spin)
    growth = _compiled("growth_squared")
    other = _compiled("axis_growth_rate_squared")
    # the compiled vector function returns (N, 3) on arrays: one row per point
    second = np.broadcast_to(np.asarray(other(I[:, 0], I[:, 1], I[:, 2], unit), dtype=float), (n, 3)).T
    kinds, rates, errs = [], [], np.zeros(n)
    for a in range(3):
        W = [np.zeros(n), np.zeros(n), np.zeros(n)]
        W[a] = unit
        s = np.asarray(growth(I[:, 0], I[:, 1], I[:, 2], *W), dtype=float) * np.ones(n)
        neutral = (I[:, a] == I[:, (a + 1) % 3]) | (I[:, a] == I[:, (a + 2) % 3])
        rate = np.sqrt(np.abs(s))
        kinds.append(np.where(neutral, "neutral", np.where(s >= 0, "unstable", "stable")))
        rates.append(np.where(spin == 0, 0.0, rate))
        with np.errstate(invalid="ignore"):
            e = np.abs(np.sqrt(np.abs(second[a])) - rate) + _EPS * rate
        errs = np.maximum(errs, np.where(neutral | (spin == 0), 0.0, e))
    table = np.empty(n, dtype=object)
    for i in range(n):  # building the dicts (the output's form), not computing
        row = {}
        for a in range(3):
            kind = str(kinds[a][i])
            if kind == "neutral":
                row[f"axis{a + 1}"] = {"kind": "neutral"}
            else:
                key = "growth_rate" if kind == "unstable" else "frequency"
                row[f"axis{a + 1}"] = {"kind": kind, key: float(rates[a][i])}
        table[i] = row
    return table, errs


def _precession(I: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The symmetric top's {"axis", "body", "space"} of :func:`.summary._precession`, as an object array, its
    estimate, and where it applies (exactly two equal moments).

    ``body``: Ω of (3.35)-(3.36), the derived expression the single path compiles, evaluated on arrays
    (elementwise: the same operations).  ``space``: φ̇ = |L|/I⊥ (3.60).  The single path takes it from the
    closed form's precession per polhode period over the period — for a symmetric top m = 0 and the
    characteristic n = 0, so φ̇ = c1 + c2 is constant and equals |L|/I⊥ exactly; its two roundings (the
    advance and the period, each correctly rounded from 40 digits) and the quotient's put it within 3u of
    |L|/I⊥, and |L|/I⊥ here is within 3u (the sum of squares, the root, the quotient) — 6u in all, far
    below 1e-12.  For a steady rotation the single path uses |L|/I⊥ itself.  The estimate is measured: the
    difference of |L| by the root of the sum of squares and by nested hypot, plus the rounding of Ω's terms
    as the single path bounds it.
    """
    from .summary import symmetric_rate_function

    n = len(I)
    e01, e12, e02 = I[:, 0] == I[:, 1], I[:, 1] == I[:, 2], I[:, 0] == I[:, 2]
    symmetric = (e01.astype(int) + e12 + e02) == 1
    axis = np.where(e01, 2, np.where(e12, 0, 1))  # the distinct (symmetry) axis
    perp = np.where(e01 | e02, I[:, 0], I[:, 1])
    Ia, wa = _take(I, axis), _take(w, axis)
    body = np.ravel(np.asarray(symmetric_rate_function()(perp, Ia, wa), dtype=float)) * np.ones(n)
    Lv = I * w
    with np.errstate(all="ignore"):
        L = np.sqrt(Lv[:, 0] * Lv[:, 0] + Lv[:, 1] * Lv[:, 1] + Lv[:, 2] * Lv[:, 2])
        L2 = np.hypot(np.hypot(Lv[:, 0], Lv[:, 1]), Lv[:, 2])
        space = L / perp
        spread = np.abs(L - L2) / perp + 4 * _EPS * space
        err = np.maximum(4 * _EPS * np.abs(wa) * (perp + Ia) / perp + 2 * _EPS * np.abs(body),
                         spread + 2 * _EPS * np.abs(space))
    table = np.empty(n, dtype=object)
    for i in np.flatnonzero(symmetric):  # building the dicts (the output's form), not computing
        table[i] = {"axis": int(axis[i]) + 1, "body": float(body[i]), "space": float(space[i])}
    fine = symmetric & np.isfinite(body) & np.isfinite(space) & (space > 0) \
        & ~np.any((Lv != 0) & (np.abs(Lv) < _TINY), axis=1)
    return table, np.where(symmetric, err, np.nan), fine


def summarize_batch(parameters: Mapping[str, np.ndarray], initial: Mapping[str, np.ndarray],
                    names: tuple[str, ...], *, strict: bool = True) -> BatchSummary:
    """The per-motion quantities ``names`` of N free tops (module docstring), SI units.

    ``parameters``: {"I1", "I2", "I3"} arrays of N; ``initial``: {"omega": (N, 3)} (the Euler angles, if
    given, do not enter these quantities).  Every point is computed elementwise, so a chunk's results do not
    depend on what else is in the chunk.
    """
    moments = [np.asarray(parameters[k], dtype=float).reshape(-1) for k in ("I1", "I2", "I3")]
    n = len(moments[0])
    w = np.asarray(initial["omega"], dtype=float)
    if any(len(x) != n for x in moments) or w.shape != (n, 3):
        raise InvalidInputError(f"expected I1, I2, I3 of N values and omega of shape (N, 3), got lengths "
                                f"{[len(x) for x in moments]} and omega of shape {w.shape}")
    I = np.stack(moments, axis=1)
    refused = _refused(I, w, strict)
    for key in ("phi", "theta", "psi"):  # the Euler angles enter none of these, but the scene refuses them non-finite
        if key in initial:
            refused |= ~np.isfinite(np.asarray(initial[key], dtype=float).reshape(-1) * np.ones(n))
    Ic = np.where(refused[:, None], 1.0, I)
    wc = np.where(refused[:, None], 0.0, w)
    # exact powers of two: max moment and max |ω| in [1/2, 1), so the setup is far from overflow and underflow
    eI = np.frexp(np.max(Ic, axis=1))[1]
    wmax = np.max(np.abs(wc), axis=1)
    ew = np.where(wmax == 0, 0, np.frexp(wmax)[1])
    Is, ws = np.ldexp(Ic, -eI[:, None]), np.ldexp(wc, -ew[:, None])
    fallback = refused.copy()
    values: dict[str, Any] = {}
    errors: dict[str, np.ndarray] = {}
    wanted = set(names)
    if wanted & {"polhode_period", "period", "flip_interval"}:
        p = _period(Is, ws)
        steady = _steady(Ic, wc)
        fallback |= steady | p["fallback"]
        with np.errstate(over="ignore", under="ignore"):
            P = np.ldexp(p["P"], -ew)  # ω = 2^ew ω_s: λ = 2^ew λ_s, P = 2^-ew P_s
        fallback |= ~np.isfinite(P) | (P < np.finfo(float).tiny)
        errP = (p["bound"] + p["measured"]) * P
        for name in ("polhode_period", "period"):
            if name in wanted:
                values[name], errors[name] = P, errP
        if "flip_interval" in wanted:
            # defined for three distinct moments only (a symmetric top has no intermediate axis to flip about)
            fallback |= (Ic[:, 0] == Ic[:, 1]) | (Ic[:, 1] == Ic[:, 2]) | (Ic[:, 0] == Ic[:, 2])
            values["flip_interval"], errors["flip_interval"] = 0.5 * P, 0.5 * errP
    if "energy" in wanted or "angular_momentum" in wanted:
        with np.errstate(over="ignore", under="ignore"):
            a = Is * ws * ws  # as the single path: moments * w0 * w0, summed in order
            T = 0.5 * (a[:, 0] + a[:, 1] + a[:, 2])
            T2 = 0.5 * (Is[:, 0] * (ws[:, 0] * ws[:, 0]) + Is[:, 1] * (ws[:, 1] * ws[:, 1])
                        + Is[:, 2] * (ws[:, 2] * ws[:, 2]))
            Lv = Is * ws
            L = np.sqrt(Lv[:, 0] * Lv[:, 0] + Lv[:, 1] * Lv[:, 1] + Lv[:, 2] * Lv[:, 2])
            L2 = np.hypot(np.hypot(Lv[:, 0], Lv[:, 1]), Lv[:, 2])
            # a sum of positive terms: no cancellation, 3 roundings; the second evaluation's difference measures
            eT = np.abs(T - T2) + 2 * _EPS * T
            eL = np.abs(L - L2) + 2 * _EPS * L
            low = np.any((a != 0) & (a < _TINY), axis=1) | np.any((Lv != 0) & (np.abs(Lv) < _TINY), axis=1)
            scale_T, scale_L = eI + 2 * ew, eI + ew
            if "energy" in wanted:
                values["energy"] = np.ldexp(T, scale_T)
                errors["energy"] = np.ldexp(eT, scale_T)
                fallback |= low | ~np.isfinite(values["energy"]) | ((values["energy"] < np.finfo(float).tiny)
                                                                    & (T != 0))
            if "angular_momentum" in wanted:
                values["angular_momentum"] = np.ldexp(L, scale_L)
                errors["angular_momentum"] = np.ldexp(eL, scale_L)
                # the planner returns |L| of a scene solved in units of its own motion as None (no power of two)
                fallback |= low | ~_comfortable(Ic, wc) | ~np.isfinite(values["angular_momentum"]) \
                    | ((values["angular_momentum"] < np.finfo(float).tiny) & (L != 0))
    if "stability" in wanted:
        table, err = _stability(Ic, wc)
        values["stability"], errors["stability"] = table, err
        # the single path evaluates it only for a rigid body's moments (triangle inequalities) and as given
        fallback |= _refused(Ic, wc, True) | ~_comfortable(Ic, wc)
    if "precession_rate" in wanted:
        table, err, symmetric = _precession(Ic, wc)
        values["precession_rate"], errors["precession_rate"] = table, err
        # defined for a symmetric top only (distinct moments or a sphere: None with a reason); a table of rates
        # is None from the planner for a scene solved in units of its own motion
        fallback |= ~symmetric | ~_comfortable(Ic, wc)
    for name in names:
        if name not in values:  # an unknown name: the planner's own message, point by point
            values[name], errors[name] = np.full(n, np.nan), np.full(n, np.nan)
            fallback[:] = True
    return BatchSummary(values={k: values[k] for k in names}, errors={k: errors[k] for k in names},
                        fallback=fallback)
