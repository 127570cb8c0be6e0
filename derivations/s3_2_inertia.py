"""Section 3.2 (and 3.3's (3.29)–(3.30)): the inertia tensor, reproduced with mechderive.

From the rigid velocity ṙ = ωᵀ r (body components, from Ṙ = ωR) the toolkit
derives T = ½Σmṙ², the inertia tensor as its Hessian in ω (3.18)–(3.19), the
angular momentum L = Iω (3.27)–(3.28), the positivity identity (3.22), the rod
and disc by integrating a uniform density with the Jacobian of the chosen
coordinates (3.20), (3.23), (3.24), the parallel axis theorem for general point
masses (3.25)–(3.26) with the chapter's examples, principal axes (3.21), and the
separation of a free body's kinetic energy (3.30); then checks the catalog.

Run: python derivations/s3_2_inertia.py [--latex]
"""

import sympy as sp

from mechderive.catalog.registry import all_claims, print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.inertia import bodies, principal_axes_symbolic
from mechderive.inertia.free_body import free_body_model
from mechderive.inertia.parallel_axis_theorem import parallel_axis_model
from mechderive.inertia.tensor import point_mass_model

args = derivation_args(__doc__.splitlines()[0])
tex = args.latex

one = point_mass_model(1)
print("A body point with body components r = (x, y, z) moves with ṙ = ωᵀ r (ω_ab = ε_abc ω_c):")
show("rdot", one.velocities[0], latex=tex)
print("\n(3.17): its kinetic energy T = ½ m ṙ²:")
show("T", sp.factor(one.kinetic_energy), latex=tex)
print("\n(3.18)-(3.19): T is quadratic in ω; its Hessian ∂²T/∂ω_a∂ω_b is the inertia tensor:")
show("I", one.inertia_tensor, latex=tex)
print("\n(3.27)-(3.28): L = m r × ṙ equals I ω (and ∂T/∂ω):")
show("L", one.angular_momentum.applyfunc(sp.factor), latex=tex)

print("\n(3.22): with c arbitrary, c_a I_ab c_b = m |r × c|² >= 0 (Lagrange's identity):")
c = sp.Matrix(sp.symbols("c1:4", real=True))
r = one.positions[0]
show("c.I.c - m|r x c|^2", sp.expand((c.T * one.inertia_tensor * c)[0] - one.masses[0] * r.cross(c).dot(r.cross(c))),
     latex=tex)

print("\n(3.20), (3.23): the uniform rod along axis 3, ρ = M/l, about its centre:")
rod = bodies.body_model("rod")
show("rho", rod.uniform_density, latex=tex)
show("I_rod", rod.inertia_cm_in_mass, latex=tex)
print("\n(3.24): the uniform disc in the 1-2 plane; polar coordinates, Jacobian:")
disc = bodies.body_model("disc")
show("dA/(dr dphi)", disc.measure, latex=tex)
show("I_disc", disc.inertia_cm_in_mass, latex=tex)

print("\n(3.25)-(3.26): three masses, positions r_i - c; the terms linear in r_i are")
pa = parallel_axis_model(3)
show("bracket_11", pa.linear_terms[0, 0], latex=tex)
print("and with Σ m r = 0 imposed they vanish:")
show("bracket", pa.linear_terms_at_centre_of_mass, latex=tex)
M, l, R = bodies.M, bodies._l, bodies._R
cx = sp.Symbol("c", real=True)
print("\nThe rod about its end, and the disc about a point displaced by (c, 0, 0):")
show("I_rod_end", bodies.body_inertia_symbolic("rod").inertia_about((0, 0, l / 2)), latex=tex)
show("I_disc_c", bodies.body_inertia_symbolic("disc").inertia_about((cx, 0, 0)), latex=tex)
print("\nThe solid cone (apex at the origin, axis 3): centre of mass and I about it and about the apex:")
cone = bodies.body_inertia_symbolic("solid_cone")
show("R_cm", cone.centre_of_mass, latex=tex)
show("I_cone_cm", cone.inertia_cm, latex=tex)
show("I_cone_apex", cone.inertia_about((0, 0, 0)), latex=tex)

print("\n(3.21): principal axes of a tensor with a product of inertia (rows of O, O I Oᵀ = diag):")
A, B, C = sp.symbols("A B C", positive=True)
moments, O = principal_axes_symbolic(sp.Matrix([[A, B, 0], [B, A, 0], [0, 0, C]]))
show("moments", sp.Matrix(moments).T, latex=tex)
show("O", O, latex=tex)

print("\n(3.30): a free body, r_i = R + Δr_i; T split by setting ω or V = Ṙ to zero:")
fb = free_body_model(3)
show("T(omega=0)", fb.translational_energy, latex=tex)
show("cross term", sp.factor(fb.cross_term), latex=tex)
show("cross term at the centre of mass", fb.cross_term_at_cm, latex=tex)

print("\nChecks of sections 3.2-3.3 against the derivations:")
results = run_claims("3.2") + run_claims(claims=[c for c in all_claims("3.3") if c.section == "3.3"])
if not print_claims(results, width=120):
    raise SystemExit(1)
