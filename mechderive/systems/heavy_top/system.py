"""The heavy symmetric top (section 3.6) as a :class:`~mechderive.systems.base.System`.

What a scene of ``system = "heavy_top"`` may say and output, and how it is solved: the closed form
(:mod:`.exact`, (3.70)-(3.80)) where it can follow the motion, the compiled DOP853 on ω and R
(:mod:`.integrate`) otherwise; each computes only what the requested quantities need.

Parameters ``I1 I3 M g l`` (I1 = I2 and I3 about the pivot), or ``I1 I3 Mgl`` (only M g l enters
the motion); initial ``theta phi psi theta_dot phi_dot psi_dot``.  Drift: E against
max_t (T + |V|), p_φ and p_ψ against max(|p_φ(0)|, |p_ψ(0)|, √(2 I1 T_max), √(I1 M g l)).

Importing this module derives nothing and imports no SymPy.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np

from ...errors import InvalidInputError
from ..base import BatchSummary, Key, OutOfReach, Quantity, Solved, System
from ..scene_keys import (SCENE_STRICT_HINT, at, check_keys, number, one_of, rename_keys)
from . import parameters as heavy_top_parameters
from .summary import SUMMARIES

if TYPE_CHECKING:  # pragma: no cover
    from ...core.drift import Drift
    from ...scenes.schema import Scene
    from ..scaling import Scaled

__all__ = ["HeavyTop", "SYSTEM"]

_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))
_RATE_KEYS = ("theta_dot", "phi_dot", "psi_dot")

_PARAMETERS = (
    Key("I1", "kg m^2", "moment about the pivot of the axes ⟂ e3 (I1 = I2)", scales_as="moment"),
    Key("I3", "kg m^2", "moment about the symmetry axis e3", scales_as="moment"),
    Key("M", "kg", "mass (give M, g, l, or Mgl)", required=False),
    Key("g", "m/s^2", "gravitational acceleration", required=False),
    Key("l", "m", "distance from the pivot to the centre of mass", required=False),
    Key("Mgl", "J", "M g l in one number, in place of M, g, l (only their product enters the motion)",
        required=False),
)
_INITIAL = (
    Key("theta", "rad", "nutation angle θ at t = 0, in [0, π]", scales_as="angle"),
    Key("phi", "rad", "precession angle φ at t = 0", scales_as="angle"),
    Key("psi", "rad", "spin angle ψ at t = 0", scales_as="angle"),
    Key("theta_dot", "rad/s", "θ̇ at t = 0", scales_as="rate"),
    Key("phi_dot", "rad/s", "φ̇ at t = 0", scales_as="rate"),
    Key("psi_dot", "rad/s", "ψ̇ at t = 0", scales_as="rate"),
)
_QUANTITIES = (
    Quantity("theta", "rad", "nutation angle θ: the axis e3 from the vertical"),
    Quantity("phi", "rad", "precession angle φ (continuous)"),
    Quantity("psi", "rad", "spin angle ψ (continuous)"),
    Quantity("theta_dot", "rad/s", "nutation rate θ̇", scales_as="rate"),
    Quantity("phi_dot", "rad/s", "precession rate φ̇", scales_as="rate"),
    Quantity("psi_dot", "rad/s", "spin rate ψ̇", scales_as="rate"),
    Quantity("u", "1", "u = cos θ (3.72)"),
    Quantity("energy", "J", "energy E = T + M g l cos θ (3.65), conserved", scales_as="energy"),
    Quantity("p_phi", "kg m^2/s", "p_φ, the vertical angular momentum (3.63), conserved",
             scales_as="angular momentum"),
    Quantity("p_psi", "kg m^2/s", "p_ψ = I3 ω3 (3.64), conserved", scales_as="angular momentum"),
    *(Quantity(f"omega{a}", "rad/s", f"angular velocity, body component ω{a}", scales_as="rate") for a in (1, 2, 3)),
    *(Quantity(q, "1", f"rotation matrix entry {q} (rows: the body axes in space components)") for q in _R_NAMES),
    *(Quantity(f"apex_{c}", "1", f"{c} component (space) of the symmetry axis e3, a unit vector") for c in "xyz"),
)

#: How each scaled output grows with the units, for the messages of :func:`mechderive.systems.scaling.refuse_overflow`.
_SCALES_AS = {**{q: "the rates" for q in ("theta_dot", "phi_dot", "psi_dot", "omega1", "omega2", "omega3")},
              "energy": "I ω² (moments times rates squared, and M g l)", "p_phi": "I ω (moments times rates)",
              "p_psi": "I ω (moments times rates)"}
_OUTPUT_KEYS = ("scene keys [parameters].I1, [parameters].I3, [initial].theta_dot, [initial].phi_dot, "
                "[initial].psi_dot")


# --- the scene's values ----------------------------------------------------------------------------

def _names(given: Mapping[str, Any]) -> tuple[str, ...]:
    """The heavy top's parameter names in the form the scene uses: I1 I3 M g l, or I1 I3 Mgl."""
    check_keys(given, "parameters", tuple(k.name for k in _PARAMETERS), (), "parameter for system 'heavy_top'")
    separate = [k for k in ("M", "g", "l") if k in given]
    if "Mgl" in given and separate:
        raise InvalidInputError("scene keys " + ", ".join(at("parameters", k) for k in ("Mgl", *separate))
                                + ": expected either Mgl or all of M, g, l (only M g l enters the motion), got both")
    names = heavy_top_parameters.MGL_KEYS if "Mgl" in given else heavy_top_parameters.PARAM_KEYS
    for key in names:
        if key not in given:
            raise InvalidInputError(f"scene key {at('parameters', key)}: missing; expected all of "
                                    + (f"{one_of(names)}, or {one_of(heavy_top_parameters.MGL_KEYS)} "
                                       "(only M g l enters the motion)" if "Mgl" not in names else one_of(names)))
    return names


