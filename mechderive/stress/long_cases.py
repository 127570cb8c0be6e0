"""Very long runs: closed forms at 10⁶ periods against references built by exact periodicity, and the
splitting integrators' energy over 10⁶ steps.

References (as in ``tests/reference/make_*_reference.py``), from one short mpmath integration:

* free top: the polhode period T is the root of ω2(t) - ω2(0) of the reference (started from the
  textbook 4K/λ), and ω(NT + τ) = ω(τ), R(NT + τ) = R(τ) Cᴺ with the monodromy C = R(0)⁻¹ R(T);
* heavy top: released at a turning point, T is the root of Ṙ33 near the first return; θ(NT + τ) =
  θ(τ), φ(NT + τ) = φ(τ) + NΔφ, ψ likewise, Δφ and Δψ the advances over [0, T] (unwrapped along a
  fine sampling), all at 30 digits and reduced mod 2π there.

τ is taken as mpf(float(NT + τ)) - NT, so reference and toolkit see the same binary time t.
"""

from __future__ import annotations

import mpmath
import numpy as np

from .checks import CF_TOL, TOP
from .core import Case, Collector
from ..errors import DerivationError
from .reference import (DPS, euler_angles, euler_matrix, find_root, free_initial_state, free_top_field,
                        free_top_period, heavy_initial_state, heavy_top_field, integrate, matrix, monodromy_power)

__all__ = ["CASES"]

N_PERIODS = 10**6
_R0 = euler_matrix(0.3, 0.7, -1.1)


def _mp_to_float(M) -> np.ndarray:
    return np.array([[float(M[i, j]) for j in range(3)] for i in range(3)])


def _long_free(col: Collector) -> None:
    from ..systems.free_top.exact import exact_free_top

    I, w0 = (1.0, 2.0, 3.0), (1.0, 0.5, 1.0)
    R0 = _mp_to_float(_R0)
    taus = [0.1 + 0.85 * k for k in range(8)]
    with mpmath.workdps(DPS):
        sol = integrate(free_top_field(I), free_initial_state(w0, R0.tolist()))
        T = find_root(lambda s: sol(s)[1] - sol(0)[1], free_top_period(I, w0))
        y0, yT = sol(0), sol(T)
        col.bound("reference", "period: |ω(T) - ω(0)|", float(max(abs(yT[k] - y0[k]) for k in range(3))), 1e-20)
        C = mpmath.inverse(matrix(y0)) * matrix(yT)
        CN = monodromy_power(C, N_PERIODS)
        ts, w_ref, R_ref = [], [], []
        for tau in taus:
            t = float(N_PERIODS * T + tau)
            y = sol(mpmath.mpf(t) - N_PERIODS * T)
            ts.append(t)
            w_ref.append([float(v) for v in y[:3]])
            R_ref.append(_mp_to_float(matrix(y) * CN))
    col.details["period (reference)"] = float(T)
    top = col.attempt("closed form", "exact_free_top", lambda: exact_free_top(I, w0, R0=R0))
    if top is None:
        return
    col.compare("closed form", "polhode period (relative)", top.polhode_period, float(T), 1e-14, scale=float(T))
    ts = np.array(ts)
    col.compare("closed form", "ω/|ω0| at 10⁶ T + τ", top.omega(ts), np.array(w_ref), CF_TOL,
                scale=float(np.linalg.norm(w0)))
    col.compare("closed form", "R at 10⁶ T + τ", top.rotation(ts), np.array(R_ref), CF_TOL)


def _unwrap_to(prev: mpmath.mpf, x: mpmath.mpf) -> mpmath.mpf:
    return x + 2 * mpmath.pi * mpmath.nint((prev - x) / (2 * mpmath.pi))


