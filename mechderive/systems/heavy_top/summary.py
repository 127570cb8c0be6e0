"""The heavy top's per-motion quantities (issue 14 §1): turning angles, roots of f, periods, rates.

Each is taken from the closed form's constants (:class:`~.exact.HeavyTopSolution`, set up at 40
digits from the exact binary inputs) — also for a scene integrated, as long as the closed form's
setup succeeds — and each estimate is *measured* on this motion:

* the roots u1 ≤ u2 ≤ u3 of f(u) (3.73): the distance of the double to the root, from f, f', f''
  evaluated at the double at 40 digits (a Newton step, or √(2|f/f''|) at a double root);
* θ_min, θ_max: from 1 ∓ u of the 40-digit roots, the double's rounding plus the root's error / sin θ;
* the nutation period 2K/κ and the advance Δφ per period (c0/κ)·2K + Σ (c_i/κ)·2Π(n_i|m) (3.74):
  the double's rounding plus the difference of two independent 40-digit evaluations (the setup's
  K by the AGM and Π by :func:`~mechderive.special.highprec.complete_pi_mp`, against Carlson's R_F
  and mpmath's own Π);
* E, p_φ, p_ψ: the closed form's constants against the chapter's (3.63)-(3.65) at 40 digits;
* the uniform precession's slow and fast rates: the model's derived roots of (3.80)
  (``precession_rates``) at 40 digits, measured by a Newton step of the quadratic; the scene's φ̇
  against the nearer one;
* the sleeping top's threshold (3.83): the model's derived ``sleeping_threshold_spin`` (u2 = 1) at
  40 digits, the estimate its rounding to a double.

Where the closed form cannot follow the motion (:class:`~..base.OutOfReach`), θ_min, θ_max, the
nutation period and the invariants are measured on the integrated trajectory; the rest is None
with the reason.  Importing this module imports neither mpmath nor SciPy.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import InvalidInputError
from ..base import Quantity, Solved

if TYPE_CHECKING:  # pragma: no cover
    from ...scenes.schema import Scene

__all__ = ["SUMMARIES", "summarize", "period"]

SUMMARIES = (
    Quantity("nutation_period", "s", "period of θ(t), 2K(m)/κ (3.73); None for a steady motion", scales_as="time"),
    Quantity("period", "s", "period of the reduced motion: the nutation period", scales_as="time"),
    Quantity("theta_min", "rad", "smallest θ of the motion (turning point u2 = cos θ_min)", scales_as="angle"),
    Quantity("theta_max", "rad", "largest θ of the motion (turning point u1 = cos θ_max)", scales_as="angle"),
    Quantity("u1", "1", "smallest root of f(u) (3.73): the lower turning point of u = cos θ"),
    Quantity("u2", "1", "middle root of f(u) (3.73): the upper turning point of u = cos θ"),
    Quantity("u3", "1", "largest root of f(u) (3.73), ≥ 1 (outside the motion)"),
    Quantity("mean_precession_rate", "rad/s", "mean of φ̇ over a nutation period: Δφ per period / period",
             scales_as="rate"),
    Quantity("precession_per_nutation", "rad", "Δφ over one nutation period (3.74)", scales_as="angle"),
    Quantity("motion_class", "1", "figure 44: monotonic precession, looping, cusps, or uniform precession"),
    Quantity("steady", "rad/s", "steady motion: kind (uniform precession, sleeping, hanging, none) and its rates "
             "(φ̇, ψ̇, ω3; the slow and fast precessions of (3.80))"),
    Quantity("minimum_spin", "rad/s", "ω3 above which the sleeping top is stable, 2√(I1 M g l)/I3 (3.83)",
             scales_as="rate"),
    Quantity("energy", "J", "energy E (3.65)", scales_as="energy"),
    Quantity("p_phi", "kg m^2/s", "p_φ, the vertical angular momentum (3.64)", scales_as="angular momentum"),
    Quantity("p_psi", "kg m^2/s", "p_ψ = I3 ω3 (3.63)", scales_as="angular momentum"),
)

_NAMES = tuple(q.name for q in SUMMARIES)

Pair = tuple[Any, Any]


def _closed_form(scene: "Scene", solved: Solved | None) -> tuple[Any, str]:
    """(the closed-form solution, "") or (None, why not): the solve's own, else set up from the scene."""
    from .exact import HeavyTopSolution, exact_heavy_top

    if solved is not None and isinstance(solved.solution, HeavyTopSolution):
        return solved.solution.precise(), ""  # the summaries are formed at 40 digits
    try:
        return exact_heavy_top(scene.parameters, scene.initial, strict=scene.strict), ""
    except InvalidInputError as exc:
        return None, f"the closed form cannot follow this motion ({exc})"


