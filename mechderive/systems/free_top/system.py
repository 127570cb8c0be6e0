"""The free top (sections 3.3-3.5) as a :class:`~mechderive.systems.base.System`.

What a scene of ``system = "free_top"`` may say and output, and how it is solved: the closed form
(:mod:`.exact`: Jacobi elliptic functions (3.4.4), the rotation by (3.5.3)) or the compiled DOP853 on
Euler's equations (3.33) and R (:mod:`.integrate`); each computes only what the requested quantities
need (ω alone never builds R).

Parameters ``I1 I2 I3`` (principal moments); initial ``omega = [w1, w2, w3]`` (body frame, rad/s)
and optional Euler angles ``phi theta psi`` (default 0: R(0) = 1).  Drift: T against T and |L|
against |L| (both ≥ 0, zero only at rest).

Importing this module derives nothing and imports no SymPy.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np

from ...errors import InvalidInputError
from ..base import Key, OutOfReach, Quantity, Solved, System
from .summary import SUMMARIES
from ..scene_keys import SCENE_STRICT_HINT, at, check_keys, number, number_list, rename_keys

if TYPE_CHECKING:  # pragma: no cover
    from ..base import BatchSummary
    from ...core.drift import Drift
    from ...scenes.schema import Scene
    from ..scaling import Scaled

__all__ = ["FreeTop", "SYSTEM"]

_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))
_ANGLES = ("phi", "theta", "psi")
_MOMENTS = ("I1", "I2", "I3")

_PARAMETERS = tuple(Key(k, "kg m^2", f"principal moment of inertia about the body axis e{k[1]}", scales_as="moment")
                    for k in _MOMENTS)
_INITIAL = (
    Key("omega", "rad/s", "angular velocity at t = 0, body components [w1, w2, w3]", size=3, scales_as="rate"),
    *(Key(k, "rad", f"Euler angle {k} at t = 0 (3.54; R(0) = 1 when all are 0)", required=False, default=0.0,
          scales_as="angle") for k in _ANGLES),
)
_QUANTITIES = (
    *(Quantity(f"omega{a}", "rad/s", f"angular velocity, body component ω{a}", scales_as="rate") for a in (1, 2, 3)),
    *(Quantity(f"L{a}", "kg m^2/s", f"angular momentum, body component L{a} = I{a} ω{a}",
               scales_as="angular momentum") for a in (1, 2, 3)),
    Quantity("energy", "J", "kinetic energy T = ½ Σ I_a ω_a² (3.46), conserved", scales_as="energy"),
    Quantity("L_norm", "kg m^2/s", "|L|, conserved", scales_as="angular momentum"),
    *(Quantity(q, "1", f"rotation matrix entry {q} (rows: the body axes in space components)") for q in _R_NAMES),
    Quantity("phi", "rad", "Euler angle φ (3.54), continuous"),
    Quantity("theta", "rad", "Euler angle θ (3.54)"),
    Quantity("psi", "rad", "Euler angle ψ (3.54), continuous"),
    *(Quantity(f"q{i}", "1", f"unit quaternion of R, component q{i}") for i in range(4)),
)

#: How each scaled output grows with the units, for the messages of :func:`mechderive.systems.scaling.refuse_overflow`.
_SCALES_AS = {**{f"omega{a}": "the rates" for a in (1, 2, 3)},
              "energy": "I ω² (moments times rates squared, and M g l)", "L_norm": "I ω (moments times rates)",
              **{f"L{a}": "I ω (moments times rates; the cat's: mass · length² / t_end)" for a in (1, 2, 3)}}
_OUTPUT_KEYS = "scene keys [parameters].I1, [parameters].I2, [parameters].I3, [initial].omega"


@functools.cache
def _invariants() -> Callable[..., list]:
    from ...core import codecache

    def build():
        from . import model as fm

        m = fm.model()
        return [fm.I1, fm.I2, fm.I3, *fm.omega_symbols()], [m.energy, m.angular_momentum_squared]
    return codecache.cached_lambdify("free_top.invariants", build, module="numpy")[0]


def _setup(scene: "Scene") -> tuple[tuple, np.ndarray, np.ndarray]:
    from ...kinematics.rotations import rotation_matrix

    p, s = scene.parameters, scene.initial
    moments = (p["I1"], p["I2"], p["I3"])
    R0 = rotation_matrix(s.get("phi", 0.0), s.get("theta", 0.0), s.get("psi", 0.0))
    return moments, np.asarray(s["omega"], dtype=float), R0


def _columns(names: tuple[str, ...], omega: Callable[[], np.ndarray], rotation: Callable[[], np.ndarray],
             angles: Callable[[], np.ndarray], quaternion: Callable[[], np.ndarray],
             moments: tuple) -> dict[str, np.ndarray]:
    cache: dict[str, np.ndarray] = {}

    def get(key: str, make: Callable[[], np.ndarray]) -> np.ndarray:
        if key not in cache:
            cache[key] = make()
        return cache[key]

    out: dict[str, np.ndarray] = {}
    I = np.array(moments)
    for q in names:
        if q.startswith("omega"):
            out[q] = get("omega", omega)[:, int(q[-1]) - 1]
        elif q in ("L1", "L2", "L3"):
            out[q] = get("omega", omega)[:, int(q[-1]) - 1] * I[int(q[-1]) - 1]
        elif q in ("energy", "L_norm"):
            w = get("omega", omega)
            E, L2 = _invariants()(*moments, *w.T)
            out[q] = np.asarray(E, float) if q == "energy" else np.sqrt(np.asarray(L2, float))
        elif q in _R_NAMES:
            out[q] = get("R", rotation)[:, int(q[1]) - 1, int(q[2]) - 1]
        elif q in _ANGLES:
            out[q] = get("angles", angles)[:, _ANGLES.index(q)]
        elif q in ("q0", "q1", "q2", "q3"):
            out[q] = get("q", quaternion)[:, int(q[1])]
        else:
            raise InvalidInputError(f"unknown free_top quantity {q!r}")
    return out


def _needs(names: tuple[str, ...]) -> list[str]:
    """The solution's methods the quantities come from: omega, rotation, euler_angles, quaternion."""
    need: list[str] = []
    for q in names:
        key = ("omega" if q.startswith("omega") or q in ("L1", "L2", "L3", "energy", "L_norm") else
               "rotation" if q in _R_NAMES else "euler_angles" if q in _ANGLES else "quaternion")
        if key not in need:
            need.append(key)
    return need


