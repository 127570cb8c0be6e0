"""Catalog entries for section 3.2: the inertia tensor, (3.17)–(3.28).

The printed forms below are the chapter's formulas transcribed *only* to be
checked; the toolkit's derivations come from :mod:`mechderive.inertia`:

- point masses (two general masses m1, m2 at body components (x_i, y_i, z_i),
  angular velocity ω = (ω1, ω2, ω3) in body components): T derived from
  ṙ = ωᵀ r, I as the Hessian of T, L = Σ m r × ṙ (:class:`PointMassModel`);
  (3.17) and (3.28) are also checked from first principles with Euler angles,
  R(t) = R3(ψ) R1(θ) R3(φ): r̃ = Rᵀ r, ṙ̃ = Ṙᵀ r, L̃ = Σ m r̃ × ṙ̃, L = R L̃;
- bodies by integrating a uniform density (:mod:`mechderive.inertia.bodies`);
  the chapter's disc radius r is called R here (r is the radial coordinate);
- the parallel axis theorem for three general masses about their centre of mass
  (:class:`ParallelAxisModel`), and the chapter's examples also by integrating
  directly about the displaced point.

A general symmetric tensor I_ab (symbols I11, I12, ...) stands for "I" where a
printed formula uses the tensor by name; the check substitutes the derived one.
"""

from __future__ import annotations

import functools

import sympy as sp

from ..core.symbols import t
from ..inertia import bodies
from ..inertia.density import DensityModel
from ..inertia.parallel_axis_theorem import parallel_axis_model
from ..inertia.principal import principal_axes_symbolic
from ..inertia.regions import Region, r, varphi, x, y, z
from ..inertia.tensor import general_inertia_symbols, point_mass_model, point_mass_tensor
from .checks import all_pass, same
from .registry import Claim, register

_half = sp.Rational(1, 2)
_c = sp.Matrix(sp.symbols("c1:4", real=True))  # an arbitrary vector (3.22)
_cx = sp.Symbol("c", real=True)  # the disc's displacement c = (c, 0, 0)
M, l, R, rho = bodies.M, bodies._l, bodies._R, bodies.rho


def _pm():
    return point_mass_model(2)


def _pairs():
    pm = _pm()
    return list(zip(pm.masses, pm.positions))


def _with_derived_tensor(formula, tensor):
    """Substitute the derived tensor for the general symbols I_ab of a printed formula."""
    I = general_inertia_symbols()
    return formula.subs({I[a, b]: tensor[a, b] for a in range(3) for b in range(a, 3)}, simultaneous=True)


@functools.cache
def _euler_route():
    """First principles with Euler angles for the first mass alone: ω(t), T and body-frame L.

    Every printed sum is linear in the masses with each term depending only on its own
    position, so the exact polynomial comparison of the whole sum plus this comparison of
    the first mass's term (m2 = 0) covers every term; one mass halves the cost.
    """
    from ..kinematics import euler

    km = euler.model()
    Rt, w = km.rotation, km.angular_velocity_body
    m, p = _pairs()[0]
    omega_subs = dict(zip(_pm().omega, w))
    v_space = Rt.diff(t).T * p  # ṙ̃ = Ṙᵀ r
    T = m * v_space.dot(v_space) / 2
    L_body = Rt * (m * (Rt.T * p).cross(v_space))  # L = R L̃, L̃ = m r̃ × ṙ̃
    return omega_subs, T, L_body


def _first_mass_only(expr):
    """The first mass's term of a printed sum (the others set to zero mass)."""
    return expr.subs({m: 0 for m, _ in _pairs()[1:]})


def _checks(*thunks):
    """Run checks in order, stopping at the first failure (a wrong formula fails fast)."""
    outcomes = []
    for thunk in thunks:
        outcome = thunk()
        outcomes.append(outcome)
        if not outcome.passed:
            break
    return all_pass(outcomes)


# ---------------------------------------------------------------- 3.2: T and I

def _printed_3_17():
    w = _pm().omega
    cross = [(m, w.cross(p)) for m, p in _pairs()]
    line2 = _half * sum(m * v.dot(v) for m, v in cross)
    line3 = _half * sum(m * (w.dot(w) * p.dot(p) - p.dot(w) ** 2) for m, p in _pairs())
    return (line2, line3)


def _check_3_17(f):
    T = _pm().kinetic_energy
    omega_subs, T_first, _ = _euler_route()
    return _checks(lambda: same(f[0], T, "line 2 vs ½Σm ṙ²"), lambda: same(f[1], T, "line 3 vs ½Σm ṙ²"),
                   lambda: same(_first_mass_only(f[0]).subs(omega_subs), T_first,
                                "line 2 with Euler-angle ω vs ½m|Ṙᵀr|² (first mass)"))


