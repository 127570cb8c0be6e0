"""The parallel axis theorem (3.25)–(3.26), derived for a general system of point masses.

Statement: if P' is displaced by c from the centre of mass, then

    I_c = I_cm + (inertia tensor (3.19) of the whole mass M placed at c).

Derivation (:class:`ParallelAxisModel`): for n point masses with positions r_i
measured from the centre of mass, I_c is (3.19) with r_i → r_i - c.  Subtracting
I_cm and the tensor of M at c leaves terms linear in the r_i (the square
bracket of (3.26)); the model derives them, then imposes Σ m_i r_i = 0 by
solving it for r_n and shows they vanish identically.

Numerically, :func:`parallel_axis` adds the compiled one-mass tensor of
:mod:`mechderive.inertia.tensor` to I_cm: the shift is (3.19) for mass M at c,
not a retyped M(c² δ_ab - c_a c_b).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import sympy as sp

from ..core.model import SymbolicModel, derived
from ..core.validate import as_finite_array
from ..errors import DerivationError, InvalidInputError, ShapeError
from .tensor import _single_tensor_function, inertia_tensor_symbolic, point_mass_tensor

__all__ = ["ParallelAxisModel", "parallel_axis_model", "parallel_axis", "parallel_axis_symbolic"]


class ParallelAxisModel(SymbolicModel):
    """Symbolic proof of (3.25) for ``n`` general point masses (n >= 2).

    Symbols: masses ``m1..mn``, positions ``x_i, y_i, z_i`` from the centre of mass
    (before the constraint is imposed), displacement ``c1, c2, c3``.
    """

    def __init__(self, n: int = 3) -> None:
        super().__init__()
        if not (isinstance(n, int) and n >= 2):
            raise InvalidInputError(f"expected n >= 2 masses for the parallel-axis derivation, got {n!r}")
        self.n = n
        self.masses = list(sp.symbols(f"m1:{n + 1}", positive=True))
        self.positions = [sp.Matrix(sp.symbols(f"x{i} y{i} z{i}", real=True)) for i in range(1, n + 1)]
        self.c = sp.Matrix(sp.symbols("c1:4", real=True))
        self.M = sum(self.masses)

    @derived
    def inertia_about_c(self) -> sp.Matrix:
        """I_c: (3.19) with every r_i replaced by r_i - c (first line of (3.26))."""
        return inertia_tensor_symbolic(self.masses, [r - self.c for r in self.positions]).applyfunc(sp.expand)

    @derived
    def inertia_about_origin(self) -> sp.Matrix:
        """I about the origin of the r_i (which is the centre of mass once the constraint holds)."""
        return inertia_tensor_symbolic(self.masses, self.positions).applyfunc(sp.expand)

    @derived
    def shift_tensor(self) -> sp.Matrix:
        """The inertia tensor (3.19) of the total mass M at c."""
        return point_mass_tensor(self.M, self.c).applyfunc(sp.expand)

    @derived
    def linear_terms(self) -> sp.Matrix:
        """I_c - I_origin - shift: the terms linear in r_i (square bracket of (3.26))."""
        lin = (self.inertia_about_c - self.inertia_about_origin - self.shift_tensor).applyfunc(sp.expand)
        # they must be of degree one in the positions (and in c): (3.26)'s bracket
        pos = [s for r in self.positions for s in r]
        for e in lin:
            if e != 0 and sp.Poly(e, *pos).total_degree() != 1:
                raise DerivationError(f"expected terms linear in the positions, got {e}")
        return lin

    @derived
    def centre_of_mass_constraint(self) -> dict[sp.Symbol, sp.Expr]:
        """Σ m_i r_i = 0 solved for the last position r_n."""
        first = sum((m * r for m, r in zip(self.masses, self.positions)), sp.zeros(3, 1))
        rn = self.positions[-1]
        sol = sp.solve(list(first), list(rn), dict=True)
        if len(sol) != 1:
            raise DerivationError(f"expected one solution of Σ m r = 0 for r_n, got {sol}")
        return sol[0]

    @derived
    def linear_terms_at_centre_of_mass(self) -> sp.Matrix:
        """The bracket of (3.26) with Σ m r = 0: identically zero — the theorem (3.25)."""
        out = self.linear_terms.subs(self.centre_of_mass_constraint).applyfunc(sp.cancel)
        if not out.is_zero_matrix:
            raise DerivationError(f"expected the linear terms to vanish at the centre of mass, got {out}")
        return out


@functools.cache
def parallel_axis_model(n: int = 3) -> ParallelAxisModel:
    """The process-wide :class:`ParallelAxisModel` for ``n`` masses."""
    return ParallelAxisModel(n)


def parallel_axis_symbolic(inertia_cm: Any, mass: Any, c: Any) -> sp.Matrix:
    """I about the point displaced by ``c`` from the centre of mass (3.25), SymPy.

    >>> import sympy as sp
    >>> M, l = sp.symbols("M l", positive=True)
    >>> parallel_axis_symbolic(sp.diag(M*l**2/12, M*l**2/12, 0), M, (0, 0, l/2))[0, 0]
    M*l**2/3
    """
    from ..formulas.parse import as_matrix

    parallel_axis_model().linear_terms_at_centre_of_mass  # the theorem, derived once per process
    I_cm = as_matrix(inertia_cm, "`inertia_cm`")
    if I_cm.shape != (3, 3):
        raise ShapeError(f"expected `inertia_cm` of shape (3, 3), got {I_cm.shape}")
    return (I_cm + point_mass_tensor(mass, c)).applyfunc(sp.factor)


def parallel_axis(inertia_cm: Any, mass: Any, c: Any) -> np.ndarray:
    """I about the point displaced by ``c`` from the centre of mass (3.25), numerically.

    Parameters
    ----------
    inertia_cm : array_like, shape (..., 3, 3)
        Inertia tensor about the centre of mass.
    mass : array_like, shape (...)
        Total mass M > 0.
    c : array_like, shape (..., 3)
        Displacement of the new point from the centre of mass, same components as ``inertia_cm``.

    >>> parallel_axis(np.diag([1.0, 1.0, 0.0]), 12.0, [0.0, 0.0, 0.5])   # rod l = 1, M = 12, about its end
    array([[4., 0., 0.],
           [0., 4., 0.],
           [0., 0., 0.]])
    """
    I = as_finite_array(inertia_cm, "inertia_cm")
    if I.ndim < 2 or I.shape[-2:] != (3, 3):
        raise ShapeError(f"expected `inertia_cm` to have shape (..., 3, 3), got {I.shape}")
    M = as_finite_array(mass, "mass")
    if np.any(M <= 0):
        raise InvalidInputError(f"expected `mass` > 0, got {float(M[M <= 0].ravel()[0])!r}")
    cv = as_finite_array(c, "c")
    if cv.ndim < 1 or cv.shape[-1] != 3:
        raise ShapeError(f"expected `c` to have shape (..., 3), got {cv.shape}")
    parallel_axis_model().linear_terms_at_centre_of_mass  # the theorem, derived once per process
    return I + _single_tensor_function()(M, cv[..., 0], cv[..., 1], cv[..., 2])
