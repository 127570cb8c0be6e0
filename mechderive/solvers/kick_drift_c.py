"""The kick–drift–kick splitting of :mod:`.kick_drift`, compiled to C with its derived stage map.

:func:`.kick_drift.propagate` calls the compiled-to-Python stage map once per stage (~3 µs each):
a 10⁶-step order-6 run of the heavy top takes about a minute.  Here the stage map — printed from
its SymPy derivation by :func:`mechderive.derive.formats.to_c_source` — and the composed-step loop
(the schedule of :func:`.kick_drift.kdk_schedule`, chained as in :func:`.kick_drift.propagate`)
are one C file, built by :mod:`mechderive.core.cbuild` and cached on disk.  The C loop runs every
output interval, returning to Python only about every 0.05 s (so that Ctrl-C is seen; the
arithmetic does not depend on where it returns), and stops when the state is no longer finite.
The arithmetic is the same sequence of stage maps as the Python driver's, so the two agree to
rounding.
"""

from __future__ import annotations

import ctypes
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..core import cbuild
from .kick_drift import kdk_schedule
from .limits import nonfinite_start, nonfinite_state

# C's long, whose size the platform decides (4 bytes on Windows)
_LONG = np.dtype(f"int{8 * ctypes.sizeof(ctypes.c_long)}")

__all__ = ["CompiledSplitting", "compiled_splitting"]

_DRIVER = r"""
/* ---- the run, resumable: where the last call stopped ---- */
typedef struct {
    double y[NDIM];
    long iv, s, row;       /* the interval, the next composed step in it, the last row recorded */
    int started;           /* 0 in a zeroed KdkRun: kdk_advance starts it */
} KdkRun;

long kdk_run_bytes(void) { return (long)sizeof(KdkRun); }
void kdk_where(const KdkRun *run, long *out) { out[0] = run->iv; out[1] = run->s; }

/* statuses: mechderive.solvers.kick_drift_c */
#define KDK_DONE 0
#define KDK_NONFINITE 1
#define KDK_CHUNK 2

static int kdk_finite(const double *v) { for (int i = 0; i < NDIM; i++) if (!isfinite(v[i])) return 0; return 1; }

/* Advance y through n_intervals output intervals; interval i takes n_steps[i] composed steps of
   size h[i].  A composed step is K(head) [D(d_1) K(k_1)] ... [D(d_s) K(k_s)] (coefficients x h),
   and consecutive steps merge the trailing kick into the next leading one (kick_drift.propagate).
   record = 0: out gets y0 and the state at every interval's end (n_intervals + 1 rows); record = 1:
   y0 and the state after every composed step (1 + sum n_steps rows) - within an interval, between
   two steps, the step's end after the next step's leading kick, which the chaining merges into it;
   at the interval's end, its end.
   run: a zeroed KdkRun on the first call; the call returns KDK_CHUNK after about `budget` stage
   calls (after a whole composed step), and a call with the same run and arrays goes on where it
   stopped, with the same arithmetic as one call.  KDK_NONFINITE: the state stopped being finite
   on step run->s of interval run->iv (1-based s; s = 0: the initial state). */
int kdk_advance(KdkRun *run, const double *y0, const double *par, int n_intervals, const long *n_steps,
                const double *h, double head, int n_stages, const double *drift, const double *kick,
                double *out, int record, long budget)
{
    double y[NDIM], tmp[NDIM];
    if (!run->started) {
        run->started = 1; run->iv = 0; run->s = 0; run->row = 0;
        for (int i = 0; i < NDIM; i++) { run->y[i] = y0[i]; out[i] = y0[i]; }
        if (!kdk_finite(run->y)) return KDK_NONFINITE;
    }
    long iv = run->iv, s = run->s, row = run->row, calls = 0;
    int status = KDK_DONE;
    for (int i = 0; i < NDIM; i++) y[i] = run->y[i];
    while (iv < n_intervals) {
        long n = n_steps[iv];
        double step = h[iv];
        if (s == 0 && n > 0) stage_apply(y, 0.0, head * step, par, tmp);
        while (s < n) {
            for (int k = 0; k < n_stages; k++) {
                double kk = kick[k] * step;
                if (k == n_stages - 1 && s < n - 1) kk += head * step;  /* merged with the next step's head */
                stage_apply(y, drift[k] * step, kk, par, tmp);
            }
            s++;
            if (record) { row++; for (int i = 0; i < NDIM; i++) out[row * NDIM + i] = y[i]; }
            if (!kdk_finite(y)) { status = KDK_NONFINITE; goto done; }
            calls += n_stages;
            if (calls >= budget && s < n) { status = KDK_CHUNK; goto done; }
        }
        if (!record) for (int i = 0; i < NDIM; i++) out[(iv + 1) * NDIM + i] = y[i];
        iv++; s = 0;
        if (calls >= budget && iv < n_intervals) { status = KDK_CHUNK; goto done; }
    }
done:
    run->iv = iv; run->s = s; run->row = row;
    for (int i = 0; i < NDIM; i++) run->y[i] = y[i];
    return status;
}
"""

_DONE, _NONFINITE, _CHUNK = 0, 1, 2


