"""What ``mechderive derive`` can print: per system, quantity name → (description, equation, derivation).

Every value is taken from the toolkit's own derivations (the models of
:mod:`mechderive.systems`, :mod:`mechderive.kinematics`, :mod:`mechderive.inertia`);
nothing here is a formula typed in.  Values are SymPy objects in the state symbols ``phi,
theta, psi, phi_dot, …`` (never functions of t), so that every format — text, LaTeX, code —
prints the same objects.  Each quantity also names its left-hand side (a SymPy object, or
:data:`ZERO` for "… = 0").

Two kinds of catalogs:

- a *system*'s, from its :meth:`~mechderive.systems.base.System.derivations` (each a
  :class:`~mechderive.systems.base.Derivation`), found through the registry of systems
  (:mod:`mechderive.systems.registry`): ``free_top``, ``heavy_top``, ``falling_cat`` and any
  system registered, or configured by a scene file (a path ending ``.toml``);
- the generic ones kept here: ``rotation``, ``angular_velocity`` (in any Euler sequence) and
  ``inertia`` (of a standard body; needs a shape).

:func:`listing` gives what can be asked of each, with the chapter's equation numbers.

>>> [name for name, _, eq in listing("heavy_top")][:3]
['lagrangian', 'accelerations', 'p_psi']
>>> SYSTEMS["heavy_top"].quantities["p_phi"].equation
'3.64'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Iterator, Mapping

import sympy as sp

from ..core.codegen import ARGUMENTS
from ..core.symbols import state_symbol, to_state_symbols
from ..errors import InvalidInputError
from .options import Options

__all__ = ["ZERO", "Quantity", "System", "SYSTEMS", "ARGUMENTS", "GENERIC", "listing", "system", "from_derivations"]

#: Marks a quantity printed as "value = 0" (no left-hand side).
ZERO = "= 0"

_s = state_symbol


def _symbols(*names: str) -> sp.Matrix:
    return sp.Matrix([_s(n) for n in names])


_RATES = ("phi_dot", "theta_dot", "psi_dot")
_OMEGA = ("omega1", "omega2", "omega3")


@dataclass(frozen=True)
class Quantity:
    """One printable quantity: a one-line description, the chapter's equation number, a derivation."""

    description: str
    equation: str
    build: Callable[[Options], Any]
    lhs: Callable[[], Any] | str


@dataclass(frozen=True)
class System:
    """A catalog: its quantities (in listing order), those printed by default, and the options it takes.

    ``requires_shape``: a shape must be given (``inertia``); a pivot is taken where a shape is.
    """

    name: str
    summary: str
    quantities: dict[str, Quantity]
    defaults: tuple[str, ...]
    takes: frozenset[str]
    parameters: Callable[[Options], dict] | None = None
    requires_shape: bool = False


# ------------------------------------------------------------------------- rotation, angular velocity
def _kin(o: Options):
    from .sequences import sequence_model

    return sequence_model(o.sequence, o.frame)


def _axis(k: int) -> Callable[[Options], Any]:
    def build(o: Options) -> sp.Matrix:
        from ..kinematics.euler import axis_rotation

        return axis_rotation(k, sp.Symbol("alpha", real=True))
    return build


_ROTATION = {
    "R": Quantity("R(φ, θ, ψ), e_a = R_ab ẽ_b, for the chosen sequence", "3.54",
                  lambda o: to_state_symbols(_kin(o).rotation), lambda: sp.Symbol("R")),
    "A": Quantity("the active rotation A = Rᵀ (SciPy's Rotation.from_euler(...).as_matrix())", "3.54",
                  lambda o: to_state_symbols(_kin(o).rotation).T, lambda: sp.Symbol("A")),
    "R1": Quantity("R1(α) = exp(α J1)", "3.52", _axis(1), lambda: sp.Symbol("R_1")),
    "R2": Quantity("R2(α) = exp(α J2)", "3.52", _axis(2), lambda: sp.Symbol("R_2")),
    "R3": Quantity("R3(α) = exp(α J3)", "3.51", _axis(3), lambda: sp.Symbol("R_3")),
}

