"""Symbolic → numeric: SymPy expressions compiled to vectorised NumPy functions.

One way from formula to function (STYLE.md habit 4): :func:`compile_expressions`
takes an expression, or a (nested) list / Matrix of them, and an ordered sequence
of argument symbols, and returns a function ``f(*args)`` that broadcasts over
NumPy arrays.  It uses :func:`sympy.lambdify` with common-subexpression
elimination (``cse=True``), and keeps every result in a process-wide cache keyed
by the expressions themselves (SymPy's structural hash and equality) and the argument
list, so identical requests never compile twice.  The generated function's docstring
lists the argument order.  (The disk cache of :mod:`.codecache` is keyed differently: by
name and a fingerprint of the package.)
"""

from __future__ import annotations

import _thread
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import ArgumentError

__all__ = ["compile_expressions", "compile_cached", "compile_scalar", "compile_cache_info", "clear_compile_cache"]

_CACHE: dict[Any, Callable[..., Any]] = {}
_LOCK = _thread.allocate_lock()  # threading.Lock(), without importing threading on every run
_STATS = {"hits": 0, "misses": 0}
_EXACT_EQUALITY: list[bool] = []  # _structural_equality_is_exact(), once per process


def _structural_equality_is_exact() -> bool:
    """Whether SymPy's ``==`` tells a Float from an equal Rational (SymPy >= 1.13: 1 != 1.0, x + 1 != x + 1.0)."""
    if _EXACT_EQUALITY:
        return _EXACT_EQUALITY[0]
    import sympy as sp

    x = sp.Symbol("x")
    _EXACT_EQUALITY.append(bool(sp.Float(1.0) != sp.Integer(1) and x + 1 != x + sp.Float(1.0)))
    return _EXACT_EQUALITY[0]


def _key(kind: str, shape: tuple[int, ...], flat: Sequence[Any], args: Sequence[Any]) -> Any:
    """The in-process cache key of a request: its container kind, shape, entries and argument symbols.

    Built from the SymPy objects themselves — a tuple hashed by SymPy's structural hash (computed
    once per expression and kept by SymPy) and compared by structural equality — instead of their
    ``srepr`` text, which for the long expressions of section 3.7 took longer than compiling them
    (~0.3 s per request).  Structural equality keeps apart what compiles differently: symbols of the
    same name with different assumptions, distinct Dummies, Floats of different precision, and (SymPy
    >= 1.13) 1 and 1.0; ``flat`` has been through :func:`_checked`, so Python numbers are SymPy ones
    (1 → Integer, 1.0 → Float).  With an older SymPy, where 1 == 1.0, the key is the ``srepr`` text.
    """
    import sympy as sp

    if not _structural_equality_is_exact():  # pragma: no cover - SymPy < 1.13
        import hashlib

        text = sp.srepr(tuple(flat)) + "|" + sp.srepr(tuple(args))
        return kind, shape, hashlib.sha256(text.encode()).hexdigest()
    # a mutable Matrix among the entries (compile_scalar given nested lists) is unhashable: key its immutable twin
    entries = tuple(sp.ImmutableMatrix(e) if isinstance(e, sp.MatrixBase) else e for e in flat)
    return kind, shape, entries, tuple(args)


def _checked(flat: list[Any], args: Sequence[Any]) -> tuple[list[Any], list[Any]]:
    """The entries as SymPy objects and the arguments as symbols; ``lambdify`` would run text as code."""
    import sympy as sp

    from .symbols import as_symbolic

    entries = [as_symbolic(e, "each expression to compile") for e in flat]
    for a in args:
        if not isinstance(a, (sp.Symbol, sp.Dummy)):
            raise ArgumentError(f"expected each argument of a compiled function to be a SymPy Symbol, got {a!r}"[:300])
    return entries, list(args)


def compile_expressions(exprs: Any, args: Sequence[Any], *, name: str = "f") -> Callable[..., Any]:
    """Return a vectorised NumPy function evaluating ``exprs`` at ``args``.

    Parameters
    ----------
    exprs
        A SymPy expression, a Matrix, or a (nested) list/tuple of expressions.
    args
        The argument symbols, in calling order.
    name
        A name for the function (used in its docstring and in logs).

    The result returns a float array of ``exprs``' shape, broadcast over the
    arguments' shapes: for a 3×3 Matrix and arguments of shape (N,), shape
    (3, 3, N) is *not* what you get — the result is moved so that the broadcast
    dimensions come first: shape (N, 3, 3).  Scalars stay scalars.

    >>> import sympy as sp
    >>> x, y = sp.symbols("x y")
    >>> f = compile_expressions(sp.Matrix([[x, y], [x * y, 1]]), [x, y])
    >>> f(np.array([1.0, 2.0]), 3.0).shape
    (2, 2, 2)
    """
    import sympy as sp

    shape: tuple[int, ...]
    if isinstance(exprs, sp.MatrixBase):
        kind, shape = "matrix", exprs.shape
        flat = list(exprs)
    elif isinstance(exprs, (list, tuple)):
        arr = np.array(exprs, dtype=object)
        kind, shape = "sequence", arr.shape
        flat = list(arr.ravel())
    else:
        kind, shape = "scalar", ()
        flat = [exprs]
    flat, args = _checked(flat, args)
    key = _key(kind, shape, flat, args)
    with _LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _STATS["hits"] += 1
            return hit
    raw = sp.lambdify(list(args), flat, modules="numpy", cse=True)
    compiled = wrap_vectorised(raw, [str(a) for a in args], shape, name)
    with _LOCK:
        _STATS["misses"] += 1
        _CACHE.setdefault(key, compiled)
        return _CACHE[key]


