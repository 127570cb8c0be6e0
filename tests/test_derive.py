"""``mechderive derive`` and :mod:`mechderive.derive`: every format checked by using its output.

- text / LaTeX: LaTeX is compiled by ``pdflatex`` when it is installed (else that test skips and
  the structural test still runs);
- sympy: the printed source is exec'd and equals the derivation (difference 0);
- python: the module is written, imported, called at seeded random points and compared with
  :func:`mechderive.core.compile.compile_expressions` to 1e-13; its doctests (the SciPy example
  of ``rotation``) run;
- c: compiled with the system C compiler (``cc -shared -fPIC``), called through ctypes, compared;
- json: parsed, and its ``srepr`` rebuilds the objects;
- the 24 sequences (12 × body/space) against SciPy's ``Rotation.from_euler``;
- the sympy.physics.mechanics export against HeavyTopModel, exactly.
"""

from __future__ import annotations

import ctypes
import doctest
import importlib.util
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp

from mechderive.cli import main
from mechderive.core.compile import compile_expressions
from mechderive.core.simplify import is_zero
from mechderive.core.symbols import state_symbol
from mechderive.derive import (SEQUENCES, SYSTEMS, derive, derive_entries, listing, render, rotation_sequence,
                               scipy_sequence, to_c_source, to_latex, to_python_source, to_sympy_source)
from mechderive.derive.formats import argument_order
from mechderive.derive.sequences import FRAMES, check_sequence, sequence_model
from mechderive.errors import InvalidInputError

# One request per system (and a few options), kept small enough for a fast suite.
CASES = {
    "heavy_top": dict(system="heavy_top"),
    "heavy_top_more": dict(system="heavy_top", quantities=["f_u", "precession_rate_u", "mass_matrix", "euler_lagrange",
                                                           "effective_potential", "minimum_spin"]),
    "heavy_top_cone": dict(system="heavy_top", quantities=["accelerations", "energy"], shape="solid_cone"),
    "free_top": dict(system="free_top"),
    "free_top_more": dict(system="free_top", quantities=["stability_A", "euler_equations_torque", "angular_momentum"],
                          sequence="XYZ"),
    "falling_cat": dict(system="falling_cat", quantities=["Omega_swivel", "field_strength"]),
    "rotation": dict(system="rotation", quantities=["R", "A", "R2"]),
    "rotation_zyx": dict(system="rotation", quantities=["R", "A"], sequence="zyx"),
    "angular_velocity": dict(system="angular_velocity", quantities=["body", "space", "matrix"]),
    "inertia": dict(system="inertia", shape="solid_cone", quantities=["centre_of_mass", "inertia_cm", "inertia_pivot"]),
}

_ENTRIES: dict[str, list] = {}


def entries(case: str) -> list:
    """The derived records of a case (derived once per test session)."""
    if case not in _ENTRIES:
        kwargs = dict(CASES[case])
        _ENTRIES[case] = derive_entries(kwargs.pop("system"), kwargs.pop("quantities", None), **kwargs)
    return _ENTRIES[case]


def _system(case: str) -> str:
    return CASES[case]["system"]


def _sample(args, rng, n=5):
    """Seeded random values for ``args``: angles in (0.3, 2.8) (away from sin θ = 0), θ0 in (0.2, 1.3)
    (cos θ0 > 0, where (3.81) is real), others in (0.5, 2)."""
    values = []
    for a in args:
        lo, hi = (0.3, 2.8) if a.name in ("theta", "phi", "psi", "bend", "swivel") else (0.5, 2.0)
        lo, hi = (0.2, 1.3) if a.name == "theta0" else (lo, hi)
        values.append(rng.uniform(lo, hi, n))
    return values


def _numeric_cases(case):
    return [d for d in entries(case) if not (d.value.free_symbols if isinstance(d.value, sp.MatrixBase)
                                             else sp.sympify(d.value).free_symbols) == set()]


# --------------------------------------------------------------------------------------- listing
def test_list_names_every_quantity_with_its_equation(capsys):
    for name, spec in SYSTEMS.items():
        assert main(["derive", name, "--list"]) == 0
        out = capsys.readouterr().out
        for q, _, eq in listing(name):
            line = next(l for l in out.splitlines() if l[3:].startswith(q + " "))
            if eq:  # a system beyond the chapter (rigid_body's potential) cites no equation
                assert f"({eq})" in line
            assert line.startswith(" *") == (q in spec.defaults)
    main(["derive", "heavy_top", "--list"])
    out = capsys.readouterr().out
    assert "p_phi" in out and "(3.64)" in out and "f_u" in out and "(3.73)" in out


