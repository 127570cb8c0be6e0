"""The exception hierarchy of mechderive.

Every error the toolkit raises on bad input derives from :class:`MechDeriveError`,
so that callers can catch one class.  Messages say what was wrong and what is
allowed, in the form "expected X, got Y".
"""

from __future__ import annotations

__all__ = [
    "MechDeriveError",
    "InvalidInputError",
    "NonFiniteValueError",
    "ShapeError",
    "NotARotationError",
    "UnphysicalInertiaError",
    "DerivationError",
    "IntegrationError",
    "ArgumentError",
    "BenchmarkError",
]


class MechDeriveError(Exception):
    """Base class of every error raised by mechderive."""


class InvalidInputError(MechDeriveError, ValueError):
    """A value is outside what the toolkit accepts (wrong range, type or form)."""


class NonFiniteValueError(InvalidInputError):
    """A NaN or infinite number was given where a finite one is needed."""


class ShapeError(InvalidInputError):
    """An array has the wrong shape."""


class NotARotationError(InvalidInputError):
    """A matrix is not a proper rotation (orthogonal with determinant +1)."""


class UnphysicalInertiaError(InvalidInputError):
    """Moments of inertia that no body can have (negative, or violating I1 + I2 >= I3)."""


class ArgumentError(InvalidInputError, TypeError):
    """A function was called with the wrong number or kind of arguments."""


class DerivationError(MechDeriveError, RuntimeError):
    """A symbolic derivation did not produce what it must (an internal consistency failure)."""


class IntegrationError(MechDeriveError, RuntimeError):
    """An ODE solver failed (e.g. a torque that blows the solution up)."""


class BenchmarkError(MechDeriveError, RuntimeError):
    """A timed benchmark run (a subprocess of ``mechderive bench``) failed."""
