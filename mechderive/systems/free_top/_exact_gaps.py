"""The free top's exact decisions from the binary inputs, without rounding (private; no mpmath).

What both setups of the closed form (:mod:`._exact_setup` at 40 digits, :mod:`.exact_extended` in
extended precision) decide before computing anything: whether ω is an eigenvector of the inertia
tensor (a steady rotation), the gaps G_k = 2T·I_k - L² as exact rationals, and from the sign of G_y
the relabelling of the body axes; and the derivations of the constants both compile (for mpmath and for
NumPy: :func:`build_gap_constants`, :func:`build_q`, :func:`build_precession`).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

__all__ = ["TINY_M1", "gaps", "is_steady", "relabelling", "signed_permutation", "build_gap_constants", "build_q",
           "build_precession"]

#: Below this 1 - m the Jacobi functions on |v| <= K/2 are tanh v, sech v, sech v to within
#: k' = √m1 < 1e-17 relative (DLMF 22.10.iii: the corrections are O(m1 sinh v cosh v) ≤ O(k')),
#: so the motion is evaluated as piecewise separatrix motion joined at the quarter periods.
TINY_M1 = 1e-34
#: the order of :func:`build_gap_constants`'s results
_NAMES = ("P2", "S2", "lambda2", "Q2", "m", "m1")


def is_steady(I: np.ndarray, w: np.ndarray) -> bool:
    """ω × (I ω) = 0 exactly: (I_b - I_c) ω_b ω_c = 0 for every pair, decided without rounding."""
    return all(I[b] == I[c] or w[b] == 0 or w[c] == 0 for b, c in ((0, 1), (1, 2), (2, 0)))


def gaps(I: np.ndarray, w: np.ndarray) -> tuple[Fraction, Fraction, list[Fraction]]:
    """(2T, L², [G_1, G_2, G_3]) exactly, G_k = 2T·I_k - L² = Σ_a I_a ω_a² (I_k - I_a)."""
    If = [Fraction(float(x)) for x in I]
    a = [If[k] * Fraction(float(w[k])) ** 2 for k in range(3)]
    two_T = sum(a)
    L2 = sum(If[k] * a[k] for k in range(3))
    return two_T, L2, [sum(a[j] * (If[k] - If[j]) for j in range(3) if j != k) for k in range(3)]


def relabelling(I: np.ndarray, G: list[Fraction]) -> tuple[int, int, int]:
    """Body axes (x, y, z): y intermediate, z the axis ω circulates about.

    z is the largest-moment axis when L² ≥ 2T·I_y (G_y ≤ 0) and the smallest otherwise; for a
    symmetric body the distinct axis (the sign of G_y then agrees: G_y = -I_z ω_z² (I_z - I_y)).
    """
    lo, mid, hi = (int(k) for k in np.argsort(I, kind="stable"))
    if I[lo] == I[mid]:
        return lo, mid, hi
    if I[mid] == I[hi]:
        return hi, mid, lo
    return (lo, mid, hi) if G[mid] <= 0 else (hi, mid, lo)


def signed_permutation(x: int, y: int, z: int) -> np.ndarray:
    """Rows e_x, e_y, σ e_z with σ = ±1 chosen so that det = +1 (a proper rotation)."""
    Pm = np.zeros((3, 3))
    Pm[0, x] = Pm[1, y] = Pm[2, z] = 1.0
    Pm[2, z] = np.linalg.det(Pm)
    return Pm


def build_gap_constants():
    """(I_x, I_y, I_z, G_x, G_y, G_z) and (P², S², λ², Q², m, m1) in them (:mod:`.exact_model`)."""
    from . import exact_model as em

    c = em.model().gap_constants
    return [em.Ix, em.Iy, em.Iz, *em.gaps], [c[k] for k in _NAMES]


def build_q():
    """Q in terms of P, S, λ (its sign follows theirs), derived from the second Euler relation."""
    import sympy as sp

    from . import exact_model as em

    return [em.Ix, em.Iy, em.Iz, *sp.symbols("P S lambda", real=True)], [em.model().constants["Q"]]


def build_precession():
    """(c1, c2, n) of φ̇ = c1 + c2/(1 - n sn²) in (I_x, I_y, I_z, 2T, L², |L|)."""
    from . import exact_model as em

    pf = em.model().precession_partial_fractions
    return [em.Ix, em.Iy, em.Iz, em.E2, em.L2, em.L], [pf["c1"], pf["c2"], pf["n"]]
