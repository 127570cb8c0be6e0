"""``system = "rigid_body"``: any rigid body about a fixed point (or free) in uniform gravity (sections 3.3-3.6).

Scene::

    system = "rigid_body"
    method = "auto"                  # closed form where one applies, else integration
    [parameters]
    I1 = 1.0                         # principal moments about the fixed point (kg m²), any order
    I2 = 2.0
    I3 = 3.0
    M = 1.0                          # mass (kg), default 0
    g = 9.81                         # gravity along -z (m/s²), default 9.81
    center_of_mass = [0.1, 0.0, 0.5] # body components of the centre of mass from the fixed point (m), default 0
    [initial]
    phi = 0.0                        # attitude: the chapter's Euler angles (3.54), default 0; θ in [0, π]
    theta = 0.3
    psi = 0.0
    omega = [0.0, 0.0, 20.0]         # body components of ω (rad/s)
    [torque]                         # optional: body components, formulas (see :mod:`.torque`)
    components = ["0", "0", "0.1"]

The equations are derived in :mod:`.model` (Euler's equations with the gravity torque of
V = M g ẑ·(Rᵀ c), the energy, the vertical angular momentum, the axial momenta); solved in
:mod:`.motion`.  ``method = "auto"`` uses the free top's closed form where gravity exerts no torque
(c = 0, M = 0 or g = 0) and the heavy symmetric top's where I1 = I2 with c = (0, 0, l), l > 0;
otherwise it integrates, and the report says which and why (``details.solver``, and the note).

Physical bodies only, unless ``strict = false``: positive principal moments about the fixed point
obeying the triangle inequalities, and the inertia tensor about the centre of mass,
I_cm = diag(I) - M (|c|² 1 - c cᵀ) (parallel axes, 3.23), a physical tensor too
(:mod:`mechderive.inertia.validate`).
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from ...errors import InvalidInputError
from ..summaries import PERIOD, invariant_quantities
from ..base import Derivation, Key, OutOfReach, Quantity, Solved, System

__all__ = ["RigidBody", "SYSTEM", "rigid_body"]

_R_NAMES = tuple(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))

_QUANTITIES = (
    *(Quantity(f"omega{a}", "rad/s", f"body component {a} of the angular velocity", "rate") for a in (1, 2, 3)),
    *(Quantity(f"L{a}", "kg m^2/s", f"body component {a} of the angular momentum about the fixed point (3.28)")
      for a in (1, 2, 3)),
    *(Quantity(n, "1", f"entry {n[1]}{n[2]} of R (3.54): e_a = R_ab ẽ_b") for n in _R_NAMES),
    *(Quantity(f"q{k}", "1", f"component {k} of the unit quaternion of Rᵀ (scalar first)") for k in range(4)),
    *(Quantity(f"apex_{x}", "1", f"space {x} component of the body's third axis e3") for x in "xyz"),
    Quantity("phi", "rad", "Euler angle φ (3.54), continuous", "angle"),
    Quantity("theta", "rad", "Euler angle θ (3.54), in [0, π]", "angle"),
    Quantity("psi", "rad", "Euler angle ψ (3.54), continuous", "angle"),
    Quantity("energy", "J", "E = T + V, V = M g ẑ·(Rᵀ c)"),
    Quantity("L_vertical", "kg m^2/s", "angular momentum about the space vertical, L·ẽ3 (3.64)"),
    Quantity("p_psi", "kg m^2/s", "p_ψ = I3 ω3 (3.63): conserved for I1 = I2 with c on axis 3"),
)

_PARAMETERS = (
    Key("I1", "kg m^2", "principal moment about the fixed point, axis e1", scales_as="moment"),
    Key("I2", "kg m^2", "principal moment about the fixed point, axis e2", scales_as="moment"),
    Key("I3", "kg m^2", "principal moment about the fixed point, axis e3", scales_as="moment"),
    Key("M", "kg", "mass", required=False, default=0.0),
    Key("g", "m/s^2", "gravity, along -ẑ (≥ 0)", required=False, default=9.81),
    Key("center_of_mass", "m", "body components (c1, c2, c3) of the centre of mass from the fixed point",
        required=False, size=3, default=(0.0, 0.0, 0.0)),
)

_INITIAL = (
    Key("phi", "rad", "Euler angle φ at t = 0 (3.54)", required=False, default=0.0, scales_as="angle"),
    Key("theta", "rad", "Euler angle θ at t = 0, in [0, π]", required=False, default=0.0, scales_as="angle"),
    Key("psi", "rad", "Euler angle ψ at t = 0", required=False, default=0.0, scales_as="angle"),
    Key("omega", "rad/s", "body components (ω1, ω2, ω3) of the angular velocity at t = 0", size=3,
        scales_as="rate"),
)

EXAMPLE = '''# An asymmetric heavy top on a pivot (the issue's example with I = (2, 3, 4): its I = (1, 2, 3) about the
# pivot is a flat plate there, whose centre of mass cannot be 0.5 off its plane)
system = "rigid_body"
method = "auto"
rtol = 1e-10

[parameters]
I1 = 2.0
I2 = 3.0
I3 = 4.0
M = 1.0
g = 9.81
center_of_mass = [0.1, 0.0, 0.5]

[initial]
phi = 0.0
theta = 0.3
psi = 0.0
omega = [0.0, 0.0, 20.0]

[time]
t_end = 20.0
samples = 2001

[output]
quantities = ["omega1", "omega2", "omega3", "R11", "R33", "apex_x", "apex_y", "apex_z", "energy", "L_vertical"]
'''


def _where(table: str, key: str, scene: bool) -> str:
    return f"scene key [{table}].{key}: " if scene else f"{key}: "


def _number(value: Any, where: str, expected: str = "a finite number", valid: Any = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidInputError(f"{where}expected {expected}, got {type(value).__name__} {value!r:.60}")
    x = float(value)
    if not math.isfinite(x) or (valid is not None and not valid(x)):
        raise InvalidInputError(f"{where}expected {expected}, got {value!r}")
    return x


def _vector(value: Any, where: str, what: str) -> tuple[float, float, float]:
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise InvalidInputError(f"{where}expected a list of 3 finite numbers {what}, got {value!r:.80}")
    return tuple(_number(v, where[:-2] + f"[{i}]: " if where else "", "a finite number")  # type: ignore[return-value]
                 for i, v in enumerate(value))


def _cm_tensor(I: Sequence[float], M: float, c: Sequence[float]) -> np.ndarray:
    """I_cm = diag(I) - M (|c|² 1 - c cᵀ): the parallel-axis theorem (3.23) from the fixed point to the centre of mass."""
    c = np.asarray(c, dtype=float)
    return np.diag(np.asarray(I, dtype=float)) - M * (np.dot(c, c) * np.eye(3) - np.outer(c, c))


def _check_keys(given: Mapping[str, Any], keys: tuple[Key, ...], table: str, scene: bool) -> None:
    names = [k.name for k in keys]
    for k in given:
        if k not in names:
            raise InvalidInputError(f"{_where(table, str(k), scene)}unknown key; expected {', '.join(names)}")
    for k in keys:
        if k.required and k.name not in given:
            raise InvalidInputError(f"{_where(table, k.name, scene)}missing; system 'rigid_body' needs "
                                    + ", ".join(x.name for x in keys if x.required))


def check_body(given: Mapping[str, Any], *, strict: bool = True, scene: bool = True) -> dict[str, Any]:
    """The ``[parameters]`` values checked, with defaults; raises naming the key, what is allowed and what it got."""
    _check_keys(given, _PARAMETERS, "parameters", scene)
    p: dict[str, Any] = {}
    for a in ("I1", "I2", "I3"):
        p[a] = _number(given[a], _where("parameters", a, scene), "a finite number > 0 (kg m²)", lambda x: x > 0)
    p["M"] = _number(given.get("M", 0.0), _where("parameters", "M", scene), "a finite number ≥ 0 (kg)",
                     lambda x: x >= 0)
    p["g"] = _number(given.get("g", 9.81), _where("parameters", "g", scene),
                     "a finite number ≥ 0 (m/s², gravity along -z)", lambda x: x >= 0)
    p["center_of_mass"] = _vector(given.get("center_of_mass", (0.0, 0.0, 0.0)),
                                  _where("parameters", "center_of_mass", scene), "[c1, c2, c3] (m, body components)")
    from ...inertia.validate import STRICT_HINT, check_inertia_tensor, check_principal_moments

    hint = "; scene: strict = false accepts it" if scene else ""
    where = "scene keys [parameters].I1, [parameters].I2, [parameters].I3: " if scene else ""
    try:
        check_principal_moments(p["I1"], p["I2"], p["I3"], strict=strict)
    except InvalidInputError as exc:
        raise type(exc)(where + str(exc).replace(STRICT_HINT, STRICT_HINT + hint)) from exc
    if strict:
        cm = _cm_tensor((p["I1"], p["I2"], p["I3"]), p["M"], p["center_of_mass"])
        try:
            check_inertia_tensor(cm, strict=None)
        except InvalidInputError as exc:
            where_cm = ("scene keys [parameters].I1, [parameters].I2, [parameters].I3, [parameters].M, "
                        "[parameters].center_of_mass: " if scene else "")
            moments = ", ".join(f"{x:.6g}" for x in np.linalg.eigvalsh(cm))
            raise type(exc)(f"{where_cm}expected the moments about the centre of mass, those of "
                            f"I_cm = diag(I) - M (|c|² 1 - c cᵀ) (parallel axes, 3.23), to be a real body's, got "
                            f"({moments}): {exc}; {STRICT_HINT}") from exc
    return p


def body_violations(p: Mapping[str, Any]) -> list[str]:
    """What a ``strict = false`` body breaks: the triangle inequalities about the fixed point, and the
    positivity and triangle inequalities of the moments about the centre of mass."""
    from ...inertia.validate import rigid_body_violations

    out = rigid_body_violations(p["I1"], p["I2"], p["I3"])
    cm = np.linalg.eigvalsh(_cm_tensor((p["I1"], p["I2"], p["I3"]), p["M"], p["center_of_mass"]))
    if np.any(cm <= 0):
        out.append(f"expected principal moments about the centre of mass > 0, got {', '.join(f'{x:.6g}' for x in cm)}")
    else:
        out += [f"about the centre of mass: {v}" for v in rigid_body_violations(*cm)]
    return out


def check_attitude(given: Mapping[str, Any], *, scene: bool = True) -> dict[str, Any]:
    """The ``[initial]`` values checked, with the angles' defaults (0)."""
    _check_keys(given, _INITIAL, "initial", scene)
    s = {k: _number(given.get(k, 0.0), _where("initial", k, scene)) for k in ("phi", "psi")}
    s["theta"] = _number(given.get("theta", 0.0), _where("initial", "theta", scene), "a number in [0, π]",
                         lambda x: 0.0 <= x <= math.pi)
    s["omega"] = _vector(given["omega"], _where("initial", "omega", scene), "[w1, w2, w3] (rad/s, body components)")
    return {k: s[k] for k in ("phi", "theta", "psi", "omega")}


