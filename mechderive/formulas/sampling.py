"""The random points of ``mechderive check``: real bodies by default, every other symbol from its range.

A claim about a system is a claim about its bodies, so by default the parameters a claim
involves are those of a *real* body — the system's :class:`~.systems.BodyRegion` (free top:
positive moments obeying the triangle inequalities; heavy top: I1 ≥ M l² + I3/2 with I1, I3,
M, g, l > 0), drawn inside it by a parametrisation of every real body, never by rejecting
draws.  The state variables and the symbols of no region are drawn uniformly from
:meth:`~.systems.System.sampling_range`.  With ``any_moments`` every parameter is drawn on
its own from its range (positive, any combination).

``--given`` values of region parameters (``I2 = I1``) replace the drawn ones; a draw whose
body the solvers' validator then refuses is rejected and counted, so a specialisation that
leaves no real body ends as ``undecided`` with that reason.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

import mpmath
import sympy as sp

from .evaluate import CannotEvaluate, PointRejected, evaluate
from .systems import System

__all__ = ["PointSampler", "Draw", "decimal_text"]

_GIVEN_REFUSED = "the --given values make a body the solvers refuse"
_GIVEN_DIGITS = 20


def decimal_text(r: sp.Rational) -> str:
    """A short exact text for a drawn value (4-decimal fractions print exactly)."""
    return str(sp.Float(r, 6)).rstrip("0").rstrip(".") if r.q != 1 else str(r)


@dataclass(frozen=True)
class Draw:
    """One random point: values of the symbols; the whole body when the region applied; or why refused."""

    point: dict
    body: dict | None = None
    refusal: str | None = None


class PointSampler:
    """Draws points for the ``symbols`` of a claim (see the module docstring).

    ``specs`` are the --given specialisations [(symbol, value)]; ``condition`` is the region's
    statement when it applies to this claim (None otherwise).
    """

    def __init__(self, system: System, symbols: list, specs: list, *, any_moments: bool) -> None:
        region = None if any_moments else system.region
        self._free = ()  # the parameters drawn each on its own, for the statement
        if any_moments and system.region is not None:
            self._free = tuple(n for n in system.region.parameters if system.names[n] in set(symbols))
        self._system = system
        self._params = {system.names[n]: n for n in region.parameters} if region else {}
        self._specs = []  # each value as the claim sees it: with the later specialisations applied too
        for k, (sym, value) in enumerate(specs):
            if sym in self._params:
                for later, by in specs[k + 1:]:
                    value = value.xreplace({later: by})
                self._specs.append((sym, value))
        self.active = bool(self._specs) or any(s in self._params for s in symbols)
        self._region = region if self.active else None
        needed = set(symbols)
        if self._region is not None:  # the specialised values may use symbols the claim no longer shows
            needed |= set().union(*(v.free_symbols for _, v in self._specs))
        self.symbols = sorted(needed, key=sp.default_sort_key)

    @property
    def condition(self) -> str | None:
        """What the points assume about the body, when that matters to the claim."""
        if self._region is not None:
            return self._region.condition + "; --any-moments (any_moments=True) drops this"
        if self._free:
            return (f"any positive {', '.join(self._free)}, each drawn on its own (--any-moments): "
                    "real bodies or not")
        return None

    def widths(self) -> list[float]:
        """Widths of the independent draws behind the symbols (for the false-positive bound)."""
        out = [self._system.sampling_range(s)[1] - self._system.sampling_range(s)[0]
               for s in self.symbols if self._region is None or s not in self._params]
        if self._region is not None:
            out += list(self._region.widths)
        return out

    def draw(self, rng: random.Random) -> Draw:
        body = self._region.draw(rng) if self._region is not None else {}
        point = {}
        for s in self.symbols:
            if s in self._params and body:
                point[s] = sp.Rational(body[self._params[s]].numerator, body[self._params[s]].denominator)
            else:
                low, high = self._system.sampling_range(s)
                point[s] = sp.Rational(f"{rng.uniform(low, high):.4f}")
        if self._region is None:
            return Draw(point)
        values: dict = {n: sp.Rational(v.numerator, v.denominator) for n, v in body.items()}
        drawn = {**{s: values[n] for s, n in self._params.items()}, **point}
        for sym, value in self._specs:
            if value.is_Rational:
                values[self._params[sym]] = value
                continue
            try:  # the evaluator, not sp.N: it refuses overflow (exp(exp(exp(I1)))) instead of computing it
                values[self._params[sym]] = evaluate(value, drawn, dps=_GIVEN_DIGITS)[0]
            except (PointRejected, CannotEvaluate) as exc:
                return Draw(point, refusal=f"{_GIVEN_REFUSED} ({exc})")
        if self._region.refusal({n: _as_float(v) for n, v in values.items()}) is not None:
            return Draw(point, refusal=_GIVEN_REFUSED)
        shown = {n: decimal_text(v) if isinstance(v, sp.Rational) else mpmath.nstr(v, 10) for n, v in values.items()}
        return Draw(point, body=shown)


def _as_float(v) -> float:
    """A float for the solvers' validators: ±inf beyond the double range (they refuse it, with a message)."""
    with mpmath.workdps(20):
        return float(mpmath.mpf(int(v.p)) / int(v.q) if isinstance(v, sp.Rational) else v)
