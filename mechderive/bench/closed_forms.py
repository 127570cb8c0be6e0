"""Closed forms found by the toolkit (issue 16): for each system of the issue, the substitution found, the
degree of P, the time per 2001 samples, the error, and the compiled DOP853 at comparable error.

Each system is a ``lagrangian`` system built from its Lagrangian text.  Times, warm (derivations and compiled
code cached, as a second run in one process is):

* ``setup``: the motion's constants from the start (E and the momenta at 55 digits, the roots of P, m, κ, the
  start's phase, the partial fractions of every cyclic rate; for a motion in t from an orbit along φ, the table of
  t(φ) the inversion starts from) — :func:`~mechderive.systems.lagrangian.closed.closed_motion`;
* ``2001 samples``: every coordinate at 2001 times over ten periods of the reduced motion (ten time scales 1/κ
  for a motion with no period: on a separatrix; for Kepler's hyperbola 1/(κ φ̇(0)), κ its orbit's along φ) — for
  Kepler's problem in t this includes the Newton iteration inverting t(φ) at every sample;
* ``DOP853``: the compiled DOP853 (the ``integrate`` method's stepper, without its error-estimating rerun)
  over the same samples at the loosest rtol among 1e-8 … 1e-13 whose error against the closed form is
  within 10× the closed form's own (measured) estimate, or its tightest if none is.

The error of the closed form is its own estimate (doubles against a 30-digit evaluation of the same
formulas); DOP853's error is its distance to the closed form.  The refused systems give the reason.
"""

from __future__ import annotations

import time

__all__ = ["closed_form_table", "report_lines", "CASES"]

_SPHERICAL = "m*l**2/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + m*g*l*cos(theta)"
_PENDULUM = "m*l**2/2*theta_dot**2 + m*g*l*cos(theta)"
_TOP = "I1/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + I3/2*(psi_dot + cos(theta)*phi_dot)**2 - M*g*l*cos(theta)"
_KEPLER = "m/2*(r_dot**2 + r**2*phi_dot**2) + k/r"
_G = {"m": 1.0, "l": 1.0, "g": 9.81}
_TOP_P = {"I1": 1.0, "I3": 0.5, "M": 1.0, "g": 9.81, "l": 0.1}