def test_default_text_output(capsys):
    assert main(["derive", "heavy_top"]) == 0
    out = capsys.readouterr().out
    for q in ("lagrangian", "accelerations", "p_psi", "p_phi", "energy"):
        assert f"# {q}:" in out
    assert "L = I₁⋅" in out and "p_ψ = I₃⋅(φ̇⋅cos(θ) + ψ̇)" in out
    assert main(["derive", "heavy_top", "p_phi"]) == 0
    assert capsys.readouterr().out.count("# p_phi") == 1


# --------------------------------------------------------------------------------- the values
def test_values_are_the_models_derivations():
    from mechderive.systems.free_top.model import model as free
    from mechderive.systems.heavy_top.model import model as heavy

    out = derive("heavy_top", ["p_phi", "f_u", "accelerations"])
    assert out["p_phi"] == heavy().azimuthal_momentum and out["f_u"] == heavy().f_u
    assert out["accelerations"] == heavy().accelerations
    assert derive("free_top", ["stability_A"])["stability_A"] == free().stability_coefficient
    # (3.58) from Ṙ Rᵀ of the sequence module equals the kinematics model's, exactly
    from mechderive.kinematics.euler import model as kin

    body = derive("angular_velocity", ["body"])["body"]
    assert all(is_zero(e) for e in body - kin().state_angular_velocity_body)


def test_shape_substitutes_the_derived_inertia():
    M, R, h = sp.symbols("M R h", positive=True)
    cone = derive("heavy_top", ["p_psi", "potential_energy"], shape="solid_cone")
    spin = state_symbol("phi_dot") * sp.cos(state_symbol("theta")) + state_symbol("psi_dot")
    assert sp.simplify(cone["p_psi"] - sp.Rational(3, 10) * M * R**2 * spin) == 0      # I3 = 3MR²/10
    g = sp.Symbol("g", positive=True)
    assert sp.simplify(cone["potential_energy"] - M * g * 3 * h / 4 * sp.cos(state_symbol("theta"))) == 0  # l = 3h/4
    d = sp.Symbol("d", positive=True)
    disc = derive("heavy_top", ["kinetic_energy"], shape="disc", pivot="-d")["kinetic_energy"]
    I1 = M * R**2 / 4 + M * d**2                                                        # (3.25)
    assert sp.expand(disc - derive("heavy_top", ["kinetic_energy"])["kinetic_energy"].subs(
        {sp.Symbol("I1", positive=True): I1, sp.Symbol("I3", positive=True): M * R**2 / 2})) == 0


def test_moments_values_simplify():
    out = derive("free_top", ["euler_equations"], moments=[1, 2, 3], values={"omega3": 0})
    w1, w2 = state_symbol("omega1"), state_symbol("omega2")
    assert out["euler_equations"] == sp.Matrix([0, 0, -w1 * w2 / 3])    # (I1 − I2)/I3 = −1/3
    top = derive("heavy_top", ["energy"], values={"g": 9.81})["energy"]
    assert sp.Rational(981, 100) in top.atoms(sp.Rational)
    s = derive("rotation", ["R"], simplify=True)["R"]
    assert all(is_zero(e) for e in s - rotation_sequence("ZXZ"))


def test_cse_prints_subexpressions(capsys):
    assert main(["derive", "heavy_top", "accelerations", "--cse"]) == 0
    out = capsys.readouterr().out
    assert "x₀ = " in out
    assert main(["derive", "heavy_top", "accelerations", "--cse", "--format", "latex"]) == 0
    assert "x_{0} &= " in capsys.readouterr().out


# ------------------------------------------------------------------------------------ sequences
def test_twenty_four_sequences_match_scipy(rng):
    from scipy.spatial.transform import Rotation

    q = [state_symbol(n) for n in ("phi", "theta", "psi")]
    for seq in SEQUENCES:
        for frame in FRAMES:
            f = compile_expressions(rotation_sequence(seq, frame=frame), q)
            angles = rng.uniform(-np.pi, np.pi, (20, 3))
            expected = Rotation.from_euler(scipy_sequence(seq, frame), angles).as_matrix()
            np.testing.assert_allclose(f(*angles.T), np.swapaxes(expected, -1, -2), rtol=0, atol=1e-14,
                                       err_msg=f"{seq} {frame}")


