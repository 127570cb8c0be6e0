"""DOP853 in C on a derived right-hand side: SciPy's algorithm without the interpreter in the loop.

SciPy's ``solve_ivp(method="DOP853")`` spends most of its time in Python: per step twelve calls of
the right-hand side and a dozen small NumPy operations, ~100 µs, against ~1 µs of arithmetic for
the 7-dimensional heavy top.  This module generates one C file holding

* the right-hand side, printed from the SymPy derivation by
  :func:`mechderive.derive.formats.to_c_source` (cse'd), and
* the DOP853 stepper of Hairer, Nørsett & Wanner (*Solving ODEs I*, §II.5 and §II.10), written to
  follow SciPy's ``scipy.integrate._ivp.rk.DOP853`` step for step: the same Butcher tableau
  (the coefficients are read from SciPy at generation time and printed exactly), the same
  initial-step heuristic (``select_initial_step``), the same error norm (the 5th- and 3rd-order
  estimates combined), the same step-size controller (safety 0.9, factors 0.2–10, exponent
  -1/8, no growth right after a rejection) and the same 7th-order dense output for the output
  times, so it takes the same steps as ``solve_ivp`` to rounding;

compiles it with the system compiler (:mod:`mechderive.core.cbuild`, cached on disk) and calls it
through :mod:`ctypes`.  The systems are autonomous (no explicit t), as both tops are.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import IntegrationError
from ..core import cbuild

__all__ = ["CompiledDOP853", "compiled_dop853", "dop853_c_source", "unavailable_error", "MIN_RTOL"]

#: The smallest rtol accepted, as in SciPy (100 ε): below it the controller chases rounding.
MIN_RTOL = 100 * np.finfo(float).eps

_STATUS = {
    1: "the step size fell below 10 ulp of t (the solution is probably singular or blows up)",
    2: "the maximum number of steps was reached",
    3: "the solution became NaN or infinite",
}

_DRIVER = r"""
/* ---- DOP853 (Hairer, Nørsett & Wanner), following scipy.integrate._ivp.rk.DOP853 ---- */
#define NST 12     /* stages of the step */
#define NSTX 16    /* stages including the three of the dense output */
#define SAFETY 0.9
#define MIN_FACTOR 0.2
#define MAX_FACTOR 10.0
#define EXPONENT (-1.0 / 8.0)   /* -1/(error estimator order + 1) */

static double rms_scaled(const double *x, const double *scale)
{
    double s = 0.0;
    for (int i = 0; i < NDIM; i++) { double v = x[i] / scale[i]; s += v * v; }
    return sqrt(s / NDIM);
}

/* K[s] = f(y + h Σ_{j<s} A[s][j] K[j]): one stage, of the step or of the dense output */
static void stage(int s, double h, const double *y, double K[NSTX][NDIM], const double *par, double *ytmp)
{
    for (int i = 0; i < NDIM; i++) {
        double acc = 0.0;
        for (int j = 0; j < s; j++) acc += DOP_A[s][j] * K[j][i];
        ytmp[i] = y[i] + h * acc;
    }
    rhs(ytmp, par, K[s]);
}

/* select_initial_step of scipy.integrate._ivp.common, order 7 */
static double initial_step(const double *y0, const double *f0, const double *par, double interval,
                           double rtol, double atol, long *nfev)
{
    double scale[NDIM], y1[NDIM], f1[NDIM], diff[NDIM];
    for (int i = 0; i < NDIM; i++) scale[i] = atol + fabs(y0[i]) * rtol;
    double d0 = rms_scaled(y0, scale), d1 = rms_scaled(f0, scale);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > interval) h0 = interval;
    for (int i = 0; i < NDIM; i++) y1[i] = y0[i] + h0 * f0[i];
    rhs(y1, par, f1); (*nfev)++;
    for (int i = 0; i < NDIM; i++) diff[i] = f1[i] - f0[i];
    double d2 = rms_scaled(diff, scale) / h0;
    double h1 = (d1 <= 1e-15 && d2 <= 1e-15) ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / fmax(d1, d2), 1.0 / 8.0);
    double h = 100 * h0;
    if (h1 < h) h = h1;
    if (interval < h) h = interval;
    return h;
}

/* Integrate y' = f(y) from t_out[0] (y0) and write y at every t_out[k] (increasing) into y_out.
   h_inout: the step to try first (0: choose one); on return the step to continue with.
   stats: nfev, accepted steps, rejected steps.  Returns 0, or a status of _STATUS. */
