"""Section 3.5: Euler angles, reproduced with mechderive.

R1 and R3 are derived as exponentials of so(3) generators, R = R3(ψ)R1(θ)R3(φ)
(3.54) is their product, and the angular velocity in Euler angles (3.58) comes
out of ω = ṘRᵀ (3.5)–(3.6), then is checked against the printed formulas.

Run: python derivations/s3_5_euler_angles.py [--latex]
"""

from mechderive.catalog.registry import print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.kinematics import euler

args = derivation_args(__doc__.splitlines()[0])
m = euler.model()

print("Generators J_a with (J_a)_bc = ε_bca (unit angular velocity about axis a):")
for a in (1, 3):
    show(f"J{a}", euler.generator(a), latex=args.latex)
print("\n(3.51)-(3.52): R3(α) = exp(α J3), R1(α) = exp(α J1):")
show("R3(alpha)", m.R3, latex=args.latex)
show("R1(alpha)", m.R1, latex=args.latex)
print("\n(3.54): R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ):")
show("R", m.state_rotation, latex=args.latex)
print("\n(3.58): body components of ω, from ω_a = ½ ε_abc (Ṙ Rᵀ)_bc:")
show("omega_body", m.state_angular_velocity_body, latex=args.latex)
print("\nω in space axes, ω̃ = Rᵀ ω:")
show("omega_space", m.state_angular_velocity_space, latex=args.latex)

print("\nChecks against the chapter's printed forms:")
results = run_claims("3.5")
if not print_claims(results):
    raise SystemExit(1)
