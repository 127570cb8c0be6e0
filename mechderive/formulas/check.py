"""Decide a user's claim ``LHS = RHS`` about a system: identity, on-shell, false, or undecided.

Semantics.  Every *defined* name of the system (heavy top: a, b, α, β, u, u_dot, p_φ, p_ψ,
E, E', ω1..3, …; free top: T, Lsq) stands for its derived function of the state and the
parameters (:mod:`.systems`), and is replaced by it first.  Then:

``identity``
    LHS − RHS ≡ 0 as a function of the state, the parameters and every time derivative
    (``theta_ddot``, ``omega1_dot``, ``dt(...)`` by the chain rule) taken as independent.
    Relations the text obtains "using a conserved quantity" are identities here because the
    constant is *defined* as a function of the state: (3.67) φ̇ = (b − a cos θ)/sin²θ holds at
    every state, with b = p_φ(state)/I1; so does (3.73) u̇² = f(u).  What conservation adds is
    a separate, on-shell claim: ``dt(b) = 0``.
``on-shell``
    not an identity, but LHS − RHS ≡ 0 once the derivatives beyond the state are those of a
    motion: q̈ from the model's Euler–Lagrange equations (heavy top), ω̇ from Euler's equations
    (3.33) without torque (free top), and ``dt(expr)`` is the derivative along that flow.
    ``dt(E) = 0`` and ``I1*dt(omega1) = (I2 - I3)*omega2*omega3`` are on-shell.
``false``
    LHS − RHS ≠ 0 at a random point (on a motion, for a claim with derivatives), shown with
    both sides' values: the difference exceeds its error bound at two precisions.
``undecided``
    no valid sample point (singular, non-real, overflowing, or needing more digits or time than
    allowed) or an expression the evaluator does not know; the detail says why.

Method, strongest first: ``exact`` — :func:`mechderive.core.simplify.is_zero`, a proof for
rational functions of sines and cosines; ``simplify`` — ``sympy.simplify`` gave 0 within the
time budget (a proof up to SymPy's correctness); ``numeric`` — at each of ``points`` seeded
random points LHS − RHS vanished within its running error bound, that bound being below
10^−K of the size of the terms, with K at least 50 (more for long typed numbers, so that a
typed approximation of π is not taken for π) and at least twice the decades by which the
expression hides some input, plus 30 (:mod:`.significance`: ``sin(θ) = sin(θ + 1e-100)`` is
evaluated with enough digits to see 1e-100, and is false): established, not proven; the
detail states the chance of a false positive and its assumption.  A proof that needs the
parameters to be positive (as they are declared: ``sqrt(M**2) = M``) says so in
:attr:`Verdict.assumptions`.

Points.  The parameters are those of a *real body* (:mod:`.sampling`): free top I1, I2, I3 > 0
obeying the triangle inequalities, heavy top I1 ≥ M l² + I3/2 with I1, I3, M, g, l > 0 — the
bodies the solvers accept — so a formula false only for impossible bodies is an identity
here, with that condition in :attr:`Verdict.assumptions`; ``any_moments=True`` draws each
parameter on its own.  The other values are short decimals drawn from each symbol's range
(:meth:`System.sampling_range`: θ ∈ (0.15, π − 0.15), other variables in (−2, 2)), so
``numeric`` and counterexamples are about that domain (e.g. ``sqrt(1 - u**2) = sin(theta)``
holds there).

``given`` entries ``name = expression`` either *define a new name* (to translate another book's
convention, e.g. ``I1_cm = I1 - M*l**2``; later entries may use earlier names) or *specialise*
a state variable or parameter (``theta_dot = 0``, ``I2 = I1``): the claim is then decided at
the states where that holds, i.e. the value is substituted after the time derivatives and the
equations of motion (``dt(theta_dot) = 0`` given ``theta_dot = 0`` is still false).
Specialising a defined quantity, a derivative, or redefining a name is refused.

Limits.  ``budget`` is the wall-clock time of the whole decision (:mod:`.budget`): parsing,
expanding ``dt``, the trig normal form (given half of the time left, a fifth in the formal pass
of a claim with derivatives, which is usually decided on a motion), the random points, and
``sympy.simplify`` (most of what is left) all stop when it is spent; the claim is then
``undecided``, saying in which step.  Only the system's own derivations, once per process,
come before it.  In the main thread a timer interrupts any step; elsewhere only checks
between steps apply, so no proof is attempted there (the verdict comes from the random
points) and expansions stop at :data:`MAX_UNTIMED_NODES` nodes.  Sizes are bounded too: a side
growing beyond :data:`MAX_NODES` nodes while ``dt`` is expanded is undecided; --given names
that build more than :data:`MAX_INPUT_NODES` nodes, numbers beyond 10^1000 or exponents beyond
100 are refused, as the parser refuses them in a single text.  ``exp(exp(exp(exp(theta)))) = 1``
is false (at θ ≈ 0.65 the left side is 1.7e352); ``dt(dt(dt(dt(dt(E))))) = 0`` is undecided
within the budget (its expansion along the motion alone takes about 15 s).

>>> check("p_psi = I3*(psi_dot + cos(theta)*phi_dot)").verdict            # (3.63)
'identity'
>>> check("I1*dt(omega1) = (I2 - I3)*omega2*omega3", "free_top").verdict   # (3.33)
'on-shell'
>>> check("dt(theta_dot) = 0").verdict
'false'
>>> v = check("sqrt((I1 + I2 - I3)**2) = I1 + I2 - I3", "free_top")   # false only for impossible bodies
>>> v.verdict, v.assumptions[0][:40]
('identity', 'a real body: I1, I2, I3 > 0 and I1 + I2 ')
>>> check("exp(exp(1000)) = 1").verdict                                     # an overflow proves nothing
'undecided'
"""

