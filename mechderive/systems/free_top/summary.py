"""The free top's per-motion quantities (``[output] summary = [...]``): the polhode period, the interval
between flips, the symmetric top's precession rates, the stability of each principal axis, the invariants.

Each comes from the closed form (:mod:`.exact`) where it has one, and its estimate is measured on this
motion, never a constant:

* ``polhode_period`` (= ``period``): 4K/λ of the Jacobi solution.  The estimate is the closed form's own
  return error: |ω(P) - ω(0)| / |ω̇(0)| (how far the body's ω is from coming back at the period, turned
  into a time by Euler's equations (3.33)), plus the rounding of P.  Without a closed form (an integrated
  run it cannot follow) it is measured on the integrated ω by :func:`mechderive.core.periodic.measure_period`.
* ``flip_interval``: half the polhode period — the time between successive reversals of ω along the
  intermediate axis (its component is the Jacobi sn, which changes sign twice a period), which is the
  flip of a body spun near that axis (the tennis racket, section 3.4.3).  Defined for three distinct
  moments and a periodic (elliptic) motion.
* ``precession_rate`` (symmetric top, two equal moments I⊥ and the symmetry axis a of moment I_a):
  {"body": Ω, "space": φ̇}: Ω of (3.35)-(3.36) read off the derived symmetric equations, the rate at which
  ω turns about the symmetry axis in the body; φ̇, the rate at which the symmetry axis turns about L in
  space, from the closed form (its precession per polhode period over the period).  The estimate is the
  rounding of Ω's terms and the difference between the closed form's φ̇ and |L|/I⊥ (3.60).
* ``stability``: per principal axis, for a spin about it at this motion's rate |ω(0)|: "stable" with the
  angular frequency of small oscillations, "unstable" with the growth rate (3.44)-(3.45), "neutral" for
  an axis of equal moments — from the eigenvalues of Euler's equations linearised about that spin
  (:func:`.stability.linearised_eigenvalues`, derived).
* ``energy`` T (3.46) and ``angular_momentum`` |L| (3.47): their values at t = 0, the estimate their largest
  deviation along the run.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..base import Quantity, Solved

__all__ = ["SUMMARIES", "summarize", "period"]

SUMMARIES = (
    Quantity("polhode_period", "s", "period of ω(t) in the body: the polhode closes (section 3.5)", "time"),
    Quantity("period", "s", "period of the reduced motion: the polhode period", "time"),
    Quantity("flip_interval", "s", "time between reversals of ω along the intermediate axis: half the polhode "
             "period (the tennis racket's flips)", "time"),
    Quantity("precession_rate", "rad/s", "symmetric top: {body: Ω of (3.36), ω about the symmetry axis in the "
             "body; space: φ̇ = |L|/I⊥ of (3.60), the axis about L}", "rate"),
    Quantity("stability", "1", "per principal axis, for a spin about it at |ω(0)|: stable (with the frequency "
             "of small oscillations) or unstable (with the growth rate), (3.44)-(3.45)"),
    Quantity("energy", "J", "kinetic energy T (3.46), conserved", "energy"),
    Quantity("angular_momentum", "kg m^2/s", "|L| (3.47), conserved", "angular momentum"),
)

_EPS = float(np.finfo(float).eps)


def _moments_and_omega(scene: Any) -> tuple[np.ndarray, np.ndarray]:
    p = scene.parameters
    return np.array([p["I1"], p["I2"], p["I3"]], dtype=float), np.asarray(scene.initial["omega"], dtype=float)


def _omega_dot(moments: np.ndarray, w: np.ndarray) -> np.ndarray:
    """ω̇ by Euler's equations (3.33) as derived (:attr:`.model.FreeTopModel.free_rhs`, compiled)."""
    from .stability import _compiled

    return np.asarray(_compiled("free_rhs")(*w, *moments), dtype=float).reshape(3)


def symmetric_rate_function() -> Any:
    """Ω(I⊥, I_a, ω_a) of (3.35)-(3.36) as derived from the symmetric top's equations
    (:attr:`.model.FreeTopModel.symmetric_precession_rate`, symmetry axis 3; another symmetry axis is the same
    equations with the axes relabelled cyclically), compiled for NumPy (elementwise on arrays too)."""
    from ...core import codecache
    from . import model as fm

    def build():
        return [fm.I1, fm.I3, fm.omega_symbols()[2]], fm.model().symmetric_precession_rate

    return codecache.cached_lambdify("free_top.symmetric_precession_rate", build, module="numpy")[0]


def _symmetric_rate(perp: float, axial: float, spin: float) -> float:
    """Ω of (3.35)-(3.36) for one symmetric top (:func:`symmetric_rate_function`)."""
    value = symmetric_rate_function()(perp, axial, spin)
    return float(np.ravel(np.asarray(value, dtype=float))[0])


def _closed_form(scene: Any, solved: Solved) -> Any:
    """The closed form of this motion: the solve's own, or one set up for an integrated run (None if none)."""
    from .exact import FreeTopSolution, exact_free_top
    from ...errors import InvalidInputError

    if isinstance(solved.solution, FreeTopSolution):
        return solved.solution
    moments, w0 = _moments_and_omega(scene)
    try:
        return exact_free_top(tuple(moments), w0, strict=scene.strict)
    except InvalidInputError:
        return None


