"""Complete elliptic integrals at high precision (mpmath numbers), fast: Bulirsch's ``cel``.

The closed-form motions need the complete integral of the third kind

    Π(n | m) = ∫₀^{π/2} dθ / ((1 - n sin²θ) √(1 - m sin²θ)),   n < 1,

to ~32 digits once per motion (the angle advanced per period, multiplied by a period
count that may reach 10⁶ or more).  ``mpmath.ellippi`` takes ~3.5 ms at 40 digits;
Bulirsch's general complete integral

    cel(k_c, p, a, b) = ∫₀^{π/2} (a cos²θ + b sin²θ) / ((cos²θ + p sin²θ) √(cos²θ + k_c² sin²θ)) dθ

with Π(n | m) = cel(√(1 - m), 1 - n, 1, 1) converges quadratically (an AGM-like
iteration: R. Bulirsch, Numer. Math. 13 (1969) 305–315; Numerical Recipes §6.11) and
takes ~0.2 ms at the same precision.
"""

from __future__ import annotations

import mpmath

from ..errors import InvalidInputError

__all__ = ["complete_pi_mp"]


def complete_pi_mp(n, m1):
    """Π(n | m) for n < 1 and 0 < m1 = 1 - m ≤ 1, at the working mpmath precision.

    >>> with mpmath.workdps(30):
    ...     print(mpmath.nstr(complete_pi_mp(mpmath.mpf("0.3"), mpmath.mpf("0.5")), 20))
    2.2503768219439466847
    """
    n, m1 = mpmath.mpf(n), mpmath.mpf(m1)
    if not n < 1 or not 0 < m1 <= 1:
        raise InvalidInputError(f"expected n < 1 and 0 < m1 <= 1, got n = {n}, m1 = {m1}")
    qc = mpmath.sqrt(m1)
    p = mpmath.sqrt(1 - n)
    a, b = mpmath.mpf(1), 1 / p
    e, em = qc, mpmath.mpf(1)
    # Stop when the AGM-like pair agrees to the working precision (less 3 digits of rounding);
    # convergence is quadratic, so this costs one or two iterations more than a looser test.
    tol = mpmath.mpf(10) ** (-(mpmath.mp.dps - 3))
    for _ in range(200):
        f = a
        a = a + b / p
        g = e / p
        b = 2 * (b + f * g)
        p = p + g
        g = em
        em = em + qc
        if abs(g - qc) <= g * tol:
            break
        qc = 2 * mpmath.sqrt(e)
        e = qc * em
    return mpmath.pi / 2 * (b + a * em) / (em * (em + p))