#: The closed form's estimate (FreeTopSolution.error_estimate) that covers each output family.
_EXACT_ESTIMATES = {"omega": "omega", "rotation": "R", "quaternion": "R", "euler_angles": "euler_angles"}
#: The integrated free top's estimate that covers each output family of :func:`_needs`.
_ESTIMATES = {"omega": "omega_error_estimate", "rotation": "rotation_error_estimate",
              "quaternion": "rotation_error_estimate", "euler_angles": "euler_angle_error_estimate"}


def _exact(scene: "Scene", t: np.ndarray) -> Solved:
    from ..scaling import units_of
    from .exact import MAX_TRACKING_POINTS, TRACKING_STEP, exact_free_top

    scaled = units_of(scene)
    moments, w0, R0 = _setup(scene)
    try:
        # the span is known: the constants in extended precision where that suffices over it (no mpmath)
        sol = exact_free_top(moments, w0, R0=R0, strict=scene.strict,
                             horizon=float(np.max(np.abs(t))) if t.size else 0.0)
    except InvalidInputError as exc:
        raise OutOfReach(f"scene keys [parameters], [initial].omega: {exc}") from exc
    if t[-1] > sol.t_max:
        raise InvalidInputError(
            f"scene key [time].t_end: expected at most {scaled.seconds(sol.t_max):.6g} s for this motion in closed "
            f"form (2^50 quarter periods or turns: beyond, the count is no longer an exact integer in double "
            f"precision), got {scaled.original.t_end!r}")
    need = _needs(scene.quantities)
    if "euler_angles" in need:
        # the continuous Euler angles are tracked on a grid of TRACKING_STEP rad of the fastest turn
        fastest = float(np.sqrt(2.0 * sol.energy / min(moments)))
        points = t[-1] * fastest / TRACKING_STEP + len(t)
        if points > MAX_TRACKING_POINTS:
            limit = (MAX_TRACKING_POINTS - len(t)) * TRACKING_STEP / fastest
            raise InvalidInputError(
                f"scene key [time].t_end: expected at most {scaled.seconds(max(limit, 0.0)):.6g} s for continuous "
                f"Euler angles (phi, theta, psi) of this motion ({MAX_TRACKING_POINTS} tracking points of "
                f"{TRACKING_STEP} rad), got {scaled.original.t_end!r}; R or the quaternion need no tracking")
    cols = _columns(scene.quantities, lambda: sol.omega(t), lambda: sol.rotation(t),
                    lambda: sol.euler_angles(t), lambda: sol.quaternion(t), moments)
    # measured on this run, at the very values output (FreeTopSolution.error_estimate): ω relative to
    # |ω|, R and q in their entries, the Euler angles in rad — none of them depends on the units
    estimate = float(sol.error_estimate(t, sorted({_EXACT_ESTIMATES[k] for k in need})))
    info = {"error_estimate": estimate, "kind": sol.kind, "polhode_period": scaled.seconds(sol.polhode_period),
            "m": sol.m}
    return Solved(cols, info, sol)


