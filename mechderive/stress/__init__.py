"""``mechderive stress``: the toolkit at the edges of its domain, each case against an independent reference.

Principle 5 of the project — near-separatrix motion, double roots, θ → 0 or π, huge spin, extreme
inertia ratios, very long times — as a table of cases.  Each case runs the toolkit's methods
(closed forms, DOP853, the structure-preserving splittings, the scene planner) and compares them
with a reference that shares nothing with them: an mpmath Taylor-series integration of equations
typed in by hand, at 30 digits (:mod:`.reference`).  Each row reports the worst error against its
tolerance, the conserved-quantity drift, whether any output held a NaN, and a verdict — ``met``,
``said so`` (the toolkit declared the request unattainable: a pass), or ``not met`` (silent
inaccuracy, NaN, or valid input refused: a failure) — see :mod:`.core`.

Families: 1 free-top separatrix, 2 uniform precession, 3 sleeping top, 4 θ near 0 or π, 5 huge spin,
6 inertia ratios, 7 long runs.  ``quick`` marks the bounded subset (``mechderive stress --quick``).

>>> [c.name for c in select("separatrix-exact")]
['separatrix-exact']
"""

from __future__ import annotations

from typing import Iterable, Sequence

from ..errors import InvalidInputError
from .core import Case, CaseResult, format_table, run_case

__all__ = ["all_cases", "select", "run_stress", "format_table", "Case", "CaseResult"]


def all_cases() -> list[Case]:
    """Every case, in family order."""
    from . import free_cases, heavy_cases, long_cases

    cases = free_cases.CASES + heavy_cases.CASES + long_cases.CASES
    return sorted(cases, key=lambda c: c.family.split()[0])  # stable: keeps the order within a family


def select(names: Sequence[str] | str | None = None, *, quick: bool = False) -> list[Case]:
    """The cases named (exact name, or a prefix such as ``pole`` or ``separatrix``), or all; ``quick`` subset.

    Raises :class:`~mechderive.errors.InvalidInputError` for a name that matches no case.
    """
    cases = all_cases()
    if quick:
        cases = [c for c in cases if c.quick]
    if names is None:
        return cases
    if isinstance(names, str):
        names = [names]
    chosen: list[Case] = []
    for name in names:
        exact = [c for c in cases if c.name == name]
        match = exact or [c for c in cases if c.name.startswith(name)]
        if not match:
            raise InvalidInputError(f"stress case {name!r}: expected a case name or prefix among "
                                    f"{', '.join(c.name for c in cases)}, got no match")
        chosen.extend(c for c in match if c not in chosen)
    return chosen


def run_stress(cases: Iterable[Case]) -> list[CaseResult]:
    """Run the cases (in order) and return their result rows."""
    return [run_case(c) for c in cases]