from __future__ import annotations

import math
import os
import random
import re
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import mpmath
import sympy as sp

from ..core.simplify import is_zero
from ..errors import InvalidInputError
from .budget import Budget, OutOfTime, timer_usable
from .evaluate import CannotEvaluate
from .inputs import (MAX_GIVEN, MAX_INPUT_DEPTH, MAX_INPUT_NODES, SYMPY_ERRORS, parse_claim_within_limits,
                     parse_givens, shown as _shown, specialise, sympy_failure)
from .parse import MAX_LENGTH, dt
from .sampling import Draw, PointSampler, decimal_text
from .significance import Comparison, compare
from .size import brief, tree_size
from ..systems.base import System as SystemBase
from .systems import System, checkable, get_system

__all__ = ["Verdict", "check", "EXIT_STATUS", "MAX_NODES", "MAX_UNTIMED_NODES", "MAX_INPUT_NODES",
           "MAX_INPUT_DEPTH", "MAX_BUDGET"]

#: Exit status of ``mechderive check`` for each verdict (2 is an input error).
EXIT_STATUS = {"identity": 0, "on-shell": 0, "false": 1, "undecided": 3}
#: The largest tree (nodes, each use of a shared subexpression counted) a side may grow to while
#: ``dt`` and the definitions are expanded; beyond it the claim is undecided.  dt⁴(E) along the
#: heavy top's motion has about 72 000 nodes (1 s); dt⁵(E) has about 800 000 (15 s to build).
MAX_NODES = 100_000
#: The same limit where no timer can interrupt a step (outside the main thread: :mod:`.budget`), so that
#: a single differentiation stays short (about 1 s).
MAX_UNTIMED_NODES = 10_000
#: The longest time budget accepted, in seconds.
MAX_BUDGET = 600
_SIMPLIFY_SHARE = 0.8  # of the time left: sympy.simplify, the last step of a decision (the rest may qualify it)
_BACKSTOP = 0.75  # seconds after the budget's end at which any step still running is interrupted
_QUALIFY = 0.3  # seconds allowed, even once the budget is spent, to find the positivity a proof used
_DEGREE = 20  # the assumed degree in the false-positive bound
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class _TooLarge(Exception):
    """An expansion beyond :data:`MAX_NODES`: the claim is undecided (caught in :func:`check`)."""


@dataclass(frozen=True)
class Verdict:
    """The decision on a claim: ``verdict`` (identity, on-shell, false, undecided), how, and why."""

    verdict: str
    method: str
    detail: str
    counterexample: dict | None = None
    assumptions: tuple[str, ...] = ()  # what the answer holds under (real bodies; positivity a proof used)

    @property
    def exit_status(self) -> int:
        return EXIT_STATUS[self.verdict]

    def as_dict(self) -> dict:
        out: dict[str, Any] = {"verdict": self.verdict, "method": self.method, "detail": self.detail}
        if self.counterexample is not None:
            out["counterexample"] = self.counterexample
        if self.assumptions:
            out["assumptions"] = list(self.assumptions)
        return out


