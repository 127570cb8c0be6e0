"""Physical inertia tensors: symmetric, positive (3.22), obeying the triangle inequalities.

For any body the principal moments satisfy I_a >= 0 (3.22), and since
I1 + I2 = Σ m (x² + y² + 2 z²) >= Σ m (x² + y²) = I3 (and cyclically), the
*triangle inequalities* I1 + I2 >= I3, I2 + I3 >= I1, I3 + I1 >= I2 hold, with
equality for a plane body.  A zero moment occurs only when all the mass lies on
a line through the point (3.22 "equality only if ... on a line"), which then
forces the other two moments to be equal; such a tensor is accepted only with
``line_body=True``.

Comparisons allow a relative tolerance ``rtol`` (default 1e-9) of the largest
moment, because a plane body's I1 + I2 = I3 holds only to rounding after a
rotation or an eigen-decomposition (errors ~ 1e-15 relative).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.validate import as_finite_array
from ..errors import ShapeError, UnphysicalInertiaError

__all__ = ["check_inertia_tensor", "check_principal_moments"]


def _g(x: float) -> str:
    return f"{float(x):.6g}"


def check_principal_moments(I1: Any, I2: Any, I3: Any, *, line_body: bool = False,
                            rtol: float = 1e-9) -> np.ndarray:
    """Return the moments as an array of shape (..., 3), raising if no body can have them.

    Raises :class:`UnphysicalInertiaError` for a negative moment, a zero moment
    (unless ``line_body``), or a violated triangle inequality.

    >>> check_principal_moments(1.0, 1.0, 2.0)      # a disc: I1 + I2 = I3
    array([1., 1., 2.])
    >>> check_principal_moments(1.0, 0.5, 3.0)
    Traceback (most recent call last):
    ...
    mechderive.errors.UnphysicalInertiaError: expected I1 + I2 >= I3 (triangle inequality), got I1 + I2 = 1.5 < I3 = 3
    """
    moments = np.stack(np.broadcast_arrays(*(as_finite_array(v, f"I{k}") for k, v in
                                             enumerate((I1, I2, I3), start=1))), axis=-1)
    scale = np.max(np.abs(moments), axis=-1, keepdims=True)
    tol = rtol * scale
    names = ("I1", "I2", "I3")
    for k in range(3):
        mk = moments[..., k]
        negative = mk < -tol[..., 0] if line_body else mk < 0
        if np.any(negative):
            bad = mk[negative].ravel()[0]
            sign = ">=" if line_body else ">"
            raise UnphysicalInertiaError(f"expected principal moments {sign} 0 (3.22), got {names[k]} = {_g(bad)}")
        if not line_body and np.any(mk <= tol[..., 0]):
            bad = mk[mk <= tol[..., 0]].ravel()[0]
            raise UnphysicalInertiaError(
                f"expected principal moments > 0 (3.22), got {names[k]} = {_g(bad)}; "
                "a zero moment is allowed only for a line body (line_body=True)")
    for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        lhs, rhs = moments[..., a] + moments[..., b], moments[..., c]
        bad = lhs < rhs - tol[..., 0]
        if np.any(bad):
            i = np.argwhere(np.atleast_1d(bad))[0]
            l_, r_ = np.atleast_1d(lhs)[tuple(i)], np.atleast_1d(rhs)[tuple(i)]
            raise UnphysicalInertiaError(
                f"expected {names[a]} + {names[b]} >= {names[c]} (triangle inequality), "
                f"got {names[a]} + {names[b]} = {_g(l_)} < {names[c]} = {_g(r_)}")
    return moments


def check_inertia_tensor(inertia: Any, *, line_body: bool = False, rtol: float = 1e-9) -> np.ndarray:
    """Return ``inertia`` as a float array (3, 3) or (..., 3, 3), raising unless it is physical.

    Checks: finite; symmetric I_ab = I_ba (within ``rtol`` of the largest entry);
    principal moments (its eigenvalues) passing :func:`check_principal_moments`.

    >>> check_inertia_tensor([[2.0, 1.0, 0], [0, 2.0, 0], [0, 0, 3.0]])
    Traceback (most recent call last):
    ...
    mechderive.errors.UnphysicalInertiaError: expected a symmetric inertia tensor (I_ab = I_ba), got I_12 = 1 but I_21 = 0
    """
    I = as_finite_array(inertia, "inertia")
    if I.ndim < 2 or I.shape[-2:] != (3, 3):
        raise ShapeError(f"expected `inertia` to have shape (3, 3) or (..., 3, 3), got {I.shape}")
    scale = np.max(np.abs(I), axis=(-2, -1), keepdims=True)
    asym = np.abs(I - np.swapaxes(I, -1, -2)) > rtol * scale
    if np.any(asym):
        idx = np.argwhere(asym)[0]
        *lead, a, b = (int(i) for i in idx)
        a, b = min(a, b), max(a, b)
        raise UnphysicalInertiaError(
            f"expected a symmetric inertia tensor (I_ab = I_ba), got I_{a + 1}{b + 1} = {_g(I[(*lead, a, b)])} "
            f"but I_{b + 1}{a + 1} = {_g(I[(*lead, b, a)])}")
    moments = np.linalg.eigvalsh(I)  # ascending; symmetric by the check above
    check_principal_moments(moments[..., 0], moments[..., 1], moments[..., 2], line_body=line_body, rtol=rtol)
    return I