register(Claim(
    "3.17", "3.2",
    "T = ½Σm ṙ² = ½Σm (ω×r)·(ω×r) = ½Σm ((ω·ω)(r·r) - (r·ω)²) for a rotating body",
    "symbolic", printed=_printed_3_17, check=_check_3_17, parts=("line 2", "line 3"),
))


def _printed_3_18():
    w, I = _pm().omega, general_inertia_symbols()
    return _half * sum(w[a] * I[a, b] * w[b] for a in range(3) for b in range(3))


register(Claim(
    "3.18", "3.2",
    "T = ½ ω_a I_ab ω_b, with I the derived inertia tensor",
    "symbolic", printed=_printed_3_18,
    check=lambda f: same(_with_derived_tensor(f, _pm().inertia_tensor), _pm().kinetic_energy, "½ωIω vs T"),
))


def _printed_3_19():
    return sp.Matrix(3, 3, lambda a, b: sum(m * (p.dot(p) * sp.KroneckerDelta(a, b) - p[a] * p[b])
                                            for m, p in _pairs()))


register(Claim(
    "3.19", "3.2",
    "I_ab = Σ m_i ((r_i·r_i) δ_ab - (r_i)_a (r_i)_b), the Hessian ∂²T/∂ω_a∂ω_b",
    "symbolic", printed=_printed_3_19,
    check=lambda f: same(f, _pm().inertia_tensor, "I_ab"),
))


def _printed_3_20():
    return sp.Matrix([[y**2 + z**2, -x * y, -x * z], [-x * y, x**2 + z**2, -y * z], [-x * z, -y * z, x**2 + y**2]])


def _cone_integral(f):
    """∫ ρ f dV over the cone, in its cylindrical coordinates with the derived Jacobian."""
    cone = bodies.body_model("solid_cone")
    pos = dict(zip((x, y, z), cone.region.position))
    integrand = f.subs(pos, simultaneous=True) * rho * cone.measure
    return integrand.applyfunc(lambda e: sp.integrate(sp.expand(e), *cone.region.limits))


def _check_3_20(f):
    # the integrand is (3.19) for a unit mass at (x, y, z), and integrating ρ times it with
    # the Jacobian over a cone reproduces the derived cone about its apex
    return _checks(lambda: same(f, point_mass_tensor(1, (x, y, z)), "integrand vs (3.19) for a unit mass"),
                   lambda: same(_cone_integral(f), bodies.body_model("solid_cone").inertia_origin,
                                "∫ρ(...)d³r over a cone about its apex"))


register(Claim(
    "3.20", "3.2",
    "continuous bodies: I = ∫ d³r ρ(r) [[y²+z², -xy, -xz], [-xy, x²+z², -yz], [-xz, -yz, x²+y²]]",
    "symbolic", printed=_printed_3_20, check=_check_3_20,
))


_I1, _I2, _I3 = sp.symbols("I1:4", positive=True)


def _check_3_21(f):
    # a tensor with a product of inertia: principal axes by the toolkit, O I Oᵀ compared with the printed diag
    A, B, C = sp.symbols("A B C", positive=True)
    I = sp.Matrix([[A, B, 0], [B, A, 0], [0, 0, C]])
    moments, O = principal_axes_symbolic(I)
    diag = f.subs(dict(zip((_I1, _I2, _I3), moments)), simultaneous=True)
    return _checks(lambda: same(diag, O * I * O.T, "O I Oᵀ"), lambda: same(O * O.T, sp.eye(3), "O Oᵀ"),
                   lambda: same(sp.Matrix([O.det()]), sp.Matrix([1]), "det O"))


register(Claim(
    "3.21", "3.2",
    "a symmetric I is diagonalised by an orthogonal O: O I Oᵀ = diag(I1, I2, I3) (rows of O = principal axes)",
    "symbolic", printed=lambda: sp.diag(_I1, _I2, _I3), check=_check_3_21,
))


def _printed_3_22():
    return sum(m * (p.dot(p) * _c.dot(_c) - p.dot(_c) ** 2) for m, p in _pairs())


def _check_3_22(f):
    I = _pm().inertia_tensor
    s = sp.symbols("s1:3", real=True)
    on_line = {q: v for (_, p), si in zip(_pairs(), s) for q, v in zip(p, si * _c)}
    return _checks(
        lambda: same(f, (_c.T * I * _c)[0], "I_ab c_a c_b"),
        # Lagrange's identity makes it a sum of squares times positive masses: hence >= 0
        lambda: same(f, sum(m * p.cross(_c).dot(p.cross(_c)) for m, p in _pairs()), "Σ m |r×c|²"),
        # and it vanishes when every r_i lies on the line through c
        lambda: same(f.subs(on_line, simultaneous=True), 0, "masses on the line of c"))


