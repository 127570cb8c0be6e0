"""``derive``: a system's quantities as SymPy objects, with a shape, numbers or another Euler sequence.

>>> out = derive("heavy_top", ["p_psi"])
>>> out["p_psi"]                                   # (3.63)
I3*(phi_dot*cos(theta) + psi_dot)
>>> derive("heavy_top", ["p_psi"], shape="solid_cone")["p_psi"]      # a uniform cone about its apex
3*M*R**2*(phi_dot*cos(theta) + psi_dot)/10
>>> derive("rotation", sequence="XYZ", frame="space")["R"][0, 2]
-sin(theta)
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Iterable, Mapping, Sequence

import sympy as sp

from ..errors import InvalidInputError
from .catalog import ZERO, System, system
from .options import API_LABELS, Options

__all__ = ["Derived", "derive", "derive_entries"]


@dataclass(frozen=True)
class Derived:
    """One derived quantity: its name, description, equation number, left-hand side and value."""

    name: str
    description: str
    equation: str
    lhs: Any
    value: Any
    sequence: str = "ZXZ"   #: the Euler sequence the value is expressed in
    frame: str = "body"     #: its body-fixed or space-fixed axes

    @property
    def is_zero_form(self) -> bool:
        """Whether it prints as "value = 0"."""
        return self.lhs is ZERO


def _check_takes(spec: System, options: Options, given: Mapping[str, Any]) -> None:
    if "shape" in spec.takes:
        given = {k: v for k, v in given.items() if k != "pivot"}  # a pivot goes with the shape
    for option, value in given.items():
        if value is not None and option not in spec.takes:
            raise InvalidInputError(f"{options.label(option)}: expected no {option} for {spec.name} (it takes "
                                    f"{', '.join(sorted(spec.takes))}), got {_short(repr(value))}")
    if "sequence" not in spec.takes and not options.is_default_sequence:
        raise InvalidInputError(f"expected the chapter's ZXZ body-fixed angles for {spec.name} (its model is "
                                f"derived in them), got {options.sequence} {options.frame}-fixed")
    if spec.requires_shape and options.shape is None:
        from ..inertia.bodies import BODIES

        raise InvalidInputError(f"expected a shape for {spec.name}, one of {', '.join(BODIES)}, got none")


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


# The values below are the catalog's derived SymPy objects (never text): sympify only wraps them.
def _apply(value: Any, subs: dict) -> Any:
    if not subs:
        return value
    if isinstance(value, sp.MatrixBase):
        return value.applyfunc(lambda e: sp.sympify(e, strict=True).subs(subs, simultaneous=True))
    return sp.sympify(value, strict=True).subs(subs, simultaneous=True)


def _simplified(value: Any) -> Any:
    if isinstance(value, sp.MatrixBase):
        return value.applyfunc(sp.simplify)
    return sp.simplify(value)


def _free_symbols(value: Any) -> set[sp.Symbol]:
    return set(value.free_symbols if isinstance(value, sp.MatrixBase) else sp.sympify(value, strict=True).free_symbols)


def _free_names(value: Any) -> set[str]:
    return {s.name for s in _free_symbols(value)}


def derive_entries(system_name: Any, quantities: Iterable[str] | None = None, *, sequence: str = "ZXZ",
                   frame: str | None = None, shape: str | None = None, pivot: Any = None,
                   moments: Sequence[Any] | None = None, values: Mapping[Any, Any] | None = None,
                   simplify: bool = False, labels: Mapping[str, str] | None = None,
                   scene_parameters: bool | Mapping[str, Any] = False) -> list[Derived]:
    """The :class:`Derived` records of :func:`derive` (with description, equation number, left-hand side).

    ``labels``: how errors name the options (:data:`.options.API_LABELS` by default; the command
    line passes :data:`.options.CLI_LABELS`).
    """
    spec = system(system_name)
    scene_values = _scene_values(system_name, scene_parameters)
    if values is not None and not isinstance(values, Mapping):
        raise InvalidInputError(f"values: expected a mapping name -> number, got {type(values).__name__}")
    options = Options(sequence=sequence, frame=frame, shape=shape, pivot=pivot, moments=moments,
                      values=dict(values or {}), simplify=simplify, labels=labels or API_LABELS)
    _check_takes(spec, options, {"shape": shape, "moments": moments, "pivot": pivot})
    names = list(spec.defaults) if quantities is None else list(quantities)
    if isinstance(quantities, str):
        names = [quantities]
    if not names:
        raise InvalidInputError(f"expected at least one quantity of {spec.name}, got none")
    unknown = [q for q in names if q not in spec.quantities]
    if unknown:
        raise InvalidInputError(f"expected quantities of {spec.name} among {', '.join(spec.quantities)}, "
                                f"got {unknown[0]!r}")
    subs = {}
    if spec.parameters is not None:
        subs.update(spec.parameters(options))
    out = []
    for q in dict.fromkeys(names):
        qs = spec.quantities[q]
        value = _apply(qs.build(options), subs)
        lhs = qs.lhs if qs.lhs is ZERO else qs.lhs()
        out.append(Derived(q, qs.description, qs.equation, lhs, value, options.sequence, options.frame))
    if options.values:
        present = set().union(*(_free_names(d.value) for d in out))
        missing = sorted(set(options.values) - present)
        if missing:
            raise InvalidInputError(f"{options.label('values', missing[0])}: expected values for symbols among "
                                    f"{', '.join(sorted(present)) or 'none'}, got {missing[0]!r}")
        out = [replace(d, value=_apply(d.value, {s: options.values[s.name] for s in _free_symbols(d.value)
                                                 if s.name in options.values}))
               for d in out]
    if scene_values:
        out = [replace(d, value=_apply(d.value, {s: scene_values[s.name] for s in _free_symbols(d.value)
                                                 if s.name in scene_values}))
               for d in out]
    if simplify:
        out = [replace(d, value=_simplified(d.value)) for d in out]
    return out


def _scene_values(system: Any, scene_parameters: bool | Mapping[str, Any]) -> dict[str, Any]:
    """{name: exact number} of a scene's scalar ``[parameters]`` (its lists are left out): those of the
    scene file ``system`` if ``scene_parameters`` is True, or ``scene_parameters`` itself (a mapping)."""
    from ..formulas.systems import find_system, is_scene_path
    from .options import as_number

    if isinstance(scene_parameters, Mapping):
        parameters = scene_parameters
    elif scene_parameters is True:
        if not is_scene_path(system):
            raise InvalidInputError(f"scene_parameters: expected a scene file (a path ending .toml) as the system, "
                                    f"got {_short(repr(system))}")
        _, parameters = find_system(system)
    elif scene_parameters is False:
        return {}
    else:
        raise InvalidInputError(f"scene_parameters: expected True, False or a mapping name -> number, got "
                                f"{_short(repr(scene_parameters))}")
    return {k: as_number(v, f"scene key [parameters].{k}") for k, v in parameters.items()
            if isinstance(k, str) and k.isidentifier() and isinstance(v, (int, float)) and not isinstance(v, bool)}


def derive(system: Any, quantities: Iterable[str] | None = None, *, sequence: str = "ZXZ",
           frame: str | None = None, shape: str | None = None, pivot: Any = None,
           moments: Sequence[Any] | None = None, values: Mapping[Any, Any] | None = None,
           simplify: bool = False, scene_parameters: bool | Mapping[str, Any] = False) -> dict[str, Any]:
    """{quantity: SymPy object} of ``system``, derived by the toolkit (never typed in).

    Parameters
    ----------
    system
        ``free_top``, ``heavy_top``, ``falling_cat``, ``rotation``, ``angular_velocity`` or ``inertia``
        (see :mod:`.catalog`; :func:`~mechderive.derive.catalog.listing` says what each offers),
        any registered system's name, a scene file (a path ending ``.toml``: the system it
        configures) or a :class:`~mechderive.systems.base.System` object.
    quantities
        Names of quantities; by default the Lagrangian, equations of motion and conserved
        quantities (or the system's main objects).
    sequence, frame
        The Euler sequence (one of the twelve; lower case = space-fixed, as in SciPy) and
        ``"body"`` or ``"space"``-fixed axes, for ``rotation``, ``angular_velocity`` and the
        free top's Lagrangian (:mod:`.sequences`).
    shape, pivot, moments, values
        A standard body's derived inertia, numeric moments (I1, I2, I3), or numbers for any
        symbol (:mod:`.options`).
    simplify
        Apply :func:`sympy.simplify` to every value (slow for the falling cat).
    scene_parameters
        True with a scene file: substitute its ``[parameters]`` numbers (exactly, as ``values``
        does) for the symbols of those names left in the results, ``values`` taking precedence;
        or those parameters as a mapping (a scene already read).

    Values are in the state symbols ``phi, theta, psi, phi_dot, …``.
    """
    return {d.name: d.value for d in derive_entries(system, quantities, sequence=sequence, frame=frame, shape=shape,
                                                     pivot=pivot, moments=moments, values=values, simplify=simplify,
                                                     scene_parameters=scene_parameters)}
