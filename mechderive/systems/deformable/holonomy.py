"""Net rotation around a loop in shape space: the Wilson loop R = P̃ exp ∮ Ω_A dx^A (3.98).

A body that changes its shape along x(t), t ∈ [t0, t1], with zero angular momentum,
turns by R(t) solving Ṙ = R Ω, Ω = Ω_A(x) ẋ^A (3.86)–(3.87), R(t0) = 1.  The solution
is the path-ordered exponential with later times to the RIGHT (3.98), computed here by
:func:`mechderive.kinematics.path_ordered.path_ordered_exponential` with
``ordering="right"`` (Magnus steps of order 4 or 6, adaptive, with its error estimate).
For a closed loop (the same shape at both ends) R is the net rotation.

Convention (section 3.7): R acts on column vectors, r_i(t) = R(t) r̃_i(x(t)) — the
active rotation; section 3.1's R is its transpose.  Ω = hat(v), hat(v)_ab = ε_abc v_c.

Loops are :class:`ShapeLoop` objects, built from

- samples ``(times, shapes)`` (a cubic spline: accuracy O(Δt⁴), limited by the samples),
- Python functions x(t) and ẋ(t) (:meth:`ShapeLoop.from_functions`), or
- SymPy expressions of the loop parameter (:meth:`ShapeLoop.from_expressions`; ẋ by SymPy).

The loop parameter is the time (s).  A loop is closed when the *shape* comes back —
r̃_i(x(t1)) = r̃_i(x(t0)) — so an angle coordinate may wind by 2π.

>>> import sympy as sp
>>> from mechderive.systems.deformable.model import DeformableBody
>>> x = sp.Symbol("x", real=True)
>>> body = DeformableBody([1, 1, 1, 1], [(1, x, 0), (-1, -x, 0), (0, 0, 1), (0, 0, -1)], [x]).numeric()
>>> s = sp.Symbol("s", real=True)
>>> there_and_back = ShapeLoop.from_expressions([sp.sin(s)], s, (0, 2 * sp.pi))
>>> bool(abs(net_rotation(body, there_and_back).R - np.eye(3)).max() < 1e-12)   # no area enclosed
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from ...core.compile import compile_expressions
from ...core.validate import as_finite_array
from ...errors import InvalidInputError, ShapeError
from ...kinematics.path_ordered import path_ordered_exponential

if TYPE_CHECKING:  # SymPy is imported at run time only to build loops from expressions
    import sympy

__all__ = ["ShapeLoop", "Holonomy", "net_rotation", "rotation_along"]


@dataclass(frozen=True)
class ShapeLoop:
    """A path x(t) in shape space with its velocity ẋ(t), t ∈ ``span`` (s).

    ``shape`` and ``velocity`` map times of shape (N,) to arrays of shape (N, n).
    """

    shape: Callable[[np.ndarray], np.ndarray]
    velocity: Callable[[np.ndarray], np.ndarray]
    span: tuple[float, float]
    dimension: int

    # ------------------------------------------------------------ constructors
    @classmethod
    def from_functions(cls, shape: Callable, velocity: Callable, span: Any) -> "ShapeLoop":
        """From vectorised functions x(t) and ẋ(t), times (N,) → (N, n).

        >>> loop = ShapeLoop.from_functions(lambda t: np.stack([np.cos(t), np.sin(t)], -1),
        ...                                 lambda t: np.stack([-np.sin(t), np.cos(t)], -1), (0, 2 * np.pi))
        >>> loop.dimension
        2
        """
        t0, t1 = _check_span(span)
        if not (callable(shape) and callable(velocity)):
            raise InvalidInputError(f"expected callables shape(t) and velocity(t), got {type(shape).__name__} "
                                    f"and {type(velocity).__name__}")
        probe = np.array([t0, t1])
        xs = as_finite_array(shape(probe), "shape(t)")
        vs = as_finite_array(velocity(probe), "velocity(t)")
        if xs.ndim != 2 or xs.shape[0] != 2 or vs.shape != xs.shape:
            raise ShapeError(f"expected shape(t) and velocity(t) of shape (N, n) for times of shape (N,), "
                             f"got {xs.shape} and {vs.shape} for N = 2")
        return cls(shape, velocity, (t0, t1), xs.shape[1])

    @classmethod
    def from_samples(cls, times: Any, shapes: Any) -> "ShapeLoop":
        """From samples x(t_k): a cubic spline (periodic when the coordinates close, else not-a-knot).

        The velocity is the spline's derivative, so the accuracy is O(Δt⁴) in the samples' spacing.
        """
        from scipy.interpolate import CubicSpline

        ts = as_finite_array(times, "times", shape=(None,))
        xs = as_finite_array(shapes, "shapes")
        if xs.ndim != 2 or xs.shape[0] != len(ts):
            raise ShapeError(f"expected `shapes` of shape ({len(ts)}, n) to match `times`, got {xs.shape}")
        if len(ts) < 4:
            raise InvalidInputError(f"expected at least 4 samples for a cubic spline, got {len(ts)}")
        if not np.all(np.diff(ts) > 0):
            raise InvalidInputError("expected strictly increasing `times`, got a non-increasing step")
        periodic = np.allclose(xs[0], xs[-1], rtol=0, atol=1e-12 * max(1.0, float(np.abs(xs).max())))
        if periodic:  # SciPy needs the end value repeated exactly
            spline = CubicSpline(ts, np.vstack([xs[:-1], xs[:1]]), axis=0, bc_type="periodic")
        else:
            spline = CubicSpline(ts, xs, axis=0, bc_type="not-a-knot")
        rate = spline.derivative()
        return cls(lambda t: spline(np.asarray(t, dtype=float)), lambda t: rate(np.asarray(t, dtype=float)),
                   (float(ts[0]), float(ts[-1])), xs.shape[1])

    @classmethod
    def from_expressions(cls, expressions: Sequence[Any], parameter: sympy.Symbol, span: Any) -> "ShapeLoop":
        """From SymPy expressions x^A(s) of the loop parameter ``s`` (time, s); ẋ^A = dx^A/ds by SymPy.

        >>> import sympy as sp
        >>> s = sp.Symbol("s", real=True)
        >>> ShapeLoop.from_expressions([s**2, sp.sin(s)], s, (0, 2 * sp.pi)).velocity(np.array([1.0]))
        array([[2.        , 0.54030231]])
        """
        import sympy as sp  # only here: loops from functions or samples need no SymPy

        if not isinstance(parameter, sp.Symbol):
            raise InvalidInputError(f"expected the loop parameter as a SymPy symbol, got {type(parameter).__name__}")
        exprs = list(expressions)
        for e in exprs:
            if not isinstance(e, (sp.Basic, int, float)) or isinstance(e, bool):
                raise InvalidInputError(f"expected SymPy expressions of {parameter}, got {type(e).__name__} {e!r}")
        exprs = [e if isinstance(e, sp.Basic) else sp.Float(e) for e in exprs]
        stray = set().union(*(e.free_symbols for e in exprs)) - {parameter}
        if stray:
            raise InvalidInputError(f"expected expressions of {parameter} only, got the symbols {sorted(map(str, stray))}")
        span_values = [float(sp.N(v)) if isinstance(v, sp.Basic) else v for v in span] \
            if isinstance(span, (tuple, list)) else span
        x = compile_expressions(exprs, [parameter], name="loop_shape")
        v = compile_expressions([sp.diff(e, parameter) for e in exprs], [parameter], name="loop_velocity")
        n = len(exprs)

        def shape(t: np.ndarray) -> np.ndarray:
            return np.broadcast_to(x(np.asarray(t, dtype=float)), np.shape(t) + (n,))

        def velocity(t: np.ndarray) -> np.ndarray:
            return np.broadcast_to(v(np.asarray(t, dtype=float)), np.shape(t) + (n,))

        return cls.from_functions(shape, velocity, span_values)

    # ------------------------------------------------------------ transformations
    def reparametrised(self, sigma: Callable, sigma_dot: Callable, span: Any) -> "ShapeLoop":
        """The same path at another pace: t ↦ x(σ(t)), ẋ = x'(σ) σ̇, for σ increasing from span to ``self.span``.

        >>> loop = ShapeLoop.from_functions(lambda t: t[:, None] ** 2, lambda t: 2 * t[:, None], (0, 1))
        >>> slow = loop.reparametrised(lambda u: u / 2, lambda u: 0.5 + 0 * u, (0, 2))
        >>> slow.velocity(np.array([1.0]))
        array([[0.5]])
        """
        u0, u1 = _check_span(span)
        ends = np.asarray(sigma(np.array([u0, u1])), dtype=float)
        if not np.allclose(ends, self.span, rtol=0, atol=1e-12 * max(1.0, abs(self.span[1]))):
            raise InvalidInputError(f"expected σ to map {(u0, u1)} onto {self.span}, got {tuple(ends)}")

        def shape(u: np.ndarray) -> np.ndarray:
            return self.shape(np.asarray(sigma(u), dtype=float))

        def velocity(u: np.ndarray) -> np.ndarray:
            return self.velocity(np.asarray(sigma(u), dtype=float)) * np.asarray(sigma_dot(u), dtype=float)[..., None]

        return ShapeLoop.from_functions(shape, velocity, (u0, u1))


@dataclass(frozen=True)
class Holonomy:
    """The rotation R(t) = P̃ exp ∫_{t0}^t Ω dt' (3.98) along a path in shape space.

    Attributes
    ----------
    R : ndarray (3, 3)
        R at the end of the path: for a closed loop, the net rotation (section 3.7's active R).
    t : ndarray (N,)
        Output times (s).
    rotations : ndarray (N, 3, 3)
        R(t) at those times.
    error_estimate : float
        The integrator's estimate of the global error of R at the end, as an angle (rad).
    steps : int
        Accepted Magnus steps.
    closure : float
        max_i |r̃_i(x(t1)) − r̃_i(x(t0))| (length units): 0 for a closed loop.
    """

    R: np.ndarray
    t: np.ndarray
    rotations: np.ndarray
    error_estimate: float
    steps: int
    closure: float


def _check_span(span: Any) -> tuple[float, float]:
    arr = as_finite_array(span, "span", shape=(2,))
    t0, t1 = float(arr[0]), float(arr[1])
    if not t1 > t0:
        raise InvalidInputError(f"expected span (t0, t1) with t1 > t0, got ({t0}, {t1})")
    return t0, t1


def _as_loop(loop: Any) -> ShapeLoop:
    if isinstance(loop, ShapeLoop):
        return loop
    if isinstance(loop, tuple) and len(loop) == 2:
        return ShapeLoop.from_samples(*loop)
    raise InvalidInputError(f"expected a ShapeLoop or a (times, shapes) pair of arrays, got {type(loop).__name__}")


def _angular_velocity(connection: Any, loop: ShapeLoop) -> Callable[[np.ndarray], np.ndarray]:
    """t ↦ v(t) with Ω(t) = hat(v) = Ω_A(x(t)) ẋ^A(t) (3.87), shape (N, 3)."""
    def omega(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        x, xdot = loop.shape(t), loop.velocity(t)
        return np.einsum("...A,...Aa->...a", xdot, connection.connection(x))
    return omega


def rotation_along(connection: Any, loop: Any, *, rtol: float = 1e-12, order: int = 6, t_eval: Any = None,
                   R0: Any = None) -> Holonomy:
    """R(t) along any path (closed or not): Ṙ = RΩ, R(t0) = R0 (default 1), later times to the right (3.98).

    ``connection`` is a :class:`~.connection.ShapeConnection` (``body.numeric(...)``); ``rtol`` is the
    target global error of R (an angle), passed to the adaptive Magnus integrator with ``order``.
    """
    loop = _as_loop(loop)
    if loop.dimension != connection.dimension:
        raise ShapeError(f"expected a loop in {connection.dimension} shape coordinates, got {loop.dimension}")
    res = path_ordered_exponential(_angular_velocity(connection, loop), loop.span, rtol=rtol, order=order,
                                   ordering="right", R0=R0, t_eval=t_eval)
    ends = connection.positions(loop.shape(np.array(loop.span)))
    closure = float(np.max(np.linalg.norm(ends[1] - ends[0], axis=-1)))
    return Holonomy(res.R[-1], res.t, res.R, float(res.error_estimate), res.steps, closure)


def net_rotation(connection: Any, loop: Any, *, rtol: float = 1e-12, order: int = 6, t_eval: Any = None,
                 closure_tol: float = 1e-9) -> Holonomy:
    """The net rotation R = P̃ exp ∮ Ω_A dx^A (3.98) of a body taken once around a closed loop.

    Raises unless the shape closes: max_i |r̃_i(end) − r̃_i(start)| ≤ ``closure_tol`` × (1 + max |r̃_i|).
    """
    loop = _as_loop(loop)
    out = rotation_along(connection, loop, rtol=rtol, order=order, t_eval=t_eval)
    size = float(np.max(np.linalg.norm(connection.positions(loop.shape(np.array(loop.span[:1]))), axis=-1)))
    if out.closure > closure_tol * (1 + size):
        raise InvalidInputError(f"expected a closed loop in shape space (r̃_i(x(t1)) = r̃_i(x(t0))), "
                                f"got a mismatch of {out.closure:.3g}")
    return out
