"""Built-in scenes: ready-made TOML scene files with a one-line description each.

Each system owns its named scenes (:meth:`mechderive.systems.base.System.builtin_scenes`); this module
lists them system by system, the scene called ``default`` (what ``mechderive run`` runs without a
scene) and the rest of its system's first, then the other systems' in the registry's order.  The
texts are ordinary scene files (:mod:`.schema`), so ``scene_text(name)`` can be saved, edited and
run again.

A scene is looked up system by system, so loading one imports only the systems listed before its own.

>>> [name for name, _ in list_scenes()][:3]
['default', 'heavy_top_looping', 'heavy_top_hanging']
>>> load_builtin("default").t_end
35.177
"""

from __future__ import annotations

from typing import Iterator

from ..errors import InvalidInputError
from ..systems import registry
from .schema import Scene, load_scene

__all__ = ["list_scenes", "scene_text", "find_builtin", "load_builtin", "DEFAULT"]

#: The scene ``mechderive run`` runs when given none.
DEFAULT = "default"


def _scenes() -> Iterator[tuple[str, str, str]]:
    """Every system's named scenes, ``(name, description, text)``, system by system (imported as needed)."""
    for system in registry.names():
        yield from registry.get(system).builtin_scenes()


def _all() -> dict[str, tuple[str, str]]:
    """name -> (description, text): the default's system's first (the default leading), then the other
    systems' in the registry's order."""
    groups = [registry.get(system).builtin_scenes() for system in registry.names()]
    groups.sort(key=lambda group: not any(name == DEFAULT for name, _, _ in group))  # stable
    ordered = sorted((s for group in groups for s in group), key=lambda s: s[0] != DEFAULT)
    return {name: (description, text) for name, description, text in ordered}


def list_scenes() -> list[tuple[str, str]]:
    """The built-in scenes as ``(name, description)`` pairs, in a fixed order."""
    return [(name, description) for name, (description, _) in _all().items()]


def scene_text(name: str) -> str:
    """The TOML text of the built-in scene ``name``.

    >>> scene_text("nope")
    Traceback (most recent call last):
    ...
    mechderive.errors.InvalidInputError: unknown built-in scene 'nope': expected one of default, ...
    """
    text = find_builtin(name)
    if text is None:
        raise InvalidInputError(f"unknown built-in scene {name!r}: expected one of {', '.join(_all())}")
    return text


def find_builtin(name: str) -> str | None:
    """The TOML text of the built-in scene ``name``, or None if there is none of that name.

    Systems are asked in the registry's order until one has it: a free top's scene imports no other
    system (listing every scene, as the message of an unknown name does, imports them all).
    """
    if isinstance(name, str):
        for found, _, text in _scenes():
            if found == name:
                return text
    return None


def load_builtin(name: str, *, cached: bool = False) -> Scene:
    """The built-in scene ``name``, parsed and checked, with ``Scene.name == name`` (``cached``: see
    :func:`~.schema.load_scene`)."""
    return load_scene(scene_text(name), name=name, cached=cached)
