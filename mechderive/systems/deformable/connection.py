"""Numbers from a :class:`~.model.DeformableBody`: compiled Ĩ, Ω_A (3.87), Ω (3.92), F_AB (3.102).

Every function here is compiled from the model's derived expressions by
:meth:`SymbolicModel.compile` (lambdify with cse, cached in memory) or, for a connection made by
:meth:`ShapeConnection.cached`, by :func:`~mechderive.core.compile.compile_cached` (the generated
code kept on disk: a warm process neither derives nor imports SymPy); nothing is re-derived.
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

import sys
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from ...core.validate import as_finite_array
from ...errors import InvalidInputError, ShapeError

# SymPy is imported only where a body is derived or compiled (inside the builders below): a
# connection loaded from the disk cache (ShapeConnection.cached) never imports it.

__all__ = ["ShapeConnection"]


class ShapeConnection:
    """The compiled numeric side of a :class:`~.model.DeformableBody` at fixed parameter values.

    Built by :meth:`DeformableBody.numeric` (compiled in memory from the given body), or by
    :meth:`ShapeConnection.cached` (compiled functions kept in the disk cache under a name, the body
    derived only on a miss).

    Attributes
    ----------
    body : DeformableBody
        The symbolic body (for a cached connection: derived on first access).
    values : dict[str, float]
        The parameter values, by name.
    masses : ndarray, shape (N,)
    """

    def __init__(self, body: Any, values: Mapping[Any, float] | None = None) -> None:
        self._body = body
        self._init([p.name for p in body.parameters], body.dimension, values, cache_name=None, build_body=None)

    @classmethod
    def cached(cls, name: str, build_body: Callable[[], Any], *, dimension: int, parameters: Sequence[str],
               values: Mapping[Any, float] | None = None) -> "ShapeConnection":
        """The connection of the body ``build_body()`` with its compiled functions in the disk cache.

        Each function is :func:`~mechderive.core.compile.compile_cached` under ``"<name>.<quantity>"``
        (e.g. ``"deformable.cat.connection"``) with the body's parameters as arguments, so ``name``
        must identify the body (not its parameter values).  ``build_body`` — deriving with SymPy —
        runs only when a function is in neither memory nor the disk cache; ``dimension`` and the
        parameter names (in the order of the body's parameters) are given so that a warm process
        needs no body at all.
        """
        self = cls.__new__(cls)
        self._body = None
        self._init(list(parameters), int(dimension), values, cache_name=name, build_body=build_body)
        return self

    def _init(self, names: list[str], dimension: int, values: Mapping[Any, float] | None, *,
              cache_name: str | None, build_body: Callable[[], Any] | None) -> None:
        self._cache_name, self._build_body, self._dimension = cache_name, build_body, dimension
        self._functions: dict[str, Callable[..., np.ndarray]] = {}
        given = dict(values or {})
        by_name: dict[str, float] = {}
        sympy = sys.modules.get("sympy")  # a SymPy symbol as a key implies SymPy is imported
        for key, value in given.items():
            name = key.name if sympy is not None and isinstance(key, sympy.Symbol) else key
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

        def masses(body: Any) -> Any:
            import sympy as sp

            return sp.Matrix(body.masses)
        self.masses = np.array(self._function("masses", masses, coordinates=False)(*self._params),
                               dtype=float).reshape(-1)
        if np.any(self.masses <= 0):
            raise InvalidInputError(f"expected every mass > 0, got {self.masses.min():g}")

    @property
    def body(self) -> Any:
        """The symbolic :class:`~.model.DeformableBody` (for a cached connection: derived now if not yet)."""
        if self._body is None:
            self._body = self._build_body()
        return self._body

    @property
    def dimension(self) -> int:
        """n, the number of shape coordinates."""
        return self._dimension

    def _shape(self, x: Any, name: str = "x") -> list[np.ndarray]:
        arr = as_finite_array(x, name)
        if arr.ndim < 1 or arr.shape[-1] != self.dimension:
            raise ShapeError(f"expected `{name}` to have shape (..., {self.dimension}), got {arr.shape}")
        return [arr[..., A] for A in range(self.dimension)]

    def _function(self, name: str, exprs: Callable[[Any], Any], *, coordinates: bool = True,
                  velocities: bool = False) -> Callable[..., np.ndarray]:
        """The compiled ``exprs(body)`` with arguments (x^A, [ẋ^A,] parameters), or (parameters) alone.

        ``exprs`` is called — deriving — only when the function is compiled, not when it is
        loaded from the disk cache.
        """
        f = self._functions.get(name)
        if f is not None:
            return f

        def build() -> tuple[list, Any]:
            body = self.body
            args = [*(body.coordinates if coordinates else ()), *(body.velocities if velocities else ()),
                    *body.parameters]
            return args, exprs(body)

        if self._cache_name is None:
            args, e = build()
            f = self.body.compile(name, e, args)
        else:
            from ...core.compile import compile_cached

            f = compile_cached(f"{self._cache_name}.{name}", build)
        self._functions[name] = f
        return f

    def _call(self, name: str, exprs: Callable[[Any], Any], *values: np.ndarray, velocities: bool = False) -> np.ndarray:
        return self._function(name, exprs, velocities=velocities)(*values, *self._params)

    def positions(self, x: Any) -> np.ndarray:
        """r̃_i(x), shape (..., N, 3)."""
        def exprs(body: Any) -> Any:
            import sympy as sp

            return sp.Matrix([list(r) for r in body.positions])
        return self._call("positions", exprs, *self._shape(x))

    def inertia(self, x: Any) -> np.ndarray:
        """Ĩ(x) (3.93), shape (..., 3, 3)."""
        return self._call("inertia_tensor", lambda body: body.inertia_tensor, *self._shape(x))

    def _check_invertible(self, x: Any) -> None:
        det = np.linalg.det(self.inertia(x))
        if np.any(det <= 0):
            raise InvalidInputError("expected shapes with an invertible inertia tensor (masses not all on one line), "
                                    f"got det Ĩ = {float(np.min(det)):.3g}")

    def connection(self, x: Any) -> np.ndarray:
        """The vectors of Ω_A(x) (3.87), shape (..., n, 3): Ω_A = hat(row A).

        Ω_A = Ĩ⁻¹L̃_A needs an invertible Ĩ: a shape with det Ĩ ≤ 0 is refused.  Where Ω_A is written over
        det Ĩ, a singular Ĩ shows as a value that is not finite, and only then is Ĩ checked; where factors
        of det Ĩ were cancelled (:attr:`DeformableBody.cancels_singular_factors`, e.g. the cat's Ω_swivel =
        L̃_1/Ĩ_11), Ω_A can stay finite there, and Ĩ is checked at every shape (also for a connection loaded
        from the disk cache, whose body is not derived).
        """
        with np.errstate(divide="ignore", invalid="ignore"):  # a singular Ĩ is reported below
            out = self._call("connection", lambda body: body.connection_vectors, *self._shape(x))
        cancelled = self._body is None or self._body.cancels_singular_factors
        if cancelled or not np.all(np.isfinite(out)):
            self._check_invertible(x)
        return out

    def angular_velocity(self, x: Any, xdot: Any) -> np.ndarray:
        """v with Ω = hat(v) = Ω_A ẋ^A (3.87), (3.92), shape (...); x and ẋ broadcast."""
        xs, vs = self._shape(x), self._shape(xdot, "xdot")
        out = self._call("angular_velocity", lambda body: body.angular_velocity_vector, *xs, *vs, velocities=True)
        out = np.asarray(out)
        return out[..., 0] if out.shape[-1:] == (1,) else out

    def field_strength(self, x: Any) -> np.ndarray:
        """The vectors of F_AB(x) (the corrected (3.103)), shape (..., n, n, 3), antisymmetric in A, B."""
        return self._call("field_strength", lambda body: body.field_strength_vectors, *self._shape(x))

    def connection_derivatives(self, x: Any) -> np.ndarray:
        """The vectors of ∂Ω_A/∂x^B, shape (..., n, n, 3) indexed [A, B]."""
        def exprs(body: Any) -> Any:
            from .derivation import vee

            return [[list(vee(d)) for d in row] for row in body.connection_derivatives]
        return self._call("connection_derivatives", exprs, *self._shape(x))