def _integrated_estimate(traj: Any, need: list[str], rate_unit: float = 1.0) -> float | None:
    """The largest of the run's measured estimates over the families the scene outputs (ω's in the scene's rad/s).

    A scene of ω columns alone is not charged with the Euler angles' 2π per unresolved pole
    passage; one that outputs angles is.
    """
    values = [getattr(traj, _ESTIMATES[k]) for k in need]
    if any(v is None for v in values):
        return None
    return float(max(np.max(v) * (rate_unit if k == "omega" else 1.0) for k, v in zip(need, values)))


def _rate_bound(moments: tuple, w0: np.ndarray) -> float:
    """The fastest rate of a free top's motion (rad/s): |ω| ≤ √(2T / I_min) times the largest coupling of
    Euler's equations (3.33), |I_b - I_c| / I_a (at least 1), the rate at which ω's direction changes.

    Square roots and quotients are taken in an order that cannot overflow for any positive moments.
    """
    I = [float(x) for x in moments]
    two_T = math.fsum((math.sqrt(i) * abs(w)) ** 2 for i, w in zip(I, w0))  # Σ I ω², by √I|ω| to stay finite
    spin = math.sqrt(two_T) / math.sqrt(min(I))
    coupling = max(1.0, *(abs(I[(a + 1) % 3] - I[(a + 2) % 3]) / I[a] for a in range(3)))
    return spin * coupling


def _integrate(scene: "Scene", t: np.ndarray) -> Solved:
    from ..scaling import check_integration_length, units_of
    from ...solvers.driver import integrate_to_rtol
    from .integrate import integrate_free_top

    scaled = units_of(scene)
    moments, w0, R0 = _setup(scene)
    check_integration_length(scene, _rate_bound(moments, w0), scaled)
    need = _needs(scene.quantities)
    rate_unit = 2.0**scaled.rate
    traj, attempts = integrate_to_rtol(
        lambda tol: integrate_free_top(moments, w0, t, R0=R0, method="DOP853", rtol=tol, atol=tol * 1e-3,
                                       strict=scene.strict),
        lambda tr: _integrated_estimate(tr, need, rate_unit), scene.rtol)
    # The Euler angles are counted along the integrator's own steps (never unwrapped from the
    # samples, which aliases at coarse sampling).
    cols = _columns(scene.quantities, lambda: traj.omega, lambda: traj.R, lambda: traj.euler_angles,
                    lambda: traj.quaternion, moments)
    info = {"error_estimate": _integrated_estimate(traj, need, rate_unit),
            "integrator": f"DOP853 ({'compiled C' if traj.backend == 'c' else 'SciPy solve_ivp'})",
            "integrator_attempts": attempts,
            "rhs_evaluations": int(traj.n_evaluations)}
    return Solved(cols, info, traj)