_ANGULAR = {
    "body": Quantity("body components ω_a of ω = ṘRᵀ", "3.58",
                     lambda o: to_state_symbols(_kin(o).angular_velocity_body), lambda: _symbols(*_OMEGA)),
    "space": Quantity("space components ω̃ = Rᵀω", "3.58",
                      lambda o: to_state_symbols(_kin(o).angular_velocity_space),
                      lambda: sp.Matrix(sp.symbols("omegatilde_1 omegatilde_2 omegatilde_3"))),
    "matrix": Quantity("ω_ac = Ṙ_ab R_cb", "3.5",
                       lambda o: to_state_symbols(_kin(o).angular_velocity_matrix), lambda: sp.Symbol("omega")),
    "convective": Quantity("Ω = R⁻¹Ṙ", "3.10",
                           lambda o: to_state_symbols(_kin(o).convective_angular_velocity_matrix),
                           lambda: sp.Symbol("Omega")),
    "euler_rates": Quantity("(φ̇, θ̇, ψ̇) from the body ω (singular at gimbal lock)", "3.58",
                            lambda o: _kin(o).euler_rates, lambda: _symbols(*_RATES)),
}

# -------------------------------------------------------------------------------------- inertia
def _body(o: Options):
    from ..inertia.bodies import body_inertia_symbolic

    return body_inertia_symbolic(o.shape)


def _about_pivot(o: Options) -> sp.Matrix:
    z = o.pivot_expr()
    return _body(o).inertia_about(sp.Matrix([0, 0, z if z is not None else 0])).applyfunc(sp.factor)


_INERTIA = {
    "centre_of_mass": Quantity("the centre of mass in the body's coordinates", "3.20",
                               lambda o: _body(o).centre_of_mass, lambda: sp.Symbol("r_cm")),
    "inertia_cm": Quantity("I about the centre of mass, by integrating ρ over the body", "3.20",
                           lambda o: _body(o).inertia_cm, lambda: sp.Symbol("I_cm")),
    "inertia_pivot": Quantity("I about the pivot (0, 0, z), by default the frame origin (parallel axes)", "3.25",
                              _about_pivot, lambda: sp.Symbol("I_P")),
    "principal_moments": Quantity("the principal moments (I1, I2, I3) about the centre of mass", "3.21",
                                  lambda o: sp.Matrix([_body(o).inertia_cm[a, a] for a in range(3)]),
                                  lambda: sp.Matrix(sp.symbols("I1 I2 I3"))),
}

_NUMBERS = frozenset({"values"})
#: The generic catalogs (not systems): rotations, angular velocities and inertia of shapes.
GENERIC: dict[str, System] = {
    "rotation": System("rotation", "rotation matrices of Euler angles (section 3.5)", _ROTATION, ("R",),
                       _NUMBERS | {"sequence"}),
    "angular_velocity": System("angular_velocity", "angular velocity in Euler angles (sections 3.1.1, 3.5.2)",
                               _ANGULAR, ("body", "space"), _NUMBERS | {"sequence"}),
    "inertia": System("inertia", "inertia of a standard body SHAPE (section 3.2)", _INERTIA,
                      ("centre_of_mass", "inertia_cm", "inertia_pivot"), _NUMBERS | {"shape"}, requires_shape=True),
}

# What a Derivation's ``options`` may name (a pivot goes with a shape).
_OPTIONS = frozenset({"sequence", "shape", "moments"})


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _merged(substitutes: list[Callable[[Options], Mapping]]) -> Callable[[Options], dict] | None:
    if not substitutes:
        return None

    def parameters(options: Options) -> dict:
        out: dict = {}
        for f in substitutes:
            out.update(f(options))
        return out
    return parameters