@dataclass(frozen=True)
class _Outcome:
    kind: str  # "zero", "nonzero", "unknown"
    method: str
    detail: str
    counterexample: dict | None = None
    assumptions: tuple[str, ...] = ()


# --- expanding -----------------------------------------------------------------------------------


def _bounded(expr: sp.Expr, doing: str) -> sp.Expr:
    """``expr``, if its tree has at most :data:`MAX_NODES` nodes (:data:`MAX_UNTIMED_NODES` where no timer
    can interrupt the next step); else :class:`_TooLarge`."""
    limit = MAX_NODES if timer_usable() else MAX_UNTIMED_NODES
    if tree_size(expr, limit + 1) > limit:
        raise _TooLarge(f"{doing} gives an expression of more than {limit} nodes (its tree, each use of a "
                        "shared subexpression counted): too large to decide here")
    return expr


def _expand(expr: sp.Expr, system: System, *, on_motion: bool, clock: Budget) -> sp.Expr:
    """Definitions substituted, dt(...) expanded (formally or along the motion), derivatives on-shell if asked.

    Each dt(...) is bounded: the time budget is checked before it and the size of its result after
    (:data:`MAX_NODES`), so that the next one never differentiates a runaway expression.
    """
    derivative = system.motion_dt if on_motion else system.formal_dt
    doing = "dt(...) along the motion" if on_motion else "dt(...)"

    def walk(e: sp.Expr) -> sp.Expr:
        if not e.has(dt):
            return e
        if isinstance(e, dt):
            inner = walk(e.args[0])
            clock.check()
            return _bounded(derivative(inner), doing)
        return e.func(*[walk(a) for a in e.args])

    out = _bounded(walk(_bounded(system.expand_definitions(expr), "substituting the definitions")), doing)
    return _bounded(system.on_shell(out), "substituting the equations of motion") if on_motion else out


def _sides(lhs: sp.Expr, rhs: sp.Expr, system: System, specs: list, *, on_motion: bool, clock: Budget,
           rename: dict | None = None) -> list[sp.Expr]:
    """Both sides expanded (:func:`_expand`), renamed, then specialised."""
    out = []
    for x in (lhs, rhs):
        e = _expand(x, system, on_motion=on_motion, clock=clock)
        out.append(_bounded(specialise(e.xreplace(rename) if rename else e, specs), "substituting --given values"))
    return out


# --- deciding LHS − RHS ≡ 0 -------------------------------------------------------------------------


def _trig_expandable(expr: sp.Expr) -> bool:
    """Whether is_zero's trig expansion is affordable: no sin(n x) with an integer |n| > 100.

    (sin(10**40*theta) would be expanded into a polynomial of degree 10^40.)
    """
    for f in expr.atoms(sp.sin, sp.cos, sp.tan):
        for term in sp.Add.make_args(f.args[0]):
            c, rest = term.as_coeff_Mul()
            if c.is_Integer and abs(c) > 100 and not rest.is_number:
                return False
    return True


def _trig_args_are_symbols(expr: sp.Expr) -> bool:
    """Whether is_zero's False is a proof: the sines and cosines are of distinct plain symbols only."""
    e = sp.expand_trig(expr.replace(sp.tan, lambda x: sp.sin(x) / sp.cos(x)))
    return all(f.args[0].is_Symbol for f in e.atoms(sp.sin, sp.cos))


def _high_precision(digits_typed: int) -> int:
    """The fewest digits an agreement is accepted at: 60, more when the input has long numbers.

    A decimal of D digits (or a fraction of D digits in all) can approximate an irrational constant
    to about D digits (2D for a fraction); the confirming precision exceeds that, so a typed
    approximation of π is never taken for π.  (:mod:`.significance` raises it further where the
    expression's own scales ask for it.)
    """
    return max(60, 2 * digits_typed + 40)


def _counterexample(result: Comparison, draw: Draw) -> dict:
    """Both sides' values at the point, to enough digits that they differ visibly."""
    with mpmath.workdps(result.digits):
        d = result.difference
        rel = abs(d) / max(abs(result.lhs), abs(result.rhs))
        shown = min(result.digits, max(30, math.ceil(-float(mpmath.log10(rel))) + 6))
        out = {"point": {s.name: decimal_text(v) for s, v in draw.point.items()},
               "lhs": mpmath.nstr(result.lhs, shown), "rhs": mpmath.nstr(result.rhs, shown),
               "difference": mpmath.nstr(d, 10), "relative difference": mpmath.nstr(rel, 5)}
    if draw.body is not None and not set(draw.body) <= set(out["point"]):  # the rest of the real body
        out["body"] = draw.body
    return out