def test_space_fixed_is_body_fixed_reversed():
    phi, theta, psi = (state_symbol(n) for n in ("phi", "theta", "psi"))
    for seq in SEQUENCES:
        space = rotation_sequence(seq, frame="space")
        body = rotation_sequence(seq[::-1]).subs({phi: psi, psi: phi}, simultaneous=True)
        assert (space - body).applyfunc(sp.expand) == sp.zeros(3, 3), seq


def _check_omega(seq, frame, rng):
    """ω of Ṙ Rᵀ (3.5)–(3.6) against a central difference of SciPy's matrices along a random path."""
    from scipy.spatial.transform import Rotation

    m = sequence_model(seq, frame)
    names = ("phi", "theta", "psi", "phi_dot", "theta_dot", "psi_dot")
    f_body = compile_expressions(derive("angular_velocity", ["body", "space"], sequence=seq, frame=frame)["body"],
                                 [state_symbol(n) for n in names])
    f_space = compile_expressions(derive("angular_velocity", ["space"], sequence=seq, frame=frame)["space"],
                                  [state_symbol(n) for n in names])
    s = scipy_sequence(m.sequence, m.frame)
    for _ in range(3):
        q, qd = rng.uniform(0.3, 1.2, 3), rng.uniform(-2, 2, 3)
        h = 1e-5
        R = lambda a: Rotation.from_euler(s, a).as_matrix().T  # noqa: E731
        Rdot = (R(q + h * qd) - R(q - h * qd)) / (2 * h)
        W = Rdot @ R(q).T
        w = np.array([W[1, 2], W[2, 0], W[0, 1]])                # ω_a = ½ ε_abc ω_bc (3.6)
        np.testing.assert_allclose(f_body(*q, *qd)[:, 0], w, atol=1e-8, err_msg=f"{seq} {frame}")
        np.testing.assert_allclose(f_space(*q, *qd)[:, 0], R(q).T @ w, atol=1e-8)


@pytest.mark.parametrize("seq,frame", [("ZXZ", "body"), ("XYZ", "body"), ("ZYX", "space"), ("YXY", "space")])
def test_angular_velocity_of_sequences(seq, frame, rng):
    _check_omega(seq, frame, rng)


@pytest.mark.slow
def test_angular_velocity_of_all_24_sequences(rng):
    for seq in SEQUENCES:
        for frame in FRAMES:
            _check_omega(seq, frame, rng)


def test_sequence_names_and_case():
    assert check_sequence("zxz") == ("ZXZ", "space")
    assert scipy_sequence("ZXZ") == "ZXZ" and scipy_sequence("ZXZ", "space") == "zxz"
    with pytest.raises(InvalidInputError, match="expected an upper-case sequence with frame 'body'"):
        check_sequence("zxz", "body")
    with pytest.raises(InvalidInputError, match=r"expected an Euler sequence among ZXZ, XYX.*got 'ZZX'"):
        check_sequence("ZZX")
    with pytest.raises(InvalidInputError, match="expected an Euler sequence .* got 'Zxz'"):
        check_sequence("Zxz")
    with pytest.raises(InvalidInputError, match="expected frame 'body' or 'space', got 'moving'"):
        check_sequence("ZXZ", "moving")


# --------------------------------------------------------------------------------------- formats
def _compiled(d):
    args = argument_order(d.value)
    return args, compile_expressions(d.value, args)


def _import(path, name):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("case", list(CASES))
def test_python_output_runs_and_matches_the_compiled_function(case, tmp_path, rng):
    src = render(entries(case), "python", system=_system(case), summary="test")
    path = tmp_path / f"gen_{case}.py"
    path.write_text(src)
    module = _import(path, f"gen_{case}")
    for d in entries(case):
        fn = getattr(module, f"{_system(case)}_{d.name}")
        args, reference = _compiled(d)
        assert [p for p in fn.__code__.co_varnames[:fn.__code__.co_argcount]] == [a.name for a in args]
        values = _sample(args, rng)
        got, expected = fn(*values), reference(*values)
        assert np.all(np.isfinite(expected))
        np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-13 * (1 + np.max(np.abs(expected))),
                                   err_msg=f"{case} {d.name}")
        assert "Arguments, in order" in fn.__doc__
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    if _system(case) == "rotation":
        assert result.attempted >= 6          # the SciPy conversion example ran