def wrap_vectorised(raw: Callable[..., Any], arg_names: Sequence[str], shape: tuple[int, ...],
                    name: str) -> Callable[..., np.ndarray]:
    """Wrap a lambdified function returning a flat list into one returning arrays of shape (*broadcast, *shape)."""
    nargs = len(arg_names)

    def compiled(*values: Any) -> np.ndarray:
        if len(values) != nargs:
            raise ArgumentError(f"{name}() expected {nargs} arguments ({', '.join(arg_names)}), got {len(values)}")
        vals = [np.asarray(v, dtype=float) for v in values]
        out = raw(*vals)
        bshape = np.broadcast_shapes(*(v.shape for v in vals)) if vals else ()
        stacked = np.stack([np.broadcast_to(np.asarray(o, dtype=float), bshape) for o in out], axis=-1)
        result = stacked.reshape(bshape + tuple(shape))
        return result if result.shape else float(result)

    compiled.__name__ = name
    compiled.__doc__ = f"{name}({', '.join(arg_names)}) -> array of shape (*broadcast, {', '.join(map(str, shape))})"
    compiled.args = tuple(arg_names)  # type: ignore[attr-defined]
    compiled.shape = tuple(shape)  # type: ignore[attr-defined]
    return compiled


def compile_cached(name: str, build: Callable[[], tuple[Sequence[Any], Any]]) -> Callable[..., np.ndarray]:
    """Like :func:`compile_expressions`, with the generated code kept in the disk cache under ``name``.

    ``build() -> (argument symbols, expressions)`` derives, and runs only when neither this process
    nor the disk cache (:mod:`.codecache`) has ``name``: a warm process neither derives nor
    imports SymPy.  ``name`` must identify what ``build`` derives.
    """
    from .codecache import cached_lambdify, shape_of

    raw, meta = cached_lambdify(name, build, module="numpy")
    return wrap_vectorised(raw, meta["args"].split(",") if meta.get("args") else [], shape_of(meta), name)


def compile_scalar(exprs: Any, args: Sequence[Any], *, name: str = "f") -> Callable[..., Any]:
    """Return a fast *scalar* function ``f(*args) -> list`` of the flattened ``exprs``.

    For hot loops (ODE right-hand sides) where the broadcasting wrapper of
    :func:`compile_expressions` costs more than the arithmetic: the result is the
    bare ``lambdify(..., modules="math", cse=True)`` function, taking Python floats
    and returning a list of floats in the row-major order of ``exprs``.  Cached
    like :func:`compile_expressions`.

    >>> import sympy as sp
    >>> x, y = sp.symbols("x y")
    >>> compile_scalar(sp.Matrix([x * y, x + y]), [x, y])(2.0, 3.0)
    [6.0, 5.0]
    """
    import sympy as sp

    flat = list(exprs) if isinstance(exprs, (sp.MatrixBase, list, tuple)) else [exprs]
    flat, args = _checked(flat, args)
    key = _key("scalar-function", (len(flat),), flat, args)
    with _LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _STATS["hits"] += 1
            return hit
    raw = sp.lambdify(list(args), flat, modules="math", cse=True)
    raw.__doc__ = f"{name}({', '.join(map(str, args))}) -> list of {len(flat)} floats"
    with _LOCK:
        _STATS["misses"] += 1
        _CACHE.setdefault(key, raw)
        return _CACHE[key]


def compile_cache_info() -> dict[str, int]:
    """Hits, misses and size of the process-wide compile cache."""
    with _LOCK:
        return {"hits": _STATS["hits"], "misses": _STATS["misses"], "size": len(_CACHE)}


def clear_compile_cache() -> None:
    """Empty the process-wide compile cache (for tests and benchmarks)."""
    with _LOCK:
        _CACHE.clear()
        _STATS["hits"] = _STATS["misses"] = 0
