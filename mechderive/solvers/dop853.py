"""DOP853 on a derived right-hand side — compiled C or SciPy — with the error estimate both tops report.

Two backends run the same algorithm (the same tableau, controller and dense output, so the same
steps to rounding):

* ``"c"`` — :mod:`.dop853_c`: the stepper and the right-hand side compiled together by the system
  C compiler (~1 µs a step for the heavy top);
* ``"scipy"`` — :func:`scipy.integrate.solve_ivp` on the compiled-to-Python right-hand side
  (~100 µs a step), also the only one for right-hand sides that call back into Python (a torque).

``backend="auto"`` takes C where a compiler is found (see :mod:`mechderive.core.cbuild`).

The error estimate is the distance to a second run at rtol/1000 and atol/1000; both backends
raise any rtol below 100·ε to 2.2e-14 (SciPy's rule; :data:`SCIPY_MIN_RTOL` is the value SciPy
reports), so from rtol ≈ 1e-11 down the second run is not much tighter and the estimate is a lower
bound — callers say so in their ``error_estimate_kind``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import IntegrationError, InvalidInputError

__all__ = ["SCIPY_MIN_RTOL", "BACKENDS", "Dop853Run", "run_dop853", "check_backend"]

#: solve_ivp raises rtol below 100·ε to this value.
SCIPY_MIN_RTOL = 2.3e-14
BACKENDS = ("auto", "c", "scipy")


@dataclass(frozen=True)
class Dop853Run:
    """One DOP853 run: ``y`` of shape (n, N) (as SciPy's), right-hand-side evaluations, accepted steps."""

    y: np.ndarray
    nfev: int
    steps: int | None


def check_backend(backend: str) -> str:
    """Validate ``backend`` (one of :data:`BACKENDS`)."""
    if backend not in BACKENDS:
        raise InvalidInputError(f"expected backend one of {', '.join(map(repr, BACKENDS))}, got {backend!r}")
    return backend


def run_dop853(fun: Callable[[float, np.ndarray], Any] | None, t: np.ndarray, y0: np.ndarray, rtol: float,
               atol: float, *, reference: bool, compiled: Any = None,
               params: Sequence[float] = ()) -> tuple[Dop853Run, float, Dop853Run | None, str]:
    """(run at ``t``, wall seconds of that run, reference run or None, how the reference was made).

    With ``compiled`` (a :class:`~.dop853_c.CompiledDOP853`) the C stepper runs with ``params``;
    otherwise SciPy's ``solve_ivp`` on ``fun(t, y)``.
    """
    if compiled is not None:
        def solve(rt: float, at: float) -> Dop853Run:
            y, stats = compiled.solve(t, y0, params, rt, at)
            return Dop853Run(y=y.T, nfev=stats["nfev"], steps=stats["steps"])
        label = "compiled DOP853"
    else:
        from scipy.integrate import solve_ivp

        def solve(rt: float, at: float) -> Dop853Run:
            sol = solve_ivp(fun, (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=rt, atol=at)
            if not sol.success:
                raise IntegrationError(f"expected solve_ivp(DOP853) to reach t = {t[-1]:g}, got: {sol.message}")
            return Dop853Run(y=sol.y, nfev=int(sol.nfev), steps=None)
        label = "DOP853"

    start = time.perf_counter()
    sol = solve(rtol, atol)
    wall = time.perf_counter() - start
    if not reference:
        return sol, wall, None, "not requested"
    rt_ref = max(rtol * 1e-3, SCIPY_MIN_RTOL)
    return sol, wall, solve(rt_ref, atol * 1e-3), f"{label} at rtol={rt_ref:.2g}, atol={atol * 1e-3:.2g}"