def _long_heavy(init: dict):
    def run(col: Collector) -> None:
        from ..systems.heavy_top.exact import exact_heavy_top

        mp = mpmath.mpf
        with mpmath.workdps(DPS):
            sol = integrate(heavy_top_field(TOP["I1"], TOP["I3"], mp(TOP["M"]) * mp(TOP["g"]) * mp(TOP["l"])),
                            heavy_initial_state(init))
            # released at a turning point: R33 - R33(0) has a double zero at T, Ṙ33 a simple one. A coarse
            # scan for the sign change of Ṙ33 after the half period finds the start (independent of the toolkit).
            signs, prev = [], None
            for k in range(1, 1001):  # t up to 20
                g = mp(k) / 50
                d = sol.derivative(g, 3 + 8)
                if prev is not None and prev * d < 0:
                    signs.append(g)
                    if len(signs) == 2:
                        break
                prev = d
            if len(signs) < 2:
                raise DerivationError("expected two sign changes of dR33/dt within t = 20")
            T = find_root(lambda s: sol.derivative(s, 3 + 8), signs[1])
            fine = [T * k / 400 for k in range(401)]
            track = [euler_angles(sol(0))]
            start = (mp(init.get("phi", 0.0)), mp(init.get("psi", 0.0)))
            phi, psi = _unwrap_to(start[0], track[0][0]), _unwrap_to(start[1], track[0][2])
            unwrapped = [(mp(0), phi, psi)]
            for s in fine[1:]:
                a = euler_angles(sol(s))
                phi, psi = _unwrap_to(phi, a[0]), _unwrap_to(psi, a[2])
                unwrapped.append((s, phi, psi))
            dphi, dpsi = unwrapped[-1][1] - unwrapped[0][1], unwrapped[-1][2] - unwrapped[0][2]
            taus = [T * (k + mp(0.3)) / 8 for k in range(8)]
            ts, ref = [], []
            for tau in taus:
                t = float(N_PERIODS * T + tau)
                tau_x = mp(t) - N_PERIODS * T
                k = max(i for i, row in enumerate(unwrapped) if row[0] <= tau_x)
                y = sol(tau_x)
                a = euler_angles(y)
                ph, ps = _unwrap_to(unwrapped[k][1], a[0]), _unwrap_to(unwrapped[k][2], a[2])
                two_pi = 2 * mpmath.pi
                wrap = lambda x: x - two_pi * mpmath.nint(x / two_pi)  # noqa: E731
                ts.append(t)
                ref.append((float(a[1]), float(wrap(ph + N_PERIODS * dphi)), float(wrap(ps + N_PERIODS * dpsi)),
                            _mp_to_float(matrix(y))))
        col.details.update(period=float(T), dphi=float(dphi), dpsi=float(dpsi))
        top = col.attempt("closed form", "exact_heavy_top", lambda: exact_heavy_top(TOP, init))
        if top is None:
            return
        col.compare("closed form", "nutation period (relative)", top.nutation_period, float(T), 1e-14,
                    scale=float(T))
        ts = np.array(ts)
        out = col.attempt("closed form", "evaluate", lambda: top.evaluate(ts, ["theta", "phi_wrapped",
                                                                              "psi_wrapped", "R"]))
        if out is None:
            return
        # R(NT + τ) = R(φ(τ) + NΔφ, θ(τ), ψ(τ) + NΔψ): rebuilt from the reference angles at 30 digits
        with mpmath.workdps(DPS):
            R_ref = np.array([_mp_to_float(euler_matrix(mp(r[1]), mp(r[0]), mp(r[2]))) for r in ref])
        col.compare("closed form", "θ at 10⁶ T + τ", out["theta"], [r[0] for r in ref], CF_TOL)
        col.compare("closed form", "φ mod 2π at 10⁶ T + τ", out["phi_wrapped"], [r[1] for r in ref], CF_TOL,
                    angle=True)
        col.compare("closed form", "ψ mod 2π at 10⁶ T + τ", out["psi_wrapped"], [r[2] for r in ref], CF_TOL,
                    angle=True)
        col.compare("closed form", "R at 10⁶ T + τ", out["R"], R_ref, CF_TOL)

    return run


