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
    both sides' values, confirmed at the higher precision below.
``undecided``
    no valid sample point (singular, non-real, outside the domain) or an expression the
    evaluator does not know; the detail says why.

Method, strongest first: ``exact`` — :func:`mechderive.core.simplify.is_zero`, a proof for
rational functions of sines and cosines; ``simplify`` — ``sympy.simplify`` gave 0 within the
time budget (a proof up to SymPy's correctness); ``numeric`` — LHS − RHS vanished to 20 digits
at 30-digit precision *and* to hi − 10 digits at hi-digit precision (hi = 60, or twice the digits
typed plus 40 when the input has long numbers, so that a typed approximation of π is not taken
for π) at each of ``points`` seeded random points, relative to the size of the terms (from a
running error bound): established, not proven; the detail states the chance of a false
positive and its assumption.  Random values are short decimals drawn from each symbol's range
(:meth:`System.sampling_range`:
θ ∈ (0.15, π − 0.15), parameters in (0.5, 2.5), other variables in (−2, 2)), so ``numeric`` and
counterexamples are about that domain (e.g. ``sqrt(1 - u**2) = sin(theta)`` holds there).

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
"""

from __future__ import annotations

import keyword
import random
import signal
import threading
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

import mpmath
import sympy as sp

from ..core.simplify import is_zero
from ..errors import InvalidInputError
from .evaluate import CannotEvaluate, PointRejected, evaluate
from .parse import FUNCTIONS, MAX_LENGTH, dt, parse_claim, parse_expression
from .systems import System, get_system

__all__ = ["Verdict", "check", "EXIT_STATUS"]

#: Exit status of ``mechderive check`` for each verdict (2 is an input error).
EXIT_STATUS = {"identity": 0, "on-shell": 0, "false": 1, "undecided": 3}
_TOL_30 = mpmath.mpf("1e-20")
_DEGREE = 20  # the assumed degree in the false-positive bound
_MAX_GIVEN = 20


@dataclass(frozen=True)
class Verdict:
    """The decision on a claim: ``verdict`` (identity, on-shell, false, undecided), how, and why."""

    verdict: str
    method: str
    detail: str
    counterexample: dict | None = None

    @property
    def exit_status(self) -> int:
        return EXIT_STATUS[self.verdict]

    def as_dict(self) -> dict:
        out: dict[str, Any] = {"verdict": self.verdict, "method": self.method, "detail": self.detail}
        if self.counterexample is not None:
            out["counterexample"] = self.counterexample
        return out


@dataclass(frozen=True)
class _Outcome:
    kind: str  # "zero", "nonzero", "unknown"
    method: str
    detail: str
    counterexample: dict | None = None


# --- time budget for symbolic steps ---------------------------------------------------------------


class _OutOfTime(BaseException):
    """Raised by the alarm; a BaseException so that SymPy's ``except Exception`` does not swallow it."""


@contextmanager
def _budget(seconds: float) -> Iterator[bool]:
    """Yield True and interrupt the block after ``seconds`` (main thread with SIGALRM); else yield False."""
    usable = hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()
    if usable and signal.getitimer(signal.ITIMER_REAL)[0] > 0:
        usable = False  # someone else's timer is armed (e.g. pytest-timeout): leave it alone
    if not usable or seconds <= 0:
        yield False
        return

    def _alarm(signum, frame):
        raise _OutOfTime()

    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield True
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _within(fn: Callable[[], Any], seconds: float, *, unbudgeted_ok: bool) -> tuple[bool, Any]:
    """(finished, result) of ``fn()`` under a time budget; without a usable alarm only if ``unbudgeted_ok``."""
    try:
        with _budget(seconds) as armed:
            if not armed and not unbudgeted_ok:
                return False, None
            return True, fn()
    except _OutOfTime:
        return False, None


# --- parsing the claim and the givens -------------------------------------------------------------


def _parse_givens(given: Sequence[str], system: System) -> tuple[dict, list, list]:
    """(names for parsing, [(symbol, value)] specialisations, [new names]) from ``name = expression`` texts."""
    if isinstance(given, str):
        raise InvalidInputError(f"expected a list of 'name = expression' strings, got the string {given!r}")
    if len(given) > _MAX_GIVEN:
        raise InvalidInputError(f"expected at most {_MAX_GIVEN} --given entries, got {len(given)}")
    names: dict[str, sp.Expr] = dict(system.names)
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
        value = system.expand_definitions(value)
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


# --- deciding LHS − RHS ≡ 0 -------------------------------------------------------------------------


def _trig_args_are_symbols(expr: sp.Expr) -> bool:
    """Whether is_zero's False is a proof: the sines and cosines are of distinct plain symbols only."""
    e = sp.expand_trig(expr.replace(sp.tan, lambda x: sp.sin(x) / sp.cos(x)))
    return all(f.args[0].is_Symbol for f in e.atoms(sp.sin, sp.cos))


def _decimal(r: sp.Rational) -> str:
    return str(sp.Float(r, 6)).rstrip("0").rstrip(".") if r.q != 1 else str(r)


def _high_precision(digits_typed: int) -> int:
    """Digits of the confirming evaluation: 60, more when the input has long numbers.

    A decimal of D digits (or a fraction of D digits in all) can approximate an irrational constant
    to about D digits (2D for a fraction); the confirming precision exceeds that, so a typed
    approximation of π is never taken for π.
    """
    return max(60, 2 * digits_typed + 40)


def _sample(lhs: sp.Expr, rhs: sp.Expr, system: System, points: int, seed: int, hi: int) -> dict:
    """Evaluate both sides at seeded random points (30 then ``hi`` digits): agreements, rejections, a counterexample."""
    syms = sorted((lhs - rhs).free_symbols | lhs.free_symbols | rhs.free_symbols, key=sp.default_sort_key)
    rng = random.Random(seed)
    needed = points if syms else 1
    agreed, rejected, attempts = 0, {}, 0
    while agreed < needed and attempts < 10 * needed:
        attempts += 1
        point = {}
        for s in syms:
            low, high = system.sampling_range(s)
            point[s] = sp.Rational(f"{rng.uniform(low, high):.4f}")
        try:
            results = {}
            for dps in (30, hi):
                (vl, el), (vr, er) = evaluate(lhs, point, dps=dps), evaluate(rhs, point, dps=dps)
                with mpmath.workdps(dps):
                    scale = (el + er) / (2 * mpmath.mp.eps) + abs(vl) + abs(vr)
                    results[dps] = (vl, vr, vl - vr, scale)
        except PointRejected as exc:
            reason = str(exc)
            rejected[reason] = rejected.get(reason, 0) + 1
            continue
        except CannotEvaluate as exc:
            return {"error": str(exc)}
        (l30, r30, d30, s30), (lhi, rhi, dhi, shi) = results[30], results[hi]
        with mpmath.workdps(hi):  # every comparison at the high precision
            ok30 = abs(d30) <= _TOL_30 * s30
            okhi = abs(dhi) <= mpmath.mpf(10) ** (10 - hi) * shi
            if ok30 and okhi:
                agreed += 1
                continue
            if not okhi and abs(dhi - d30) <= _TOL_30 * s30:  # a difference both precisions see
                rel = abs(dhi) / max(abs(lhi), abs(rhi), shi * mpmath.mpf(10) ** -hi)
                return {"counterexample": {
                    "point": {s.name: _decimal(v) for s, v in point.items()},
                    "lhs": mpmath.nstr(lhi, 30), "rhs": mpmath.nstr(rhi, 30),
                    "difference": mpmath.nstr(dhi, 10), "relative difference": mpmath.nstr(rel, 5)}}
        reason = f"the 30- and {hi}-digit values disagree (ill-conditioned)"
        rejected[reason] = rejected.get(reason, 0) + 1
    widths = [system.sampling_range(s)[1] - system.sampling_range(s)[0] for s in syms]
    return {"agreed": agreed, "needed": needed, "rejected": rejected, "attempts": attempts,
            "width": min(widths) if widths else 1.0, "symbols": syms}


def _false_positive_bound(points: int, width: float, hi: int) -> float:
    """(4 (δ/2)^(1/d) / w)^n: Pólya's bound on the measure of {|p| ≤ δ} for a monic degree-d polynomial.

    δ = 10^(10 − hi) is the tolerance of the ``hi``-digit evaluation; the assumption (stated in the
    verdict) is that a nonzero difference is, in some sampled variable of range width w, a
    polynomial of degree ≤ d = 20 whose leading coefficient is at least the size of the terms.
    """
    per_point = min(1.0, 4 * (10.0 ** (10 - hi) / 2) ** (1 / _DEGREE) / width)
    return per_point ** points


def _decide(lhs: sp.Expr, rhs: sp.Expr, system: System, *, points: int, seed: int, budget: float,
            hi: int) -> _Outcome:
    diff = lhs - rhs
    if diff == 0:
        return _Outcome("zero", "exact", "proven: both sides are the same expression")
    if diff.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        return _Outcome("unknown", "none", f"singular: LHS − RHS = {str(diff)[:80]} (division by zero)")
    done, exact = _within(lambda: is_zero(diff), budget, unbudgeted_ok=sp.count_ops(diff) < 400)
    exact = exact if done else None
    if exact:
        return _Outcome("zero", "exact", "proven: LHS − RHS reduces to 0 modulo sin² + cos² = 1 (trig normal form)")
    proven_nonzero = exact is False and _trig_args_are_symbols(diff)
    sample = _sample(lhs, rhs, system, points, seed, hi)
    if "error" in sample:
        return _Outcome("unknown", "none", sample["error"])
    if "counterexample" in sample:
        return _Outcome("nonzero", "numeric", f"LHS ≠ RHS at a random point (confirmed at {hi} digits)",
                        sample["counterexample"])
    if proven_nonzero:
        return _Outcome("nonzero", "exact", "LHS − RHS has a nonzero trig normal form, though it agreed to "
                        f"{hi - 10} digits at every sampled point")
    if sample["agreed"] < sample["needed"]:
        reasons = "; ".join(f"{n}× {r}" for r, n in sorted(sample["rejected"].items(), key=lambda x: -x[1])[:3])
        return _Outcome("unknown", "none", f"only {sample['agreed']} of {sample['attempts']} random points gave "
                        f"trustworthy real values ({reasons})")
    done, simplified = _within(lambda: sp.simplify(diff), budget, unbudgeted_ok=False)
    if done and simplified == 0:
        return _Outcome("zero", "simplify",
                        f"proven: sympy.simplify(LHS − RHS) = 0 (and it agreed numerically at {points} points)")
    n = sample["agreed"]
    if not sample["symbols"]:
        return _Outcome("zero", "numeric", f"not proven: both sides are constants equal to {hi - 10} digits")
    bound = _false_positive_bound(n, sample["width"], hi)
    return _Outcome("zero", "numeric", (
        f"not proven: LHS − RHS vanished to 20 digits at 30-digit precision and to {hi - 10} digits at "
        f"{hi}-digit precision at each of {n} random points; probability of a false positive < {bound:.0e}, assuming a "
        f"nonzero difference would be a polynomial of degree ≤ {_DEGREE} in a sampled variable (Pólya's bound)"))


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


def check(claim: str, system: str = "heavy_top", *, given: Sequence[str] = (), points: int = 20,
          seed: int = 20261121, budget: float = 5.0) -> Verdict:
    """Decide ``claim`` ("LHS = RHS") for ``system`` ("heavy_top" or "free_top"); see the module docstring.

    ``given``: "name = expression" entries (new names or specialisations); ``points``: random
    points of the numeric method (≥ 20); ``seed``: their seed; ``budget``: seconds allowed for
    each symbolic step (is_zero, sympy.simplify).  Input errors raise
    :class:`~mechderive.errors.InvalidInputError`.
    """
    if not isinstance(points, int) or isinstance(points, bool) or not 20 <= points <= 1000:
        raise InvalidInputError(f"expected points between 20 and 1000, got {points!r}")
    if not isinstance(budget, (int, float)) or not 0 <= budget <= 600:
        raise InvalidInputError(f"expected a time budget between 0 and 600 seconds, got {budget!r}")
    sys_ = get_system(system)
    names, specs, new = _parse_givens(given, sys_)
    lhs, rhs = parse_claim(claim, names, hints=sys_.hints)
    typed = sum(ch.isdigit() for text in (claim, *given) for ch in text)
    opts = {"points": points, "seed": seed, "budget": budget, "hi": _high_precision(typed)}
    used = _context([lhs, rhs], sys_, new, specs)

    formal = [_specialise(_expand(x, sys_, on_motion=False), specs) for x in (lhs, rhs)]
    off = _decide(*formal, sys_, **opts)
    if off.kind == "zero":
        return Verdict("identity", off.method, off.detail + used)
    has_derivatives = any(sys_.kind(s) == "derivative" for e in formal for s in e.free_symbols)
    if not has_derivatives:
        if off.kind == "nonzero":
            return Verdict("false", off.method, off.detail + used, _with_given(off.counterexample, specs))
        return Verdict("undecided", off.method, off.detail + used)
    on = [_specialise(_expand(x, sys_, on_motion=True), specs) for x in (lhs, rhs)]
    motion = {"heavy_top": "θ̈, φ̈, ψ̈ from the Euler–Lagrange equations of L = T − V",
              "free_top": "ω̇ from Euler's equations (3.33) without torque"}[sys_.name]
    result = _decide(*on, sys_, **opts)
    where = f"; on a motion: {motion}{used}"
    if result.kind == "zero":
        return Verdict("on-shell", result.method, result.detail + where + "; not an identity off the motion")
    if result.kind == "nonzero":
        return Verdict("false", result.method, result.detail + where, _with_given(result.counterexample, specs))
    return Verdict("undecided", result.method, result.detail + where)


def _with_given(counterexample: dict | None, specs: list) -> dict | None:
    if counterexample is None or not specs:
        return counterexample
    return {**counterexample, "given": {str(s): str(v) for s, v in specs}}