int dop853_solve(const double *par, const double *y0, int n_out, const double *t_out, double *y_out,
                 double rtol, double atol, long max_steps, double *h_inout, long *stats)
{
    double K[NSTX][NDIM], y[NDIM], y_new[NDIM], ytmp[NDIM], F[7][NDIM];
    long nfev = 0, nstep = 0, nrej = 0;
    double t = t_out[0], t_end = t_out[n_out - 1];
    int k = 1, status = 0;
    for (int i = 0; i < NDIM; i++) { y[i] = y0[i]; y_out[i] = y0[i]; }
    if (n_out < 2) { stats[0] = stats[1] = stats[2] = 0; return 0; }
    rhs(y, par, K[0]); nfev++;
    double h_abs = *h_inout > 0 ? *h_inout : initial_step(y, K[0], par, t_end - t, rtol, atol, &nfev);
    while (k < n_out) {
        double min_step = 10 * fabs(nextafter(t, INFINITY) - t);
        if (h_abs < min_step) h_abs = min_step;
        int rejected = 0;
        double t_new, h;
        for (;;) {
            if (h_abs < min_step) { status = 1; goto done; }
            t_new = t + h_abs;
            if (t_new > t_end) t_new = t_end;
            h = t_new - t;
            h_abs = fabs(h);
            for (int s = 1; s < NST; s++) { stage(s, h, y, K, par, ytmp); nfev++; }
            for (int i = 0; i < NDIM; i++) {
                double acc = 0.0;
                for (int j = 0; j < NST; j++) acc += DOP_B[j] * K[j][i];
                y_new[i] = y[i] + h * acc;
            }
            rhs(y_new, par, K[NST]); nfev++;
            double e5 = 0.0, e3 = 0.0;
            for (int i = 0; i < NDIM; i++) {
                double sc = atol + fmax(fabs(y[i]), fabs(y_new[i])) * rtol;
                double a5 = 0.0, a3 = 0.0;
                for (int j = 0; j <= NST; j++) { a5 += DOP_E5[j] * K[j][i]; a3 += DOP_E3[j] * K[j][i]; }
                a5 /= sc; a3 /= sc;
                e5 += a5 * a5; e3 += a3 * a3;
            }
            double err = (e5 == 0.0 && e3 == 0.0) ? 0.0 : h_abs * e5 / sqrt((e5 + 0.01 * e3) * NDIM);
            if (err < 1.0) {
                double factor = err == 0.0 ? MAX_FACTOR : fmin(MAX_FACTOR, SAFETY * pow(err, EXPONENT));
                if (rejected && factor > 1.0) factor = 1.0;
                h_abs *= factor;
                break;
            }
            /* a NaN error norm also lands here and shrinks the step, as in SciPy */
            double shrink = SAFETY * pow(err, EXPONENT);
            h_abs *= (shrink > MIN_FACTOR) ? shrink : MIN_FACTOR;
            rejected = 1; nrej++;
        }
        nstep++;
        int dense = 0;
        while (k < n_out && t_out[k] <= t_new) {
            double *out = y_out + (long)k * NDIM;
            if (t_out[k] == t_new) {
                for (int i = 0; i < NDIM; i++) out[i] = y_new[i];
            } else {
                if (!dense) {
                    for (int s = NST + 1; s < NSTX; s++) { stage(s, h, y, K, par, ytmp); nfev++; }
                    for (int i = 0; i < NDIM; i++) {
                        double dy = y_new[i] - y[i];
                        F[0][i] = dy;
                        F[1][i] = h * K[0][i] - dy;
                        F[2][i] = 2 * dy - h * (K[NST][i] + K[0][i]);
                        for (int r = 0; r < 4; r++) {
                            double acc = 0.0;
                            for (int j = 0; j < NSTX; j++) acc += DOP_D[r][j] * K[j][i];
                            F[3 + r][i] = h * acc;
                        }
                    }
                    dense = 1;
                }
                double x = (t_out[k] - t) / h;
                for (int i = 0; i < NDIM; i++) {
                    double v = 0.0;
                    for (int r = 6; r >= 0; r--) { v += F[r][i]; v *= ((6 - r) % 2 == 0) ? x : 1.0 - x; }
                    out[i] = y[i] + v;
                }
            }
            k++;
        }
        t = t_new;
        for (int i = 0; i < NDIM; i++) {
            if (!isfinite(y_new[i])) { status = 3; goto done; }
            y[i] = y_new[i];
            K[0][i] = K[NST][i];
        }
        if (nstep >= max_steps && k < n_out) { status = 2; goto done; }
    }
done:
    *h_inout = h_abs;
    stats[0] = nfev; stats[1] = nstep; stats[2] = nrej;
    return status;
}
"""


def _c_array(name: str, values: np.ndarray) -> str:
    values = np.asarray(values, dtype=float)
    if values.ndim == 1:
        body = ", ".join(repr(float(v)) for v in values)
        return f"static const double {name}[{values.size}] = {{{body}}};"
    rows = ",\n    ".join("{" + ", ".join(repr(float(v)) for v in row) + "}" for row in values)
    return f"static const double {name}[{values.shape[0]}][{values.shape[1]}] = {{\n    {rows}}};"


def dop853_c_source(exprs: Any, state: Sequence[Any], params: Sequence[Any], *, name: str) -> str:
    """The complete C source: the right-hand side ``exprs`` (ẏ in the order of ``state``) and the stepper.

    ``exprs`` are SymPy expressions in the symbols ``state`` and ``params`` only (autonomous).
    """
    from scipy.integrate._ivp import dop853_coefficients as coef

    from ..derive.formats import to_c_source

    n, n_par = len(state), len(params)
    fn = f"{name}_rhs_expr"
    rhs_source = to_c_source(exprs, [*state, *params], fn, include=False,
                             doc=f"{name}: the derived right-hand side, d(state)/dt.")
    glue_args = ", ".join([f"y[{i}]" for i in range(n)] + [f"par[{i}]" for i in range(n_par)] + ["dy"])
    parts = [
        f"/* {name}: DOP853 on a right-hand side derived by mechderive (generated; safe to delete). */",
        "#include <math.h>",
        f"#define NDIM {n}",
        # SciPy's tableau, printed exactly (repr round-trips); prefixed so no derived name can clash
        _c_array("DOP_A", coef.A), _c_array("DOP_B", coef.B), _c_array("DOP_E3", coef.E3),
        _c_array("DOP_E5", coef.E5), _c_array("DOP_D", coef.D),
        rhs_source.replace(f"void {fn}(", f"static void {fn}(", 1),
        f"static void rhs(const double *y, const double *par, double *dy) {{ {fn}({glue_args}); }}",
        _DRIVER,
    ]
    return "\n".join(parts)


@dataclass(frozen=True)
class CompiledDOP853:
    """A compiled DOP853 stepper for one derived system with ``n`` state and ``n_par`` parameter values."""

    name: str
    n: int
    n_par: int
    _solve: Any

    def solve(self, t_eval: np.ndarray, y0: np.ndarray, params: Sequence[float], rtol: float, atol: float, *,
              max_steps: int = 10**9) -> tuple[np.ndarray, dict]:
        """(y at every ``t_eval``, shape (N, n); dict(nfev, steps, rejected)).

        ``t_eval`` increasing with ``t_eval[0]`` the initial time; ``rtol`` is raised to
        :data:`MIN_RTOL` as in SciPy.  Raises :class:`~mechderive.errors.IntegrationError` when
        the step size collapses, the solution stops being finite, or ``max_steps`` is reached.
        """
        t = np.ascontiguousarray(t_eval, dtype=float)
        y0 = np.ascontiguousarray(y0, dtype=float)
        par = np.ascontiguousarray(params, dtype=float)
        if y0.shape != (self.n,) or par.shape != (self.n_par,):
            raise IntegrationError(f"expected y0 of shape ({self.n},) and {self.n_par} parameters, got "
                                   f"{y0.shape} and {par.shape}")
        out = np.empty((t.size, self.n))
        stats = (ctypes.c_long * 3)()
        h = ctypes.c_double(0.0)
        status = self._solve(par, y0, int(t.size), t, out, float(max(rtol, MIN_RTOL)), float(atol),
                             int(max_steps), ctypes.byref(h), stats)
        if status != 0:
            raise IntegrationError(f"expected DOP853 ({self.name}, compiled) to reach t = {t[-1]:g}, got: "
                                   f"{_STATUS.get(status, f'status {status}')}")
        return out, dict(nfev=int(stats[0]), steps=int(stats[1]), rejected=int(stats[2]))


def unavailable_error(name: str, fallback: str = "scipy", *, kind: str = "dop853") -> IntegrationError:
    """The error for ``backend='c'`` when the compiled ``kind`` ("dop853" here, "kdk" for
    :mod:`.kick_drift_c`) of system ``name`` could not be had, with the reason."""
    return IntegrationError(f"expected a C compiler for backend='c', got none usable: "
                            f"{cbuild.why_unavailable(f'{kind}_{name}')}; use backend='auto' or '{fallback}'")


def compiled_dop853(name: str, build: Callable[[], tuple[Any, Sequence[Any], Sequence[Any]]]) -> CompiledDOP853 | None:
    """The compiled stepper ``name``, or None when no C compiler is available (or it is switched off).

    ``build()`` returns (right-hand-side expressions, state symbols, parameter symbols); it runs —
    deriving with SymPy — only when the library is not in the cache.  The dimensions are recorded
    in the library itself (``dop853_dims``), so a cached library is used without deriving.
    """
    def source() -> str:
        exprs, state, params = build()
        text = dop853_c_source(exprs, state, params, name=name)
        return text + f"\nvoid dop853_dims(int *out) {{ out[0] = {len(state)}; out[1] = {len(params)}; }}\n"

    lib = cbuild.load_or_none(f"dop853_{name}", source)
    if lib is None:
        return None
    dims = (ctypes.c_int * 2)()
    lib.dop853_dims(dims)
    fn = lib.dop853_solve
    vec = np.ctypeslib.ndpointer(dtype=float, flags="C_CONTIGUOUS")
    fn.argtypes = [vec, vec, ctypes.c_int, vec, vec, ctypes.c_double, ctypes.c_double, ctypes.c_long,
                   ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long)]
    fn.restype = ctypes.c_int
    return CompiledDOP853(name=name, n=int(dims[0]), n_par=int(dims[1]), _solve=fn)
