"""Section 3.4: free tops, reproduced with mechderive.

From the free Euler equations (3.33): the symmetric top (3.34)–(3.37), the Earth's
wobble (3.38)–(3.39), the linear stability of steady spins (3.40)–(3.45) — both the
chapter's elimination of η3 and the eigenvalues of the Jacobian for every axis — and
Poinsot's constants of motion (3.46)–(3.49).  Ends with a numerical demonstration of
the intermediate-axis instability against the derived growth rate.

Run: python derivations/s3_4_free_tops.py [--latex]
"""

import numpy as np
import sympy as sp

from mechderive.catalog.registry import print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.systems.free_top import model as ft
from mechderive.systems.free_top import stability

args = derivation_args(__doc__.splitlines()[0])
m = ft.model()

print("(3.34): the symmetric top I2 = I1, ω̇ =")
show("omega_dot", m.symmetric_rhs, latex=args.latex)
print("\n(3.36): ω̇1 = Ω ω2, ω̇2 = -Ω ω1 with")
show("Omega", m.symmetric_precession_rate, latex=args.latex)
print("\n(3.37): the general solution exp(tM)·(ω1, ω2)(0):")
show("(omega1, omega2)", m.symmetric_general_solution, latex=args.latex)

earth = m.symmetric_precession_rate.subs({ft.I3: ft.I1 * sp.Rational(301, 300)})
print("\n(3.38)-(3.39): Earth, (I1 - I3)/I1 = -1/300:")
show("Omega_earth", earth, latex=args.latex)
print(f"  period 2π/|Ω| at ω3 = 2π/day (one turn a day): {float(2 * sp.pi / abs(earth.subs(ft.omega_symbols()[2], 2 * sp.pi))):.1f} days;"
      f" at ω3 = 1 rad/day: {float(2 * sp.pi / abs(earth.subs(ft.omega_symbols()[2], 1))):.1f} days")

print("\n(3.42)-(3.43): I_a η̇_a at first order about ω = (Ω, 0, 0):")
show("I eta_dot", m.linearised_axis1, latex=args.latex)
print("\n(3.44): I2 η̈2 = A η2 with")
show("A", m.stability_coefficient, latex=args.latex)
print("\nAny axis: eigenvalues of J = ∂ω̇/∂ω at ω = Ω e_a are 0, ±√s_a:")
for a in range(3):
    show(f"s_{a + 1}", m.axis_growth_squared[a], latex=args.latex)
print("At a general steady ω (ω ∥ Iω), s =")
show("s", m.growth_squared, latex=args.latex)
print("\n(3.45) and its generalisation, classification by the sign of s_a:")
for moments in [(2.0, 3.0, 4.0), (3.0, 2.0, 4.0), (2.0, 4.0, 3.0), (2.0, 2.0, 3.0), (3.0, 3.0, 3.0)]:
    print(f"  I = {moments}: {stability.principal_axis_stability(*moments)}")

print("\n(3.46)-(3.47): rates of T and L² along Euler's equations:")
show("dT/dt", m.energy_rate, latex=args.latex)
show("dL^2/dt", m.angular_momentum_squared_rate, latex=args.latex)
print("(3.49): ∇_ω T =")
show("grad T", m.energy_gradient, latex=args.latex)
print("Invariable plane: ω·L =")
show("omega.L", m.omega_dot_angular_momentum, latex=args.latex)

print("\nIntermediate-axis instability, integrated (DOP853, rtol 1e-12) vs √(A/I2):")
from scipy.integrate import solve_ivp  # noqa: E402

I = (2.0, 1.0, 2.5)  # spin about e1 with I2 < I1 < I3: unstable
rate = stability.instability_growth_rate(*I, 1.0, axis=1)
f = m.compile("free_rhs_flat", list(m.free_rhs), list(ft.omega_symbols()) + [ft.I1, ft.I2, ft.I3])
sol = solve_ivp(lambda t, w: f(*w, *I), (0, 40), [1.0, 1e-10, 0.0], method="DOP853", rtol=1e-12, atol=1e-16,
                dense_output=True)
ts = np.linspace(0, 40, 4001)
eta2 = np.abs(sol.sol(ts)[1])
window = (eta2 > 1e-8) & (eta2 < 1e-4)
slope = np.polyfit(ts[window], np.log(eta2[window]), 1)[0]
print(f"  fitted {slope:.6f}, derived √(A/I2) = {rate:.6f}, relative difference {abs(slope / rate - 1):.1e}")

print("\nChecks against the chapter's printed forms:")
results = run_claims("3.4")
if not print_claims(results) or abs(slope / rate - 1) > 0.01:
    raise SystemExit(1)
