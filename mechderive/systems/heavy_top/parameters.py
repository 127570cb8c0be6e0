"""Validation of a heavy top's parameters and initial state (the scene-file names).

Parameters ``I1 I3 M g l``: I1 = I2 and I3 are the principal moments about the pivot
P (as in (3.62)), M the mass, g the gravitational acceleration, l the distance from P
to the centre of mass.  All must be finite and positive.  The moments about the
centre of mass, I1 - M l² and I3, must be those of a real body: I1 - M l² > 0 and
the triangle inequality I1_cm + I2_cm ≥ I3, i.e. 2 (I1 - M l²) ≥ I3.  (The motion
depends on I1, I3 and M g l only, so a top whose M l² is too large for its I1 can
be described with a smaller l and larger M g.)

Initial state ``theta phi psi theta_dot phi_dot psi_dot`` (rad, rad/s), θ in [0, π].
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ...errors import InvalidInputError, UnphysicalInertiaError

__all__ = ["PARAMETER_NAMES", "INITIAL_NAMES", "check_parameters", "check_initial"]

PARAMETER_NAMES = ("I1", "I3", "M", "g", "l")
INITIAL_NAMES = ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")


def _finite_float(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidInputError(f"expected `{name}` to be a number, got {value!r}")
    x = float(value)
    if not np.isfinite(x):
        raise InvalidInputError(f"expected `{name}` to be finite, got {x}")
    return x


def _check_keys(given: Mapping[str, Any], allowed: tuple[str, ...], what: str) -> None:
    unknown = [k for k in given if k not in allowed]
    if unknown:
        raise InvalidInputError(f"unknown {what} {unknown[0]!r}: expected one of {', '.join(allowed)}")
    missing = [k for k in allowed if k not in given]
    if missing:
        raise InvalidInputError(f"missing {what} {missing[0]!r}: expected all of {', '.join(allowed)}")


def check_parameters(parameters: Mapping[str, Any]) -> dict[str, float]:
    """Return the parameters as floats, raising unless they describe a real heavy top.

    >>> check_parameters(dict(I1=1.0, I3=0.5, M=1.0, g=9.81, l=0.1))["l"]
    0.1
    """
    _check_keys(parameters, PARAMETER_NAMES, "parameter")
    p = {k: _finite_float(parameters[k], k) for k in PARAMETER_NAMES}
    for k in PARAMETER_NAMES:
        if not p[k] > 0:
            raise InvalidInputError(f"expected `{k}` > 0, got {p[k]!r}")
    i1_cm = p["I1"] - p["M"] * p["l"] ** 2
    if not i1_cm > 0:
        raise UnphysicalInertiaError(
            f"expected I1 > M l² (I1 is about the pivot; I1 - M l² is the moment about the centre of mass), "
            f"got I1 = {p['I1']:g} <= M l² = {p['M'] * p['l'] ** 2:g}")
    if 2 * i1_cm < p["I3"] * (1 - 1e-12):
        raise UnphysicalInertiaError(
            f"expected 2 (I1 - M l²) >= I3 (triangle inequality for the moments about the centre of mass), "
            f"got 2 (I1 - M l²) = {2 * i1_cm:g} < I3 = {p['I3']:g}; the motion depends only on I1, I3 and "
            "M g l, so the same top can be given with a smaller M l²")
    return p


def check_initial(initial: Mapping[str, Any]) -> dict[str, float]:
    """Return the initial state as floats, raising unless θ is in [0, π] and all are finite.

    >>> check_initial(dict(theta=0.5, phi=0, psi=0, theta_dot=0, phi_dot=0, psi_dot=5))["psi_dot"]
    5.0
    """
    _check_keys(initial, INITIAL_NAMES, "initial value")
    s = {k: _finite_float(initial[k], k) for k in INITIAL_NAMES}
    if not 0 <= s["theta"] <= np.pi:
        raise InvalidInputError(f"expected `theta` in [0, π], got {s['theta']!r}")
    return s
