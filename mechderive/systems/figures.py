"""Geometry for the systems' pictures (NumPy only: matplotlib is loaded by :mod:`mechderive.scenes.plot`)."""

from __future__ import annotations

import numpy as np

__all__ = ["sphere_grid"]


def sphere_grid(a: float, b: float, c: float, n: int = 24) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A wireframe of the ellipsoid with semi-axes a, b, c (the unit sphere for 1, 1, 1)."""
    lon, lat = np.meshgrid(np.linspace(0, 2 * np.pi, n + 1), np.linspace(0, np.pi, n // 2 + 1))
    return a * np.sin(lat) * np.cos(lon), b * np.sin(lat) * np.sin(lon), c * np.cos(lat)
