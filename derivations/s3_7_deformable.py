"""Section 3.7: deformable bodies, reproduced with mechderive.

From one generic point mass with r = R r̃ and Ṙ = RΩ (a generic rotation by the Cayley
map), R⁻¹L = L̃ − Ĩ v with Ω = hat(v); L = 0 then gives Ω = hat(Ĩ⁻¹L̃) (3.92).  The
small-loop expansion of the right-ordered Wilson loop (3.98) gives the field strength,
F_AB = ∂Ω_B/∂x^A − ∂Ω_A/∂x^B + [Ω_A, Ω_B] (the chapter's (3.103) has the derivative terms
swapped).  Then a falling cat turns over by π with L = 0.  Finally the printed forms are
checked.

Convention (section 3.7): r_i = R r̃_i, R acting on columns — section 3.1's R transposed.

Run: python derivations/s3_7_deformable.py [--latex]
"""

import numpy as np

from mechderive.catalog.registry import print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.systems.deformable import derivation
from mechderive.systems.deformable.cat import falling_cat

args = derivation_args(__doc__.splitlines()[0])
d = derivation.model()

print("(3.90): L = m r × ṙ of one mass, r = R r̃, R(t) any matrix:")
show("L_1", d.space_angular_momentum[0], latex=args.latex)
print("\nR⁻¹L for a rotation R with Ṙ = RΩ (independent of R):")
show("R^-1 L", d.body_frame_momentum, latex=args.latex)
print("\n(3.94) the apparent angular momentum, R⁻¹L at Ω = 0, and (3.93) Ĩ = −∂(R⁻¹L)/∂v:")
show("Ltilde", d.apparent_angular_momentum, latex=args.latex)
show("Itilde", d.inertia_per_mass, latex=args.latex)
print("\n(3.92): Ω solving L̃ − Ĩ v = 0 for a general symmetric Ĩ (Ω_12 shown):")
show("Omega_12", d.angular_velocity_solution[0, 1], latex=args.latex)
print("\n(3.97): on L = 0, L̃ in terms of Ĩ and Ω:")
show("Ltilde", d.apparent_momentum_on_shell, latex=args.latex)
print("\n(3.102): the O(α²) coefficient of ∮α_1 α̇_2 dt in P̃ exp ∮Ω (later times on the right):")
show("F_12", d.field_strength_form[(1, 2)], latex=args.latex)

cat = falling_cat(samples=21)
print(f"\nThe falling cat: peak bend {np.degrees(cat.peak_bend):.4f}°, net turn {cat.flip_angle[-1]:.12f} rad "
      f"(π − turn = {np.pi - cat.flip_angle[-1]:.1e}), max |L| = {np.abs(cat.angular_momentum).max():.1e} kg m²/s")

print("\nChecks against the chapter's printed forms:")
results = run_claims("3.7")
if not print_claims(results):
    raise SystemExit(1)
