"""Formulas in: parse a user's formula safely and decide it against a system's derived model.

``check(claim, system, given=...)`` returns a :class:`Verdict` — identity, on-shell, false (with a
counterexample) or undecided, and what it assumes (real bodies; the parameters' signs where a
proof used them) — see :mod:`mechderive.formulas.check`; the parser
(:mod:`.parse`) builds SymPy expressions from a whitelist without ``eval``/``sympify``; each
system's names and derived definitions are in :mod:`.systems`.

>>> check("u_dot**2 = (1 - u**2)*(alpha - beta*u) - (b - a*u)**2").verdict   # (3.73)
'identity'
"""

from .check import EXIT_STATUS, Verdict, check
from .parse import parse_claim, parse_expression
from .systems import get_system

__all__ = ["check", "Verdict", "EXIT_STATUS", "parse_claim", "parse_expression", "get_system"]
