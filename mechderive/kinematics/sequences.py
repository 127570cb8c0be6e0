"""The twelve Euler sequences, body-fixed or space-fixed, in the chapter's passive convention.

Convention (section 3.1, (3.50)–(3.54)): e_a = R_ab ẽ_b, so R is *passive* and the elementary
rotations are the derived R_k(α) = exp(α J_k) of :func:`mechderive.kinematics.euler.axis_rotation`
((3.51), (3.52); R2 likewise).  The three angles (α1, α2, α3) are called φ, θ, ψ for every
sequence (first, second, third rotation) and are functions of t in the derivation.

A rotation by α about a *body* axis e_k turns the frame as e' = R_k(α) e, so R → R_k(α) R
(left multiplication, the chapter's steps (3.50)).  A rotation about a *space* axis ẽ_k turns
the active rotation A = Rᵀ as A → Q A, so R → R R_k(α) (right multiplication).  Hence, for the
sequence "ABC" with angles (φ, θ, ψ):

    body-fixed (intrinsic):   R = R_C(ψ) R_B(θ) R_A(φ)        — (3.54) for "ZXZ"
    space-fixed (extrinsic):  R = R_A(φ) R_B(θ) R_C(ψ)

and a space-fixed "ABC" with angles (φ, θ, ψ) is the body-fixed "CBA" with angles (ψ, θ, φ).

SciPy (:class:`scipy.spatial.transform.Rotation`, active): upper-case sequences are intrinsic,
lower-case extrinsic, with the angles in the same order, and

    Rotation.from_euler(scipy_sequence(seq, frame), [φ, θ, ψ]).as_matrix() == R(φ, θ, ψ).T

(see :mod:`mechderive.kinematics.conversions`; tested for all 24 in ``tests/test_derive.py``).

The angular velocity is derived exactly as the chapter does: ω = Ṙ Rᵀ (3.5), body components
ω_a = ½ ε_abc ω_bc (3.6), space components ω̃ = Rᵀ ω, and the convective Ω = Rᵀ Ṙ (3.10), each
entry brought to the exact normal form of :func:`mechderive.core.simplify.trig_normal`
(sin² + cos² = 1 reduced).

>>> R = rotation_sequence("ZXZ")
>>> from mechderive.kinematics.euler import model
>>> (R - model().state_rotation).applyfunc(sp.expand) == sp.zeros(3, 3)    # (3.54)
True
>>> scipy_sequence("XYZ", frame="space")
'xyz'
"""

from __future__ import annotations

import functools

import sympy as sp

from ..core.model import SymbolicModel, derived
from ..core.simplify import simplify_trig, trig_normal
from ..core.symbols import euler_angles, state_symbol, t, to_state_symbols
from ..errors import InvalidInputError
from .euler_symbolic import axis_rotation

__all__ = ["PROPER", "TAIT_BRYAN", "SEQUENCES", "FRAMES", "check_sequence", "scipy_sequence",
           "SequenceKinematics", "sequence_model", "rotation_sequence", "angular_velocity_sequence"]

#: Proper Euler sequences (first axis = last axis).
PROPER = ("ZXZ", "XYX", "YZY", "ZYZ", "XZX", "YXY")
#: Tait–Bryan sequences (three different axes).
TAIT_BRYAN = ("XYZ", "YZX", "ZXY", "XZY", "ZYX", "YXZ")
#: The twelve sequences, the chapter's first.
SEQUENCES = PROPER + TAIT_BRYAN
#: Body-fixed (intrinsic) or space-fixed (extrinsic) axes.
FRAMES = ("body", "space")
_AXIS = {"X": 1, "Y": 2, "Z": 3}


def check_sequence(sequence: str, frame: str | None = None) -> tuple[str, str]:
    """(SEQUENCE in upper case, "body" or "space") from a sequence and an optional frame.

    Lower-case letters mean space-fixed, as in SciPy; ``frame`` overrides upper case.  Raises
    :class:`~mechderive.errors.InvalidInputError` for anything else.

    >>> check_sequence("zyx")
    ('ZYX', 'space')
    >>> check_sequence("ZXZ", "space")
    ('ZXZ', 'space')
    """
    if not isinstance(sequence, str) or sequence.upper() not in SEQUENCES or not (
            sequence.isupper() or sequence.islower()):
        raise InvalidInputError(f"expected an Euler sequence among {', '.join(SEQUENCES)} (lower case for "
                                f"space-fixed axes, as in SciPy), got {sequence!r}")
    if frame is not None and frame not in FRAMES:
        raise InvalidInputError(f"expected frame 'body' or 'space', got {frame!r}")
    implied = "space" if sequence.islower() else "body"
    if sequence.islower() and frame == "body":
        raise InvalidInputError(f"expected an upper-case sequence with frame 'body' (lower case means "
                                f"space-fixed, as in SciPy), got {sequence!r}")
    return sequence.upper(), frame or implied


def scipy_sequence(sequence: str, frame: str | None = None) -> str:
    """SciPy's ``from_euler`` string for the sequence: upper case intrinsic, lower case extrinsic.

    With it, ``Rotation.from_euler(s, [φ, θ, ψ]).as_matrix()`` is Rᵀ (module docstring).
    """
    seq, fr = check_sequence(sequence, frame)
    return seq if fr == "body" else seq.lower()