def _units(scene: "Scene") -> "Scaled":
    """The units of the motion: Euler's equations (3.33) are homogeneous in the moments and, with
    t → t/c, ω → c ω, in time."""
    from .. import scaling as u

    p, s = scene.parameters, scene.initial
    I = (p["I1"], p["I2"], p["I3"])
    w = s["omega"]
    k = u.moment_exponent(I)
    nonzero = [u.exponent(x) for x in w if x != 0]
    j = max(nonzero) if nonzero else 0
    said = {"keys": _OUTPUT_KEYS, "scales": _SCALES_AS, "fastest": float(max((abs(r) for r in w), default=0.0))}
    if u.comfortable(k, j) and u.comfortable(*(u.exponent(x) for x in I)):
        return u.Scaled(scene, scene, **said)
    Is = [u.exact_ldexp(x, -k) for x in I]
    if any(x is None for x in Is):
        u.refuse_ratio(u.keys_text("parameters", _MOMENTS), "the moments")
    ws = [u.exact_ldexp(x, -j) for x in w]
    if any(x is None for x in ws):
        u.refuse_ratio("scene key [initial].omega", "the components of omega")
    t_end = u.scaled_time(scene.t_end, j)
    scaled = dataclasses.replace(scene, parameters=dict(zip(_MOMENTS, Is)),
                                 initial={**s, "omega": tuple(ws)}, t_end=t_end, strict=False)
    columns = {**{f"omega{a}": j for a in (1, 2, 3)}, **{f"L{a}": k + j for a in (1, 2, 3)},
               "L_norm": k + j, "energy": k + 2 * j}
    return u.Scaled(scene, scaled, time=j, columns=columns, rate=j, **said)


_TOP = """\
[parameters]
I1 = 1.0
I2 = 2.0
I3 = 3.0
"""

_TUMBLING = f"""\
# A free asymmetric top (3.4.4): ω moves on a closed polhode, the body tumbles.
system = "free_top"

{_TOP}
[initial]
omega = [1.0, 0.5, 1.0]  # body frame, rad/s; Euler angles default to 0 (R(0) = 1)

[time]
t_end = 100.0
samples = 2001

[output]
quantities = ["omega1", "omega2", "omega3", "R11", "R12", "R13", "R21", "R22", "R23", "R31", "R32", "R33"]
"""

# (name, description, TOML text); the free tops have I = (1, 2, 3)
_SCENES: tuple[tuple[str, str, str], ...] = (
    ("free_top_tumbling",
     "free asymmetric top, I = (1, 2, 3), ω(0) = (1, 0.5, 1): ω circles e3 (L² > 2 T I2), 100 s",
     _TUMBLING),
    ("free_top_near_separatrix",
     "free top with L² - 2 T I2 = 1e-10 L²: a polhode just on the e3 side of the separatrix (3.4.4, figure 33)",
     f"""\
# L² - 2 T I2 = Σ I_a (I_a - I2) ω_a² = 3 ω3² - ω1² is set to 1.00000036e-10 L² by the choice of ω3
# (ω3 = sqrt((ω1² (1 + ε) + 4 ε ω2²) / (3 (1 - 3 ε))), ε = 1e-10, rounded to the nearest double).
system = "free_top"

{_TOP}
[initial]
omega = [1.0, 0.5, 0.5773502693339634]

[time]
t_end = 100.0
samples = 4001

[output]
quantities = ["omega1", "omega2", "omega3", "energy", "L_norm"]
"""),
    ("tennis_racket",
     "spin about the intermediate axis with a 1e-6 perturbation: the tennis-racket flip (3.4.3)",
     f"""\
# Spin ω2 = 1 rad/s about the intermediate axis, ω1 = ω3 = 1e-6: unstable (3.4.3); the perturbation
# grows like exp(ω2 √((I2 - I1)(I3 - I2) / (I1 I3)) t) = exp(0.577 t) and the body flips over.
system = "free_top"

{_TOP}
[initial]
omega = [1e-6, 1.0, 1e-6]

[time]
t_end = 100.0
samples = 4001

[output]
quantities = ["omega1", "omega2", "omega3"]
"""),
)


def _moments_for_plot(result: Any) -> tuple[float, float, float]:
    """The moments of the picture's ellipsoid: the scene's, or ``extra["moments"]`` of a plot of bare data."""
    scene = getattr(result, "scene", None)
    if scene is not None:
        return tuple(float(scene.parameters[k]) for k in _MOMENTS)  # type: ignore[return-value]
    moments = result.extra.get("moments")
    try:
        values = tuple(float(m) for m in moments)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        values = ()
    if len(values) != 3 or not all(math.isfinite(m) and m > 0 for m in values):
        raise InvalidInputError(f"plot of free_top: expected extra['moments'] = (I1, I2, I3), three numbers > 0, "
                                f"got {moments!r}")
    return values  # type: ignore[return-value]