_SUMMARIES = (PERIOD,) + invariant_quantities({
    "energy": ("J", "energy E = T + V, conserved without an applied torque", "energy"),
    "L_vertical": ("kg m^2/s", "angular momentum about the vertical ẽ3, conserved", "angular momentum"),
    "p_psi": ("kg m^2/s", "I3 ω3, conserved where the body is symmetric about e3 with c on it", "angular momentum"),
})


class RigidBody(System):
    """A rigid body about a fixed point in uniform gravity, with an optional applied torque (``[torque]``)."""

    name = "rigid_body"
    summary = "any rigid body about a fixed point (or free) in uniform gravity, with an optional applied torque"
    section = "3.3-3.6"
    extra_keys = ("torque",)
    parameters = _PARAMETERS
    initial = _INITIAL
    quantities = _QUANTITIES
    animation_quantities = ("omega1", "omega2", "omega3",
                            "R11", "R12", "R13", "R21", "R22", "R23", "R31", "R32", "R33")
    summaries = _SUMMARIES
    methods: tuple[str, ...] = ("exact", "integrate")
    #: a sweep's points per chunk: each integrated point is milliseconds of C (:mod:`.batch`)
    batch_chunk = 100
    bytes_per_sample = 1200

    def __init__(self, torque: Any = None) -> None:
        self.torque = torque
        if torque is not None:
            self.methods = ("integrate",)

    # --- the scene schema -------------------------------------------------------------------------

    def configure(self, definition: Mapping[str, Any]) -> "RigidBody":
        """The body of a scene: with the ``[torque]`` table given, a body with that applied torque."""
        unknown = [k for k in definition if k != "torque"]
        if unknown:
            raise InvalidInputError(f"scene key {unknown[0]}: unknown key for system 'rigid_body'; expected [torque]")
        from .torque import check_torque

        torque = check_torque(definition.get("torque"))
        if torque is None:
            return self if self.torque is None else RigidBody()
        return self if torque == self.torque else RigidBody(torque)

    def check_parameters(self, given: Mapping[str, Any], *, strict: bool = True) -> dict[str, Any]:
        return check_body(given, strict=strict)

    def check_initial(self, given: Mapping[str, Any], parameters: Mapping[str, Any]) -> dict[str, Any]:
        return check_attitude(given)

    def waived(self, parameters: Mapping[str, Any]) -> list[str]:
        return body_violations(parameters)

    # --- solving --------------------------------------------------------------------------------

    def body(self, parameters: Mapping[str, Any]) -> Any:
        """The :class:`.motion.Body` of checked ``parameters``."""
        from .motion import Body

        return Body(I=(parameters["I1"], parameters["I2"], parameters["I3"]), M=parameters["M"], g=parameters["g"],
                    c=tuple(parameters["center_of_mass"]), torque=self.torque)

    def solve(self, scene: Any, method: str, t: np.ndarray) -> Solved:
        """``method``: "exact" (the closed form of :func:`.motion.closed_form_plan`, else :class:`OutOfReach`)
        or "integrate"; only what the quantities need is evaluated (ω and R always, for the drift check)."""
        from . import motion as mo

        body = self.body(scene.parameters)
        names = tuple(scene.quantities)
        if "p_psi" in names and not mo.conserved_axial(body)[2]:
            raise InvalidInputError(
                "scene key [output].quantities: expected p_psi only for a body symmetric about e3 with its centre "
                "of mass on it (I1 = I2, c1 = c2 = 0) and no applied torque, where the derivation finds I3 ω3 "
                "conserved; got I = ({:g}, {:g}, {:g}), c = ({:g}, {:g}, {:g}); ask for L3 = I3 ω3".format(
                    *body.I, *body.c))
        need = mo.families(names)
        if method == "exact":
            which, why = mo.closed_form_plan(body, scene.initial)
            solver = mo.free_closed_form if which == "free" else mo.heavy_closed_form
            motion = solver(body, scene.initial, t, need, scene.strict)
            motion.info = {"solver": why, **motion.info}
        elif method == "integrate":
            motion = mo.integrate_body(body, scene.initial, t, scene.rtol,
                                       need=tuple(k for k in need if k != "quaternion"))
            motion.info["why"] = self._why_integrated(scene, body)
        else:
            raise InvalidInputError(f"expected method one of {', '.join(map(repr, self.methods))}, got {method!r}")
        return self.solved(names, motion, body)

    @staticmethod
    def solved(names: tuple[str, ...], motion: Any, body: Any) -> Solved:
        """The :class:`Solved` of a solved ``motion``: the columns ``names`` and the estimate of their families."""
        from . import motion as mo

        need = mo.families(names)
        est = max((motion.estimates[k] for k in need if k in motion.estimates), default=0.0)
        info = {"error_estimate": float(est), **motion.info}
        return Solved(mo.columns(names, motion, body), info, motion)

    def summarize_batch(self, parameters: Mapping[str, np.ndarray], initial: Mapping[str, np.ndarray],
                        names: tuple[str, ...], *, strict: bool = True, scene: Any = None) -> Any:
        """The summaries of a sweep's points that integrate (:mod:`.batch`); None without the sweep's scene."""
        from .batch import summarize_batch

        return None if scene is None else summarize_batch(self, scene, parameters, initial, names)

    @staticmethod
    def _why_integrated(scene: Any, body: Any) -> str:
        from .motion import closed_form_plan

        if scene.method == "integrate":
            return "method = 'integrate'"
        try:
            closed_form_plan(body, scene.initial)
        except OutOfReach as exc:
            return f"no closed form applies: {exc}"
        return "the closed form could not follow this motion (see the note)"

    def summarize(self, scene: Any, solved: Solved, t: np.ndarray, names: tuple[str, ...]) -> dict:
        """``period`` of the reduced motion (ω and the vertical's body components R_a3; for a body symmetric
        about e3 with c on it, cos θ, ω1² + ω2² and ω3), measured on the solution (a symmetric top's is its
        nutation period; an asymmetric heavy body's motion is in general not periodic, and says so);
        E, L·ẽ3 and p_ψ where conserved: their values at t = 0 and their variation along the run."""
        from ..summaries import invariants_of, period_of

        out = invariants_of(self.drift(scene, solved, t), tuple(n for n in names if n != "period"),
                            "nothing is with an applied torque; p_ψ = I3 ω3 only for a body symmetric about e3 "
                            "(I1 = I2) with its centre of mass on that axis")
        if "period" in names:
            from .motion import conserved_axial

            motion = solved.solution
            w, gamma = motion.omega, motion.R[:, :, 2]  # body components of ω and of the vertical ẽ3
            if conserved_axial(self.body(scene.parameters))[2]:
                # symmetric about e3: ψ is cyclic too; (cos θ, ω1² + ω2², ω3) do not see it
                state = np.stack([gamma[:, 2], w[:, 0] ** 2 + w[:, 1] ** 2, w[:, 2]], axis=1)
            else:
                state = np.concatenate([w, gamma], axis=1)
            out["period"] = period_of(np.asarray(motion.t), state)
        return {name: out[name] for name in names}

    def drift(self, scene: Any, solved: Solved, t: np.ndarray) -> dict:
        from .motion import drifts

        return drifts(self.body(scene.parameters), solved.solution)

    # --- derive, check -------------------------------------------------------------------------

    def parameter_values(self, parameters: Mapping[str, Any]) -> dict[str, float]:
        """I1 I2 I3 M g, and c1 c2 c3 from ``center_of_mass``."""
        values = super().parameter_values(parameters)
        values.update({f"c{a + 1}": float(x) for a, x in enumerate(parameters.get("center_of_mass", ()))})
        return values

    def first_order_model(self) -> tuple | None:
        """Euler–Poisson equations in (ω, γ), γ = (R13, R23, R33) the body components of the vertical:
        ω̇ from Euler's equations with the gravity torque (which depends on γ only), γ̇ = γ × ω (derived in
        :attr:`~.model.RigidBodyModel.vertical_rate_generic`).  None with an applied torque (it may
        depend on t and the whole of R)."""
        if self.torque is not None:
            return None
        from . import model as rm

        m = rm.model()
        R = rm.rotation_symbols()
        state = (*rm.omega_symbols(), R[0, 2], R[1, 2], R[2, 2])
        free = {tau: 0 for tau in rm.tau_symbols}
        rhs = (*m.euler_rhs_generic.subs(free), *m.vertical_rate_generic)
        return rhs, state, rm.parameters()

    def check_system(self) -> Any:
        """The symbols of ``mechderive check``: ω1..3 and R13, R23, R33 (the state of the Euler–Poisson
        equations, :meth:`first_order_model`), their rates on a motion, the parameters, ``energy`` and
        ``L_vertical``; None with an applied torque."""
        model = self.first_order_model()
        if model is None:
            return None
        import sympy as sp

        from ...core import check_system as cs
        from ...core.symbols import state_symbol
        from . import model as rm

        rhs, state, params = model
        names = tuple(x.name for x in state)
        meaning = {"omega1": "body component ω1 of the angular velocity", "omega2": "ω2", "omega3": "ω3",
                   "R13": "R13 = e1·ẽ3, body component of the upward vertical", "R23": "R23 = e2·ẽ3",
                   "R33": "R33 = e3·ẽ3 = cos θ"}
        qs = [cs.Quantity(n, x, "state", meaning[n]) for n, x in zip(names, state)]
        qs += [cs.Quantity(n + "_dot", state_symbol(n + "_dot"), "derivative", f"rate of {n} (fixed on a motion)")
               for n in names]
        qs += [cs.Quantity(p.name, p, "parameter", "a parameter of the body") for p in params]
        qs += [cs.Quantity("energy", sp.Symbol("energy", real=True), "defined", "E = ½ Σ I_a ω_a² + M g Σ c_a R_a3",
                           lambda s: rm.model().energy_generic),
               cs.Quantity("L_vertical", sp.Symbol("L_vertical", real=True), "defined", "L·ẽ3 = Σ I_a ω_a R_a3",
                           lambda s: rm.model().vertical_momentum_generic)]
        return cs.System(name=self.name, summary=self.summary, coordinates=names, order=1,
                         highest=lambda: {state_symbol(n + "_dot"): r for n, r in zip(names, rhs)},
                         quantities=qs, domain={}, motion="Euler's equations with the gravity torque, γ̇ = γ × ω")

    def derivations(self) -> tuple[Derivation, ...]:
        """Euler's equations with the gravity torque (and the applied one), V, τ_gravity, E and L·ẽ3."""
        torque = self.torque

        def euler(_options: Any) -> Any:
            from . import model as rm

            eqs = rm.model().euler_equations_generic
            applied = torque.expressions() if torque is not None else [0, 0, 0]
            return eqs.subs(dict(zip(rm.tau_symbols, applied)), simultaneous=True)

        def get(attr: str) -> Any:
            def build(_options: Any) -> Any:
                from . import model as rm

                return getattr(rm.model(), attr)
            return build

        return (
            Derivation("euler_equations", "Euler's equations with the gravity torque, I_a ω̇_a - (I_b - I_c) ω_b ω_c "
                       "- τ_a = 0 (R generic: rows = body axes)", "(3.33)", euler),
            Derivation("potential", "V = M g ẑ·(Rᵀ c): the height of the centre of mass", "", get("potential_generic")),
            Derivation("gravity_torque", "τ = -∂V/∂α under R → (1 + hat(δα)) R, checked against c × F", "",
                       get("torque_generic")),
            Derivation("energy", "E = T + V, conserved without an applied torque", "(3.65)", get("energy_generic")),
            Derivation("L_vertical", "L·ẽ3 = Σ I_a ω_a R_a3, conserved without an applied torque", "(3.64)",
                       get("vertical_momentum_generic")),
            Derivation("axial_momentum_rates", "d(I_a ω_a)/dt along the equations: p_ψ = I3 ω3 is conserved where "
                       "the third vanishes (I1 = I2, c1 = c2 = 0)", "(3.63)", get("axial_momentum_rates")),
        )

    def motion_geometry(self, result: Any) -> Any:
        """The box with the body's principal moments about the fixed point, its e3 trace, ω and L."""
        from ..figures import body_geometry, box_half_lengths

        p = result.scene.parameters
        moments = (p["I1"], p["I2"], p["I3"])
        return body_geometry(result.t, result.columns, moments, shape="box", size=box_half_lengths(*moments),
                             traces_from_apex=True)

    def example_scene(self) -> str:
        return EXAMPLE


