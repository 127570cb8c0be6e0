"""The printed closed form of u̇² = P(u) for each root configuration the toolkit solves beyond the motion between two
real roots (issue 16; ``mechderive derive SCENE.toml closed_form_u_<configuration>``): the formulas of
:mod:`mechderive.solvers.quadrature_open` and :mod:`mechderive.solvers.quadrature_motion`, written in the roots of P
and its leading coefficient c (P = c·Π(u − roots)).

The elliptic ones are written in the amplitude χ of the Jacobi argument v = κ(t − t₀) + v₀ (sn v = sin χ,
cn v = cos χ, dn v = √(1 − m sin²χ), dχ/dt = κ dn) and given as [u(χ), m, κ]; the elementary ones in τ = t − t₀.
Each is checked in the tests by putting it back into u̇² = P(u): symbolically for the elementary ones, at 30 digits
at random roots and amplitudes for the elliptic ones (u̇ = (du/dχ)·κ·dn).

==================  =========  ======================================================================================
name                 deg P      motion
==================  =========  ======================================================================================
polynomial           ≤ 1        u = u₀ + u̇₀τ + (c₁/4)τ² (ü = P'/2 = c₁/2), u̇₀² = P(u₀)
sinh                 2, c > 0   no real root, P = c((u − α)² + β²): u = α + β sinh(κτ + v₀), κ = √c
cosh                 2, c > 0   outside the real roots r₁ < r₂: u = (r₁ + r₂)/2 + σ(r₂ − r₁)/2·cosh κ(t − t_turn)
double_root          2, c > 0   P = c(u − r)²: u = r + (u₀ − r)e^{sκτ}, s = ±1 (towards r or away), never reaching r
cn_cubic             3          one real root r, pair α ± iβ: u = r + σA(1 − cn)/(1 + cn), A² = (r − α)² + β²,
                                m = (1 − σ(r − α)/A)/2, κ² = |c|A, σ = sign c (B&F 239.00 and its mirror)
cn_quartic           4, c < 0   between real roots a < b, pair α ± iβ: u = (A + B cn)/(C + D cn) (B&F 259.00)
cn_quartic_outside   4, c > 0   outside the real roots, e on the start's side, f the other: through ∞ (B&F 260.00)
tan                  4, c > 0   no real root, pairs α₁ ± iβ₁, α₂ ± iβ₂: u = α₁ + b tan(φ₀ + χ), b = ±β₁
==================  =========  ======================================================================================

A quartic with four real roots outside them runs through ∞ on the Möbius arc of ``closed_form_u`` with its roots
labelled cyclically (u_a = r₄, u_b = r₁ through ∞, u_c = r₂, u_d = r₃); the cubic's branch u ≥ r₃ likewise.
"""

from __future__ import annotations

from typing import Any

__all__ = ["configuration_formulas", "CONFIGURATIONS"]

#: degree -> the configurations printed for it
CONFIGURATIONS = {0: ("polynomial",), 1: ("polynomial",), 2: ("sinh", "cosh", "double_root"), 3: ("cn_cubic",),
                  4: ("cn_quartic", "cn_quartic_outside", "tan")}