def _solver_parameters(scene: "Scene") -> dict:
    """I1 I3 M g l for the compiled functions (``Mgl`` realised as M = 1, g = Mgl, l = 1: only M g l enters)."""
    return heavy_top_parameters.check_params(scene.parameters, strict=scene.strict)


# --- conserved quantities, derived and compiled like everything else ----------------------------

def _build_invariants():
    from . import model as hm

    m = hm.model()
    return [*hm.PARAMETERS, *hm.STATE], [m.energy, m.azimuthal_momentum, m.spin_momentum]


#: (name, build, module) of the compiled (E, p_φ, p_ψ) (3.63)–(3.65), as :func:`_heavy_invariants` takes it
_INVARIANTS_JOB = ("heavy_top.invariants", _build_invariants, "numpy")


@functools.cache
def _heavy_invariants() -> Callable[..., list]:
    from ...core import codecache

    name, build, module = _INVARIANTS_JOB
    return codecache.cached_lambdify(name, build, module=module)[0]


def _heavy_drifts(p: dict, energy: Any, p_phi: Any, p_psi: Any, cos_theta: Any) -> dict[str, "Drift"]:
    """E, p_φ, p_ψ (3.63)-(3.65) along a heavy top's motion against scales of that motion.

    E against max_t (T + |V|) with V = M g l cos θ, T = E - V: the size of the terms E sums.
    p_φ and p_ψ against max(|p_φ(0)|, |p_ψ(0)|, √(2 I1 T_max), √(I1 M g l)): the momenta's own
    size, that of the angular momentum the kinetic energy implies (|L| ~ √(2 I T)), and the
    momentum gravity gives in a time √(I1 / M g l) — so p_φ = 0 is measured against p_ψ, the
    sleeping top's p_ψ against itself, a top let go from rest against √(I1 M g l).
    """
    from ...core.drift import drift

    I1, mgl = float(p["I1"]), float(p["M"] * p["g"] * p["l"])
    E, pf, ps = (np.asarray(x, dtype=float) for x in (energy, p_phi, p_psi))
    V = mgl * np.asarray(cos_theta, dtype=float)
    T = np.maximum(E - V, 0.0)
    with np.errstate(invalid="ignore"):
        e_scale = float(np.nanmax(T + np.abs(V))) if np.any(np.isfinite(T)) else float("nan")
        t_max = float(np.nanmax(T)) if np.any(np.isfinite(T)) else 0.0
    # (√(I1 M g l) is finite: a momentum undefined at t = 0 does not make the scale undefined)
    p_scale = float(np.nanmax([abs(pf[0]), abs(ps[0]), np.sqrt(2.0 * I1 * t_max), np.sqrt(I1 * mgl)]))
    momenta = "max(|p_φ(0)|, |p_ψ(0)|, √(2 I1 T_max), √(I1 M g l))"
    return {"energy": drift(E, e_scale, "max_t (T + |V|)"), "p_phi": drift(pf, p_scale, momenta),
            "p_psi": drift(ps, p_scale, momenta)}


# --- which solver values the quantities need ------------------------------------------------------

_DIRECT = {"theta": "theta", "phi": "phi", "psi": "psi", "theta_dot": "theta_dot", "phi_dot": "phi_dot",
           "psi_dot": "psi_dot", "u": "u"}


#: what the closed form evaluates without φ̇ and ψ̇'s partial fractions
_ANGLE_FREE = frozenset({"u", "u_dot", "theta", "theta_dot", "phi_dot", "psi_dot"})


def _needs(names: tuple[str, ...]) -> list[str]:
    need: list[str] = []
    for q in names:
        if q in _DIRECT:
            key = _DIRECT[q]
        elif q in _R_NAMES:
            key = "R"
        elif q.startswith("apex_"):
            key = "apex"
        elif q.startswith("omega"):
            key = "omega"
        elif q in ("energy", "p_phi", "p_psi"):
            need.extend(k for k in ("theta", "theta_dot", "phi_dot", "psi_dot") if k not in need)
            continue
        else:
            raise InvalidInputError(f"unknown heavy_top quantity {q!r}")
        if key not in need:
            need.append(key)
    return need


