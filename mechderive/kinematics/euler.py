"""Rotations and Euler angles (sections 3.1, 3.1.1, 3.5): numeric functions, and the derivations on demand.

Convention (the chapter's, kept throughout the toolkit): e_a = R_ab ẽ_b, so the *rows* of R are
the body axes in space components and R is the *passive* rotation; Euler angles (3.50)–(3.54):
R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ).

This module imports no SymPy.  The numeric functions (:func:`rotation_matrix`,
:func:`angular_velocity_body`, :func:`angular_velocity_space`, :func:`euler_angles_from_matrix`)
come from :mod:`.rotations`; the symbolic ones (:func:`model`, :class:`KinematicsModel`,
:func:`generator`, :func:`axis_rotation`, :func:`euler_rotation`) are derived in
:mod:`.euler_symbolic` and loaded, with SymPy, the first time one of them is asked for.

>>> import numpy as np
>>> R = rotation_matrix(0.3, 0.5, 0.7)
>>> bool(np.allclose(R @ R.T, np.eye(3)))
True
"""

from __future__ import annotations

import importlib
from typing import Any

from .rotations import angular_velocity_body, angular_velocity_space, euler_angles_from_matrix, rotation_matrix

__all__ = [
    "KinematicsModel",
    "model",
    "generator",
    "axis_rotation",
    "euler_rotation",
    "rotation_matrix",
    "angular_velocity_body",
    "angular_velocity_space",
    "euler_angles_from_matrix",
]

_SYMBOLIC = frozenset({"KinematicsModel", "model", "generator", "axis_rotation", "euler_rotation"})


def __getattr__(name: str) -> Any:
    if name in _SYMBOLIC:
        value = getattr(importlib.import_module(f"{__name__}_symbolic"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
