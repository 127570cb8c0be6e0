"""Regions of integration for continuous bodies: a parametrisation and iterated limits (3.20).

A :class:`Region` is a map from coordinates (u1, ..., uk) to body components
(x, y, z) together with limits, innermost first as in :func:`sympy.integrate`
(inner limits may depend on outer coordinates).  k = 3 is a solid, k = 2 a
surface (shell, disc), k = 1 a curve (rod, ring).  The measure is *derived* from
the map, never typed in: with J = ∂(x, y, z)/∂(u1..uk),

    d(volume, area or length) = sqrt(det(Jᵀ J)) du1 ... duk,

which is |det J| for a solid (e.g. r² sin ϑ in spherical coordinates, r in
cylindrical ones) and the area or arc-length element for a surface or curve.
The absolute value is resolved by sampling the sign of its argument inside the
region (a regular parametrisation does not change sign there); a change of sign
raises :class:`DerivationError`.

Coordinate symbols are shared module constants: ``x, y, z`` (Cartesian), ``r``
(radial, >= 0), ``vartheta`` (polar angle from axis 3), ``varphi`` (azimuth
about axis 3).  A density is an expression in its region's coordinates
(:attr:`Region.coordinates`).
"""

from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Any

import sympy as sp

from ..errors import DerivationError, InvalidInputError, ShapeError
from ..core.simplify import trig_normal
from ..formulas.parse import as_expression

__all__ = ["Region", "box", "solid_of_revolution", "x", "y", "z", "r", "vartheta", "varphi"]

x, y, z = sp.symbols("x y z", real=True)
r = sp.Symbol("r", positive=True)  # radial coordinate; positive so that sqrt(r**2) = r
vartheta = sp.Symbol("vartheta", real=True)
varphi = sp.Symbol("varphi", real=True)


@dataclass(frozen=True)
class Region:
    """A parametrised region: ``position`` (x, y, z) of the coordinates within ``limits``.

    Parameters
    ----------
    name : str
        A short description, e.g. ``"box [0, a] x [0, b] x [0, c]"``.
    position : tuple of 3 SymPy expressions
        Body components of the point with the given coordinates.
    limits : tuple of (symbol, lower, upper)
        Innermost first; the symbols are the region's coordinates.
    """

    name: str
    position: tuple[sp.Expr, sp.Expr, sp.Expr]
    limits: tuple[tuple[sp.Symbol, sp.Expr, sp.Expr], ...]

    def __post_init__(self) -> None:
        if len(self.position) != 3:
            raise ShapeError(f"expected a position with 3 components, got {len(self.position)}")
        if not 1 <= len(self.limits) <= 3:
            raise ShapeError(f"expected 1 to 3 coordinates (curve, surface or solid), got {len(self.limits)}")
        # Programs pass SymPy objects here; text would be evaluated by sympify, so it is refused.
        object.__setattr__(self, "position", tuple(as_expression(p, "each `position` component")
                                                   for p in self.position))
        limits = []
        for limit in self.limits:
            if not (isinstance(limit, (tuple, list)) and len(limit) == 3 and isinstance(limit[0], sp.Symbol)):
                raise InvalidInputError(f"expected each limit as (symbol, lower, upper), got {limit!r}")
            v, a, b = limit
            limits.append((v, as_expression(a, f"the lower limit of {v}"), as_expression(b, f"the upper limit of {v}")))
        object.__setattr__(self, "limits", tuple(limits))
        for v, a, b in self.limits:
            if a.is_number and b.is_number and not bool(a < b):
                raise InvalidInputError(f"expected lower < upper limit for {v}, got {a} and {b}")

    @property
    def coordinates(self) -> tuple[sp.Symbol, ...]:
        """The coordinates, outermost last (the order of :attr:`limits`)."""
        return tuple(v for v, _, _ in self.limits)

    @property
    def dimension(self) -> int:
        """3 for a solid, 2 for a surface, 1 for a curve."""
        return len(self.limits)

    def measure(self) -> sp.Expr:
        """The volume / area / length element sqrt(det(Jᵀ J)) of the parametrisation."""
        J = sp.Matrix(self.position).jacobian(list(self.coordinates))
        gram = sp.factor(trig_normal(sp.expand((J.T * J).det())))
        return _drop_abs(sp.sqrt(gram), self)

    def sample_points(self, count: int = 7, seed: int = 3) -> list[dict[sp.Symbol, float]]:
        """Seeded interior points (other symbols set to values in (0.5, 2)), for sign checks."""
        rng = random.Random(seed)
        others = sorted(set().union(*(e.free_symbols for e in self._all_exprs()))
                        - set(self.coordinates), key=sp.default_sort_key)
        points = []
        for _ in range(count):
            vals: dict[sp.Symbol, float] = {s: rng.uniform(0.5, 2.0) for s in others}
            for v, a, b in reversed(self.limits):  # outermost first
                lo, hi = float(a.subs(vals)), float(b.subs(vals))
                vals[v] = lo + rng.uniform(0.05, 0.95) * (hi - lo)
            points.append(vals)
        return points

    def _all_exprs(self) -> list[sp.Expr]:
        return [*self.position, *(e for _, a, b in self.limits for e in (a, b))]


