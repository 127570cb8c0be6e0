"""The kick–drift–kick splitting of :mod:`.kick_drift`, compiled to C with its derived stage map.

:func:`.kick_drift.propagate` calls the compiled-to-Python stage map once per stage (~3 µs each):
a 10⁶-step order-6 run of the heavy top takes about a minute.  Here the stage map — printed from
its SymPy derivation by :func:`mechderive.derive.formats.to_c_source` — and the composed-step loop
(the schedule of :func:`.kick_drift.kdk_schedule`, chained as in :func:`.kick_drift.propagate`)
are one C file, built by :mod:`mechderive.core.cbuild` and cached on disk.  One call runs every
output interval, so the interpreter is out of the loop entirely.  The arithmetic is the same
sequence of stage maps as the Python driver's, so the two agree to rounding.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..core import cbuild
from .kick_drift import kdk_schedule

__all__ = ["CompiledSplitting", "compiled_splitting"]

_DRIVER = r"""
/* Advance y through n_intervals output intervals; interval i takes n_steps[i] composed steps of
   size h[i].  A composed step is K(head) [D(d_1) K(k_1)] ... [D(d_s) K(k_s)] (coefficients × h),
   and consecutive steps merge the trailing kick into the next leading one (kick_drift.propagate). */
void kdk_run(const double *y0, const double *par, int n_intervals, const long *n_steps, const double *h,
             double head, int n_stages, const double *drift, const double *kick, double *out)
{
    double y[NDIM], tmp[NDIM];
    for (int i = 0; i < NDIM; i++) { y[i] = y0[i]; out[i] = y0[i]; }
    for (int iv = 0; iv < n_intervals; iv++) {
        long n = n_steps[iv];
        double step = h[iv];
        if (n > 0) {
            stage_apply(y, 0.0, head * step, par, tmp);
            for (long s = 0; s < n; s++) {
                for (int k = 0; k < n_stages; k++) {
                    double kk = kick[k] * step;
                    if (k == n_stages - 1 && s < n - 1) kk += head * step;  /* merged with the next step's head */
                    stage_apply(y, drift[k] * step, kk, par, tmp);
                }
            }
        }
        for (int i = 0; i < NDIM; i++) out[(long)(iv + 1) * NDIM + i] = y[i];
    }
}

/* kdk_run, recording the state after every composed step in out (1 + sum n_steps rows): within an
   interval, between two steps, the step's end after the next step's leading kick, which the chaining
   merges into it; at the interval's end, its end.  The arithmetic is kdk_run's. */
