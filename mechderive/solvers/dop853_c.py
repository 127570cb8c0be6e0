"""DOP853 in C on a derived right-hand side: SciPy's algorithm without the interpreter in the loop.

SciPy's ``solve_ivp(method="DOP853")`` spends most of its time in Python: per step twelve calls of
the right-hand side and a dozen small NumPy operations, ~100 µs, against ~1 µs of arithmetic for
the 7-dimensional heavy top.  This module generates two C libraries:

* the system's right-hand side, printed from the SymPy derivation by
  :func:`mechderive.derive.formats.to_c_source` (cse'd), and
* the DOP853 stepper for states of its size, which calls the right-hand side through a pointer (one
  stepper serves every system of that size: a new system compiles only its right-hand side) — of Hairer, Nørsett & Wanner (*Solving ODEs I*, §II.5 and §II.10), written to
  follow SciPy's ``scipy.integrate._ivp.rk.DOP853`` step for step: the same Butcher tableau
  (the coefficients are read from SciPy at generation time and printed exactly), the same
  initial-step heuristic (``select_initial_step``), the same error norm (the 5th- and 3rd-order
  estimates combined), the same step-size controller (safety 0.9, factors 0.2–10, exponent
  -1/8, no growth right after a rejection) and the same 7th-order dense output for the output
  times, so it takes the same steps as ``solve_ivp`` to rounding; and, on request, the
  continuous Euler half-angles of a quaternion in the state, followed along every accepted step
  (:mod:`mechderive.solvers.half_angles`, whose Python twin runs on SciPy's stepper);

compiles them with the system compiler (:mod:`mechderive.core.cbuild`, cached on disk) and calls the
stepper through :mod:`ctypes`, handing it the right-hand side.  The systems are autonomous (no explicit t), as both tops are.

A run never hangs and never returns NaN: the stepper stops with a status — made an
:class:`~mechderive.errors.IntegrationError` saying where and why — when the state or the
right-hand side at the initial state is not finite (SciPy's first step would be NaN there, and its
step loop would never end), when every step tried down to 10 ulp of t meets NaN, when the step
size collapses, and after ``max_steps`` steps (:data:`~mechderive.solvers.limits.MAX_STEPS`).  Its
state lives in a buffer owned by Python, so the run goes in calls of bounded wall time
(:data:`CHUNK_SECONDS`) between which Python sees Ctrl-C; where a call stops does not change a bit
of the result.

A batch of runs (a sweep's points: :meth:`CompiledDOP853.solve_batch`) goes through one more C
function, ``dop853_solve_batch``, which hands each point's own Run buffer to the same
``dop853_solve``: every point takes the steps it takes alone (bit for bit), ends with its own status
(one point that blows up does not stop the others), and the batch too runs in calls of bounded wall
time, the evaluations of all its points counted against one budget.
"""

from __future__ import annotations

import ctypes
import functools
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import IntegrationError
from ..core import cbuild
from .half_angles import DECADE_THRESHOLDS, DECADES, MAX_REFINEMENTS
from .limits import check_max_steps, nonfinite_start, nonfinite_state, too_many_steps

__all__ = ["CompiledDOP853", "BatchRun", "DONE", "compiled_dop853", "rhs_c_source", "stepper_c_source",
           "unavailable_error", "MIN_RTOL", "CHUNK_SECONDS", "FIRST_CHUNK"]

#: The smallest rtol accepted, as in SciPy (100 ε): below it the controller chases rounding.
MIN_RTOL = 100 * np.finfo(float).eps

# the statuses of dop853_solve (ST_* in the C source)
_DONE, _TOO_SMALL, _MAX_STEPS, _NONFINITE, _NONFINITE_START, _NONFINITE_RHS, _CHUNK = range(7)

#: Wall seconds aimed at per call into C: between calls Python runs its signal handlers, so Ctrl-C
#: (SIGINT) stops a compiled run within about this time.  The first call makes :data:`FIRST_CHUNK`
#: right-hand-side evaluations (~4 ms for the heavy top, ~25 ms for the falling cat), each next one
#: as many as the measured speed fits in this time (at most 4× more than the last).  A call costs
#: ~50 µs in ctypes: a run of 10⁴ steps (heavy top, 100 nutation periods) makes 2 calls, a run of
#: 10⁶ steps ~30; the instructions executed in C are those of one call to within ~200
#: (valgrind --tool=callgrind).
CHUNK_SECONDS = 0.05
FIRST_CHUNK = 1 << 16

# C's long, whose size the platform decides (4 bytes on Windows)
_LONG = np.dtype(f"int{8 * ctypes.sizeof(ctypes.c_long)}")
_LONG_MAX = int(np.iinfo(_LONG).max)

