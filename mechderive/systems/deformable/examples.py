"""Small bodies used by the catalog, the tests and the derivation script of section 3.7.

:func:`three_mass_body` is a deliberately generic body: three unit masses whose
positions are polynomials in two shape coordinates (x, y), with the centre of mass at
the origin by construction.  Its gauge potentials Ω_x, Ω_y do not commute and depend
on the shape, so every term of (3.101)–(3.103) is non-zero — unlike the falling cat of
:mod:`.cat`, whose connection stays along one axis.

:func:`gauge_rotation` is a non-trivial change of representative S(x, y) (3.88).

>>> body = three_mass_body()
>>> [str(x) for x in body.coordinates]
['x', 'y']
"""

from __future__ import annotations

import functools

import sympy as sp

from ...kinematics.euler import axis_rotation
from .model import DeformableBody

__all__ = ["three_mass_body", "gauge_rotation", "BASE_SHAPE", "shape_symbols"]

#: A shape (x, y) at which the test body is examined (exact rationals).
BASE_SHAPE = (sp.Rational(3, 10), sp.Rational(1, 2))


@functools.cache
def shape_symbols() -> tuple[sp.Symbol, sp.Symbol]:
    """The shape coordinates (x, y) of :func:`three_mass_body`."""
    return sp.symbols("x y", real=True)


@functools.cache
def three_mass_body() -> DeformableBody:
    """Unit masses at (1, x, 0), (−1, 0, y), (0, −x, −y): Σ m r̃ = 0 for every (x, y)."""
    x, y = shape_symbols()
    return DeformableBody([1, 1, 1], [(1, x, 0), (-1, 0, y), (0, -x, -y)], [x, y])


@functools.cache
def gauge_rotation() -> sp.Matrix:
    """S(x, y) = Q3(x) Q1(y/2 + x y): active rotations about e3 and e1 (transposes of (3.51)–(3.52))."""
    x, y = shape_symbols()
    return axis_rotation(3, x).T * axis_rotation(1, y / 2 + x * y).T