SYSTEM = RigidBody()


class ConfiguredRigidBody(RigidBody):
    """A :class:`RigidBody` with its parameter values given in Python (:func:`rigid_body`): they become the
    defaults of ``[parameters]``, so a scene of it needs only ``[initial]``, ``[time]`` and ``[output]``."""

    def __init__(self, values: dict[str, Any], torque: Any = None) -> None:
        super().__init__(torque)
        self.values = values
        self.parameters = tuple(Key(k.name, k.unit, k.meaning, required=False, size=k.size, default=values[k.name],
                                    scales_as=k.scales_as) for k in _PARAMETERS)

    def check_parameters(self, given: Mapping[str, Any], *, strict: bool = True) -> dict[str, Any]:
        return check_body({**self.values, **given}, strict=strict)

    def scene_mapping(self, initial: Mapping[str, Any], *, t_end: float, samples: int, quantities: Sequence[str],
                      rtol: float = 1e-10, method: str = "auto", strict: bool = True) -> dict:
        """This body as a scene (the mapping :func:`mechderive.scenes.schema.parse_scene` reads)."""
        scene: dict[str, Any] = {"system": "rigid_body", "method": method, "rtol": rtol, "strict": strict,
                                 "parameters": {k: (list(v) if isinstance(v, tuple) else v)
                                                for k, v in self.values.items()},
                                 "initial": dict(initial), "time": {"t_end": t_end, "samples": samples},
                                 "output": {"quantities": list(quantities)}}
        if self.torque is not None:
            scene["torque"] = {"components": list(self.torque.components)}
        return scene


