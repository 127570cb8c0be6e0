"""``system = "lagrangian"``: any holonomic system from its Lagrangian (:mod:`.system`).

:mod:`.definition` parses and checks a definition (text through the whitelist parser, never
evaluated), :mod:`.model` derives its equations of motion, :mod:`.system` runs and checks them.
"""

from __future__ import annotations

from typing import Any, Sequence

__all__ = ["from_lagrangian"]


def from_lagrangian(lagrangian: Any, coordinates: Sequence[Any], parameters: Sequence[Any] = (),
                    name: str | None = None) -> Any:
    """See :func:`mechderive.systems.lagrangian.system.from_lagrangian`."""
    from .system import from_lagrangian as build

    return build(lagrangian, coordinates, parameters, name)
