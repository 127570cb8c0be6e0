"""Principal moments and principal axes (3.21).

Convention (section 3.2): an orthogonal O with O I Oᵀ = diag(I1, I2, I3).  The
**rows** of O are the principal axes, in the components in which I is given —
O relates the given frame to the principal frame exactly as R of (3.2) relates
the space frame to the body frame: e'_a = O_ab e_b (the text's "{O e_a}", with
matrices acting on basis vectors).  In particular, if I is given in space
components Ĩ, then O is the R of a body frame along the principal axes and
Ĩ = Oᵀ diag(I1, I2, I3) O.

The O returned is a proper rotation (det O = +1): if the eigenvectors come out
left-handed the last row is negated.  Each row is fixed only up to sign, and
for repeated moments any orthonormal basis of the degenerate eigenspace is
returned (numpy.linalg.eigh gives an orthonormal one for a symmetric matrix;
the symbolic path applies Gram–Schmidt).  Moments are in ascending order
numerically; symbolically, numbers ascending first, then symbolic moments in SymPy's
canonical order.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import sympy as sp

from ..errors import DerivationError, ShapeError
from .validate import check_inertia_tensor

__all__ = ["principal_axes", "principal_axes_symbolic"]


def principal_axes(inertia: Any, *, line_body: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (..., 3), ascending, and O (..., 3, 3) with O I Oᵀ = diag (3.21).

    ``inertia`` is validated by :func:`check_inertia_tensor` (``line_body`` passed on).

    >>> moments, O = principal_axes([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 3.0]])
    >>> moments
    array([1., 3., 3.])
    >>> bool(np.isclose(np.linalg.det(O), 1.0))
    True
    """
    I = check_inertia_tensor(inertia, line_body=line_body)
    moments, vectors = np.linalg.eigh(I)  # columns are orthonormal eigenvectors
    O = np.swapaxes(vectors, -1, -2).copy()  # rows are the principal axes
    sign = np.sign(np.linalg.det(O))
    O[..., 2, :] *= sign[..., None]
    return moments, O


def _sort_key(value: sp.Expr) -> tuple:
    return (0, float(value)) if value.is_number else (1, sp.default_sort_key(value))


def principal_axes_symbolic(inertia: Any) -> tuple[list[sp.Expr], sp.Matrix]:
    """Principal moments and O (rows = principal axes) for a SymPy tensor SymPy can diagonalise.

    Meant for diagonal and block-diagonal tensors (and numeric-entry ones); raises
    :class:`DerivationError` if SymPy's eigenvectors do not diagonalise I exactly.

    >>> import sympy as sp
    >>> A, B, C = sp.symbols("A B C", positive=True)
    >>> moments, O = principal_axes_symbolic(sp.Matrix([[A, B, 0], [B, A, 0], [0, 0, C]]))
    >>> moments
    [C, A - B, A + B]
    >>> O
    Matrix([
    [         0,          0, 1],
    [-sqrt(2)/2,  sqrt(2)/2, 0],
    [-sqrt(2)/2, -sqrt(2)/2, 0]])
    """
    from ..formulas.parse import as_matrix

    I = as_matrix(inertia, "`inertia`")
    if I.shape != (3, 3):
        raise ShapeError(f"expected `inertia` of shape (3, 3), got {I.shape}")
    if not (I - I.T).applyfunc(sp.simplify).is_zero_matrix:
        raise ShapeError(f"expected a symmetric inertia tensor (I_ab = I_ba), got {I}")
    groups = sorted(I.eigenvects(), key=lambda g: _sort_key(g[0]))
    moments: list[sp.Expr] = []
    rows: list[sp.Matrix] = []
    for value, multiplicity, vectors in groups:
        # Gram–Schmidt: any orthonormal basis of a degenerate eigenspace will do
        basis = sp.GramSchmidt([sp.Matrix(v) for v in vectors], orthonormal=True)
        if len(basis) != multiplicity:
            raise DerivationError(f"expected {multiplicity} eigenvectors for moment {value}, got {len(basis)}")
        moments += [value] * multiplicity
        rows += [sp.simplify(b).T for b in basis]
    O = sp.Matrix(sp.Matrix.vstack(*rows))  # mutable, for the sign fix below
    det = sp.simplify(O.det())
    if det == -1:
        O[2, :] = -O[2, :]
    elif det != 1:
        raise DerivationError(f"expected det O = ±1, got {det}")
    residual = (O * I * O.T - sp.diag(*moments)).applyfunc(sp.simplify)
    if not residual.is_zero_matrix:
        raise DerivationError(f"expected O I Oᵀ to be diag{tuple(moments)}, got residual {residual}")
    return moments, O