register(Claim(
    "3.22", "3.2",
    "I_ab c_a c_b = Σ m (r² c² - (r·c)²) >= 0, zero when the r_i lie on the line of c",
    "symbolic", printed=_printed_3_22, check=_check_3_22,
))


def _printed_3_23():
    xs = sp.Symbol("x", real=True)
    return (sp.Integral((M / l) * xs**2, (xs, -l / 2, l / 2)), M * l**2 / 12)


def _check_3_23(f):
    derived = bodies.body_inertia_symbolic("rod").inertia_cm  # rod along axis 3
    return _checks(lambda: same(f[0].doit(), derived[0, 0], "∫ρx²dx"), lambda: same(f[1], derived[0, 0], "I1"),
                   lambda: same(sp.diag(f[1], f[1], 0), derived, "diag(I1, I1, 0)"))


register(Claim(
    "3.23", "3.2",
    "uniform rod of length l about its centre: I = diag(I1, I1, 0), I1 = ∫ρx²dx = M l²/12",
    "symbolic", printed=_printed_3_23, check=_check_3_23, parts=("∫ρx²dx", "I1 = Ml²/12"),
))


def _printed_3_24():
    rp = sp.Symbol("r'", positive=True)
    density = M / (sp.pi * R**2)
    return (M * R**2 / 2, M * R**2 / 4, M * R**2 / 4, 2 * sp.pi * density * sp.Integral(rp**3, (rp, 0, R)))


def _check_3_24(f):
    I3, I1, I2, integral = f
    derived = bodies.body_inertia_symbolic("disc").inertia_cm  # disc in the 1-2 plane
    return _checks(lambda: same(sp.diag(I1, I2, I3), derived, "diag(I1, I2, I3)"),
                   lambda: same(integral.doit(), derived[2, 2], "2πρ∫r'³dr'"),
                   lambda: same(I1 + I2, I3, "I1 + I2 = I3"))


register(Claim(
    "3.24", "3.2",
    "uniform disc of radius R (the text's r): I3 = 2πρ∫r'³dr' = ½MR², I1 = I2 = ¼MR²",
    "symbolic", printed=_printed_3_24, check=_check_3_24, parts=("I3", "I1", "I2", "2πρ∫r'³dr'"),
))


# ---------------------------------------------------------------- 3.2.1: parallel axis theorem

def _pa():
    return parallel_axis_model(3)


def _printed_3_25():
    pa, I, Ms = _pa(), general_inertia_symbols(), sp.Symbol("M", positive=True)
    c = pa.c
    return I + Ms * (c.dot(c) * sp.eye(3) - c * c.T)


def _check_3_25(f):
    pa = _pa()
    con = pa.centre_of_mass_constraint
    filled = _with_derived_tensor(f, pa.inertia_about_origin.subs(con)).subs(sp.Symbol("M", positive=True), pa.M)
    return same(filled, pa.inertia_about_c.subs(con), "I_c for three masses about their centre of mass")


register(Claim(
    "3.25", "3.2.1",
    "parallel axis: (I_c)_ab = (I_cm)_ab + M(c² δ_ab - c_a c_b) about a point displaced by c from the centre of mass",
    "symbolic", printed=_printed_3_25, check=_check_3_25,
))


def _printed_3_26():
    pa = _pa()
    c = pa.c
    d = sp.eye(3)
    expansion = sp.Matrix(3, 3, lambda a, b: sum(
        m * (p.dot(p) * d[a, b] - p[a] * p[b] + (-2 * p.dot(c) * d[a, b] + p[a] * c[b] + p[b] * c[a])
             + (c.dot(c) * d[a, b] - c[a] * c[b])) for m, p in zip(pa.masses, pa.positions)))
    bracket = sp.Matrix(3, 3, lambda a, b: sum(m * (-2 * p.dot(c) * d[a, b] + p[a] * c[b] + p[b] * c[a])
                                               for m, p in zip(pa.masses, pa.positions)))
    return (expansion, bracket)


def _check_3_26(f):
    pa = _pa()
    expansion, bracket = f
    return _checks(lambda: same(expansion, pa.inertia_about_c, "expansion of Σm (r-c) tensor"),
                   lambda: same(bracket, pa.linear_terms, "bracket"),
                   lambda: same(bracket.subs(pa.centre_of_mass_constraint), sp.zeros(3, 3), "bracket at Σ m r = 0"))


register(Claim(
    "3.26", "3.2.1",
    "expansion of I about r_i - c; the bracket linear in r_i vanishes when Σ m_i r_i = 0",
    "symbolic", printed=_printed_3_26, check=_check_3_26, parts=("expansion", "bracket"),
))