def period(scene: "Scene") -> float | None:
    """The nutation period (s) of ``scene`` from the closed form's setup; None where the motion is steady
    or the closed form cannot follow it (scene in any units: solved in those of its own motion)."""
    scaled = scene.model.scale(scene)
    sol, _ = _closed_form(scaled.scene, None)
    if sol is None or sol.kind == "steady" or not math.isfinite(sol.nutation_period):
        return None
    return scaled.seconds(sol.nutation_period)


def summarize(scene: "Scene", solved: Solved, t: np.ndarray, names: tuple[str, ...]) -> dict[str, Pair]:
    """{name: (value, estimate)} of the heavy top's per-motion quantities ``names`` (see :data:`SUMMARIES`),
    in the solver's units; a quantity that does not apply is (None, the reason)."""
    unknown = [n for n in names if n not in _NAMES]
    if unknown:
        raise InvalidInputError(f"unknown heavy_top per-motion quantity {unknown[0]!r}: expected one of "
                                f"{', '.join(_NAMES)}")
    sol, why = _closed_form(scene, solved)
    if sol is None:
        measured = _Measured(solved, t, why)
        return {n: measured.of(n) for n in names}
    import mpmath

    with mpmath.workdps(sol._mp.get("dps", 40)):
        closed = _Closed(sol)
        return {n: closed.of(n) for n in names}


def not_sleeping(theta: float, theta_dot: float) -> str:
    """Why ``minimum_spin`` does not apply to a top launched at θ, θ̇ (also the batch's reason)."""
    return (f"applies to a sleeping top (θ = θ̇ = 0 at t = 0, (3.82)); this one starts at θ = {theta:.6g} rad, "
            f"θ̇ = {theta_dot:.6g} rad/s")


#: ``steady``'s value for a motion that is not steady (nutating): no rates to give
NOT_STEADY = {"kind": "none"}


# --- from the closed form ----------------------------------------------------------------------------

def _rounding(x_mp: Any) -> tuple[float, float]:
    """(the double nearest ``x_mp``, its distance from it): the rounding actually incurred."""
    import mpmath

    x = float(x_mp)
    return x, float(abs(mpmath.mpf(x) - x_mp))


_RATE_ARGS = ("I1", "I3", "M", "g", "l", "theta0", "omega3")


def _derived(name: str, args: tuple[str, ...], member: int | None = None) -> Any:
    """A derived quantity of the heavy-top model (``member`` of a tuple), compiled for mpmath once (disk cache)."""
    from ...core import codecache
    from . import model as hm

    def build() -> tuple:
        value = getattr(hm.model(), name)
        symbols = {"I1": hm.I1, "I3": hm.I3, "M": hm.M, "g": hm.g, "l": hm.l, "theta0": hm.theta0,
                   "omega3": hm.omega3}
        return [symbols[a] for a in args], value if member is None else value[member]

    label = f"heavy_top.summary.{name}" + ("" if member is None else f".{member}")
    return codecache.cached_lambdify(label, build, module="mpmath")[0]