_DRIVER = r"""
/* ---- DOP853 (Hairer, Nørsett & Wanner), following scipy.integrate._ivp.rk.DOP853 ---- */
#define NST 12     /* stages of the step */
#define NSTX 16    /* stages including the three of the dense output */
#define SAFETY 0.9
#define MIN_FACTOR 0.2
#define MAX_FACTOR 10.0
#define EXPONENT (-1.0 / 8.0)   /* -1/(error estimator order + 1) */

/* the right-hand side f(y) (with the parameters par) into dy: a function of another library */
typedef void (*rhs_fn)(const double *y, const double *par, double *dy);

static double rms_scaled(const double *x, const double *scale)
{
    double s = 0.0;
    for (int i = 0; i < NDIM; i++) { double v = x[i] / scale[i]; s += v * v; }
    return sqrt(s / NDIM);
}

/* K[s] = f(y + h Σ_{j<s} A[s][j] K[j]): one stage, of the step or of the dense output */
static void stage(rhs_fn rhs, int s, double h, const double *y, double K[NSTX][NDIM], const double *par,
                  double *ytmp)
{
    for (int i = 0; i < NDIM; i++) {
        double acc = 0.0;
        for (int j = 0; j < s; j++) acc += DOP_A[s][j] * K[j][i];
        ytmp[i] = y[i] + h * acc;
    }
    rhs(ytmp, par, K[s]);
}

/* select_initial_step of scipy.integrate._ivp.common, order 7 */
static double initial_step(rhs_fn rhs, const double *y0, const double *f0, const double *par, double interval,
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

/* ---- continuous arguments of z_A = q0 + i q3 and z_B = q1 + i q2 (mechderive.solvers.half_angles) ---- */
#define TRACK_DEPTH 48
#define SPEED_MARGIN 1.5
#define TWO_PI 6.283185307179586
#define NDEC 17            /* approaches counted below 1e0, 1e-1, ..., 1e-16 */

typedef struct {
    int qoff;              /* index of q0 in y */
    double offset[2];      /* continuous argument = atan2(z) + offset where z != 0 */
    double held[2];        /* the continuous argument while z = 0 exactly */
    double closest[2];     /* smallest lower bound of |z| met (0: a piece not resolved) */
    int departing[2];      /* z(0) = 0 exactly: the first step leaves it along z'(0) */
    double speed[2];       /* bound of |dz/dt| on the current step */
    double near[2][NDEC];  /* entries of the path below |z| = 10^-k */
    int depth[2];          /* the path is below 10^-k for k < depth (thresholds decrease) */
    long refinements;      /* halvings left in this step */
} Track;

/* a piece staying at |z| >= rho (0: unresolved, as if through z = 0) */
static void track_approach(Track *tr, int p, double rho)
{
    int d = tr->depth[p];
    if (rho < tr->closest[p]) tr->closest[p] = rho;
    while (d < NDEC && rho < TRACK_DECADE[d]) { tr->near[p][d] += 1.0; d++; }   /* entering */
    while (d > 0 && !(rho < TRACK_DECADE[d - 1])) d--;                        /* leaving */
    tr->depth[p] = d;
}

typedef struct {           /* one accepted step, with its dense output made on demand */
    double h;
    const double *y, *y_new, *par;
    double (*K)[NDIM];
    double (*F)[NDIM];
    double *ytmp;
    long *nfev;
    int dense;
    rhs_fn rhs;
} Step;

static void dense_prepare(Step *st)
{
    if (st->dense) return;
    for (int s = NST + 1; s < NSTX; s++) { stage(st->rhs, s, st->h, st->y, st->K, st->par, st->ytmp); (*st->nfev)++; }
    for (int i = 0; i < NDIM; i++) {
        double dy = st->y_new[i] - st->y[i];
        st->F[0][i] = dy;
        st->F[1][i] = st->h * st->K[0][i] - dy;
        st->F[2][i] = 2 * dy - st->h * (st->K[NST][i] + st->K[0][i]);
        for (int r = 0; r < 4; r++) {
            double acc = 0.0;
            for (int j = 0; j < NSTX; j++) acc += DOP_D[r][j] * st->K[j][i];
            st->F[3 + r][i] = st->h * acc;
        }
    }
    st->dense = 1;
}

/* y at t + x h, 0 < x < 1, by the 7th-order dense output */
static void dense_eval(Step *st, double x, double *out)
{
    dense_prepare(st);
    for (int i = 0; i < NDIM; i++) {
        double v = 0.0;
        for (int r = 6; r >= 0; r--) { v += st->F[r][i]; v *= ((6 - r) % 2 == 0) ? x : 1.0 - x; }
        out[i] = st->y[i] + v;
    }
}

static void track_pairs(const Track *tr, const double *y, double z[2][2])
{
    z[0][0] = y[tr->qoff];     z[0][1] = y[tr->qoff + 3];
    z[1][0] = y[tr->qoff + 1]; z[1][1] = y[tr->qoff + 2];
}

static double wrap_pi(double x) { return x - TWO_PI * nearbyint(x / TWO_PI); }

static double track_arg(const Track *tr, int p, const double z[2])
{
    return (z[0] * z[0] + z[1] * z[1] == 0.0) ? tr->held[p] : atan2(z[1], z[0]) + tr->offset[p];
}

static void track_start(Track *tr, const double *y0, const double *f0, const double *args0)
{
    double z[2][2], zd[2][2];
    track_pairs(tr, y0, z);
    track_pairs(tr, f0, zd);
    for (int p = 0; p < 2; p++) {
        tr->closest[p] = INFINITY;
        tr->departing[p] = 0;
        tr->offset[p] = 0.0;
        tr->held[p] = args0[p];
        tr->depth[p] = 0;
        for (int k = 0; k < NDEC; k++) tr->near[p][k] = 0.0;
        if (z[p][0] * z[p][0] + z[p][1] * z[p][1] != 0.0) {
            tr->offset[p] = args0[p] - atan2(z[p][1], z[p][0]);
        } else if (zd[p][0] != 0.0 || zd[p][1] != 0.0) {
            /* leaving z = 0 along z'(0): its direction, the representative nearest the given one */
            tr->held[p] = args0[p] + wrap_pi(atan2(zd[p][1], zd[p][0]) - args0[p]);
            tr->departing[p] = 1;
        }
    }
}

/* 2 pi k keeping atan2(z) + 2 pi k continuous along the chord za -> zb: it meets y = 0 at
   x = (za x zb)/(yb - ya), negative iff the cross product and yb - ya have opposite signs */
static double track_crossing(const double za[2], const double zb[2])
{
    int below_a = signbit(za[1]) != 0, below_b = signbit(zb[1]) != 0;
    if (below_a == below_b) return 0.0;
    double cross = za[0] * zb[1] - za[1] * zb[0];
    if (!below_a && cross > 0.0) return TWO_PI;
    if (below_a && cross < 0.0) return -TWO_PI;
    return 0.0;
}

/* the piece [xa, xb] of the step: halve until the turn of each argument is certain */
static void track_piece(Track *tr, Step *st, double xa, double za[2][2], double xb, double zb[2][2], int depth)
{
    double rho[2] = {0.0, 0.0};
    int ok[2] = {1, 1}, touch[2] = {0, 0};   /* touch: 1 leaving z = 0, 2 arriving, 3 at 0 throughout */
    int halving_helps = 1;                   /* not with an infinite or NaN length: half of it is as long */
    for (int p = 0; p < 2; p++) {
        /* |q| ~ 1: no overflow; a |z| below 1e-154 squares to 0 and counts as z = 0 */
        double ra2 = za[p][0] * za[p][0] + za[p][1] * za[p][1];
        double rb2 = zb[p][0] * zb[p][0] + zb[p][1] * zb[p][1];
        if (ra2 == 0.0 || rb2 == 0.0) {
            touch[p] = ra2 == rb2 ? 3 : (ra2 == 0.0 ? 1 : 2);
            ok[p] = touch[p] == 3;
        } else {
            double length = tr->speed[p] * st->h * (xb - xa);
            if (!isfinite(length)) halving_helps = 0;
            rho[p] = 0.5 * (sqrt(ra2) + sqrt(rb2) - length);
            /* the path stays at |z| >= rho, so turns by <= length/rho < pi: the chord's turn */
            ok[p] = rho[p] > 0.0 && length < 0.5 * TWO_PI * rho[p];
        }
    }
    if (!(ok[0] && ok[1]) && depth < TRACK_DEPTH && halving_helps && tr->refinements > 0) {
        tr->refinements--;
        double xm = 0.5 * (xa + xb), ym[NDIM], zm[2][2];
        dense_eval(st, xm, ym);
        track_pairs(tr, ym, zm);
        track_piece(tr, st, xa, za, xm, zm, depth + 1);
        track_piece(tr, st, xm, zm, xb, zb, depth + 1);
        return;
    }
    for (int p = 0; p < 2; p++) {
        if (touch[p] == 1) {           /* leaving z = 0: the turn from the held argument, wrapped */
            double a = atan2(zb[p][1], zb[p][0]);
            tr->offset[p] = tr->held[p] + wrap_pi(a - tr->held[p]) - a;
        } else if (touch[p] == 2) {
            tr->held[p] = atan2(za[p][1], za[p][0]) + tr->offset[p];
        } else if (touch[p] == 0) {
            tr->offset[p] += track_crossing(za[p], zb[p]);
        }
        if (touch[p] == 3 || (touch[p] == 1 && tr->departing[p])) {
            /* held at z = 0, or leaving it at the start along z'(0): not a passage */
        } else if (!tr->departing[p]) {
            track_approach(tr, p, ok[p] ? rho[p] : 0.0);
        }
    }
}

/* ---- the run, resumable: all that carries from one accepted step to the next ---- */
typedef struct {
    double t, h_abs;       /* the time reached and the step to try next */
    double y[NDIM], f[NDIM];   /* the state at t and f(y) */
    long nfev, nstep, nrej;
    int k;                 /* the next output index */
    int started;           /* 0 in a zeroed Run: dop853_solve starts it */
    Track tr;
} Run;

long dop853_run_bytes(void) { return (long)sizeof(Run); }

/* statuses: mechderive.solvers.dop853_c._STATUS */
#define ST_DONE 0
#define ST_TOO_SMALL 1
#define ST_MAX_STEPS 2
#define ST_NONFINITE 3
#define ST_NONFINITE_START 4
#define ST_NONFINITE_RHS 5
#define ST_CHUNK 6

static int all_finite(const double *v) { for (int i = 0; i < NDIM; i++) if (!isfinite(v[i])) return 0; return 1; }

/* Integrate y' = f(y) from t_out[0] (y0) and write y at every t_out[k] (increasing) into y_out.
   run: a zeroed Run on the first call; the call returns ST_CHUNK once it has made `budget` more
   right-hand-side evaluations (after a whole step), and a call with the same run and arrays goes on
   where it stopped, taking the very steps of an uninterrupted run.  Returns a status ST_*.
   stats: nfev, accepted steps, rejected steps; where: t reached, the step to try next.
   qoff >= 0: also follow the arguments of q0 + i q3 and q1 + i q2 (q0 at y[qoff]) along every
   step, from arg_out[0], arg_out[1] (overwritten where z(0) = 0); their values at t_out go to
   arg_out (n_out x 2), the smallest lower bound of |z| met to closest[0..1] and the counts of
   entries below |z| = 10^-k to closest[2 + NDEC p + k]. */
int dop853_solve(rhs_fn rhs, Run *run, const double *par, const double *y0, int n_out, const double *t_out, double *y_out,
                 double rtol, double atol, long max_steps, long budget, long *stats, double *where,
                 int qoff, double *arg_out, double *closest)
{
    double K[NSTX][NDIM], y[NDIM], y_new[NDIM], ytmp[NDIM], F[7][NDIM];
    double t_end = t_out[n_out - 1];
    int status = ST_CHUNK;
    if (!run->started) {
        run->started = 1;
        run->t = t_out[0]; run->k = 1; run->h_abs = 0.0;
        run->nfev = run->nstep = run->nrej = 0;
        for (int i = 0; i < NDIM; i++) { run->y[i] = y0[i]; y_out[i] = y0[i]; }
        if (n_out < 2) { run->k = n_out; status = ST_DONE; goto report; }
        if (!all_finite(run->y)) { status = ST_NONFINITE_START; goto report; }
        rhs(run->y, par, run->f); run->nfev++;
        if (!all_finite(run->f)) { status = ST_NONFINITE_START; goto report; }
        if (qoff >= 0) {
            double args0[2] = {arg_out[0], arg_out[1]}, z0[2][2];
            run->tr.qoff = qoff;
            track_start(&run->tr, run->y, run->f, args0);
            track_pairs(&run->tr, run->y, z0);
            arg_out[0] = track_arg(&run->tr, 0, z0[0]); arg_out[1] = track_arg(&run->tr, 1, z0[1]);
        }
        run->h_abs = initial_step(rhs, run->y, run->f, par, t_end - run->t, rtol, atol, &run->nfev);
        /* a NaN step would never fall below the smallest one: the run would not end */
        if (!(run->h_abs > 0.0 && isfinite(run->h_abs))) { status = ST_NONFINITE_START; goto report; }
    }
    /* the loop works on local copies (kept in registers); they go back to run at the end */
    long nfev = run->nfev, nstep = run->nstep, nrej = run->nrej, nfev_stop = run->nfev + budget;
    double t = run->t, h_abs = run->h_abs;
    int k = run->k;
    Track tr = run->tr;
    for (int i = 0; i < NDIM; i++) { y[i] = run->y[i]; K[0][i] = run->f[i]; }
    while (k < n_out) {
        double min_step = 10 * fabs(nextafter(t, INFINITY) - t);
        if (h_abs < min_step) h_abs = min_step;
        int rejected = 0, nan_error = 0;
        double t_new, h;
        for (;;) {
            if (h_abs < min_step) { status = nan_error ? ST_NONFINITE_RHS : ST_TOO_SMALL; goto done; }
            t_new = t + h_abs;
            if (t_new > t_end) t_new = t_end;
            h = t_new - t;
            h_abs = fabs(h);
            for (int s = 1; s < NST; s++) { stage(rhs, s, h, y, K, par, ytmp); nfev++; }
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
            /* a NaN error norm also lands here and shrinks the step, as in SciPy: the step may have
               been too long for the right-hand side; if it stays NaN down to min_step, that is said */
            nan_error = isnan(err);
            double shrink = SAFETY * pow(err, EXPONENT);
            h_abs *= (shrink > MIN_FACTOR) ? shrink : MIN_FACTOR;
            rejected = 1; nrej++;
        }
        if (!all_finite(y_new)) { status = ST_NONFINITE; goto done; }
        nstep++;
        Step st = {h, y, y_new, par, K, F, ytmp, &nfev, 0, rhs};
        double xa = 0.0, za[2][2], zb[2][2];
        if (qoff >= 0) {
            for (int p = 0; p < 2; p++) {
                int i = qoff + (p ? 1 : 0), j = qoff + (p ? 2 : 3);
                double v2 = 0.0;
                for (int s = 0; s <= NST; s++) v2 = fmax(v2, K[s][i] * K[s][i] + K[s][j] * K[s][j]);
                tr.speed[p] = SPEED_MARGIN * sqrt(v2);
            }
            tr.refinements = TRACK_REFINEMENTS;
            track_pairs(&tr, y, za);
        }
        while (k < n_out && t_out[k] <= t_new) {
            double *out = y_out + (long)k * NDIM;
            if (t_out[k] == t_new) {
                for (int i = 0; i < NDIM; i++) out[i] = y_new[i];
            } else {
                double x = (t_out[k] - t) / h;
                dense_eval(&st, x, out);
                if (qoff >= 0) {
                    track_pairs(&tr, out, zb);
                    track_piece(&tr, &st, xa, za, x, zb, 0);
                    xa = x;
                    za[0][0] = zb[0][0]; za[0][1] = zb[0][1]; za[1][0] = zb[1][0]; za[1][1] = zb[1][1];
                    arg_out[2L * k] = track_arg(&tr, 0, zb[0]); arg_out[2L * k + 1] = track_arg(&tr, 1, zb[1]);
                }
            }
            k++;
        }
        if (qoff >= 0) {
            track_pairs(&tr, y_new, zb);
            track_piece(&tr, &st, xa, za, 1.0, zb, 0);
            tr.departing[0] = tr.departing[1] = 0;
            if (t_out[k - 1] == t_new) {
                arg_out[2L * (k - 1)] = track_arg(&tr, 0, zb[0]);
                arg_out[2L * (k - 1) + 1] = track_arg(&tr, 1, zb[1]);
            }
        }
        t = t_new;
        for (int i = 0; i < NDIM; i++) { y[i] = y_new[i]; K[0][i] = K[NST][i]; }
        if (k < n_out && nstep >= max_steps) { status = ST_MAX_STEPS; goto done; }
        if (k < n_out && nfev >= nfev_stop) { status = ST_CHUNK; goto done; }
    }
    status = ST_DONE;
done:
    run->t = t; run->h_abs = h_abs; run->k = k;
    run->nfev = nfev; run->nstep = nstep; run->nrej = nrej;
    run->tr = tr;
    for (int i = 0; i < NDIM; i++) { run->y[i] = y[i]; run->f[i] = K[0][i]; }
report:
    stats[0] = run->nfev; stats[1] = run->nstep; stats[2] = run->nrej;
    where[0] = run->t; where[1] = run->h_abs;
    if (qoff >= 0) {
        closest[0] = run->tr.closest[0]; closest[1] = run->tr.closest[1];
        for (int p = 0; p < 2; p++) for (int d = 0; d < NDEC; d++) closest[2 + NDEC * p + d] = run->tr.near[p][d];
    }
    return status;
}

/* ---- a batch: independent runs, each exactly the run dop853_solve makes alone ---- */
/* Point i has its own Run (runs + i run_words, zeroed: not started), parameters par + i npar, initial
   state, tolerances rtol[i], atol[i], outputs (y_out + i n_out NDIM; with qoff >= 0 arg_out + 2 i n_out
   and closest + i (2 + 2 NDEC)), stats + 3 i, where + 2 i and status[i].  Only points whose status is
   ST_CHUNK are advanced (the caller sets it for the points to run); each is handed to dop853_solve with
   the evaluations left of `budget`, so its steps are those of a run of its own (where a call stops does
   not change them), and its status is its own: one point that blows up or stalls ends there, the others
   go on.  The call returns once `budget` evaluations in all have been made (after a whole step) or no
   point is left; the result is the number of points still ST_CHUNK. */
long dop853_solve_batch(rhs_fn rhs, long n_pts, double *runs, long run_words, int npar, const double *par,
                        const double *y0, int n_out, const double *t_out, double *y_out, const double *rtol,
                        const double *atol, long max_steps, long budget, long *stats, double *where, int qoff,
                        double *arg_out, double *closest, int *status)
{
    long left = budget, pending = 0;
    for (long i = 0; i < n_pts; i++) {
        if (status[i] != ST_CHUNK) continue;
        if (left <= 0) { pending++; continue; }
        Run *run = (Run *)(runs + i * run_words);
        long before = run->started ? run->nfev : 0;
        status[i] = dop853_solve(rhs, run, par + i * npar, y0 + i * NDIM, n_out, t_out, y_out + i * (long)n_out * NDIM,
                                 rtol[i], atol[i], max_steps, left, stats + 3 * i, where + 2 * i, qoff,
                                 qoff >= 0 ? arg_out + 2 * i * (long)n_out : arg_out,
                                 qoff >= 0 ? closest + i * (2 + 2 * NDEC) : closest);
        left -= run->nfev - before;
        if (status[i] == ST_CHUNK) pending++;
    }
    return pending;
}
"""


