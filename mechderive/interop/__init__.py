"""Interoperation with other libraries: :mod:`.mechanics` exports to :mod:`sympy.physics.mechanics`.

The SciPy ``Rotation`` conversions live in :mod:`mechderive.kinematics.conversions` and, for every
Euler sequence, :func:`mechderive.derive.sequences.scipy_sequence`.
"""

from .mechanics import MechanicsModel, to_mechanics

__all__ = ["MechanicsModel", "to_mechanics"]