def rigid_body(I1: float, I2: float, I3: float, M: float = 0.0, g: float = 9.81,
               center_of_mass: Sequence[float] = (0.0, 0.0, 0.0), torque: Sequence[str] | None = None, *,
               strict: bool = True) -> ConfiguredRigidBody:
    """A rigid body about a fixed point in uniform gravity (-g ẑ), as a configured :class:`RigidBody`.

    ``I1 I2 I3``: principal moments about the fixed point (kg m²); ``M`` (kg); ``g`` (m/s², ≥ 0);
    ``center_of_mass``: its body components from the fixed point (m); ``torque``: three formula
    strings, the body components of an applied torque (see :mod:`.torque`); ``strict=False``
    accepts moments no rigid body has.  Checked at once (same rules and messages as a scene's).

    >>> top = rigid_body(2.0, 3.0, 4.0, M=1.0, center_of_mass=(0.1, 0.0, 0.5))
    >>> top.methods, top.values["g"]
    (('exact', 'integrate'), 9.81)
    >>> sorted(top.scene_mapping({"omega": [0, 0, 20]}, t_end=1.0, samples=11, quantities=["omega1"]))[:3]
    ['initial', 'method', 'output']
    """
    from .torque import check_torque

    values = check_body(dict(I1=I1, I2=I2, I3=I3, M=M, g=g, center_of_mass=tuple(center_of_mass)), strict=strict,
                        scene=False)
    checked = check_torque(None if torque is None else {"components": list(torque)})
    return ConfiguredRigidBody(values, checked)