def from_derivations(obj: Any) -> System:
    """The catalog of a system object (a :class:`~mechderive.systems.base.System`): its ``derivations()``,
    titled by their ``summary`` (:class:`~mechderive.systems.base.Derivations`) or the system's.

    Raises :class:`InvalidInputError` naming the system where a derivation is malformed (a name
    that is not an identifier or is repeated, an unknown option) or where it has none.
    """
    name = getattr(obj, "name", "?")
    given = obj.derivations() or ()
    derivations = tuple(given)
    if not derivations:
        raise InvalidInputError(f"expected a system with derivations for derive, got {name!r}, which has none")
    quantities: dict[str, Quantity] = {}
    takes, substitutes = set(_NUMBERS), []
    for d in derivations:
        if not isinstance(getattr(d, "name", None), str) or not d.name.isidentifier() or d.name in quantities:
            raise InvalidInputError(f"expected distinct identifiers as the names of {name}'s derivations, got "
                                    f"{getattr(d, 'name', d)!r}")
        unknown = set(d.options) - _OPTIONS
        if unknown:
            raise InvalidInputError(f"expected the options of {name}'s derivation {d.name!r} among "
                                    f"{', '.join(sorted(_OPTIONS))}, got {sorted(unknown)[0]!r}")
        if d.lhs is None:
            lhs = lambda n=d.name: sp.Symbol(n)  # noqa: E731
        elif isinstance(d.lhs, str):
            if d.lhs != ZERO:
                raise InvalidInputError(f"expected the left-hand side of {name}'s derivation {d.name!r} to be a "
                                        f"callable, a SymPy object or {ZERO!r}, got {_short(repr(d.lhs))}")
            lhs = ZERO
        else:
            lhs = d.lhs if callable(d.lhs) and not isinstance(d.lhs, sp.Basic) else (lambda v=d.lhs: v)
        quantities[d.name] = Quantity(d.meaning, d.equation, d.build, lhs)
        takes |= set(d.options)
        if d.substitute is not None and d.substitute not in substitutes:
            substitutes.append(d.substitute)
    defaults = tuple(d.name for d in derivations if d.default) or tuple(quantities)
    summary = getattr(given, "summary", "") or getattr(obj, "summary", "") or ""
    return System(name, summary, quantities, defaults, frozenset(takes), _merged(substitutes))


def _derivable(obj: Any) -> bool:
    return bool(obj.derivations())


def names() -> tuple[str, ...]:
    """What ``derive`` knows by name: the registered systems with derivations, then the generic catalogs."""
    from ..formulas.systems import names as registered

    return registered(_derivable) + tuple(GENERIC)


def system(name: Any) -> System:
    """The catalog of ``name``: a generic catalog, a registered system's name, a scene file (a path
    ending ``.toml``) or a system object; raises listing the systems otherwise."""
    from ..formulas.systems import find_system, is_scene_path

    from ..systems import registry

    if isinstance(name, str) and name in GENERIC:
        return GENERIC[name]
    if isinstance(name, str) and not is_scene_path(name) and name not in registry.names():
        raise InvalidInputError(f"expected a system among {', '.join(names())}, got {name!r}")
    obj, _ = find_system(name)
    return from_derivations(obj)


class _Systems(Mapping):
    """{name: catalog} of every system and generic catalog, looked up through the registry on access
    (an unknown name raises :class:`InvalidInputError` listing the known ones)."""

    def __getitem__(self, name: str) -> System:
        if not isinstance(name, str) or name not in names():
            raise InvalidInputError(f"expected a system among {', '.join(names())}, got {_short(repr(name))}")
        return system(name)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in names()

    def get(self, name: str, default: Any = None) -> Any:
        return self[name] if name in self else default

    def __iter__(self) -> Iterator[str]:
        return iter(names())

    def __len__(self) -> int:
        return len(names())


#: Every catalog by name (the registered systems' through the registry, then the generic ones).
SYSTEMS: Mapping[str, System] = _Systems()


def listing(name: Any) -> list[tuple[str, str, str]]:
    """[(quantity, description, equation number)] of a system, defaults first."""
    return [(q, spec.description, spec.equation) for q, spec in system(name).quantities.items()]