def _c_array(name: str, values: np.ndarray) -> str:
    values = np.asarray(values, dtype=float)
    if values.ndim == 1:
        body = ", ".join(repr(float(v)) for v in values)
        return f"static const double {name}[{values.size}] = {{{body}}};"
    rows = ",\n    ".join("{" + ", ".join(repr(float(v)) for v in row) + "}" for row in values)
    return f"static const double {name}[{values.shape[0]}][{values.shape[1]}] = {{\n    {rows}}};"


def rhs_c_source(exprs: Any, state: Sequence[Any], params: Sequence[Any], *, name: str) -> str:
    """The C source of the right-hand side ``exprs`` (ẏ in the order of ``state``) as a library of its own:
    ``mechderive_rhs(y, par, dy)``, which the stepper of :func:`stepper_c_source` calls through a pointer,
    and ``dop853_dims`` (the state's and the parameters' sizes, so a cached library is used without deriving).

    ``exprs`` are SymPy expressions in the symbols ``state`` and ``params`` only (autonomous).
    """
    from ..core.codegen import to_c_source

    n, n_par = len(state), len(params)
    fn = f"{name}_rhs_expr"
    rhs_source = to_c_source(exprs, [*state, *params], fn, include=False,
                             doc=f"{name}: the derived right-hand side, d(state)/dt.")
    glue_args = ", ".join([f"y[{i}]" for i in range(n)] + [f"par[{i}]" for i in range(n_par)] + ["dy"])
    return "\n".join([
        f"/* {name}: the right-hand side derived by mechderive, for its DOP853 stepper (generated; safe to delete). */",
        "#include <math.h>",
        rhs_source.replace(f"void {fn}(", f"static void {fn}(", 1),
        f"void mechderive_rhs(const double *y, const double *par, double *dy) {{ {fn}({glue_args}); }}",
        f"void dop853_dims(int *out) {{ out[0] = {n}; out[1] = {n_par}; }}",
        "",
    ])


