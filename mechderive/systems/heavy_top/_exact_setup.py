"""The heavy top's closed-form setup at 40 digits (mpmath), and its angles' constants at that precision.

:func:`.exact.exact_heavy_top` sets a motion up in extended precision where its measured errors allow
(:mod:`.exact_extended`, no mpmath); this module is the rest: motions next to a passage through the pole or
the bottom, to the separatrix or to a double root, and what :mod:`.exact_extended` cannot vouch for.  It is
imported only then (a warm run of an ordinary motion loads neither it nor mpmath).  :func:`setup` finds the
roots u1 ≤ u2 ≤ u3 of f(u) (3.73), κ, m, the phase's start v0 = F(A0|m) and the passages' signs, raising the
working precision as far as 1 ∓ u needs (see its comments); :func:`kept_fractions` and
:func:`precise_advance` give the partial fractions of φ̇, ψ̇ (3.74)-(3.75) and their advance per nutation
period.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...core.phase import DD
from ...errors import DerivationError, InvalidInputError
from .exact import _DPS, HeavyTopSolution, _angle_functions, _nutation_functions, _passage_sign, classify

if TYPE_CHECKING:  # pragma: no cover
    import mpmath

__all__ = ["setup", "kept_fractions", "precise_advance"]


def real_roots(coeffs: list, known: "mpmath.mpf | None" = None) -> list:
    """The three real roots of the cubic f(u) (coefficients of u³, u², u, 1), sorted, at 40 digits.

    With a known root (a top started at a turning point, θ̇ = 0) the cubic is deflated and the
    quadratic solved in closed form; otherwise double-precision roots are polished by Newton's
    method at 40 digits, falling back to mpmath's polyroots when two roots nearly coincide
    (where Newton's convergence is slow).
    """
    import mpmath

    c3, c2, c1, c0 = coeffs
    if known is not None:
        # f(u) = (u - u0)(c3 u² + b2 u + b1): synthetic division
        b2 = c2 + c3 * known
        b1 = c1 + b2 * known
        others = quadratic_roots(c3, b2, b1)
        if others is not None:
            return sorted([known, *others])
    biggest = max(abs(c) for c in coeffs)
    if known is None and abs(c3) < mpmath.mpf(2) ** -600 * biggest:
        # β = 2 M g l / I1 negligible against the rates (a scene solved in units of a fast motion): one
        # root far out at ~ -c2/c3 (≈ α/β, beyond every double), the other two O(1).  Newton's method
        # finds the far one; dividing it out from the constant term down, q0 = -c0/u3, q1 = (q0 - c1)/u3,
        # q2 = (q1 - c2)/u3, leaves their quadratic without cancellation.
        far = -c2 / c3
        for _ in range(100):
            step = (((c3 * far + c2) * far + c1) * far + c0) / ((3 * c3 * far + 2 * c2) * far + c1)
            far -= step
            if abs(step) <= mpmath.mpf(10) ** (-mpmath.mp.dps + 2) * abs(far):
                break
        q0 = -c0 / far
        q1 = (q0 - c1) / far
        others = quadratic_roots((q1 - c2) / far, q1, q0)
        if others is None:
            raise DerivationError(f"expected three real roots of f(u), got a complex pair beside u = {far}")
        return sorted([far, *others])
    approx = np.roots([float(c) for c in coeffs])
    if np.all(np.abs(approx.imag) <= 1e-9 * (1 + np.abs(approx))):
        approx = np.sort(approx.real)
        if np.min(np.diff(approx)) > 1e-5 * (1 + np.max(np.abs(approx))):
            roots = []
            for r in approx:
                x = mpmath.mpf(float(r))
                for _ in range(8):
                    fx = ((c3 * x + c2) * x + c1) * x + c0
                    step = fx / ((3 * c3 * x + 2 * c2) * x + c1)
                    x -= step
                    if abs(step) <= mpmath.mpf(10) ** (-mpmath.mp.dps + 2) * (1 + abs(x)):
                        break
                roots.append(x)
            return sorted(roots)
    roots = mpmath.polyroots(coeffs, maxsteps=200, extraprec=4 * mpmath.mp.dps)
    tiny = mpmath.mpf(10) ** (-mpmath.mp.dps // 2)
    real = sorted(mpmath.re(r) for r in roots if abs(mpmath.im(r)) <= tiny * (1 + abs(r)))
    if len(real) != 3:
        raise DerivationError(f"expected three real roots of f(u), got {roots}")
    return real


def quadratic_roots(a, b, c) -> list | None:
    """The real roots of a u² + b u + c (mpmath, no cancellation: Numerical Recipes 5.6); None if complex.

    A discriminant negative by the working precision's rounding only is a double root.
    """
    import mpmath

    disc = b * b - 4 * a * c
    if disc < 0 and disc > -mpmath.mpf(10) ** (-mpmath.mp.dps + 5) * (b * b + abs(4 * a * c)):
        disc = mpmath.mpf(0)  # a double root, up to the 40-digit rounding
    if disc < 0:
        return None
    sq = mpmath.sqrt(disc)
    q = -(b + (sq if b >= 0 else -sq)) / 2
    return [q / a, c / q] if q != 0 else [mpmath.mpf(0), mpmath.mpf(0)]


#: Below this 1 - u2 (or 1 + u1) the 40-digit roots would leave fewer than 30 of its digits.
_NEAR_PASSAGE = 1e-10
#: No real input needs this many: b ∓ a resolved at d digits makes 1 ∓ u ≳ 10^(-2d).
_MAX_DPS = 1000
#: Below this, 1 - u2 (1 + u1) would be a subnormal or zero double: the evaluation forms
#: 1 ∓ u = (1 ∓ u2) + (u2 - u1)cn² (sn²) and 1 - n± from it in double precision.
_UNDERFLOW = 1e-150


def setup(params: dict, init: dict) -> HeavyTopSolution:
    import mpmath

    f = _nutation_functions()
    mp = mpmath.mpf
    P = [mp(params[k]) for k in ("I1", "I3", "M", "g", "l")]
    S = [mp(init[k]) for k in ("theta", "theta_dot", "phi_dot", "psi_dot")]
    a, b, alpha, beta = f["state"](*P, *S)
    I1, I3 = P[0], P[1]
    th0 = S[0]
    u0 = mpmath.cos(th0)
    # 1 ∓ u0 of the start itself, from the half angle (cos θ0 at 40 digits is 1 for θ0 < 1e-20)
    start_gaps = (2 * mpmath.sin(th0 / 2) ** 2, 2 * mpmath.cos(th0 / 2) ** 2)
    refuse_too_close(start_gaps[0], "pole")  # 1 - u2 <= 1 - u0
    energy = (I1 * (S[1] ** 2 + S[2] ** 2 * mpmath.sin(th0) ** 2) + I3 * (S[3] + S[2] * u0) ** 2) / 2 \
        + P[2] * P[3] * P[4] * u0
    coeffs = f["f"](a, b, alpha, beta)
    common = dict(parameters=dict(params), initial=dict(init), energy=float(energy), p_phi=float(I1 * b),
                  p_psi=float(I1 * a), f_coefficients=tuple(float(c) for c in coeffs))
    d_pole, d_bottom = f["gaps"](*P, *S)
    # a root known exactly deflates the cubic, and the other two come from a quadratic without loss:
    # ±1 at an exact passage (f(±1) = -(b ∓ a)², 3.76), u0 for a start at a turning point (θ̇0 = 0).
    # Otherwise a near double root u2 ≈ u3 (next to the separatrix) is only found to the square
    # root of the working precision (m1 = 1.2e-21 came out for 1e-76 at 40 digits: θ 1e-8 for 1e-36)
    known = mp(1) if d_pole == 0 else mp(-1) if d_bottom == 0 else u0 if S[1] == 0 else None
    u_1, u_2, u_3 = real_roots(coeffs, known=known)
    separated = known is not None and known in (u_2, u_3)  # u3 - u2 then to the working precision
    # u0 lies in [u1, u2] up to the roots' own accuracy (40 digits); snap it in, and keep the
    # turning points in [-1, 1] (a root at ±1 can come out as ±(1 + 4e-40)).
    u_2, u_1 = min(max(u_2, u0), mp(1)), max(min(u_1, u0), mp(-1))
    # A near pole (bottom) passage: 1 - u2 (1 + u1) is tiny, and the roots, accurate to 10^-dps
    # absolutely, keep only dps + log10(1 ∓ u) of its digits.  But n± (3.74)-(3.75) and with them
    # the turn of φ and ψ by ~π at the passage depend on its *relative* value (at 40 digits,
    # 1 + u1 = 3e-32 came out 2e-9 off relative, and R 7e-9 off).  The inputs are exact binary
    # numbers: redo the setup with as many more digits as 1 ∓ u has leading zeros.  f(±1) = -(b ∓ a)²
    # (3.73): the apex reaches the pole (bottom) only if b = a (b = -a); a root at ±1 with b ∓ a ≠ 0
    # means the working digits could not resolve 1 ∓ u (~(b ∓ a)²) at all: double them first.
    # b ∓ a from the state in the half angle (model.passage_factors): zero exactly when the apex
    # passes through the pole (bottom), and resolved at any precision when it only comes near
    # (b - a from a and b would be 0 at 40 digits for θ0 = 1e-30, posing as an exact passage)
    # an exact passage: ±1 is a root of f (3.76) exactly; the nearest computed root is it
    if d_pole == 0:
        if abs(u_3 - 1) < abs(u_2 - 1):
            u_3 = mp(1)
        else:
            u_2 = mp(1)
    if d_bottom == 0:
        u_1 = mp(-1)
    gaps = ((1 - u_2, d_pole), (1 + u_1, d_bottom))
    if any(g == 0 and d != 0 for g, d in gaps):
        if mpmath.mp.dps >= _MAX_DPS:
            raise DerivationError(f"expected 1 - u2 and 1 + u1 resolved within {_MAX_DPS} digits, got a root at "
                                  f"±1 with b ∓ a = {mpmath.nstr(b - a, 3)}, {mpmath.nstr(b + a, 3)}")
        with mpmath.workdps(2 * mpmath.mp.dps):
            return setup(params, init)
    near = [g for g in (*(g for g, _ in gaps), *start_gaps) if g > 0]
    # next to the separatrix (u3 - u2 → 0, m → 1): u3 - u2 to ~40 digits as well, which takes
    # twice its leading zeros when u2 and u3 are a near double root of one solve
    sep = u_3 - u_2
    if 0 < sep < _NEAR_PASSAGE:
        near.append(sep if separated else sep**2)
    elif sep == 0 and u_2 - u_1 > 0 and S[1] != 0:
        # u2 = u3 is a sleeping top at the stability threshold — not a moving one: unresolved
        if mpmath.mp.dps >= _MAX_DPS:
            raise DerivationError(f"expected u3 - u2 resolved within {_MAX_DPS} digits, got 0")
        with mpmath.workdps(2 * mpmath.mp.dps):
            return setup(params, init)
    if near and min(near) < _NEAR_PASSAGE:
        # (a gap below 10^-dps is only an upper bound: the next pass measures it again)
        needed = _DPS + int(mpmath.ceil(-mpmath.log10(min(near))))
        if needed > mpmath.mp.dps:
            if needed > _MAX_DPS:
                raise DerivationError(f"expected 1 ∓ u resolved within {_MAX_DPS} digits, got {min(near)}")
            with mpmath.workdps(needed):
                return setup(params, init)
    for (g, _), where in zip(gaps, ("pole", "bottom")):
        refuse_too_close(g, where)
    amp = u_2 - u_1
    scale = mp(10) ** (-mpmath.mp.dps + 8)
    roots_f = (float(u_1), float(u_2), float(u_3))
    if amp <= scale or (mpmath.sin(th0) == 0 and S[1] == 0):
        return HeavyTopSolution(
            kind="steady", roots=roots_f, m=0.0, m1=1.0, nutation_period=float("nan"), conditioning=1.0,
            motion_class="uniform precession", _kappa=DD(0.0, 0.0), _v0=DD(0.0, 0.0), _period=None,
            _u1=float(u0), _amp=0.0, _one_minus_u2=float(1 - u0), _one_plus_u1=float(1 + u0),
            _theta_const=float(th0), _mp=dict(steady=True, beta=float(beta), d_minus=float(d_pole),
                                              d_plus=float(d_bottom)), **common)
    roots = (u_1, u_2, u_3)
    kappa2, m, m1 = f["nutation"](beta, *roots)
    if m1 < _UNDERFLOW:
        raise InvalidInputError(
            f"expected the motion at least 1e-150 from the separatrix (1 - m >= 1e-150: the nutation period "
            f"~ln(1/(1 - m)) and the Jacobi functions take 1 - m as a double), got 1 - m = {mpmath.nstr(m1, 3)}: "
            f"integrating it (integrate_heavy_top; a scene's method 'integrate') follows such a motion")
    kappa = mpmath.sqrt(kappa2)
    s0 = min(max((u0 - u_1) / amp, mp(0)), mp(1))
    u_dot0 = -mpmath.sin(th0) * S[1]
    A0 = mpmath.sign(u_dot0) * mpmath.asin(mpmath.sqrt(s0)) if u_dot0 != 0 else \
        (mpmath.pi / 2 if s0 > mp(1) / 2 else mp(0))
    K = mpmath.ellipk(m) if m1 != 0 else mpmath.inf
    # v0 = F(A0|m) as (the turning point next to it) + δ0, δ0 with its full relative accuracy: past
    # A0 = π/4, F(A0|m) = K - F(χ|m) with tan χ = cot A0 / k' (DLMF 19.7.8), cos A0 = √((u2 - u0)/amp)
    if abs(A0) > mpmath.pi / 4 and m1 != 0:
        anchor = int(mpmath.sign(A0))
        chi = mpmath.atan2(mpmath.sqrt((u_2 - u0) / amp), mpmath.sqrt(m1) * mpmath.sqrt(s0))
        dv0 = -anchor * mpmath.ellipf(chi, m)
    else:
        anchor, dv0 = 0, mpmath.ellipf(A0, m)
    v0 = anchor * K + dv0 if m1 != 0 else dv0
    period = None if m1 == 0 else DD.of(2 * K)
    n_plus = (u_2 - u_1) / (1 - u_1) if u_1 < 1 else mp(0)
    n_minus = -(u_2 - u_1) / (1 + u_1) if u_1 > -1 else -mpmath.inf
    return HeavyTopSolution(
        kind="nutating", roots=roots_f, m=float(m), m1=float(m1),
        nutation_period=float(2 * K / kappa) if period is not None else float("inf"),
        conditioning=float(max(1 / (1 - n_plus) if n_plus < 1 else mpmath.inf, 1 - n_minus)),
        motion_class=classify(float(u_1), float(u_2), float(a), float(b)),
        _kappa=DD.of(kappa), _v0=DD.of(v0), _period=period, _u1=float(u_1), _amp=float(amp),
        _one_minus_u2=float(1 - u_2), _one_plus_u1=float(1 + u_1), _theta_const=float(th0),
        _mp=dict(steady=False, I1=I1, I3=I3, a=a, b=b, roots=roots, kappa=kappa, m=m, m1=m1, A0=A0, K=K,
                 anchor=anchor if period is not None else None, dv0=DD.of(dv0),
                 # for the error estimate: 1 ∓ u_k to full relative accuracy, b ∓ a, β
                 gaps_minus=tuple(float(1 - r) for r in roots), gaps_plus=tuple(float(1 + r) for r in roots),
                 d_minus=float(d_pole), d_plus=float(d_bottom), beta=float(beta),
                 # sn v0 = sin A0, cn v0 = cos A0 exactly (v0 = F(A0|m), DLMF 22.16.1)
                 pole_sign=_passage_sign(mpmath.cos(A0), -mpmath.sin(A0), S[1]),
                 bottom_sign=_passage_sign(mpmath.sin(A0), mpmath.cos(A0), -S[1]),
                 scale=scale, dps=mpmath.mp.dps), **common)


def refuse_too_close(gap, where: str) -> None:
    """Raise unless 1 ∓ u at the closest approach to the pole (bottom), ``gap``, is 0 or ≥ :data:`_UNDERFLOW`.

    Below it Carlson's R_J of the passage (~1/√(gap)·1/gap) under- or overflows in double
    precision; the motion is then within ~1e-75 rad of the pole, where φ and ψ individually turn
    by O(1) in a time that no double resolves — a steady approximation would be wrong for them.
    """
    if 0 < gap < _UNDERFLOW:
        import mpmath

        raise InvalidInputError(
            f"expected the apex to stay at least ~1e-75 rad from the {where} unless it passes through it exactly "
            f"(1 ∓ cos θ ≥ 1e-150: below, Carlson's integrals of the passage under- or overflow in double "
            f"precision), got a motion coming within {mpmath.nstr(mpmath.sqrt(2 * gap), 3)} rad of it: use theta = "
            f"{'0' if where == 'pole' else 'pi'} for the {where} itself, or integrate the motion (integrate_heavy_top; "
            f"a scene's method 'integrate')")


def partial_fractions(f, args: tuple) -> list:
    """The partial-fraction constants; at an exact pole or bottom passage (1 ∓ u = 0) the term
    whose coefficient vanishes with b ∓ a comes out 0/0: it is returned as NaN and dropped."""
    try:
        return list(f(*args))
    except ZeroDivisionError:
        import mpmath

        I1, I3, a, b, u1, u2, u3 = args
        eps = mpmath.mpf(10) ** (-_DPS)
        near = list(f(I1, I3, a, b, u1 + eps if u1 == -1 else u1, u2 - eps if u2 == 1 else u2, u3))
        for k in range(1, len(near), 2):
            if abs(near[k + 1]) > 1 / eps ** mpmath.mpf("0.5") or abs(near[k]) > 1 / eps ** mpmath.mpf("0.5"):
                near[k], near[k + 1] = mpmath.nan, mpmath.nan
        return near


def kept_fractions(sol: HeavyTopSolution) -> dict[str, tuple]:
    """(c0, [(c_i, n_i)]) for φ and ψ: the partial fractions of φ̇/κ, ψ̇/κ (3.74), (3.75) in u = u1 + (u2 - u1)sn².

    At 40 digits (more near a passage, see :func:`setup`).  At an exact passage (b = ±a) the
    n₊ (n₋) term is absent: its coefficient vanishes and it is dropped.
    """
    import mpmath

    v = sol._mp
    f = _angle_functions()
    frac_args = (v["I1"], v["I3"], v["a"], v["b"], *v["roots"])
    out = {}
    for name in ("phi", "psi"):
        flat = partial_fractions(f[name], frac_args)
        kept = [(c, n) for c, n in zip(flat[1::2], flat[2::2])
                if mpmath.isfinite(c) and mpmath.isfinite(n) and abs(c) > v["scale"] * (abs(v["a"]) + abs(v["b"]) + 1)]
        out[name] = (flat[0], kept)
    return out


def precise_advance(sol: HeavyTopSolution) -> dict[str, DD]:
    """Δφ and Δψ per nutation period at 40 digits: (c0/κ)·2K + Σ (c_i/κ)·2Π(n_i | m).

    Near the pole Π(n₊ | m) ~ (1 - n₊)^(-1/2) needs 1 - n₊ to full relative accuracy (from
    float(n₊) it would carry 1e-16/(1 - n₊): 8e-8 rad per period in φ - ψ at 1 - n₊ = 5e-10),
    which the working precision gives.
    """
    from ...special.highprec import complete_pi_mp

    v = sol._mp
    kappa, K = v["kappa"], v["K"]
    complete: dict = {}  # φ and ψ share their characteristics n±
    out = {}
    for name, (c0, kept) in sol._angle_fractions.items():
        per = (c0 / kappa) * 2 * K
        for c, n in kept:
            if n not in complete:
                complete[n] = complete_pi_mp(n, v["m1"])
            per += (c / kappa) * 2 * complete[n]
        out[name] = DD.of(per)
    return out
