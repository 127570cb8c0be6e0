"""§3.6 generalised (issue 16): the printed closed forms of u̇² = P(u) for each root configuration
(``derive SCENE.toml closed_form_u_<configuration>``), each put back into u̇² = P(u): symbolically (the elementary
ones, by difference), or at 30 digits at seeded random roots and amplitudes (the elliptic ones: u̇ = (du/dχ)·κ·dn,
du/dχ by mpmath's numerical derivative, P = c·Π(u − roots) written here from the roots)."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechderive.systems.lagrangian.configurations import configuration_formulas

U = sp.Symbol("u")
C = sp.Symbol("c", real=True)
T = sp.Symbol("t")


def _symbols(expr):
    return {s.name: s for s in expr.free_symbols}


def _zero(expr):
    return sp.expand(expr.rewrite(sp.exp)) == 0


def test_elementary_forms_satisfy_the_quadrature_symbolically():
    """u̇² − P(u) expands to 0 (hyperbolic functions rewritten in exponentials): deg ≤ 1 with c_0 = u̇_0² − c_1 u_0 (the start on the motion); sinh with
    P = c((u − z_re)² + z_im²); cosh with P = c(u − u_1)(u − u_2), σ = ±1; the double root with P = c(u − u_r)²,
    s = ±1 (c > 0 in the three: κ = √c)."""
    cp = sp.Symbol("c", positive=True)
    line = configuration_formulas(U, C, 1)["polynomial"][1]
    s = _symbols(line)
    P = s["c_1"] * line + (s["udot_0"] ** 2 - s["c_1"] * s["u_0"])
    assert sp.expand(sp.diff(line, T) ** 2 - P) == 0
    forms = configuration_formulas(U, cp, 2)
    u = forms["sinh"][1]
    s = _symbols(u)
    assert _zero(sp.diff(u, T) ** 2 - cp * ((u - s["z_re"]) ** 2 + s["z_im"] ** 2))
    for sign in (1, -1):
        u = forms["cosh"][1]
        s = _symbols(u)
        u = u.subs(s["sigma"], sign)
        assert _zero(sp.diff(u, T) ** 2 - cp * (u - s["u_1"]) * (u - s["u_2"]))
        u = forms["double_root"][1]
        s = _symbols(u)
        u = u.subs(s["s"], sign)
        assert _zero(sp.diff(u, T) ** 2 - cp * (u - s["u_r"]) ** 2)


def _check_elliptic(value, lead, roots, values, rng):
    """[u(χ), m, κ] at 30 digits: 0 < m < 1 and u̇² = P(u) at 6 random amplitudes (relative 1e-25 of |P| + |u̇²|)."""
    names = sorted(values)
    chi = sp.Symbol("chi", real=True)
    f = sp.lambdify([chi, *[sp.Symbol(n, real=True) for n in names]], list(value), "mpmath")
    with mpmath.workdps(30):
        args = [mpmath.mpf(values[n]) for n in names]
        _, m, kappa = f(mpmath.mpf("0.3"), *args)
        assert 0 < m < 1
        for x in rng.uniform(-1.4, 1.4, size=6):
            x = mpmath.mpf(x)
            u = f(x, *args)[0]
            dudchi = mpmath.diff(lambda y: f(y, *args)[0], x)
            u_dot_sq = (dudchi * kappa) ** 2 * (1 - m * mpmath.sin(x) ** 2)
            P = lead * mpmath.fprod(u - r for r in roots)
            assert abs(u_dot_sq - P) <= mpmath.mpf(10) ** -25 * (abs(P) + abs(u_dot_sq)), (x, u_dot_sq, P)
    return m


@pytest.mark.parametrize("config", ["cn_cubic", "cn_quartic", "cn_quartic_outside", "tan"])
def test_elliptic_forms_satisfy_the_quadrature_at_30_digits(config, rng):
    """Random roots (seeded) of the configuration, both signs where a sign is a choice (σ = sign c of the cubic, b = ±z1_im
    of the tan form, which real root the start is beside), each at six random amplitudes χ."""
    degree = 3 if config == "cn_cubic" else 4
    lead = sp.Symbol("c", real=True)
    value = configuration_formulas(U, lead, degree)[config][1]
    for _ in range(3):
        zr, zi = rng.normal(), abs(rng.normal()) + 0.1
        z = (mpmath.mpc(zr, zi), mpmath.mpc(zr, -zi))
        if config == "cn_cubic":
            r, c = rng.normal(), rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 2.0)
            values = {"u_r": r, "z_re": zr, "z_im": zi, "sigma": np.sign(c), "c": c}
            roots = (mpmath.mpf(r), *z)
        elif config == "cn_quartic":
            a, b = sorted(rng.normal(size=2) * 2)
            c = -rng.uniform(0.5, 2.0)
            values = {"u_a": a, "u_b": b, "z_re": zr, "z_im": zi, "c": c}
            roots = (mpmath.mpf(a), mpmath.mpf(b), *z)
        elif config == "cn_quartic_outside":
            e, f = rng.normal(size=2) * 2  # either order: e the root beside the start
            c = rng.uniform(0.5, 2.0)
            values = {"u_e": e, "u_f": f, "z_re": zr, "z_im": zi, "c": c}
            roots = (mpmath.mpf(e), mpmath.mpf(f), *z)
        else:
            z2r, z2i = rng.normal(), abs(rng.normal()) + 0.1
            c = rng.uniform(0.5, 2.0)
            values = {"z1_re": zr, "z1_im": zi, "z2_re": z2r, "z2_im": z2i, "c": c, "b": rng.choice([-1, 1]) * zi}
            roots = (*z, mpmath.mpc(z2r, z2i), mpmath.mpc(z2r, -z2i))
        _check_elliptic(value, values["c"], roots, values, rng)


def test_derive_prints_each_configuration_in_text_latex_and_python(tmp_path):
    """The command prints the cn form of a quartic with a complex pair in the three formats; the generated NumPy code,
    run, gives a u(χ) that satisfies u̇² = P(u) with the scene's own P (its roots at 30 digits from the motion's
    start), in doubles to 1e-12 of |P| + |u̇²| (a finite difference of the doubles, step 1e-5: truncation ~1e-10 of
    du/dχ, so 1e-8 relative here)."""
    import contextlib
    import io

    from mechderive.cli import main

    scene = tmp_path / "quartic.toml"
    scene.write_text('system = "lagrangian"\ncoordinates = ["x", "y"]\n'
                     'lagrangian = "x_dot**2/2 + y_dot**2/(2*(1 + x**2)) - x**4/4 + x"\n[parameters]\n'
                     '[initial]\nx = 0.3\ny = 0.0\nx_dot = 0.5\ny_dot = 0.8\n[time]\nt_end = 1.0\nsamples = 3\n'
                     '[output]\nquantities = ["x"]\n', encoding="utf-8")
    printed = {}
    for fmt in ("text", "latex", "python"):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            main(["derive", str(scene), "closed_form_u_cn_quartic", "--format", fmt])
        printed[fmt] = out.getvalue()
    assert "cos(χ)" in printed["text"] and "\\cos{\\left(\\chi \\right)}" in printed["latex"]
    namespace: dict = {}
    exec(printed["python"], namespace)
    function = next(v for k, v in namespace.items() if k.endswith("closed_form_u_cn_quartic"))
    # P = 2E − p²(1 + x²) − x⁴/2 + 2x with the start's E and p (by hand), its roots at 30 digits
    with mpmath.workdps(30):
        x0, xd0, yd0 = mpmath.mpf("0.3"), mpmath.mpf("0.5"), mpmath.mpf("0.8")
        p = yd0 / (1 + x0**2)
        E = xd0**2 / 2 + p**2 * (1 + x0**2) / 2 + x0**4 / 4 - x0
        coeffs = [-mpmath.mpf(1) / 2, 0, -p**2, 2, 2 * E - p**2]
        roots = mpmath.polyroots(coeffs, extraprec=60)
        real = sorted(mpmath.re(r) for r in roots if abs(mpmath.im(r)) < 1e-20)
        pair = next(r for r in roots if mpmath.im(r) > 1e-20)
    args = dict(u_a=float(real[0]), u_b=float(real[1]), z_re=float(pair.real), z_im=float(pair.imag))
    chi = np.array([0.2, 1.1, 2.5])
    h = 1e-5
    u, m, kappa = (function(chi=chi, **args)[..., i, 0] for i in range(3))
    dudchi = (function(chi=chi + h, **args)[..., 0, 0] - function(chi=chi - h, **args)[..., 0, 0]) / (2 * h)
    u_dot_sq = (dudchi * kappa) ** 2 * (1 - m * np.sin(chi) ** 2)
    P = np.polyval([float(c) for c in coeffs], u)
    assert np.all(np.abs(u_dot_sq - P) <= 1e-8 * (np.abs(P) + np.abs(u_dot_sq)))


def test_a_configuration_of_another_degree_is_refused_with_the_reason():
    from mechderive.errors import DerivationError
    from mechderive.scenes.schema import parse_scene

    # the cn scene of test_s3_6_closed_form_in_time (same group: its reduction derived once)
    system = parse_scene({"system": "lagrangian", "coordinates": ["x", "y"], "parameters": {},
                          "lagrangian": "x_dot**2/2 + y_dot**2/(2*(1 + x**2)) - x**4/4 + x",
                          "initial": dict(x=0.3, y=0.0, x_dot=0.5, y_dot=0.8), "time": {"t_end": 1.0, "samples": 2},
                          "output": {"quantities": ["x"]}}).model
    derivation = next(d for d in system.derivations() if d.name == "closed_form_u_sinh")
    with pytest.raises(DerivationError, match="expected P of degree 2, got degree 4"):
        derivation.build(None)
