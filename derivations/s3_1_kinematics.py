"""Section 3.1: kinematics of a rotating body, reproduced with mechderive.

From R(φ, θ, ψ) alone the toolkit derives the angular-velocity matrix ω = ṘRᵀ
(3.5), shows it antisymmetric, extracts the vector ω_a = ½ε_abc ω_bc (3.6),
the convective angular velocity Ω = R⁻¹Ṙ (3.10), and checks every statement of
sections 3.1–3.1.2 in the catalog (including the path-ordered exponential).

Run: python derivations/s3_1_kinematics.py [--latex]
"""

from mechderive.catalog.registry import print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.core.simplify import simplify_trig
from mechderive.kinematics import euler

args = derivation_args(__doc__.splitlines()[0])
m = euler.model()

print("(3.5): the angular-velocity matrix ω = Ṙ Rᵀ of R(φ, θ, ψ):")
show("omega", m.angular_velocity_matrix, latex=args.latex)
print("\nIt is antisymmetric, ω + ωᵀ =")
show("omega + omega^T", (m.angular_velocity_matrix + m.angular_velocity_matrix.T).applyfunc(simplify_trig),
     latex=args.latex)
print("\n(3.6): its vector ω_a = ½ ε_abc ω_bc (body components):")
show("omega_a", m.angular_velocity_body, latex=args.latex)
print("\n(3.10): the convective angular velocity Ω = R⁻¹Ṙ; its vector is ω in space components:")
show("Omega", m.convective_angular_velocity_matrix, latex=args.latex)

print("\nChecks of sections 3.1–3.1.2 against the derivations:")
results = run_claims("3.1")
if not print_claims(results):
    raise SystemExit(1)
