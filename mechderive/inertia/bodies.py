"""Uniform standard bodies, each derived by integrating a constant density (3.20), (3.23), (3.24).

Every body is a uniform density ρ on a parametrised region (solid, surface or
curve); its mass M = ρ · (volume, area or length) is integrated like everything
else, and ρ is then eliminated in favour of M.  No table value appears here:
the tables live in the tests and in the catalog's printed forms.

Bodies, their dimensions (keywords besides ``mass``), coordinates and frames
(origin O, axes) — all lengths in one unit, mass in another:

==================  ======================  =========================================================
name                dimensions              region (coordinates), frame
==================  ======================  =========================================================
``rod``             ``length``              curve (0, 0, s), |s| <= l/2; along axis 3, O at centre
``disc``            ``radius``              surface, polar (r, φ) in the 1–2 plane; O at centre
``ring``            ``radius``              thin hoop, curve (R cos φ, R sin φ, 0); O at centre
``solid_sphere``    ``radius``              solid, spherical (r, ϑ, φ); O at centre
``hollow_sphere``   ``radius``              thin shell, surface (ϑ, φ) at r = R; O at centre
``solid_cylinder``  ``radius, height``      solid of revolution r <= R, |z| <= h/2; axis 3, O at centre
``cuboid``          ``a, b, c``             box of edges a, b, c along axes 1, 2, 3; O at centre
``solid_ellipsoid`` ``a, b, c``             solid, scaled spherical; semi-axes a, b, c; O at centre
``solid_cone``      ``radius, height``      solid of revolution r <= R z/h, 0 <= z <= h; O at the **apex**
==================  ======================  =========================================================

Use :meth:`BodyInertia.inertia_about` for any other point, e.g. the cone's apex
``(0, 0, 0)`` or the rod's end ``(0, 0, l/2)``.

>>> b = body_inertia("rod", mass=3.0, length=2.0)
>>> b.inertia_cm
array([[1., 0., 0.],
       [0., 1., 0.],
       [0., 0., 0.]])
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import sympy as sp

from ..core.model import derived
from ..core.validate import as_finite_array
from ..errors import DerivationError, InvalidInputError
from .body import BodyInertia
from .density import DensityModel
from .regions import Region, box, r, solid_of_revolution, varphi, vartheta, z

__all__ = ["BODIES", "BodySpec", "UniformBodyModel", "body_model", "body_inertia", "body_inertia_symbolic"]

#: mass, uniform density and the dimension symbols (positive), shared by every body
M, rho = sp.symbols("M rho", positive=True)
_l, _R, _h, _a, _b, _c = sp.symbols("l R h a b c", positive=True)
_s = sp.Symbol("s", real=True)  # arc length along the rod


@dataclass(frozen=True)
class BodySpec:
    """A standard body: its dimension keywords and symbols, and how to build its region."""

    name: str
    dimensions: tuple[str, ...]
    symbols: tuple[sp.Symbol, ...]
    region: Callable[[], Region]
    line_body: bool = False


def _spherical(scale: tuple[Any, Any, Any], radial: Any) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    sx, sy, sz = scale
    return (sx * radial * sp.sin(vartheta) * sp.cos(varphi), sy * radial * sp.sin(vartheta) * sp.sin(varphi),
            sz * radial * sp.cos(vartheta))


_ANGLES = ((vartheta, 0, sp.pi), (varphi, 0, 2 * sp.pi))

_SPECS = {spec.name: spec for spec in [
    BodySpec("rod", ("length",), (_l,),
             lambda: Region("rod along axis 3", (0, 0, _s), ((_s, -_l / 2, _l / 2),)), line_body=True),
    BodySpec("disc", ("radius",), (_R,),
             lambda: Region("disc in the 1-2 plane", (r * sp.cos(varphi), r * sp.sin(varphi), 0),
                            ((r, 0, _R), (varphi, 0, 2 * sp.pi)))),
    BodySpec("ring", ("radius",), (_R,),
             lambda: Region("ring in the 1-2 plane", (_R * sp.cos(varphi), _R * sp.sin(varphi), 0),
                            ((varphi, 0, 2 * sp.pi),))),
    BodySpec("solid_sphere", ("radius",), (_R,),
             lambda: Region("solid sphere", _spherical((1, 1, 1), r), ((r, 0, _R), *_ANGLES))),
    BodySpec("hollow_sphere", ("radius",), (_R,),
             lambda: Region("spherical shell", _spherical((1, 1, 1), _R), _ANGLES)),
    BodySpec("solid_cylinder", ("radius", "height"), (_R, _h),
             lambda: solid_of_revolution(_R, (-_h / 2, _h / 2))),
    BodySpec("cuboid", ("a", "b", "c"), (_a, _b, _c),
             lambda: box((-_a / 2, _a / 2), (-_b / 2, _b / 2), (-_c / 2, _c / 2))),
    BodySpec("solid_ellipsoid", ("a", "b", "c"), (_a, _b, _c),
             lambda: Region("solid ellipsoid", _spherical((_a, _b, _c), r), ((r, 0, 1), *_ANGLES))),
    BodySpec("solid_cone", ("radius", "height"), (_R, _h),
             lambda: solid_of_revolution(_R * z / _h, (0, _h))),
]}

#: Names of the standard bodies.
BODIES: tuple[str, ...] = tuple(_SPECS)


class UniformBodyModel(DensityModel):
    """A :class:`DensityModel` with constant density ρ, re-expressed in the mass M."""

    def __init__(self, spec: BodySpec) -> None:
        super().__init__(rho, spec.region())
        self.spec = spec

    @derived
    def uniform_density(self) -> sp.Expr:
        """ρ solved from M = ∫ ρ dV, e.g. M / (π R² h) for the cylinder."""
        sol = sp.solve(sp.Eq(self.mass, M), rho)
        if len(sol) != 1:
            raise DerivationError(f"expected one density for mass M, got {sol}")
        return sol[0]

    @derived
    def inertia_cm_in_mass(self) -> sp.Matrix:
        """I about the centre of mass, in M and the dimensions."""
        return self.inertia_cm.subs(rho, self.uniform_density).applyfunc(sp.factor)

    @derived
    def symbolic(self) -> BodyInertia:
        """The body's :class:`BodyInertia` in the symbols M and the dimensions."""
        return BodyInertia(M, self.centre_of_mass, self.inertia_cm_in_mass, line_body=self.spec.line_body)

    def numeric(self, mass: np.ndarray, dims: list[np.ndarray]) -> BodyInertia:
        """Evaluate the compiled derivation at numbers (arrays broadcast)."""
        args = [M, *self.spec.symbols]
        f_com = self.compile(f"{self.spec.name}_centre_of_mass", self.centre_of_mass, args)
        f_I = self.compile(f"{self.spec.name}_inertia_cm", self.inertia_cm_in_mass, args)
        bshape = np.broadcast_shapes(mass.shape, *(d.shape for d in dims))
        com = np.broadcast_to(f_com(mass, *dims)[..., 0], bshape + (3,))
        I = np.broadcast_to(f_I(mass, *dims), bshape + (3, 3))
        return BodyInertia(mass if mass.ndim else float(mass), com, I, line_body=self.spec.line_body)


