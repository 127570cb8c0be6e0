"""Section 3.5.3: the free symmetric top in Euler angles and the wobbling plate, reproduced with mechderive.

With L along ẽ3, the body components of L are L·(column 3 of R(φ, θ, ψ)); equating them
to (I1ω1, I1ω2, I3ω3), with ω in Euler angles from (3.58), gives the Euler-angle rates
(3.59)–(3.60); a disc, I3 = 2I1, gives the wobbling plate (3.61).

Run: python derivations/s3_5_3_free_symmetric_top.py [--latex]
"""

import sympy as sp

from mechderive.catalog.registry import print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.core.symbols import state_symbol
from mechderive.systems.free_top import model as ft

args = derivation_args(__doc__.splitlines()[0])
m = ft.model()
phi_dot, theta_dot, psi_dot = (state_symbol(n) for n in ("phi_dot", "theta_dot", "psi_dot"))
theta = state_symbol("theta")
w3 = ft.omega_symbols()[2]

print("L = L ẽ3 in body components, L_a = L R_a3:")
show("L_body", m.fixed_L_body_components, latex=args.latex)
print("\nEuler-angle rates solved from I ω = L_body, ω from (3.58):")
for r, v in m.symmetric_top_euler_rates.items():
    show(str(r), v, latex=args.latex)
print("\n... and with L cos θ = I3 ω3 ((3.59): ψ̇ = Ω; (3.60)):")
rates = m.symmetric_top_euler_rates_spin
for r, v in rates.items():
    show(str(r), v, latex=args.latex)
ratio = sp.simplify(rates[phi_dot] / rates[psi_dot])
print("\nWobble/spin ratio for any symmetric top:")
show("phi_dot/psi_dot", ratio, latex=args.latex)
disc = sp.simplify(ratio.subs(ft.I3, 2 * ft.I1))
print("\n(3.61) disc, I3 = 2 I1:")
show("psi_dot", rates[psi_dot].subs(ft.I3, 2 * ft.I1), latex=args.latex)
show("phi_dot/psi_dot", disc, latex=args.latex)
show("relative excess over -2", sp.series(disc / -2 - 1, theta, 0, 6), latex=args.latex)
space = sp.simplify((rates[phi_dot] + rates[psi_dot]).subs(ft.I3, 2 * ft.I1))
show("phi_dot + psi_dot (a body point near e3, seen from space)", space, latex=args.latex)
for deg in (1, 10, 30):
    print(f"  θ = {deg:2d}°: φ̇/ψ̇ = {float(disc.subs(theta, sp.pi * deg / 180)):+.5f}")

print("\nChecks against the chapter's printed forms:")
results = run_claims("3.5.3")
if not print_claims(results):
    raise SystemExit(1)
