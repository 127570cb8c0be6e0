"""Symmetric compositions: raising a symmetric 2nd-order step to order 4 and 6.

If S(h) is a *symmetric* (time-reversible, S(h)S(-h) = 1) one-step method of
order 2 — e.g. the Strang splitting S(h) = φ_A(h/2) φ_B(h) φ_A(h/2) — then the
composition

    S(γ_s h) ∘ … ∘ S(γ_2 h) ∘ S(γ_1 h)

with palindromic weights γ (γ_i = γ_{s+1-i}) is again symmetric, so its order is
even.  It has order 4 iff Σγ = 1 and Σγ³ = 0; order 6 needs in addition Σγ⁵ = 0
and one condition on ordered sums that no closed form of the weights shows
(Yoshida 1990, Phys. Lett. A 150, 262; Hairer, Lubich & Wanner, *Geometric
Numerical Integration*, §II.4 and §V.3).

Three families are provided, each a palindromic weight tuple summing to 1:

* :func:`triple_jump` — Yoshida's / Suzuki's recursive triple jump
  S_{2k}(h) = S_{2k-2}(γ₁h) S_{2k-2}(γ₀h) S_{2k-2}(γ₁h) with γ₁ = 1/(2 - 2^{1/(2k-1)}),
  γ₀ = 1 - 2γ₁, derived from Σγ = 1, Σγ^{2k-1} = 0 (3 stages for order 4, 9 for order 6);
* :func:`suzuki_fractal` — Suzuki's 5-stage fractal (Phys. Lett. A 146, 319 (1990)),
  p = 1/(4 - 4^{1/(2k-1)}): S(ph)S(ph)S((1-4p)h)S(ph)S(ph), smaller error constants,
  recursively (5 stages for order 4, 25 for order 6);
* :func:`yoshida6` — Yoshida's 7-stage order-6 "solution A" (Table 1 of Yoshida 1990),
  weights given there to 15 digits (the order-6 conditions hold to ~1e-15).

>>> w = triple_jump(4)
>>> len(w), round(sum(w), 15), abs(sum(g**3 for g in w)) < 1e-15
(3, 1.0, True)
"""

from __future__ import annotations

from ..errors import InvalidInputError

__all__ = ["triple_jump", "suzuki_fractal", "yoshida6", "merged_sequence"]

Weights = tuple[float, ...]


def _check_order(order: int) -> int:
    if order not in (2, 4, 6, 8):
        raise InvalidInputError(f"expected order one of 2, 4, 6, 8, got {order!r}")
    return order


def triple_jump(order: int) -> Weights:
    """Palindromic weights of the recursive triple jump, order 2 → ``order`` (3^((order-2)/2) stages).

    At each level the weights (γ₁, γ₀, γ₁) solve 2γ₁ + γ₀ = 1, 2γ₁^{n} + γ₀^{n} = 0 with n = order - 1.

    >>> [round(g, 10) for g in triple_jump(4)]
    [1.351207192, -1.7024143839, 1.351207192]
    """
    weights: Weights = (1.0,)
    for k in range(2, _check_order(order) // 2 + 1):  # raise 2k-2 -> 2k
        n = 2 * k - 1
        g1 = 1.0 / (2.0 - 2.0 ** (1.0 / n))
        g0 = 1.0 - 2.0 * g1
        weights = tuple(g * w for g in (g1, g0, g1) for w in weights)
    return weights


def suzuki_fractal(order: int) -> Weights:
    """Palindromic weights of Suzuki's 5-stage fractal, order 2 → ``order`` (5^((order-2)/2) stages).

    At each level (p, p, 1-4p, p, p) with 4p^{n} + (1-4p)^{n} = 0, n = order - 1.

    >>> [round(g, 10) for g in suzuki_fractal(4)][:3]
    [0.4144907718, 0.4144907718, -0.6579630872]
    """
    weights: Weights = (1.0,)
    for k in range(2, _check_order(order) // 2 + 1):
        n = 2 * k - 1
        p = 1.0 / (4.0 - 4.0 ** (1.0 / n))
        weights = tuple(g * w for g in (p, p, 1.0 - 4.0 * p, p, p) for w in weights)
    return weights


def yoshida6() -> Weights:
    """Yoshida's 7-stage order-6 weights, "solution A" of Yoshida (1990), Table 1 (w₃ w₂ w₁ w₀ w₁ w₂ w₃).

    >>> w = yoshida6()
    >>> len(w), abs(sum(w) - 1) < 1e-15, abs(sum(g**3 for g in w)) < 1e-13, abs(sum(g**5 for g in w)) < 1e-13
    (7, True, True, True)
    """
    w1, w2, w3 = -1.17767998417887, 0.235573213359357, 0.784513610477560
    w0 = 1.0 - 2.0 * (w1 + w2 + w3)
    return (w3, w2, w1, w0, w1, w2, w3)


def merged_sequence(weights: Weights, pieces: int) -> list[tuple[int, float]]:
    """The sub-flows of one composed step of the Strang splitting of ``pieces`` flows, merged.

    The Strang step of weight γ is φ_0(γ/2) φ_1(γ/2) … φ_{n-1}(γ) … φ_1(γ/2) φ_0(γ/2)
    (written in the order applied; time coefficients relative to the step h).  Adjacent
    sub-flows of the same piece commute and are merged, so a composition of s Strang
    steps costs s·(2n - 2) + 1 sub-flows instead of s·(2n - 1).  Returns
    [(piece, coefficient), ...]; the first and last entries are piece 0 with the same
    coefficient γ_1/2, and consecutive steps may merge them too (see the kernels).

    >>> merged_sequence((1.0,), 3)
    [(0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5)]
    >>> merged_sequence((0.5, 0.5), 2)
    [(0, 0.25), (1, 0.5), (0, 0.5), (1, 0.5), (0, 0.25)]
    """
    if pieces < 2:
        raise InvalidInputError(f"expected at least 2 pieces to split, got {pieces}")
    seq: list[tuple[int, float]] = []
    for g in weights:
        strang = [(k, g / 2) for k in range(pieces - 1)] + [(pieces - 1, g)] + \
                 [(k, g / 2) for k in reversed(range(pieces - 1))]
        for piece, c in strang:
            if seq and seq[-1][0] == piece:
                seq[-1] = (piece, seq[-1][1] + c)
            else:
                seq.append((piece, c))
    return seq
