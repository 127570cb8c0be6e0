"""Generate 30-digit reference motions for the generic reduction of a Lagrangian (issue 16).

Method.  mpmath's Taylor-series ODE solver (``mpmath.odefun``) integrates equations of motion that are
WRITTEN BY HAND below (Euler–Lagrange worked out on paper, or Newton) — not derived by SymPy and not by
mechderive.  Working precision ``WORK_DPS`` = 36 digits (40 for the two near-separatrix pendulums,
50 for the conical pendulum), ``odefun`` tolerance 10^-dps (its local truncation error per Taylor step),
Taylor degree 30; the stored strings carry 30 significant digits.  ``--check`` regenerates everything
with 10 more digits in both the working precision and the tolerance: on 2026-11-28 every stored string
(periods, advances, all samples, tiny values near a crossing included) came back identical.  Where a
coordinate is unwrapped far (θ of the rotating pendulum ≈ 12720 at 2024.65 T), 30 significant digits are
an absolute 1e-26: that, not the integration, limits such samples.

Times are doubles that are exact dyadic numbers (multiples of 2^-20): the "t" string is the exact
decimal value of that double and the motion is integrated to exactly that time.  Initial values are
the doubles listed in CASES, converted with ``mpmath.mpf(float)``.

Long times use the period symmetry: the period T is a simple root (Newton on the dense solution, at
the working precision) of q_k(t) - q_k(0) (- 2π for the rotating pendulums), or of q̇_k(t) when the
motion starts at a turning point; the state returns and a cyclic coordinate advances by Δ per period,
so q(NT + τ) = q(τ) + NΔ.  Samples at 100.3 T, 137.8 T, 1000.1 T, 2024.65 T cost nothing beyond the first period.  The conical pendulum is
not exactly steady: its φ̇ is the double float(sqrt(9.81/cos(0.8))) computed in
doubles, not the exact steady rate, so θ oscillates by ~1e-16 rad about
the cone (θ̇ ~ 1e-17); its "period" is that of this small oscillation (the cubic's nearly double root),
and its samples run to t < 100 (3.3 T, 10.8 T, 37.1 T, 92.65 T).

Independent second methods (printed): the period and the advances from a quadrature of the reduced
one-degree-of-freedom problem (u = cos θ: u̇² = f(u) cubic; T = 4∫_0^{π/2} dχ / √(-A (u - u3)) with
u = u1 + (u2 - u1) sin²χ, where f = A (u - u1)(u - u2)(u - u3); mpmath.quad, tanh-sinh), the complete
elliptic integral K (mpmath.ellipk) for the pendulum, Kepler's laws for the orbits (and Kepler's equation
at the sample times of the ellipse and the hyperbola).  Each sample's energy (Jacobi integral) and
conserved momenta are compared with their initial values.

Hand-written equations (m, l, g, k, β, I1, I3, M, a as in the Lagrangians of CASES):

A  spherical pendulum, Newton in Cartesian coordinates (no coordinate singularity at the pole):
   bob r = (x, y, z), z up, pivot at the origin, |r| = l;  r̈ = -g ẑ + μ r with the rod's multiplier
   fixed by (r·r)¨ = 0:  μ = (g z - |ṙ|²)/l².  Read-off: x = l sinθ cosφ, y = l sinθ sinφ, z = -l cosθ;
   θ = atan2(√(x²+y²), -z), φ = atan2(y, x) unwrapped (φ is monotonic: p_φ = m l² sin²θ φ̇ ≠ 0), and
   for the planar case A4 (y ≡ 0, φ ≡ 0) θ = atan2(x, -z), signed, through the pole.
   θ̇ = (-z ρ̇ + ρ ż)/(ρ² + z²), ρ̇ = (x ẋ + y ẏ)/ρ;  φ̇ = (x ẏ - y ẋ)/ρ².
   Energy m l²/2 (θ̇² + sin²θ φ̇²) - m g l cosθ, momentum p_φ = m l² sin²θ φ̇.
B  heavy symmetric top, Euler–Lagrange in Euler angles, ω3 = ψ̇ + cosθ φ̇:
   ψ:  d/dt (I3 ω3) = 0;   φ:  d/dt (I1 sin²θ φ̇ + I3 ω3 cosθ) = 0  ⇒  φ̈ = θ̇ (I3 ω3 - 2 I1 cosθ φ̇)/(I1 sinθ);
   ψ̈ = ω̇3 - d/dt(cosθ φ̇) = sinθ θ̇ φ̇ - cosθ φ̈;
   θ:  I1 θ̈ = I1 sinθ cosθ φ̇² - I3 ω3 sinθ φ̇ + M g l sinθ.
   Energy I1/2 (θ̇² + sin²θ φ̇²) + I3/2 ω3² + M g l cosθ;  p_φ = I1 sin²θ φ̇ + I3 ω3 cosθ, p_ψ = I3 ω3.
C  pendulum: θ̈ = -(g/l) sinθ;  energy m l²/2 θ̇² - m g l cosθ.
D  central force: m r̈ = m r φ̇² - k/r² - 2β/r³ (β = 0 for Kepler);  d/dt (m r² φ̇) = 0 ⇒ φ̈ = -2 ṙ φ̇ / r.
   Energy m/2 (ṙ² + r² φ̇²) - k/r - β/r², p_φ = m r² φ̇.
E  top on a vertically accelerating pivot, L = B's kinetic terms + M/2 (a t)² - M a t l sinθ θ̇
   - M g (a t²/2 + l cosθ).  φ and ψ enter as in B.  θ:
     ∂L/∂θ̇ = I1 θ̇ - M a t l sinθ,   d/dt ∂L/∂θ̇ = I1 θ̈ - M a l sinθ - M a t l cosθ θ̇,
     ∂L/∂θ = I1 sinθ cosθ φ̇² - I3 ω3 sinθ φ̇ - M a t l cosθ θ̇ + M g l sinθ,
   so I1 θ̈ = I1 sinθ cosθ φ̇² - I3 ω3 sinθ φ̇ + M (g + a) l sinθ: the two t-dependent terms
   (±M a t l cosθ θ̇) cancel and M/2 (a t)², -M g a t²/2 depend on t alone.  Equivalently
   -M a t l sinθ θ̇ = d/dt(M a t l cosθ) - M a l cosθ, a total derivative plus the potential of an extra
   gravity a.  The motion is B's with g → g + a; the right-hand side below keeps the t terms as derived.
   The Jacobi integral of this L is not conserved (L depends on t); the energy checked is that of the
   equivalent time-independent top, I1/2 (θ̇² + sin²θ φ̇²) + I3/2 ω3² + M (g + a) l cosθ, with p_φ, p_ψ as in B.

Figures of the run of 2026-11-28 (one core, pure-Python mpmath, no gmpy): generation 141 s in all, per
case 1.7 s (conical) to 35 s (near-separatrix libration), the tops 6-15 s; energy and momenta of the samples
at the working precision within 1e-36 relative (9e-34 for the rotating pendulum's far-unwrapped θ); the
period from the ODE against the second method within 2e-37 relative (5e-36 for the conical pendulum, whose
cubic has a nearly double root), the advances within 2e-34 absolute; Kepler's equation against the orbit
samples within 4e-34; --check 409 s.

Run:  python tests/reference/make_quadrature_reference.py [name ...]
      (about 2.5 minutes on one core of the development machine; writes quadrature_cases.json; with
      names, only those cases are regenerated and the others are kept from the existing file)
      python tests/reference/make_quadrature_reference.py --check [name ...]
      (regenerates at 10 more digits and prints the largest difference from the file; about 7 minutes)
"""

