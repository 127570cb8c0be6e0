"""Small oscillations and stability about an equilibrium or a steady motion, derived for any system.

Two entry points, one result type (:class:`Linearization`):

* :func:`linearize_lagrangian` — a system given by its Lagrangian L(q, q̇).  The cyclic
  coordinates (∂L/∂q_c ≡ 0) are eliminated by Routh's procedure
  (:class:`~mechderive.core.lagrangian.LagrangianModel`): their momenta p_c = ∂L/∂q̇_c are
  fixed at the values the point gives, and the Routhian R = L − Σ p_c q̇_c is a Lagrangian of
  the remaining coordinates q_r.  A *relative equilibrium* (a steady motion: the q_r at rest,
  the cyclic coordinates turning at constant rates — a conical pendulum, a precessing or
  sleeping top) is an equilibrium of R: ∂R/∂q_r = 0 at q̇_r = 0; this is checked.  Expanding R
  to second order about it, R₂ = ½ δq̇ᵀM δq̇ + δq̇ᵀC δq − ½ δqᵀK δq, gives

      M δq̈ + G δq̇ + K δq = 0,   G = C − Cᵀ (gyroscopic, from the reduction),

  the characteristic polynomial det(M λ² + G λ + K) and its roots.  Perturbations that keep
  the conserved momenta are covered; one that changes a p_c moves to a neighbouring steady
  motion (Routh's notion of stability of a steady motion).
* :func:`linearize_first_order` — a first-order system ẋ = F(x) (Euler's equations (3.33)
  about a steady rotation): δẋ = J δx with J = ∂F/∂x at the point (checked F = 0 there),
  characteristic polynomial det(λ − J).

The point is given by ``at``: values of the remaining coordinates and, for a cyclic one, of
its velocity ``q_dot`` or its momentum ``p_q`` (default: velocity 0); the remaining velocities
are 0 (given or not).  Values and parameters may be numbers or SymPy expressions; parameters
not given stay symbols, so that e.g. the free top's A of (3.44) and the sleeping top's
criterion (3.83) come out as formulas.  A point where the coordinates are singular (θ = 0 of
Euler angles for the sleeping top) is handled when the reduced Lagrangian is smooth there:
the expansion is then taken as a series along δ (a removable 0/0).

Eigenvalues are exact where SymPy finds them in closed form (factors of degree ≤ 2 in λ, or
in μ = λ² for a conservative system, whose polynomial is even), else numeric (mpmath at
40 digits) when every parameter is a number.  Oscillation frequencies are the positive
imaginary parts of the eigenvalues on the imaginary axis (rad per unit time), growth rates
the positive real parts.  :attr:`Linearization.stable` is the *linear* verdict: True when no
eigenvalue has a positive real part and those on the imaginary axis are semisimple (no
secular drift) — for a conservative system this is marginal (the linearization does not decide
nonlinear stability; :attr:`Linearization.verdict` says so); None when it depends on symbolic
parameters (then :attr:`Linearization.condition` states it where it can be derived).

The simple pendulum, hanging down:

>>> g, l = sp.symbols("g l", positive=True)
>>> th, th_dot = sp.symbols("theta theta_dot", real=True)
>>> lin = linearize_lagrangian(l**2 * th_dot**2 / 2 + g * l * sp.cos(th), [th], [th_dot], {th: 0})
>>> lin.K, lin.frequencies, lin.stable
(Matrix([[g*l]]), (sqrt(g)/sqrt(l),), True)
>>> linearize_lagrangian(l**2 * th_dot**2 / 2 + g * l * sp.cos(th), [th], [th_dot], {th: sp.pi}).growth_rates
(sqrt(g)/sqrt(l),)
"""

from __future__ import annotations

import functools
import math
import numbers
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Mapping, Sequence

import sympy as sp

from ..errors import DerivationError, InvalidInputError
from .lagrangian import LagrangianModel, vanishes
from .simplify import trig_normal
from .symbols import as_symbolic, coordinate, t

__all__ = ["Linearization", "linearize_lagrangian", "linearize_first_order", "linearization_derivation",
           "parse_point", "LAMBDA"]

#: The eigenvalue symbol of the characteristic polynomials.
LAMBDA = sp.Symbol("lambda")

#: Working precision (digits) of the numeric roots and of the decisions made on numbers.
_DIGITS = 40
#: |x| below this (relative to the scale of the numbers it is compared with) is zero: numeric roots
#: at 40 digits are accurate to ~1e-38 (simple) and ~1e-19 (double roots), so 1e-15 separates a
#: true zero (or a real root's rounding-level imaginary part) from any physical value.
_ZERO = 1e-15