def _drop_abs(expr: sp.Expr, region: Region) -> sp.Expr:
    """Replace each Abs(e) by ±e, the sign found at interior sample points."""
    points = region.sample_points()
    replacements = {}
    for a in expr.atoms(sp.Abs):
        signs = {sp.sign(sp.N(a.args[0].subs(p))) for p in points}
        if signs == {1}:
            replacements[a] = a.args[0]
        elif signs == {-1}:
            replacements[a] = -a.args[0]
        else:
            raise DerivationError(f"expected the Jacobian factor {a.args[0]} to keep one sign on {region.name}, "
                                  f"got signs {sorted(signs)}")
    return expr.xreplace(replacements)


def _pair(value: Any, name: str) -> tuple[sp.Expr, sp.Expr]:
    try:
        lo, hi = value
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"expected `{name}` as a pair (lower, upper), got {value!r}") from exc
    return as_expression(lo, f"the lower end of `{name}`"), as_expression(hi, f"the upper end of `{name}`")


def box(x_range: Any, y_range: Any, z_range: Any) -> Region:
    """The box x_range × y_range × z_range in Cartesian coordinates (x, y, z) (Jacobian 1).

    >>> box((0, 1), (0, 2), (0, 3)).measure()
    1
    """
    (x0, x1), (y0, y1), (z0, z1) = _pair(x_range, "x_range"), _pair(y_range, "y_range"), _pair(z_range, "z_range")
    return Region(f"box [{x0}, {x1}] x [{y0}, {y1}] x [{z0}, {z1}]", (x, y, z),
                  ((x, x0, x1), (y, y0, y1), (z, z0, z1)))


def solid_of_revolution(radius: Any, z_range: Any) -> Region:
    """The solid z0 <= z <= z1, r <= R(z) about axis 3, in cylindrical coordinates (r, varphi, z).

    ``radius`` is an expression in the module's ``z`` (or a constant); the
    coordinates are r (distance from axis 3), varphi (azimuth from axis 1) and z.

    >>> solid_of_revolution(1 - z, (0, 1)).measure()
    r
    """
    R = as_expression(radius, "`radius`")
    z0, z1 = _pair(z_range, "z_range")
    stray = {s for s in R.free_symbols if s.name == "z" and s != z}
    if stray:
        raise InvalidInputError(f"expected `radius` in the coordinate mechderive.inertia.regions.z, "
                                f"got a different symbol named z ({sp.srepr(next(iter(stray)))})")
    return Region(f"solid of revolution r <= {R}, {z0} <= z <= {z1}",
                  (r * sp.cos(varphi), r * sp.sin(varphi), z),
                  ((r, 0, R), (varphi, 0, 2 * sp.pi), (z, z0, z1)))