def _sample(lhs: sp.Expr, rhs: sp.Expr, system: System, points: int, seed: int, hi: int, *, specs: list,
            any_moments: bool, clock: Budget) -> dict:
    """Compare both sides at seeded random points (:func:`.significance.compare`).

    Returns the agreements, the rejections by reason, or a counterexample.  Every evaluation
    counts against the time budget; :class:`~.budget.OutOfTime` once it is spent.
    """
    syms = sorted(lhs.free_symbols | rhs.free_symbols, key=sp.default_sort_key)
    sampler = PointSampler(system, syms, specs, any_moments=any_moments)
    rng = random.Random(seed)
    needed = points if syms else 1
    where = " among real bodies" if sampler.active and not any_moments else ""
    agreed, rejected, attempts, digits, agreed_to = 0, {}, 0, [], []
    while agreed < needed and attempts < 10 * needed:
        clock.doing = (f"comparing both sides at random points{where} ({agreed} of {needed} agreed, "
                       f"{attempts - agreed} rejected so far)")
        clock.check()
        attempts += 1
        draw = sampler.draw(rng)
        if draw.refusal is not None:
            rejected[draw.refusal] = rejected.get(draw.refusal, 0) + 1
            continue
        try:
            result = compare(lhs, rhs, draw.point, base=hi, deadline=clock.end)
        except CannotEvaluate as exc:
            return {"error": str(exc), "condition": sampler.condition}
        if result.kind == "differ":
            return {"counterexample": _counterexample(result, draw), "digits": result.digits,
                    "condition": sampler.condition}
        if result.kind == "reject":
            rejected[result.reason] = rejected.get(result.reason, 0) + 1
            continue
        agreed += 1
        digits.append(result.digits)
        agreed_to.append(result.agreed_to)
    clock.check()  # a last rejection may have been the budget's end
    widths = sampler.widths()
    return {"agreed": agreed, "needed": needed, "rejected": rejected, "attempts": attempts,
            "width": min(widths) if widths else 1.0, "symbols": syms, "condition": sampler.condition,
            "digits": (min(digits), max(digits)) if digits else None, "agreed_to": min(agreed_to, default=0)}


def _false_positive_bound(points: int, width: float, agreed_to: int) -> float:
    """(4 (δ/2)^(1/d) / w)^n: Pólya's bound on the measure of {|p| ≤ δ} for a monic degree-d polynomial.

    δ = 10^−K, K the digits (of the size of the terms) to which LHS − RHS vanished at each point;
    the assumption (stated in the verdict) is that a nonzero difference is, in some sampled
    variable of range width w, a polynomial of degree ≤ d = 20 whose leading coefficient is at
    least the size of the terms.
    """
    per_point = min(1.0, 4 * (10.0 ** -agreed_to / 2) ** (1 / _DEGREE) / width)
    return per_point ** points


def _digits_text(span: tuple[int, int] | None) -> str:
    if span is None:
        return ""
    low, high = span
    return f"{low} digits" if low == high else f"{low}-{high} digits"


def _quietly(fn: Callable[[], Any]) -> Callable[[], Any]:
    """``fn`` returning None where SymPy fails on the expression: an optional proof that fails proves nothing."""
    def attempt() -> Any:
        try:
            return fn()
        except SYMPY_ERRORS:
            return None
    return attempt