from __future__ import annotations

import json
import math
import sys
import time
from decimal import Decimal
from pathlib import Path

import mpmath

DPS = 30            # digits stored
WORK_DPS = 36       # digits integrated (per-case override in CASES)
DEGREE = 30         # Taylor degree of odefun
OUT = Path(__file__).with_name("quadrature_cases.json")
DYADIC = 2 ** 20    # sample times are multiples of 2^-20 (exact doubles, exact decimals)
NEAR = 1            # an event sample is this many 2^-20 s after the event (≈ 1e-6 s)
FRACTIONS = (0.13, 0.37, 0.61, 0.88)
MORE_FRACTIONS = (0.74, 0.25)  # added while a case has fewer than 6 first-period samples
LONG = ((100, 0.3), (137, 0.8), (1000, 0.1), (2024, 0.65))

L_SPH = "m*l**2/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + m*g*l*cos(theta)"
L_TOP = ("I1/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + I3/2*(psi_dot + cos(theta)*phi_dot)**2"
         " - M*g*l*cos(theta)")
L_PEN = "m*l**2/2*theta_dot**2 + m*g*l*cos(theta)"
L_KEP = "m/2*(r_dot**2 + r**2*phi_dot**2) + k/r"
L_PRE = "m/2*(r_dot**2 + r**2*phi_dot**2) + k/r + beta/r**2"
L_ACC = ("I1/2*(theta_dot**2 + sin(theta)**2*phi_dot**2) + I3/2*(psi_dot + cos(theta)*phi_dot)**2"
         " + M/2*(a*t)**2 - M*a*t*l*sin(theta)*theta_dot - M*g*(a*t**2/2 + l*cos(theta))")
