"""Stability of the steady rotations of a free rigid body: section 3.4.3, (3.40)–(3.45), generalised.

Conventions: principal axes e1, e2, e3 with moments I1, I2, I3 — those of a body: > 0 and
obeying I_a + I_b >= I_c (:func:`mechderive.inertia.validate.check_principal_moments`
raises :class:`~mechderive.errors.UnphysicalInertiaError` otherwise); ω in body
components (rad per unit time); any consistent units.

What is derived (in :class:`~mechderive.systems.free_top.model.FreeTopModel`, never typed
here).  A rotation is *steady* when Euler's equations (3.33) give ω̇ = 0, i.e.
ω × Iω = 0: ω along a principal axis, or any ω in a plane of equal moments (any ω at
all for a sphere).  Linearising ω̇ = F(ω) about it, η̇ = J η with J = ∂F/∂ω.  Since
trace J = 0 and J ω = 2F(ω) = 0, the characteristic polynomial is λ³ - s λ, so the
eigenvalues are 0 (the perturbation along ω, a change of spin rate) and ±√s, with

    s(ω) = Σ_a ω_a² (I_a - I_b)(I_c - I_a) / (I_b I_c)        (a, b, c cyclic).

For a spin Ω about axis 1 this is s = A/I2 with A = (Ω²/I3)(I3 - I1)(I1 - I2) of (3.44).

Classification of the spin about a principal axis a (the chapter's "stable" is the
linearised statement: oscillation rather than growth):

- ``"unstable"``: s_a > 0, I_a strictly between the other two — η grows like e^{√s t};
- ``"stable"``:   s_a < 0, I_a the strictly largest or smallest (or the symmetry axis of a
  symmetric top) — η oscillates with angular frequency √(-s_a);
- ``"neutral"``:  s_a = 0, I_a equal to another moment — every linearised eigenvalue is 0.
  For a sphere η stays constant; in the equal-moment plane of a symmetric top J is
  nilpotent and ω drifts linearly in t along the circle of steady spins (no exponential
  growth, no restoring oscillation).

The sign of s_a is evaluated from the factored product of moment differences, so it
is exact for floating-point moments: moments are "equal" only if they are equal floats
(pass ``rtol`` to treat nearly equal moments as equal).

>>> principal_axis_stability(1.0, 2.0, 3.0)
{1: 'stable', 2: 'unstable', 3: 'stable'}
>>> print(f"{instability_growth_rate(2.0, 1.0, 2.5, 1.0, axis=1):.10f}")   # √(A/I2), A = 0.2, I2 = 1
0.4472135955
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...core.validate import as_finite_array
from ...errors import DerivationError, InvalidInputError
from ...inertia.validate import check_principal_moments
from . import model as _model

__all__ = ["principal_axis_stability", "linearised_eigenvalues", "instability_growth_rate", "is_steady_rotation"]


def _moments(I1: Any, I2: Any, I3: Any) -> np.ndarray:
    """(I1, I2, I3) as floats, raising unless they are the principal moments of some body (> 0, triangle inequalities)."""
    return check_principal_moments(*(float(as_finite_array(v, f"I{k}", shape=())) for k, v in
                                     enumerate((I1, I2, I3), start=1)))


def _axis(axis: Any) -> int:
    if isinstance(axis, bool) or axis not in (1, 2, 3):
        raise InvalidInputError(f"expected axis 1, 2 or 3, got {axis!r}")
    return int(axis)


def _compiled(name: str):
    m = _model.model()
    moments = [_model.I1, _model.I2, _model.I3]
    w = list(_model.omega_symbols())
    if name == "free_rhs":  # flat: shape (3,)
        return m.compile("free_rhs_flat", list(m.free_rhs), w + moments)
    if name == "growth_squared":
        return m.compile("growth_squared", m.growth_squared, moments + w)
    if name == "axis_growth_squared":  # at unit spin, Ω = 1
        return m.compile("axis_growth_squared", [e.subs(_model.Omega, 1) for e in m.axis_growth_squared], moments)
    if name == "axis_growth_rate_squared":  # A_a / I_b with A_1 = A of (3.44)
        exprs = [m.axis_stability_coefficients[a] / moments[_model.cyclic_axes(a + 1)[1]] for a in range(3)]
        return m.compile("axis_growth_rate_squared", exprs, moments + [_model.Omega])
    raise DerivationError(f"no stability function {name!r}")  # pragma: no cover - internal


def _steadiness(moments: np.ndarray, omega: np.ndarray) -> float:
    """sin of the angle between ω and L = Iω, computed as |I ω̇| / (|ω| |Iω|) with ω̇ from the derived equations."""
    wdot = np.asarray(_compiled("free_rhs")(*omega, *moments), dtype=float)
    norm = np.linalg.norm(omega) * np.linalg.norm(moments * omega)
    return 0.0 if norm == 0 else float(np.linalg.norm(moments * wdot) / norm)


def is_steady_rotation(I1: float, I2: float, I3: float, omega: Any, *, rtol: float = 1e-9) -> bool:
    """Whether ω (body components) is a steady rotation: ω̇ = 0 in (3.33), i.e. ω ∥ L = Iω within ``rtol`` (angle, rad).

    >>> is_steady_rotation(1.0, 2.0, 3.0, [0.0, 5.0, 0.0]), is_steady_rotation(1.0, 2.0, 3.0, [1.0, 1.0, 0.0])
    (True, False)
    >>> is_steady_rotation(1.0, 1.0, 1.5, [1.0, 1.0, 0.0])   # any axis in the plane of equal moments
    True
    """
    return _steadiness(_moments(I1, I2, I3), as_finite_array(omega, "omega", shape=(3,))) <= rtol


def linearised_eigenvalues(I1: float, I2: float, I3: float, omega: Any, *, rtol: float = 1e-9) -> np.ndarray:
    """Eigenvalues (0, √s, -√s) of Euler's equations linearised about the steady rotation ω; complex, shape (3,).

    ``omega`` holds the body components of a steady rotation (see the module docstring);
    √s is the principal square root (≥ 0, or i·√|s|).  Real nonzero eigenvalues mean
    exponential growth ((3.44) with A > 0), imaginary ones oscillation.  Raises
    :class:`~mechderive.errors.InvalidInputError` if ω is not steady (sin∠(ω, Iω) > ``rtol``).

    >>> linearised_eigenvalues(1.0, 2.0, 3.0, [0.0, 2.0, 0.0]).real.round(8)   # intermediate axis: 2/√3
    array([ 0.        ,  1.15470054, -1.15470054])
    >>> linearised_eigenvalues(1.0, 2.0, 3.0, [0.0, 0.0, 2.0])   # largest axis: s = 4·(2)(-1)/2, oscillation
    array([ 0.+0.j,  0.+2.j, -0.-2.j])
    >>> linearised_eigenvalues(1.0, 2.0, 3.0, [1.0, 1.0, 0.0])
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: expected a steady rotation (ω parallel to L = Iω: a principal axis, or any axis in a plane of equal moments), got ω = [1.0, 1.0, 0.0] at sin∠(ω, L) = 0.316 > rtol = 1e-09
    """
    moments = _moments(I1, I2, I3)
    w = as_finite_array(omega, "omega", shape=(3,))
    sine = _steadiness(moments, w)
    if sine > rtol:
        raise InvalidInputError(
            "expected a steady rotation (ω parallel to L = Iω: a principal axis, or any axis in a plane of equal "
            f"moments), got ω = {[float(x) for x in w]} at sin∠(ω, L) = {sine:.3g} > rtol = {rtol:g}")
    s = float(_compiled("growth_squared")(*moments, *w))
    root = complex(np.emath.sqrt(s))
    return np.array([0.0, root, -root], dtype=complex)


def principal_axis_stability(I1: float, I2: float, I3: float, *, rtol: float = 0.0) -> dict[int, str]:
    """Stability of steady spin about each principal axis: {1: ..., 2: ..., 3: ...}, each "stable", "unstable" or "neutral".

    Decided by the sign of the derived s_a (module docstring); moments within ``rtol``
    × the largest moment of each other count as equal (default: exactly equal).  (3.45):
    spin about e1 is unstable iff I2 < I1 < I3 or I3 < I1 < I2.

    >>> principal_axis_stability(2.0, 1.0, 2.0)      # a symmetric top, symmetry axis e2
    {1: 'neutral', 2: 'stable', 3: 'neutral'}
    >>> principal_axis_stability(1.0, 1.0, 1.0)
    {1: 'neutral', 2: 'neutral', 3: 'neutral'}
    """
    moments = _moments(I1, I2, I3)
    tol = float(as_finite_array(rtol, "rtol", shape=())) * float(np.max(moments))
    s = np.asarray(_compiled("axis_growth_squared")(*moments), dtype=float)
    out: dict[int, str] = {}
    for a in range(3):
        others = [moments[b] for b in range(3) if b != a]
        if s[a] == 0 or min(abs(moments[a] - x) for x in others) <= tol:
            out[a + 1] = "neutral"
        else:
            out[a + 1] = "unstable" if s[a] > 0 else "stable"
    return out


def instability_growth_rate(I1: float, I2: float, I3: float, Omega: float, axis: int = 1) -> float:
    """e-folding rate √(A/I2) of a perturbation of the spin Ω about ``axis`` (3.44), in 1/time.

    For axis 1, A = (Ω²/I3)(I3 - I1)(I1 - I2) and I2 η̈2 = A η2; other axes by cyclic
    relabelling (axis 2: √(A_2/I3), axis 3: √(A_3/I1)).  Raises
    :class:`~mechderive.errors.InvalidInputError` unless A > 0 (spin about the
    intermediate axis) and Ω ≠ 0.

    >>> instability_growth_rate(1.0, 2.0, 3.0, 1.0, axis=1)
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: expected spin about the intermediate axis (A > 0 in (3.44)), got axis 1 with A/I2 = -0.333333 < 0: stable, perturbations oscillate with angular frequency 0.57735
    """
    moments = _moments(I1, I2, I3)
    a = _axis(axis)
    Om = float(as_finite_array(Omega, "Omega", shape=()))
    if Om == 0:
        raise InvalidInputError("expected a nonzero spin Omega, got 0.0")
    value = float(np.asarray(_compiled("axis_growth_rate_squared")(*moments, Om))[a - 1])
    b = _model.cyclic_axes(a)[1] + 1
    if not value > 0:
        kind = ("stable, perturbations oscillate with angular frequency " + f"{np.sqrt(-value):.6g}"
                if value < 0 else "neutral (equal moments), no exponential growth")
        raise InvalidInputError(f"expected spin about the intermediate axis (A > 0 in (3.44)), got axis {a} "
                                f"with A/I{b} = {value:.6g} {'<' if value < 0 else '='} 0: {kind}")
    return float(np.sqrt(value))