def _spec(name: str) -> BodySpec:
    if name not in _SPECS:
        raise InvalidInputError(f"expected a body name among {', '.join(map(repr, BODIES))}, got {name!r}")
    return _SPECS[name]


@functools.cache
def body_model(name: str) -> UniformBodyModel:
    """The process-wide derivation of body ``name`` (integrated once)."""
    return UniformBodyModel(_spec(name))


def body_inertia_symbolic(name: str) -> BodyInertia:
    """The body's mass, centre of mass and I_cm in symbols M and its dimensions (see module table).

    >>> body_inertia_symbolic("disc").inertia_cm
    Matrix([
    [M*R**2/4,        0,        0],
    [       0, M*R**2/4,        0],
    [       0,        0, M*R**2/2]])
    """
    return body_model(name).symbolic


def body_inertia(name: str, *, mass: Any, **dimensions: Any) -> BodyInertia:
    """Numeric mass, centre of mass and inertia tensor about it of a uniform standard body.

    ``mass`` and the dimensions (keywords listed in the module table) are
    positive numbers or arrays that broadcast; the result has mass (...),
    centre of mass (..., 3) and tensor (..., 3, 3).

    >>> body_inertia("solid_cone", mass=1.0, radius=1.0, height=4.0).centre_of_mass
    array([0., 0., 3.])
    """
    spec = _spec(name)
    if set(dimensions) != set(spec.dimensions):
        raise InvalidInputError(f"expected dimensions ({', '.join(spec.dimensions)}) for {name!r}, "
                                f"got ({', '.join(sorted(dimensions))})")
    values = {"mass": mass, **dimensions}
    arrays = {}
    for key, value in values.items():
        arr = as_finite_array(value, key)
        if np.any(arr <= 0):
            raise InvalidInputError(f"expected `{key}` > 0, got {float(arr[arr <= 0].ravel()[0])!r}")
        arrays[key] = arr
    return body_model(name).numeric(arrays["mass"], [arrays[d] for d in spec.dimensions])