def _columns(names: tuple[str, ...], values: dict[str, np.ndarray], params: dict) -> dict[str, np.ndarray]:
    """The requested columns from the solver's values; ``params`` in :data:`PARAM_KEYS` form (checked)."""
    out: dict[str, np.ndarray] = {}
    inv = None
    for q in names:
        if q in _DIRECT:
            out[q] = values[_DIRECT[q]]
        elif q in _R_NAMES:
            out[q] = values["R"][..., int(q[1]) - 1, int(q[2]) - 1]
        elif q.startswith("apex_"):
            out[q] = values["apex"][..., "xyz".index(q[-1])]
        elif q.startswith("omega"):
            out[q] = values["omega"][..., int(q[-1]) - 1]
        else:
            if inv is None:
                p = [params[k] for k in ("I1", "I3", "M", "g", "l")]
                inv = _heavy_invariants()(*p, values["theta"], values["theta_dot"], values["phi_dot"], values["psi_dot"])
            out[q] = np.broadcast_to(np.asarray(inv[("energy", "p_phi", "p_psi").index(q)], float), values["theta"].shape)
    return out


# --- the closed form -------------------------------------------------------------------------------

#: The quantities that are ill-conditioned near a pole passage (only φ ± ψ is defined there).
_POLE_CONDITIONED = ("phi", "psi", "phi_wrapped", "psi_wrapped", "phi_dot", "psi_dot")
#: The estimate names whose values are rates (rad/s): in a scaled scene their estimate scales too.
_RATE_ESTIMATES = ("theta_dot", "phi_dot", "psi_dot", "u_dot", "omega")
_STATE_KEYS = ("theta", "theta_dot", "phi_dot", "psi_dot")


def _estimate(top: Any, t: np.ndarray, names: list[str], scaled: "Scaled") -> float:
    """The closed form's estimate over ``names`` in the scene's units (a rate's estimate converted from the solver's)."""
    if scaled.rate == 0:
        return float(top.error_estimate(t, names))
    rates = [k for k in names if k in _RATE_ESTIMATES]
    others = [k for k in names if k not in _RATE_ESTIMATES]
    return max(float(top.error_estimate(t, others)) if others else 0.0,
               float(np.ldexp(top.error_estimate(t, rates), scaled.rate)) if rates else 0.0)


def _shared_prefix() -> None:
    """Derive what both u(t)'s constants (f(u) (3.73) through the Routhian) and the child's jobs are derived
    from — the Lagrangian, the conserved momenta, the cyclic velocities solved from them, a, b, α, β (3.66),
    (3.72) of the state — once, in this process, before :func:`~mechderive.core.codecache.prefetch` forks the
    child that goes on from there (both processes derived them before: ~40% of a cold start's CPU time,
    doubled).  This process needs all of it next anyway (a, b, α, β first)."""
    from . import model as hm

    m = hm.model()
    _ = m.cyclic_velocities, m.momenta_in_ab, m.constants_from_state
    # both processes compile next, and lambdify's code printer imports this module on first use (~11 ms)
    import sympy.codegen.ast  # noqa: F401


def _exact(scene: "Scene", t: np.ndarray) -> Solved:
    from ..scaling import keys_text, units_of
    from .exact import exact_heavy_top

    scaled = units_of(scene)
    need = _needs(scene.quantities)
    angles = any(k not in _ANGLE_FREE for k in need)
    if angles or "phi_dot" in need or "psi_dot" in need:
        # φ̇ and ψ̇'s partial fractions and rates will be needed: derived on a second core meanwhile (cold start);
        # so are b ∓ a in the half angle (the extended setup's last constants) and the invariants (the drift
        # check of φ, ψ or their rates), which this process would otherwise derive after u(t)'s constants
        from ...core.codecache import prefetch
        from .exact import angle_function_jobs
        from .exact_extended import gap_jobs

        prefetch([*gap_jobs(), *angle_function_jobs(angles=angles), _INVARIANTS_JOB], prepare=_shared_prefix)
    try:
        # over the scene's span the constants are set up in extended precision where their measured errors
        # allow (no mpmath imported: most of a warm run's solve stage was mpmath's import and 40-digit setup)
        top = exact_heavy_top(scene.parameters, scene.initial, strict=scene.strict,
                              horizon=float(np.max(np.abs(t))) if t.size else 0.0)
    except InvalidInputError as exc:
        raise OutOfReach(f"{keys_text('initial', _STATE_KEYS)} (with the parameters): {exc}") from exc
    if t[-1] > top.t_max:
        raise InvalidInputError(
            f"scene key [time].t_end: expected at most {scaled.seconds(top.t_max):.6g} s for this motion in closed "
            f"form (2^51 nutation periods of {scaled.seconds(top.nutation_period):.6g} s: beyond, the period count "
            f"is no longer an exact integer in double precision), got {scaled.original.t_end!r}")
    values, ps = top._evaluate(t, need)
    cols = _columns(scene.quantities, values, _solver_parameters(scene))

    # measured on this run, at the very values output, from what the quantities need only
    # (HeavyTopSolution.error_estimate: residuals of the derived equations, quadrature of the rates)
    estimate = _estimate(top, t, need, scaled)
    info = {"error_estimate": estimate,
            "evaluated": ps.computed, "motion_class": top.motion_class,
            "nutation_period": scaled.seconds(top.nutation_period)}
    angles = [k for k in need if k in _POLE_CONDITIONED]
    if angles and estimate > scene.rtol:
        # Near the pole (or the bottom) φ and ψ each are ill-conditioned — the motion itself defines
        # them poorly there, and the estimate counts it; R, the apex and ω, built from the
        # well-conditioned half sums and differences, may still meet rtol: say so if they do.
        rest = [k for k in need if k not in _POLE_CONDITIONED] or ["R"]
        if _estimate(top, t, rest, scaled) <= scene.rtol:
            info["error_estimate_kind"] = "near-pole conditioning of φ, ψ"
    return Solved(cols, info, top)


