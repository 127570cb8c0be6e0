"""The textbook catalog: one entry per checkable claim of the chapter.

Each :class:`Claim` holds the chapter's *printed* formula (transcribed only to be
checked, never used by the toolkit) and a *check* that compares a formula with
the toolkit's own derivation.  Keeping the two apart makes every check
falsifiable: the test suite feeds each check a perturbed formula and requires
it to fail (see :func:`perturb`).

A claim that states several formulas at once (a tuple, list or dict of them, named by
:attr:`Claim.parts`) is perturbed *member by member*: each member in turn is replaced by a
wrong one while the others stay right (:meth:`Claim.wrong_forms`), so a check that ignores a
member cannot pass unnoticed.  For a misprint the members of the *corrected* formula are the
ones perturbed: it is the form that must pass, so it is the form whose check must be able to fail.

Statuses
--------
``verified``     the printed formula agrees with the derivation;
``misprint``     the printed formula fails, and the entry's ``corrected`` formula passes;
``constructed``  the claim holds by construction (the toolkit chose a parameter to make it true,
                 :attr:`Claim.constructed` says which); the check then passes on independent
                 evidence measured from the same computation — not a failure;
``failed``       anything else (including a stale misprint entry whose printed form passes).
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable

from ..errors import InvalidInputError

__all__ = ["Outcome", "Claim", "ClaimResult", "register", "all_claims", "run_claims", "print_claims", "perturb",
           "member_count", "member_of", "with_member", "STATUSES", "SECTION_MODULES"]

#: Every status a claim can get, in the order ``mechderive verify`` counts them; only ``failed`` is a failure.
STATUSES = ("verified", "misprint", "constructed", "failed")

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
        Builds deliberately wrong formulas, for claims whose members :func:`perturb` cannot alter
        meaningfully (a count, a set of coordinates, a constant of motion — whose affine image is
        again one).  For a single formula: the wrong formula.  For a claim with ``parts``: a
        container shaped like the formula whose member k is the wrong alternative to member k
        (``None``: use :func:`perturb` on that member).
    parts : tuple of str
        Names of the members, for a claim whose formula is a tuple, list or dict of formulas
        (in order; a dict's in iteration order).  Empty for a single formula.
    constructed : str or None
        For a claim that holds by construction: what was constructed, and why the check's
        evidence is nonetheless independent (the status is then ``constructed``).
    """

    equation: str
    section: str
    statement: str
    method: str
    printed: Callable[[], Any]
    check: Callable[[Any], Outcome]
    corrected: Callable[[], Any] | None = None
    perturbed: Callable[[], Any] | None = None
    parts: tuple[str, ...] = ()
    constructed: str | None = None

    def __post_init__(self) -> None:
        if self.method not in ("symbolic", "numeric", "integration"):
            raise InvalidInputError(f"expected method 'symbolic', 'numeric' or 'integration', got {self.method!r}")
        if len(self.parts) == 1:
            raise InvalidInputError(f"expected no parts (one formula) or at least two, got {self.parts!r}")

    def passing_form(self) -> Any:
        """The formula that must pass its check: the corrected one for a misprint, else the printed one."""
        return self.corrected() if self.corrected is not None else self.printed()

    def member_names(self) -> tuple[str, ...]:
        """The names of the members perturbed one at a time: ``parts``, or the equation for a single formula."""
        return self.parts or (self.equation,)

    def wrong_forms(self, formula: Any = None) -> list[tuple[str, Any]]:
        """(member name, formula with that member alone made wrong) for every member of ``formula``.

        ``formula`` defaults to :meth:`passing_form` (pass it to reuse one already built).  A check
        that is falsifiable everywhere fails on every one of these.
        """
        if formula is None:
            formula = self.passing_form()
        n = member_count(formula)
        if n != len(self.member_names()):
            raise InvalidInputError(f"({self.equation}): expected {len(self.member_names())} members "
                             f"({', '.join(self.member_names())}), got a formula with {n}")
        if not self.parts:
            return [(self.equation, self.perturbed() if self.perturbed is not None else perturb(formula))]
        alternatives = self.perturbed() if self.perturbed is not None else None
        out = []
        for k, name in enumerate(self.parts):
            wrong = None if alternatives is None else member_of(alternatives, k)
            out.append((name, with_member(formula, k, perturb(member_of(formula, k)) if wrong is None else wrong)))
        return out


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
    note: str = ""  # for ``constructed``: what holds by construction

    def as_dict(self) -> dict[str, Any]:
        return {
            "equation": self.equation,
            "section": self.section,
            "claim": self.claim,
            "method": self.method,
            "status": self.status,
            "seconds": round(self.seconds, 4),
            "detail": self.detail,
            "note": self.note,
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
    note = claim.constructed or ""
    try:
        printed = claim.check(claim.printed())
        if claim.constructed is not None:
            status = "constructed" if printed.passed else "failed"
            detail = ("evidence: " if printed.passed else "") + printed.detail
        elif claim.corrected is None:
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
                       time.perf_counter() - start, detail, note)