class _Closed:
    """The per-motion quantities of one closed-form motion, each computed once (at the setup's precision)."""

    def __init__(self, sol: Any) -> None:
        import mpmath

        self.sol, self.mp = sol, mpmath
        p, s = sol.parameters, sol.initial
        mpf = mpmath.mpf
        self.I1, self.I3 = mpf(p["I1"]), mpf(p["I3"])
        self.mgl = mpf(p["M"]) * mpf(p["g"]) * mpf(p["l"])
        self.th0, self.thd0, self.phd0, self.psd0 = (mpf(s[k]) for k in ("theta", "theta_dot", "phi_dot", "psi_dot"))
        self.w3 = self.psd0 + self.phd0 * mpmath.cos(self.th0)  # ω3 (3.63)
        self.steady = sol.kind == "steady"
        # a uniform precession given in doubles nutates by ~1e-17: figure 44's class (u2 - u1 ≤ 1e-12) says steady
        self.steady_motion = self.steady or sol.motion_class == "uniform precession"
        self._memo: dict[str, Pair] = {}

    def of(self, name: str) -> Pair:
        if name not in self._memo:
            self._memo[name] = getattr(self, "_" + name)()
        return self._memo[name]

    # f(u) (3.73) at the setup's precision
    def _coefficients(self) -> list:
        if "coefficients" not in self.__dict__:
            from .exact import _nutation_functions

            f = _nutation_functions()
            p, s = self.sol.parameters, self.sol.initial
            P = [self.mp.mpf(p[k]) for k in ("I1", "I3", "M", "g", "l")]
            S = [self.mp.mpf(s[k]) for k in ("theta", "theta_dot", "phi_dot", "psi_dot")]
            self.__dict__["coefficients"] = list(f["f"](*f["state"](*P, *S)))
        return self.__dict__["coefficients"]

    def _root_error(self, u: Any) -> float:
        """|u - the nearest root of f| for u near a root: f, f', f'' at u at 40 digits, with their rounding.

        Min of twice the Newton step 2|f/f'| (a simple root: the step is the distance) and √(2|f/f''|)
        (a double root, f' → 0: the quadratic's).
        """
        mp = self.mp
        c3, c2, c1, c0 = self._coefficients()
        u = mp.mpf(u)
        f = ((c3 * u + c2) * u + c1) * u + c0
        f = abs(f) + mp.mpf(10) ** (-mp.mp.dps + 1) * (abs(c3 * u**3) + abs(c2 * u * u) + abs(c1 * u) + abs(c0))
        d1 = abs((3 * c3 * u + 2 * c2) * u + c1)
        d2 = abs(6 * c3 * u + 2 * c2)
        candidates = [2 * f / d1] if d1 else []
        if d2:
            candidates.append(mp.sqrt(2 * f / d2))
        return float(min(candidates)) if candidates else float("inf")

    def _roots(self, k: int) -> Pair:
        u = self.sol.roots[k]
        return u, self._root_error(u)

    def _u1(self) -> Pair:
        return self._roots(0)

    def _u2(self) -> Pair:
        return self._roots(1)

    def _u3(self) -> Pair:
        return self._roots(2)

    def _turning(self, k: int) -> Pair:
        """θ at the turning point u_k (k = 0: θ_max, 1: θ_min); θ0 for a steady motion."""
        mp = self.mp
        if self.steady:
            # the motion stays at θ0 (an equilibrium of θ for the top at the pole or the bottom): the error
            # is how far the double root u1 = u2 may lie from cos θ0, in θ
            th0 = float(self.sol.initial["theta"])
            if th0 in (0.0, math.pi):
                return th0, 0.0  # θ = θ̇ = 0 (π) is an exact equilibrium of θ's equation: θ stays θ0 exactly
            err_u = self._root_error(math.cos(th0))
            return th0, err_u / math.sin(th0)
        r = self.sol._mp["roots"][k]
        theta = 2 * mp.atan2(mp.sqrt(1 - r), mp.sqrt(1 + r))  # θ from 1 ∓ u, without cancellation at the poles
        value, rounding = _rounding(theta)
        f = ((self._coefficients()[0] * r + self._coefficients()[1]) * r + self._coefficients()[2]) * r \
            + self._coefficients()[3]
        slope = abs((3 * self._coefficients()[0] * r + 2 * self._coefficients()[1]) * r + self._coefficients()[2])
        err_u = abs(f) / slope if slope else mp.mpf(0)
        s = mp.sin(theta)
        err = err_u / s if s > mp.sqrt(err_u) else mp.sqrt(2 * err_u)
        return value, rounding + float(err)

    def _theta_min(self) -> Pair:
        return self._turning(1)

    def _theta_max(self) -> Pair:
        return self._turning(0)

    def _not_nutating(self) -> Pair:
        return None, (f"not a nutating motion: this top is steady ({self.sol.motion_class}, θ = θ0 = "
                      f"{self.sol.initial['theta']:.17g} for all t), it has no nutation period")

    def _period_mp(self) -> tuple[Any, Any]:
        """2K/κ at 40 digits, by the setup's K (AGM) and by Carlson's R_F(0, 1 - m, 1)."""
        v = self.sol._mp
        return 2 * v["K"] / v["kappa"], 2 * self.mp.elliprf(0, v["m1"], 1) / v["kappa"]

    def _nutation_period(self) -> Pair:
        if self.steady or self.sol._period is None:
            return self._not_nutating() if self.steady else (None, "on the separatrix (m = 1): no period")
        T, T2 = self._period_mp()
        value, rounding = _rounding(T)
        return value, rounding + float(abs(T - T2))

    def _period(self) -> Pair:
        return self._nutation_period()

    def _advance_mp(self) -> tuple[Any, Any]:
        """Δφ per nutation period at 40 digits, by the closed form's own advance (plus π per exact passage
        through the pole or the bottom, as its φ(t) turns there) and independently by mpmath's Π(n|m)."""
        mp, sol, v = self.mp, self.sol, self.sol._mp
        dd = sol._per_period_precise["phi"]
        passages = (sol._one_minus_u2 == 0.0) + (sol._one_plus_u1 == 0.0)
        first = mp.mpf(dd.hi) + mp.mpf(dd.lo) + passages * mp.pi
        c0, kept = sol._angle_fractions["phi"]
        kappa = v["kappa"]
        second = (c0 / kappa) * 2 * mp.elliprf(0, v["m1"], 1)
        for c, n in kept:
            second += (c / kappa) * 2 * mp.ellippi(n, v["m"])
        return first, second + passages * mp.pi

    def _precession_per_nutation(self) -> Pair:
        if self.steady or self.sol._period is None:
            return self._not_nutating() if self.steady else (None, "on the separatrix (m = 1): no period")
        a, b = self._advance_mp()
        value, rounding = _rounding(a)
        return value, rounding + float(abs(a - b))

    def _mean_precession_rate(self) -> Pair:
        if self.steady:
            if self.sol.initial["theta"] in (0.0, math.pi):
                return None, "at the pole (or the bottom) only φ̇ ± ψ̇ is defined: see steady's omega3"
            return float(self.phd0), 0.0  # φ̇ is constant, exactly the initial rate
        if self.sol._period is None:
            return None, "on the separatrix (m = 1): no period"
        a, b = self._advance_mp()
        T, T2 = self._period_mp()
        value, rounding = _rounding(a / T)
        return value, rounding + float(abs(a / T - b / T2))

    def _motion_class(self) -> Pair:
        return self.sol.motion_class, None

    def _minimum_spin_mp(self) -> Any:
        """The derived threshold (:attr:`.model.HeavyTopModel.sleeping_threshold_spin`: u2 = 1 of the sleeping
        top's f(u), (3.83)) at 40 digits; only M g l enters, given as M with g = l = 1."""
        with self.mp.workdps(40):
            return _derived("sleeping_threshold_spin", ("I1", "I3", "M", "g", "l"))(
                self.I1, self.I3, self.mgl, 1, 1)[0]

    def _sleeping(self) -> bool:
        return self.sol.initial["theta"] == 0.0 and self.sol.initial["theta_dot"] == 0.0

    def _minimum_spin(self) -> Pair:
        if not self._sleeping():
            s = self.sol.initial
            return None, not_sleeping(s["theta"], s["theta_dot"])
        return _rounding(self._minimum_spin_mp())

    def _steady(self) -> Pair:
        mp, sol = self.mp, self.sol
        w3, w3_err = _rounding(self.w3)
        if not self.steady_motion:
            return dict(NOT_STEADY), None
        th0 = sol.initial["theta"]
        if self._sleeping():
            ms, ms_err = _rounding(self._minimum_spin_mp())
            return {"kind": "sleeping", "omega3": w3, "minimum_spin": ms, "stable": abs(w3) > ms}, max(w3_err, ms_err)
        if th0 == math.pi:
            return {"kind": "hanging", "omega3": w3}, w3_err
        # uniform precession: the two roots φ̇ of (3.80) as derived (:attr:`.model.HeavyTopModel.precession_rates`,
        # free of cancellation), at 40 digits; the Newton step of the quadratic below measures them
        c = self.I1 * mp.cos(self.th0)
        B = self.I3 * self.w3
        disc = B * B - 4 * c * self.mgl
        out: dict[str, Any] = {"kind": "uniform precession", "phi_dot": sol.initial["phi_dot"],
                               "psi_dot": sol.initial["psi_dot"], "omega3": w3}
        errs = [w3_err]
        rates = []
        if disc >= 0:
            args = (self.I1, self.I3, self.mgl, 1, 1, self.th0, self.w3)
            with mp.workdps(40):
                rates = [_derived("precession_rates", _RATE_ARGS, 0)(*args)[0]] + (
                    [_derived("precession_rates", _RATE_ARGS, 1)(*args)[0]] if c != 0 else [])
            rates.sort(key=abs)
        for key, r in zip(("slow_precession", "fast_precession"), rates):
            out[key], e = _rounding(r)
            residual = abs(self.mgl - r * (B - c * r)) / abs(B - 2 * c * r)  # the Newton step of (3.80)
            errs.append(e + float(residual))
        if len(rates) < 2:
            out["fast_precession"] = None
        if rates:
            near = min(rates, key=lambda r: abs(r - self.phd0))
            out["branch"] = "slow" if near is rates[0] else "fast"
            # how far the scene's φ̇ is from the (3.80) rate it is: measured, not assumed 0
            errs.append(float(abs(near - self.phd0)))
        return out, max(errs)

    # the invariants: the closed form's constants against the chapter's formulas at 40 digits
    def _invariant(self, name: str, exact: Any) -> Pair:
        value = getattr(self.sol, name)
        return value, float(abs(self.mp.mpf(value) - exact))

    def _energy(self) -> Pair:
        mp = self.mp
        E = (self.I1 * (self.thd0**2 + (self.phd0 * mp.sin(self.th0))**2) + self.I3 * self.w3**2) / 2 \
            + self.mgl * mp.cos(self.th0)  # (3.65)
        return self._invariant("energy", E)

    def _p_phi(self) -> Pair:
        mp = self.mp
        return self._invariant("p_phi", self.I1 * mp.sin(self.th0)**2 * self.phd0
                               + self.I3 * mp.cos(self.th0) * self.w3)  # (3.64)

    def _p_psi(self) -> Pair:
        return self._invariant("p_psi", self.I3 * self.w3)  # (3.63)


