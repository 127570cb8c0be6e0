"""How far an integrator may go, and what it says when it stops.

Every stepper of :mod:`mechderive.solvers` (compiled or not) stops with an
:class:`~mechderive.errors.IntegrationError` — never a NaN, never a loop without end — when

* the state, or the right-hand side at the initial state, is not finite (a NaN or an infinity:
  a parameter or initial value out of floating-point range, or a motion that blows up);
* it has taken ``max_steps`` steps (default :data:`MAX_STEPS`) without reaching the end; a
  fixed-step method, whose number of steps is known before it starts, refuses at once.

The messages say where the run got to and what to change.

>>> check_max_steps(None) == MAX_STEPS
True
>>> err = too_many_steps("DOP853", t=1.5, t_end=10.0, steps=100, max_steps=100)
>>> str(err).split(":")[0]
'expected DOP853 to reach t = 10 within max_steps = 100 steps, got to t = 1.5 after 100 steps'
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import IntegrationError, InvalidInputError

__all__ = ["MAX_STEPS", "check_max_steps", "too_many_steps", "check_fixed_steps", "nonfinite_state",
           "nonfinite_start", "first_nonfinite_row", "check_outputs"]

#: The default limit of steps of one integration: 10⁷ steps take ~10–30 s compiled (heavy top, ~1–2 µs
#: a step with the half-angle tracking; up to a few minutes where the tracking must refine every step)
#: and ~20 min through SciPy; the longest runs of the package and its tests take ≤ 2·10⁶ (a 10⁶-step
#: splitting and its Richardson rerun; 10⁴ nutation periods at rtol 1e-14: ~1.5·10⁶).  More means a
#: motion too fast or too long for the tolerance, better said in seconds than run for an hour.
MAX_STEPS = 10**7


def check_max_steps(max_steps: Any) -> int:
    """``max_steps`` as an int >= 1 (``None``: :data:`MAX_STEPS`)."""
    if max_steps is None:
        return MAX_STEPS
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise InvalidInputError(f"expected `max_steps` to be an integer >= 1, got {max_steps!r}")
    return int(max_steps)


def too_many_steps(method: str, *, t: float, t_end: float, steps: int, max_steps: int) -> IntegrationError:
    """The error of an adaptive run stopped at ``t`` after ``steps`` = ``max_steps`` steps."""
    return IntegrationError(f"expected {method} to reach t = {t_end:.6g} within max_steps = {max_steps} steps, "
                            f"got to t = {t:.6g} after {steps} steps: the motion is too fast or too long for this "
                            "tolerance; shorten t_end, loosen rtol, or raise max_steps")


def check_fixed_steps(method: str, steps: int, max_steps: int, *, step: float, t_end: float) -> None:
    """Refuse a fixed-step run of ``steps`` steps (of about ``step``, to ``t_end``) above ``max_steps``."""
    if steps > max_steps:
        raise IntegrationError(f"expected {method} to reach t = {t_end:.6g} within max_steps = {max_steps} steps, "
                               f"got {steps} steps of {step:.3g} needed: increase step, shorten t_end, or raise "
                               "max_steps")


def nonfinite_state(method: str, *, t: float, steps: int, member: int | None = None,
                    cause: BaseException | None = None) -> IntegrationError:
    """The error of a run whose state became NaN or infinite on the step from ``t`` (after ``steps``
    steps); ``member`` of an ensemble; ``cause`` the exception of a ``math`` function that said so."""
    who = "the state" if member is None else f"the state of member {member}"
    why = "" if cause is None else f" ({type(cause).__name__}: {cause})"
    return IntegrationError(f"expected {method} to keep {who} finite, got NaN or infinity{why} on the step from "
                            f"t = {t:.6g} (after {steps} steps): a parameter or initial value is probably out of "
                            "floating-point range, or the motion blows up there")


def nonfinite_start(method: str, *, t0: float, what: str = "the right-hand side") -> IntegrationError:
    """The error of a run that cannot start: ``what`` is NaN or infinite at the initial state."""
    return IntegrationError(f"expected {what} of {method} to be finite at the initial state (t = {t0:.6g}), got NaN "
                            "or infinity: a parameter or initial value is out of floating-point range")


def first_nonfinite_row(rows: np.ndarray) -> int | None:
    """The index of the first row of ``rows`` (2-d) holding a NaN or infinity, or None."""
    bad = ~np.isfinite(rows).all(axis=tuple(range(1, rows.ndim)))
    return int(np.argmax(bad)) if bad.any() else None



def check_outputs(method: str, outputs: dict[str, Any]) -> None:
    """Raise :class:`IntegrationError` naming the first of ``outputs`` (name → array, number or None)
    holding a NaN or an infinity — e.g. an energy that overflows while the state is still finite."""
    for name, value in outputs.items():
        if value is not None and not np.all(np.isfinite(np.asarray(value, dtype=float))):
            raise IntegrationError(f"expected every output of {method} to be finite, got NaN or infinity in `{name}`: "
                                   "a parameter or initial value is probably out of floating-point range (squares "
                                   "of ω or L overflow beyond ~1e154)")