void kdk_record(const double *y0, const double *par, int n_intervals, const long *n_steps, const double *h,
                double head, int n_stages, const double *drift, const double *kick, double *out)
{
    double y[NDIM], tmp[NDIM];
    long row = 0;
    for (int i = 0; i < NDIM; i++) { y[i] = y0[i]; out[i] = y0[i]; }
    for (int iv = 0; iv < n_intervals; iv++) {
        long n = n_steps[iv];
        double step = h[iv];
        if (n > 0) stage_apply(y, 0.0, head * step, par, tmp);
        for (long s = 0; s < n; s++) {
            for (int k = 0; k < n_stages; k++) {
                double kk = kick[k] * step;
                if (k == n_stages - 1 && s < n - 1) kk += head * step;
                stage_apply(y, drift[k] * step, kk, par, tmp);
            }
            row++;
            for (int i = 0; i < NDIM; i++) out[row * NDIM + i] = y[i];
        }
    }
}
"""


def _source(exprs: Any, state: Sequence[Any], h_drift: Any, h_kick: Any, params: Sequence[Any], name: str) -> str:
    from ..derive.formats import to_c_source

    fn = f"{name}_stage_expr"
    n, n_par = len(state), len(params)
    stage = to_c_source(exprs, [*state, h_drift, h_kick, *params], fn, include=False,
                        doc=f"{name}: one drift–kick stage, derived.")
    call = ", ".join([f"y[{i}]" for i in range(n)] + ["hd", "hk"] + [f"par[{i}]" for i in range(n_par)] + ["tmp"])
    return "\n".join([
        f"/* {name}: kick–drift–kick splitting on a stage map derived by mechderive (generated; safe to delete). */",
        "#include <math.h>",
        f"#define NDIM {n}",
        stage.replace(f"void {fn}(", f"static void {fn}(", 1),
        "static void stage_apply(double *y, double hd, double hk, const double *par, double *tmp)",
        f"{{ {fn}({call}); for (int i = 0; i < NDIM; i++) y[i] = tmp[i]; }}",
        _DRIVER,
        f"void kdk_dims(int *out) {{ out[0] = {n}; out[1] = {n_par}; }}",
    ]) + "\n"


@dataclass(frozen=True)
class CompiledSplitting:
    """A compiled composed kick–drift–kick splitting for one derived stage map."""

    name: str
    n: int
    n_par: int
    _run: Any
    _record: Any = None

    def propagate(self, y0: Sequence[float], params: Sequence[float], intervals: Sequence[tuple[int, float]],
                  weights: Sequence[float]) -> np.ndarray:
        """States after each output interval, shape (len(intervals) + 1, n); row 0 is ``y0``.

        ``intervals``: (number of composed steps, step size) per interval, as
        :func:`mechderive.systems.free_top.integrate._interval_steps` gives; ``weights`` the
        composition weights (order 2, 4 or 6).
        """
        args = _c_arguments(y0, params, intervals, weights)
        out = np.empty((len(intervals) + 1, self.n))
        self._run(*args, out)
        return out

    def propagate_recorded(self, y0: Sequence[float], params: Sequence[float], intervals: Sequence[tuple[int, float]],
                           weights: Sequence[float]) -> np.ndarray:
        """:meth:`propagate` (the same arithmetic) with the state recorded after every composed step:
        shape (1 + Σ n, n), row 0 ``y0``; within an interval the row between two steps is the end of
        the first followed by the leading kick of the next (merged with it by the chaining), at the
        interval's end its end."""
        args = _c_arguments(y0, params, intervals, weights)
        out = np.empty((1 + sum(n for n, _ in intervals), self.n))
        self._record(*args, out)
        return out


def compiled_splitting(name: str, build: Callable[[], tuple]) -> CompiledSplitting | None:
    """The compiled splitting ``name``, or None without a usable C compiler.

    ``build()`` returns (stage-map expressions, state symbols, h_drift symbol, h_kick symbol,
    parameter symbols) and runs — deriving — only when the library is not cached.
    """
    lib = cbuild.load_or_none(f"kdk_{name}", lambda: _source(*build(), name=name))
    if lib is None:
        return None
    dims = (ctypes.c_int * 2)()
    lib.kdk_dims(dims)
    fn = lib.kdk_run
    vec = np.ctypeslib.ndpointer(dtype=float, flags="C_CONTIGUOUS")
    longs = np.ctypeslib.ndpointer(dtype=np.int64, flags="C_CONTIGUOUS")
    fn.argtypes = [vec, vec, ctypes.c_int, longs, vec, ctypes.c_double, ctypes.c_int, vec, vec, vec]
    fn.restype = None
    rec = lib.kdk_record
    rec.argtypes = [vec, vec, ctypes.c_int, longs, vec, ctypes.c_double, ctypes.c_int, vec, vec, vec]
    rec.restype = None
    return CompiledSplitting(name=name, n=int(dims[0]), n_par=int(dims[1]), _run=fn, _record=rec)


def _c_arguments(y0: Sequence[float], params: Sequence[float], intervals: Sequence[tuple[int, float]],
                 weights: Sequence[float]) -> tuple:
    """The C driver's arguments before ``out``: state, parameters, the intervals and the stage schedule."""
    head, stages = kdk_schedule(weights)
    return (np.ascontiguousarray(y0, dtype=float), np.ascontiguousarray(params, dtype=float), len(intervals),
            np.ascontiguousarray([n for n, _ in intervals], dtype=np.int64),
            np.ascontiguousarray([h for _, h in intervals], dtype=float), float(head), len(stages),
            np.ascontiguousarray([d for d, _ in stages], dtype=float),
            np.ascontiguousarray([k for _, k in stages], dtype=float))
