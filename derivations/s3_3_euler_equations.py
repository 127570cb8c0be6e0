"""Section 3.3.1: Euler's equations, reproduced with mechderive.

dL/dt is expanded in the body frame, L = L_a e_a with L_a = I_a ω_a (principal axes,
3.28) and ė_a = ω_ac e_c (3.5)–(3.6), giving Euler's equations (3.33) with a torque τ;
then the space components L̃ = Rᵀ L are differentiated for a generic R(t) with Ṙ = ωR
to show that Euler's equations mean dL̃/dt = Rᵀτ — zero for a free body (3.31).

Run: python derivations/s3_3_euler_equations.py [--latex]
"""

from mechderive.catalog.registry import print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.systems.free_top import model as ft

args = derivation_args(__doc__.splitlines()[0])
m = ft.model()

print("(3.28): L_a = I_ab ω_b in principal axes:")
show("L_body", m.angular_momentum_body, latex=args.latex)
print("\n(3.32): body components of dL/dt = L̇_a e_a + L_a ω_ac e_c:")
show("dL/dt", m.rate_of_angular_momentum, latex=args.latex)
print("\n(3.33) with torque: dL/dt - τ = 0, solved for ω̇:")
show("euler_equations", m.euler_equations, latex=args.latex)
show("omega_dot", m.euler_rhs, latex=args.latex)
print("\n(3.31): d(Rᵀ L)/dt on Euler's equations, R generic with Ṙ = ωR (the torque in space axes):")
show("dL_space/dt", m.space_rate_of_angular_momentum, latex=args.latex)

print("\nChecks against the chapter's printed forms:")
results = run_claims("3.3.1")
if not print_claims(results):
    raise SystemExit(1)
