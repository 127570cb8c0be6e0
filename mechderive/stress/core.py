"""The bookkeeping of the stress cases: checks, result rows, verdicts, the runner and the table.

A case is a function that fills a :class:`Collector` with checks — each a comparison of one
quantity from one method against the independent reference, with its tolerance — and may record
conserved-quantity drifts and details (the closed form's ``conditioning``, 1 - m, ...).

Verdicts, per case:

``met``
    every check within its tolerance, no NaN or inf in any output;
``said so``
    as ``met``, except that the toolkit itself declared a request unattainable (a scene's
    ``rtol_met = False`` with its note) — a legitimate answer;
``not met``
    a check failed: an error beyond its tolerance that the toolkit did not announce (silent
    inaccuracy), a NaN/inf in an output, an error estimate more than 10× below the actual error,
    valid input refused with an error, or invalid input accepted.  The reason names the check.
"""

from __future__ import annotations

import math
import time
import traceback
import warnings
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, Iterable

import numpy as np

from ..errors import MechDeriveError

__all__ = ["Check", "Case", "CaseResult", "Collector", "run_case", "format_table", "format_header", "format_row",
           "wrap_angle"]


@dataclass(frozen=True)
class Check:
    """One comparison: ``error`` of ``quantity`` from ``method`` against the reference, and its bound."""

    method: str
    quantity: str
    error: float  # nan when the output was not finite or not produced
    tol: float
    status: str  # "ok", "fail" or "said so"
    note: str = ""
    kind: str = "error"  # "error" (against the reference), "bound", "drift", "condition"

    @property
    def ratio(self) -> float:
        if not math.isfinite(self.error):
            return math.inf
        return self.error / self.tol if self.tol > 0 else (0.0 if self.error == 0 else math.inf)


@dataclass(frozen=True)
class Case:
    """A stress case: ``run(collector)`` computes and records its checks."""

    name: str
    family: str
    description: str
    system: str
    inputs: str
    methods: tuple[str, ...]
    reference: str
    tolerance: str  # the tolerances and their one-line justification
    run: Callable[["Collector"], None]
    quick: bool = False


@dataclass
class CaseResult:
    """The result row of one case (see the module docstring for the verdicts)."""

    name: str
    family: str
    description: str
    system: str
    inputs: str
    methods: tuple[str, ...]
    reference: str
    tolerance: str
    max_error: float
    max_error_tol: float
    max_error_what: str
    drift: float | None
    nan_free: bool
    verdict: str
    reason: str
    seconds: float
    checks: list[Check] = field(default_factory=list)
    drifts: dict[str, float] = field(default_factory=dict)
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return self.verdict in ("met", "said so")

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["passed"] = self.passed
        return _jsonable(d)


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else str(v)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    return x


def wrap_angle(x: Any) -> np.ndarray:
    """x reduced to (-π, π]."""
    x = np.asarray(x, dtype=float)
    return x - 2 * np.pi * np.round(x / (2 * np.pi))


class Collector:
    """Accumulates a case's checks, drifts and details."""

    def __init__(self) -> None:
        self.checks: list[Check] = []
        self.drifts: dict[str, float] = {}
        self.details: dict[str, Any] = {}
        self.nan_outputs: list[str] = []
        self.summary: list[str] = []  # short facts shown in the row (conditioning, 1 - m, ...)

    # --- comparisons --------------------------------------------------------------------------

    def _finite(self, method: str, quantity: str, got: np.ndarray) -> bool:
        if np.all(np.isfinite(got)):
            return True
        self.nan_outputs.append(f"{method}:{quantity}")
        bad = int(np.sum(~np.isfinite(got)))
        self.checks.append(Check(method, quantity, math.nan, 0.0, "fail", f"{bad} NaN/inf value(s) in the output",
                                 "condition"))
        return False

    def compare(self, method: str, quantity: str, got: Any, want: Any, tol: float, *, scale: float = 1.0,
                angle: bool = False, note: str = "") -> float:
        """Record max |got - want| / scale (differences wrapped to (-π, π] if ``angle``) against ``tol``."""
        got = np.asarray(got, dtype=float)
        want = np.asarray(want, dtype=float)
        if not self._finite(method, quantity, got):
            return math.nan
        diff = got - want
        if angle:
            diff = wrap_angle(diff)
        err = float(np.max(np.abs(diff))) / scale if diff.size else 0.0
        self.checks.append(Check(method, quantity, err, tol, "ok" if err <= tol else "fail", note))
        return err

    def bound(self, method: str, quantity: str, value: float, limit: float, note: str = "",
              kind: str = "bound") -> None:
        """Record a one-sided check value ≤ limit (a drift, a deviation, an estimate's honesty)."""
        value = float(value)
        ok = math.isfinite(value) and value <= limit
        if not math.isfinite(value):
            self.nan_outputs.append(f"{method}:{quantity}")
        self.checks.append(Check(method, quantity, value, limit, "ok" if ok else "fail", note, kind))

    def condition(self, method: str, what: str, ok: bool, note: str = "") -> None:
        """Record a yes/no check (error 0 when it holds, inf when not)."""
        self.checks.append(Check(method, what, 0.0 if ok else math.inf, 0.0, "ok" if ok else "fail", note,
                                 "condition"))

    def honest_estimate(self, method: str, quantity: str, actual: float, estimate: float | None,
                        floor: float = 1e-13) -> None:
        """The method's own error estimate must not be more than 10× below its actual error (plus a floor)."""
        if estimate is None or not math.isfinite(float(estimate)):
            self.condition(method, f"{quantity} error estimate", False, "no finite error estimate reported")
            return
        self.bound(method, f"{quantity} error ≤ 10·estimate + {floor:g}", actual, 10 * float(estimate) + floor,
                   note=f"estimate {float(estimate):.2g}")

    def said_so(self, method: str, quantity: str, error: float, tol: float, note: str) -> None:
        """The toolkit declared the request unattainable: a legitimate outcome, recorded as such."""
        self.checks.append(Check(method, quantity, float(error), tol, "said so", note))  # kind "error"

    def drift(self, method: str, name: str, value: float, limit: float) -> None:
        self.drifts[f"{method}:{name}"] = float(value)
        self.bound(method, f"{name} drift", value, limit, kind="drift")

    # --- running toolkit code -------------------------------------------------------------------

    def attempt(self, method: str, what: str, fn: Callable[[], Any]) -> Any:
        """Run ``fn``; valid input refused with a toolkit error is recorded as a failure, result None."""
        try:
            return fn()
        except MechDeriveError as exc:
            self.checks.append(Check(method, what, math.nan, 0.0, "fail",
                                     f"valid input refused: {type(exc).__name__}: {exc}", "condition"))
            return None

    def expect_refusal(self, method: str, what: str, fn: Callable[[], Any], error: type, match: str = "") -> None:
        """Bad input must raise ``error`` (a mechderive.errors class) whose message contains ``match``."""
        try:
            fn()
        except error as exc:
            ok = match in str(exc)
            self.condition(method, f"refuses {what}", ok, f"{type(exc).__name__}: {exc}"[:160])
            return
        except Exception as exc:  # noqa: BLE001 - reported, not hidden
            self.condition(method, f"refuses {what}", False, f"raised {type(exc).__name__} instead of "
                                                               f"{error.__name__}: {exc}"[:160])
            return
        self.condition(method, f"refuses {what}", False, f"accepted; expected {error.__name__}")


