"""SciPy's DOP853 on a compiled right-hand side, with the error estimate both integrators report.

The estimate is the distance to a second run at rtol/1000 and atol/1000; SciPy raises any
rtol below 100·ε to 2.3e-14, so from rtol ≈ 1e-11 down the second run is not much tighter
and the estimate is a lower bound — callers say so in their ``error_estimate_kind``.
"""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from ..errors import IntegrationError

__all__ = ["SCIPY_MIN_RTOL", "run_dop853"]

#: solve_ivp raises rtol below 100·ε to this value.
SCIPY_MIN_RTOL = 2.3e-14


def run_dop853(fun: Callable[[float, np.ndarray], Any], t: np.ndarray, y0: np.ndarray, rtol: float, atol: float,
               *, reference: bool) -> tuple[Any, float, Any, str]:
    """(solution at ``t``, wall seconds, reference solution or None, how the reference was made)."""
    from scipy.integrate import solve_ivp

    def solve(rt: float, at: float) -> Any:
        sol = solve_ivp(fun, (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=rt, atol=at)
        if not sol.success:
            raise IntegrationError(f"expected solve_ivp(DOP853) to reach t = {t[-1]:g}, got: {sol.message}")
        return sol

    start = time.perf_counter()
    sol = solve(rtol, atol)
    wall = time.perf_counter() - start
    if not reference:
        return sol, wall, None, "not requested"
    rt_ref = max(rtol * 1e-3, SCIPY_MIN_RTOL)
    return sol, wall, solve(rt_ref, atol * 1e-3), f"DOP853 at rtol={rt_ref:.2g}, atol={atol * 1e-3:.2g}"