def run_claims(section: str | None = None, claims: Iterable[Claim] | None = None) -> list[ClaimResult]:
    """Check every claim (of ``section``), returning one :class:`ClaimResult` per claim."""
    return [evaluate(c) for c in (all_claims(section) if claims is None else claims)]


def print_claims(results: list[ClaimResult], *, width: int | None = None) -> bool:
    """Print one line per result (for the derivations/ scripts); True when none failed."""
    for r in results:
        detail = r.detail if width is None else r.detail[:width]
        note = f" [{r.note}]" if r.note else ""
        print(f"  ({r.equation}) {r.status}{note}: {detail}")
    return not any(r.status == "failed" for r in results)


def member_count(formula: Any) -> int:
    """How many formulas ``formula`` states: the length of a tuple, list or dict, else 1."""
    return len(formula) if isinstance(formula, (tuple, list, dict)) else 1


def member_of(formula: Any, k: int) -> Any:
    """Member ``k`` of ``formula`` (see :func:`member_count`)."""
    if isinstance(formula, dict):
        return list(formula.values())[k]
    if isinstance(formula, (tuple, list)):
        return formula[k]
    if k != 0:
        raise InvalidInputError(f"expected member 0 of a single formula, got {k}")
    return formula


def with_member(formula: Any, k: int, value: Any) -> Any:
    """A copy of ``formula`` with its member ``k`` (see :func:`member_count`) replaced by ``value``."""
    if isinstance(formula, dict):
        key = list(formula)[k]
        return {**formula, key: value}
    if isinstance(formula, (tuple, list)):
        return type(formula)([*formula[:k], value, *formula[k + 1:]])
    if k != 0:
        raise InvalidInputError(f"expected member 0 of a single formula, got {k}")
    return value


def perturb(formula: Any, member: int | None = None, *, entry: int = 0) -> Any:
    """A deliberately wrong version of ``formula``: one entry scaled by 101/100 and shifted by 1/7.

    Without ``member`` the entry is in the first member (recursively: the first member, a matrix's
    first entry, an equation's right-hand side); with ``member`` it is in that member
    (:func:`with_member`).  ``entry`` picks a matrix's entry (row-major) instead of its first.  Works on
    SymPy expressions and numbers, matrices, and (nested) tuples/lists/dicts of them.
    """
    import sympy as sp

    if member is not None:
        return with_member(formula, member, perturb(member_of(formula, member), entry=entry))
    if isinstance(formula, sp.MatrixBase):
        m = sp.Matrix(formula)
        if not 0 <= entry < len(m):
            raise InvalidInputError(f"expected an entry in [0, {len(m)}), got {entry}")
        m[entry] = perturb(m[entry])
        return m
    if isinstance(formula, (dict, list, tuple)):
        return perturb(formula, 0, entry=entry)
    if entry != 0:
        raise InvalidInputError(f"expected entry 0 of a formula that is not a matrix, got {entry}")
    if isinstance(formula, sp.Equality):
        return sp.Eq(formula.lhs, perturb(formula.rhs), evaluate=False)
    from ..formulas.parse import as_expression

    expr = as_expression(formula, "the formula")  # never text: sympify would evaluate it
    # Scale *and* shift: scaling alone leaves an entry that is identically zero (but not
    # structurally 0, like an unsimplified diagonal of ṘRᵀ) unchanged.
    return expr * sp.Rational(101, 100) + sp.Rational(1, 7)