@functools.cache
def _direct(name: str, position: tuple, limits: tuple) -> sp.Matrix:
    """I about the origin of a uniform body given by (position, limits), ρ eliminated for M."""
    model = DensityModel(rho, Region(name, position, limits))
    density = sp.solve(sp.Eq(model.mass, M), rho)[0]
    return model.inertia_origin.subs(rho, density).applyfunc(sp.factor)


def _check_rod_end(f):
    about_end = bodies.body_inertia_symbolic("rod").inertia_about((0, 0, l / 2))
    s = sp.Symbol("s", real=True)
    direct = _direct("rod from its end", (0, 0, s), ((s, 0, l),))  # integrated from the end, no theorem used
    return _checks(lambda: same(f[0], about_end[0, 0], "parallel axis"), lambda: same(f[1], about_end[0, 0], "M l²/3"),
                   lambda: same(f[1], direct[0, 0], "direct ∫ from the end"))


register(Claim(
    "3.2.1 rod about its end", "3.2.1",
    "the rod about one end: I1 = M l²/12 + M (l/2)² = M l²/3",
    "symbolic", printed=lambda: (M * l**2 / 12 + M * (l / 2) ** 2, M * l**2 / 3), check=_check_rod_end,
    parts=("Ml²/12 + M(l/2)²", "Ml²/3"),
))


def _printed_disc_displaced():
    c2 = _cx**2
    first = M * sp.diag(R**2 / 4, R**2 / 4, R**2 / 2) + M * (sp.diag(c2, c2, c2) - sp.diag(c2, 0, 0))
    return (first, M * sp.diag(R**2 / 4, R**2 / 4 + c2, R**2 / 2 + c2))


def _check_disc_displaced(f):
    theorem = bodies.body_inertia_symbolic("disc").inertia_about((_cx, 0, 0))
    # positions measured from the displaced point: r - c
    direct = _direct("disc about (c, 0, 0)", (r * sp.cos(varphi) - _cx, r * sp.sin(varphi), 0),
                     ((r, 0, R), (varphi, 0, 2 * sp.pi)))
    return _checks(lambda: same(f[0], theorem, "intermediate form"), lambda: same(f[1], theorem, "result"),
                   lambda: same(f[1], direct, "direct ∫ about (c, 0, 0)"))


register(Claim(
    "3.2.1 disc displaced", "3.2.1",
    "the disc about a point displaced by c = (c, 0, 0): I = M diag(R²/4, R²/4 + c², R²/2 + c²)",
    "symbolic", printed=_printed_disc_displaced, check=_check_disc_displaced,
    parts=("intermediate form", "result"),
))


# ---------------------------------------------------------------- 3.2.2: angular momentum

def _printed_3_27():
    w, I = _pm().omega, general_inertia_symbols()
    line2 = sum((m * p.cross(w.cross(p)) for m, p in _pairs()), sp.zeros(3, 1))
    line3 = sum((m * (p.dot(p) * w - w.dot(p) * p) for m, p in _pairs()), sp.zeros(3, 1))
    return (line2, line3, I * w)


def _check_3_27(f):
    L = _pm().angular_momentum  # Σ m r × ṙ with the derived ṙ
    return _checks(lambda: same(f[0], L, "Σm r×(ω×r)"), lambda: same(f[1], L, "Σm(r²ω - (ω·r)r)"),
                   lambda: same(_with_derived_tensor(f[2], _pm().inertia_tensor), L, "I ω"))


register(Claim(
    "3.27", "3.2.2",
    "L = Σm r×ṙ = Σm r×(ω×r) = Σm(r²ω - (ω·r)r) = I ω",
    "symbolic", printed=_printed_3_27, check=_check_3_27, parts=("Σm r×(ω×r)", "Σm(r²ω − (ω·r)r)", "Iω"),
))


def _check_3_28(f):
    pm = _pm()
    filled = _with_derived_tensor(f, pm.inertia_tensor)
    omega_subs, _, L_body = _euler_route()
    return _checks(lambda: same(filled, pm.angular_momentum, "I_ab ω_b vs Σ m r × ṙ"),
                   lambda: same(_first_mass_only(filled).subs(omega_subs), L_body,
                                "with Euler-angle ω vs R m r̃×ṙ̃ (first mass)"))


register(Claim(
    "3.28", "3.2.2",
    "body components: L_a = I_ab ω_b (checked against R L̃ with L̃ = Σ m r̃ × ṙ̃ from R(φ, θ, ψ))",
    "symbolic", printed=lambda: general_inertia_symbols() * _pm().omega, check=_check_3_28,
))

__all__: list[str] = []  # registers claims on import; nothing to export
