"""The optional applied torque of a rigid body: three formulas typed by the user, parsed by the whitelist.

Scene form::

    [torque]
    components = ["0", "0", "0.1"]          # tau1, tau2, tau3 (body components, N m)

Each component is a formula of ``t``, ``omega1 omega2 omega3``, ``R11 … R33`` (the chapter's R,
rows = body axes) and the parameters ``I1 I2 I3 M g c1 c2 c3`` (c = ``center_of_mass``), parsed by
:func:`mechderive.formulas.parse.parse_expression` — a syntax tree walked with a whitelist, never
``eval`` (a motor ``"0.1"``, a damper ``"-0.05*omega1"``, a gravity-gradient torque
``"3*0.001**2*(I3 - I2)*R23*R33"``).  The texts are checked here, before anything is solved.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any, Mapping

from ...errors import InvalidInputError

__all__ = ["Torque", "check_torque", "TORQUE_NAMES"]

#: The names a torque formula may use besides the parser's functions and ``pi``.
TORQUE_NAMES = ("t", "omega1", "omega2", "omega3", *(f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)),
                "I1", "I2", "I3", "M", "g", "c1", "c2", "c3")

_KEY = "scene table [torque]"


@dataclass(frozen=True)
class Torque:
    """Three checked formula texts (body components τ1, τ2, τ3)."""

    components: tuple[str, str, str]

    @property
    def digest(self) -> str:
        """A short hash of the texts: part of the compiled code's name (one name per derived system)."""
        return hashlib.sha256("\x1f".join(self.components).encode()).hexdigest()[:16]

    def expressions(self) -> list[Any]:
        """The three SymPy expressions in the model's symbols (R entries as generic symbols R11 … R33)."""
        from ...formulas.parse import parse_expression
        from .model import names

        table = names()
        return [parse_expression(text, table, what=f"torque component tau{a + 1}")
                for a, text in enumerate(self.components)]

    def depends_on_time(self) -> bool:
        from .model import time_symbol

        return any(e.has(time_symbol) for e in self.expressions())


def check_torque(value: Any) -> Torque | None:
    """The ``[torque]`` table checked: ``components`` = a list of 3 formula strings, each parsed (never run)."""
    if value is None:
        return None
    if isinstance(value, Torque):
        return value
    if not isinstance(value, Mapping):
        if isinstance(value, (list, tuple)):
            value = {"components": value}
        else:
            raise InvalidInputError(f"{_KEY}: expected a table with components = [\"tau1\", \"tau2\", \"tau3\"], "
                                    f"got {type(value).__name__} {value!r:.60}")
    unknown = [k for k in value if k != "components"]
    if unknown:
        raise InvalidInputError(f"scene key [torque].{unknown[0]}: unknown key; expected components")
    comps = value.get("components")
    if (not isinstance(comps, (list, tuple)) or len(comps) != 3
            or not all(isinstance(c, (str, int, float)) and not isinstance(c, bool) for c in comps)):
        raise InvalidInputError(f"scene key [torque].components: expected a list of 3 formula strings "
                                f"(tau1, tau2, tau3: body components, N m), got {comps!r:.80}")
    torque = Torque(tuple(str(c) for c in comps))  # type: ignore[arg-type]
    from ...errors import MechDeriveError

    try:
        torque.expressions()
    except MechDeriveError as exc:
        raise type(exc)(f"scene key [torque].components: {exc}; a component may use "
                        f"{', '.join(TORQUE_NAMES)}") from exc
    return torque