def stepper_c_source(n: int) -> str:
    """The C source of the DOP853 stepper for states of ``n`` values, one library for every system of that size:
    the right-hand side is an argument (a function of the system's own library, :func:`rhs_c_source`).

    The stepper is most of the C (~24 kB against ~2 kB for a small right-hand side) and most of the compile
    time (measured: 0.50 s of CPU at -O2 for the whole file, 0.07 s for the right-hand side alone), so a
    new system costs one small compile; the call through a pointer costs nothing measurable next to a
    right-hand side's arithmetic (the closed-form benchmark's DOP853 rows, before and after).
    """
    from scipy.integrate._ivp import dop853_coefficients as coef

    return "\n".join([
        f"/* DOP853 for {n}-dimensional states, the right-hand side an argument (generated by mechderive; safe to "
        "delete). */",
        "#include <math.h>",
        f"#define NDIM {n}",
        f"#define TRACK_REFINEMENTS {MAX_REFINEMENTS}L  /* half_angles.MAX_REFINEMENTS: halvings per step */",
        # SciPy's tableau, printed exactly (repr round-trips); prefixed so no derived name can clash
        _c_array("DOP_A", coef.A), _c_array("DOP_B", coef.B), _c_array("DOP_E3", coef.E3),
        _c_array("DOP_E5", coef.E5), _c_array("DOP_D", coef.D), _c_array("TRACK_DECADE", DECADE_THRESHOLDS),
        _DRIVER,
    ])