def configuration_formulas(u: Any, lead: Any, degree: int) -> dict:
    """{configuration: (lhs, value, meaning)} for P of ``degree`` with leading coefficient ``lead`` in the variable
    ``u`` (its name is printed): see the module docstring."""
    import sympy as sp

    name = sp.Symbol(str(u))
    tau = sp.Symbol("t") - sp.Symbol("t_0")
    chi = sp.Symbol("chi", real=True)
    cn = sp.cos(chi)
    kappa_sym, k2 = sp.Symbol("kappa"), sp.Symbol("k") ** 2
    # the complex pair z_re ± i z_im (not α, β: those name the heavy top's constants (3.72) in generated code)
    alpha, beta, sigma, r = sp.symbols("z_re z_im sigma u_r", real=True)
    out: dict = {}
    elliptic_lhs = sp.Matrix([name, k2, kappa_sym])
    for config in CONFIGURATIONS[degree]:
        if config == "polynomial":
            c1 = sp.Symbol("c_1", real=True)
            u0, v0 = sp.Symbol("u_0", real=True), sp.Symbol("udot_0", real=True)
            out[config] = (name, u0 + v0 * tau + c1 / 4 * tau**2,
                           "uniform (deg P = 0) or uniformly accelerated (deg P = 1, P = c_1 u + c_0) motion: "
                           "udot_0 = ±√P(u_0) at t_0")
        elif config == "sinh":
            kappa = sp.sqrt(lead)
            v0 = sp.Symbol("v_0", real=True)
            out[config] = (name, alpha + beta * sp.sinh(kappa * tau + v0),
                           "P = c((u − z_re)² + z_im²), c > 0, no real root: u passes every value, κ = √c")
        elif config == "cosh":
            r1, r2 = sp.symbols("u_1 u_2", real=True)
            t_turn = sp.Symbol("t_turn", real=True)
            kappa = sp.sqrt(lead)
            out[config] = (name, (r1 + r2) / 2 + sigma * (r2 - r1) / 2
                           * sp.cosh(kappa * (sp.Symbol("t") - t_turn)),
                           "P = c(u − u_1)(u − u_2), c > 0, u outside [u_1, u_2]: σ = +1 beyond u_2, −1 below u_1; it "
                           "turns at the root at t_turn and escapes to ∞ both ways (κ = √c)")
        elif config == "double_root":
            s, u0 = sp.Symbol("s", real=True), sp.Symbol("u_0", real=True)
            out[config] = (name, r + (u0 - r) * sp.exp(s * sp.sqrt(lead) * tau),
                           "P = c(u − u_r)², c > 0 (a separatrix of the inverted oscillator): s = ±1 the sign of "
                           "(u − u_r)·u̇, away from u_r (+1) or towards it (−1), never reaching it")
        elif config == "cn_cubic":
            A = sp.sqrt((r - alpha) ** 2 + beta**2)
            value = sp.Matrix([r + sigma * A * (1 - cn) / (1 + cn), (1 - sigma * (r - alpha) / A) / 2,
                               sp.sqrt(sp.Abs(lead) * A)])
            out[config] = (elliptic_lhs, value,
                           "one real root u_r and the pair z_re ± i z_im: u from u_r out to ∞ on the side σ = sign c, reached "
                           "at cn = −1 (χ = π) in finite time; cn v = cos χ")
        elif config == "cn_quartic":
            a, b = sp.symbols("u_a u_b", real=True)
            da, db = sp.sqrt((a - alpha) ** 2 + beta**2), sp.sqrt((b - alpha) ** 2 + beta**2)
            A, B, C, D = a * db + b * da, a * db - b * da, db + da, db - da
            value = sp.Matrix([(A + B * cn) / (C + D * cn), ((b - a) ** 2 - (da - db) ** 2) / (4 * da * db),
                               sp.sqrt(-lead * da * db)])
            out[config] = (elliptic_lhs, value,
                           "real roots u_a < u_b and the pair z_re ± i z_im, c < 0: u oscillates between u_a (cn = 1) and u_b "
                           "(cn = −1), period 4K/κ")
        elif config == "cn_quartic_outside":
            e, f = sp.symbols("u_e u_f", real=True)
            E, F = sp.sqrt((e - alpha) ** 2 + beta**2), sp.sqrt((f - alpha) ** 2 + beta**2)
            value = sp.Matrix([(e * F - f * E + (e * F + f * E) * cn) / (F - E + (F + E) * cn),
                               ((E + F) ** 2 - (e - f) ** 2) / (4 * E * F), sp.sqrt(lead * E * F)])
            out[config] = (elliptic_lhs, value,
                           "real roots u_e (on the start's side) and u_f, the pair z = z_re ± i z_im, c > 0, u outside "
                           "[u_e, u_f]: from u_e (cn = 1) out to ∞ at cn = (E − F)/(E + F), E = |u_e − z|, F = |u_f − z|")
        elif config == "tan":
            a1, b1, a2, b2 = sp.symbols("z1_re z1_im z2_re z2_im", real=True)
            bb = sp.Symbol("b", real=True)
            A, B, C = (a1 - a2) ** 2 + b2**2, (a1 - a2) * bb, b1**2
            R = sp.sqrt(((A - C) / 2) ** 2 + B**2)
            lam1 = (A + C) / 2 + R
            phi0 = sp.atan2(B, (A - C) / 2) / 2
            value = sp.Matrix([a1 + bb * sp.tan(phi0 + chi), 2 * R / lam1, sp.sqrt(lead * lam1)])
            out[config] = (elliptic_lhs, value,
                           "no real root, pairs z1_re ± i z1_im, z2_re ± i z2_im, c > 0: b = ±z1_im (the sign of u̇), χ = am v, "
                           "u passes every value, escaping at φ₀ + χ = ±π/2")
    return out
