"""Catalog entries for section 3.3: the free body's kinetic energy separates (3.29)–(3.30).

The derivation is :class:`mechderive.inertia.free_body.FreeBodyModel` for three
general point masses: r_i = R + Δr_i (3.29), velocities ṙ_i = Ṙ + Δṙ_i with
the rigid Δṙ_i = ωᵀ Δr_i derived in :mod:`mechderive.inertia.tensor`.  All
vectors are written in body components (V = Ṙ in the body frame); T involves
only dot products, so the frame does not matter.  "I" in the printed form is a
general symmetric tensor of symbols, replaced by the derived I about the centre
of mass, and M by Σ m_i.
"""

from __future__ import annotations

import sympy as sp

from ..inertia.free_body import free_body_model
from ..inertia.tensor import general_inertia_symbols
from .checks import all_pass, same
from .registry import Claim, register

__all__: list[str] = []  # registers claims on import; nothing to export

_M = sp.Symbol("M", positive=True)


def _printed_3_30():
    fb = free_body_model(3)
    V, w, I = fb.V, fb.omega, general_inertia_symbols()
    half = sp.Rational(1, 2)
    line2 = sum(m * (half * V.dot(V) + V.dot(w.cross(d)) + half * w.cross(d).dot(w.cross(d)))
                for m, d in zip(fb.masses, fb.offsets))
    line3 = half * _M * V.dot(V) + half * (w.T * I * w)[0]
    return (line2, line3)


def _check_3_30(f):
    fb = free_body_model(3)
    line2, line3 = f
    I = general_inertia_symbols()
    filled = line3.subs({I[a, b]: fb.inertia_cm[a, b] for a in range(3) for b in range(a, 3)}, simultaneous=True)
    filled = filled.subs(_M, fb.M)
    first = same(line2, fb.kinetic_energy, "line 2 vs ½Σm ṙ² (any reference point)")
    if not first.passed:  # fail fast on a wrong formula
        return first
    return all_pass([first, same(filled, fb.kinetic_energy_at_cm, "line 3 vs ½Σm ṙ² with Σ m Δr = 0")])


register(Claim(
    "3.30", "3.3",
    "with r_i = R + Δr_i (3.29) and Σ m Δr_i = 0: T = ½MṘ² + ½ω_a I_ab ω_b (centre of mass + rotation)",
    "symbolic", printed=_printed_3_30, check=_check_3_30, parts=("line 2", "line 3"),
))
