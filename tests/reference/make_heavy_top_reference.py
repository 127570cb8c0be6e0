"""Generate the 30-digit reference motions of the heavy symmetric top used by the tests.

Reference method, independent of mechderive's Lagrangian derivation and closed form:
mpmath's Taylor-series ODE solver (``mpmath.odefun``) at 30 digits on the Newton–Euler
equations of the top — body ω and the chapter's R, with I = diag(I1, I1, I3) about the
pivot and the gravity torque τ = l e3 × (-M g ẽ3) in body components,

    I1 ω̇1 = (I1 - I3) ω2 ω3 + M g l R23,   I1 ω̇2 = (I3 - I1) ω3 ω1 - M g l R13,   I3 ω̇3 = 0,
    Ṙ = hat(ω) R  (3.11),

— written here by hand.  Euler angles are read off R at 30 digits (θ = atan2(√(R13²+R23²), R33),
φ = atan2(R31, -R32), ψ = atan2(R13, R23)) and unwrapped along a fine sampling.  Long
times use the symmetry of the motion: the nutation period T is a simple root of R33(t) - R33(0), or of
Ṙ33 when the top starts at a turning point (the state (θ, θ̇) returns), φ and ψ advance by Δφ, Δψ per period, so

    θ(NT + τ) = θ(τ),  φ(NT + τ) = φ(τ) + NΔφ,  ψ(NT + τ) = ψ(τ) + NΔψ.

Run: python tests/reference/make_heavy_top_reference.py   (a few minutes; writes heavy_top_cases.json)
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import mpmath

DPS = 30
OUT = Path(__file__).with_name("heavy_top_cases.json")
TOP = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0)  # BASELINE.md's top: I1 = 1, I3 = 0.5, M g l = 1

CASES = [
    # name, parameters, initial (theta, phi, psi, theta_dot, phi_dot, psi_dot), short times, long (N, tau)
    ("cusps_released", TOP, (0.5, 0.0, 0.0, 0.0, 0.0, 5.0), [0.4, 1.3, 2.9], [(100, 1.1), (10**4, 2.2)]),
    ("monotonic", TOP, (0.5, 0.3, -0.2, 0.0, 0.3, 5.0), [0.4, 2.1], [(100, 0.7)]),
    ("looping", TOP, (0.5, 0.0, 0.0, 0.0, -0.5, 5.0), [0.4, 2.1], [(100, 1.7)]),
    ("looping_moving_start", TOP, (0.5, 1.0, 2.0, 0.2, 0.4, 5.0), [0.4, 2.1], [(100, 0.9)]),
    ("hanging", TOP, (2.5, 0.0, 0.0, 0.0, 0.3, 3.0), [0.4, 2.1], [(100, 1.3)]),
    ("near_sleeping_stable", TOP, (1e-3, 0.0, 0.0, 0.0, 0.0, 10.0), [0.3, 0.9], []),
]


def _rhs(p):
    I1, I3 = mpmath.mpf(p["I1"]), mpmath.mpf(p["I3"])
    mgl = mpmath.mpf(p["M"]) * mpmath.mpf(p["g"]) * mpmath.mpf(p["l"])

    def f(t, y):
        w = y[:3]
        R = [y[3:6], y[6:9], y[9:12]]
        dw = [((I1 - I3) * w[1] * w[2] + mgl * R[1][2]) / I1,
              ((I3 - I1) * w[2] * w[0] - mgl * R[0][2]) / I1,
              mpmath.mpf(0)]
        W = [[0, w[2], -w[1]], [-w[2], 0, w[0]], [w[1], -w[0], 0]]
        dR = [W[i][0] * R[0][j] + W[i][1] * R[1][j] + W[i][2] * R[2][j] for i in range(3) for j in range(3)]
        return dw + dR
    return f


def _initial_state(init):
    th, ph, ps, thd, phd, psd = (mpmath.mpf(x) for x in init)
    c, s = mpmath.cos, mpmath.sin
    R3 = lambda a: mpmath.matrix([[c(a), s(a), 0], [-s(a), c(a), 0], [0, 0, 1]])
    R1 = lambda a: mpmath.matrix([[1, 0, 0], [0, c(a), s(a)], [0, -s(a), c(a)]])
    R = R3(ps) * R1(th) * R3(ph)
    w = [phd * s(th) * s(ps) + thd * c(ps), phd * s(th) * c(ps) - thd * s(ps), psd + phd * c(th)]  # (3.58)
    return w + [R[i, j] for i in range(3) for j in range(3)]


def _angles(y):
    R13, R23, R33, R31, R32 = y[3 + 2], y[3 + 5], y[3 + 8], y[3 + 6], y[3 + 7]
    return (mpmath.atan2(R31, -R32), mpmath.atan2(mpmath.sqrt(R13**2 + R23**2), R33), mpmath.atan2(R13, R23))


def _unwrapped(sol, times, start):
    """φ, ψ along ``times`` (sorted, from 0), unwrapped; θ; starting from the given φ0, ψ0."""
    out, prev = [], None
    for t in times:
        ph, th, ps = _angles(sol(t))
        if prev is None:
            ph += 2 * mpmath.pi * mpmath.nint((start[0] - ph) / (2 * mpmath.pi))
            ps += 2 * mpmath.pi * mpmath.nint((start[1] - ps) / (2 * mpmath.pi))
        else:
            ph += 2 * mpmath.pi * mpmath.nint((prev[0] - ph) / (2 * mpmath.pi))
            ps += 2 * mpmath.pi * mpmath.nint((prev[2] - ps) / (2 * mpmath.pi))
        prev = (ph, th, ps)
        out.append(prev)
    return out


def main() -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    from mechderive.systems.heavy_top.exact import exact_heavy_top

    cases = []
    with mpmath.workdps(DPS):
        for name, p, init, short, long in CASES:
            start = time.time()
            y0 = _initial_state(init)
            sol = mpmath.odefun(_rhs(p), 0, y0, tol=mpmath.mpf(10) ** (-DPS + 2))
            rows = []
            horizon = max(short)
            guess = None
            if long:
                keys = ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")
                guess = exact_heavy_top(p, dict(zip(keys, init))).nutation_period  # a starting point only
                horizon = max(horizon, 1.5 * guess)
            grid = [mpmath.mpf(horizon) * k / 400 for k in range(401)]
            for t in short:
                grid.append(mpmath.mpf(t))
            grid = sorted(set(grid))
            track = dict(zip(grid, _unwrapped(sol, grid, (mpmath.mpf(init[1]), mpmath.mpf(init[2])))))

            def record(t_float, ang):
                rows.append({"t": t_float, "phi": mpmath.nstr(ang[0], DPS), "theta": mpmath.nstr(ang[1], DPS),
                             "psi": mpmath.nstr(ang[2], DPS)})

            for t in short:
                record(t, track[mpmath.mpf(t)])
            period = None
            if long:
                rhs = _rhs(p)
                if init[3] == 0:
                    # released at a turning point: u(t) - u0 has a double zero at T, u̇ a simple one
                    g = lambda s: rhs(s, sol(s))[3 + 8]
                else:
                    g = lambda s: sol(s)[3 + 8] - y0[3 + 8]
                T = mpmath.findroot(g, mpmath.mpf(guess))
                # the same phase, not the half-way crossing: θ̇ has the sign it had at t = 0 (or both 0)
                if abs(T - guess) > guess / 4:
                    raise SystemExit(f"{name}: period root {T} far from {guess}")
                period = T
                end = _unwrapped(sol, [g for g in grid if g < T] + [T], (mpmath.mpf(init[1]), mpmath.mpf(init[2])))[-1]
                dphi, dpsi = end[0] - mpmath.mpf(init[1]), end[2] - mpmath.mpf(init[2])
                for N, tau in long:
                    t_float = float(N * T + tau)
                    tau_exact = mpmath.mpf(t_float) - N * T
                    near = _unwrapped(sol, [g for g in grid if g < tau_exact] + [tau_exact],
                                      (mpmath.mpf(init[1]), mpmath.mpf(init[2])))[-1]
                    record(t_float, (near[0] + N * dphi, near[1], near[2] + N * dpsi))
            cases.append({"name": name, "parameters": p,
                          "initial": dict(zip(("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot"), init)),
                          "period": None if period is None else mpmath.nstr(period, DPS), "points": rows})
            print(f"{name}: {time.time() - start:.1f} s", flush=True)
    OUT.write_text(json.dumps({"source": "tests/reference/make_heavy_top_reference.py", "dps": DPS,
                               "method": "mpmath.odefun (Taylor) on the Newton-Euler equations (body ω, R); "
                                         "nutation periodicity for long times", "cases": cases}, indent=1))


if __name__ == "__main__":
    main()
