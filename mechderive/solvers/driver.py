"""One integration driver for every system: a derived term, a solver, a tolerance controller, one trajectory.

* A :class:`Term` is a derived, autonomous first-order system y' = f(y; p): its SymPy right-hand
  side (built on demand), its state and parameter symbols, its invariants (functions of (p, y)),
  and, optionally, where a unit quaternion sits in the state (renormalised on output, its Euler
  half-angles followed along the steps: :mod:`.half_angles`).  A non-autonomous system carries
  t as a state variable with t' = 1.
* The solver is DOP853: compiled to C (:mod:`.dop853_c`) where a compiler exists, SciPy's stepper
  on the compiled-to-NumPy right-hand side otherwise (:func:`.dop853.run_dop853`).
* :func:`integrate_to_rtol` is the controller: rerun tighter while the measured global error exceeds
  the requested tolerance.
* :class:`Trajectory` holds the states at the output times, the invariants along them, and the
  global error estimate measured on the run (the distance to a rerun at a tighter tolerance).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import InvalidInputError
from .dop853 import SCIPY_MIN_RTOL, check_backend, run_dop853

__all__ = ["Term", "Trajectory", "integrate", "integrate_to_rtol", "MAX_ATTEMPTS"]


@dataclass(frozen=True)
class Term:
    """A derived system y' = f(y; p).

    ``name`` keys the compiled code in the caches (one name per derived system: a system built from a
    user's text includes a hash of that text).  ``build()`` returns (right-hand-side expressions, state
    symbols, parameter symbols) and runs — deriving with SymPy — only when the compiled code is in no
    cache.  ``invariants()`` returns the invariants' expressions in the parameter and state symbols,
    named by ``invariant_names``.
    ``quaternion``: index of q0 of a unit quaternion (q0, q1, q2, q3) in the state, or None.
    """

    name: str
    build: Callable[[], tuple[Sequence[Any], Sequence[Any], Sequence[Any]]]
    invariants: Callable[[], Sequence[Any]] | None = None
    invariant_names: tuple[str, ...] = ()
    quaternion: int | None = None

    def rhs(self) -> Callable[..., list]:
        """f compiled to NumPy, called as f(*y, *p) (for SciPy's stepper)."""
        return _numpy_rhs(self)

    def invariant_function(self) -> Callable[..., list] | None:
        """g(*p, *y) -> list of the invariants, or None when the term has none."""
        return None if self.invariants is None else _numpy_invariants(self)


@functools.cache
def _numpy_rhs(term: Term) -> Callable[..., list]:
    from ..core.codecache import cached_lambdify

    def build() -> tuple:
        exprs, state, params = term.build()
        return [*state, *params], list(exprs)
    return cached_lambdify(f"{term.name}.rhs", build)[0]


@functools.cache
def _numpy_invariants(term: Term) -> Callable[..., list]:
    from ..core.codecache import cached_lambdify

    def build() -> tuple:
        _, state, params = term.build()
        return [*params, *state], list(term.invariants())
    return cached_lambdify(f"{term.name}.invariants", build)[0]


@functools.cache
def _compiled(term: Term) -> Any:
    from .dop853_c import compiled_dop853

    def build() -> tuple:
        import sympy as sp

        exprs, state, params = term.build()
        return sp.Matrix(list(exprs)), list(state), list(params)
    return compiled_dop853(term.name, build)


@dataclass
class Trajectory:
    """States ``y`` (N, n) at the times ``t`` (N,), with what the run measured.

    ``error_estimate`` is the largest distance, over the samples and the state components, to a rerun
    at a tighter tolerance (times the factor of :func:`.dop853.reference_tolerance`), or None when no
    rerun was made; ``component_error`` the same per state component (n,).  ``invariants`` (N, k) are
    the term's invariants along the run, named by ``invariant_names``.
    """

    t: np.ndarray
    y: np.ndarray
    n_evaluations: int
    n_steps: int | None
    backend: str
    wall: float
    error_estimate: float | None = None
    component_error: np.ndarray | None = None
    error_estimate_kind: str = ""
    invariants: np.ndarray | None = None
    invariant_names: tuple[str, ...] = ()
    args: np.ndarray | None = None  # tracked quaternion half-angles (N, 2), when asked for
    extra: dict = field(default_factory=dict)

    def invariant(self, name: str) -> np.ndarray:
        return self.invariants[:, self.invariant_names.index(name)]


def integrate(term: Term, y0: Sequence[float], t: Sequence[float], params: Sequence[float], *, rtol: float,
              atol: float | None = None, backend: str = "auto", estimate_error: bool = True,
              track: Sequence[float] | None = None, max_steps: int | None = None) -> Trajectory:
    """Integrate ``term`` from ``y0`` at ``t[0]`` through the increasing times ``t`` with parameter values ``params``.

    ``backend``: "c" (the compiled stepper; an error where there is no compiler), "scipy", or "auto"
    (C where available).  ``atol`` defaults to ``rtol * 1e-3``.  ``track = (σ0, δ0)`` follows the
    half-angles of the term's quaternion (it must have one).  Raises
    :class:`~mechderive.errors.IntegrationError` when the run cannot reach ``t[-1]``.
    """
    check_backend(backend)
    t = np.asarray(t, dtype=float)
    y0 = np.asarray(y0, dtype=float)
    par = tuple(float(x) for x in params)
    atol = rtol * 1e-3 if atol is None else atol
    compiled = None if backend == "scipy" else _compiled(term)
    if compiled is None and backend == "c":
        from .dop853_c import unavailable_error
        raise unavailable_error(term.name, "scipy")
    fun = None
    if compiled is None:
        rhs = term.rhs()

        def fun(_t: float, y: np.ndarray) -> list:
            return rhs(*y.tolist(), *par)
    tracking = None
    if track is not None:
        if term.quaternion is None:
            raise InvalidInputError(f"term {term.name!r} has no quaternion to track")
        tracking = (term.quaternion, tuple(track))
    sol, wall, ref, kind, factor = run_dop853(fun, t, y0, rtol, atol, reference=estimate_error, compiled=compiled,
                                              params=par, track=tracking, max_steps=max_steps)
    y = np.ascontiguousarray(sol.y.T)
    est = comp = None
    if ref is not None:
        comp = np.max(np.abs(y - ref.y.T), axis=0) * factor
        est = float(np.max(comp)) if comp.size else 0.0
        kind = f"distance to {kind}"
    traj = Trajectory(t=t, y=y, n_evaluations=int(sol.nfev), n_steps=sol.steps,
                      backend="scipy" if compiled is None else "c", wall=wall, error_estimate=est,
                      component_error=comp, error_estimate_kind=kind if ref is not None else "", args=sol.args)
    fn = term.invariant_function()
    if fn is not None:
        with np.errstate(all="ignore"):
            vals = fn(*par, *y.T)
        traj.invariants = np.stack([np.broadcast_to(np.asarray(v, float), t.shape) for v in vals], axis=-1)
        traj.invariant_names = term.invariant_names
    return traj


#: Integrator runs per scene at most: the first at the scene's rtol, then tightened.
MAX_ATTEMPTS = 3


def integrate_to_rtol(run: Callable[[float], Any], estimate: Callable[[Any], float | None],
                      rtol: float) -> tuple[Any, list[dict]]:
    """Run the integrator at ``rtol``; while the global error estimate exceeds it, rerun tighter.

    DOP853 bounds the error per step; over many steps the global error grows past it (×20 over
    ten nutation periods is typical).  The global error of a high-order method scales close to
    linearly with its tolerance, so the next tolerance is the last one times rtol/estimate, with
    a safety factor 1/2, down to the smallest SciPy accepts (2.3e-14).  With the compiled
    stepper a rerun costs milliseconds.  Returns the last run and one record per attempt.
    """
    tol, attempts = rtol, []
    while True:
        traj = run(tol)
        est = estimate(traj)
        attempts.append({"integrator_rtol": tol, "error_estimate": est})
        if est is None or est <= rtol or len(attempts) >= MAX_ATTEMPTS or tol <= SCIPY_MIN_RTOL:
            return traj, attempts
        tol = max(tol * 0.5 * rtol / est, SCIPY_MIN_RTOL)
