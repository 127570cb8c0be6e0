"""Deformable bodies, section 3.7: gauge potential, Wilson loop, field strength, the falling cat.

Modules, one job each:

- :mod:`.derivation` — the body-independent derivations (3.90)–(3.97) and (3.102);
- :mod:`.model` — :class:`DeformableBody`: point masses at r̃_i(x), with Ĩ (3.93), L̃ (3.94),
  Ω (3.92), Ω_A (3.87), F_AB (3.103, corrected) derived lazily, and gauge changes (3.88);
- :mod:`.connection` — the compiled numbers of a body (:meth:`DeformableBody.numeric`);
- :mod:`.holonomy` — loops in shape space and the net rotation P̃ exp ∮ Ω_A dx^A (3.98);
- :mod:`.cat` — a falling cat that turns over with L = 0, and its time series for scenes;
- :mod:`.examples` — a small generic test body.

Convention of section 3.7: r_i = R r̃_i, R acting on column vectors (the active
rotation, R(3.1) = R(3.7)ᵀ), Ω = R⁻¹Ṙ, hat(v)_ab = ε_abc v_c.
"""

from typing import Any

from .cat import falling_cat, falling_cat_motion, flip_bend
from .connection import ShapeConnection
from .holonomy import Holonomy, ShapeLoop, net_rotation, rotation_along

__all__ = [
    "DeformableBody",
    "Holonomy",
    "ShapeConnection",
    "ShapeLoop",
    "centred_positions",
    "falling_cat",
    "falling_cat_motion",
    "flip_bend",
    "net_rotation",
    "rotation_along",
]


def __getattr__(name: str) -> Any:
    # The symbolic model imports SymPy: loaded on first use, so that a falling cat whose compiled
    # functions are in the disk cache runs without SymPy (PEP 562).
    if name in ("DeformableBody", "centred_positions"):
        from . import model

        return getattr(model, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
