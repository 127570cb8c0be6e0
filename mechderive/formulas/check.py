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

import keyword
import math
import random
import time
from dataclasses import dataclass
from typing import Any, Sequence

import mpmath
import sympy as sp

from ..core.simplify import is_zero
from ..errors import InvalidInputError
from .budget import within
from .evaluate import CannotEvaluate
from .parse import FUNCTIONS, MAX_LENGTH, dt, parse_claim, parse_expression
from .sampling import Draw, PointSampler, decimal_text
from .significance import Comparison, compare
from .systems import System, get_system

__all__ = ["Verdict", "check", "EXIT_STATUS"]

#: Exit status of ``mechderive check`` for each verdict (2 is an input error).
EXIT_STATUS = {"identity": 0, "on-shell": 0, "false": 1, "undecided": 3}
_DEGREE = 20  # the assumed degree in the false-positive bound
_MAX_GIVEN = 20


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


# --- parsing the claim and the givens -------------------------------------------------------------


def _parse_givens(given: Sequence[str], system: System, rename: dict | None = None) -> tuple[dict, list, list]:
    """(names for parsing, [(symbol, value)] specialisations, [new names]) from ``name = expression`` texts.

    A specialisation's value has the earlier specialisations substituted (``I2 = I1`` then
    ``I3 = I2`` makes I3 = I1).  ``rename`` maps symbols to stand-ins used throughout (the
    assumption-free parameters of :func:`_positivity_used`).
    """
    rename = rename or {}
    if isinstance(given, str):
        raise InvalidInputError(f"expected a list of 'name = expression' strings, got the string {given!r}")
    if len(given) > _MAX_GIVEN:
        raise InvalidInputError(f"expected at most {_MAX_GIVEN} --given entries, got {len(given)}")
    names: dict[str, sp.Expr] = {n: rename.get(s, s) for n, s in system.names.items()}
    specs: list[tuple[sp.Symbol, sp.Expr]] = []
    new: list[str] = []
    for text in given:
        if not isinstance(text, str) or len(text) > MAX_LENGTH or text.count("=") != 1 or "==" in text:
            raise InvalidInputError(f"expected --given 'name = expression' with one '=', got {str(text)[:80]!r}")
        left, right = (s.strip() for s in text.split("="))
        if not left.isidentifier() or keyword.iskeyword(left) or not left.isascii():
            raise InvalidInputError(
                f"expected --given 'name = expression' with a plain name on the left, got {left[:60]!r}")
        if left in FUNCTIONS or left == "pi":
            raise InvalidInputError(f"expected a name that is not a function or constant, got {left!r}")
        value = parse_expression(right, names, hints=system.hints, what=f"value of {left}")
        if left in new:
            raise InvalidInputError(f"expected each new name defined once, got {left!r} twice")
        if left not in system.names:
            names[left] = value
            new.append(left)
            continue
        sym = system.names[left]
        kind = system.kind(sym)
        if kind not in ("state", "parameter"):
            what = {"defined": "the defined quantity", "derivative": "the time derivative"}.get(kind, "the symbol")
            raise InvalidInputError(
                f"expected --given to define a new name or specialise a state variable or parameter, got {what} "
                f"{left!r} (fixed by {'its definition' if kind == 'defined' else 'the equations of motion'})")
        if value.has(dt):
            raise InvalidInputError(f"expected a value without dt() for {left}, got {right.strip()[:60]!r}")
        value = _specialise(system.expand_definitions(value).xreplace(rename), specs)
        sym = rename.get(sym, sym)
        if value.has(sym):
            raise InvalidInputError(f"expected the value of {left} not to depend on {left}, got {value}")
        if sym.is_positive and value.is_positive is False:
            raise InvalidInputError(f"expected a positive value for {left}, got {value}")
        beyond = sorted(s.name for s in value.free_symbols if system.kind(s) == "derivative")
        if beyond:
            raise InvalidInputError(f"expected the value of {left} in the state and the parameters, got {beyond[0]}")
        specs.append((sym, value))
    return names, specs, new