# ------------------------------------------------------------------------------------ result
@dataclass(frozen=True)
class Linearization:
    """A derived linearization and its spectrum (see the module docstring for the conventions).

    ``kind`` is ``"lagrangian"`` (M δq̈ + G δq̇ + K δq = 0 in the remaining coordinates
    ``variables``; ``jacobian`` is None) or ``"first_order"`` (δẋ = J δx, ``jacobian`` = J;
    ``M``, ``G``, ``K`` are None).  ``point`` maps each coordinate (or state) symbol and each
    velocity to its value; ``cyclic`` lists the eliminated coordinates and ``momenta`` their
    conserved momenta {p_c: value}.  ``characteristic_polynomial`` is monic in :data:`LAMBDA`.
    ``eigenvalues`` lists every root with its multiplicity (exact when ``exact``, else
    40-digit floats; empty when neither is possible); ``squared_frequencies`` holds ω² = −λ²
    for each root pair of a polynomial even in λ (conservative systems), exact, one per pair:
    ω² > 0 oscillates at ω, ω² < 0 grows at √(−ω²).  ``frequencies`` (rad per unit time) and
    ``growth_rates`` (per unit time) are exact or numeric, one per mode; ``stable``,
    ``verdict``, ``condition`` as in the module docstring.
    """

    kind: str
    variables: tuple
    point: dict
    cyclic: tuple
    momenta: dict
    M: sp.Matrix | None
    G: sp.Matrix | None
    K: sp.Matrix | None
    jacobian: sp.Matrix | None
    characteristic_polynomial: sp.Poly
    eigenvalues: tuple
    exact: bool
    squared_frequencies: tuple
    frequencies: tuple
    growth_rates: tuple
    stable: bool | None
    verdict: str
    condition: Any = None
    numeric_eigenvalues: tuple | None = field(default=None)

    # --- the equations --------------------------------------------------------------------
    def perturbation_symbols(self) -> tuple[tuple, tuple, tuple]:
        """(δq, δq̇, δq̈) as symbols ``delta_<q>``, ``delta_<q>_dot``, ``delta_<q>_ddot`` (first order: δx, δẋ, ())."""
        names = [f"delta_{v.name}" for v in self.variables]
        dq = tuple(sp.Symbol(n, real=True) for n in names)
        dv = tuple(sp.Symbol(n + "_dot", real=True) for n in names)
        da = tuple(sp.Symbol(n + "_ddot", real=True) for n in names) if self.kind == "lagrangian" else ()
        return dq, dv, da

    @property
    def equations(self) -> sp.Matrix:
        """The linearized equations, each = 0: M δq̈ + G δq̇ + K δq, or δẋ − J δx."""
        dq, dv, da = (sp.Matrix(x) if x else None for x in self.perturbation_symbols())
        if self.kind == "lagrangian":
            blocks = ((self.M, da), (self.G, dv), (self.K, dq))
        else:
            blocks = ((sp.eye(len(self.variables)), dv), (-self.jacobian, dq))
        n = len(self.variables)
        return sp.Matrix([sp.Add(*[_tidy(A[i, j]) * x[j] for A, x in blocks for j in range(n)]) for i in range(n)])

    def state_matrix(self) -> sp.Matrix:
        """A of δẋ = A δx: J itself, or [[0, 1], [−M⁻¹K, −M⁻¹G]] for a Lagrangian system (x = (δq, δq̇))."""
        if self.kind != "lagrangian":
            return self.jacobian
        n = self.M.shape[0]
        Minv = self.M.inv()
        return sp.Matrix(sp.BlockMatrix([[sp.zeros(n), sp.eye(n)], [-Minv * self.K, -Minv * self.G]]))

    # --- rendering ------------------------------------------------------------------------
    def _point_text(self) -> str:
        return ", ".join(f"{k} = {_show(v)}" for k, v in self.point.items())

    def text(self) -> str:
        """A plain-text report: the point, the matrices, the polynomial, the spectrum and the verdict.

        Exact numbers too long to read (decimals made exact, cos(7/10), …) are shown to 12 digits.
        """
        lines = [f"linearization about {self._point_text()}"]
        if self.cyclic:
            lines.append("  cyclic coordinates eliminated (Routh): " + ", ".join(map(str, self.cyclic))
                         + "; conserved momenta " + ", ".join(f"{k} = {_show(v)}" for k, v in self.momenta.items()))
        names = ", ".join(map(str, self.variables))
        if self.kind == "lagrangian":
            lines.append(f"  M δq̈ + G δq̇ + K δq = 0, q = ({names})")
            for label, m in (("M", self.M), ("G", self.G), ("K", self.K)):
                lines.append(f"  {label} = {_show_matrix(m)}")
        else:
            lines.append(f"  δẋ = J δx, x = ({names})")
            lines.append(f"  J = {_show_matrix(self.jacobian)}")
        lines.append(f"  characteristic polynomial: {_show(self.polynomial_expression())} = 0")
        if self.squared_frequencies:
            lines.append("  ω² = −λ² (per root pair): " + ", ".join(map(_show, self.squared_frequencies)))
        lines.append("  eigenvalues" + (" (exact)" if self.exact else " (numeric)") + ": "
                     + (", ".join(map(_show, self.eigenvalues)) or "not available"))
        if self.numeric_eigenvalues is not None and self.exact and any(
                _show(e) != _complex_text(z) for e, z in zip(self.eigenvalues, self.numeric_eigenvalues)):
            lines.append("  numerically: " + ", ".join(_complex_text(z) for z in self.numeric_eigenvalues))
        lines.append("  frequencies (rad/s): " + (", ".join(_value_text(f) for f in self.frequencies) or "none"))
        lines.append("  growth rates (1/s): " + (", ".join(_value_text(r) for r in self.growth_rates) or "none"))
        lines.append(f"  {self.verdict}")
        return "\n".join(lines)

    def polynomial_expression(self) -> sp.Expr:
        """The characteristic polynomial as an expression with each coefficient factored (for printing)."""
        coeffs = self.characteristic_polynomial.all_coeffs()
        n = len(coeffs) - 1
        return sp.Add(*[_tidy(c) * LAMBDA ** (n - i) for i, c in enumerate(coeffs)])

    def latex(self) -> str:
        """A LaTeX rendering: the linearized equations, the characteristic polynomial and the spectrum."""
        rename = {}
        for v, *deltas in zip(self.variables, *[x for x in self.perturbation_symbols() if x]):
            base = sp.latex(v)
            for d, accent in zip(deltas, ("{%s}", r"\dot{%s}", r"\ddot{%s}")):
                rename[d] = sp.Symbol(r"\delta " + accent % base)
        parts = [r"\begin{aligned}"]
        for e in self.equations:
            parts.append(sp.latex(e.xreplace(rename)) + r" &= 0 \\")
        parts.append(sp.latex(self.polynomial_expression()) + r" &= 0 \\")
        if self.eigenvalues:
            parts.append(r"\lambda &\in \left\{" + ", ".join(sp.latex(e) for e in self.eigenvalues) + r"\right\} \\")
        if self.frequencies:
            parts.append(r"\omega &\in \left\{" + ", ".join(sp.latex(f) for f in self.frequencies) + r"\right\} \\")
        if self.growth_rates:
            parts.append(r"\sigma &\in \left\{" + ", ".join(sp.latex(r) for r in self.growth_rates) + r"\right\} \\")
        parts.append(r"\end{aligned}")
        return "\n".join(parts)

    def __str__(self) -> str:
        return self.text()


#: An exact number printed longer than this is shown to 12 digits instead.
_READABLE = 40


def _show(x: Any) -> str:
    """``x`` as text; a number without symbols whose exact form is long, to 12 significant digits."""
    x = sp.sympify(x, strict=True)
    text = sp.sstr(x)
    if x.is_Rational and x.q > 1000:  # a decimal made exact
        return f"{float(x):.15g}"
    if len(text) <= _READABLE:
        return text
    if not x.free_symbols:
        return _complex_text(complex(x.evalf(17)))
    if isinstance(x, sp.Poly) or not isinstance(x, sp.Expr):
        return text
    return sp.sstr(sp.N(x, 12))


def _show_matrix(m: sp.Matrix) -> str:
    return "[" + ", ".join("[" + ", ".join(_show(e) for e in row) + "]" for row in m.tolist()) + "]"


def _value_text(x: Any) -> str:
    x = sp.sympify(x, strict=True)
    if x.free_symbols:
        return sp.sstr(x)
    shown = _complex_text(complex(x.evalf(17)))
    exact = sp.sstr(x)
    return shown if isinstance(x, sp.Float) or exact == shown or len(exact) > _READABLE else f"{exact} ≈ {shown}"


def _complex_text(z: complex) -> str:
    if z.imag == 0:
        return f"{z.real:.12g}"
    return f"{z.real:.12g}{z.imag:+.12g}i"


# ------------------------------------------------------------------------------------ inputs
def _exact_number(value: Any, what: str) -> sp.Expr:
    """A value as a SymPy expression; a Python or NumPy float becomes the rational its shortest repr writes."""
    if isinstance(value, bool):
        raise InvalidInputError(f"expected {what} to be a number or a SymPy expression, got {value!r}")
    if isinstance(value, numbers.Real) and not isinstance(value, (numbers.Integral, sp.Basic)):
        x = float(value)
        if not math.isfinite(x):
            raise InvalidInputError(f"expected {what} to be finite, got {x!r}")
        f = Fraction(repr(x))
        return sp.Rational(f.numerator, f.denominator)
    expr = as_symbolic(value, what)
    if not isinstance(expr, sp.Expr):
        raise InvalidInputError(f"expected {what} to be a scalar, got {type(expr).__name__}")
    if expr.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise InvalidInputError(f"expected {what} to be finite, got {expr}")
    return expr


