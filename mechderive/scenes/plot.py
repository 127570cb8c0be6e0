"""Pictures of a scene's result (needs matplotlib: ``pip install 'mechderive[plot]'``).

Each system draws its own picture (:meth:`mechderive.systems.base.System.plot`) from the quantities
it names (its ``plot_quantities``, which ``mechderive run --plot`` solves too); e.g. the heavy top
the path of its apex on the unit sphere (the chapter's figure 44) and θ(t), the free top its
polhode on the inertia ellipsoid (3.46) and ω(t), the falling cat its flip angle.  A system with
no picture of its own gets every column against t.

:func:`plot_scene` draws from sampled quantities (``data["t"]`` and the system's quantity names;
``extra`` may give a ``"title"`` and, where the picture needs the body and there is no scene, its
``"moments"``); :func:`plot_result` draws a :class:`~mechderive.scenes.planner.RunResult`.

The picture is written to a temporary file renamed into place
(:func:`mechderive.scenes.output.atomic_output`): never half a file under ``path``.
matplotlib is imported inside the drawing functions only, and used through its
object interface with the Agg canvas: no pyplot, no change to the caller's
backend or global figure list.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InvalidInputError, ShapeError
from ..systems import registry
from .output import atomic_output, check_output_path

__all__ = ["PLOT_SUFFIXES", "plot_scene", "plot_result", "required_data"]

PLOT_SUFFIXES = (".png", ".pdf", ".svg")

_EXTRA_KEYS = ("moments", "title")
_MISSING_MATPLOTLIB = "plotting needs matplotlib: pip install 'mechderive[plot]'"


@dataclass(frozen=True)
class _Picture:
    """What a system's :meth:`~mechderive.systems.base.System.plot` draws: the times, the columns by
    name, the scene (None for bare data) and the caller's ``extra``."""

    t: np.ndarray
    columns: Mapping[str, np.ndarray]
    scene: Any = None
    extra: Mapping[str, Any] = field(default_factory=dict)


def _import_matplotlib() -> tuple[Any, Any]:
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        import mpl_toolkits.mplot3d  # noqa: F401  (registers the "3d" projection)
    except ImportError as exc:
        raise InvalidInputError(_MISSING_MATPLOTLIB) from exc
    return Figure, FigureCanvasAgg


def _model(system: Any) -> Any:
    if not isinstance(system, str) or system not in registry.names():
        raise InvalidInputError(f"expected a system, one of {', '.join(registry.names())}, got {system!r}")
    return registry.get(system)


def required_data(system: str) -> tuple[str, ...]:
    """The data a picture of ``system`` needs: ``t`` and the system's ``plot_quantities``."""
    return ("t", *_model(system).plot_quantities)


def _check_data(system: str, data: Mapping[str, Any], needed: tuple[str, ...]) -> dict[str, np.ndarray]:
    if not isinstance(data, Mapping):
        raise InvalidInputError(f"expected `data` to be a mapping name -> array, got {type(data).__name__}")
    missing = [k for k in needed if k not in data]
    if missing:
        raise InvalidInputError(f"plot of {system}: expected data {', '.join(needed)}, got no {missing[0]!r}")
    keys = needed if len(needed) > 1 else tuple(data)  # a generic picture draws every column given
    arrays = {k: np.asarray(data[k], dtype=float) for k in keys}
    n = arrays["t"].shape
    for k, a in arrays.items():
        if a.ndim != 1 or a.shape != n:
            raise ShapeError(f"plot of {system}: expected data {k!r} to be 1-D with the shape of t, {n}, "
                             f"got {a.shape}")
    return arrays


def _columns_against_t(fig: Any, picture: _Picture) -> None:
    """The generic picture: every column against t."""
    ax = fig.add_subplot(1, 1, 1)
    for name, column in picture.columns.items():
        if name != "t":
            ax.plot(picture.t, column, label=name)
    ax.set_xlabel("t (s)")
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)


def _draw(model: Any, picture: _Picture, path: Path, title: str, what: str) -> Path:
    Figure, FigureCanvasAgg = _import_matplotlib()
    fig = Figure(figsize=(6.5, 4.8), layout="constrained")
    FigureCanvasAgg(fig)
    if not model.plot(picture, fig):
        _columns_against_t(fig, picture)
    fig.suptitle(title)
    with atomic_output(path, what=what) as tmp:
        fig.savefig(tmp, dpi=110, format=path.suffix.lower()[1:])
    return path


def plot_scene(system: str, data: Mapping[str, Any], path: str | os.PathLike, *,
               extra: Mapping[str, Any] | None = None, what: str = "plot file") -> Path:
    """Draw the result of a ``system`` scene from ``data`` (name -> samples, with ``"t"``) to ``path``.

    ``path`` ends in .png, .pdf or .svg.  ``extra`` may hold ``"title"`` (a string)
    and, for a picture of the body without a scene (the free top's ellipsoid), ``"moments"``
    (I1, I2, I3).  ``what`` names the file in error messages (the command line passes
    ``"--plot"``).  Returns the path.  Raises :class:`~mechderive.errors.InvalidInputError`
    if matplotlib is missing.
    """
    _import_matplotlib()
    model = _model(system)
    path = check_output_path(path, PLOT_SUFFIXES, what=what)
    extra = {} if extra is None else extra
    if not isinstance(extra, Mapping) or any(k not in _EXTRA_KEYS for k in extra):
        raise InvalidInputError(f"expected `extra` to be a mapping with keys among {', '.join(_EXTRA_KEYS)}, "
                                f"got {extra!r}")
    title = extra.get("title", system.replace("_", " "))
    if not isinstance(title, str):
        raise InvalidInputError(f"expected extra['title'] to be a string, got {title!r}")
    d = _check_data(system, data, ("t", *model.plot_quantities))
    return _draw(model, _Picture(d["t"], d, None, extra), path, title, what)


def plot_result(result: Any, path: str | os.PathLike, *, title: str | None = None,
                what: str = "plot file") -> Path:
    """Draw a run's result (a :class:`~mechderive.scenes.planner.RunResult`) to ``path`` with its system's
    picture; ``title`` defaults to the scene's name or its system's."""
    _import_matplotlib()
    scene = result.scene
    path = check_output_path(path, PLOT_SUFFIXES, what=what)
    columns = {k: np.asarray(v, dtype=float) for k, v in result.columns.items()}
    picture = _Picture(np.asarray(result.t, dtype=float), columns, scene, {})
    return _draw(scene.model, picture, path, title if title is not None else (scene.name or scene.system), what)