P_SPH = dict(m=1.0, l=1.0, g=9.81)
P_TOP = dict(I1=1.0, I3=0.5, M=1.0, g=9.81, l=0.1)
P_ACC = dict(I1=1.0, I3=0.5, M=1.0, g=9.81, l=0.1, a=3.0)
PHI_DOT_CONICAL = float(math.sqrt(9.81 / (1.0 * math.cos(0.8))))


def _case(name, system, coords, lag, params, initial, **kw):
    return dict(name=name, system=system, coordinates=coords, lagrangian=lag, parameters=params,
                initial={k: float(v) for k, v in initial.items()}, **kw)


def _sph(th, ph, thd, phd):
    return {"theta": th, "phi": ph, "theta_dot": thd, "phi_dot": phd}


def _top(th, ph, ps, thd, phd, psd):
    return {"theta": th, "phi": ph, "psi": ps, "theta_dot": thd, "phi_dot": phd, "psi_dot": psd}


# Period events: ("turn", k) = root of the k-th state component's velocity-like component k (start at a
# turning point), ("return", k, offset) = root of y_k - y_k(0) - offset.  Events inside the first period:
# (label, k, level) = first crossing of y_k = level after t = 0.
CASES = [
    _case("spherical_generic", "sph", ["theta", "phi"], L_SPH, P_SPH, _sph(1.0, 0.0, 0.0, 2.0),
          period=("turn", 5), events=[("turning", 5, 0)]),
    _case("spherical_moving_start", "sph", ["theta", "phi"], L_SPH, P_SPH, _sph(0.7, 0.4, 1.3, -1.5),
          period=("return", 2, 0), events=[("turning", 5, 0)]),
    _case("spherical_conical", "sph", ["theta", "phi"], L_SPH, P_SPH, _sph(0.8, 0.0, 0.0, PHI_DOT_CONICAL),
          period=("turn", 5), events=[("turning", 5, 0)], dps=50, long="conical"),
    _case("spherical_through_pole", "sph_planar", ["theta", "phi"], L_SPH, P_SPH, _sph(1.0, 0.0, 0.0, 0.0),
          period=("turn", 3), events=[("fold", 0, 0), ("turning", 3, 0)]),
    _case("spherical_near_pole", "sph", ["theta", "phi"], L_SPH, P_SPH, _sph(1.0, 0.0, 0.0, 0.05),
          period=("turn", 5), events=[("turning_near_fold", 5, 0)]),
    _case("top_default", "top", ["theta", "phi", "psi"], L_TOP, P_TOP, _top(0.5, 0, 0, 0, 0, 20.0),
          period=("turn", 3), events=[("turning", 3, 0)]),
    _case("top_looping", "top", ["theta", "phi", "psi"], L_TOP, P_TOP, _top(0.5, 0, 0, 0, -2.0, 20.0),
          period=("turn", 3), events=[("turning", 3, 0), ("phi_dot_zero", 4, 0)]),
    _case("top_moving_start", "top", ["theta", "phi", "psi"], L_TOP, P_TOP, _top(0.9, 0.3, -0.2, 0.3, 1.0, 15.0),
          period=("return", 0, 0), events=[("turning", 3, 0)]),
    _case("pendulum_libration", "pen", ["theta"], L_PEN, P_SPH, {"theta": 2.0, "theta_dot": 0.0},
          period=("turn", 1), events=[("fold", 0, 0), ("turning", 1, 0)]),
    _case("pendulum_rotation", "pen", ["theta"], L_PEN, P_SPH, {"theta": 0.0, "theta_dot": 7.0},
          period=("return", 0, "2pi"), events=[("fold", 0, "pi")]),
    _case("pendulum_near_separatrix_libration", "pen", ["theta"], L_PEN, P_SPH,
          {"theta": 0.0, "theta_dot": 6.2641}, period=("return", 0, 0),
          events=[("turning", 1, 0), ("fold", 0, 0)], dps=40),
    _case("pendulum_near_separatrix_rotation", "pen", ["theta"], L_PEN, P_SPH,
          {"theta": 0.0, "theta_dot": 6.2643}, period=("return", 0, "2pi"), events=[("fold", 0, "pi")], dps=40),
    _case("kepler_ellipse", "kep", ["r", "phi"], L_KEP, dict(m=1.0, k=1.0),
          {"r": 1.0, "phi": 0.0, "r_dot": 0.1, "phi_dot": 1.2},
          period=("return", 0, 0), events=[("apocentre", 2, 0, -1), ("pericentre", 2, 0, 1)]),
    _case("kepler_hyperbola", "kep", ["r", "phi"], L_KEP, dict(m=1.0, k=1.0),
          {"r": 1.0, "phi": 0.0, "r_dot": 0.2, "phi_dot": 1.6},
          period=None, times=[0.5, 1.5, 3.25, 7.5, 15.0, 30.0]),
    _case("precessing_orbit", "kep", ["r", "phi"], L_PRE, dict(m=1.0, k=1.0, beta=0.05),
          {"r": 1.0, "phi": 0.0, "r_dot": 0.0, "phi_dot": 1.1},
          period=("turn", 2), events=[("apocentre", 2, 0)]),
    _case("top_accelerating_pivot", "acc", ["theta", "phi", "psi"], L_ACC, P_ACC, _top(0.5, 0, 0, 0, 0, 20.0),
          period=("turn", 3), events=[("turning", 3, 0)]),
]