def _symbol_list(values: Any, what: str) -> tuple[sp.Symbol, ...]:
    if isinstance(values, (str, sp.Basic)) or not hasattr(values, "__iter__"):
        raise InvalidInputError(f"expected {what} as a sequence of SymPy symbols, got {values!r}")
    out = tuple(values)
    if not out:
        raise InvalidInputError(f"expected at least one of the {what}, got none")
    for s in out:
        if not isinstance(s, sp.Symbol):
            raise InvalidInputError(f"expected each of the {what} to be a SymPy symbol, got {s!r}")
    if len(set(out)) != len(out):
        raise InvalidInputError(f"expected distinct {what}, got {list(out)}")
    return out


def _key_lookup(keys: Sequence[sp.Symbol]) -> dict:
    look: dict[Any, sp.Symbol] = {}
    for k in keys:
        look[k] = k
        look.setdefault(k.name, k)
    return look


def _parameter_values(parameters: Mapping[Any, Any] | None, protected: Sequence[sp.Symbol],
                      free: set) -> dict:
    """{symbol: value} for ``parameters`` (keys: symbols or their names, among the free symbols ``free``)."""
    if parameters is None:
        return {}
    if not isinstance(parameters, Mapping):
        raise InvalidInputError(f"expected parameters as a mapping {{symbol or name: value}}, got {parameters!r}")
    names = {s.name: s for s in free}
    out = {}
    for key, value in parameters.items():
        sym = key if isinstance(key, sp.Symbol) else names.get(key) if isinstance(key, str) else None
        if sym is None or sym not in free:
            shown = key.name if isinstance(key, sp.Symbol) else key
            known = ", ".join(sorted(s.name for s in free)) or "none"
            raise InvalidInputError(f"expected parameters among the equations' symbols ({known}), got {shown!r}")
        if sym in protected:
            raise InvalidInputError(f"expected parameters, got the coordinate or state {sym.name!r}; give it in `at`")
        out[sym] = _exact_number(value, f"parameter {sym.name}")
        if out[sym].free_symbols & set(protected):
            raise InvalidInputError(f"expected the value of parameter {sym.name} free of the coordinates and "
                                    f"velocities, got {out[sym]}")
    return out


# ------------------------------------------------------------------------------- expansions
def _finite(e: sp.Expr) -> bool:
    return not e.has(sp.zoo, sp.nan, sp.oo, -sp.oo)


def _tidy(e: Any) -> sp.Expr:
    """An exact, short form: the trig normal form, factored; numbers kept exact."""
    e = sp.sympify(e, strict=True)
    if e == 0 or e.is_Number:
        return e
    try:
        out = sp.factor(trig_normal(e))
    except (sp.PolynomialError, sp.polys.polyerrors.PolificationFailed, TypeError, ValueError):
        out = sp.cancel(e)
    out = out if sp.count_ops(out) <= sp.count_ops(e) else e
    if out.has(sp.sqrt(sp.Wild("w")).func) and not out.free_symbols:  # √(3 + 2√2) = 1 + √2
        nested = sp.sqrtdenest(out)
        out = nested if sp.count_ops(nested) < sp.count_ops(out) else out
    return out


def _ray_taylor(expr: sp.Expr, eps: sp.Symbol, order: int) -> list[sp.Expr]:
    """[c0, …, c_order]: Taylor coefficients of expr(ε) at ε = 0, by differentiation (cheap on a ray)."""
    out, d = [], expr
    for k in range(order + 1):
        out.append(sp.expand(d.xreplace({eps: 0}) / math.factorial(k)))
        if k < order:
            d = d.diff(eps)
    return out


#: Highest order to which the denominator of a removable 0/0 is allowed to vanish along a ray.
_MAX_VALUATION = 8


def _series_coefficients(expr: sp.Expr, shifts: dict, order: int, where: str) -> list[sp.Expr]:
    """[c0, c1, …, c_order] of expr(x0 + ε δ) in ε, each polynomial in the δ; raises where expr is singular.

    ``shifts`` maps each symbol to (x0, δ).  The terms whose denominator vanishes at x0 (a removable
    0/0, e.g. the Routhian's p²(1 − cos θ)/sin²θ at θ = 0) are expanded as N(ε)/D(ε): D's first
    nonzero Taylor coefficient, at order k, must be matched by N vanishing to order k; the quotient's
    coefficients are polynomials in δ when the expression is smooth at x0 (else the limit depends
    on the direction, and the coordinates are singular there).
    """
    eps = sp.Dummy("epsilon")
    point = {s: v for s, (v, _) in shifts.items()}
    ray = {s: v + eps * d for s, (v, d) in shifts.items()}
    regular, singular = [], []
    for term in sp.Add.make_args(sp.expand(expr)):
        den = sp.fraction(sp.together(term))[1]
        (singular if _is_zero(den.xreplace(point)) else regular).append(term)
    coeffs = _ray_taylor(sp.Add(*regular).xreplace(ray), eps, order)
    singular_text = f"the terms {sp.sstr(sp.Add(*singular))}"
    if singular:
        num, den = sp.fraction(sp.together(sp.Add(*singular)))
        num, den = num.xreplace(ray), den.xreplace(ray)
        b, k = [], None
        d_k = den
        for j in range(_MAX_VALUATION + order + 1):
            c = sp.expand(d_k.xreplace({eps: 0}) / math.factorial(j))
            b.append(c)
            if k is None and not _is_zero(c):
                k = j
            if k is not None and j >= k + order:
                break
            d_k = d_k.diff(eps)
            if k is None and j == _MAX_VALUATION:
                raise InvalidInputError(f"expected the equations finite at {where}, got {singular_text} "
                                        "with a denominator vanishing there to every order")
        a = _ray_taylor(num, eps, k + order)
        low = [x for x in a[:k] if not _is_zero(x)]
        if low:
            raise InvalidInputError(
                f"expected the equations smooth at {where}, got {singular_text}, infinite there "
                "(the coordinates are singular at this point: use others, or a point where the motion is regular)")
        a, b = a[k:], [sp.Integer(0) if _is_zero(x) else x for x in b[k:]]
        quotient: list[sp.Expr] = []
        for j in range(order + 1):
            rest = a[j] - sum(quotient[i] * b[j - i] for i in range(j))
            quotient.append(sp.cancel(rest / b[0]))
        coeffs = [sp.expand(x + y) for x, y in zip(coeffs, quotient)]
    deltas = [d for _, d in shifts.values()]
    for c in coeffs:
        if not _finite(c) or (deltas and not sp.cancel(c).is_polynomial(*deltas)):
            raise InvalidInputError(
                f"expected the equations smooth at {where}, got {singular_text if singular else 'a term'} whose "
                "limit there depends on the direction of approach (the coordinates are singular at this point)")
    return [sp.expand(sp.cancel(c)) for c in coeffs]


