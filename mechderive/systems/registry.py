"""The registry of systems: the one place that knows which systems exist.

The built-in systems are listed by name with the module that defines them, imported on first
request (so ``import mechderive`` derives and imports nothing).  A user system is registered at
run time with :func:`register`, from a test module, a notebook or a package of one's own:

>>> from mechderive.systems import registry
>>> "heavy_top" in registry.names()
True
"""

from __future__ import annotations

import _thread
import importlib

from ..errors import InvalidInputError
from .base import System

__all__ = ["register", "register_system", "unregister", "get", "names", "is_builtin"]

#: built-in system name -> module whose ``SYSTEM`` attribute is the system (imported on first use)
_BUILTIN = {
    "free_top": "mechderive.systems.free_top.system",
    "heavy_top": "mechderive.systems.heavy_top.system",
    "falling_cat": "mechderive.systems.deformable.system",
    "rigid_body": "mechderive.systems.rigid_body.system",
    "lagrangian": "mechderive.systems.lagrangian.system",
}

_LOCK = _thread.allocate_lock()  # threading.Lock(), without importing threading on every run
_LOADED: dict[str, System] = {}


def register(system: System, *, replace: bool = False) -> System:
    """Make ``system`` known by its ``name`` to scenes, ``derive``, ``check`` and the CLI; returns it.

    Registering a name already taken raises, unless ``replace`` (a test re-registering its own).
    """
    if not isinstance(system, System):
        raise InvalidInputError(f"expected a mechderive.systems.base.System to register, got {type(system).__name__}")
    name = system.name
    if not isinstance(name, str) or not name.isidentifier():
        raise InvalidInputError(f"expected a system name that is an identifier, got {name!r}")
    with _LOCK:
        if not replace and (name in _LOADED or name in _BUILTIN):
            raise InvalidInputError(f"system {name!r} is already registered; pass replace=True to replace it")
        _LOADED[name] = system
    return system


#: the public name of :func:`register` (``mechderive.register_system``)
register_system = register


def unregister(name: str) -> None:
    """Forget the user system ``name`` (a built-in one cannot be removed)."""
    if name in _BUILTIN:
        raise InvalidInputError(f"system {name!r} is built in and cannot be unregistered")
    with _LOCK:
        _LOADED.pop(name, None)


def names() -> tuple[str, ...]:
    """Every system's name: the built-in ones, then those registered, in order of registration."""
    with _LOCK:
        return tuple(_BUILTIN) + tuple(n for n in _LOADED if n not in _BUILTIN)


def get(name: str) -> System:
    """The system called ``name``; raises :class:`InvalidInputError` listing the known ones."""
    with _LOCK:
        hit = _LOADED.get(name)
    if hit is not None:
        return hit
    module = _BUILTIN.get(name) if isinstance(name, str) else None
    if module is None:
        known = ", ".join(repr(n) for n in names())
        raise InvalidInputError(f"expected a system one of {known}, got {name!r}")
    system = importlib.import_module(module).SYSTEM
    with _LOCK:
        return _LOADED.setdefault(name, system)


def is_builtin(name: str) -> bool:
    """Whether ``name`` is a system shipped with the package, not replaced by a program's own."""
    module = _BUILTIN.get(name) if isinstance(name, str) else None
    if module is None:
        return False
    with _LOCK:
        hit = _LOADED.get(name)
    return hit is None or hit is importlib.import_module(module).SYSTEM
