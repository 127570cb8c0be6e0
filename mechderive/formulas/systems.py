"""Each system's named symbols for ``mechderive check``, found through the registry of systems.

The type is :class:`mechderive.core.check_system.System` (re-exported here with
:class:`Quantity`, :class:`BodyRegion` and :class:`RigidBody`): a system's state, derivatives,
parameters and *derived* definitions, the jet of its state and the flow of its equations of
motion.  Each system builds its own in its ``check_system()`` (the built-in ones in
``mechderive/systems/*/derive_entries.py``); :func:`get_system` asks the registry
(:mod:`mechderive.systems.registry`) and never names a system, so a registered user system is
checked like a built-in one.  :func:`find_system` also takes a scene file (a path ending
``.toml``: the system it configures) or a system object.

>>> heavy = get_system("heavy_top")
>>> heavy.symbol("u_dot") in heavy.names.values()
True
>>> heavy.definition(heavy.symbol("u_dot"))
-theta_dot*sin(theta)
>>> free = get_system("free_top")
>>> sp.expand(free.motion_dt(free.definition(free.symbol("T"))))   # (3.46): T is conserved
0
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import Any, Callable

import sympy as sp

from ..core.check_system import BodyRegion, Quantity, RigidBody, System
from ..errors import InvalidInputError

__all__ = ["Quantity", "BodyRegion", "RigidBody", "System", "get_system", "find_system", "names",
           "SCENE_SUFFIX"]

#: A system argument ending so is a scene file, read for its system (and parameters).
SCENE_SUFFIX = ".toml"

_LOCK = threading.Lock()
# id(system object) -> (the object, kept alive so that the id stays its own; its check system)
_CHECK: dict[int, tuple[Any, System | None]] = {}


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def is_scene_path(value: Any) -> bool:
    """Whether a system argument names a scene file (a ``str`` or path ending ``.toml``)."""
    return isinstance(value, os.PathLike) or (isinstance(value, str) and value.endswith(SCENE_SUFFIX))


def builtin_or_registered(name: str) -> Any:
    """The registered system ``name`` (a :class:`mechderive.systems.base.System`).

    Raises :class:`InvalidInputError` for a name the registry does not know.
    """
    from ..systems import registry

    try:
        return registry.get(name)
    except ModuleNotFoundError as exc:
        fallback = _entries_module(name, exc)
        if fallback is None:
            raise
        return fallback


class _Entries:
    """A built-in system seen through its ``derive_entries`` module alone: used only while the
    registry's module of that system (``systems/<package>/system.py``) is not there yet."""

    def __init__(self, name: str, module: Any) -> None:
        self.name, self._module = name, module
        self.summary = ""

    def derivations(self) -> tuple:
        return self._module.derivations()

    def check_system(self) -> Any:
        return self._module.check_system()


def _entries_module(name: str, exc: ModuleNotFoundError) -> Any:
    import importlib

    from ..systems import registry

    module = registry._BUILTIN.get(name)
    if module is None or exc.name != module:
        return None
    entries = module.rsplit(".", 1)[0] + ".derive_entries"
    try:
        return _Entries(name, importlib.import_module(entries))
    except ModuleNotFoundError:
        return None


def scene_system(path: Any) -> tuple[Any, dict]:
    """(the system a scene file configures, the scene's ``[parameters]``): ``scene.model``, the
    concrete system (a ``rigid_body`` or ``lagrangian`` scene's own), or the registered system."""
    from ..scenes.schema import load_scene

    scene = load_scene(Path(path))
    model = scene.model if scene.model is not None else builtin_or_registered(scene.system)
    return model, dict(scene.parameters)


def find_system(system: Any) -> tuple[Any, dict]:
    """(system object, scene parameters) for a registered name, a scene file or a system object.

    A name is looked up in the registry; a path ending ``.toml`` is read as a scene
    (:func:`scene_system`); a :class:`mechderive.systems.base.System` is taken as it is.
    """
    from ..systems.base import System as _Base

    if isinstance(system, (_Base, _Entries)):
        return system, {}
    if is_scene_path(system):
        return scene_system(system)
    if isinstance(system, str):
        return builtin_or_registered(system), {}
    raise InvalidInputError(f"expected a system's name, a scene file (.toml) or a System, got "
                            f"{type(system).__name__} {_short(repr(system))}")


def check_system_of(system: Any) -> System | None:
    """The check system of a system object (built once per object: its definitions are derived once)."""
    with _LOCK:
        hit = _CHECK.get(id(system))
    if hit is not None and hit[0] is system:
        return hit[1]
    out = system.check_system()
    if out is not None and not isinstance(out, System):
        raise InvalidInputError(f"expected check_system() of system {getattr(system, 'name', '?')!r} to return a "
                                f"mechderive.formulas.systems.System or None, got {type(out).__name__}")
    with _LOCK:
        _CHECK[id(system)] = (system, out)
    return out


def names(has: Callable[[Any], bool] | None = None) -> tuple[str, ...]:
    """The registered systems' names (those for which ``has(system)`` holds, if given); a system
    whose module cannot be loaded is left out."""
    from ..errors import MechDeriveError
    from ..systems import registry

    out = []
    for name in registry.names():
        try:
            system = builtin_or_registered(name)
            if has is None or has(system):
                out.append(name)
        except (MechDeriveError, ImportError):
            continue
    return tuple(out)


def checkable() -> tuple[str, ...]:
    """The names of the systems ``check`` knows (those with a check system), sorted."""
    return tuple(sorted(names(lambda s: check_system_of(s) is not None)))


def get_system(name: Any) -> System:
    """The check system of ``name`` (a registered system's name, a scene file or a system object).

    Its symbol table is cheap; definitions are derived on first use, once per system object.
    """
    if isinstance(name, System):
        return name
    if isinstance(name, str) and not is_scene_path(name) and name not in names():
        raise InvalidInputError(f"expected a system among {', '.join(checkable())}, got {_short(repr(name))}")
    system, _ = find_system(name)
    out = check_system_of(system)
    if out is None:
        shown = name if isinstance(name, str) else getattr(system, "name", name)
        raise InvalidInputError(f"expected a system among {', '.join(checkable())}, got {_short(repr(shown))}")
    return out