def _check_at_rest(residuals: Sequence[tuple[str, sp.Expr]], rtol: float, what: str) -> None:
    """Raise unless each residual vanishes: exactly (symbols) or within ``rtol`` of its terms' size (numbers)."""
    for label, r in residuals:
        r = sp.expand(r)
        if r == 0:
            continue
        if r.free_symbols:
            if vanishes(r):
                continue
            raise InvalidInputError(
                f"expected {what}, got {label} = {_tidy(r)} ≠ 0 (with symbolic values it must vanish identically: "
                "give the relation among the parameters in `parameters`, e.g. the rate of a steady motion)")
        value = abs(complex(r.evalf(_DIGITS)))
        scale = sum(abs(complex(term.evalf(_DIGITS))) for term in sp.Add.make_args(r))
        if value <= rtol * scale or value == 0:
            continue
        raise InvalidInputError(
            f"expected {what}, got {label} = {value:.3g} ≠ 0 (relative {value / scale:.3g} of its terms' size "
            f"{scale:.3g}, allowed {rtol:g})")


# ----------------------------------------------------------------------------------- spectrum
def _is_zero(c: sp.Expr) -> bool:
    """Whether ``c`` is zero: exactly with symbols; a number below 1e-40 in magnitude (at 50 digits) counts as 0,
    so an exact zero written as e.g. sin²(7/10) + cos²(7/10) − 1 is recognised (use units in which the
    system's numbers are not that small)."""
    c = sp.sympify(c, strict=True)
    if c == 0:
        return True
    if c.free_symbols:
        return vanishes(c)
    return abs(complex(c.evalf(_DIGITS + 10))) < 10.0 ** (-_DIGITS)


def _sign_candidates(e: sp.Expr) -> list[sp.Expr]:
    """``e`` in forms whose sign SymPy's assumptions may decide: as is, factored, and with sin² = 1 − cos²."""
    cands = [e, sp.factor(e)]
    alt = sp.factor(sp.expand(e.replace(sp.sin, lambda x: sp.sqrt(1 - sp.cos(x) ** 2))))
    if not any(p.exp.is_Rational and not p.exp.is_Integer and p.base.has(sp.cos) for p in alt.atoms(sp.Pow)):
        cands.append(alt)
    return cands


def _sign(e: sp.Expr) -> int | None:
    """+1, −1 or 0 for a real expression whose sign is decided (exactly, or at 40 digits for a number), else None."""
    e = sp.sympify(e, strict=True)
    if not e.free_symbols:
        z = complex(e.evalf(_DIGITS))
        return 0 if z.real == 0 else (1 if z.real > 0 else -1)
    for c in _sign_candidates(e):
        if c.is_positive:
            return 1
        if c.is_negative:
            return -1
        if c.is_zero:
            return 0
    return None


def _condition_positive(e: sp.Expr) -> Any:
    """``e > 0`` with the factors known positive dropped and those known negative flipped (odd powers)."""
    num, den = sp.fraction(sp.factor(sp.together(e)))
    parts = [p.as_base_exp() for p in sp.Mul.make_args(num)]
    parts += [(b, -k) for b, k in (p.as_base_exp() for p in sp.Mul.make_args(den))]
    keep, sign = [], 1
    for base, k in parts:
        odd = not (k.is_Integer and int(k) % 2 == 0)
        s = _sign(base)
        if s == 1:
            continue
        if s == -1:
            sign *= -1 if odd else 1
            continue
        keep.append(base ** abs(k))
    lhs = sp.Mul(*keep)
    if lhs == 1:
        return sp.true if sign > 0 else sp.false
    return sp.StrictGreaterThan(lhs, 0) if sign > 0 else sp.StrictLessThan(lhs, 0)


def _numeric_roots(coeffs: Sequence[sp.Expr]) -> list[complex]:
    """Roots of the polynomial with these (numeric) coefficients, highest first, at 40 digits."""
    import mpmath

    with mpmath.workdps(_DIGITS):
        cs = [mpmath.mpmathify(complex(c.evalf(_DIGITS + 5))) if sp.im(c.evalf()) != 0
              else mpmath.mpf(str(c.evalf(_DIGITS + 5))) for c in coeffs]
        if len(cs) == 1:
            return []
        try:
            roots = mpmath.polyroots(cs, maxsteps=400, extraprec=4 * _DIGITS)
        except mpmath.libmp.NoConvergence:  # pragma: no cover - defensive
            import numpy as np

            return [complex(r) for r in np.roots([complex(c) for c in cs])]
        return [complex(r) for r in roots]


@dataclass
class _Spectrum:
    eigenvalues: list
    exact: bool
    squared: list
    frequencies: list
    growth: list
    decay: list
    undecided: bool
    imaginary_axis: list  # (λ exact-or-float, algebraic multiplicity)
    numeric: list | None
    condition: Any