def _decide(lhs: sp.Expr, rhs: sp.Expr, system: System, *, clock: Budget, proof_share: float, points: int,
            seed: int, hi: int, specs: list, any_moments: bool) -> _Outcome:
    """Whether LHS − RHS ≡ 0: the trig normal form (``proof_share`` of the time left), random points,
    then ``sympy.simplify`` with what is left (see the module docstring)."""
    diff = lhs - rhs
    if diff == 0:
        return _Outcome("zero", "exact", "proven: both sides are the same expression")
    if diff.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        return _Outcome("unknown", "none", f"singular: LHS − RHS = {brief(diff, 80)} (division by zero)")
    # Proofs run only under a timer: even a small expression can expand without end (cosh(cosh(… of a sum).
    clock.doing = "proving LHS − RHS = 0 in the trig normal form"
    exact = None
    if _trig_expandable(diff):
        done, exact = clock.attempt(_quietly(lambda: is_zero(diff)), proof_share, unbudgeted_ok=False)
        exact = exact if done else None
    if exact:
        return _Outcome("zero", "exact", "proven: LHS − RHS reduces to 0 modulo sin² + cos² = 1 (trig normal form)")
    proven_nonzero = exact is False and clock.attempt(_quietly(lambda: _trig_args_are_symbols(diff)), proof_share,
                                                      unbudgeted_ok=False) == (True, True)
    sample = clock.run("comparing both sides at random points",
                       lambda: _sample(lhs, rhs, system, points, seed, hi, specs=specs, any_moments=any_moments,
                                       clock=clock))
    region = (sample["condition"],) if sample.get("condition") else ()
    where = "" if not region or any_moments else " among real bodies"
    if "error" in sample:
        return _Outcome("unknown", "none", sample["error"], assumptions=region)
    if "counterexample" in sample:
        return _Outcome("nonzero", "numeric", f"LHS ≠ RHS at a random point{where} (the difference exceeds its "
                        f"error bound at two precisions, up to {sample['digits']} digits)",
                        sample["counterexample"], assumptions=region)
    if proven_nonzero and (sample["agreed"] or not where):  # (no real body at all is not a counterexample)
        seen = (f", though it vanished to {sample['agreed_to']} digits at the {sample['agreed']} points sampled{where}"
                if sample["agreed"] else "")
        return _Outcome("nonzero", "exact", f"LHS − RHS has a nonzero trig normal form{seen}")
    if sample["agreed"] < sample["needed"]:
        reasons = "; ".join(f"{n}× {r}" for r, n in sorted(sample["rejected"].items(), key=lambda x: -x[1])[:3])
        return _Outcome("unknown", "none", f"only {sample['agreed']} of {sample['attempts']} random points{where} "
                        f"gave trustworthy real values ({reasons})", assumptions=region)
    clock.doing = "simplifying LHS − RHS"
    done, simplified = clock.attempt(_quietly(lambda: sp.simplify(diff)), _SIMPLIFY_SHARE, unbudgeted_ok=False)
    if done and simplified == 0:
        return _Outcome("zero", "simplify",
                        f"proven: sympy.simplify(LHS − RHS) = 0 (and it agreed numerically at {points} points)")
    n, k = sample["agreed"], sample["agreed_to"]
    at = _digits_text(sample["digits"])
    if not sample["symbols"]:
        return _Outcome("zero", "numeric", f"not proven: both sides are constants equal to {k} digits ({at})")
    bound = _false_positive_bound(n, sample["width"], k)
    return _Outcome("zero", "numeric", (
        f"not proven: LHS − RHS vanished within its error bound, below 10^-{k} of the size of the terms, at each "
        f"of {n} random points{where} ({at}, chosen from the scales in the expression); probability of a false "
        f"positive < {bound:.0e}, assuming a nonzero difference would be a polynomial of degree ≤ {_DEGREE} in a "
        "sampled variable (Pólya's bound)"), assumptions=region)


# --- the public entry point --------------------------------------------------------------------------


def _context(exprs: Sequence[sp.Expr], system: System, new: list[str], specs: list) -> str:
    """What was substituted: the definitions used, the --given names and specialisations."""
    used = sorted({s.name for e in exprs for s in e.free_symbols if system.kind(s) == "defined"}, key=str.lower)
    parts = []
    if used:
        parts.append("definitions used: " + ", ".join(used))
    if new:
        parts.append("--given names: " + ", ".join(new))
    if specs:
        parts.append("at " + ", ".join(f"{s} = {v}" for s, v in specs))
    return "".join("; " + p for p in parts)


def _positive_parameters(system: System, exprs: Sequence[sp.Expr]) -> list[str]:
    """The positive parameters of ``system`` that occur in ``exprs``, by name."""
    return sorted({s.name for e in exprs for s in e.free_symbols
                   if system.kind(s) == "parameter" and s.is_positive})