class FreeTop(System):
    """The free rigid body (3.3-3.5): closed form (Jacobi elliptic functions) and integration."""

    name = "free_top"
    summary = "free rigid body (no torque): closed form (Jacobi elliptic functions) or integration"
    section = "3.4, 3.5"
    parameters = _PARAMETERS
    initial = _INITIAL
    quantities = _QUANTITIES
    animation_quantities = ("omega1", "omega2", "omega3",
                            "R11", "R12", "R13", "R21", "R22", "R23", "R31", "R32", "R33")
    summaries = SUMMARIES
    methods = ("exact", "integrate")
    #: measured: the growth of maxrss from 5·10⁵ samples is 225-490 bytes per sample
    bytes_per_sample = 600
    plot_quantities = ("omega1", "omega2", "omega3")

    def check_parameters(self, given: Mapping[str, Any], *, strict: bool = True) -> dict[str, Any]:
        """I1, I2, I3 > 0 and, unless ``strict`` is False, the triangle inequalities of a body's moments."""
        check_keys(given, "parameters", _MOMENTS, _MOMENTS, "parameter for system 'free_top'")
        expected = "a number > 0" + ("" if strict else " (strict = false does not waive this)")
        p = {k: number(at("parameters", k), given[k], expected=expected, valid=lambda x: x > 0) for k in _MOMENTS}
        try:
            # sums of moments near the largest double overflow to inf, which the comparisons order rightly
            with np.errstate(all="ignore"):
                from ...inertia.validate import STRICT_HINT, check_principal_moments  # imports SymPy: only here

                check_principal_moments(p["I1"], p["I2"], p["I3"], strict=strict)
        except InvalidInputError as exc:
            renamed = rename_keys(exc, "parameters", _MOMENTS)
            raise type(renamed)(str(renamed).replace(STRICT_HINT, SCENE_STRICT_HINT)) from exc
        return p

    def check_initial(self, given: Mapping[str, Any], parameters: Mapping[str, Any]) -> dict[str, Any]:
        """``omega`` (3 finite numbers, rad/s) and the Euler angles φ, θ, ψ (default 0)."""
        check_keys(given, "initial", tuple(k.name for k in _INITIAL), ("omega",), "initial value for system 'free_top'")
        state: dict[str, Any] = {"omega": number_list("[initial].omega", given["omega"], 3,
                                                      "a list of 3 finite numbers [w1, w2, w3] (rad/s)")}
        state.update({k: number(at("initial", k), given.get(k, 0.0)) for k in _ANGLES})
        return state

    def waived(self, parameters: Mapping[str, Any]) -> list[str]:
        from ...inertia.validate import rigid_body_violations

        with np.errstate(all="ignore"):
            return rigid_body_violations(parameters["I1"], parameters["I2"], parameters["I3"])

    def scale(self, scene: "Scene") -> "Scaled":
        from ..scaling import check_outputs

        scaled = _units(scene)
        if not scaled.identity:
            work = scaled.scene
            I, w = np.array([work.parameters[k] for k in _MOMENTS]), np.array(work.initial["omega"])
            check_outputs(scaled, {"energy": 0.5 * float(np.dot(I, w * w)), "L_norm": float(np.linalg.norm(I * w))})
        return scaled

    def summarize(self, scene: "Scene", solved: Solved, t: np.ndarray,
                  names: tuple[str, ...]) -> dict[str, tuple[Any, Any]]:
        """Polhode period, flip interval, precession rates, stability per axis, T and |L| (:mod:`.summary`)."""
        from .summary import summarize

        return summarize(scene, solved, t, names)

    def summarize_batch(self, parameters: Mapping[str, np.ndarray], initial: Mapping[str, np.ndarray],
                        names: tuple[str, ...], *, strict: bool = True, scene: Any = None) -> BatchSummary:
        """N motions at once, vectorised in NumPy/SciPy (:mod:`.batch`); ill-conditioned points fall back."""
        from .batch import summarize_batch

        return summarize_batch(parameters, initial, names, strict=strict)

    def period(self, scene: "Scene") -> float | None:
        """The polhode period (s), for ``[time] samples_per_period``; None for a steady or separatrix motion."""
        from .summary import period

        return period(scene)

    def solve(self, scene: "Scene", method: str, t: np.ndarray) -> Solved:
        return _exact(scene, t) if method == "exact" else _integrate(scene, t)

    def drift(self, scene: "Scene", solved: Solved, t: np.ndarray) -> dict[str, "Drift"]:
        """E = T against T and |L| against |L| (both ≥ 0, zero only at rest), closed form or integrated ω."""
        from ...core.drift import drift

        solution = solved.solution
        moments, _, _ = _setup(scene)
        w = solution.omega(t) if callable(getattr(solution, "omega", None)) else solution.omega
        E, L2 = _invariants()(*moments, *np.asarray(w).T)
        E, L = np.asarray(E, float), np.sqrt(np.asarray(L2, float))
        with np.errstate(invalid="ignore"):
            return {"energy": drift(E, float(np.nanmax(E)), "max_t T"),
                    "L_norm": drift(L, float(np.nanmax(L)), "max_t |L|")}

    def derivations(self) -> tuple:
        from .derive_entries import derivations

        return derivations()

    def check_system(self) -> Any:
        from .derive_entries import check_system

        return check_system()

    def first_order_model(self) -> tuple:
        """(Euler's equations (3.33) ω̇ = f(ω), (ω1, ω2, ω3), (I1, I2, I3)) for the generic linearization
        (the stability coefficient A (3.44)-(3.45) about a steady rotation)."""
        from . import model as fm

        return fm.model().free_rhs, fm.omega_symbols(), (fm.I1, fm.I2, fm.I3)

    def plot(self, result: Any, figure: Any) -> bool:
        """Left, the polhode (3.4.4): ω(t) on the inertia ellipsoid I1 ω1² + I2 ω2² + I3 ω3² = 2T (3.46),
        drawn as a wireframe with semi-axes √(2T / I_a), T the mean over the samples (constant for the
        exact motion); right, ω1, ω2, ω3 against t."""
        from ..figures import sphere_grid

        moments = _moments_for_plot(result)
        d = result.columns
        figure.set_size_inches(11.5, 5.0)
        w = np.stack([d["omega1"], d["omega2"], d["omega3"]])
        two_t = float(np.nanmean(np.einsum("a,a...->...", np.array(moments), w * w)))
        ax = figure.add_subplot(1, 2, 1, projection="3d")
        if two_t > 0:
            axes = [math.sqrt(two_t / m) for m in moments]
            ax.plot_wireframe(*sphere_grid(*axes), color="0.55", linewidth=0.35, alpha=0.45)
            ax.set_box_aspect(axes)
        ax.locator_params(nbins=5)
        ax.plot(w[0], w[1], w[2], color="C0", linewidth=1.2)
        ax.set_xlabel("ω1 (rad/s)")
        ax.set_ylabel("ω2 (rad/s)")
        ax.set_zlabel("ω3 (rad/s)")
        ax.set_title("polhode on the inertia ellipsoid")
        right = figure.add_subplot(1, 2, 2)
        for a in range(3):
            right.plot(result.t, w[a], label=f"ω{a + 1}")
        right.set_xlabel("t (s)")
        right.set_ylabel("ω (rad/s, body frame)")
        right.set_title("angular velocity")
        right.legend(fontsize="small")
        right.grid(True, alpha=0.3)
        return True

    def motion_geometry(self, result: Any) -> Any:
        """The box with these principal moments (:func:`..figures.box_half_lengths`), ω and L (fixed), the
        herpolhode in space and the polhode in the body."""
        from ..figures import body_geometry, box_half_lengths

        moments = _moments_for_plot(result)
        return body_geometry(result.t, result.columns, moments, shape="box", size=box_half_lengths(*moments),
                             with_polhode=True)

    def example_scene(self) -> str:
        return _TUMBLING

    def builtin_scenes(self) -> tuple[tuple[str, str, str], ...]:
        return _SCENES


SYSTEM = FreeTop()