def test_rotation_python_documents_the_scipy_conversion(capsys):
    assert main(["derive", "rotation", "--sequence", "XYZ", "--frame", "space", "--format", "python"]) == 0
    out = capsys.readouterr().out
    assert 'Rotation.from_euler("xyz", angles).as_matrix().T' in out
    assert "Rotation.from_matrix(R.T).as_euler(\"xyz\")" in out


def _cc():
    return shutil.which("cc") or shutil.which("gcc")


@pytest.mark.skipif(_cc() is None, reason="no C compiler")
@pytest.mark.parametrize("case", ["heavy_top", "heavy_top_more", "free_top_more", "falling_cat", "rotation_zyx",
                                  "angular_velocity", "inertia"])
def test_c_output_compiles_and_matches(case, tmp_path, rng):
    src = render(entries(case), "c", system=_system(case), summary="test")
    (tmp_path / "gen.c").write_text(src)
    lib = tmp_path / "gen.so"
    proc = subprocess.run([_cc(), "-std=c99", "-O1", "-Wall", "-Werror", "-shared", "-fPIC", "-o", str(lib),
                           str(tmp_path / "gen.c"), "-lm"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    so = ctypes.CDLL(str(lib))
    for d in _numeric_cases(case):
        args, reference = _compiled(d)
        fn = getattr(so, f"{_system(case)}_{d.name}")
        n = len(d.value) if isinstance(d.value, sp.MatrixBase) else 1
        fn.argtypes = [ctypes.c_double] * len(args) + [ctypes.POINTER(ctypes.c_double)]
        fn.restype = None
        for point in np.array(_sample(args, rng, 4)).T:
            out = (ctypes.c_double * n)()
            fn(*map(float, point), out)
            expected = np.ravel(reference(*point))
            assert np.all(np.isfinite(expected))
            np.testing.assert_allclose(np.array(out), expected, rtol=1e-12,
                                       atol=1e-13 * (1 + np.max(np.abs(expected))), err_msg=f"{case} {d.name}")


@pytest.mark.parametrize("case", list(CASES))
def test_sympy_output_rebuilds_the_objects(case):
    src = render(entries(case), "sympy", system=_system(case), summary="test")
    ns: dict = {}
    exec(src, ns)  # noqa: S102 - our own generated source
    for d in entries(case):
        rebuilt = ns[d.name]
        diff = rebuilt - d.value
        assert (diff.applyfunc(sp.expand) == sp.zeros(*diff.shape)) if isinstance(diff, sp.MatrixBase) \
            else sp.expand(diff) == 0
        assert (rebuilt.free_symbols if hasattr(rebuilt, "free_symbols") else set()) == \
            (d.value.free_symbols if hasattr(d.value, "free_symbols") else set())   # same assumptions


@pytest.mark.parametrize("case", ["heavy_top", "free_top_more", "rotation", "inertia"])
def test_json_output(case):
    data = json.loads(render(entries(case), "json", system=_system(case), summary="test"))
    assert data["system"] == _system(case)
    for item, d in zip(data["quantities"], entries(case)):
        assert item["name"] == d.name and item["equation"] == d.equation
        assert set(item) >= {"text", "latex", "str", "srepr", "description"}
        assert eval(item["srepr"], dict(vars(sp))) == d.value  # noqa: S307 - srepr of our own objects


# ------------------------------------------------------------------------------------------ LaTeX
def _latex_document(cases):
    body = "\n\n".join(render(entries(c), "latex", system=_system(c), summary="test", cse=(c == "heavy_top_more"))
                       for c in cases)
    return ("\\documentclass{article}\n\\usepackage{amsmath}\n\\usepackage[a3paper,landscape,margin=1cm]{geometry}\n"
            "\\begin{document}\n" + body + "\n\\end{document}\n")


def test_latex_structure():
    for case in CASES:
        text = render(entries(case), "latex", system=_system(case), summary="test")
        assert text.count("\\begin{equation}") == text.count("\\end{equation}") == len(entries(case))
        depth = 0
        for ch in text.replace("\\{", "").replace("\\}", ""):
            depth += {"{": 1, "}": -1}.get(ch, 0)
            assert depth >= 0
        assert depth == 0
    heavy = render(entries("heavy_top"), "latex", system="heavy_top")
    assert "\\dot{\\phi}" in heavy and "I_{1}" in heavy and "\\ddot{\\theta}" in heavy and "p_{\\psi} =" in heavy
    assert to_latex(sp.Symbol("omega1_dot")) == "\\dot{\\omega}_{1}"


@pytest.mark.skipif(shutil.which("pdflatex") is None, reason="pdflatex not installed (apt-get install texlive-latex-base)")
def test_latex_compiles_with_pdflatex(tmp_path):
    cases = [c for c in CASES if c != "falling_cat"] + ["falling_cat"]
    (tmp_path / "doc.tex").write_text(_latex_document(cases), encoding="utf-8")
    proc = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error", "doc.tex"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout[-3000:]
    assert (tmp_path / "doc.pdf").stat().st_size > 1000
    assert "Undefined control sequence" not in proc.stdout


# --------------------------------------------------------------------------------- code functions
def test_code_functions_check_their_arguments():
    x, y = sp.symbols("x y")
    with pytest.raises(InvalidInputError, match="expected the arguments to include every free symbol, got y missing"):
        to_python_source(x + y, [x])
    with pytest.raises(InvalidInputError, match="expected a C identifier for the function name, got 'double'"):
        to_c_source(x, [x], "double")
    with pytest.raises(InvalidInputError, match="expected expressions in plain symbols for code, got f"):
        to_python_source(sp.Function("f")(x), [x])
    lam = sp.Symbol("lambda")                            # a Python keyword as a symbol name
    ns: dict = {}
    exec(to_python_source(lam**2, [lam], "square"), ns)  # noqa: S102
    assert float(ns["square"](3.0)) == 9.0
    assert "y0_" in to_c_source(sp.Symbol("y0") + 1, None, "shift")   # <math.h>'s y0 not shadowed
    src = to_sympy_source({"b": sp.Symbol("beta", positive=True) + sp.Rational(1, 3)})
    ns = {}
    exec(src, ns)  # noqa: S102
    assert ns["b"] - sp.Symbol("beta", positive=True) == sp.Rational(1, 3)


# ------------------------------------------------------------------------------------- interop
def test_mechanics_export_agrees_with_the_heavy_top():
    from mechderive.interop import to_mechanics
    from mechderive.kinematics.euler import model as kin
    from mechderive.systems.heavy_top.model import model as heavy

    m = to_mechanics("heavy_top")
    assert all(is_zero(e) for e in m.to_state(m.frame.dcm(m.space)) - kin().state_rotation)   # B.dcm(N) = R
    h = heavy()
    assert is_zero(m.to_state(m.lagrangian) - h.state_lagrangian)
    # mechanics' M q̈ − F vanishes identically at our accelerations, and the mass matrices agree
    assert all(is_zero(e) for e in m.mass_matrix() * h.accelerations - m.forcing())
    assert all(is_zero(e) for e in m.mass_matrix() - h.mass_matrix)
    free = to_mechanics("free_top")
    ours = derive("free_top", ["lagrangian"])["lagrangian"]
    assert is_zero(free.to_state(free.lagrangian) - ours)
    with pytest.raises(InvalidInputError, match="expected a system among heavy_top, free_top, got 'cat'"):
        to_mechanics("cat")


# ---------------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("argv,message", [
    (["derive", "nope"], "expected a system among free_top, heavy_top, falling_cat, rigid_body, rotation, angular_velocity, "
                         "inertia, got 'nope'"),
    (["derive", "heavy_top", "q_dot"], "expected quantities of heavy_top among lagrangian, accelerations, .*got 'q_dot'"),
    (["derive", "heavy_top", "--format", "pdf"], "expected a format among text, latex, sympy, python, c, json, got 'pdf'"),
    (["derive", "rotation", "--sequence", "XXY"], "expected an Euler sequence among ZXZ, .*got 'XXY'"),
    (["derive", "rotation", "--frame", "moving"], "expected frame 'body' or 'space', got 'moving'"),
    (["derive", "heavy_top", "--sequence", "XYZ"], "expected the chapter's ZXZ body-fixed angles for heavy_top"),
    (["derive", "inertia"], "expected a shape after inertia, one of rod, disc, .*got 'none'"),
    (["derive", "inertia", "pyramid"], "expected a shape after inertia, .*got 'pyramid'"),
    (["derive", "heavy_top", "--shape", "pyramid"], "--shape: expected a shape among rod, disc, .*got 'pyramid'"),
    (["derive", "heavy_top", "--shape", "cuboid"], r"--shape: expected a body symmetric about axis 3 \(I1 = I2\)"),
    (["derive", "heavy_top", "--moments", "1", "2", "2"],
     "--moments: expected I1 = I2 for the symmetric heavy top, got 1 and 2"),
    (["derive", "free_top", "--moments", "1", "1", "3"], "--moments: expected I1 \\+ I2 >= I3 \\(triangle"),
    (["derive", "free_top", "--moments", "1", "-1", "1"], "--moments: expected .*> 0"),
    (["derive", "free_top", "--moments", "1", "x", "1"], "--moments I2: expected a number like 9.81"),
    (["derive", "rotation", "--shape", "disc"], "--shape: expected no shape for rotation"),
    (["derive", "heavy_top", "--set", "q=1"], "--set q: expected values for symbols among .*got 'q'"),
    (["derive", "heavy_top", "--set", "g"], "--set: expected NAME=NUMBER with NAME a symbol's name, got 'g'"),
    (["derive", "heavy_top", "--set", "g=fast"],
     "--set g: expected a number like 9.81, -1.5e-3 or 1/3, got 'fast': .*unknown symbol 'fast'"),
    (["derive", "heavy_top", "--set", "g=1/0"], "--set g: .*division by zero"),
    (["derive", "heavy_top", "--set", "g=1e400"], "--set g: expected a number 0 or of magnitude 1e-300 to 1e300"),
    (["derive", "heavy_top", "--set", "g=pi"], "--set g: expected a rational number"),
    (["derive", "heavy_top", "--pivot", "1"], "--pivot: expected a shape with the pivot"),
    (["derive", "heavy_top", "--shape", "disc", "--pivot", "h"],
     r"--pivot: expected the pivot below the centre of mass \(l >= 0\), got l = -h"),
    (["derive", "heavy_top", "--shape", "disc", "--pivot", "sqrt(-h)"], "--pivot: expected a real expression"),
    (["derive", "heavy_top", "--shape", "disc", "--pivot", "dt(h)"], "--pivot: expected a point on axis 3"),
    (["derive", "heavy_top", "--shape", "disc", "--pivot=-e"], "--pivot: expected a symbol, got 'e'"),
    (["derive", "heavy_top", "--shape", "disc", "--pivot", "(a+b+c+d+f)**2"],
     "--pivot: expected a pivot like -h/2 or h/4 - d, with at most 6 symbols, degree 4 and 10 terms"),
])
def test_bad_input_lists_what_is_allowed(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("mechderive: error: ")
    import re

    assert re.search(message, err), err


def test_bad_input_from_python():
    with pytest.raises(InvalidInputError, match="expected a system among .* got 'top'"):
        derive("top")
    with pytest.raises(InvalidInputError, match="expected quantities of free_top among lagrangian, .* got 'L'"):
        derive("free_top", ["L"])
    with pytest.raises(InvalidInputError, match="expected a format among text, .* got 'md'"):
        render([], "md")
    with pytest.raises(InvalidInputError, match="shape, moments: expected a body shape or numeric moments, got both"):
        derive("free_top", shape="disc", moments=[1, 1, 2])
    with pytest.raises(InvalidInputError, match="expected a shape for inertia, one of rod, .* got none"):
        derive("inertia")
    with pytest.raises(InvalidInputError, match="pivot: expected a symbol name starting with a letter, got '__impor"):
        derive("inertia", ["inertia_pivot"], shape="disc", pivot="__import__")
    with pytest.raises(InvalidInputError, match=r"values\['g'\]: expected a number 0 or of magnitude"):
        derive("heavy_top", ["energy"], values={"g": 1e-310})
    with pytest.raises(InvalidInputError, match=r"values\['g'\]: expected a finite real number, got nan"):
        derive("heavy_top", ["energy"], values={"g": float("nan")})
    with pytest.raises(InvalidInputError, match="moments I1: expected a real number, got True"):
        derive("free_top", moments=[True, 1, 1])
    with pytest.raises(InvalidInputError, match="moments: expected three moments I1 I2 I3, got '1 1 1'"):
        derive("free_top", moments="1 1 1")
    with pytest.raises(InvalidInputError, match="pivot: expected the pivot as a number, an expression or its text"):
        derive("inertia", ["inertia_pivot"], shape="disc", pivot=[0])


def test_cli_module_is_light():
    code = ("import argparse, sys; from mechderive.cli import derive; "
            "derive.add_parser(argparse.ArgumentParser().add_subparsers()); print('sympy' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.stdout.strip() == "False", proc.stderr