# --- measured on the trajectory -----------------------------------------------------------------------

class _Measured:
    """What an integrated trajectory shows when the closed form cannot follow the motion: θ's extremes
    (each refined by the parabola through the sample and its neighbours; the estimate is the refinement
    plus the integration's own), the nutation period from the spacing of θ's maxima, and the invariants'
    mean with their spread along the run."""

    def __init__(self, solved: Solved, t: np.ndarray, why: str) -> None:
        self.traj, self.t, self.why = solved.solution, np.asarray(t, dtype=float), why
        self.theta = np.asarray(self.traj.euler_angles[:, 1], dtype=float) \
            if hasattr(self.traj, "euler_angles") else None
        own = getattr(self.traj, "euler_angle_error_estimate", None)
        self.own = float(own) if own is not None else float("nan")

    def of(self, name: str) -> Pair:
        if self.theta is None:
            return None, f"{self.why}; the solution holds no trajectory to measure"
        if name in ("theta_min", "theta_max"):
            return self._extreme(name == "theta_max")
        if name in ("nutation_period", "period"):
            return self._period()
        if name in ("energy", "p_phi", "p_psi") and self.traj.invariants is not None:
            col = np.asarray(self.traj.invariants, dtype=float)[:, ("energy", "p_phi", "p_psi").index(name)]
            return float(col[0]), float(np.max(np.abs(col - col[0])))
        return None, f"{self.why}; {name} is not measured on the integrated trajectory"

    @staticmethod
    def _vertex(t: np.ndarray, y: np.ndarray, i: int, k: int) -> tuple[float, float] | None:
        """(t, y) of the vertex of the parabola through the samples i - k, i, i + k, or None if not a maximum."""
        h0, h1 = t[i] - t[i - k], t[i + k] - t[i]
        d0, d1 = (y[i] - y[i - k]) / h0, (y[i + k] - y[i]) / h1
        curv = (d1 - d0) / (h0 + h1)  # half y'' of the parabola
        if not curv < 0:
            return None
        slope = (d0 * h1 + d1 * h0) / (h0 + h1)  # the parabola's slope at t_i
        dt = -slope / (2 * curv)
        return t[i] + dt, y[i] + slope * dt + curv * dt * dt

    def _peaks(self, sign: float) -> list[tuple[float, float, float, float]]:
        """(t, θ, error of t, error of θ) of each interior local extreme of sign·θ: the vertex of the parabola
        through the sample and its neighbours, its error measured against that through the next-but-one
        samples (whose error, O(h²) larger by 4, bounds the narrow one's)."""
        y, t = sign * self.theta, self.t
        out = []
        for i in range(2, len(y) - 2):
            if y[i] >= y[i - 1] and y[i] > y[i + 1]:
                narrow, wide = self._vertex(t, y, i, 1), self._vertex(t, y, i, 2)
                if narrow is not None and wide is not None:
                    out.append((narrow[0], sign * narrow[1], abs(narrow[0] - wide[0]), abs(narrow[1] - wide[1])))
        return out

    def _extreme(self, largest: bool) -> Pair:
        sign = 1.0 if largest else -1.0
        peaks = self._peaks(sign)
        if not peaks:
            return None, f"{self.why}; θ reaches no interior {'maximum' if largest else 'minimum'} in the samples"
        best = max(peaks, key=lambda p: sign * p[1])
        # the other extremes are the same turning point again: their spread is measured too
        spread = max(abs(p[1] - best[1]) for p in peaks)
        return float(best[1]), best[3] + spread + self.own

    def _period(self) -> Pair:
        peaks = self._peaks(1.0)
        if len(peaks) < 2:
            return None, f"{self.why}; fewer than two maxima of θ in the samples: no period measured"
        times = np.array([p[0] for p in peaks])
        gaps = np.diff(times)
        mean = float((times[-1] - times[0]) / (len(times) - 1))
        timing = (peaks[0][2] + peaks[-1][2]) / (len(times) - 1)
        return mean, float(np.max(np.abs(gaps - mean))) + timing