def _splitting(system: str):
    """Energy over 10⁶ fixed steps: bounded (symplectic), not drifting."""
    def run(col: Collector) -> None:
        from ..systems.free_top.integrate import integrate_free_top
        from ..systems.heavy_top.integrate import integrate_heavy_top

        step, n = 0.1, 10**6

        def go(t_end: float):
            t = np.linspace(0.0, t_end, 2001)
            if system == "heavy_top":
                return integrate_heavy_top(TOP, dict(theta=0.5, psi_dot=5.0), t, method="splitting", step=step,
                                           order=4, estimate_error=False)
            return integrate_free_top((1.0, 2.0, 3.0), (1.0, 0.5, 1.0), t, method="splitting", step=step, order=4,
                                      estimate_error=False)

        early, late = go(step * n / 100), go(step * n)
        for traj, label in ((early, "10⁴ steps"), (late, "10⁶ steps")):
            col._finite(f"splitting-4 {label}", "ω", traj.omega)
            col._finite(f"splitting-4 {label}", "q", traj.quaternion)
        # bounded: the energy error over 10⁶ steps within 2× its oscillation over the first 10⁴, plus the
        # round-off random walk (~1e-16 √(5·10⁶ stages) ≈ 2e-13, ×5)
        e0, e1 = float(early.energy_drift), float(late.energy_drift)
        col.drift("splitting-4 10⁶ steps", "energy", e1, 2 * e0 + 1e-12)
        col.details.update(energy_drift_first_1e4_steps=e0, energy_drift_1e6_steps=e1, steps=int(late.n_steps))
        if system == "heavy_top":
            col.drift("splitting-4 10⁶ steps", "p_phi", float(late.p_phi_drift), 1e-11)
            col.drift("splitting-4 10⁶ steps", "p_psi", float(late.p_psi_drift), 1e-11)
        else:
            col.drift("splitting-4 10⁶ steps", "|L|", float(late.angular_momentum_drift), 1e-11)

    return run


_REF = "one period of an mpmath Taylor integration (30 digits) + exact periodicity / monodromy"
CASES = [
    Case(name="long-free-1e6", family="7 long runs",
         description="free top I = (1, 2, 3) at 10⁶ polhode periods + τ (t ≈ 6.8e6), 8 values of τ",
         system="free_top", inputs="I = (1, 2, 3), ω0 = (1, 0.5, 1), R0 = R(0.3, 0.7, -1.1)",
         methods=("closed form",), reference=_REF,
         tolerance=f"ω {CF_TOL:g}·|ω0|, R {CF_TOL:g}: the closed form claims the same error at 10⁶ periods as at one",
         run=_long_free, quick=True),
    Case(name="long-heavy-cusps-1e6", family="7 long runs",
         description="heavy top released at θ0 = 0.5 (cusps) at 10⁶ nutation periods + τ (t ≈ 3.5e6)",
         system="heavy_top", inputs="TOP; theta=0.5, psi_dot=5", methods=("closed form",), reference=_REF,
         tolerance=f"θ, φ and ψ mod 2π, R: {CF_TOL:g} (as at one period)",
         run=_long_heavy(dict(theta=0.5, psi_dot=5.0)), quick=True),
    Case(name="long-heavy-looping-1e6", family="7 long runs",
         description="heavy top released at θ0 = 0.5 with φ̇ = -0.5 (loops) at 10⁶ nutation periods + τ",
         system="heavy_top", inputs="TOP; theta=0.5, phi_dot=-0.5, psi_dot=5", methods=("closed form",),
         reference=_REF, tolerance=f"θ, φ and ψ mod 2π, R: {CF_TOL:g}",
         run=_long_heavy(dict(theta=0.5, phi_dot=-0.5, psi_dot=5.0))),
    Case(name="long-splitting-heavy-1e6-steps", family="7 long runs",
         description="heavy-top splitting (order 4, h = 0.1 ≈ T/35) over 10⁶ steps: energy bounded",
         system="heavy_top", inputs="TOP; theta=0.5, psi_dot=5", methods=("splitting-4",),
         reference="the exact conservation of E, p_φ, p_ψ; its own first 10⁴ steps",
         tolerance="energy ≤ 2× its first-10⁴-step oscillation + 1e-12; p_φ, p_ψ ≤ 1e-11 (rounding)",
         run=_splitting("heavy_top")),
    Case(name="long-splitting-free-1e6-steps", family="7 long runs",
         description="free-top Lie–Poisson splitting (order 4, h = 0.1) over 10⁶ steps: energy bounded",
         system="free_top", inputs="I = (1, 2, 3), ω0 = (1, 0.5, 1)", methods=("splitting-4",),
         reference="the exact conservation of T and |L|; its own first 10⁴ steps",
         tolerance="energy ≤ 2× its first-10⁴-step oscillation + 1e-12; |L| ≤ 1e-11 (rounding)",
         run=_splitting("free_top")),
]
