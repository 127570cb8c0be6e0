"""Generate the 30-digit reference motions of the free rigid body used by the tests.

Reference method, independent of mechderive's closed form: mpmath's Taylor-series ODE
solver (``mpmath.odefun``) at 30 digits on Euler's equations (3.33) together with
Ṙ = hat(ω) R (3.11), hat(ω)_ab = ε_abc ω_c.  For long times the exact periodicity of
ω is used: the polhode period T is located as a root of ω_y(t) - ω_y(0) of the
mpmath solution, the monodromy C = R(0)⁻¹ R(T) is taken from the same solution (R(0)⁻¹ as an inverse: the
float R(0) is orthogonal only to rounding), and

    ω(N T + τ) = ω(τ),     R(N T + τ) = R(τ) Cᴺ

(R(t + T) and R(t) solve the same linear equation Ṙ = hat(ω) R).  Cᴺ is formed from
C's axis and angle at 30 digits.

Run:  python tests/reference/make_free_top_reference.py   (a few minutes; writes free_top_cases.json)
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import mpmath
import numpy as np

DPS = 30
OUT = Path(__file__).with_name("free_top_cases.json")


def _random_rotation(seed: int) -> list[list[float]]:
    from scipy.spatial.transform import Rotation

    return Rotation.random(random_state=seed).as_matrix().tolist()


CASES = [
    # name, moments, omega0, R0, short times, long (N periods + tau) pairs
    ("generic", (1.0, 2.0, 3.0), (1.0, 0.5, 1.0), _random_rotation(7), [0.5, 1.7, 3.1], [(10, 1.3), (10**4, 2.9)]),
    ("separatrix_above_1e-10", (1.0, 2.0, 3.0), (1.0, 0.0, math.sqrt((1 + 3e-10) / 3)), None, [0.5, 4.0, 11.0],
     [(3, 5.0), (10**4, 7.5)]),
    ("separatrix_below_1e-10", (1.0, 2.0, 3.0), (1.0, 0.0, math.sqrt((1 - 3e-10) / 3)), _random_rotation(11),
     [0.5, 4.0, 11.0], [(3, 5.0), (10**4, 7.5)]),
    ("separatrix_1e-12", (1.0, 2.0, 3.0), (1.0, 1e-6, math.sqrt((1 + 3e-12) / 3)), None, [1.0, 6.0], []),
    # I3(I3 - I2) / (I1(I2 - I1)) = 0.75², so ω1 = 0.75 ω3 puts L² = 2T·I2 exactly in binary
    ("separatrix_exact", (1.0, 2.0, 2.25), (0.75, 0.5, 1.0), _random_rotation(3), [0.5, 3.0, 8.0, 20.0], []),
    ("symmetric", (1.0, 1.0, 2.0), (0.3, 0.4, 1.0), _random_rotation(5), [0.5, 2.0], [(10**4, 1.1)]),
    ("prolate_symmetric_order_321", (3.0, 2.0, 2.0), (0.2, -0.7, 0.4), None, [0.7, 2.5], [(10**4, 0.4)]),
    ("sphere", (1.5, 1.5, 1.5), (0.3, -0.2, 0.9), None, [0.5, 100.0], []),
    ("permuted_axes", (2.0, 3.0, 1.0), (0.4, 1.0, -1.2), None, [0.5, 2.2], [(100, 0.8)]),
]


def _rhs(I):
    def f(t, y):
        w = y[:3]
        dw = [(I[1] - I[2]) * w[1] * w[2] / I[0], (I[2] - I[0]) * w[2] * w[0] / I[1],
              (I[0] - I[1]) * w[0] * w[1] / I[2]]
        W = [[0, w[2], -w[1]], [-w[2], 0, w[0]], [w[1], -w[0], 0]]
        R = [y[3:6], y[6:9], y[9:12]]
        dR = [W[i][0] * R[0][j] + W[i][1] * R[1][j] + W[i][2] * R[2][j] for i in range(3) for j in range(3)]
        return dw + dR
    return f


def _mat(y) -> mpmath.matrix:
    return mpmath.matrix([[y[3 + 3 * i + j] for j in range(3)] for i in range(3)])


def _power(C: mpmath.matrix, N: int) -> mpmath.matrix:
    """Cᴺ for a rotation C, via its axis and angle (Rodrigues), at the working precision."""
    tr = C[0, 0] + C[1, 1] + C[2, 2]
    v = mpmath.matrix([C[2, 1] - C[1, 2], C[0, 2] - C[2, 0], C[1, 0] - C[0, 1]])  # 2 sin(angle) axis
    s = mpmath.norm(v) / 2
    # atan2 keeps full precision at every angle (acos of the trace loses half the digits near 0 and π)
    angle = mpmath.atan2(s, (tr - 1) / 2)
    if s == 0:
        return mpmath.eye(3)
    axis = v / (2 * s)
    a = N * angle
    K = mpmath.matrix([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return mpmath.eye(3) + mpmath.sin(a) * K + (1 - mpmath.cos(a)) * K * K


def main() -> None:
    out = []
    with mpmath.workdps(DPS):
        for name, I, w0, R0, short, long in CASES:
            start = time.time()
            Im = [mpmath.mpf(x) for x in I]
            R0f = np.eye(3).tolist() if R0 is None else R0
            y0 = [mpmath.mpf(x) for x in w0] + [mpmath.mpf(x) for row in R0f for x in row]
            sol = mpmath.odefun(_rhs(Im), 0, y0, tol=mpmath.mpf(10) ** (-DPS + 2))
            rows = []

            def record(t_float, tau, C=None, N=0):
                y = sol(tau)
                R = _mat(y)
                if C is not None:
                    R = R * _power(C, N)
                rows.append({"t": t_float, "omega": [mpmath.nstr(v, DPS) for v in y[:3]],
                             "R": [[mpmath.nstr(R[i, j], DPS) for j in range(3)] for i in range(3)]})

            for t in short:
                record(t, mpmath.mpf(t))
            period = None
            if long:
                sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
                from mechderive.systems.free_top.exact import exact_free_top

                guess = exact_free_top(I, w0).polhode_period  # only a starting point for the root
                # ω_y returns to ω_y(0) twice per period; ω_x's sign picks the right crossing.
                T = mpmath.findroot(lambda s: sol(s)[1] - y0[1], mpmath.mpf(guess))
                if abs(sol(T)[0] - y0[0]) > mpmath.mpf(10) ** -20:
                    raise SystemExit(f"{name}: period root is not a full period")
                period = T
                # R(0)⁻¹, not R(0)ᵀ: the float R(0) is orthogonal only to ~1e-16, which would cost
                # 1e-17 rad per period in Cᴺ.
                C = mpmath.inverse(_mat(y0)) * _mat(sol(T))
                for N, tau in long:
                    t_float = float(N * T + tau)
                    record(t_float, mpmath.mpf(t_float) - N * T, C, N)
            out.append({"name": name, "moments": list(I), "omega0": list(w0), "R0": R0f,
                        "period": None if period is None else mpmath.nstr(period, DPS), "points": rows})
            print(f"{name}: {time.time() - start:.1f} s", flush=True)
    OUT.write_text(json.dumps({"source": "tests/reference/make_free_top_reference.py", "dps": DPS,
                               "method": "mpmath.odefun (Taylor) on Euler's equations + Rdot = hat(w) R; "
                                         "periodicity + monodromy for long times",
                               "cases": out}, indent=1))


if __name__ == "__main__":
    main()