def mp(x):
    return mpmath.mpf(float(x))


def _params(p):
    return {k: mp(v) for k, v in p.items()}


# ---------------------------------------------------------------- hand-written systems

def sph_state0(p, q):
    l = p["l"]
    th, ph, thd, phd = mp(q["theta"]), mp(q["phi"]), mp(q["theta_dot"]), mp(q["phi_dot"])
    s, c, sp, cp = mpmath.sin(th), mpmath.cos(th), mpmath.sin(ph), mpmath.cos(ph)
    return [l * s * cp, l * s * sp, -l * c,
            l * (c * cp * thd - s * sp * phd), l * (c * sp * thd + s * cp * phd), l * s * thd]


def sph_rhs(p):
    g, l2 = p["g"], p["l"] ** 2

    def f(t, y):
        x, yy, z, vx, vy, vz = y
        mu = (g * z - (vx * vx + vy * vy + vz * vz)) / l2
        return [vx, vy, vz, mu * x, mu * yy, mu * z - g]
    return f


def sph_read(y, planar):
    x, yy, z, vx, vy, vz = y
    if planar:  # y ≡ 0, φ ≡ 0, θ signed
        th = mpmath.atan2(x, -z)
        thd = (-z * vx + x * vz) / (x * x + z * z)
        return {"theta": th, "phi": mpmath.mpf(0)}, {"theta_dot": thd, "phi_dot": mpmath.mpf(0)}
    rho2 = x * x + yy * yy
    rho = mpmath.sqrt(rho2)
    rhod = (x * vx + yy * vy) / rho
    th = mpmath.atan2(rho, -z)
    thd = (-z * rhod + rho * vz) / (rho2 + z * z)
    phd = (x * vy - yy * vx) / rho2
    return {"theta": th, "phi": mpmath.atan2(yy, x)}, {"theta_dot": thd, "phi_dot": phd}


def top_rhs(p):
    I1, I3, M, g, l = p["I1"], p["I3"], p["M"], p["g"], p["l"]
    a = p.get("a")

    def f(t, y):
        th, ph, ps, thd, phd, psd = y
        s, c = mpmath.sin(th), mpmath.cos(th)
        w3 = psd + c * phd
        dLdth = I1 * s * c * phd ** 2 - I3 * w3 * s * phd + M * g * l * s
        if a is None:
            thdd = dLdth / I1
        else:  # E: the terms of ∂L/∂θ and d/dt ∂L/∂θ̇ as derived in the docstring
            dLdth = dLdth - M * a * t * l * c * thd
            thdd = (dLdth + M * a * l * s + M * a * t * l * c * thd) / I1
        phdd = thd * (I3 * w3 - 2 * I1 * c * phd) / (I1 * s)
        psdd = s * thd * phd - c * phdd
        return [thd, phd, psd, thdd, phdd, psdd]
    return f


def pen_rhs(p):
    w2 = p["g"] / p["l"]
    return lambda t, y: [y[1], -w2 * mpmath.sin(y[0])]


def kep_rhs(p):
    m, k, beta = p["m"], p["k"], p.get("beta", mpmath.mpf(0))

    def f(t, y):
        r, ph, rd, phd = y
        return [rd, phd, r * phd ** 2 - k / (m * r ** 2) - 2 * beta / (m * r ** 3), -2 * rd * phd / r]
    return f