def _analyse(poly: sp.Poly) -> _Spectrum:
    """Roots of the monic characteristic polynomial, classified (see the module docstring)."""
    lam = LAMBDA
    coeffs = list(poly.all_coeffs())  # highest first
    n = len(coeffs) - 1
    k = 0
    while k < n and _is_zero(coeffs[n - k]):
        k += 1
    rest = coeffs[: n - k + 1]  # Q(λ) = P(λ)/λ^k, highest first
    m = len(rest) - 1
    even = all(_is_zero(rest[i]) for i in range(1, m + 1, 2))  # odd powers of Q vanish (m even then)
    numeric_ok = not any(c.free_symbols for c in coeffs)
    mu = sp.Symbol("mu")
    if even:
        reduced = sp.Poly(sum(rest[i] * mu ** ((m - i) // 2) for i in range(0, m + 1, 2)), mu)
    else:
        reduced = sp.Poly(sum(rest[i] * lam ** (m - i) for i in range(m + 1)), lam)
    exact_roots: dict = {}
    if reduced.degree() > 0:
        try:
            exact_roots = sp.roots(reduced, cubics=False, quartics=False)
        except (NotImplementedError, sp.PolynomialError):
            exact_roots = {}
    exact = sum(exact_roots.values()) == reduced.degree()
    spec = _Spectrum([], exact, [], [], [], [], False, [], None, None)
    if k:
        spec.eigenvalues += [sp.Integer(0)] * k
        spec.imaginary_axis.append((sp.Integer(0), k))
    if exact:
        items = [(_tidy(r), mult) for r, mult in exact_roots.items()]
    elif numeric_ok:
        vals = _numeric_roots(reduced.all_coeffs())
        items = _group([complex(v) for v in vals])
    else:
        spec.undecided = True
        spec.exact = False
        spec.eigenvalues = []
        spec.condition = _coefficient_condition(reduced, even) if even else None
        return spec
    for r, mult in items:
        if even:
            spec.squared.append(_tidy(-r) if exact else sp.Float(-r.real, 17) if abs(r.imag) <= _ZERO * abs(r)
                                else sp.Float(-r.real, 17) - sp.I * sp.Float(r.imag, 17))
            _classify_pair(spec, r, mult, exact)
        else:
            _classify_root(spec, r, mult, exact)
    if numeric_ok:
        spec.numeric = [complex(sp.sympify(z, strict=True).evalf(17)) for z in spec.eigenvalues]
    if spec.undecided:
        spec.condition = _coefficient_condition(reduced, even, exact_roots if exact else None)
    return spec


def _group(values: list[complex]) -> list[tuple[complex, int]]:
    """Numeric roots grouped into (value, multiplicity) where they agree to the working accuracy."""
    out: list[list] = []
    for v in values:
        for g in out:
            if abs(v - g[0]) <= 1e-12 * max(1.0, abs(v)):
                g[1] += 1
                break
        else:
            out.append([v, 1])
    return [(complex(v), c) for v, c in out]


def _classify_pair(spec: _Spectrum, r: Any, mult: int, exact: bool) -> None:
    """λ² = r (multiplicity ``mult``): λ = ±√r, on the imaginary axis iff r is real and negative."""
    if exact and r.free_symbols:
        s = _sign(r)
    else:
        z = complex(sp.sympify(r, strict=True).evalf(_DIGITS)) if exact else complex(r)
        s = (0 if z.real == 0 else (1 if z.real > 0 else -1)) if abs(z.imag) <= _ZERO * abs(z) else None
        if s is None:  # complex r: a quartet ±a ± ib
            import cmath

            root = cmath.sqrt(z)
            pair = sp.sqrt(r) if exact else sp.Float(root.real, 17) + sp.I * sp.Float(root.imag, 17)
            spec.eigenvalues += [pair] * mult + [-pair] * mult
            spec.growth += [sp.Float(abs(root.real), 17)] * mult
            return
    if s == -1:
        w = _tidy(sp.sqrt(-r)) if exact else sp.Float(math.sqrt(-z.real), 17)
        spec.eigenvalues += [sp.I * w] * mult + [-sp.I * w] * mult
        spec.frequencies += [w] * mult
        spec.imaginary_axis += [(sp.I * w, mult), (-sp.I * w, mult)]
    elif s == 1:
        g = _tidy(sp.sqrt(r)) if exact else sp.Float(math.sqrt(z.real), 17)
        spec.eigenvalues += [g] * mult + [-g] * mult
        spec.growth += [g] * mult
    elif s == 0:  # pragma: no cover - zero roots were factored out
        spec.eigenvalues += [sp.Integer(0)] * (2 * mult)
    else:
        spec.eigenvalues += [sp.sqrt(r)] * mult + [-sp.sqrt(r)] * mult
        spec.undecided = True


def _classify_root(spec: _Spectrum, r: Any, mult: int, exact: bool) -> None:
    """One root λ = r of a polynomial that is not even."""
    if exact:
        spec.eigenvalues += [r] * mult
        if r.free_symbols:
            re = _sign(sp.re(r))
        else:
            z = complex(r.evalf(_DIGITS))
            re = 0 if abs(z.real) <= _ZERO * abs(z) else (1 if z.real > 0 else -1)
        if re is None:
            spec.undecided = True
        elif re > 0:
            spec.growth += [_tidy(sp.re(r))] * mult
        elif re < 0:
            spec.decay += [_tidy(-sp.re(r))] * mult
        else:
            im = _tidy(sp.im(r))
            if _sign(im) == 1:
                spec.frequencies += [im] * mult
            spec.imaginary_axis.append((r, mult))
        return
    z = complex(r)
    spec.eigenvalues += [sp.Float(z.real, 17) + sp.I * sp.Float(z.imag, 17)] * mult
    if abs(z.real) <= _ZERO * max(abs(z), 1e-300):
        if z.imag > 0:
            spec.frequencies += [sp.Float(z.imag, 17)] * mult
        spec.imaginary_axis.append((1j * z.imag, mult))
    elif z.real > 0:
        spec.growth += [sp.Float(z.real, 17)] * mult
    else:
        spec.decay += [sp.Float(-z.real, 17)] * mult


def _coefficient_condition(reduced: sp.Poly, even: bool, roots: dict | None = None) -> Any:
    """For a polynomial in μ = λ² of degree ≤ 2: every μ real and < 0, as inequalities on its coefficients."""
    if not even:
        return None
    if roots is not None and all(r.is_real for r in roots):
        return sp.And(*[_condition_positive(-r) for r in roots])
    c = reduced.monic().all_coeffs()
    if len(c) == 2:
        return _condition_positive(c[1])
    if len(c) == 3:
        b, q = c[1], c[2]
        return sp.And(_condition_positive(b), _condition_positive(q), _condition_positive(sp.expand(b**2 - 4 * q)))
    return None


def _nullity(matrix: sp.Matrix, value: Any) -> int | None:
    """dim ker of ``matrix`` (λ substituted by ``value``): exact for symbols, SVD on numbers."""
    if isinstance(value, complex):
        value = sp.Float(value.real, 20) + sp.I * sp.Float(value.imag, 20)
    A = matrix.subs(LAMBDA, value)
    if A.free_symbols:
        try:
            return A.shape[1] - A.applyfunc(_tidy).rank(simplify=True)
        except Exception:  # noqa: BLE001 - SymPy's rank can fail in many ways on symbolic entries
            return None
    import numpy as np

    a = np.array(A.evalf(20).tolist(), dtype=complex)
    s = np.linalg.svd(a, compute_uv=False)
    tol = 1e-9 * max(1.0, float(np.max(np.abs(a))) if a.size else 1.0)
    return int(np.sum(s <= tol))


def _finish(kind: str, variables: tuple, point: dict, cyclic: tuple, momenta: dict, M, G, K, J,
            pencil: sp.Matrix) -> Linearization:
    """The characteristic polynomial det(pencil) made monic, its roots classified, the verdict."""
    det = pencil.det(method="berkowitz")
    poly = sp.Poly(sp.expand(det), LAMBDA)
    lead = poly.LC()
    if _is_zero(lead):
        raise InvalidInputError("expected a regular linearization (det M ≠ 0), got a singular mass matrix "
                                f"M = {sp.sstr(M.tolist()) if M is not None else '?'} at this point")
    poly = sp.Poly([_tidy(c / lead) for c in poly.all_coeffs()], LAMBDA)
    spec = _analyse(poly)
    drift: list = []
    if not spec.growth and not spec.undecided:
        for value, mult in spec.imaginary_axis:
            if mult > 1:
                nul = _nullity(pencil, value)
                if nul is None:
                    spec.undecided = True
                elif nul < mult:
                    drift.append(value)
    stable, verdict = _verdict(spec, drift)
    return Linearization(kind, variables, point, cyclic, momenta, M, G, K, J, poly, tuple(spec.eigenvalues),
                         spec.exact, tuple(spec.squared), tuple(spec.frequencies), tuple(spec.growth), stable,
                         verdict, spec.condition, None if spec.numeric is None else tuple(spec.numeric))


def _verdict(spec: _Spectrum, drift: list) -> tuple[bool | None, str]:
    if spec.growth:
        return False, ("unstable: perturbations grow exponentially (eigenvalues with positive real part, growth rates "
                       + ", ".join(_value_text(g) for g in spec.growth) + ")")
    if spec.undecided:
        cond = "" if spec.condition is None else f"; stable (marginally) iff {spec.condition}"
        return None, "undecided for symbolic parameters: the signs of the roots depend on them" + cond
    if drift:
        return False, ("neutral: a repeated eigenvalue on the imaginary axis without a full set of eigenvectors "
                       f"({', '.join(map(_value_text, drift))}) — perturbations drift linearly in t (no exponential "
                       "growth, no restoring oscillation)")
    zeros = sum(mult for value, mult in spec.imaginary_axis if value == 0)
    if spec.decay and not spec.imaginary_axis:
        return True, "asymptotically stable: every eigenvalue has a negative real part"
    note = (f"; {zeros} zero eigenvalue(s): neutral directions (a family of neighbouring equilibria or steady motions)"
            if zeros else "")
    if zeros and not spec.frequencies and not spec.decay:
        return True, "neutral: every eigenvalue is zero (semisimple): perturbations neither grow nor oscillate" + \
            " in the linear approximation"
    where = "on the imaginary axis or in the left half-plane" if spec.decay else "on the imaginary axis"
    return True, (f"stable in the linear approximation, marginally: every eigenvalue is {where}, those on the axis "
                  "semisimple (no secular drift); the linearization alone does not decide nonlinear (Lyapunov) "
                  "stability" + note)


# ------------------------------------------------------------------------------- entry points
def linearize_lagrangian(L: Any, coordinates: Sequence[sp.Symbol], velocities: Sequence[sp.Symbol],
                         at: Mapping[Any, Any], parameters: Mapping[Any, Any] | None = None, *,
                         rtol: float = 1e-10) -> Linearization:
    """Linearize the Lagrangian system L(q, q̇) about an equilibrium or a steady motion (module docstring).

    Parameters
    ----------
    L
        The Lagrangian, a SymPy expression in the plain symbols ``coordinates`` and ``velocities``
        and constant parameters (no explicit t).
    coordinates, velocities
        The symbols q_i and q̇_i, in matching order.
    at
        The point: {symbol or name: value} for every non-cyclic coordinate; for a cyclic one its
        velocity (``phi_dot``) or its momentum (``p_phi``), default velocity 0; non-cyclic
        velocities must be 0 (or absent); cyclic positions are accepted and ignored.
    parameters
        {symbol or name: value} substituted before anything else (numbers, or expressions such as
        ``{g: Omega**2*l*cos(theta0)}`` to make a symbolic point steady); others stay symbols.
    rtol
        For numeric points: the reduced generalised forces ∂R/∂q_r must vanish to ``rtol`` × the
        size of their terms (default 1e-10); with symbols they must vanish identically.

    Raises :class:`~mechderive.errors.InvalidInputError` when ``at`` names an unknown symbol,
    misses a coordinate, is not a (relative) equilibrium (saying which equation fails and by how
    much), or when the reduced Lagrangian is singular at the point.
    """
    L = as_symbolic(L, "the Lagrangian")
    if not isinstance(L, sp.Expr) or getattr(L, "is_Matrix", False):
        raise InvalidInputError(f"expected the Lagrangian as a scalar SymPy expression, got {type(L).__name__}")
    qs = _symbol_list(coordinates, "coordinates")
    vs = _symbol_list(velocities, "velocities")
    if len(qs) != len(vs):
        raise InvalidInputError(f"expected one velocity per coordinate, got {len(qs)} coordinates and {len(vs)} velocities")
    if set(qs) & set(vs):
        raise InvalidInputError(f"expected velocities distinct from the coordinates, got {sorted(set(qs) & set(vs), key=str)}")
    if not isinstance(at, Mapping):
        raise InvalidInputError(f"expected the point `at` as a mapping {{symbol or name: value}}, got {at!r}")
    at = {k: _exact_number(v, f"the value of {getattr(k, 'name', k)} in `at`") for k, v in at.items()}
    pvals = _parameter_values(parameters, qs + vs, L.free_symbols.union(*(v.free_symbols for v in at.values())))
    if any(s.name == "t" for s in L.free_symbols) or L.has(t):
        raise InvalidInputError("expected an autonomous Lagrangian (no explicit t): a time-dependent system has no "
                                "equilibria in this sense")
    funcs = [coordinate(q.name) for q in qs]
    to_t = {**{q: f for q, f in zip(qs, funcs)}, **{v: f.diff(t) for v, f in zip(vs, funcs)}}
    model = _reduction(L.xreplace(to_t), tuple(funcs))
    inner_q, inner_v = model.positions, model.velocities
    cyclic = model.cyclic_coordinates
    cyc_idx = [funcs.index(c) for c in cyclic]
    rem_idx = [i for i in range(len(qs)) if i not in cyc_idx]
    if not rem_idx:
        raise InvalidInputError(
            f"expected at least one non-cyclic coordinate, got every coordinate cyclic ({', '.join(q.name for q in qs)}): "
            "every motion at constant rates is steady, and the perturbations only change the rates")
    psyms = [model.momentum_symbols[c] for c in cyclic] if cyclic else []

    look = _key_lookup([*qs, *vs, *psyms])
    given: dict = {}
    for key, value in dict(at).items():
        sym = look.get(key) if isinstance(key, (str, sp.Symbol)) else None
        if sym is None:
            allowed = ", ".join([*(qs[i].name for i in rem_idx), *(vs[i].name for i in cyc_idx),
                                 *(p.name for p in psyms)])
            shown = key.name if isinstance(key, sp.Symbol) else key
            raise InvalidInputError(f"expected the point `at` to give values of {allowed}, got {shown!r}")
        if sym in given:
            raise InvalidInputError(f"expected each of `at`'s names once, got {sym.name} twice")
        given[sym] = value.xreplace(pvals)
        if given[sym].free_symbols & (set(qs) | set(vs)):
            raise InvalidInputError(f"expected the value of {sym.name} free of the coordinates and velocities, "
                                    f"got {given[sym]}")

    point: dict = {}
    for i in rem_idx:
        if qs[i] not in given:
            raise InvalidInputError(f"expected a value of {qs[i].name} in the point `at` (a non-cyclic coordinate), "
                                    "got none")
        point[qs[i]] = given[qs[i]]
    for i in rem_idx:
        v = given.get(vs[i], sp.Integer(0))
        if not _is_zero(v):
            raise InvalidInputError(
                f"expected {vs[i].name} = 0 in `at` (an equilibrium or steady motion has the non-cyclic coordinates at "
                f"rest; cyclic ones: {', '.join(qs[j].name for j in cyc_idx) or 'none'}), got {v}")
    inner = {inner_q[i]: point[qs[i]] for i in rem_idx}
    inner.update({inner_v[i]: 0 for i in rem_idx})
    momenta: dict = {}
    cyc_rates = {}
    for j, c, p in zip(cyc_idx, cyclic, psyms):
        if vs[j] in given and p in given:
            raise InvalidInputError(f"expected {vs[j].name} or {p.name} in `at`, not both")
        if p in given:
            momenta[p] = given[p]
        else:
            cyc_rates[inner_v[j]] = given.get(vs[j], sp.Integer(0))
    for j, c, p in zip(cyc_idx, cyclic, psyms):
        if p not in momenta:
            momenta[p] = _tidy(model.momenta[j].xreplace(pvals).xreplace({**inner, **cyc_rates}))
        if qs[j] in given:
            pass  # the position of a cyclic coordinate does not enter: any value is the same steady motion
    for j in cyc_idx:
        if vs[j] in given:
            point[vs[j]] = given[vs[j]]
    for i in rem_idx:
        point[vs[i]] = sp.Integer(0)

    # the model is of the Lagrangian as given (parameters symbolic: its Routhian is derived once per
    # system, and the cyclic coordinates do not depend on the values); the numbers go in here
    R = (model.routhian if cyclic else model.state_lagrangian).xreplace(pvals).xreplace(momenta)
    rq = [inner_q[i] for i in rem_idx]
    rv = [inner_v[i] for i in rem_idx]
    names = [qs[i].name for i in rem_idx]
    where = ", ".join(f"{k} = {v}" for k, v in point.items())
    Q, Mm, C, H = _quadratic_lagrangian(R, rq, rv, [point[qs[i]] for i in rem_idx], where)
    try:
        _check_at_rest([(f"∂R/∂{n} (the {n} equation of motion at rest)" if cyclic else f"∂L/∂{n} (the {n} "
                         "equation of motion at rest)", q) for n, q in zip(names, Q)], rtol,
                       "a relative equilibrium (the reduced generalised forces vanish)" if cyclic else
                       "an equilibrium (the generalised forces vanish)")
    except InvalidInputError as exc:
        hint = _steady_rate_hint(model, pvals, inner, rq, cyc_idx, psyms, given, vs) if len(rq) == 1 else ""
        raise InvalidInputError(f"{exc}{hint}") from None
    Mm = Mm.applyfunc(_tidy)
    G = (C - C.T).applyfunc(_tidy)
    K = (-H).applyfunc(_tidy)
    pencil = Mm * LAMBDA**2 + G * LAMBDA + K
    momenta_out = {p: momenta[p] for p in psyms}
    return _finish("lagrangian", tuple(qs[i] for i in rem_idx), point, tuple(qs[j] for j in cyc_idx), momenta_out,
                   Mm, G, K, None, pencil)


def _steady_rate_hint(model, pvals: dict, inner: dict, rq: list, cyc_idx: list, psyms: list, given: dict,
                      vs: tuple) -> str:
    """'; steady motions here have phi_dot = …' when one cyclic rate was given as a number and missed."""
    rated = [j for j, p in zip(cyc_idx, psyms) if vs[j] in given and p not in given]
    if len(rated) != 1 or len(cyc_idx) != 1:
        return ""
    j, (p,) = rated[0], psyms
    r = sp.Dummy("rate")
    momentum = model.momenta[j].xreplace(pvals).xreplace({**inner, model.velocities[j]: r})
    R = model.routhian.xreplace(pvals).xreplace({p: momentum})
    try:
        Q = sp.together(R.diff(rq[0]).xreplace(inner))
        if Q.free_symbols != {r} or not _finite(Q):
            return ""
        num = sp.Poly(sp.numer(Q), r)
        roots = [complex(x) for x in num.nroots(n=15)]
    except (sp.PolynomialError, sp.polys.polyerrors.PolificationFailed, ValueError, TypeError,
            NotImplementedError, sp.polys.polyerrors.NoConvergence):
        return ""
    real = sorted(z.real for z in roots if abs(z.imag) <= 1e-12 * max(1.0, abs(z)))
    if not real:
        return f"; no steady motion at this point has a real {vs[j].name}"
    return f"; steady motions at this point have {vs[j].name} = " + " or ".join(f"{x:.15g}" for x in real)


@functools.lru_cache(maxsize=32)
def _reduction(L: sp.Expr, coordinates: tuple) -> LagrangianModel:
    """The Lagrangian model of L, shared by the calls on one system (its Routhian is derived once)."""
    return LagrangianModel(L, coordinates)


def _quadratic_lagrangian(R: sp.Expr, rq: list, rv: list, values: list, where: str):
    """(∂R/∂q, M, C, H) at q = values, q̇ = 0: R₂ = ½ q̇ᵀMq̇ + q̇ᵀC q + ½ qᵀH q; a series where 0/0."""
    at = {**dict(zip(rq, values)), **{v: 0 for v in rv}}
    n = len(rq)
    try:
        Q = [R.diff(q).xreplace(at) for q in rq]
        M = sp.Matrix(n, n, lambda i, j: R.diff(rv[i], rv[j]).xreplace(at))
        C = sp.Matrix(n, n, lambda i, j: R.diff(rv[i], rq[j]).xreplace(at))
        H = sp.Matrix(n, n, lambda i, j: R.diff(rq[i], rq[j]).xreplace(at))
        if all(_finite(e) for e in [*Q, *M, *C, *H]):
            return Q, M, C, H
    except (ZeroDivisionError, ValueError):
        pass
    dq = [sp.Dummy(f"d{q.name}") for q in rq]
    dv = [sp.Dummy(f"d{v.name}") for v in rv]
    shifts = {**{q: (x, d) for q, x, d in zip(rq, values, dq)}, **{v: (0, d) for v, d in zip(rv, dv)}}
    c = _series_coefficients(R, shifts, 2, where)
    Q = [c[1].diff(d) for d in dq]
    if any(e.has(*dq, *dv) for e in Q):  # pragma: no cover - c1 is linear
        raise DerivationError(f"expected the first-order term linear in the perturbation, got {c[1]}")
    M = sp.Matrix(n, n, lambda i, j: c[2].diff(dv[i], dv[j]))
    C = sp.Matrix(n, n, lambda i, j: c[2].diff(dv[i], dq[j]))
    H = sp.Matrix(n, n, lambda i, j: c[2].diff(dq[i], dq[j]))
    return Q, M, C, H


def linearize_first_order(rhs: Any, state: Sequence[sp.Symbol], at: Mapping[Any, Any],
                          parameters: Mapping[Any, Any] | None = None, *, rtol: float = 1e-10) -> Linearization:
    """Linearize ẋ = F(x) about a steady point x0 (F(x0) = 0): δẋ = J δx, J = ∂F/∂x at x0.

    ``rhs`` is F (a list or column of SymPy expressions in ``state`` and parameters), ``state``
    the symbols x in the same order, ``at`` {symbol or name: value} for every state component,
    ``parameters`` and ``rtol`` as in :func:`linearize_lagrangian`.  Euler's equations (3.33)
    about a spin Ω about e1 give det(λ − J) = λ(λ² − A/I2) with A of (3.44).

    >>> I1, I2, I3 = sp.symbols("I1 I2 I3", positive=True)
    >>> w = sp.symbols("omega1:4", real=True)
    >>> F = [(I2 - I3) * w[1] * w[2] / I1, (I3 - I1) * w[2] * w[0] / I2, (I1 - I2) * w[0] * w[1] / I3]
    >>> lin = linearize_first_order(F, w, {w[0]: 2, w[1]: 0, w[2]: 0}, {I1: 2, I2: 1, I3: 3})
    >>> lin.growth_rates, lin.stable
    ((2*sqrt(3)/3,), False)
    """
    F = as_symbolic(rhs, "the right-hand side")
    if not isinstance(F, sp.MatrixBase):
        F = sp.Matrix([F])
    F = sp.Matrix(list(F))
    xs = _symbol_list(state, "state")
    if len(F) != len(xs):
        raise InvalidInputError(f"expected one right-hand side per state component, got {len(F)} for {len(xs)}")
    if not isinstance(at, Mapping):
        raise InvalidInputError(f"expected the point `at` as a mapping {{symbol or name: value}}, got {at!r}")
    at = {k: _exact_number(v, f"the value of {getattr(k, 'name', k)} in `at`") for k, v in at.items()}
    free = set().union(*(e.free_symbols for e in F), *(v.free_symbols for v in at.values()))
    pvals = _parameter_values(parameters, xs, free)
    F = F.xreplace(pvals)
    if any(s.name == "t" for s in F.free_symbols):
        raise InvalidInputError("expected an autonomous system (no explicit t)")
    look = _key_lookup(xs)
    point: dict = {}
    for key, value in dict(at).items():
        sym = look.get(key) if isinstance(key, (str, sp.Symbol)) else None
        if sym is None:
            shown = key.name if isinstance(key, sp.Symbol) else key
            raise InvalidInputError(f"expected the point `at` to give values of {', '.join(x.name for x in xs)}, "
                                    f"got {shown!r}")
        if sym in point:
            raise InvalidInputError(f"expected each of `at`'s names once, got {sym.name} twice")
        point[sym] = value.xreplace(pvals)
    missing = [x.name for x in xs if x not in point]
    if missing:
        raise InvalidInputError(f"expected a value of every state component in `at`, got none for {', '.join(missing)}")
    point = {x: point[x] for x in xs}
    where = ", ".join(f"{k} = {v}" for k, v in point.items())
    n = len(xs)
    F0 = [f.xreplace(point) for f in F]
    J = sp.Matrix(n, n, lambda i, j: F[i].diff(xs[j]).xreplace(point))
    if not all(_finite(e) for e in [*F0, *J]):
        d = [sp.Dummy(f"d{x.name}") for x in xs]
        shifts = {x: (point[x], dx) for x, dx in zip(xs, d)}
        cs = [_series_coefficients(f, shifts, 1, where) for f in F]
        F0 = [c[0] for c in cs]
        J = sp.Matrix(n, n, lambda i, j: cs[i][1].diff(d[j]))
    _check_at_rest([(f"d{x.name}/dt", f0) for x, f0 in zip(xs, F0)], rtol, "a steady point (every rate zero)")
    J = J.applyfunc(_tidy)
    pencil = LAMBDA * sp.eye(n) - J
    return _finish("first_order", xs, point, (), {}, None, None, None, J, pencil)


# ------------------------------------------------------------------------------------ CLI text
def _split_top_level(text: str) -> list[str]:
    parts, depth, cur = [], 0, []
    for ch in text:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    parts.append("".join(cur))
    return parts


def parse_point(text: str, allowed: Sequence[sp.Symbol], parameters: Sequence[sp.Symbol] = (),
                label: str = "--at") -> dict:
    """``"theta=0.3, phi_dot=sqrt(g/l)"`` → {theta: 3/10, phi_dot: sqrt(g/l)}, by the whitelist parser.

    Each piece is ``name = formula``; ``name`` one of ``allowed``, the formula in numbers, ``pi``,
    the whitelisted functions and the ``parameters`` (never evaluated as code).  Errors start with
    ``label``.
    """
    from ..formulas.parse import MAX_LENGTH, parse_expression

    if not isinstance(text, str):
        raise InvalidInputError(f"{label}: expected text like 'theta=0.3, phi_dot=2.0', got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise InvalidInputError(f"{label}: expected at most {MAX_LENGTH} characters, got {len(text)}")
    if not text.strip():
        raise InvalidInputError(f"{label}: expected 'name=value, ...' (names: "
                                f"{', '.join(s.name for s in allowed)}), got nothing")
    names = {s.name: s for s in allowed}
    pnames = {s.name: s for s in parameters}
    out: dict = {}
    for piece in _split_top_level(text):
        if piece.count("=") != 1:
            raise InvalidInputError(f"{label}: expected 'name=value' pieces separated by commas, got {piece.strip()!r}")
        name, value = (s.strip() for s in piece.split("="))
        if name not in names:
            raise InvalidInputError(f"{label}: expected a name among {', '.join(names)}, got {name!r}")
        sym = names[name]
        if sym in out:
            raise InvalidInputError(f"{label}: expected each name once, got {name} twice")
        try:
            out[sym] = parse_expression(value, pnames, what=f"value of {name}")
        except InvalidInputError as exc:
            raise InvalidInputError(f"{label}: {name}: {exc}") from None
    return out


def linearization_derivation(system: Any, at_text: str, parameters: Mapping[str, Any] | None = None,
                             *, label: str = "--at") -> tuple[sp.Matrix, str, Linearization]:
    """What ``mechderive derive SCENE.toml linearization --at "theta=0.3, phi_dot=2.0"`` prints.

    ``system`` is a :class:`mechderive.systems.base.System`; its :meth:`lagrangian_model` (else
    :meth:`first_order_model`) gives the equations.  ``at_text`` is parsed by the whitelist
    parser (:func:`parse_point`): names of the coordinates, velocities and conserved momenta
    ``p_<cyclic>`` (or of the state), values in numbers, ``pi``, functions and the system's
    parameter names.  ``parameters`` ({name: number}, e.g. a scene's ``[parameters]``) are
    substituted; those not given stay symbols.  Returns (the linearized equations as a column of
    SymPy expressions, each = 0; the text report; the :class:`Linearization`).
    """
    lagrangian = system.lagrangian_model() if hasattr(system, "lagrangian_model") else None
    first = None if lagrangian is not None else (
        system.first_order_model() if hasattr(system, "first_order_model") else None)
    name = getattr(system, "name", type(system).__name__)
    if lagrangian is None and first is None:
        raise InvalidInputError(f"system {name!r} offers no Lagrangian or first-order model to linearize")
    if lagrangian is not None:
        L, qs, vs, params = lagrangian
        qs, vs = tuple(qs), tuple(vs)
        psyms = [sp.Symbol("p_" + q.name, real=True) for q in qs]
        parsed = parse_point(at_text, [*qs, *vs, *psyms], tuple(params), label)
        at = {k.name: v for k, v in parsed.items()}
        values = _named_parameters(parameters, params, parsed, as_symbolic(L).free_symbols)
        result = linearize_lagrangian(L, qs, vs, at, values)
    else:
        rhs, xs, params = first
        parsed = parse_point(at_text, tuple(xs), tuple(params), label)
        values = _named_parameters(parameters, params, parsed, as_symbolic(sp.Matrix(list(rhs))).free_symbols)
        result = linearize_first_order(rhs, xs, {k.name: v for k, v in parsed.items()}, values)
    return result.equations, result.text(), result


def _named_parameters(parameters: Mapping[str, Any] | None, params: Sequence[sp.Symbol], parsed: dict,
                      used: set) -> dict | None:
    """The given parameter numbers as {symbol: value}, for the parameters the equations or `at` use (a scene's
    other parameters, e.g. of output expressions only, are left out)."""
    if not parameters:
        return None
    by_name = {p.name: p for p in params}
    out = {}
    for key, value in parameters.items():
        sym = by_name.get(key) if isinstance(key, str) else key if key in params else None
        if sym is None:
            raise InvalidInputError(f"expected parameters among {', '.join(by_name) or 'none'}, got {key!r}")
        if sym in used or any(sym in v.free_symbols for v in parsed.values()):
            out[sym] = _exact_number(value, f"parameter {sym.name}")
    return out