def _source(exprs: Any, state: Sequence[Any], h_drift: Any, h_kick: Any, params: Sequence[Any], name: str) -> str:
    from ..core.codegen import to_c_source

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
    _advance: Any
    _where: Any = None
    _run_words: int = 0

    def propagate(self, y0: Sequence[float], params: Sequence[float], intervals: Sequence[tuple[int, float]],
                  weights: Sequence[float], *, t0: float = 0.0) -> np.ndarray:
        """States after each output interval, shape (len(intervals) + 1, n); row 0 is ``y0``.

        ``intervals``: (number of composed steps, step size) per interval, as
        :func:`mechderive.solvers.driver.interval_steps` gives; ``weights`` the
        composition weights (order 2, 4 or 6).  The C loop returns to Python about every
        :data:`~.dop853_c.CHUNK_SECONDS` (so Ctrl-C is seen), with the same arithmetic as one call.
        Raises :class:`~mechderive.errors.IntegrationError` when the state stops being finite,
        naming the time (``t0`` the time of ``y0``).
        """
        return self._drive(y0, params, intervals, weights, t0, record=False)

    def propagate_recorded(self, y0: Sequence[float], params: Sequence[float], intervals: Sequence[tuple[int, float]],
                           weights: Sequence[float], *, t0: float = 0.0) -> np.ndarray:
        """:meth:`propagate` (the same arithmetic) with the state recorded after every composed step:
        shape (1 + Σ n, n), row 0 ``y0``; within an interval the row between two steps is the end of
        the first followed by the leading kick of the next (merged with it by the chaining), at the
        interval's end its end."""
        return self._drive(y0, params, intervals, weights, t0, record=True)

    def _drive(self, y0: Sequence[float], params: Sequence[float], intervals: Sequence[tuple[int, float]],
               weights: Sequence[float], t0: float, *, record: bool, chunk_calls: int | None = None) -> np.ndarray:
        """Call the C loop until it is done, in pieces of ``chunk_calls`` stage calls (None: adapted
        to :data:`~.dop853_c.CHUNK_SECONDS`, as :meth:`.dop853_c.CompiledDOP853.solve` does)."""
        from .dop853_c import CHUNK_SECONDS, FIRST_CHUNK

        args = _c_arguments(y0, params, intervals, weights)
        rows = 1 + (sum(n for n, _ in intervals) if record else len(intervals))
        out = np.empty((rows, self.n))
        run = np.zeros(self._run_words)  # the C KdkRun, zeroed: not started
        budget = FIRST_CHUNK if chunk_calls is None else max(1, int(chunk_calls))
        while True:
            start = time.perf_counter()
            status = self._advance(run, *args, out, int(record), budget)
            if status != _CHUNK:
                break
            if chunk_calls is None:
                fit = budget * CHUNK_SECONDS / max(time.perf_counter() - start, 1e-6)
                budget = int(min(4.0 * budget, max(fit, 64.0), 2.0**30))
        if status == _NONFINITE:
            where = np.zeros(2, dtype=_LONG)
            self._where(run, where)
            iv, s = int(where[0]), int(where[1])
            label = f"the kick–drift–kick splitting ({self.name}, compiled)"
            if iv == 0 and s == 0:
                raise nonfinite_start(label, t0=t0, what="the initial state")
            # step s (1-based) of interval iv went wrong: it started after s - 1 steps of that interval
            t = t0 + sum(n * h for n, h in intervals[:iv]) + (s - 1) * intervals[iv][1]
            raise nonfinite_state(label, t=t, steps=sum(n for n, _ in intervals[:iv]) + s - 1)
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
    lib.kdk_run_bytes.restype = ctypes.c_long
    fn = lib.kdk_advance
    vec = np.ctypeslib.ndpointer(dtype=float, flags="C_CONTIGUOUS")
    longs = np.ctypeslib.ndpointer(dtype=_LONG, flags="C_CONTIGUOUS")
    fn.argtypes = [vec, vec, vec, ctypes.c_int, longs, vec, ctypes.c_double, ctypes.c_int, vec, vec, vec, ctypes.c_int,
                   ctypes.c_long]
    fn.restype = ctypes.c_int
    where = lib.kdk_where
    where.argtypes = [vec, longs]
    where.restype = None
    words = -(-int(lib.kdk_run_bytes()) // 8)  # the KdkRun in doubles: 8-byte aligned
    return CompiledSplitting(name=name, n=int(dims[0]), n_par=int(dims[1]), _advance=fn, _where=where,
                             _run_words=words)


def _c_arguments(y0: Sequence[float], params: Sequence[float], intervals: Sequence[tuple[int, float]],
                 weights: Sequence[float]) -> tuple:
    """The C driver's arguments before ``out``: state, parameters, the intervals and the stage schedule."""
    head, stages = kdk_schedule(weights)
    return (np.ascontiguousarray(y0, dtype=float), np.ascontiguousarray(params, dtype=float), len(intervals),
            np.ascontiguousarray([n for n, _ in intervals], dtype=_LONG),
            np.ascontiguousarray([h for _, h in intervals], dtype=float), float(head), len(stages),
            np.ascontiguousarray([d for d, _ in stages], dtype=float),
            np.ascontiguousarray([k for _, k in stages], dtype=float))
