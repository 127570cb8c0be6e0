"""Numbers from a :class:`~.model.DeformableBody`: compiled Ĩ, Ω_A (3.87), Ω (3.92), F_AB (3.102).

Every function here is compiled from the model's derived expressions by
:meth:`SymbolicModel.compile` (lambdify with cse, cached); nothing is re-derived.
Arrays broadcast over leading dimensions: a shape ``x`` has shape (..., n), a shape
velocity the same.  Vectors of so(3) are in the hat convention of section 3.7's
package (Ω = hat(v), hat(v)_ab = ε_abc v_c), ready for
:func:`mechderive.kinematics.path_ordered.path_ordered_exponential`.

>>> import sympy as sp
>>> from mechderive.systems.deformable.model import DeformableBody
>>> x = sp.Symbol("x", real=True)
>>> arm = [(1, x, 0), (-1, -x, 0), (0, 0, 1), (0, 0, -1)]   # a dumbbell turning in the 1-2 plane, and a fixed one
>>> body = DeformableBody([1, 1, 1, 1], arm, [x])
>>> body.numeric().connection([0.0])     # Ω_x = hat(v), v = (0, 0, 1/(1 + x²)): the body turns back
array([[0., 0., 1.]])
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
import sympy as sp

from ...core.validate import as_finite_array
from ...errors import InvalidInputError, ShapeError
from .derivation import vee

__all__ = ["ShapeConnection"]


class ShapeConnection:
    """The compiled numeric side of a :class:`~.model.DeformableBody` at fixed parameter values.

    Attributes
    ----------
    body : DeformableBody
    values : dict[str, float]
        The parameter values, by name.
    masses : ndarray, shape (N,)
    """

    def __init__(self, body: Any, values: Mapping[Any, float] | None = None) -> None:
        self.body = body
        given = dict(values or {})
        names = [p.name for p in body.parameters]
        by_name: dict[str, float] = {}
        for key, value in given.items():
            name = key.name if isinstance(key, sp.Symbol) else key
            if not isinstance(name, str) or name not in names:
                raise InvalidInputError(f"unknown parameter {key!r}: expected one of {', '.join(names) or '(none)'}")
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise InvalidInputError(f"expected parameter `{name}` to be a number, got {value!r}")
            by_name[name] = float(as_finite_array(value, name, shape=()))
        missing = [n for n in names if n not in by_name]
        if missing:
            raise InvalidInputError(f"missing parameter {missing[0]!r}: expected values for all of {', '.join(names)}")
        self.values = by_name
        self._params = [by_name[n] for n in names]
        args = [*body.coordinates, *body.parameters]
        self.masses = np.array(body.compile("masses", sp.Matrix(body.masses), list(body.parameters))(*self._params),
                               dtype=float).reshape(-1)
        if np.any(self.masses <= 0):
            raise InvalidInputError(f"expected every mass > 0, got {self.masses.min():g}")
        self._args = args

    @property
    def dimension(self) -> int:
        """n, the number of shape coordinates."""
        return self.body.dimension

    def _shape(self, x: Any, name: str = "x") -> list[np.ndarray]:
        arr = as_finite_array(x, name)
        if arr.ndim < 1 or arr.shape[-1] != self.dimension:
            raise ShapeError(f"expected `{name}` to have shape (..., {self.dimension}), got {arr.shape}")
        return [arr[..., A] for A in range(self.dimension)]

    def _call(self, name: str, exprs: Any, extra: tuple = (), *values: np.ndarray) -> np.ndarray:
        f = self.body.compile(name, exprs, [*self.body.coordinates, *extra, *self.body.parameters])
        return f(*values, *self._params)

    def positions(self, x: Any) -> np.ndarray:
        """r̃_i(x), shape (..., N, 3)."""
        return self._call("positions", sp.Matrix([list(r) for r in self.body.positions]), (), *self._shape(x))

    def inertia(self, x: Any) -> np.ndarray:
        """Ĩ(x) (3.93), shape (..., 3, 3)."""
        return self._call("inertia_tensor", self.body.inertia_tensor, (), *self._shape(x))

    def _check_invertible(self, x: Any) -> None:
        det = np.linalg.det(self.inertia(x))
        if np.any(det <= 0):
            raise InvalidInputError("expected shapes with an invertible inertia tensor (masses not all on one line), "
                                    f"got det Ĩ = {float(np.min(det)):.3g}")

    def connection(self, x: Any) -> np.ndarray:
        """The vectors of Ω_A(x) (3.87), shape (..., n, 3): Ω_A = hat(row A)."""
        with np.errstate(divide="ignore", invalid="ignore"):  # a singular Ĩ is reported below
            out = self._call("connection", self.body.connection_vectors, (), *self._shape(x))
        if not np.all(np.isfinite(out)):
            self._check_invertible(x)
        return out

    def angular_velocity(self, x: Any, xdot: Any) -> np.ndarray:
        """v with Ω = hat(v) = Ω_A ẋ^A (3.87), (3.92), shape (...); x and ẋ broadcast."""
        xs, vs = self._shape(x), self._shape(xdot, "xdot")
        out = self._call("angular_velocity", self.body.angular_velocity_vector, tuple(self.body.velocities), *xs, *vs)
        out = np.asarray(out)
        return out[..., 0] if out.shape[-1:] == (1,) else out

    def field_strength(self, x: Any) -> np.ndarray:
        """The vectors of F_AB(x) (the corrected (3.103)), shape (..., n, n, 3), antisymmetric in A, B."""
        return self._call("field_strength", self.body.field_strength_vectors, (), *self._shape(x))

    def connection_derivatives(self, x: Any) -> np.ndarray:
        """The vectors of ∂Ω_A/∂x^B, shape (..., n, n, 3) indexed [A, B]."""
        exprs = [[list(vee(d)) for d in row] for row in self.body.connection_derivatives]
        return self._call("connection_derivatives", exprs, (), *self._shape(x))
