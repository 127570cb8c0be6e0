"""Pictures of a scene's result (needs matplotlib: ``pip install 'mechderive[plot]'``).

:func:`plot_scene` draws, from sampled quantities (``data["t"]`` and the names of
:data:`mechderive.scenes.schema.QUANTITIES`):

- ``heavy_top``: left, the path of the apex e3 on the unit sphere (3-D, over a faint
  wireframe sphere; the chapter's figure 44), from ``apex_x apex_y apex_z``; right,
  θ(t) from ``theta``;
- ``free_top``: left, the polhode (3.4.4): ω(t) on the inertia ellipsoid
  I1 ω1² + I2 ω2² + I3 ω3² = 2T (3.46), drawn as a wireframe with semi-axes
  √(2T / I_a), T the mean over the samples (constant for the exact motion), from
  ``omega1 omega2 omega3`` and ``extra={"moments": (I1, I2, I3)}``; right, ω1, ω2,
  ω3 against t;
- ``falling_cat``: the flip angle against t, from ``flip_angle``.

The picture is written to a temporary file renamed into place
(:func:`mechderive.scenes.output.atomic_output`): never half a file under ``path``.
matplotlib is imported inside :func:`plot_scene` only, and used through its
object interface with the Agg canvas: no pyplot, no change to the caller's
backend or global figure list.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InvalidInputError, ShapeError
from .output import atomic_output, check_output_path

__all__ = ["PLOT_SUFFIXES", "REQUIRED_DATA", "plot_scene"]

PLOT_SUFFIXES = (".png", ".pdf", ".svg")

#: The data each kind of plot needs.
REQUIRED_DATA: dict[str, tuple[str, ...]] = {
    "heavy_top": ("t", "theta", "apex_x", "apex_y", "apex_z"),
    "free_top": ("t", "omega1", "omega2", "omega3"),
    "falling_cat": ("t", "flip_angle"),
}
_EXTRA_KEYS = ("moments", "title")
_MISSING_MATPLOTLIB = "plotting needs matplotlib: pip install 'mechderive[plot]'"


def _import_matplotlib() -> tuple[Any, Any]:
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        import mpl_toolkits.mplot3d  # noqa: F401  (registers the "3d" projection)
    except ImportError as exc:
        raise InvalidInputError(_MISSING_MATPLOTLIB) from exc
    return Figure, FigureCanvasAgg


def _check_data(system: str, data: Mapping[str, Any]) -> dict[str, np.ndarray]:
    if not isinstance(data, Mapping):
        raise InvalidInputError(f"expected `data` to be a mapping name -> array, got {type(data).__name__}")
    needed = REQUIRED_DATA[system]
    missing = [k for k in needed if k not in data]
    if missing:
        raise InvalidInputError(f"plot of {system}: expected data {', '.join(needed)}, got no {missing[0]!r}")
    arrays = {k: np.asarray(data[k], dtype=float) for k in needed}
    n = arrays["t"].shape
    for k, a in arrays.items():
        if a.ndim != 1 or a.shape != n:
            raise ShapeError(f"plot of {system}: expected data {k!r} to be 1-D with the shape of t, {n}, "
                             f"got {a.shape}")
    return arrays


def _check_moments(extra: Mapping[str, Any]) -> tuple[float, float, float]:
    moments = extra.get("moments")
    try:
        values = tuple(float(m) for m in moments)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        values = ()
    if len(values) != 3 or not all(math.isfinite(m) and m > 0 for m in values):
        raise InvalidInputError(f"plot of free_top: expected extra['moments'] = (I1, I2, I3), three numbers > 0, "
                                f"got {moments!r}")
    return values  # type: ignore[return-value]


def _sphere_grid(a: float, b: float, c: float, n: int = 24) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lon, lat = np.meshgrid(np.linspace(0, 2 * np.pi, n + 1), np.linspace(0, np.pi, n // 2 + 1))
    return a * np.sin(lat) * np.cos(lon), b * np.sin(lat) * np.sin(lon), c * np.cos(lat)


def _heavy_top(fig: Any, d: dict[str, np.ndarray]) -> None:
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.plot_wireframe(*_sphere_grid(1.0, 1.0, 1.0), color="0.55", linewidth=0.35, alpha=0.45)
    ax.plot(d["apex_x"], d["apex_y"], d["apex_z"], color="C0", linewidth=1.0)
    ax.scatter([d["apex_x"][0]], [d["apex_y"][0]], [d["apex_z"][0]], color="C3", s=12, label="t = 0")
    ax.set_box_aspect((1, 1, 1))
    ax.locator_params(nbins=5)
    ax.set_xlabel("x (unit sphere)")
    ax.set_ylabel("y (unit sphere)")
    ax.set_zlabel("z, up (unit sphere)")
    ax.set_title("apex e3 on the unit sphere")
    ax.legend(loc="upper left", fontsize="small")
    right = fig.add_subplot(1, 2, 2)
    right.plot(d["t"], d["theta"], color="C0")
    right.set_xlabel("t (s)")
    right.set_ylabel("θ (rad)")
    right.set_title("nutation θ(t)")
    right.grid(True, alpha=0.3)


def _free_top(fig: Any, d: dict[str, np.ndarray], moments: tuple[float, float, float]) -> None:
    w = np.stack([d["omega1"], d["omega2"], d["omega3"]])
    two_t = float(np.nanmean(np.einsum("a,a...->...", np.array(moments), w * w)))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    if two_t > 0:
        axes = [math.sqrt(two_t / m) for m in moments]
        ax.plot_wireframe(*_sphere_grid(*axes), color="0.55", linewidth=0.35, alpha=0.45)
        ax.set_box_aspect(axes)
    ax.locator_params(nbins=5)
    ax.plot(w[0], w[1], w[2], color="C0", linewidth=1.2)
    ax.set_xlabel("ω1 (rad/s)")
    ax.set_ylabel("ω2 (rad/s)")
    ax.set_zlabel("ω3 (rad/s)")
    ax.set_title("polhode on the inertia ellipsoid")
    right = fig.add_subplot(1, 2, 2)
    for a in range(3):
        right.plot(d["t"], w[a], label=f"ω{a + 1}")
    right.set_xlabel("t (s)")
    right.set_ylabel("ω (rad/s, body frame)")
    right.set_title("angular velocity")
    right.legend(fontsize="small")
    right.grid(True, alpha=0.3)


def _falling_cat(fig: Any, d: dict[str, np.ndarray]) -> None:
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(d["t"], d["flip_angle"], color="C0")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("flip angle (rad)")
    ax.set_title("rotation of the body at zero angular momentum")
    ax.grid(True, alpha=0.3)


def plot_scene(system: str, data: Mapping[str, Any], path: str | os.PathLike, *,
               extra: Mapping[str, Any] | None = None, what: str = "plot file") -> Path:
    """Draw the result of a ``system`` scene from ``data`` (name -> samples, with ``"t"``) to ``path``.

    ``path`` ends in .png, .pdf or .svg.  ``extra`` may hold ``"title"`` (a string)
    and, for a free top, must hold ``"moments"`` (I1, I2, I3).  ``what`` names the
    file in error messages (the command line passes ``"--plot"``).  Returns the path.
    Raises :class:`~mechderive.errors.InvalidInputError` if matplotlib is missing.
    """
    Figure, FigureCanvasAgg = _import_matplotlib()
    if system not in REQUIRED_DATA:
        raise InvalidInputError(f"expected a system, one of {', '.join(REQUIRED_DATA)}, got {system!r}")
    path = check_output_path(path, PLOT_SUFFIXES, what=what)
    extra = {} if extra is None else extra
    if not isinstance(extra, Mapping) or any(k not in _EXTRA_KEYS for k in extra):
        raise InvalidInputError(f"expected `extra` to be a mapping with keys among {', '.join(_EXTRA_KEYS)}, "
                                f"got {extra!r}")
    title = extra.get("title", system.replace("_", " "))
    if not isinstance(title, str):
        raise InvalidInputError(f"expected extra['title'] to be a string, got {title!r}")
    d = _check_data(system, data)
    fig = Figure(figsize=(6.5, 4.8) if system == "falling_cat" else (11.5, 5.0), layout="constrained")
    FigureCanvasAgg(fig)
    if system == "heavy_top":
        _heavy_top(fig, d)
    elif system == "free_top":
        _free_top(fig, d, _check_moments(extra))
    else:
        _falling_cat(fig, d)
    fig.suptitle(title)
    with atomic_output(path, what=what) as tmp:
        fig.savefig(tmp, dpi=110, format=path.suffix.lower()[1:])
    return path