# --- integration -----------------------------------------------------------------------------------

def _rate_bound(scene: "Scene") -> float:
    """The fastest rate of a heavy top's motion (rad/s): of the body's ω, of its nutation, of the pendulum.

    ω3 = ψ̇ + φ̇ cos θ is constant (p_ψ = I3 ω3, 3.64); ω1² + ω2² ≤ 2 T / I1 with T ≤ E - V ≤ T0 + 2 M g l
    (3.65); the fast nutation turns at a = I3 ω3 / I1 (3.70), which exceeds ω3 where I3 > I1 (a body
    only with strict = false); the pendulum's rate √(M g l / I1) sets the time scale of a top let go
    from rest.  Square roots are taken before the quotients, so nothing overflows.
    """
    p, s = _solver_parameters(scene), scene.initial
    I1, I3, mgl = p["I1"], p["I3"], p["M"] * p["g"] * p["l"]
    th = s["theta"]
    w3 = abs(s["psi_dot"] + s["phi_dot"] * math.cos(th))
    transverse = math.hypot(s["theta_dot"], s["phi_dot"] * math.sin(th))  # √(ω1² + ω2²) at t = 0
    pendulum = math.sqrt(mgl) / math.sqrt(I1)
    return max(math.hypot(transverse, 2.0 * pendulum), w3, w3 * (I3 / I1) if w3 else 0.0, pendulum)


def _integrate(scene: "Scene", t: np.ndarray) -> Solved:
    from ...kinematics.rotations import euler_rates
    from ..scaling import check_integration_length, units_of
    from ...solvers.driver import integrate_to_rtol
    from .integrate import integrate_heavy_top

    scaled = units_of(scene)
    check_integration_length(scene, _rate_bound(scene), scaled)
    rate_unit = 2.0**scaled.rate

    def estimate(tr: Any) -> float | None:
        # ω in rad/s of the scene, R and the angles in rad (HeavyTopTrajectory.angle_error_estimate's parts)
        parts = (tr.omega_error_estimate, tr.rotation_error_estimate, tr.euler_angle_error_estimate)
        if any(x is None for x in parts):
            return None
        return float(max(parts[0] * rate_unit, parts[1], parts[2]))

    traj, attempts = integrate_to_rtol(
        lambda tol: integrate_heavy_top(scene.parameters, scene.initial, t, method="DOP853", rtol=tol,
                                        atol=tol * 1e-3, strict=scene.strict),
        estimate, scene.rtol)
    phi, theta, psi = traj.euler_angles.T
    values: dict[str, np.ndarray] = {"phi": phi, "theta": theta, "psi": psi, "u": np.cos(theta), "R": traj.R,
                                     "omega": traj.omega, "apex": traj.R[:, 2, :]}
    need = _needs(scene.quantities)
    if any(k in need for k in ("theta_dot", "phi_dot", "psi_dot")):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            rates = euler_rates(theta, psi, *traj.omega.T)  # singular where sin θ = 0: inf/nan reported there
        values.update(phi_dot=rates[:, 0], theta_dot=rates[:, 1], psi_dot=rates[:, 2])
    # E, p_φ, p_ψ from ω and R (the integrator's own invariants), not through the Euler rates,
    # which are singular at θ = 0.
    inv = np.asarray(traj.invariants, dtype=float)
    cols = _columns(tuple(q for q in scene.quantities if q not in ("energy", "p_phi", "p_psi")), values,
                    _solver_parameters(scene))
    for k, name in enumerate(("energy", "p_phi", "p_psi")):
        if name in scene.quantities:
            cols[name] = inv[:, k]
    cols = {q: cols[q] for q in scene.quantities}
    est = estimate(traj)
    info = {"error_estimate": est,
            "error_estimate_kind": traj.error_estimate_kind,
            "integrator": f"DOP853 ({'compiled C' if traj.backend == 'c' else 'SciPy solve_ivp'})",
            "integrator_attempts": attempts,
            "rhs_evaluations": int(traj.n_evaluations),
            "integrator_drift": {"energy": float(np.max(traj.energy_drift)),
                                 "p_phi": float(np.max(traj.p_phi_drift)),
                                 "p_psi": float(np.max(traj.p_psi_drift))}}
    return Solved(cols, info, traj)