def _expand(expr: sp.Expr, system: System, *, on_motion: bool) -> sp.Expr:
    """Definitions substituted, dt(...) expanded (formally or along the motion), derivatives on-shell if asked."""
    derivative = system.motion_dt if on_motion else system.formal_dt

    def walk(e: sp.Expr) -> sp.Expr:
        if not e.has(dt):
            return e
        if isinstance(e, dt):
            return derivative(walk(e.args[0]))
        return e.func(*[walk(a) for a in e.args])

    out = walk(system.expand_definitions(expr))
    return system.on_shell(out) if on_motion else out


def _specialise(expr: sp.Expr, specs: list) -> sp.Expr:
    for sym, value in specs:
        expr = expr.xreplace({sym: value})
    return expr


def _sides(lhs: sp.Expr, rhs: sp.Expr, system: System, specs: list, *, on_motion: bool,
           rename: dict | None = None) -> list[sp.Expr]:
    """Both sides expanded (:func:`_expand`), renamed, then specialised."""
    out = []
    for x in (lhs, rhs):
        e = _expand(x, system, on_motion=on_motion)
        out.append(_specialise(e.xreplace(rename) if rename else e, specs))
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
            any_moments: bool, budget: float) -> dict:
    """Compare both sides at seeded random points (:func:`.significance.compare`).

    Returns the agreements, the rejections by reason, or a counterexample.  Evaluations beyond
    ``hi`` digits share a time budget of ``budget`` seconds.
    """
    syms = sorted(lhs.free_symbols | rhs.free_symbols, key=sp.default_sort_key)
    sampler = PointSampler(system, syms, specs, any_moments=any_moments)
    rng = random.Random(seed)
    needed = points if syms else 1
    deadline = time.monotonic() + budget
    agreed, rejected, attempts, digits, agreed_to = 0, {}, 0, [], []
    while agreed < needed and attempts < 10 * needed:
        attempts += 1
        draw = sampler.draw(rng)
        if draw.refusal is not None:
            rejected[draw.refusal] = rejected.get(draw.refusal, 0) + 1
            continue
        try:
            result = compare(lhs, rhs, draw.point, base=hi, deadline=deadline)
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


def _decide(lhs: sp.Expr, rhs: sp.Expr, system: System, *, points: int, seed: int, budget: float,
            hi: int, specs: list, any_moments: bool) -> _Outcome:
    diff = lhs - rhs
    if diff == 0:
        return _Outcome("zero", "exact", "proven: both sides are the same expression")
    if diff.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        return _Outcome("unknown", "none", f"singular: LHS − RHS = {str(diff)[:80]} (division by zero)")
    done, exact = (within(lambda: is_zero(diff), budget, unbudgeted_ok=sp.count_ops(diff) < 400)
                   if _trig_expandable(diff) else (False, None))
    exact = exact if done else None
    if exact:
        return _Outcome("zero", "exact", "proven: LHS − RHS reduces to 0 modulo sin² + cos² = 1 (trig normal form)")
    proven_nonzero = exact is False and _trig_args_are_symbols(diff)
    sample = _sample(lhs, rhs, system, points, seed, hi, specs=specs, any_moments=any_moments, budget=budget)
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
    done, simplified = within(lambda: sp.simplify(diff), budget, unbudgeted_ok=False)
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


def _positivity_used(claim: str, given: Sequence[str], system: System, parsed: tuple, *, on_motion: bool,
                     method: str, budget: float) -> list[str]:
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
    names, specs, _ = _parse_givens(given, system, rename)
    lhs, rhs = parse_claim(claim, names, hints=system.hints)
    lhs0, rhs0, specs0 = parsed
    same = (lhs0.xreplace(rename) == lhs and rhs0.xreplace(rename) == rhs
            and [(rename.get(s, s), v.xreplace(rename)) for s, v in specs0] == specs)
    if same and method == "exact":
        return []
    left, right = _sides(lhs, rhs, system, specs, on_motion=on_motion, rename=rename)
    stand_ins = set(rename.values())
    present = sorted({s.name for s in left.free_symbols | right.free_symbols if s in stand_ins})
    diff = left - right
    if not present or diff == 0:
        return []
    if method == "exact":
        done, proven = within(lambda: is_zero(diff), budget, unbudgeted_ok=sp.count_ops(diff) < 400
                              ) if _trig_expandable(diff) else (False, None)
    else:
        done, simplified = within(lambda: sp.simplify(diff), budget, unbudgeted_ok=False)
        proven = done and simplified == 0
    return [] if done and proven else present