def _polhode(scene: Any, solved: Solved, t: np.ndarray) -> tuple[Any, Any]:
    """(period, estimate) or (None, reason)."""
    moments, w0 = _moments_and_omega(scene)
    sol = _closed_form(scene, solved)
    if sol is not None:
        if sol.kind == "steady":
            return None, "a steady rotation about a principal axis: ω does not move in the body"
        if sol.kind == "separatrix":
            return None, "on the separatrix: the polhode never closes (the period is infinite)"
        P = float(sol.polhode_period)
        rate = float(np.linalg.norm(_omega_dot(moments, w0)))
        back = sol.omega(np.array([0.0, P]))
        return P, float(np.linalg.norm(back[1] - back[0])) / rate + 2 * float(np.spacing(P))
    from ...core.periodic import measure_period

    w = solved.solution.omega(t) if callable(getattr(solved.solution, "omega", None)) else solved.solution.omega
    found = measure_period(t, np.asarray(w))
    return (found.period, found.estimate) if found.period is not None else (None, found.reason)


def _precession(scene: Any, solved: Solved) -> tuple[Any, Any]:
    moments, w = _moments_and_omega(scene)
    equal = [(a, b) for a in range(3) for b in range(a + 1, 3) if moments[a] == moments[b]]
    if len(equal) != 1:
        why = "all three moments are equal: every axis is principal, ω is constant" if len(equal) == 3 else \
            "the moments are distinct: not a symmetric top (see polhode_period)"
        return None, why
    a = ({0, 1, 2} - set(equal[0])).pop()
    perp, Ia, wa = float(moments[equal[0][0]]), float(moments[a]), float(w[a])
    body = _symmetric_rate(perp, Ia, wa)
    # in space: the closed form's precession of the body about L per polhode period (Π of the third kind),
    # measured against |L|/I⊥ — the two must agree for a symmetric top, (3.60)
    L = float(np.linalg.norm(moments * w))
    sol = _closed_form(scene, solved)
    if sol is None or sol.kind != "elliptic" or not math.isfinite(sol.precession_per_period):
        space, spread = L / perp, 4 * _EPS * L / perp
        if sol is None or sol.kind != "steady":
            return {"axis": a + 1, "body": body, "space": None}, "no closed form of this motion to measure φ̇ on"
    else:
        space = float(sol.precession_per_period) / float(sol.polhode_period)
        spread = abs(space - L / perp)
    error = max(4 * _EPS * abs(wa) * (perp + Ia) / perp + 2 * _EPS * abs(body), spread + 2 * _EPS * abs(space))
    return {"axis": a + 1, "body": body, "space": space}, error


def _stability(scene: Any) -> dict:
    from .stability import linearised_eigenvalues

    moments, w = _moments_and_omega(scene)
    spin = float(np.linalg.norm(w))
    out = {}
    for a in range(3):
        others = [moments[b] for b in range(3) if b != a]
        if moments[a] in others:
            out[f"axis{a + 1}"] = {"kind": "neutral"}
            continue
        omega = np.zeros(3)
        omega[a] = spin if spin else 1.0
        root = complex(linearised_eigenvalues(*moments, omega)[1])
        if abs(root.real) >= abs(root.imag):
            out[f"axis{a + 1}"] = {"kind": "unstable", "growth_rate": abs(root.real) if spin else 0.0}
        else:
            out[f"axis{a + 1}"] = {"kind": "stable", "frequency": abs(root.imag) if spin else 0.0}
    return out


def _invariants(scene: Any, solved: Solved, t: np.ndarray) -> dict[str, tuple[float, float]]:
    moments, w0 = _moments_and_omega(scene)
    sol = solved.solution
    w = np.asarray(sol.omega(t) if callable(getattr(sol, "omega", None)) else sol.omega)
    T = 0.5 * np.sum(moments * w * w, axis=1)
    L = np.linalg.norm(moments * w, axis=1)
    T0 = 0.5 * float(np.sum(moments * w0 * w0))
    L0 = float(np.linalg.norm(moments * w0))
    return {"energy": (T0, float(np.max(np.abs(T - T0)))), "angular_momentum": (L0, float(np.max(np.abs(L - L0))))}


def summarize(scene: Any, solved: Solved, t: np.ndarray, names: tuple[str, ...]) -> dict[str, tuple[Any, Any]]:
    """The free top's per-motion quantities ``names`` (module docstring), {name: (value, estimate)}."""
    out: dict[str, tuple[Any, Any]] = {}
    cache: dict[str, Any] = {}

    def polhode() -> tuple[Any, Any]:
        if "polhode" not in cache:
            cache["polhode"] = _polhode(scene, solved, t)
        return cache["polhode"]

    for name in names:
        if name in ("polhode_period", "period"):
            out[name] = polhode()
        elif name == "flip_interval":
            moments, _ = _moments_and_omega(scene)
            P, e = polhode()
            if len(set(moments.tolist())) < 3:
                out[name] = (None, "two moments are equal: there is no intermediate axis to flip about")
            elif P is None:
                out[name] = (None, e)
            else:
                out[name] = (0.5 * P, 0.5 * e)
        elif name == "precession_rate":
            out[name] = _precession(scene, solved)
        elif name == "stability":
            out[name] = (_stability(scene), None)
        elif name in ("energy", "angular_momentum"):
            if "invariants" not in cache:
                cache["invariants"] = _invariants(scene, solved, t)
            out[name] = cache["invariants"][name]
    return out


def period(scene: Any) -> float | None:
    """The polhode period of the scene's motion before solving (s), None where it is not periodic."""
    from .exact import exact_free_top
    from ...errors import InvalidInputError

    moments, w0 = _moments_and_omega(scene)
    try:
        sol = exact_free_top(tuple(moments), w0, strict=scene.strict)
    except InvalidInputError:
        return None
    P = float(sol.polhode_period)
    return P if sol.kind == "elliptic" and math.isfinite(P) else None
