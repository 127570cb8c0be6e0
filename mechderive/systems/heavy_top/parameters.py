"""Validation of a heavy top's parameters and initial state — one implementation for every solver.

Parameters ``I1 I3 M g l``: I1 = I2 and I3 are the principal moments about the pivot
P (as in (3.62)), M the mass, g the gravitational acceleration, l the distance from P
to the centre of mass.  I1, I3, M > 0; g, l ≥ 0 (g l = 0 is a free symmetric top,
which the integrators accept and the closed form refers to ``free_top``).  The moments
about the centre of mass, I1 - M l² and I3, must be those of a real body: the
triangle inequality I1_cm + I2_cm ≥ I3, i.e. I1 - M l² ≥ I3/2.

The motion depends on M, g, l only through M g l (V = M g l cos θ (3.65), β = 2 M g l / I1
(3.73)), so ``Mgl`` (≥ 0) may be given in their place: ``I1 I3 Mgl``.  A body with pivot
moments I1, I3 and any M g l > 0 then exists iff I1 ≥ I3/2 (take l small and M g large:
M l² → 0), which is what is checked.  Giving ``Mgl`` together with any of M, g, l, or only
some of M, g, l, is refused.  The checked parameters always come back as ``I1 I3 M g l``,
``Mgl`` realised as M = 1, g = Mgl, l = 1 (the same M g l, bit for bit) — a realisation for
the solvers, not a body: check the mapping the user gave, not this one, a second time.

``strict=False`` waives the rigid-body condition (I1 - M l² ≥ I3/2, or I1 ≥ I3/2 with
``Mgl``): published benchmarks use tops whose I1 about the pivot is below M l², and the
equations of motion do not care.  It never waives I1, I3, M > 0, g, l, Mgl ≥ 0 or
finiteness.  :func:`rigid_body_violations` lists what it waived, for a run's report.

Initial state ``theta phi psi theta_dot phi_dot psi_dot`` (rad, rad/s), θ in [0, π];
only θ is required, the others default to 0.  Values may be arrays (ensembles).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...core.validate import as_finite_array
from ...errors import InvalidInputError, NonFiniteValueError, UnphysicalInertiaError

__all__ = ["PARAM_KEYS", "MGL_KEYS", "INITIAL_KEYS", "STRICT_HINT", "check_params", "check_initial",
           "parameter_keys", "rigid_body_violations", "gravity_product"]

#: The parameters the solvers take (and :func:`check_params` returns).
PARAM_KEYS = ("I1", "I3", "M", "g", "l")
#: The same top with M g l in one number (only the product enters the motion).
MGL_KEYS = ("I1", "I3", "Mgl")
INITIAL_KEYS = ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")
#: How to proceed with a top no rigid body is (the entry points all take ``strict``).
STRICT_HINT = "pass strict=False (scene: strict = false) to accept moments no rigid body has"
_NOT_WAIVED = "; strict=False does not waive this"


def _check_keys(mapping: Any, name: str, allowed: tuple[str, ...], required: tuple[str, ...]) -> None:
    if not isinstance(mapping, Mapping):
        raise InvalidInputError(f"expected `{name}` to be a dict with keys {', '.join(allowed)}, "
                                f"got {type(mapping).__name__}")
    unknown = [k for k in mapping if k not in allowed]
    if unknown:
        raise InvalidInputError(f"expected `{name}` keys among {', '.join(allowed)}, "
                                f"got unknown key(s) {', '.join(map(repr, unknown))}")
    missing = [k for k in required if k not in mapping]
    if missing:
        raise InvalidInputError(f"expected `{name}` to have key(s) {', '.join(required)}, "
                                f"got none for {', '.join(map(repr, missing))}")


def _first(arr: np.ndarray, mask: np.ndarray) -> float:
    return float(np.broadcast_to(arr, mask.shape)[mask].ravel()[0])


def parameter_keys(params: Any, name: str = "params") -> tuple[str, ...]:
    """The form ``params`` is given in: :data:`PARAM_KEYS` or :data:`MGL_KEYS`, refusing any mixture.

    >>> parameter_keys(dict(I1=1.0, I3=0.5, Mgl=1.0))
    ('I1', 'I3', 'Mgl')
    >>> parameter_keys(dict(I1=1.0, I3=0.5, M=1.0, Mgl=1.0))
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: expected `params` to give either Mgl or all of M, g, l, got both Mgl and M
    """
    try:
        _check_keys(params, name, PARAM_KEYS + ("Mgl",), ())
    except InvalidInputError as exc:
        raise InvalidInputError(str(exc).replace(", Mgl, got", ", got") +
                                (" (Mgl may replace M, g, l)" if isinstance(params, Mapping) else "")) from None
    separate = [k for k in ("M", "g", "l") if k in params]
    if "Mgl" in params and separate:
        raise InvalidInputError(f"expected `{name}` to give either Mgl or all of M, g, l, got both Mgl and "
                                f"{', '.join(separate)}")
    keys = MGL_KEYS if "Mgl" in params else PARAM_KEYS
    missing = [k for k in keys if k not in params]
    if missing:
        alternative = " (or give Mgl in place of M, g, l)" if keys == PARAM_KEYS else ""
        raise InvalidInputError(f"expected `{name}` to have key(s) {', '.join(keys)}, "
                                f"got none for {', '.join(map(repr, missing))}{alternative}")
    return keys


def _values(params: Mapping[str, Any], keys: tuple[str, ...], strict: bool) -> dict[str, np.ndarray]:
    kept = _NOT_WAIVED if not strict else ""
    try:
        v = {k: as_finite_array(params[k], f"params['{k}']") for k in keys}
    except NonFiniteValueError as exc:
        raise NonFiniteValueError(str(exc) + kept) from exc
    for k in ("I1", "I3"):
        bad = v[k] <= 0
        if np.any(bad):
            raise UnphysicalInertiaError(f"expected params['{k}'] > 0 (a principal moment about the pivot), "
                                         f"got {_first(v[k], bad):g}"
                                         + (kept + " (the equations of motion divide by I1 and I3)" if kept else ""))
    for k, positive in (("M", True), ("g", False), ("l", False), ("Mgl", False)):
        if k not in v:
            continue
        bad = v[k] <= 0 if positive else v[k] < 0
        if np.any(bad):
            raise InvalidInputError(f"expected params['{k}'] {'>' if positive else '>='} 0, "
                                    f"got {_first(v[k], bad):g}" + kept)
    return v


def _violations(v: dict[str, np.ndarray], rtol: float) -> list[str]:
    """The rigid-body condition, if violated, as one "expected ..., got ..." sentence (first bad element)."""
    if "Mgl" in v:
        bad = v["I1"] < v["I3"] / 2 - rtol * v["I1"]
        if np.any(bad):
            return ["expected I1 >= I3/2 (given M g l alone, a body exists iff the triangle inequality about the "
                    "centre of mass, I1 - M l² >= I3/2, holds for some small l), "
                    f"got I1 = {_first(v['I1'], bad):.6g} < I3/2 = {_first(v['I3'] / 2, bad):.6g}"]
        return []
    with np.errstate(over="ignore"):  # M l² beyond the doubles is inf, and I1 - inf < I3/2: refused as it should
        I1_cm = v["I1"] - v["M"] * v["l"] ** 2
    bad = I1_cm < v["I3"] / 2 - rtol * v["I1"]
    if np.any(bad):
        return ["expected I1 - M l² >= I3/2 (the triangle inequality I1_cm + I2_cm >= I3 about the centre of mass, "
                f"I1_cm = I1 - M l²), got I1 - M l² = {_first(I1_cm, bad):.6g} "
                f"< I3/2 = {_first(v['I3'] / 2, bad):.6g}"]
    return []


def check_params(params: Mapping[str, Any], *, strict: bool = True, rtol: float = 1e-9) -> dict[str, Any]:
    """Return the parameters as floats (or arrays), keys :data:`PARAM_KEYS`, raising unless a heavy top has them.

    Accepts ``I1 I3 M g l`` or ``I1 I3 Mgl`` (see the module docstring; ``Mgl`` comes back as
    M = 1, g = Mgl, l = 1).  Checks: finite; I1, I3 > 0; M > 0; g, l, Mgl ≥ 0; and, unless
    ``strict=False``, that a rigid body has these moments: I1 - M l² ≥ I3/2 (I1 ≥ I3/2 with
    ``Mgl``), within ``rtol`` of I1, for a plane body where it holds with equality up to rounding.

    >>> check_params(dict(I1=1.0, I3=0.5, M=1.0, g=1.0, l=1.0))
    Traceback (most recent call last):
    ...
    mechderive.errors.UnphysicalInertiaError: expected I1 - M l² >= I3/2 (...), got I1 - M l² = 0 < I3/2 = 0.25; ... strict=False ...
    >>> check_params(dict(I1=1.0, I3=0.5, M=1.0, g=1.0, l=1.0), strict=False)["l"]
    1.0
    >>> check_params(dict(I1=1.0, I3=0.5, Mgl=1.0))
    {'I1': 1.0, 'I3': 0.5, 'M': 1.0, 'g': 1.0, 'l': 1.0}
    """
    keys = parameter_keys(params)
    v = _values(params, keys, strict)
    if strict:
        violated = _violations(v, rtol)
        if violated:
            # with M g l alone a body needs only I1 >= I3/2: say so where that would pass
            as_mgl = {"I1": v["I1"], "I3": v["I3"], "Mgl": v.get("M")}
            escape = ("give Mgl in place of M, g, l (only M g l enters the motion; then I1 >= I3/2 suffices), or "
                      if "M" in v and not _violations(as_mgl, rtol) else "")
            raise UnphysicalInertiaError(f"{violated[0]}; no rigid body has these moments: {escape}{STRICT_HINT}")
    if "Mgl" in v:
        v = {"I1": v["I1"], "I3": v["I3"], "M": np.asarray(1.0), "g": v["Mgl"], "l": np.asarray(1.0)}
    return {k: (float(a) if a.ndim == 0 else a) for k, a in v.items()}


def rigid_body_violations(params: Mapping[str, Any], *, rtol: float = 1e-9) -> list[str]:
    """What ``strict=False`` waives for ``params`` (checked otherwise as by :func:`check_params`); [] for a body.

    >>> rigid_body_violations(dict(I1=0.2, I3=0.5, Mgl=1.0))
    ['expected I1 >= I3/2 (given M g l alone, ...), got I1 = 0.2 < I3/2 = 0.25']
    """
    return _violations(_values(params, parameter_keys(params), strict=False), rtol)


def gravity_product(params: Mapping[str, Any]) -> Any:
    """M g l of unchecked-but-valid ``params`` in either form: ``Mgl``, or the product M g l (in that order).

    >>> gravity_product(dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)), gravity_product(dict(I1=1.0, I3=0.5, Mgl=1.0))
    (1.0, 1.0)
    """
    if "Mgl" in params:
        return params["Mgl"]
    return params["M"] * params["g"] * params["l"]


def check_initial(initial: Mapping[str, Any]) -> dict[str, Any]:
    """Return the initial Euler angles and rates (rad, rad/s) as floats or arrays, defaults 0 except θ.

    >>> check_initial(dict(theta=0.5, psi_dot=5.0))["psi_dot"]
    5.0
    """
    _check_keys(initial, "initial", INITIAL_KEYS, ("theta",))
    v = {k: as_finite_array(initial.get(k, 0.0), f"initial['{k}']") for k in INITIAL_KEYS}
    th = v["theta"]
    bad = (th < 0) | (th > math.pi)
    if np.any(bad):
        raise InvalidInputError(f"expected 0 <= initial['theta'] <= pi, got {_first(th, bad):g}")
    return {k: (float(a) if a.ndim == 0 else a) for k, a in v.items()}




#: Aliases used by the scene schema.
PARAMETER_NAMES = PARAM_KEYS
INITIAL_NAMES = INITIAL_KEYS
check_parameters = check_params