def _positivity_used(claim: str, given: Sequence[str], system: System, parsed: tuple, *, on_motion: bool,
                     method: str, clock: Budget) -> list[str]:
    """The positive parameters a proof relied on being positive: [] if it holds for any real values.

    The claim is parsed again with the parameters replaced by merely real stand-ins.  If that
    parse is the original one renamed (no automatic simplification such as sqrt(M**2) = M used
    the sign) and the proof is the trig normal form — polynomial algebra, blind to signs — the
    proof did not use positivity.  Otherwise it is tried again on the stand-ins; if it fails (or
    runs out of time) the parameters present are named.  (The system's definitions are taken
    as derived, for positive parameters.)
    """
    rename = {s: sp.Symbol(s.name, real=True) for s in system.names.values()
              if system.kind(s) == "parameter" and s.is_positive}
    names, specs, _ = parse_givens(given, system, rename)
    lhs, rhs = parse_claim_within_limits(claim, names, system)
    lhs0, rhs0, specs0 = parsed
    same = (lhs0.xreplace(rename) == lhs and rhs0.xreplace(rename) == rhs
            and [(rename.get(s, s), v.xreplace(rename)) for s, v in specs0] == specs)
    if same and method == "exact":
        return []
    left, right = _sides(lhs, rhs, system, specs, on_motion=on_motion, clock=clock, rename=rename)
    stand_ins = set(rename.values())
    present = sorted({s.name for s in left.free_symbols | right.free_symbols if s in stand_ins})
    diff = left - right
    if not present or diff == 0:
        return []
    if method == "exact":
        done, proven = (clock.attempt(_quietly(lambda: is_zero(diff)), unbudgeted_ok=False) if _trig_expandable(diff)
                        else (False, None))
    else:
        done, simplified = clock.attempt(_quietly(lambda: sp.simplify(diff)), unbudgeted_ok=False)
        proven = done and simplified == 0
    return [] if done and proven else present


def _check_options(points: object, seed: object, budget: object, any_moments: object) -> None:
    """Refuse option values out of range, naming the option."""
    if not isinstance(points, int) or isinstance(points, bool) or not 20 <= points <= 1000:
        raise InvalidInputError(f"points: expected an integer between 20 and 1000, got {_shown(points)}")
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise InvalidInputError(f"seed: expected an integer, got {_shown(seed)}")
    if (not isinstance(budget, (int, float)) or isinstance(budget, bool) or not math.isfinite(budget)
            or not 0 < budget <= MAX_BUDGET):
        raise InvalidInputError(f"budget: expected a time of more than 0 and at most {MAX_BUDGET} seconds, "
                                f"got {_shown(budget)}")
    if not isinstance(any_moments, bool):
        raise InvalidInputError(f"any_moments: expected True or False, got {_shown(any_moments)}")


def check(claim: str, system: Any = "heavy_top", *, given: Sequence[str] = (), points: int = 20,
          seed: int = 20261121, budget: float = 5.0, any_moments: bool = False) -> Verdict:
    """Decide ``claim`` ("LHS = RHS") for ``system``; see the module docstring.

    ``system``: a registered system's name ("heavy_top", "free_top", or one registered with
    :func:`mechderive.systems.registry.register` whose ``check_system()`` gives its symbols), a
    scene file (a path ending ``.toml``: the system it configures), or a system object.

    ``given``: "name = expression" entries (new names or specialisations); ``points``: random
    points of the numeric method (20 to 1000); ``seed``: their seed; ``budget``: the seconds of
    wall-clock time the whole decision may take (more than 0, at most :data:`MAX_BUDGET`):
    parsing, expanding ``dt``, proving, sampling and simplifying all stop when it is spent, and
    the verdict is then ``undecided``, saying in which step (:mod:`.budget`: enforced by an
    interval timer in the main thread, by checks between steps elsewhere).  The one-time
    derivation of the system's definitions that the texts name (up to about 4 s for all of the
    heavy top's, once per process) comes before and is not counted.  ``any_moments``: draw the
    parameters independently (any positive values) instead of only those of a real body
    (:mod:`.sampling`).  What the answer assumes is in :attr:`Verdict.assumptions`.

    Input errors raise :class:`~mechderive.errors.InvalidInputError` with a message starting with
    the argument it is about (``claim '…': ``, ``given '…': ``, ``points: `` …); an expression
    that grows beyond :data:`MAX_NODES` nodes while being expanded is ``undecided``.
    """
    _check_options(points, seed, budget, any_moments)
    if not isinstance(system, (str, os.PathLike, System, SystemBase)):
        raise InvalidInputError(f"system: expected a name among {', '.join(checkable())}, got {_shown(system)}")
    try:
        sys_ = get_system(system)
    except InvalidInputError as exc:
        raise InvalidInputError(f"system: {exc}") from None
    if (isinstance(claim, str) and len(claim) <= MAX_LENGTH and isinstance(given, Sequence)
            and not isinstance(given, str) and len(given) <= MAX_GIVEN
            and all(isinstance(g, str) and len(g) <= MAX_LENGTH for g in given)):
        # the system's own derivations that the texts name: a fixed cost, not the claim's
        sys_.prepare(_NAME.findall(" ".join([claim, *given])))
    clock = Budget(budget)
    try:
        with clock.backstop(_BACKSTOP):
            return _check(claim, sys_, given, clock, points=points, seed=seed, any_moments=any_moments)
    except OutOfTime as exc:
        if not clock.spent(exc):
            raise
        return Verdict("undecided", "none", f"the time budget of {budget:g} s (--budget) ran out while {clock.doing}")
    except _TooLarge as exc:
        return Verdict("undecided", "none", str(exc))
    except InvalidInputError:
        raise
    except SYMPY_ERRORS as exc:  # SymPy giving up on an expansion of odd input: nothing decided
        return Verdict("undecided", "none", f"SymPy failed while {clock.doing}: {sympy_failure(exc)}")