#: :attr:`BatchRun.status` of a run that reached the last output time
DONE = _DONE


@dataclass(frozen=True)
class BatchRun:
    """M runs of :meth:`CompiledDOP853.solve_batch`: ``y`` (M, N, n) at the output times; per run the
    evaluations, accepted and rejected steps, ``status`` (:data:`DONE`, else the stepper's reason) and
    ``errors`` (None, or the :class:`~mechderive.errors.IntegrationError` :meth:`CompiledDOP853.solve`
    raises for it: its ``y`` rows past where it stopped are not defined); ``wall``: seconds of the whole
    batch; with tracking ``args`` (M, N, 2), ``closest`` (M, 2) and ``near`` (M, 2, DECADES)."""

    y: np.ndarray
    nfev: np.ndarray
    steps: np.ndarray
    rejected: np.ndarray
    status: np.ndarray
    errors: list
    wall: float
    args: np.ndarray | None = None
    closest: np.ndarray | None = None
    near: np.ndarray | None = None

    def info(self, i: int) -> dict:
        """Run ``i``'s statistics as :meth:`CompiledDOP853.solve` returns them."""
        out = dict(nfev=int(self.nfev[i]), steps=int(self.steps[i]), rejected=int(self.rejected[i]))
        if self.args is not None:
            out.update(args=self.args[i], closest=self.closest[i], near=self.near[i])
        return out


