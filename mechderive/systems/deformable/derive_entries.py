"""The falling cat's formulas for ``derive`` (section 3.7); it has no symbols for ``check``.

:func:`derivations` lists what ``mechderive derive falling_cat`` prints: the gauge potential,
field strength and the body quantities of the two jointed halves, derived in :mod:`.cat`.
"""

from __future__ import annotations

import functools

import sympy as sp

from ..base import Derivation, Derivations

__all__ = ["derivations", "check_system"]

#: the title of ``derive``'s output
_SUMMARY = "the falling cat, two jointed halves (section 3.7)"


def _cat():
    from .cat import cat_body

    return cat_body()


@functools.cache
def derivations() -> Derivations:
    """What ``mechderive derive falling_cat`` can print, defaults first (Ω_bend, Ω_swivel, F)."""
    return Derivations((
        Derivation("Omega_bend", "gauge potential Ω_A for A = bend (Ω = Ω_A ẋ^A at L = 0)", "3.87",
                   lambda o: _cat().connection[0], lhs=lambda: sp.Symbol("Omega_bend"), default=True),
        Derivation("Omega_swivel", "gauge potential Ω_A for A = swivel", "3.87",
                   lambda o: _cat().connection[1], lhs=lambda: sp.Symbol("Omega_swivel"), default=True),
        Derivation("field_strength", "F_AB, A = bend, B = swivel (as corrected in catalog 3.7)", "3.103",
                   lambda o: _cat().field_strength[0][1], lhs=lambda: sp.Symbol("F_bend,swivel"), default=True),
        Derivation("angular_velocity", "Ω = R⁻¹Ṙ = hat(Ĩ⁻¹ L̃) at L = 0", "3.92",
                   lambda o: _cat().angular_velocity, lhs=lambda: sp.Symbol("Omega")),
        Derivation("inertia_tensor", "Ĩ of the shape", "3.93", lambda o: _cat().inertia_tensor,
                   lhs=lambda: sp.Symbol("Itilde")),
        Derivation("apparent_angular_momentum", "L̃ of the shape change", "3.94",
                   lambda o: _cat().apparent_angular_momentum, lhs=lambda: sp.Symbol("Ltilde")),
    ), summary=_SUMMARY)


def check_system() -> None:
    """The falling cat has no symbol table for ``mechderive check`` (None)."""
    return None
