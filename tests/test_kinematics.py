"""Symbolic kinematics (section 3.1): the fast structured derivations against the direct slow ones."""

from __future__ import annotations


def test_structured_angular_velocity_equals_the_simplified_rdot_rt_3_5_3_6():
    """ω of R = R3(ψ) R1(θ) R3(φ) by the product rule and conjugation (the fast derivation) equals
    ½ ε_abc (Ṙ Rᵀ)_bc simplified entry by entry (the slow one it replaces), and R1, R3 by Rodrigues'
    closed form equal SymPy's general matrix exponential."""
    import sympy as sp

    from mechderive.core.symbols import t
    from mechderive.kinematics.euler_symbolic import _exp, _exp_generator, _simplify_matrix, generator, model

    alpha = sp.Symbol("alpha", real=True)
    for axis in (1, 2, 3):
        assert sp.simplify(_exp(alpha * generator(axis)) - _exp_generator(alpha, generator(axis))) == sp.zeros(3)
    from mechderive.kinematics.euler_symbolic import axis_rotation

    beta = sp.Symbol("beta") / 2  # axis 2 (kept per process, in a symbol of its own) at another angle
    assert axis_rotation(2, beta) == _simplify_matrix(_exp(beta * generator(2)))
    m = model()
    R = m.rotation
    slow = _simplify_matrix(R.diff(t) * R.T)
    assert sp.simplify(slow - m.angular_velocity_matrix) == sp.zeros(3)
    vec = sp.Matrix([sp.Rational(1, 2) * sum(sp.LeviCivita(a, b, c) * slow[b - 1, c - 1]
                                             for b in (1, 2, 3) for c in (1, 2, 3)) for a in (1, 2, 3)])
    assert sp.simplify(vec - m.angular_velocity_body) == sp.zeros(3, 1)