@dataclass(frozen=True)
class CompiledDOP853:
    """A compiled DOP853 stepper for one derived system with ``n`` state and ``n_par`` parameter values."""

    name: str
    n: int
    n_par: int
    _solve: Any
    _run_words: int = 0
    _solve_batch: Any = None

    def solve(self, t_eval: np.ndarray, y0: np.ndarray, params: Sequence[float], rtol: float, atol: float, *,
              max_steps: int | None = None, track: tuple[int, Sequence[float]] | None = None,
              chunk_evaluations: int | None = None) -> tuple[np.ndarray, dict]:
        """(y at every ``t_eval``, shape (N, n); dict(nfev, steps, rejected[, args, closest])).

        ``t_eval`` increasing with ``t_eval[0]`` the initial time; ``rtol`` is raised to
        :data:`MIN_RTOL` as in SciPy.  ``track = (qoff, (σ0, δ0))``: also follow the arguments of
        q0 + i q3 and q1 + i q2 (q0 at index ``qoff``) along every step
        (:mod:`mechderive.solvers.half_angles`): ``args`` (N, 2) at ``t_eval``, ``closest`` (2,) and
        ``near`` (2, DECADES).  ``max_steps``: accepted steps allowed (default
        :data:`~mechderive.solvers.limits.MAX_STEPS`).  The stepper runs in calls of
        ``chunk_evaluations`` right-hand-side evaluations each (default: adapted so that a call
        takes about :data:`CHUNK_SECONDS`), between which Python sees Ctrl-C; the steps and the
        result do not depend on it.
        Raises :class:`~mechderive.errors.IntegrationError` when the state or the right-hand side at
        the initial state is not finite, the step size collapses, or ``max_steps`` is reached.
        """
        max_steps = min(check_max_steps(max_steps), _LONG_MAX // 2)
        t = np.ascontiguousarray(t_eval, dtype=float)
        y0 = np.ascontiguousarray(y0, dtype=float)
        par = np.ascontiguousarray(params, dtype=float)
        if y0.shape != (self.n,) or par.shape != (self.n_par,):
            raise IntegrationError(f"expected y0 of shape ({self.n},) and {self.n_par} parameters, got "
                                   f"{y0.shape} and {par.shape}")
        if track is not None and not 0 <= track[0] <= self.n - 4:
            raise IntegrationError(f"expected a quaternion at y[{track[0]}:{track[0] + 4}] to track, got a state of "
                                   f"{self.n} values")
        label = f"DOP853 ({self.name}, compiled)"
        if not np.all(np.isfinite(par)):
            raise nonfinite_start(label, t0=float(t[0]), what="the parameters")
        out = np.empty((t.size, self.n))
        args = np.zeros((t.size, 2))
        closest = np.zeros(2 + 2 * DECADES)
        if track is not None:
            args[0] = track[1]
        stats = np.zeros(3, dtype=_LONG)
        where = np.zeros(2)
        run = np.zeros(self._run_words)  # the C Run, zeroed: not started
        qoff = -1 if track is None else int(track[0])
        rtol = float(max(rtol, MIN_RTOL))
        budget = FIRST_CHUNK if chunk_evaluations is None else min(max(1, int(chunk_evaluations)), _LONG_MAX // 4)
        while True:
            start = time.perf_counter()
            status = self._solve(run, par, y0, int(t.size), t, out, rtol, float(atol), max_steps, budget, stats,
                                 where, qoff, args, closest)
            if status != _CHUNK:
                break
            if chunk_evaluations is None:  # as many as fit in CHUNK_SECONDS at the speed just measured
                fit = budget * CHUNK_SECONDS / max(time.perf_counter() - start, 1e-6)
                budget = int(min(4.0 * budget, max(fit, 64.0), _LONG_MAX // 4))
        if status != _DONE:
            raise self._error(status, label, t, where, stats, max_steps)
        info = dict(nfev=int(stats[0]), steps=int(stats[1]), rejected=int(stats[2]))
        if track is not None:
            info.update(args=args, closest=closest[:2], near=closest[2:].reshape(2, DECADES).astype(np.int64))
        return out, info

    def solve_batch(self, t_eval: np.ndarray, y0: np.ndarray, params: np.ndarray, rtol: Any, atol: Any, *,
                    max_steps: int | None = None, track: tuple[int, np.ndarray] | None = None,
                    chunk_evaluations: int | None = None) -> "BatchRun":
        """M runs at once: y0 (M, n), ``params`` (M, n_par), ``rtol`` and ``atol`` scalars or (M,), all
        with the output times ``t_eval``; ``track = (qoff, args0 (M, 2))`` as in :meth:`solve`.

        Each run takes exactly the steps :meth:`solve` takes from the same point (the same C function,
        handed the run's own buffer: its outputs equal :meth:`solve`'s bit for bit), with its own status:
        a run that does not reach ``t_eval[-1]`` (a state or right-hand side not finite, the step size
        collapsing, ``max_steps``) has its :class:`~mechderive.errors.IntegrationError` in
        :attr:`BatchRun.errors` — the one :meth:`solve` raises — and the others go on.  The batch runs in
        calls of bounded wall time (:data:`CHUNK_SECONDS`, the evaluations of all its runs counted), so
        Ctrl-C stops it as it stops a single run.
        """
        if self._solve_batch is None:  # pragma: no cover - every library built by this module has it
            raise IntegrationError(f"expected the compiled DOP853 of {self.name!r} to have its batch entry point, "
                                   "got a library without it")
        max_steps = min(check_max_steps(max_steps), _LONG_MAX // 2)
        t = np.ascontiguousarray(t_eval, dtype=float)
        y0 = np.ascontiguousarray(y0, dtype=float)
        m = y0.shape[0] if y0.ndim == 2 else -1
        par = np.ascontiguousarray(np.reshape(params, (m, self.n_par)) if m >= 0 else params, dtype=float)
        if y0.shape != (m, self.n) or par.shape != (m, self.n_par):
            raise IntegrationError(f"expected y0 of shape (M, {self.n}) and parameters of shape (M, {self.n_par}), "
                                   f"got {y0.shape} and {np.shape(params)}")
        # each run's tolerance as solve() takes it: rtol raised to MIN_RTOL
        rt = np.ascontiguousarray(np.maximum(np.broadcast_to(np.asarray(rtol, dtype=float), (m,)), MIN_RTOL))
        at = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, dtype=float), (m,)))
        if track is not None and not 0 <= track[0] <= self.n - 4:
            raise IntegrationError(f"expected a quaternion at y[{track[0]}:{track[0] + 4}] to track, got a state of "
                                   f"{self.n} values")
        label = f"DOP853 ({self.name}, compiled)"
        out = np.empty((m, t.size, self.n))
        qoff = -1 if track is None else int(track[0])
        args = np.zeros((m, t.size, 2) if track is not None else (1, 1, 2))
        closest = np.zeros((m, 2 + 2 * DECADES) if track is not None else (1, 2 + 2 * DECADES))
        if track is not None:
            args[:, 0] = np.reshape(track[1], (m, 2))
        stats = np.zeros((m, 3), dtype=_LONG)
        where = np.zeros((m, 2))
        runs = np.zeros((m, self._run_words))  # each C Run zeroed: not started
        status = np.full(m, _CHUNK, dtype=np.intc)
        errors: list[IntegrationError | None] = [None] * m
        for i in np.flatnonzero(~np.all(np.isfinite(par), axis=1)):  # as solve() refuses before running
            status[i] = _NONFINITE_START
            errors[i] = nonfinite_start(label, t0=float(t[0]), what="the parameters")
        budget = FIRST_CHUNK if chunk_evaluations is None else min(max(1, int(chunk_evaluations)), _LONG_MAX // 4)
        start = time.perf_counter()
        while m > 0:
            call = time.perf_counter()
            left = self._solve_batch(m, runs, self._run_words, self.n_par, par, y0, int(t.size), t, out, rt, at,
                                     max_steps, budget, stats, where, qoff, args, closest, status)
            if left == 0:
                break
            if chunk_evaluations is None:  # as many as fit in CHUNK_SECONDS at the speed just measured
                fit = budget * CHUNK_SECONDS / max(time.perf_counter() - call, 1e-6)
                budget = int(min(4.0 * budget, max(fit, 64.0), _LONG_MAX // 4))
        wall = time.perf_counter() - start
        for i in np.flatnonzero(status != _DONE):
            if errors[i] is None:
                errors[i] = self._error(int(status[i]), label, t, where[i], stats[i], max_steps)
        return BatchRun(y=out, nfev=stats[:, 0].astype(np.int64), steps=stats[:, 1].astype(np.int64),
                        rejected=stats[:, 2].astype(np.int64), status=status.astype(np.int64), errors=errors,
                        wall=wall, args=args if track is not None else None,
                        closest=closest[:, :2] if track is not None else None,
                        near=closest[:, 2:].reshape(m, 2, DECADES).astype(np.int64) if track is not None else None)

    @staticmethod
    def _error(status: int, label: str, t: np.ndarray, where: np.ndarray, stats: np.ndarray,
               max_steps: int) -> IntegrationError:
        t_reached, steps = float(where[0]), int(stats[1])
        if status == _NONFINITE_START:
            return nonfinite_start(label, t0=float(t[0]))
        if status == _NONFINITE:
            return nonfinite_state(label, t=t_reached, steps=steps)
        if status == _NONFINITE_RHS:
            return IntegrationError(f"expected the right-hand side of {label} to be finite near the state at "
                                    f"t = {t_reached:.6g} (after {steps} steps), got NaN or infinity on every step "
                                    "tried, down to 10 ulp of t: the motion probably blows up there, or a parameter "
                                    "is out of floating-point range")
        if status == _MAX_STEPS:
            return too_many_steps(label, t=t_reached, t_end=float(t[-1]), steps=steps, max_steps=max_steps)
        if status == _TOO_SMALL:
            return IntegrationError(f"expected {label} to reach t = {float(t[-1]):.6g}, got stuck at "
                                    f"t = {t_reached:.6g}: the step size fell below 10 ulp of t (the solution is "
                                    "probably singular or blows up there)")
        return IntegrationError(f"expected {label} to end with a known status, got {status}")  # pragma: no cover


def unavailable_error(name: str, fallback: str = "scipy", *, kind: str = "dop853") -> IntegrationError:
    """The error for ``backend='c'`` when the compiled ``kind`` ("dop853" here, "kdk" for
    :mod:`.kick_drift_c`) of system ``name`` could not be had, with the reason."""
    return IntegrationError(f"expected a C compiler for backend='c', got none usable: "
                            f"{cbuild.why_unavailable(f'{kind}_{name}')}; use backend='auto' or '{fallback}'")


def compiled_dop853(name: str, build: Callable[[], tuple[Any, Sequence[Any], Sequence[Any]]]) -> CompiledDOP853 | None:
    """The compiled stepper ``name``, or None when no C compiler is available (or it is switched off).

    ``build()`` returns (right-hand-side expressions, state symbols, parameter symbols); it runs —
    deriving with SymPy — only when the library is not in the cache.  Two libraries: the system's
    right-hand side (``dop853_<name>``, which records the dimensions, so a cached one is used without
    deriving) and the stepper for its state's size (``dop853_stepper_<n>``, shared by every system of
    that size, built once per cache).
    """
    lib = cbuild.load_or_none(f"dop853_{name}", lambda: rhs_c_source(*build(), name=name))
    if lib is None:
        return None
    dims = (ctypes.c_int * 2)()
    lib.dop853_dims(dims)
    n, n_par = int(dims[0]), int(dims[1])
    stepper = _stepper(n)
    if stepper is None:
        return None
    fn, batch, words = stepper
    rhs = ctypes.cast(lib.mechderive_rhs, ctypes.c_void_p)
    return CompiledDOP853(name=name, n=n, n_par=n_par, _solve=functools.partial(fn, rhs), _run_words=words,
                          _solve_batch=functools.partial(batch, rhs))


def _stepper(n: int) -> tuple[Any, Any, int] | None:
    """(dop853_solve, dop853_solve_batch, the Run's size in doubles) of the stepper for ``n`` state values."""
    lib = cbuild.load_or_none(f"dop853_stepper_{n}", lambda: stepper_c_source(n))
    if lib is None:
        return None
    vec = np.ctypeslib.ndpointer(dtype=float, flags="C_CONTIGUOUS")
    longs = np.ctypeslib.ndpointer(dtype=_LONG, flags="C_CONTIGUOUS")
    fn = lib.dop853_solve
    fn.argtypes = [ctypes.c_void_p, vec, vec, vec, ctypes.c_int, vec, vec, ctypes.c_double, ctypes.c_double,
                   ctypes.c_long, ctypes.c_long, longs, vec, ctypes.c_int, vec, vec]
    fn.restype = ctypes.c_int
    batch = lib.dop853_solve_batch
    batch.argtypes = [ctypes.c_void_p, ctypes.c_long, vec, ctypes.c_long, ctypes.c_int, vec, vec, ctypes.c_int, vec,
                      vec, vec, vec, ctypes.c_long, ctypes.c_long, longs, vec, ctypes.c_int, vec, vec,
                      np.ctypeslib.ndpointer(dtype=np.intc, flags="C_CONTIGUOUS")]
    batch.restype = ctypes.c_long
    lib.dop853_run_bytes.restype = ctypes.c_long
    return fn, batch, -(-int(lib.dop853_run_bytes()) // 8)  # the Run in doubles: 8-byte aligned