# --- units -----------------------------------------------------------------------------------------

#: Initial φ, ψ beyond this (rad) are reduced mod 2π exactly before the solve: the closed form adds φ0 to
#: its phase in double-double, whose 2π carries ~1e-32 relative, so R would err ~|φ0|·1e-16.
_LARGEST_ANGLE = 4 * math.pi


def _reduced_angles(scene: "Scene", scaled: "Scaled") -> "Scaled":
    """``scaled`` with a large initial φ or ψ reduced mod 2π (the motion does not depend on them: both are
    cyclic (3.63)-(3.64)); the turns taken off are added back to the output columns of φ and ψ."""
    from ..scaling import reduce_angle

    big = {k: scene.initial[k] for k in ("phi", "psi") if abs(scene.initial[k]) > _LARGEST_ANGLE}
    if not big:
        return scaled
    reduced, offsets = {}, {}
    for k, x in big.items():
        reduced[k], offsets[k] = reduce_angle(x)
    work = dataclasses.replace(scaled.scene, initial={**scaled.scene.initial, **reduced}, strict=False)
    return dataclasses.replace(scaled, scene=work, offsets=offsets)


def _units(scene: "Scene") -> "Scaled":
    """The units of the motion: the Lagrangian (3.62), T - V = ½ I1 (θ̇² + φ̇² sin²θ) + ½ I3 (ψ̇ + φ̇ cos θ)²
    - M g l cos θ, is multiplied by a constant when I1, I3 and M g l are (the motion is unchanged), and a
    change of the time unit t → t/c multiplies the rates by c and leaves the motion the same if M g l is
    multiplied by c²."""
    from .. import scaling as u

    p, s = scene.parameters, scene.initial
    I1, I3 = p["I1"], p["I3"]
    gravity = [p["Mgl"], 1.0, 1.0] if "Mgl" in p else [p["M"], p["g"], p["l"]]
    k = u.moment_exponent((I1, I3))
    mgl_exp = sum(u.exponent(f) for f in gravity) if all(gravity) else None
    rate_exps = [u.exponent(s[r]) for r in _RATE_KEYS if s[r] != 0]
    # the fastest rate: the largest of the rates, and of √(M g l / I1), the pendulum's
    candidates = rate_exps + ([(mgl_exp - u.exponent(I1)) // 2] if mgl_exp is not None else [])
    j = max(candidates) if candidates else 0
    said = {"keys": _OUTPUT_KEYS, "scales": _SCALES_AS,
            "fastest": float(max((abs(s.get(r, 0.0)) for r in _RATE_KEYS), default=0.0))}
    if u.comfortable(k, j) and (mgl_exp is None or u.comfortable(mgl_exp)):
        return u.Scaled(scene, scene, **said)
    where = u.keys_text("parameters", ("I1", "I3") + (("Mgl",) if "Mgl" in p else ("M", "g", "l")))
    I1s, I3s = u.exact_ldexp(I1, -k), u.exact_ldexp(I3, -k)
    if I1s is None or I3s is None:
        u.refuse_ratio(u.keys_text("parameters", ("I1", "I3")), "the moments I1 and I3")
    g = u.split_product(gravity, -k - 2 * j)
    if g is None:
        u.refuse_ratio(where, "M g l against I1 and the rates")
    rates = {}
    for r in _RATE_KEYS:
        v = u.exact_ldexp(s[r], -j)
        if v is None:
            # a rate below 2^-1022 of the fastest: as good as zero against it over any reachable time,
            # but not exactly: say so rather than change the motion
            u.refuse_ratio(u.keys_text("initial", _RATE_KEYS), "theta_dot, phi_dot, psi_dot and √(M g l / I1)")
        rates[r] = v
    t_end = u.scaled_time(scene.t_end, j)
    params = {"I1": I1s, "I3": I3s, **dict(zip(("M", "g", "l"), g))}
    scaled = dataclasses.replace(scene, parameters=params, initial={**s, **rates}, t_end=t_end, strict=False)
    columns = {**{q: j for q in ("theta_dot", "phi_dot", "psi_dot", "omega1", "omega2", "omega3")},
               "energy": k + 2 * j, "p_phi": k + j, "p_psi": k + j}
    return u.Scaled(scene, scaled, time=j, columns=columns, rate=j, **said)


def _initial_invariants(work: "Scene") -> dict[str, float]:
    """E, p_φ, p_ψ at t = 0 in the solver's units (refused up front where they leave the doubles)."""
    p, s = heavy_top_parameters.check_params(work.parameters, strict=False), work.initial
    th, w3 = s["theta"], s["psi_dot"] + s["phi_dot"] * np.cos(s["theta"])
    E = 0.5 * (p["I1"] * (s["theta_dot"] ** 2 + (s["phi_dot"] * np.sin(th)) ** 2) + p["I3"] * w3 ** 2) \
        + p["M"] * p["g"] * p["l"] * np.cos(th)
    return {"energy": E, "p_psi": p["I3"] * w3,
            "p_phi": p["I1"] * np.sin(th) ** 2 * s["phi_dot"] + p["I3"] * w3 * np.cos(th)}


# --- built-in scenes -------------------------------------------------------------------------------

_TOP = """\
[parameters]            # I1 about the pivot; M g l = 1
I1 = 1.0
I3 = 0.5
M = 0.1
g = 10.0
l = 1.0
"""

_DEFAULT = f"""\
# A heavy top let go at θ0 = 0.5 with θ̇ = φ̇ = 0 and ψ̇ = ω3 = 5 rad/s (section 3.6.1):
# θ nutates between 0.5 and 0.7576 with period 3.5177 s; the apex traces cusps.
system = "heavy_top"
method = "auto"

{_TOP}
[initial]
theta = 0.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 5.0

[time]
t_end = 35.177          # 10 nutation periods
samples = 2001

[output]
quantities = ["theta", "phi", "psi"]
"""

# (name, description, TOML text): the heavy tops share the top of the chapter's examples, I1 = 1 (about the
# pivot), I3 = 0.5, M g l = 1 (M = 0.1, g = 10, l = 1), whose sleeping threshold (3.83) is
# ω3 = 2 √(I1 M g l) / I3 = 4 rad/s; the gyroscope is the textbook's horizontal one, given with Mgl.
_SCENES: tuple[tuple[str, str, str], ...] = (
    ("default",
     "heavy top let go from rest at θ = 0.5 with spin 5 rad/s: cusped nutation (3.6.1), 10 nutation periods",
     _DEFAULT),
    ("heavy_top_looping",
     "heavy top pushed against its spin: φ̇ changes sign and the apex draws loops (figure 44)",
     f"""\
# Let go at θ0 = 0.5 with φ̇ = -0.5 rad/s against the spin ψ̇ = 5 rad/s: b - a u changes sign
# between the turning points θ = 0.5 and θ ≈ 1.095, so the apex path loops (figure 44, middle).
system = "heavy_top"

{_TOP}
[initial]
theta = 0.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = -0.5
psi_dot = 5.0

[time]
t_end = 20.0
samples = 2001

[output]
quantities = ["theta", "phi", "psi", "apex_x", "apex_y", "apex_z"]
"""),
    ("heavy_top_hanging",
     "heavy top let go below the pivot at θ = 2.5 with spin 5 rad/s",
     f"""\
# Let go below the horizontal, θ0 = 2.5, spin ψ̇ = 5 rad/s: θ nutates between 2.5 and about 2.638.
system = "heavy_top"

{_TOP}
[initial]
theta = 2.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 5.0

[time]
t_end = 20.0
samples = 2001

[output]
quantities = ["theta", "phi", "psi", "apex_x", "apex_y", "apex_z"]
"""),
    ("sleeping_top",
     "upright heavy top (θ = 0) spinning at 6 rad/s, above the threshold 2√(I1 M g l)/I3 = 4 rad/s: stable",
     f"""\
# A sleeping top (3.6.3): θ = θ̇ = 0 with ω3 = 6 rad/s > 2 √(I1 M g l) / I3 = 4 rad/s, so it stays up.
# φ and ψ are not separately defined at θ = 0; ask for the apex instead.
system = "heavy_top"

{_TOP}
[initial]
theta = 0.0
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 6.0

[time]
t_end = 10.0
samples = 1001

[output]
quantities = ["theta", "energy", "apex_x", "apex_y", "apex_z"]
"""),
    ("gyroscope",
     "horizontal gyroscope let go at θ = π/2 (p_φ = 0), spin 300 rad/s: dips 8.34° and precesses at 2.59 rad/s "
     "(≈ M g l / (I3 ω3) = 2.62)",
     """\
# The horizontal gyroscope (3.6.2): let go at θ = π/2 with φ̇ = 0, so p_φ = 0 and the apex starts at a cusp.
# It dips to θ = 98.34° and nutates with period 0.1752 s while precessing at 2.588 rad/s on average,
# near the leading-order M g l / (I3 ω3) = 2.616 rad/s.  Only M g l enters the motion: given as Mgl
# (M = 1 kg, g = 9.81 m/s², l = 0.1 m; I1 = 0.010625 kg m² about the pivot, I3 = 0.00125 kg m²).
system = "heavy_top"

[parameters]
I1 = 0.010625
I3 = 0.00125
Mgl = 0.981

[initial]
theta = 1.5707963267948966
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 300.0

[time]
t_end = 1.7522257106587  # 10 nutation periods
samples = 2001

[output]
quantities = ["theta", "phi", "apex_x", "apex_y", "apex_z", "p_phi"]
"""),
)


# --- the system ------------------------------------------------------------------------------------

class HeavyTop(System):
    """The heavy symmetric top about a fixed pivot (3.6): closed form (3.70)-(3.80) and integration."""

    name = "heavy_top"
    summary = "heavy symmetric top on a fixed pivot in uniform gravity: closed form (Jacobi elliptic) or integration"
    section = "3.6"
    parameters = _PARAMETERS
    initial = _INITIAL
    quantities = _QUANTITIES
    animation_quantities = ("omega1", "omega2", "omega3",
                            "R11", "R12", "R13", "R21", "R22", "R23", "R31", "R32", "R33")
    methods = ("exact", "integrate")
    #: measured: the growth of maxrss from 5·10⁵ samples is 360-510 bytes per sample, closed form and
    #: integration, one quantity and all
    bytes_per_sample = 600
    plot_quantities = ("theta", "apex_x", "apex_y", "apex_z")
    summaries = SUMMARIES

    def check_parameters(self, given: Mapping[str, Any], *, strict: bool = True) -> dict[str, Any]:
        """I1, I3 and M g l (or Mgl) > 0 and, unless ``strict`` is False, I1 - M l² ≥ I3/2 (a body's);
        the form given (M g l or Mgl) is kept."""
        names = _names(given)
        expected = "a number > 0" + ("" if strict else " (strict = false does not waive this)")
        p = {k: number(at("parameters", k), given[k], expected=expected, valid=lambda x: x > 0) for k in names}
        # Sums and squares of moments near the largest double overflow to ±inf, which the comparisons order
        # rightly: the checks' answers stand; NumPy's RuntimeWarnings would only be noise before the message.
        try:
            with np.errstate(all="ignore"):
                heavy_top_parameters.check_params(p, strict=strict)
        except InvalidInputError as exc:
            renamed = rename_keys(exc, "parameters", names)
            raise type(renamed)(str(renamed).replace(heavy_top_parameters.STRICT_HINT, SCENE_STRICT_HINT)) from exc
        return p

    def check_initial(self, given: Mapping[str, Any], parameters: Mapping[str, Any]) -> dict[str, Any]:
        """All six of θ ∈ [0, π], φ, ψ (rad) and θ̇, φ̇, ψ̇ (rad/s), finite."""
        names = heavy_top_parameters.INITIAL_NAMES
        check_keys(given, "initial", names, names, "initial value for system 'heavy_top'")
        s = {k: number(at("initial", k), given[k]) for k in names}
        number("[initial].theta", s["theta"], expected="a number in [0, π]", valid=lambda x: 0 <= x <= math.pi)
        try:
            heavy_top_parameters.check_initial(s)
        except InvalidInputError as exc:
            raise rename_keys(exc, "initial", names) from exc
        return s

    def waived(self, parameters: Mapping[str, Any]) -> list[str]:
        with np.errstate(all="ignore"):  # as in check_parameters
            return heavy_top_parameters.rigid_body_violations(parameters)

    def scale(self, scene: "Scene") -> "Scaled":
        from ..scaling import check_outputs

        scaled = _reduced_angles(scene, _units(scene))
        if not scaled.identity:
            check_outputs(scaled, _initial_invariants(scaled.scene))
        return scaled

    def solve(self, scene: "Scene", method: str, t: np.ndarray) -> Solved:
        return _exact(scene, t) if method == "exact" else _integrate(scene, t)

    def summarize(self, scene: "Scene", solved: Solved, t: np.ndarray,
                  names: tuple[str, ...]) -> dict[str, tuple[Any, Any]]:
        """Turning angles, roots of f (3.73), nutation period, mean precession, figure 44's class, the steady
        motions (3.80), (3.83) and the invariants: see :mod:`.summary`."""
        from .summary import summarize

        return summarize(scene, solved, t, names)

    def summarize_batch(self, parameters: Mapping[str, np.ndarray], initial: Mapping[str, np.ndarray],
                        names: tuple[str, ...], *, strict: bool = True, scene: Any = None) -> BatchSummary | None:
        """Turning angles, roots, nutation period, precession, class and invariants of N tops at once, in
        NumPy from the derived constants (:mod:`.batch`); the ill-conditioned points go one by one."""
        from .batch import summarize_batch

        return summarize_batch(parameters, initial, names, strict=strict)

    def period(self, scene: "Scene") -> float | None:
        """The nutation period 2K(m)/κ (s) from the closed form's setup; None where steady or out of its reach."""
        from .summary import period

        return period(scene)

    def drift(self, scene: "Scene", solved: Solved, t: np.ndarray) -> dict[str, "Drift"]:
        from ...core.drift import drift

        cols, solution = solved.columns, solved.solution
        p = _solver_parameters(scene)
        if hasattr(solution, "_evaluate") and not any(q in cols for q in ("phi", "psi", "phi_dot", "psi_dot",
                                                                          "energy", "p_phi", "p_psi", "omega1",
                                                                          "omega2", "omega3", "apex_x", "apex_y",
                                                                          "R11")):
            # Only u or θ asked for: check the energy through u̇² = f(u) (3.73), which needs nothing
            # beyond u itself; p_φ and p_ψ enter the closed form as the constants b and a, exactly.
            # Its scale: the size of f's terms at |u| ≤ 1.
            v, _ = solution._evaluate(t, ["u", "u_dot"])
            c3, c2, c1, c0 = solution.f_coefficients
            f = ((c3 * v["u"] + c2) * v["u"] + c1) * v["u"] + c0
            return {"energy (u̇² - f(u))": drift(v["u_dot"] ** 2 - f, abs(c0) + abs(c1) + abs(c2) + abs(c3),
                                                 "|c0| + |c1| + |c2| + |c3| of f(u)", reference=0.0)}
        if hasattr(solution, "_evaluate"):
            v, _ = solution._evaluate(t, ["theta", "theta_dot", "phi_dot", "psi_dot"])
            E, pf, ps = _heavy_invariants()(*(p[k] for k in heavy_top_parameters.PARAM_KEYS), v["theta"],
                                            v["theta_dot"], v["phi_dot"], v["psi_dot"])
            return _heavy_drifts(p, E, pf, ps, np.cos(v["theta"]))
        # the integrator's own invariants, from ω and R (no Euler rates, singular at θ = 0)
        inv = np.asarray(solution.invariants, dtype=float)
        return _heavy_drifts(p, inv[:, 0], inv[:, 1], inv[:, 2], solution.R[:, 2, 2])

    def derivations(self) -> tuple:
        from .derive_entries import derivations

        return derivations()

    def check_system(self) -> Any:
        from .derive_entries import check_system

        return check_system()

    def parameter_values(self, parameters: Mapping[str, Any]) -> dict[str, float]:
        """I1 I3 M g l; a scene given with ``Mgl`` as M = Mgl, g = l = 1 (only the product enters (3.62)'s motion)."""
        values = super().parameter_values(parameters)
        if "Mgl" in values:
            values.update(M=values.pop("Mgl"), g=1.0, l=1.0)
        return values

    def lagrangian_model(self) -> tuple:
        """(L (3.62) in the state symbols, (φ, θ, ψ), (φ̇, θ̇, ψ̇), (I1, I3, M, g, l)) for the generic
        linearization (the sleeping top's criterion (3.83) about θ = 0)."""
        from . import model as hm

        return (hm.model().state_lagrangian, (hm.phi, hm.theta, hm.psi), (hm.phi_dot, hm.theta_dot, hm.psi_dot),
                tuple(hm.PARAMETERS))

    def plot(self, result: Any, figure: Any) -> bool:
        """Left, the path of the apex e3 on the unit sphere (3-D, over a faint wireframe sphere; the
        chapter's figure 44); right, θ(t)."""
        from ..figures import sphere_grid

        d = result.columns
        figure.set_size_inches(11.5, 5.0)
        ax = figure.add_subplot(1, 2, 1, projection="3d")
        ax.plot_wireframe(*sphere_grid(1.0, 1.0, 1.0), color="0.55", linewidth=0.35, alpha=0.45)
        ax.plot(d["apex_x"], d["apex_y"], d["apex_z"], color="C0", linewidth=1.0)
        ax.scatter([d["apex_x"][0]], [d["apex_y"][0]], [d["apex_z"][0]], color="C3", s=12, label="t = 0")
        ax.set_box_aspect((1, 1, 1))
        ax.locator_params(nbins=5)
        ax.set_xlabel("x (unit sphere)")
        ax.set_ylabel("y (unit sphere)")
        ax.set_zlabel("z, up (unit sphere)")
        ax.set_title("apex e3 on the unit sphere")
        ax.legend(loc="upper left", fontsize="small")
        right = figure.add_subplot(1, 2, 2)
        right.plot(result.t, d["theta"], color="C0")
        right.set_xlabel("t (s)")
        right.set_ylabel("θ (rad)")
        right.set_title("nutation θ(t)")
        right.grid(True, alpha=0.3)
        return True

    def motion_geometry(self, result: Any) -> Any:
        """A cone about its apex at the pivot, sized from I1 and I3 (:func:`..figures.cone_of`), with the trace
        of its symmetry axis (the apex path of figure 44), ω and L."""
        from ..figures import body_geometry, cone_of

        p = result.scene.parameters
        I1, I3 = p["I1"], p["I3"]
        return body_geometry(result.t, result.columns, (I1, I1, I3), shape="cone", size=cone_of(I1, I3),
                             traces_from_apex=True)

    def example_scene(self) -> str:
        return _DEFAULT

    def builtin_scenes(self) -> tuple[tuple[str, str, str], ...]:
        return _SCENES


SYSTEM = HeavyTop()
