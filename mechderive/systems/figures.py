"""Geometry for the systems' pictures (NumPy only: matplotlib is loaded by :mod:`mechderive.scenes.plot`)."""

from __future__ import annotations

import numpy as np

__all__ = ["sphere_grid"]


def sphere_grid(a: float, b: float, c: float, n: int = 24) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A wireframe of the ellipsoid with semi-axes a, b, c (the unit sphere for 1, 1, 1)."""
    lon, lat = np.meshgrid(np.linspace(0, 2 * np.pi, n + 1), np.linspace(0, np.pi, n // 2 + 1))
    return a * np.sin(lat) * np.cos(lon), b * np.sin(lat) * np.sin(lon), c * np.cos(lat)


__all__ += ["MotionGeometry", "body_geometry", "box_half_lengths", "cone_of"]


class MotionGeometry:
    """What ``mechderive run --animate`` draws of a motion, all in the space frame ẽ (NumPy arrays).

    ``t`` (N,); ``R`` (N, 3, 3) in the chapter's convention e_a = R_ab ẽ_b (row a: the body axis e_a in
    space components); ``shape`` "cone" (``size`` = (height, base radius), apex at the origin, axis e3)
    or "box" (``size`` = half-lengths along e1, e2, e3, centred at the origin); ``omega`` and ``L``
    (N, 3): ω and L in space components; ``traces``: {label: (N, 3) points in space} drawn as the
    motion goes (the heavy top's apex, the tip of ω: the herpolhode); ``polhode``: ω in the body (N, 3)
    and the moments, for the inset of the free body (or None).
    """

    def __init__(self, t, R, shape, size, omega, L, traces=None, polhode=None, moments=None):
        self.t, self.R, self.shape, self.size = t, R, shape, tuple(float(s) for s in size)
        self.omega, self.L = omega, L
        self.traces = dict(traces or {})
        self.polhode, self.moments = polhode, moments


def box_half_lengths(I1: float, I2: float, I3: float) -> tuple[float, float, float]:
    """Half-lengths (a1, a2, a3) of the uniform box of mass 1 with these principal moments about its centre:
    I1 = (a2² + a3²)/3 and cyclically, so a1² = 3 (I2 + I3 - I1)/2; normalised to a largest of 1 (only the
    proportions are drawn).  A moment set no box has (strict = false) gets a thin side instead of none."""
    squares = np.array([I2 + I3 - I1, I3 + I1 - I2, I1 + I2 - I3], dtype=float) * 1.5
    squares = np.maximum(squares, 1e-3 * np.max(np.abs(squares)))
    half = np.sqrt(squares)
    return tuple(half / np.max(half))  # type: ignore[return-value]


def cone_of(I1: float, I3: float) -> tuple[float, float]:
    """(height, base radius) of the uniform solid cone about its apex with these moments, normalised to a
    height of 1: I3 = (3/10) r², I1 = (3/5)(r²/4 + h²) per unit mass; a top no cone matches (I1 < I3/8·…)
    is drawn as a flat cone of radius 1."""
    r2 = 10.0 * I3 / 3.0
    h2 = 5.0 * I1 / 3.0 - r2 / 4.0
    if not h2 > 0:
        return 0.15, 1.0
    h = float(np.sqrt(h2))
    return 1.0, float(np.sqrt(r2)) / h


def body_geometry(t: np.ndarray, columns: dict, moments: tuple[float, float, float], *, shape: str,
                  size: tuple, traces_from_apex: bool = False, with_polhode: bool = False) -> MotionGeometry:
    """A :class:`MotionGeometry` from a run's columns ``R11 … R33`` and ``omega1 … omega3`` (body components)."""
    R = np.stack([np.stack([columns[f"R{a}{b}"] for b in (1, 2, 3)], axis=-1) for a in (1, 2, 3)], axis=-2)
    w_body = np.stack([columns[f"omega{a}"] for a in (1, 2, 3)], axis=-1)
    I = np.asarray(moments, dtype=float)
    # v = v_a e_a = v_a R_ab ẽ_b: the space components are Rᵀ v
    omega = np.einsum("nab,na->nb", R, w_body)
    L = np.einsum("nab,na->nb", R, I * w_body)
    traces = {}
    if traces_from_apex:
        traces["apex"] = R[:, 2, :] * size[0]
    else:  # a free body: ω's tip moves on the invariable plane, ⊥ L (the herpolhode)
        scale = float(np.max(np.linalg.norm(omega, axis=-1))) or 1.0
        traces["tip of ω (herpolhode)"] = omega / scale * 1.1 * max(size)
    return MotionGeometry(t, R, shape, size, omega, L, traces, w_body if with_polhode else None, tuple(I))
