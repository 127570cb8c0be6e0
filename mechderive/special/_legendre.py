"""Half-range Carlson forms and complete integrals behind :mod:`mechderive.special.integrals` (private).

Each ``half`` value is I(ψ) for |ψ| <= π/2 written as s·G(c², ...) with G even in c;
:func:`assemble` adds the quasi-periodic part 2jI (DLMF 19.2.10).

>>> import numpy as np
>>> j, s, c = reduce_angle(np.array([np.pi + 0.25]))
>>> float(j[0]), round(float(s[0]), 15), round(float(c[0]), 15)
(1.0, 0.247403959254523, 0.968912421710645)
"""

from __future__ import annotations

import numpy as np
from ._carlson import elliprc, elliprd, elliprf, elliprj

from ..errors import InvalidInputError
from ._doubledouble import PI_HI, PI_LO, two_prod, two_sum

__all__ = [
    "reduce_angle",
    "delta2",
    "one_minus_n_s2",
    "NEG_N",
    "assemble",
    "complete_e",
    "complete_pi_rj",
    "complete_pi",
    "pi_half",
    "check_m_one",
    "check_pole",
    "periods_pi",
]

NEG_N = -0.25  # below: the change-of-parameter forms for Π (no cancellation)


def reduce_angle(phi: np.ndarray):
    """φ = jπ + ψ, |ψ| <~ π/2; return j, sin ψ, cos ψ (ψ in double-double, first-order corrected)."""
    j = np.rint(phi / PI_HI)
    p_hi, p_lo = two_prod(j, PI_HI)
    psi_hi, psi_lo = two_sum(phi - p_hi, -p_lo - j * PI_LO)   # phi - p_hi exact (Sterbenz)
    s0, c0 = np.sin(psi_hi), np.cos(psi_hi)
    return j, s0 + c0 * psi_lo, c0 - s0 * psi_lo


def delta2(s, c, p):
    """Δ² = 1 - m s², as c² + m1 s² when m > 1/2 (no cancellation near m = 1)."""
    m = np.broadcast_to(p.m, s.shape)
    return np.where(m <= 0.5, 1.0 - m * s * s, c * c + (p.m1 + p.m1_lo) * s * s)


def one_minus_n_s2(n, s, c):
    """1 - n s², as c² + (1 - n) s² when n >= 1/2 (exact 1 - n, no cancellation for n <= 1)."""
    return np.where(n < 0.5, 1.0 - n * s * s, c * c + (1.0 - n) * s * s)


def assemble(j, s, c, half, complete):
    """2jI + I(ψ) from the half-range value I(ψ) = s·G(c², ...) for |ψ| <= π/2.

    If rounding left |ψ| slightly beyond π/2 (c < 0), mirror: I(ψ) = ±2I - I(±π - ψ).
    """
    past = c < 0
    jeff = j + np.where(past, np.where(s < 0, -1.0, 1.0), 0.0)
    with np.errstate(invalid="ignore"):
        periodic = np.where(jeff != 0, 2.0 * jeff * complete, 0.0)
    return periodic + np.where(past, -half, half)


def complete_e(p):
    """E(m) = m1 R_F(0, m1, 1) + (m m1/3) R_D(0, 1, m1) (DLMF 19.25.10 at φ = π/2); E(1) = 1."""
    m1 = p.m1 + p.m1_lo
    safe = np.where(m1 == 0, 1.0, m1)
    e = m1 * elliprf(0.0, safe, 1.0) + p.m * m1 / 3.0 * elliprd(0.0, 1.0, safe)
    return np.where(m1 == 0, 1.0, e)


def complete_pi_rj(n, p):
    """R_J(0, m1, 1, 1 - n), the third-kind part of Π(n|m) = K + (n/3)·R_J (DLMF 19.25.2)."""
    m1 = np.broadcast_to(p.m1 + p.m1_lo, np.broadcast(n, p.m1).shape)
    bad = (m1 == 0) | (n == 1)
    with np.errstate(all="ignore"):
        rj = elliprj(0.0, np.where(bad, 1.0, m1), 1.0, np.where(bad, 1.0, 1.0 - n))
    return np.where(bad, np.inf, rj)


