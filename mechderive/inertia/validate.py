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

``strict=False`` waives the triangle inequalities — published benchmarks use moments
such as (3, 3, 9), beyond the flat plate, which Euler's equations (3.33) integrate
without complaint — but never positivity: the equations divide by each moment.
:func:`rigid_body_violations` lists what such moments violate (for a run's report).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.validate import as_finite_array
from ..errors import NonFiniteValueError, ShapeError, UnphysicalInertiaError

__all__ = ["check_inertia_tensor", "check_principal_moments", "rigid_body_violations", "STRICT_HINT"]

#: How a caller that offers ``strict`` tells the user to proceed with moments no rigid body has.
STRICT_HINT = "pass strict=False (scene: strict = false) to accept moments no rigid body has"


def _g(x: float) -> str:
    return f"{float(x):.6g}"


def _triangle_violations(moments: np.ndarray, tol: np.ndarray) -> list[str]:
    """The violated triangle inequalities as "expected ..., got ..." (the first offending element of an array)."""
    names = ("I1", "I2", "I3")
    found = []
    for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        with np.errstate(over="ignore"):  # two moments near the double range's end sum to inf, which is >= any
            lhs, rhs = moments[..., a] + moments[..., b], moments[..., c]
        bad = lhs < rhs - tol[..., 0]
        if np.any(bad):
            i = np.argwhere(np.atleast_1d(bad))[0]
            l_, r_ = np.atleast_1d(lhs)[tuple(i)], np.atleast_1d(rhs)[tuple(i)]
            found.append(f"expected {names[a]} + {names[b]} >= {names[c]} (triangle inequality), "
                         f"got {names[a]} + {names[b]} = {_g(l_)} < {names[c]} = {_g(r_)}")
    return found


def rigid_body_violations(I1: Any, I2: Any, I3: Any, *, rtol: float = 1e-9) -> list[str]:
    """The triangle inequalities that positive moments violate — what ``strict=False`` waives; [] for a body.

    >>> rigid_body_violations(3.0, 3.0, 9.0)
    ['expected I1 + I2 >= I3 (triangle inequality), got I1 + I2 = 6 < I3 = 9']
    """
    moments = check_principal_moments(I1, I2, I3, rtol=rtol, strict=False)
    return _triangle_violations(moments, rtol * np.max(np.abs(moments), axis=-1, keepdims=True))


def check_principal_moments(I1: Any, I2: Any, I3: Any, *, line_body: bool = False,
                            rtol: float = 1e-9, strict: bool | None = None) -> np.ndarray:
    """Return the moments as an array of shape (..., 3), raising if no body can have them.

    Raises :class:`UnphysicalInertiaError` for a negative moment, a zero moment
    (unless ``line_body``), or a violated triangle inequality.

    ``strict``: ``False`` accepts moments violating the triangle inequalities (no rigid
    body has them, but Euler's equations do not care); non-positive moments are refused
    all the same.  ``True`` refuses them, the message saying that ``strict=False`` (scene:
    ``strict = false``) accepts them — for callers that offer that keyword; ``None``
    (default) refuses them without that hint, for callers that do not.

    >>> check_principal_moments(1.0, 1.0, 2.0)      # a disc: I1 + I2 = I3
    array([1., 1., 2.])
    >>> check_principal_moments(1.0, 0.5, 3.0)
    Traceback (most recent call last):
    ...
    mechderive.errors.UnphysicalInertiaError: expected I1 + I2 >= I3 (triangle inequality), got I1 + I2 = 1.5 < I3 = 3
    >>> check_principal_moments(3.0, 3.0, 9.0, strict=False)
    array([3., 3., 9.])
    """
    # never waived: T = ½ Σ I_a ω_a² and Euler's equations (3.33) divide by each moment
    kept = "; strict=False does not waive this (Euler's equations divide by each moment)" \
        if strict is False else ""
    try:
        moments = np.stack(np.broadcast_arrays(*(as_finite_array(v, f"I{k}") for k, v in
                                                 enumerate((I1, I2, I3), start=1))), axis=-1)
    except NonFiniteValueError as exc:
        raise NonFiniteValueError(str(exc) + kept) from exc
    scale = np.max(np.abs(moments), axis=-1, keepdims=True)
    tol = rtol * scale
    names = ("I1", "I2", "I3")
    if strict is not False and np.all(moments > 0):
        # a moment small against the others is only a rounded zero (a line body) where the triangle
        # inequalities hold; where they fail, that is what is wrong (I1 = 1e308, I2 = 2, I3 = 3 is no
        # line body: I2 + I3 < I1), and it names all three moments
        violated = _triangle_violations(moments, tol)
        if violated:
            hint = ("; no rigid body has these moments (a flat plate reaches I1 + I2 = I3): " + STRICT_HINT
                    if strict else "")
            raise UnphysicalInertiaError(violated[0] + hint)
    for k in range(3):
        mk = moments[..., k]
        negative = mk < -tol[..., 0] if line_body else mk < 0
        if np.any(negative):
            bad = mk[negative].ravel()[0]
            sign = ">=" if line_body else ">"
            raise UnphysicalInertiaError(f"expected principal moments {sign} 0 (3.22), got {names[k]} = {_g(bad)}"
                                         + kept)
        if not line_body and np.any(mk <= (tol[..., 0] if strict is not False else 0.0)):
            bad = mk[mk <= tol[..., 0]].ravel()[0]
            raise UnphysicalInertiaError(
                f"expected principal moments > 0 (3.22), got {names[k]} = {_g(bad)}; "
                "a zero moment is allowed only for a line body (line_body=True)" + kept)
    if strict is not False:
        violated = _triangle_violations(moments, tol)
        if violated:
            hint = ("; no rigid body has these moments (a flat plate reaches I1 + I2 = I3): " + STRICT_HINT
                    if strict else "")
            raise UnphysicalInertiaError(violated[0] + hint)
    return moments


def check_inertia_tensor(inertia: Any, *, line_body: bool = False, rtol: float = 1e-9,
                         strict: bool | None = None) -> np.ndarray:
    """Return ``inertia`` as a float array (3, 3) or (..., 3, 3), raising unless it is physical.

    Checks: finite; symmetric I_ab = I_ba (within ``rtol`` of the largest entry);
    principal moments (its eigenvalues) passing :func:`check_principal_moments` (``strict``
    passed on: ``False`` waives the triangle inequalities, never symmetry or positivity).

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
    check_principal_moments(moments[..., 0], moments[..., 1], moments[..., 2], line_body=line_body, rtol=rtol,
                            strict=strict)
    return I