#: (label, coordinates, L, parameters, initial)
CASES: tuple = (
    ("spherical pendulum", ["theta", "phi"], _SPHERICAL, _G, {"theta": 1.0, "phi": 0.0, "theta_dot": 0.0,
                                                              "phi_dot": 2.0}),
    ("spherical pendulum through the pole", ["theta", "phi"], _SPHERICAL, _G,
     {"theta": 1.0, "phi": 0.0, "theta_dot": 0.0, "phi_dot": 0.0}),
    ("heavy top as a Lagrangian", ["theta", "phi", "psi"], _TOP, _TOP_P,
     {"theta": 0.5, "phi": 0.0, "psi": 0.0, "theta_dot": 0.0, "phi_dot": 0.0, "psi_dot": 20.0}),
    ("top, pivot accelerating at 3 m/s²", ["theta", "phi", "psi"],
     _TOP.replace("- M*g*l*cos(theta)", "+ M/2*(a*t)**2 - M*a*t*l*sin(theta)*theta_dot - M*g*(a*t**2/2 + l*cos(theta))"),
     {**_TOP_P, "a": 3.0}, {"theta": 0.5, "phi": 0.0, "psi": 0.0, "theta_dot": 0.0, "phi_dot": 0.0, "psi_dot": 20.0}),
    ("pendulum, libration", ["theta"], _PENDULUM, _G, {"theta": 2.0, "theta_dot": 0.0}),
    ("pendulum, rotation", ["theta"], _PENDULUM, _G, {"theta": 0.0, "theta_dot": 7.0}),
    ("pendulum, 1e-5 below the separatrix", ["theta"], _PENDULUM, _G, {"theta": 0.0, "theta_dot": 6.2641}),
    # g = 4 and θ̇0 = 4 are exact in binary: E is the top's potential energy to the last bit (m = 1, no period)
    ("pendulum on the separatrix", ["theta"], _PENDULUM, {"m": 1.0, "l": 1.0, "g": 4.0},
     {"theta": 0.0, "theta_dot": 4.0}),
    ("double well over the hump (u = x²)", ["x"], "x_dot**2/2 + x**2/2 - x**4/4", {}, {"x": 0.5, "x_dot": 1.0}),
    ("Kepler ellipse in t (orbit along φ, t(φ) inverted)", ["r", "phi"], _KEPLER, {"m": 1.0, "k": 1.0},
     {"r": 1.0, "phi": 0.0, "r_dot": 0.1, "phi_dot": 1.2}),
    ("Kepler hyperbola in t (orbit along φ, t(φ) inverted)", ["r", "phi"], _KEPLER, {"m": 1.0, "k": 1.0},
     {"r": 1.0, "phi": 0.0, "r_dot": 0.2, "phi_dot": 1.6}),
    ("precessing orbit 1/r² + 1/r in t (along φ)", ["r", "phi"], _KEPLER + " + beta/r**2",
     {"m": 1.0, "k": 1.0, "beta": 0.05}, {"r": 1.0, "phi": 0.0, "r_dot": 0.0, "phi_dot": 1.1}),
    ("double pendulum", ["a", "b"], "a_dot**2 + b_dot**2/2 + a_dot*b_dot*cos(a - b) + 2*g*cos(a) + g*cos(b)",
     {"g": 9.81}, {"a": 0.5, "b": 0.2, "a_dot": 0.0, "b_dot": 0.0}),
    ("quintic potential", ["x"], "x_dot**2/2 - x**5", {}, {"x": 0.3, "x_dot": 0.1}),
)


def _case(label: str, coordinates: list, lagrangian: str, parameters: dict, initial: dict, quick: bool) -> dict:
    import numpy as np

    from ..systems.base import OutOfReach
    from ..systems.lagrangian import from_lagrangian
    from ..systems.lagrangian.closed import closed_motion

    system = from_lagrangian(lagrangian, coordinates, list(parameters))
    found, reason = system.reduction()
    row: dict = {"system": label, "substitution": found.name if found else "none",
                 "degree": found.degree if found else None}
    try:
        warm = closed_motion(system, parameters, initial)  # warm: derivations and compiled code once
        if found is None:  # solved through an orbit along a cyclic coordinate: its substitution, along it
            row.update(substitution=f"{warm.found.name} along {warm.along}", degree=warm.found.degree)
        start = time.perf_counter()
        motion = closed_motion(system, parameters, initial)
        motion.columns(np.zeros(1), list(coordinates))  # the cyclic rates' partial fractions and Π series
        setup = time.perf_counter() - start
    except OutOfReach as exc:
        row["reason"] = str(exc)
        return row
    # 10.37 and 1000.37 periods: a grid commensurate with the period would sample one phase only; a motion
    # with no period (m = 1: a separatrix) over as many of its time scales 1/κ
    scale = float(motion.time_scale)
    t = np.linspace(0.0, 10.37 * scale, 2001)
    wanted = list(coordinates)
    repeats = 3 if quick else 10
    # a motion solved through an inversion (Kepler's t(φ)) keeps its last one for the estimate: forgotten before each
    # timed call, so that every repeat solves
    forget = getattr(motion, "forget", lambda: None)
    start = time.perf_counter()
    for _ in range(repeats):
        forget()
        cols = motion.columns(t, wanted)
    evaluate = (time.perf_counter() - start) / repeats
    estimate, _ = motion.estimate(t, wanted)
    row.update(kind=motion.describe()["motion"], setup=setup, evaluate=evaluate, error=estimate)
    # DOP853 at comparable error: the loosest rtol whose distance to the closed form is ≤ 10× its estimate
    from ..solvers.driver import integrate

    d, eq = system.definition, system.equations
    y0 = ([initial[q] for q in d.coordinates] + [initial[q + "_dot"] for q in d.coordinates]
          + ([0.0] if d.uses_time else []))
    p = [parameters[n] for n in d.dynamics_parameters]
    best = None
    for rtol in (1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13):
        integrate(eq.term, y0, t, p, rtol=rtol, estimate_error=False)  # compiled once
        start = time.perf_counter()
        traj = integrate(eq.term, y0, t, p, rtol=rtol, estimate_error=False)
        seconds = time.perf_counter() - start
        error = max(float(np.max(np.abs(traj.y[:, i] - cols[q]))) for i, q in enumerate(d.coordinates))
        best = {"rtol": rtol, "seconds": seconds, "error": error}
        if error <= 10 * max(estimate, 1e-15):
            break
    # a long run: 2001 samples over 1000 periods — the closed form's cost does not grow, DOP853's does
    long_t = np.linspace(0.0, 1000.37 * scale, 2001)
    forget()
    start = time.perf_counter()
    long_cols = motion.columns(long_t, wanted)
    best["closed_long"] = time.perf_counter() - start
    start = time.perf_counter()
    traj = integrate(eq.term, y0, long_t, p, rtol=best["rtol"], estimate_error=False)
    best["long_seconds"] = time.perf_counter() - start
    best["long_error"] = max(float(np.max(np.abs(traj.y[:, i] - long_cols[q]))) for i, q in enumerate(d.coordinates))
    best["closed_long_error"] = motion.estimate(long_t, wanted)[0]
    row["dop853"] = best
    return row


