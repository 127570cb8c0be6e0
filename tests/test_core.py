"""The derive→compile core: lazy derivation logs, the compile cache, exact trig simplification, validation."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from mechderive.core import compile as cc
from mechderive.core.model import SymbolicModel, derivation_seconds, derived, deriving
from mechderive.core.simplify import TrigField, factor, is_zero, is_zero_rational, simplify_trig, trig_normal
from mechderive.core.validate import as_finite_array, check_positive
from mechderive.errors import InvalidInputError, NonFiniteValueError, ShapeError
from mechderive.kinematics.euler import KinematicsModel


# --- laziness: a request derives only what it needs --------------------------------------------

def test_requesting_rotation_derives_nothing_about_angular_velocity():
    m = KinematicsModel()
    assert m.derived == []
    m.state_rotation
    assert m.derived == ["R3", "R1", "rotation", "state_rotation"]
    assert not m.is_derived("angular_velocity_matrix")


def test_body_angular_velocity_does_not_derive_space_or_convective_quantities():
    m = KinematicsModel()
    m.state_angular_velocity_body
    # by the structure of R = R3 R1 R3: the elementary rotations and their ω, not R itself or Ṙ Rᵀ
    assert set(m.derived) == {"R3", "R1", "elementary_angular_velocities", "angular_velocity_body",
                              "state_angular_velocity_body"}
    assert not m.is_derived("angular_velocity_space") and not m.is_derived("convective_angular_velocity_matrix")
    before = list(m.derived)
    m.state_angular_velocity_body  # cached: no second derivation
    assert m.derived == before


def test_derived_runs_once_and_is_logged_in_order():
    calls = []

    class Toy(SymbolicModel):
        @derived
        def a(self):
            calls.append("a")
            return sp.Symbol("x") ** 2

        @derived
        def b(self):
            calls.append("b")
            return self.a.diff(sp.Symbol("x"))

    toy = Toy()
    assert toy.b == 2 * sp.Symbol("x")
    assert toy.b == 2 * sp.Symbol("x")
    # b starts first and asks for a; the log records completions, so a precedes b.
    assert calls == ["b", "a"] and toy.derived == ["a", "b"]
    assert Toy.quantities() == ["a", "b"]


# --- the compile layer -----------------------------------------------------------------------

def test_a_deriving_block_is_counted_once_with_the_derivations_inside_it():
    # a cold start's imports (SymPy's 0.4-1 s) are counted as deriving when the block that derives does them
    import time

    class Slow(SymbolicModel):
        @derived
        def x(self):
            time.sleep(0.03)
            return 1

    before = derivation_seconds()
    start = time.perf_counter()
    with deriving():
        time.sleep(0.03)  # stands for an import
        assert Slow().x == 1
    wall = time.perf_counter() - start
    spent = derivation_seconds() - before
    # the block's 0.06 s and more, but not its derivation's 0.03 s twice (which would exceed the block's wall)
    assert 0.06 <= spent <= wall


def test_compile_cache_never_compiles_twice():
    x, y = sp.symbols("x y")
    expr = sp.Matrix([[sp.sin(x) * y, x], [y, 1]])
    before = cc.compile_cache_info()
    f1 = cc.compile_expressions(expr, [x, y], name="f")
    f2 = cc.compile_expressions(sp.Matrix([[sp.sin(x) * y, x], [y, 1]]), [x, y], name="g")
    after = cc.compile_cache_info()
    assert f1 is f2
    assert after["misses"] - before["misses"] <= 1 and after["hits"] - before["hits"] >= 1


def test_compile_cache_keeps_apart_what_compiles_differently():
    """The in-process key is structural (no srepr): equal requests share a function, look-alikes do not."""
    x, xr = sp.Symbol("x"), sp.Symbol("x", positive=True)
    d1, d2 = sp.Dummy("x"), sp.Dummy("x")
    f = cc.compile_expressions([x / 3, 1], [x])
    assert cc.compile_expressions([x / 3, 1], [x]) is f  # rebuilt, structurally equal: a hit
    assert cc.compile_expressions([x / 3, 1.0], [x]) is not f  # 1 and 1.0
    assert cc.compile_expressions([x / 3, sp.Float(1.0)], [x]) is not f
    assert cc.compile_expressions([x / sp.Float(3.0), 1], [x]) is not f
    assert cc.compile_expressions([xr / 3, 1], [xr]) is not f  # same name, other assumptions
    assert cc.compile_expressions(sp.Matrix([x / 3, 1]), [x]) is not f  # container kind
    assert cc.compile_expressions(sp.Matrix([[x / 3, 1]]), [x]) is not cc.compile_expressions(sp.Matrix([x / 3, 1]), [x])
    assert cc.compile_expressions(d1 + 1, [d1]) is not cc.compile_expressions(d2 + 1, [d2])
    assert cc.compile_expressions(sp.Float("0.1", 15) * x, [x]) is not cc.compile_expressions(sp.Float("0.1", 30) * x, [x])
    assert cc.compile_scalar([x, 1], [x]) is not cc.compile_scalar([x, 1.0], [x])
    assert cc.compile_expressions([x / 3, 1.0], [x])(3.0).tolist() == [1.0, 1.0]


def test_compiled_matrix_broadcasts_and_matches_sympy(rng):
    x, y = sp.symbols("x y")
    expr = sp.Matrix([[sp.sin(x) * y, x], [sp.exp(y), 1]])
    f = cc.compile_expressions(expr, [x, y])
    xs, ys = rng.normal(size=5), rng.normal(size=5)
    out = f(xs, ys)
    assert out.shape == (5, 2, 2)
    for i in range(5):
        ref = np.array(expr.subs({x: xs[i], y: ys[i]}).evalf(30), dtype=float)
        np.testing.assert_allclose(out[i], ref, rtol=1e-15)
    assert f(0.5, 2.0).shape == (2, 2)
    assert "x, y" in f.__doc__


def test_compiled_scalar_returns_float():
    x = sp.Symbol("x")
    assert cc.compile_expressions(x**2, [x])(3.0) == 9.0


def test_model_compile_logs_name_once():
    m = KinematicsModel()
    syms = [sp.Symbol(n, real=True) for n in ("phi", "theta", "psi")]
    f1 = m.compile("R", m.state_rotation, syms)
    f2 = m.compile("R", m.state_rotation, syms)
    assert f1 is f2 and m.compiled == ["R"]


# --- exact trigonometric identities ----------------------------------------------------------

def test_is_zero_proves_identities_and_refutes_non_identities():
    a, b, c = sp.symbols("a b c", real=True)
    assert is_zero(sp.sin(a) ** 2 + sp.cos(a) ** 2 - 1) is True
    assert is_zero(sp.sin(a + b) - sp.sin(a) * sp.cos(b) - sp.cos(a) * sp.sin(b)) is True
    assert is_zero(sp.tan(a) * sp.cos(a) - sp.sin(a)) is True
    assert is_zero(c * (sp.cos(a) ** 4 - sp.sin(a) ** 4 - sp.cos(2 * a))) is True
    assert is_zero(sp.sin(a) ** 2 - sp.cos(a) ** 2) is False
    assert is_zero(sp.sin(a) * 1.0000001 - sp.sin(a)) is False
    assert is_zero(sp.sqrt(a) - 1) is None  # outside the method: caller must decide otherwise
    # fractions (the unreduced N/D, N reduced modulo cos² + sin² − 1): the half-angle forms of the heavy top's b ∓ a
    assert is_zero(c * (1 - sp.cos(a)) / sp.sin(a) ** 2 - c / (1 + sp.cos(a))) is True
    assert is_zero(2 * sp.sin(a) ** 2 / (1 - sp.sin(a)) - 2 * sp.sin(a) ** 2 * (1 + sp.sin(a)) / sp.cos(a) ** 2) is True
    assert is_zero(c / (1 + sp.cos(a)) - c / (1 - sp.cos(a))) is False


def test_trig_normal_and_simplify_trig():
    a = sp.Symbol("a", real=True)
    assert trig_normal(sp.cos(a) ** 2 + sp.sin(a) ** 2) == 1
    assert simplify_trig((1 - sp.cos(a) ** 2) / sp.sin(a)) == sp.sin(a)
    # several angles, reduced in turn: the normal form has no cos² of either
    b, x, y = sp.symbols("b x y", real=True)
    e = (x * sp.cos(a) ** 3 * sp.cos(b) ** 2 + y * sp.sin(a) * sp.cos(b)) / (x + y * sp.cos(a) ** 2)
    n = trig_normal(e)
    assert not n.has(sp.cos(a) ** 2) and not n.has(sp.cos(b) ** 2) and is_zero(n - e)


def test_trig_field_arithmetic_gives_the_trig_normal_form():
    """Substituting into a polynomial in the field, then normalising, is trig_normal of the substituted
    expression (the same rational function, the same reduction: factored, the same expression)."""
    a, t, x, y = sp.symbols("a t x y", real=True)
    values = {x: (sp.cos(t) + a * sp.sin(t) ** 2) / a, y: a * sp.sin(t) * sp.cos(t) - sp.cos(t) ** 2}
    poly = x**3 - 2 * x * y + y**2 / 3 + 1
    F = TrigField(values.values())
    got = F.normal(F(poly.xreplace(values)))
    assert sp.factor(got) == sp.factor(trig_normal(poly.subs(values)))
    assert not got.has(sp.cos(t) ** 2)
    assert F.normal(F(sp.sin(t) ** 2 + sp.cos(t) ** 2 - 1)) == 0


# --- validation ------------------------------------------------------------------------------

def test_validation_messages():
    with pytest.raises(ShapeError, match=r"expected `w` to have shape \(3,\), got \(2,\)"):
        as_finite_array([1.0, 2.0], "w", shape=(3,))
    with pytest.raises(NonFiniteValueError, match="expected `w` to be finite, got inf"):
        as_finite_array([1.0, np.inf, 0.0], "w")
    with pytest.raises(InvalidInputError, match="expected `w` to be numeric, got 'abc'"):
        as_finite_array("abc", "w")
    with pytest.raises(InvalidInputError, match=r"expected `I1` > 0, got -1.0"):
        check_positive(-1, "I1")


# --- the disk cache of generated code (principle 2: nothing derived or compiled twice) -----------------

def test_disk_cache_keeps_bytecode_and_survives_a_corrupt_copy(tmp_path, monkeypatch):
    import sympy as sp

    from mechderive.core import codecache

    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    codecache.set_disk_cache(True)
    x = sp.Symbol("x")
    try:
        f, _ = codecache.cached_lambdify("test.square_plus_one", lambda: ([x], x**2 + 1))
        codecache.clear_memory()
        g, _ = codecache.cached_lambdify("test.square_plus_one", lambda: pytest.fail("derived again"))
        source = next(tmp_path.rglob("test.square_plus_one.numpy.py"))
        marshalled = source.with_name(source.name + ".marshal")
        assert marshalled.exists() and g(3.0) == f(3.0) == [10.0]
        marshalled.write_bytes(b"not bytecode")  # a damaged copy is recompiled from the source
        codecache.clear_memory()
        h, _ = codecache.cached_lambdify("test.square_plus_one", lambda: pytest.fail("derived again"))
        assert h(2.0) == [5.0]
    finally:
        codecache.set_disk_cache(None)
        codecache.clear_memory()


def test_dependency_versions_match_importlib_metadata():
    from importlib.metadata import version

    from mechderive.core.codecache import _version

    for dist in ("sympy", "numpy", "mpmath"):
        assert _version(dist) == version(dist)


def phi_dot_sq_form(x, y, th):
    return x**2 * sp.cos(th) ** 2 - x**2 - y**2


def test_factor_is_sympys_factor_expression_for_expression():
    """core.simplify.factor skips Wang's irreducibility proofs where a polynomial is linear in a generator with
    coprime coefficients, or quadratic in one with a discriminant that is no square: its result must be
    sympy.factor's, srepr for srepr, whether or not a shortcut applies."""
    x, y, z = sp.symbols("x y z")
    a, b = sp.symbols("a b", positive=True)
    th = sp.Symbol("theta", real=True)
    exprs = [
        2 * a * b / x,  # monomials only
        (-2 * x * y - 4 * z * sp.sin(th) ** 2 + 6 * x) / a,  # content −2 split off, linear in z: the shortcut
        (x * y + y * z) / (x**2 - 1),  # y (x + z): a monomial factor, and x² − 1 = (x − 1)(x + 1): by Wang
        (x + y) ** 2 * (x - z) / (a * x**2),  # square-free parts (x + y) with multiplicity 2
        x**2 * y**2 - z**2,  # (xy − z)(xy + z): of degree 1 in z? no, 2; by Wang
        x**2 + y**2 + z,  # linear in z, a = 1: irreducible
        sp.Rational(3, 4) * x - sp.Rational(1, 2) * y,  # rational coefficients: SymPy's route over QQ
        x * sp.cos(th) + y * sp.sin(th) - a * b,
        -phi_dot_sq_form(x, y, th),  # quadratic in y, discriminant not a square: the second shortcut
        x**2 + y**2, x**2 - y**2, 4 * x**2 - 9, x**2 - 2, (x + y) ** 2 * z**2,  # squares and non-squares
        x**2 * z + x * y + a * b - 1, (x * z + y) * (x * y + z),
        sp.expand((x**2 - 1) * (a * y - b * z)), sp.expand((a - b) * (y - z) * (y + z) ** 2),  # linear with a
        sp.expand(3 * (x - y) * (2 * x + y) * (z - 1)), sp.expand(-(x**2 + y**2) * (x * z - 2)),  # common factor
        2 * x * y + 2 * x * z, (a * x + a * y) / (b * z - b), -x * y**2 / (2 * x * y - 4 * y),  # sums with common
        x / y + z, (x + 1 / y) * (x - y) / 3, sp.Rational(1, 2) * (x + y) ** 2 / z,  # factors, denominators in sums
        sp.sqrt(2) * x + y,  # an algebraic coefficient: SymPy's route
        sp.Integer(0), sp.Integer(5), x,
    ]
    for e in exprs:
        assert sp.srepr(factor(e)) == sp.srepr(sp.factor(e)), e


def test_is_zero_rational_decides_as_the_field_does():
    # the unreduced fraction N/D (no gcds) against the sum in the field Q(symbols), on identities and near misses
    a, b, u, x = sp.symbols("a b u x", real=True)
    along = u + (1 - u) * x
    rate = (b - a * along) / (1 - along**2)
    identity = (a + b) / (2 * (1 + along)) - (a - b) / (2 * (1 - along)) - rate
    assert is_zero_rational(identity) is True
    assert is_zero_rational(identity + a / (1 - x)) is False
    assert is_zero_rational(sp.Rational(1, 3) - sp.Integer(1) / 3) is True
    assert is_zero_rational((a**2 - b**2) / (a - b) - a - b) is True
    assert is_zero_rational(2 * a / 4 - a / 2 + 1 / (a * b) - 1 / (b * a)) is True
    assert is_zero_rational(sp.sin(a) + a) is None
    assert is_zero_rational(sp.sqrt(a) - a) is None
    assert is_zero_rational(sp.Float(0.5) * a - a / 2) is True  # a float: by the field, as before
