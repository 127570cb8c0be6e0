"""Input checks shared by every layer: finite numbers, shapes, rotation matrices; and the mask tests
:func:`every` and :func:`some` they and the numerical loops use (cheap on one element).

Checks raise; they never silently repair input (STYLE.md habit 6).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import NonFiniteValueError, NotARotationError, ShapeError, InvalidInputError

__all__ = ["as_finite_array", "check_rotation_matrix", "check_positive", "every", "some"]


def as_finite_array(value: Any, name: str, *, shape: tuple[int | None, ...] | None = None) -> np.ndarray:
    """Return ``value`` as a float array, raising if it is not numeric, finite and of ``shape``.

    ``shape`` may use ``None`` for a free dimension; a leading ``...`` is not supported:
    give the trailing shape with ``trailing=True`` semantics by passing e.g. ``(None, 3, 3)``.
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"expected `{name}` to be numeric, got {value!r}") from exc
    if shape is not None:
        if arr.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, arr.shape)):
            want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
            raise ShapeError(f"expected `{name}` to have shape {want}, got {arr.shape}")
    if not every(np.isfinite(arr)):
        bad = arr[~np.isfinite(arr)].ravel()[0]
        raise NonFiniteValueError(f"expected `{name}` to be finite, got {bad} in it")
    return arr


def every(mask: Any) -> bool:
    """Whether every element of the boolean ``mask`` (an array, a NumPy or Python bool) is true.

    ``mask.all()`` goes through NumPy's Python-level reduction (~5k instructions); a mask of one element (a
    closed form's batch of one, a scalar parameter) is read directly: the loops of the elliptic integrals and
    functions test one at every step.
    """
    if type(mask) is bool:
        return mask
    return bool(mask) if mask.size == 1 else bool(mask.all())


def some(mask: Any) -> bool:
    """Whether some element of the boolean ``mask`` is true (see :func:`every`)."""
    if type(mask) is bool:
        return mask
    return bool(mask) if mask.size == 1 else bool(mask.any())


def check_positive(value: float, name: str) -> float:
    """Return ``float(value)`` if it is finite and > 0, else raise."""
    x = float(as_finite_array(value, name, shape=()))
    if not x > 0:
        raise InvalidInputError(f"expected `{name}` > 0, got {x!r}")
    return x


def check_rotation_matrix(matrix: Any, name: str = "R", *, atol: float = 1e-9) -> np.ndarray:
    """Return ``matrix`` as an array of rotation matrices, shape (3, 3) or (..., 3, 3).

    Raises :class:`NotARotationError` unless RᵀR = 1 within ``atol`` (max-abs) and det R = +1;
    an improper matrix (det -1, a rotation with a reflection) is refused, not flipped.
    """
    arr = np.asarray(matrix, dtype=float) if not isinstance(matrix, np.ndarray) else matrix.astype(float)
    if arr.ndim < 2 or arr.shape[-2:] != (3, 3):
        raise ShapeError(f"expected `{name}` to have shape (3, 3) or (..., 3, 3), got {arr.shape}")
    arr = as_finite_array(arr, name)
    gram = np.einsum("...ki,...kj->...ij", arr, arr)
    err = np.max(np.abs(gram - np.eye(3)), axis=(-2, -1))
    worst = float(np.max(err))
    if worst > atol:
        raise NotARotationError(
            f"expected `{name}` orthogonal (RᵀR = 1 within {atol:g}), got max |RᵀR - 1| = {worst:.3g}"
        )
    det = np.linalg.det(arr)
    if np.any(det < 0):
        raise NotARotationError(
            f"expected `{name}` to have det +1 (a proper rotation), got det = {float(np.min(det)):.6g} "
            "(a rotation combined with a reflection)"
        )
    return arr
