"""Section 3.6: the heavy symmetric top, reproduced with mechderive.

The Lagrangian (3.62) is derived as T − V with T = ½ωᵀ diag(I1, I1, I3) ω, ω from ṘRᵀ
(3.58), and V = M g l R33; the generic Lagrangian layer then finds the ignorable
coordinates, their momenta (3.63)–(3.64), the energy (3.65) and the Routhian, from which
(3.67)–(3.70) follow; f(u) (3.73) comes from the reduced energy, and the released,
uniformly precessing and sleeping tops (3.77)–(3.83) by algebra on f.  Finally the chapter's
printed forms are checked (``mechderive verify --section 3.6``).

Run: python derivations/s3_6_heavy_top.py [--latex]
"""

import time

from mechderive.catalog.registry import print_claims, run_claims
from mechderive.core.display import derivation_args, show
from mechderive.systems.heavy_top.model import model

args = derivation_args(__doc__.splitlines()[0])
start = time.perf_counter()
m = model()
tex = args.latex

print("(3.62): T = ½ ωᵀ diag(I1, I1, I3) ω with ω of (3.58), V = M g l R33:")
show("T", m.kinetic_energy, latex=tex)
show("V", m.potential_energy, latex=tex)
show("L", m.state_lagrangian, latex=tex)
print("\nIgnorable coordinates (∂L/∂q ≡ 0):", ", ".join(str(q) for q in m.cyclic_coordinates))
print("\n(3.63)-(3.65): conserved momenta and energy:")
show("p_psi", m.spin_momentum, latex=tex)
show("p_phi", m.azimuthal_momentum, latex=tex)
show("E", m.energy, latex=tex)
print("\nRouth reduction: the cyclic velocities from p_φ, p_ψ, and R = L − p_φ φ̇ − p_ψ ψ̇:")
for v, e in m.cyclic_velocities.items():
    show(str(v), e, latex=tex)
show("R", m.routhian, latex=tex)
print("\n(3.66)-(3.68): with p_φ = I1 b, p_ψ = I1 a:")
show("phi_dot", m.precession_rate_theta, latex=tex)
show("psi_dot", m.spin_rate_theta, latex=tex)
print("\n(3.69)-(3.70): E' = E − ½ I3 ω3², and the effective potential:")
show("E'", m.reduced_energy, latex=tex)
show("V_eff", m.effective_potential_theta, latex=tex)
print("\n(3.73)-(3.76): u = cos θ, α = 2E'/I1, β = 2Mgl/I1:")
show("f(u)", m.f_u, latex=tex)
show("phi_dot(u)", m.precession_rate_u, latex=tex)
show("psi_dot(u)", m.spin_rate_u, latex=tex)
show("(f(1), f(-1))", m.f_at_poles, latex=tex)
show("(f(+oo), f(-oo))", m.f_limits, latex=tex)
print("\n(3.77)-(3.78): letting the top go (θ̇ = φ̇ = 0):")
show("u0", m.released_u, latex=tex)
show("f'(u0)", m.released_f_slope, latex=tex)
show("p_phi(t=0)", m.released_azimuthal_momentum, latex=tex)
print("\n(3.79)-(3.81): uniform precession, a double root u0 of f:")
show("(f(u0), f'(u0))", m.double_root_conditions, latex=tex)
show("beta/2", m.uniform_precession_half_beta, latex=tex)
show("(3.80)", m.uniform_precession_condition, latex=tex)
slow, fast = m.precession_rates
show("phi_dot slow", slow, latex=tex)
show("phi_dot fast", fast, latex=tex)
show("discriminant", m.precession_discriminant, latex=tex)
show("minimum omega3 (cos θ0 > 0)", m.minimum_spin, latex=tex)
print("\n(3.82)-(3.83): the sleeping top, θ = θ̇ = 0:")
show("(b, beta) upright", tuple(m.sleeping_constants.values()), latex=tex)
show("f(u)", m.sleeping_f, latex=tex)
show("u2", m.sleeping_second_root, latex=tex)
show("u2(omega3)", m.sleeping_second_root_spin, latex=tex)
show("threshold omega3", m.sleeping_threshold_spin, latex=tex)
print("\nThe equations of motion in Euler angles (generic layer, M q̈ = F solved):")
for name, acc in zip(m.acceleration_symbols, m.accelerations):
    show(str(name), acc, latex=tex)
print(f"\nDerived {len(m.derived)} quantities in {time.perf_counter() - start:.1f} s.")

print("\nChecks against the chapter's printed forms:")
results = run_claims("3.6")
if not print_claims(results):
    raise SystemExit(1)
