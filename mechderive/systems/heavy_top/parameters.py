"""Validation of a heavy top's parameters and initial state — one implementation for every solver.

Parameters ``I1 I3 M g l``: I1 = I2 and I3 are the principal moments about the pivot
P (as in (3.62)), M the mass, g the gravitational acceleration, l the distance from P
to the centre of mass.  I1, I3, M > 0; g, l ≥ 0 (g l = 0 is a free symmetric top,
which the integrators accept and the closed form refers to ``free_top``).  The moments
about the centre of mass, I1 - M l² and I3, must be those of a real body: the
triangle inequality I1_cm + I2_cm ≥ I3, i.e. I1 - M l² ≥ I3/2.  (The motion depends on
I1, I3 and M g l only, so a top whose M l² is too large for its I1 can be described
with a smaller l and a larger M g.)

Initial state ``theta phi psi theta_dot phi_dot psi_dot`` (rad, rad/s), θ in [0, π];
only θ is required, the others default to 0.  Values may be arrays (ensembles).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...core.validate import as_finite_array
from ...errors import InvalidInputError, UnphysicalInertiaError

__all__ = ["PARAM_KEYS", "INITIAL_KEYS", "check_params", "check_initial"]

PARAM_KEYS = ("I1", "I3", "M", "g", "l")
INITIAL_KEYS = ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")


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


def check_params(params: Mapping[str, Any], *, rtol: float = 1e-9) -> dict[str, Any]:
    """Return the parameters as floats (or arrays), raising unless a rigid heavy top has them.

    Checks (see the module docstring): keys exactly I1, I3, M, g, l; finite; I1, I3 > 0;
    M > 0; g ≥ 0; l ≥ 0; and the centre-of-mass triangle inequality I1 - M l² ≥ I3/2
    (within ``rtol`` of I1, for a plane body where it holds with equality up to rounding).

    >>> check_params(dict(I1=1.0, I3=0.5, M=1.0, g=1.0, l=1.0))
    Traceback (most recent call last):
    ...
    mechderive.errors.UnphysicalInertiaError: expected I1 - M l² >= I3/2 (the triangle inequality ...), got I1 - M l² = 0 < I3/2 = 0.25
    """
    _check_keys(params, "params", PARAM_KEYS, PARAM_KEYS)
    v = {k: as_finite_array(params[k], f"params['{k}']") for k in PARAM_KEYS}
    for k in ("I1", "I3"):
        bad = v[k] <= 0
        if np.any(bad):
            raise UnphysicalInertiaError(f"expected params['{k}'] > 0 (a principal moment about the pivot), "
                                         f"got {_first(v[k], bad):g}")
    for k, strict in (("M", True), ("g", False), ("l", False)):
        bad = v[k] <= 0 if strict else v[k] < 0
        if np.any(bad):
            raise InvalidInputError(f"expected params['{k}'] {'>' if strict else '>='} 0, got {_first(v[k], bad):g}")
    I1_cm = v["I1"] - v["M"] * v["l"] ** 2
    bad = I1_cm < v["I3"] / 2 - rtol * v["I1"]
    if np.any(bad):
        raise UnphysicalInertiaError(
            "expected I1 - M l² >= I3/2 (the triangle inequality I1_cm + I2_cm >= I3 about the centre of mass, "
            f"I1_cm = I1 - M l²), got I1 - M l² = {_first(I1_cm, bad):.6g} < I3/2 = {_first(v['I3'] / 2, bad):.6g}")
    return {k: (float(a) if a.ndim == 0 else a) for k, a in v.items()}


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