class SequenceKinematics(SymbolicModel):
    """R(φ, θ, ψ) and ω for one Euler sequence and frame, derived lazily (see the module docstring)."""

    def __init__(self, sequence: str = "ZXZ", frame: str | None = None) -> None:
        super().__init__()
        self.sequence, self.frame = check_sequence(sequence, frame)

    @property
    def axes(self) -> tuple[int, int, int]:
        """The axis numbers (1, 2, 3) of the three rotations, in order."""
        return tuple(_AXIS[c] for c in self.sequence)  # type: ignore[return-value]

    @derived
    def factors(self) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix]:
        """(R_A(φ), R_B(θ), R_C(ψ)): the derived passive axis rotations, functions of t."""
        return tuple(axis_rotation(k, q) for k, q in zip(self.axes, euler_angles()))  # type: ignore[return-value]

    @derived
    def rotation(self) -> sp.Matrix:
        """R = R_C(ψ) R_B(θ) R_A(φ) (body-fixed, (3.54) for ZXZ) or R_A(φ) R_B(θ) R_C(ψ) (space-fixed)."""
        f1, f2, f3 = self.factors
        return sp.expand(f3 * f2 * f1 if self.frame == "body" else f1 * f2 * f3)

    @derived
    def angular_velocity_product(self) -> sp.Matrix:
        """Ṙ Rᵀ (3.5), unsimplified (each entry a trigonometric polynomial in the angles and rates)."""
        R = self.rotation
        return R.diff(t) * R.T

    @derived
    def angular_velocity_matrix(self) -> sp.Matrix:
        """ω = Ṙ Rᵀ (3.5), antisymmetric, in the exact trigonometric normal form."""
        return self.angular_velocity_product.applyfunc(trig_normal)

    @derived
    def angular_velocity_body(self) -> sp.Matrix:
        """Body components ω_a = ½ ε_abc ω_bc (3.6) of Ṙ Rᵀ; (3.58) for ZXZ body-fixed."""
        w = self.angular_velocity_product
        return sp.Matrix([sp.Rational(1, 2) * sum(sp.LeviCivita(a, b, c) * w[b - 1, c - 1]
                                                  for b in (1, 2, 3) for c in (1, 2, 3))
                          for a in (1, 2, 3)]).applyfunc(trig_normal)

    @derived
    def angular_velocity_space(self) -> sp.Matrix:
        """Space components ω̃ = Rᵀ ω (r̃_b = r_a R_ab)."""
        return (self.rotation.T * self.angular_velocity_body).applyfunc(trig_normal)

    @derived
    def convective_angular_velocity_matrix(self) -> sp.Matrix:
        """Ω = Rᵀ Ṙ (3.10), in the exact trigonometric normal form."""
        R = self.rotation
        return (R.T * R.diff(t)).applyfunc(trig_normal)

    @derived
    def euler_rates(self) -> sp.Matrix:
        """(φ̇, θ̇, ψ̇) in the body ω = (omega1, omega2, omega3): the body components solved (singular at gimbal lock)."""
        rates = [state_symbol(n) for n in ("phi_dot", "theta_dot", "psi_dot")]
        w = [state_symbol(f"omega{a}") for a in (1, 2, 3)]
        body = to_state_symbols(self.angular_velocity_body)
        sol = sp.solve([body[a] - w[a] for a in range(3)], rates, dict=True)
        if len(sol) != 1:
            from ..errors import DerivationError

            raise DerivationError(f"expected the body ω to determine the Euler rates uniquely, got {sol}")
        return sp.Matrix([simplify_trig(sol[0][r]) for r in rates])


@functools.cache
def _model(sequence: str, frame: str) -> SequenceKinematics:
    return SequenceKinematics(sequence, frame)


def sequence_model(sequence: str = "ZXZ", frame: str | None = None) -> SequenceKinematics:
    """The process-wide :class:`SequenceKinematics` of a sequence and frame (derived once)."""
    return _model(*check_sequence(sequence, frame))


def rotation_sequence(sequence: str = "ZXZ", *, frame: str | None = None) -> sp.Matrix:
    """R(φ, θ, ψ) of the sequence, in the symbols ``phi, theta, psi`` (module docstring).

    >>> rotation_sequence("XYZ", frame="space")[0, 2]
    -sin(theta)
    """
    return to_state_symbols(sequence_model(sequence, frame).rotation)


def angular_velocity_sequence(sequence: str = "ZXZ", *, frame: str | None = None,
                              components: str = "body") -> sp.Matrix:
    """ω from Ṙ Rᵀ for the sequence: body components (3.6) or space components, in the state symbols.

    >>> angular_velocity_sequence("ZXZ").T          # (3.58)
    Matrix([[phi_dot*sin(psi)*sin(theta) + theta_dot*cos(psi), phi_dot*sin(theta)*cos(psi) - theta_dot*sin(psi), phi_dot*cos(theta) + psi_dot]])
    """
    m = sequence_model(sequence, frame)
    if components not in FRAMES:
        raise InvalidInputError(f"expected components 'body' or 'space', got {components!r}")
    return to_state_symbols(m.angular_velocity_body if components == "body" else m.angular_velocity_space)