def check(claim: str, system: str = "heavy_top", *, given: Sequence[str] = (), points: int = 20,
          seed: int = 20261121, budget: float = 5.0, any_moments: bool = False) -> Verdict:
    """Decide ``claim`` ("LHS = RHS") for ``system`` ("heavy_top" or "free_top"); see the module docstring.

    ``given``: "name = expression" entries (new names or specialisations); ``points``: random
    points of the numeric method (≥ 20); ``seed``: their seed; ``budget``: seconds allowed for
    each symbolic step (is_zero, sympy.simplify) and, in each numeric step, for all the
    evaluations beyond the base precision (60 digits, more for long typed numbers);
    ``any_moments``: draw the parameters independently (any positive values) instead of only
    those of a real body (:mod:`.sampling`).  What the answer assumes is in
    :attr:`Verdict.assumptions`.  Input errors raise :class:`~mechderive.errors.InvalidInputError`.
    """
    if not isinstance(points, int) or isinstance(points, bool) or not 20 <= points <= 1000:
        raise InvalidInputError(f"expected points between 20 and 1000, got {points!r}")
    if not isinstance(budget, (int, float)) or not 0 <= budget <= 600:
        raise InvalidInputError(f"expected a time budget between 0 and 600 seconds, got {budget!r}")
    if not isinstance(any_moments, bool):
        raise InvalidInputError(f"expected any_moments to be True or False, got {any_moments!r}")
    sys_ = get_system(system)
    names, specs, new = _parse_givens(given, sys_)
    lhs, rhs = parse_claim(claim, names, hints=sys_.hints)
    typed = sum(ch.isdigit() for text in (claim, *given) for ch in text)
    opts = {"points": points, "seed": seed, "budget": budget, "hi": _high_precision(typed), "specs": specs,
            "any_moments": any_moments}
    used = _context([lhs, rhs], sys_, new, specs)

    def verdict(name: str, outcome: _Outcome, detail: str, *, on_motion: bool) -> Verdict:
        assumptions = list(outcome.assumptions)
        if outcome.kind == "zero" and outcome.method in ("exact", "simplify"):
            positive = _positivity_used(claim, given, sys_, (lhs, rhs, specs), on_motion=on_motion,
                                        method=outcome.method, budget=budget)
            if positive:
                assumptions.append(f"{', '.join(positive)} > 0: the proof uses the parameters' positivity")
        example = _with_given(outcome.counterexample, specs)
        return Verdict(name, outcome.method, detail, example, tuple(assumptions))

    formal = _sides(lhs, rhs, sys_, specs, on_motion=False)
    off = _decide(*formal, sys_, **opts)
    if off.kind == "zero":
        return verdict("identity", off, off.detail + used, on_motion=False)
    has_derivatives = any(sys_.kind(s) == "derivative" for e in formal for s in e.free_symbols)
    if not has_derivatives:
        return verdict("false" if off.kind == "nonzero" else "undecided", off, off.detail + used, on_motion=False)
    on = _sides(lhs, rhs, sys_, specs, on_motion=True)
    motion = {"heavy_top": "θ̈, φ̈, ψ̈ from the Euler–Lagrange equations of L = T − V",
              "free_top": "ω̇ from Euler's equations (3.33) without torque"}[sys_.name]
    result = _decide(*on, sys_, **opts)
    where = f"; on a motion: {motion}{used}"
    if result.kind == "zero":
        return verdict("on-shell", result, result.detail + where + "; not an identity off the motion", on_motion=True)
    return verdict("false" if result.kind == "nonzero" else "undecided", result, result.detail + where,
                   on_motion=True)


def _with_given(counterexample: dict | None, specs: list) -> dict | None:
    if counterexample is None or not specs:
        return counterexample
    return {**counterexample, "given": {str(s): str(v) for s, v in specs}}