def complete_pi(n, p):
    """Π(n|m) for n != 1, m < 1 (inf where it diverges).

    n >= -1/4: K + (n/3) R_J(0, m1, 1, 1 - n) (DLMF 19.25.2).  n < -1/4: the R_J term
    would cancel most of K (K/Π grows with |n|: ~3 at n = -10, m = 0.9), so use the
    change of parameter DLMF 19.21.12 with (p - 1)(q - 1) = m, which leaves positive terms:
    Π = π / (2√(p q)) + (m / (3|n|)) R_J(0, m1, 1, q),  p = 1 - n, q = 1 + m/|n|.
    """
    m = p.m
    m1 = np.broadcast_to(p.m1 + p.m1_lo, np.broadcast(n, m).shape)
    neg = n < NEG_N
    an = np.where(neg, -n, 1.0)
    q = 1.0 + m / an
    with np.errstate(all="ignore"):
        transformed = (np.pi / 2.0) / np.sqrt((1.0 - n) * q) + m / (3.0 * an) * elliprj(
            0.0, np.where(m1 == 0, 1.0, m1), 1.0, q)
        direct = p.K_hi + p.K_lo + n / 3.0 * complete_pi_rj(n, p)
    return np.where(m1 == 0, np.inf, np.where(neg, transformed, direct))


def pi_half(n, s, c, d2, m):
    """Π(n; ψ|m) for |ψ| <= π/2 given s = sin ψ, c = cos ψ (>= 0 or mirrored), d2 = Δ².

    DLMF 19.25.14, or for n < -1/4 its change of parameter (DLMF 19.21.12, positive terms):
    Π = s R_C(c²Δ², p q) + (m s³ / (3|n|)) R_J(c², Δ², 1, q),  p = 1 - n s², q = 1 + m s²/|n|.
    """
    c2 = c * c
    s2 = s * s
    neg = n < NEG_N
    an = np.where(neg, -n, 1.0)
    pp = one_minus_n_s2(n, s, c)
    with np.errstate(all="ignore"):
        # Only the branch in use is evaluated (each costs an R_J per point); both when mixed.
        if np.all(neg):
            q = 1.0 + m * s2 / an
            return s * elliprc(c2 * d2, pp * q) + m * s * s2 / (3.0 * an) * elliprj(c2, d2, 1.0, q)
        direct = s * elliprf(c2, d2, 1.0) + n / 3.0 * s * s2 * elliprj(c2, d2, 1.0, pp)
        if not np.any(neg):
            return direct
        q = 1.0 + m * s2 / an
        transformed = s * elliprc(c2 * d2, pp * q) + m * s * s2 / (3.0 * an) * elliprj(c2, d2, 1.0, q)
    return np.where(neg, transformed, direct)


def check_m_one(p, j, c, phi, what):
    """F and Π at m = 1 exist only for |φ| < π/2."""
    bad = np.broadcast_to(p.m1 == 0, j.shape) & ((j != 0) | (c <= 0))
    if np.any(bad):
        raise InvalidInputError(
            f"expected |phi| < pi/2 when m = 1 ({what} diverges at pi/2), got phi = {float(phi[bad].ravel()[0])!r}"
        )


def check_pole(q, n, s, c, where_name, where_val):
    """Raise where 1 - n sin²φ is zero to within its rounding (a pole of the integrand)."""
    scale = np.where(n < 0.5, 1.0 + np.abs(n) * s * s, c * c + np.abs(1.0 - n) * s * s)
    at_pole = np.abs(q) <= 4.0 * np.finfo(float).eps * scale
    if np.any(at_pole):
        i = np.flatnonzero(at_pole.ravel())[0]
        raise InvalidInputError(
            f"expected 1 - n sin²φ != 0 (a pole of the integrand), got n = {float(n.ravel()[i])!r}, "
            f"{where_name} = {float(where_val.ravel()[i])!r}"
        )


def periods_pi(n, p):
    """Π(n|m) for the ``periods`` shift (raises where it diverges)."""
    if np.any(p.m1 == 0) or np.any(n == 1):
        raise InvalidInputError("expected m < 1 and n != 1 with `periods` (Π(n|m) diverges), got m = 1 or n = 1")
    return complete_pi(n, p)
