"""The textbook catalog: one entry per checkable claim of the chapter.

Each :class:`Claim` holds the chapter's *printed* formula (transcribed only to be
checked, never used by the toolkit) and a *check* that compares a formula with
the toolkit's own derivation.  Keeping the two apart makes every check
falsifiable: the test suite feeds each check a perturbed formula and requires
it to fail (see :func:`perturb`).

Statuses
--------
``verified``  the printed formula agrees with the derivation;
``misprint``  the printed formula fails, and the entry's ``corrected`` formula passes;
``failed``    anything else (including a stale misprint entry whose printed form passes).
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable

__all__ = ["Outcome", "Claim", "ClaimResult", "register", "all_claims", "run_claims", "print_claims", "perturb",
           "SECTION_MODULES"]

#: Modules that register the claims of each part of the chapter, imported on first use.
SECTION_MODULES = (
    "mechderive.catalog.s3_1_kinematics",
    "mechderive.catalog.s3_1_path_ordered",
    "mechderive.catalog.s3_2_inertia",
    "mechderive.catalog.s3_3_rigid_motion",
    "mechderive.catalog.s3_3_euler_equations",
    "mechderive.catalog.s3_4_free_tops",
    "mechderive.catalog.s3_4_exact_motion",
    "mechderive.catalog.s3_5_euler_angles",
    "mechderive.catalog.s3_5_3_free_symmetric_top",
    "mechderive.catalog.s3_6_heavy_top",
    "mechderive.catalog.s3_7_deformable",
)


@dataclass(frozen=True)
class Outcome:
    """The result of checking one formula: whether it holds, and a one-line detail."""

    passed: bool
    detail: str = ""


@dataclass(frozen=True)
class Claim:
    """A checkable statement of the chapter.

    Attributes
    ----------
    equation : str
        The equation number, e.g. ``"3.58"``, or a name for an unnumbered example
        (``"3.2 rod about its end"``).
    section : str
        The chapter section, e.g. ``"3.5.2"``.
    statement : str
        One line saying what is claimed.
    method : str
        How the check decides: ``"symbolic"`` (exact identity after simplification),
        ``"numeric"`` (random points at 30 digits with mpmath) or ``"integration"``
        (against a numerical solution).
    printed : callable
        Builds the chapter's printed formula (SymPy objects or a number).
    check : callable
        ``check(formula) -> Outcome``: whether ``formula`` agrees with the toolkit's derivation.
    corrected : callable or None
        For a misprint: builds the corrected formula.
    perturbed : callable or None
        Builds a deliberately wrong formula, for claims whose printed form :func:`perturb` cannot alter.
    """

    equation: str
    section: str
    statement: str
    method: str
    printed: Callable[[], Any]
    check: Callable[[Any], Outcome]
    corrected: Callable[[], Any] | None = None
    perturbed: Callable[[], Any] | None = None

    def __post_init__(self) -> None:
        if self.method not in ("symbolic", "numeric", "integration"):
            raise ValueError(f"expected method 'symbolic', 'numeric' or 'integration', got {self.method!r}")


@dataclass
class ClaimResult:
    """One row of ``mechderive verify``."""

    equation: str
    section: str
    claim: str
    method: str
    status: str
    seconds: float
    detail: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {
            "equation": self.equation,
            "section": self.section,
            "claim": self.claim,
            "method": self.method,
            "status": self.status,
            "seconds": round(self.seconds, 4),
            "detail": self.detail,
        }


_REGISTRY: list[Claim] = []


def register(claim: Claim) -> Claim:
    """Add ``claim`` to the catalog (called at import of a section module)."""
    if any(c.equation == claim.equation and c.statement == claim.statement for c in _REGISTRY):
        return claim
    _REGISTRY.append(claim)
    return claim


def _section_key(section: str) -> tuple[int, ...]:
    return tuple(int(p) for p in section.split(".") if p.isdigit())


def _equation_key(eq: str) -> tuple:
    head = eq.split()[0]
    try:
        return (0, tuple(int(p) for p in head.split(".")), eq)
    except ValueError:
        return (1, (), eq)


def all_claims(section: str | None = None) -> list[Claim]:
    """Every registered claim, ordered by section then equation; optionally only ``section`` and its subsections."""
    for name in SECTION_MODULES:
        try:
            importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise
    claims = list(_REGISTRY)
    if section is not None:
        claims = [c for c in claims if c.section == section or c.section.startswith(section + ".")]
    return sorted(claims, key=lambda c: (_section_key(c.section), _equation_key(c.equation)))


def evaluate(claim: Claim) -> ClaimResult:
    """Run one claim's check and classify it."""
    start = time.perf_counter()
    try:
        printed = claim.check(claim.printed())
        if claim.corrected is None:
            status = "verified" if printed.passed else "failed"
            detail = printed.detail
        elif printed.passed:
            status, detail = "failed", "marked as a misprint, but the printed form passes: " + printed.detail
        else:
            fixed = claim.check(claim.corrected())
            status = "misprint" if fixed.passed else "failed"
            detail = f"printed form fails ({printed.detail}); corrected form: {fixed.detail}"
    except Exception as exc:  # a check that crashes is a failed check, reported, not hidden
        status, detail = "failed", f"check raised {type(exc).__name__}: {exc}"
    return ClaimResult(claim.equation, claim.section, claim.statement, claim.method, status,
                       time.perf_counter() - start, detail)


def run_claims(section: str | None = None, claims: Iterable[Claim] | None = None) -> list[ClaimResult]:
    """Check every claim (of ``section``), returning one :class:`ClaimResult` per claim."""
    return [evaluate(c) for c in (all_claims(section) if claims is None else claims)]


def print_claims(results: list[ClaimResult], *, width: int | None = None) -> bool:
    """Print one line per result (for the derivations/ scripts); True when none failed."""
    for r in results:
        detail = r.detail if width is None else r.detail[:width]
        print(f"  ({r.equation}) {r.status}: {detail}")
    return not any(r.status == "failed" for r in results)


def perturb(formula: Any) -> Any:
    """A deliberately wrong version of ``formula``: its first entry scaled by 101/100 and shifted by 1/7.

    Works on SymPy expressions and numbers, matrices, and (nested) tuples/lists/dicts of them.
    """
    import sympy as sp

    if isinstance(formula, sp.MatrixBase):
        m = sp.Matrix(formula)
        for i in range(len(m)):
            m[i] = perturb(m[i])
            return m
        return m
    if isinstance(formula, dict):
        key = next(iter(formula))
        return {**formula, key: perturb(formula[key])}
    if isinstance(formula, (list, tuple)):
        return type(formula)([perturb(formula[0]), *formula[1:]])
    if isinstance(formula, sp.Equality):
        return sp.Eq(formula.lhs, perturb(formula.rhs), evaluate=False)
    expr = sp.sympify(formula)
    # Scale *and* shift: scaling alone leaves an entry that is identically zero (but not
    # structurally 0, like an unsimplified diagonal of ṘRᵀ) unchanged.
    return expr * sp.Rational(101, 100) + sp.Rational(1, 7)