def energy_momenta(system, p, q, qd):
    """The hand-written energy (Jacobi integral; for E that of the top with g + a) and conserved momenta."""
    if system in ("sph", "sph_planar"):
        m, l, g = p["m"], p["l"], p["g"]
        s = mpmath.sin(q["theta"])
        E = m * l ** 2 / 2 * (qd["theta_dot"] ** 2 + s ** 2 * qd["phi_dot"] ** 2) - m * g * l * mpmath.cos(q["theta"])
        return E, {"phi": m * l ** 2 * s ** 2 * qd["phi_dot"]}
    if system in ("top", "acc"):
        I1, I3, M, l = p["I1"], p["I3"], p["M"], p["l"]
        G = p["g"] + p.get("a", 0)
        s, c = mpmath.sin(q["theta"]), mpmath.cos(q["theta"])
        w3 = qd["psi_dot"] + c * qd["phi_dot"]
        E = I1 / 2 * (qd["theta_dot"] ** 2 + s ** 2 * qd["phi_dot"] ** 2) + I3 / 2 * w3 ** 2 + M * G * l * c
        return E, {"phi": I1 * s ** 2 * qd["phi_dot"] + I3 * w3 * c, "psi": I3 * w3}
    if system == "pen":
        m, l, g = p["m"], p["l"], p["g"]
        return m * l ** 2 / 2 * qd["theta_dot"] ** 2 - m * g * l * mpmath.cos(q["theta"]), {}
    if system == "kep":
        m, k, beta = p["m"], p["k"], p.get("beta", 0)
        r = q["r"]
        E = m / 2 * (qd["r_dot"] ** 2 + r ** 2 * qd["phi_dot"] ** 2) - k / r - beta / r ** 2
        return E, {"phi": m * r ** 2 * qd["phi_dot"]}
    raise ValueError(system)


