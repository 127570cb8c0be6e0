"""The result of an inertia computation: mass, centre of mass, inertia tensor about it.

:class:`BodyInertia` holds either SymPy objects (a derivation's result) or NumPy
arrays (numbers, possibly batched: mass (...), centre of mass (..., 3), tensor
(..., 3, 3)).  Numeric instances are validated when built (habit 6): mass > 0
and a physical tensor (:func:`check_inertia_tensor`; ``line_body=True`` admits
the zero moment of a rod).  Components are body components in the body's own
coordinates (each body documents its origin and axes).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
import sympy as sp

from ..core.validate import as_finite_array
from ..errors import InvalidInputError, ShapeError
from ..formulas.parse import as_expression, as_matrix
from .parallel_axis_theorem import parallel_axis, parallel_axis_symbolic
from .validate import check_inertia_tensor

__all__ = ["BodyInertia"]


@dataclass(frozen=True)
class BodyInertia:
    """Mass M, centre of mass, and inertia tensor about the centre of mass.

    >>> b = BodyInertia(12.0, [0.0, 0.0, 0.0], np.diag([1.0, 1.0, 0.0]), line_body=True)  # rod M=12, l=1
    >>> float(b.inertia_about([0.0, 0.0, 0.5])[0, 0])                                   # about its end, (3.25)
    4.0
    """

    mass: Any
    centre_of_mass: Any
    inertia_cm: Any
    line_body: bool = field(default=False, kw_only=True)

    @property
    def is_symbolic(self) -> bool:
        """Whether the fields are SymPy objects."""
        return isinstance(self.inertia_cm, sp.MatrixBase)

    def __post_init__(self) -> None:
        if self.is_symbolic:
            com = as_matrix(self.centre_of_mass, "`centre_of_mass`")
            if com.shape != (3, 1) or self.inertia_cm.shape != (3, 3):
                raise ShapeError(f"expected a 3-vector and a 3x3 tensor, got {com.shape} and {self.inertia_cm.shape}")
            object.__setattr__(self, "centre_of_mass", com)
            object.__setattr__(self, "mass", as_expression(self.mass, "`mass`"))
            return
        M = as_finite_array(self.mass, "mass")
        if np.any(M <= 0):
            raise InvalidInputError(f"expected `mass` > 0, got {float(M[M <= 0].ravel()[0])!r}")
        com = as_finite_array(self.centre_of_mass, "centre_of_mass")
        if com.ndim < 1 or com.shape[-1] != 3:
            raise ShapeError(f"expected `centre_of_mass` to have shape (..., 3), got {com.shape}")
        I = check_inertia_tensor(self.inertia_cm, line_body=self.line_body)
        object.__setattr__(self, "mass", M if M.ndim else float(M))
        object.__setattr__(self, "centre_of_mass", com)
        object.__setattr__(self, "inertia_cm", I)

    def inertia_about(self, point: Any) -> Any:
        """The inertia tensor about ``point`` (body coordinates) by the parallel axis theorem (3.25)."""
        if self.is_symbolic:
            return parallel_axis_symbolic(self.inertia_cm, self.mass, as_matrix(point, "`point`") - self.centre_of_mass)
        p = as_finite_array(point, "point")
        return parallel_axis(self.inertia_cm, self.mass, p - self.centre_of_mass)

    def as_numeric(self) -> "BodyInertia":
        """The same quantities as floats (a symbolic instance must have no free symbols left)."""
        if not self.is_symbolic:
            return self
        free = self.inertia_cm.free_symbols | self.centre_of_mass.free_symbols | self.mass.free_symbols
        if free:
            names = ", ".join(sorted(map(str, free)))
            raise InvalidInputError(f"expected no free symbols to make numbers, got {names}")
        return BodyInertia(float(self.mass), np.array(self.centre_of_mass, dtype=float).ravel(),
                           np.array(self.inertia_cm, dtype=float), line_body=self.line_body)

    def subs(self, values: dict) -> "BodyInertia":
        """A symbolic instance with ``values`` substituted (e.g. dimensions)."""
        if not self.is_symbolic:
            raise InvalidInputError("expected a symbolic BodyInertia to substitute into, got a numeric one")
        if not isinstance(values, Mapping):
            raise InvalidInputError(f"expected `values` as a mapping symbol -> value, got {type(values).__name__}")
        # subs would evaluate text keys and values: both must be SymPy objects or numbers.
        checked = {as_expression(k, "each key of `values`"): as_expression(v, f"the value of {k}")
                   for k, v in values.items()}
        return BodyInertia(self.mass.subs(checked), self.centre_of_mass.subs(checked),
                           self.inertia_cm.subs(checked), line_body=self.line_body)