def closed_form_table(*, quick: bool = False) -> dict:
    """{rows: [{system, substitution, degree, kind, setup, evaluate, error, dop853: {rtol, seconds, error}} or
    {system, substitution, degree, reason}]}."""
    rows = []
    # quick: the first six, the Kepler ellipse in t and the two refused
    for case in CASES[:6] + CASES[-5:-4] + CASES[-2:] if quick else CASES:
        try:
            rows.append(_case(*case, quick=quick))
        except Exception as exc:  # noqa: BLE001 - a benchmark row reports its failure and the table goes on
            rows.append({"system": case[0], "substitution": "?", "degree": None,
                         "reason": f"{type(exc).__name__}: {exc}"})
    return {"rows": rows}


def report_lines(result: dict) -> list[str]:
    lines = ["## 9. Closed forms found by the toolkit (issue 16): per 2001 samples over 10 (and 1000) periods, warm",
             "", "| system | substitution | degree | motion | setup | 2001 samples | error (estimate) | DOP853 rtol | "
             "DOP853 time | DOP853 error | speed-up | 1000 periods: closed / DOP853 time | error |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        if "reason" in r:
            lines.append(f"| {r['system']} | {r['substitution']} | {r['degree'] or '—'} | integrated: "
                         f"{_short(r['reason'])} | | | | | | | | | |")
            continue
        dop = r["dop853"]
        total = r["setup"] + r["evaluate"]
        lines.append(f"| {r['system']} | {r['substitution']} | {r['degree']} | {r['kind']} | {r['setup'] * 1e3:.1f} ms "
                     f"| {r['evaluate'] * 1e3:.2f} ms | {r['error']:.1e} | {dop['rtol']:.0e} | "
                     f"{dop['seconds'] * 1e3:.1f} ms | {dop['error']:.1e} | "
                     f"{dop['seconds'] / r['evaluate']:.1f}× ({dop['seconds'] / total:.2f}× with setup) | "
                     f"{dop['closed_long'] * 1e3:.1f} / {dop['long_seconds'] * 1e3:.1f} ms | "
                     f"{dop['closed_long_error']:.1e} / {dop['long_error']:.1e} |")
    return lines + [""]


def _short(text: str, n: int = 90) -> str:
    return text if len(text) <= n else text[: n - 1] + "…"