def run_case(case: Case) -> CaseResult:
    """Run one case and turn its checks into a result row."""
    col = Collector()
    start = time.perf_counter()
    crash = ""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            case.run(col)
        except Exception as exc:  # noqa: BLE001 - a crash is a verdict, not an abort of the whole run
            crash = f"crashed: {type(exc).__name__}: {exc}"
            col.details["traceback"] = traceback.format_exc(limit=6)
    if caught:  # kept for the report (a RuntimeWarning "invalid value" usually means a NaN somewhere)
        col.details["warnings"] = sorted({f"{w.category.__name__}: {w.message}" for w in caught})
    seconds = time.perf_counter() - start
    # the worst error against the reference (not the auxiliary bounds), by its ratio to its tolerance
    errors = [c for c in col.checks if c.kind == "error" and c.method != "reference" and c.status != "said so"]
    worst = max(errors, key=lambda c: (c.ratio if math.isfinite(c.ratio) else 1e300), default=None)
    failed = [c for c in col.checks if c.status == "fail"]
    said = [c for c in col.checks if c.status == "said so"]
    if crash:
        verdict, reason = "not met", crash
    elif failed:
        verdict = "not met"
        reason = "; ".join(f"{c.method} {c.quantity}: " + (c.note if not math.isfinite(c.error) or c.tol == 0
                                                           else f"{c.error:.2g} > {c.tol:.2g}"
                                                           + (f" ({c.note})" if c.note else ""))
                           for c in failed[:3])
        if len(failed) > 3:
            reason += f"; and {len(failed) - 3} more"
    elif said:
        verdict, reason = "said so", "; ".join(f"{c.method} {c.quantity}: {c.note}" for c in said[:2])
    else:
        verdict, reason = "met", f"{len(col.checks)} checks within tolerance"
    return CaseResult(
        name=case.name, family=case.family, description=case.description, system=case.system, inputs=case.inputs,
        methods=case.methods, reference=case.reference, tolerance=case.tolerance,
        max_error=worst.error if worst else 0.0, max_error_tol=worst.tol if worst else 0.0,
        max_error_what=f"{worst.method} {worst.quantity}" if worst else "",
        drift=max(col.drifts.values()) if col.drifts else None, nan_free=not col.nan_outputs,
        verdict=verdict, reason=reason, seconds=seconds, checks=col.checks, drifts=col.drifts,
        details={**col.details, **({"nan_outputs": col.nan_outputs} if col.nan_outputs else {}),
                 **({"summary": col.summary} if col.summary else {})})


_COLUMNS = (("case", 32), ("max err", 8), ("tol", 6), ("drift", 8), ("NaN", 4), ("verdict", 8), ("sec", 6))


def format_row(r: CaseResult) -> str:
    """One fixed-width line: case, worst error against the reference and its tolerance, drift, NaN, verdict."""
    err = "—" if not r.max_error_what else (f"{r.max_error:.1e}" if math.isfinite(r.max_error) else "NaN")
    tol = "—" if not r.max_error_what else f"{r.max_error_tol:.0e}"
    detail = r.reason if r.verdict != "met" or not r.max_error_what else f"worst: {r.max_error_what}; {r.reason}"
    if r.details.get("summary"):
        detail = "[" + ", ".join(r.details["summary"]) + "] " + detail
    cells = (r.name, err, tol, "—" if r.drift is None else f"{r.drift:.1e}", "no" if r.nan_free else "YES",
             r.verdict, f"{r.seconds:.1f}")
    return " ".join(c.ljust(w) for c, (_, w) in zip(cells, _COLUMNS)) + " " + detail


def format_header() -> str:
    head = " ".join(n.ljust(w) for n, w in _COLUMNS) + " detail (worst error's method and quantity, or the reason)"
    return head + "\n" + "-" * len(head)


def format_table(results: Iterable[CaseResult]) -> str:
    """The header and one line per case (:func:`format_row`)."""
    return "\n".join([format_header(), *(format_row(r) for r in results)])