class Motion:
    """The integrated motion of one case: y(t) from odefun, read off as coordinates (φ unwrapped)."""

    def __init__(self, case):
        self.case, self.system = case, case["system"]
        self.p = _params(case["parameters"])
        q = case["initial"]
        s = self.system
        if s in ("sph", "sph_planar"):
            self.y0, self.f = sph_state0(self.p, q), sph_rhs(self.p)
        elif s in ("top", "acc"):
            self.y0 = [mp(q[k]) for k in ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")]
            self.f = top_rhs(self.p)
        elif s == "pen":
            self.y0, self.f = [mp(q["theta"]), mp(q["theta_dot"])], pen_rhs(self.p)
        elif s == "kep":
            self.y0, self.f = [mp(q[k]) for k in ("r", "phi", "r_dot", "phi_dot")], kep_rhs(self.p)
        self.sol = mpmath.odefun(self.f, 0, self.y0, tol=mpmath.mpf(10) ** (-mpmath.mp.dps), degree=DEGREE)
        if s == "sph":
            self.track = [(mpmath.mpf(0), mp(q["phi"]))]  # (t, unwrapped φ), increasing t

    def _phi(self, t, raw):
        """Unwrapped φ at t: nearest-branch unwrapping from the last tracked time before t, in steps of at
        most 1/256 s (φ turns by less than π in such a step, even at the pole passage of A5)."""
        i = max(j for j, (tj, _) in enumerate(self.track) if tj <= t)
        t0, phi0 = self.track[i]
        n = int((t - t0) * 256) + 1
        for j in range(1, n):
            phi0 = self._unwrap(phi0, self.read_raw(t0 + (t - t0) * j / n)[0]["phi"])
        val = self._unwrap(phi0, raw)
        if i == len(self.track) - 1 and t > t0:
            self.track.append((t, val))
        return val

    @staticmethod
    def _unwrap(prev, raw):
        return raw + 2 * mpmath.pi * mpmath.nint((prev - raw) / (2 * mpmath.pi))

    def read_raw(self, t):
        y = self.sol(t)
        s = self.system
        if s in ("sph", "sph_planar"):
            return sph_read(y, s == "sph_planar")
        if s in ("top", "acc"):
            return (dict(zip(("theta", "phi", "psi"), y[:3])), dict(zip(("theta_dot", "phi_dot", "psi_dot"), y[3:])))
        if s == "pen":
            return {"theta": y[0]}, {"theta_dot": y[1]}
        return {"r": y[0], "phi": y[1]}, {"r_dot": y[2], "phi_dot": y[3]}

    def read(self, t):
        q, qd = self.read_raw(t)
        if self.system == "sph":
            q["phi"] = self._phi(t, q["phi"])
        return q, qd

    def root(self, k, level, guess):
        """Newton on y_k(t) = level from guess (y_k' = f_k)."""
        t = mpmath.mpf(guess)
        for _ in range(30):
            y = self.sol(t)
            dt = (y[k] - level) / self.f(t, y)[k]
            t -= dt
            if abs(dt) < abs(t) * mpmath.mpf(10) ** (-mpmath.mp.dps + 1):
                return t
        raise RuntimeError(f"{self.case['name']}: Newton did not converge")

    def first_crossing(self, k, level, t_end, direction=0, n=200):
        """First crossing of y_k = level in (0, t_end] (direction +1: upward, -1: downward, 0: either)."""
        prev = None
        for j in range(1, n + 1):
            t = t_end * j / n
            v = self.sol(t)[k] - level
            if prev is not None and (prev[1] > 0) != (v > 0) and direction * (v - prev[1]) >= 0:
                # bisect a little, then Newton
                a, b, va = prev[0], t, prev[1]
                for _ in range(20):
                    mid = (a + b) / 2
                    vm = self.sol(mid)[k] - level
                    if (vm > 0) == (va > 0):
                        a, va = mid, vm
                    else:
                        b = mid
                return self.root(k, level, (a + b) / 2)
            prev = (t, v)
        return None


# ---------------------------------------------------------------- independent second methods

def _cubic_period(f, u0, rates):
    """T and per-period advances ∮ rate(u) dt of u̇² = f(u) (cubic), u oscillating between the roots around u0."""
    pts = [mpmath.mpf(x) for x in (-1, 0, 1, 2)]
    V = mpmath.matrix([[x ** 3, x ** 2, x, 1] for x in pts])
    c = mpmath.lu_solve(V, mpmath.matrix([f(x) for x in pts]))
    coeffs = [c[0], c[1], c[2], c[3]]
    roots = sorted(mpmath.re(r) for r in mpmath.polyroots(coeffs, maxsteps=200, extraprec=4 * mpmath.mp.prec))
    A = coeffs[0]
    eps = mpmath.mpf(10) ** (-mpmath.mp.dps // 2)
    for i in range(2):
        u1, u2 = roots[i], roots[i + 1]
        if u1 - eps <= u0 <= u2 + eps and (u1 == u2 or f((u1 + u2) / 2) > 0):
            break
    else:
        raise RuntimeError("no oscillation interval")
    u3 = roots[2] if i == 0 else roots[0]

    def u_of(chi):
        return u1 + (u2 - u1) * mpmath.sin(chi) ** 2

    def integral(rate):
        return 4 * mpmath.quad(lambda chi: rate(u_of(chi)) / mpmath.sqrt(-A * (u_of(chi) - u3)),
                               [0, mpmath.pi / 4, mpmath.pi / 2])
    return integral(lambda u: 1), {k: integral(r) for k, r in rates.items()}


def second_method(case, motion):
    """(T, advances) by a method independent of the ODE integration; None where not applicable."""
    s, p = case["system"], motion.p
    q0, qd0 = motion.read_raw(0)
    E, mom = energy_momenta(s, p, q0, qd0)
    if s in ("sph", "sph_planar"):
        m, l, g = p["m"], p["l"], p["g"]
        e, w2, b = E / (m * l ** 2), g / l, mom["phi"] / (m * l ** 2)
        T, adv = _cubic_period(lambda u: (1 - u ** 2) * (2 * e + 2 * w2 * u) - b ** 2, mpmath.cos(q0["theta"]),
                               {"phi": lambda u: b / (1 - u ** 2)} if b else {})
        if s == "sph_planar":  # signed θ: one swing 1 → -1 → 1 is two oscillations of u = cosθ
            return 2 * T, {}
        return T, adv
    if s in ("top", "acc"):
        I1, I3, M, l = p["I1"], p["I3"], p["M"], p["l"]
        G = p["g"] + p.get("a", 0)
        w3 = mom["psi"] / I3
        alpha, beta = 2 * (E - I3 * w3 ** 2 / 2) / I1, 2 * M * G * l / I1
        a, b = mom["psi"] / I1, mom["phi"] / I1
        phid = lambda u: (b - a * u) / (1 - u ** 2)
        return _cubic_period(lambda u: (1 - u ** 2) * (alpha - beta * u) - (b - a * u) ** 2,
                             mpmath.cos(q0["theta"]), {"phi": phid, "psi": lambda u: w3 - u * phid(u)})
    if s == "pen":
        w0 = mpmath.sqrt(p["g"] / p["l"])
        if E < p["m"] * p["g"] * p["l"]:  # libration: sin(θmax/2)² = (E/(m l²) + w0²)/(2 w0²)
            m_ = (E / (p["m"] * p["l"] ** 2) + w0 ** 2) / (2 * w0 ** 2)
            return 4 * mpmath.ellipk(m_) / w0, {}
        v = mpmath.sqrt(2 * (E / (p["m"] * p["l"] ** 2) + w0 ** 2))  # speed at the bottom
        return 4 * mpmath.ellipk(4 * w0 ** 2 / v ** 2) / v, {"theta": 2 * mpmath.pi}
    if s == "kep":
        m, k, beta = p["m"], p["k"], p.get("beta", 0)
        if E >= 0:
            return None, {}
        a = -k / (2 * E)
        pphi = mom["phi"]
        # the radial motion is Kepler's with p² → p² - 2 m β: the same T; φ turns by 2π p / √(p² - 2 m β)
        return (2 * mpmath.pi * mpmath.sqrt(m * a ** 3 / k),
                {"phi": 2 * mpmath.pi * pphi / mpmath.sqrt(pphi ** 2 - 2 * m * beta)})
    raise ValueError(s)


def kepler_r(case, motion, t):
    """r(t) from Kepler's equation (elliptic or hyperbolic), an independent check of the orbit samples."""
    p = motion.p
    m, k = p["m"], p["k"]
    q0, qd0 = motion.read_raw(0)
    E, mom = energy_momenta("kep", p, q0, qd0)
    r0, rd0 = q0["r"], qd0["r_dot"]
    if E < 0:
        a = -k / (2 * E)
        n = mpmath.sqrt(k / (m * a ** 3))
        ecosE, esinE = 1 - r0 / a, r0 * rd0 / mpmath.sqrt(k * a / m)
        e = mpmath.sqrt(ecosE ** 2 + esinE ** 2)
        E0 = mpmath.atan2(esinE, ecosE)
        M = E0 - esinE + n * t
        Ea = mpmath.findroot(lambda x: x - e * mpmath.sin(x) - M, M)
        return a * (1 - e * mpmath.cos(Ea))
    a = k / (2 * E)
    n = mpmath.sqrt(k / (m * a ** 3))
    ecoshH, esinhH = 1 + r0 / a, r0 * rd0 / mpmath.sqrt(k * a / m)
    e = mpmath.sqrt(ecoshH ** 2 - esinhH ** 2)
    H0 = mpmath.asinh(esinhH / e)
    M = esinhH - H0 + n * t
    H = mpmath.findroot(lambda x: e * mpmath.sinh(x) - x - M, mpmath.asinh(M / e) if M else 0)
    return a * (e * mpmath.cosh(H) - 1)


# ---------------------------------------------------------------- generation

def dyadic(x):
    return round(float(x) * DYADIC) / DYADIC


def tstr(t_float):
    return str(Decimal(t_float))


def fmt(x):
    return mpmath.nstr(x, DPS)


def generate(case, report=print, only_times=None):
    """The JSON entry of one case (and a dict of self-check figures).  ``only_times``: keep the samples
    at those first-period times only, with no period (used by the test's regeneration)."""
    name, system = case["name"], case["system"]
    start = time.time()
    figures = {}
    motion = Motion(case)
    q0, qd0 = motion.read_raw(0)
    E0, P0 = energy_momenta(system, motion.p, q0, qd0)
    samples = []  # (t_float, q, qd)
    period, advance = None, {}
    if only_times is not None:
        for t in only_times:
            samples.append((t,) + motion.read(mpmath.mpf(t)))
    elif case["period"] is None:
        T2, _ = second_method(case, motion)
        assert T2 is None
        for t in case["times"]:
            q, qd = motion.read(mpmath.mpf(t))
            samples.append((t, q, qd))
        if system == "kep":
            figures["kepler_equation_r_max_diff"] = max(abs(q["r"] - kepler_r(case, motion, mpmath.mpf(t)))
                                                        for t, q, _ in samples)
    else:
        T2, adv2 = second_method(case, motion)
        kind, k = case["period"][0], case["period"][1]
        if kind == "turn":
            T = motion.root(k, 0, T2)
        else:
            off = case["period"][2]
            off = 2 * mpmath.pi if off == "2pi" else mpmath.mpf(off)
            T = motion.root(k, motion.y0[k] + off, T2)
        period = T
        figures["period_vs_second_method"] = abs(T - T2) / T
        # first-period samples: fractions plus the events
        times = [dyadic(fr * T) for fr in FRACTIONS]
        for label, k, level, *direction in case["events"]:
            level = mpmath.pi if level == "pi" else mpmath.mpf(level)
            te = motion.first_crossing(k, level, T, *direction)
            if te is None:
                raise RuntimeError(f"{name}: no {label} event")
            times.append(round(float(te) * DYADIC + NEAR) / DYADIC)
            figures[f"event_{label}"] = float(te)
        for fr in MORE_FRACTIONS:
            if len(set(times)) < 6:
                times.append(dyadic(fr * T))
        times = sorted(set(times))
        for t in times:
            samples.append((t,) + motion.read(mpmath.mpf(t)))
        qT, qdT = motion.read(T)
        cyclic = {"sph": ["phi"], "sph_planar": [], "top": ["phi", "psi"], "acc": ["phi", "psi"],
                  "pen": ["theta"] if "theta" in adv2 else [], "kep": ["phi"]}[system]
        for c in cyclic:
            advance[c] = qT[c] - q0[c]
        figures["state_return"] = max([abs(qT[c] - q0[c]) for c in q0 if c not in cyclic] +
                                      [abs(qdT[c] - qd0[c]) for c in qd0])
        figures["advance_vs_second_method"] = max([abs(advance[c] - adv2[c]) for c in adv2] + [mpmath.mpf(0)])
        if set(adv2) - set(advance) or (system != "sph_planar" and set(advance) - set(adv2)):
            raise RuntimeError(f"{name}: advances {set(advance)} vs {set(adv2)}")
        long = LONG
        if case.get("long") == "conical":  # samples up to t = 100
            nmax = int(100 / float(T)) - 1
            long = ((3, 0.3), (10, 0.8), (37, 0.1), (nmax, 0.65))
        for N, fr in long:
            t = dyadic((N + fr) * T)
            tau = mpmath.mpf(t) - N * T
            q, qd = motion.read(tau)
            q = {c: v + N * advance[c] if c in advance else v for c, v in q.items()}
            samples.append((t, q, qd))
        if system == "kep":
            figures["kepler_equation_r_max_diff"] = max(abs(q["r"] - kepler_r(case, motion, mpmath.mpf(t)))
                                                        for t, q, _ in samples)
    errE, errP = mpmath.mpf(0), mpmath.mpf(0)
    for t, q, qd in samples:
        E, P = energy_momenta(system, motion.p, q, qd)
        errE = max(errE, abs(E - E0) / max(abs(E0), 1))
        for c in P:
            errP = max(errP, abs(P[c] - P0[c]) / max(abs(P0[c]), 1))
    figures["energy_rel"], figures["momenta_rel"] = errE, errP
    figures["seconds"] = time.time() - start
    entry = {"name": name, "coordinates": case["coordinates"], "lagrangian": case["lagrangian"],
             "parameters": case["parameters"], "initial": case["initial"],
             "period": None if period is None else fmt(period),
             "advance": {c: fmt(v) for c, v in advance.items()},
             "samples": [{"t": tstr(t), "q": {c: fmt(q[c]) for c in case["coordinates"]},
                          "q_dot": {c + "_dot": fmt(qd[c + "_dot"]) for c in case["coordinates"]}}
                         for t, q, qd in samples]}
    report(f"{name}: {figures['seconds']:.1f} s, dps {mpmath.mp.dps}, "
           + ", ".join(f"{k} {mpmath.nstr(v, 3) if not isinstance(v, float) else f'{v:.6g}'}"
                       for k, v in figures.items() if k != "seconds"))
    return entry, figures


def check(names=None, extra=10) -> None:
    """Regenerate at ``extra`` more digits (tolerance and working precision) and compare with the file."""
    stored = {c["name"]: c for c in json.loads(OUT.read_text())["cases"]}
    for case in CASES:
        if names and case["name"] not in names:
            continue
        with mpmath.workdps(case.get("dps", WORK_DPS) + extra):
            entry, _ = generate(case, report=lambda s: None)
            old = stored[case["name"]]
            diffs = []
            if old["period"] is not None:
                diffs.append(abs(mpmath.mpf(entry["period"]) - mpmath.mpf(old["period"])) / mpmath.mpf(old["period"]))
            for c, v in old["advance"].items():
                diffs.append(abs(mpmath.mpf(entry["advance"][c]) - mpmath.mpf(v)) / max(1, abs(mpmath.mpf(v))))
            assert [s["t"] for s in entry["samples"]] == [s["t"] for s in old["samples"]], case["name"]
            for new, s in zip(entry["samples"], old["samples"]):
                for key in ("q", "q_dot"):
                    for c, v in s[key].items():
                        diffs.append(abs(mpmath.mpf(new[key][c]) - mpmath.mpf(v)) / max(1, abs(mpmath.mpf(v))))
            print(f"{case['name']}: at {mpmath.mp.dps} digits, max difference from the file "
                  f"{mpmath.nstr(max(diffs), 3)} (relative to max(1, |value|))", flush=True)


def _write(entries):
    OUT.write_text(json.dumps({
        "source": "tests/reference/make_quadrature_reference.py", "dps": DPS,
        "method": f"mpmath.odefun (Taylor, degree {DEGREE}, tol 10^-dps at {WORK_DPS} digits, 40 near the "
                  "separatrix, 50 for the conical pendulum) on hand-written equations of motion; period "
                  "symmetry for long times; times are exact dyadic doubles",
        "cases": entries}, indent=1) + "\n")


def main(names=None) -> None:
    old = {}
    if names and OUT.exists():
        old = {c["name"]: c for c in json.loads(OUT.read_text())["cases"]}
    total = time.time()
    entries = []
    for case in CASES:
        if names and case["name"] not in names:
            if case["name"] in old:
                entries.append(old[case["name"]])
            continue
        with mpmath.workdps(case.get("dps", WORK_DPS)):
            entry, _ = generate(case, report=lambda s: print(s, flush=True))
        entries.append(entry)
        _write(entries + [old[c["name"]] for c in CASES[len(entries):] if c["name"] in old])  # progress
    _write(entries)
    print(f"total {time.time() - total:.1f} s")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--check"]:
        check(sys.argv[2:] or None)
    else:
        main(sys.argv[1:] or None)