def _check(claim: str, sys_: System, given: Sequence[str], clock: Budget, *, points: int, seed: int,
           any_moments: bool) -> Verdict:
    names, specs, new = clock.run("parsing the --given entries", lambda: parse_givens(given, sys_))
    lhs, rhs = clock.run("parsing the claim", lambda: parse_claim_within_limits(claim, names, sys_))
    typed = sum(ch.isdigit() for text in (claim, *given) for ch in text)
    opts = {"points": points, "seed": seed, "hi": _high_precision(typed), "specs": specs, "any_moments": any_moments}
    used = _context([lhs, rhs], sys_, new, specs)

    def verdict(name: str, outcome: _Outcome, detail: str, *, sides: Sequence[sp.Expr], on_motion: bool) -> Verdict:
        assumptions = list(outcome.assumptions)
        if outcome.kind == "zero" and outcome.method in ("exact", "simplify"):
            present = _positive_parameters(sys_, sides)
            positive = present
            if present:  # a little time beyond a spent budget: the verdict is decided, this only qualifies it
                clock.doing = "finding whether the proof used the parameters' positivity"
                qualify = Budget(max(clock.left(), _QUALIFY))
                done, used_ = qualify.attempt(_quietly(lambda: _positivity_used(
                    claim, given, sys_, (lhs, rhs, specs), on_motion=on_motion, method=outcome.method, clock=qualify,
                )), unbudgeted_ok=True)
                positive = used_ if done and used_ is not None else present  # (not found: say all of them)
            if positive:
                assumptions.append(f"{', '.join(positive)} > 0: the proof uses the parameters' positivity")
        example = _with_given(outcome.counterexample, specs)
        return Verdict(name, outcome.method, detail, example, tuple(assumptions))

    formal = clock.run("substituting the definitions and expanding dt(...)",
                       lambda: _sides(lhs, rhs, sys_, specs, on_motion=False, clock=clock))
    has_derivatives = any(sys_.kind(s) == "derivative" for e in formal for s in e.free_symbols)
    # a claim with derivatives is usually decided on a motion: the formal proof gets less of the time
    off = _decide(*formal, sys_, clock=clock, proof_share=0.2 if has_derivatives else 0.5, **opts)
    if off.kind == "zero":
        return verdict("identity", off, off.detail + used, sides=formal, on_motion=False)
    if not has_derivatives:
        return verdict("false" if off.kind == "nonzero" else "undecided", off, off.detail + used, sides=formal,
                       on_motion=False)
    on = clock.run("expanding dt(...) along the motion (the equations of motion substituted)",
                   lambda: _sides(lhs, rhs, sys_, specs, on_motion=True, clock=clock))
    motion = sys_.motion
    result = _decide(*on, sys_, clock=clock, proof_share=0.5, **opts)
    where = f"; on a motion: {motion}{used}"
    if result.kind == "zero":
        return verdict("on-shell", result, result.detail + where + "; not an identity off the motion", sides=on,
                       on_motion=True)
    return verdict("false" if result.kind == "nonzero" else "undecided", result, result.detail + where, sides=on,
                   on_motion=True)


def _with_given(counterexample: dict | None, specs: list) -> dict | None:
    if counterexample is None or not specs:
        return counterexample
    return {**counterexample, "given": {str(s): str(v) for s, v in specs}}
