"""Pictures that move: ``mechderive run SCENE --animate top.gif|top.mp4``.

The system gives the geometry of its motion (:meth:`mechderive.systems.base.System.motion_geometry`:
the body's orientation R(t), its shape sized from its moments — a cone about the pivot for the heavy
symmetric top, a box with the body's principal moments otherwise — ω and L in space, and the traces:
the heavy top's apex path, the tip of ω, i.e. the herpolhode); this module draws it with
matplotlib's animation writers: Pillow for ``.gif`` (matplotlib depends on Pillow), ffmpeg for
``.mp4`` when it is on the PATH (else a clear error before anything is solved).  The free body gets a
second panel: the polhode, ω in the body, on its inertia ellipsoid (3.46) with equal axis scales.

At most :data:`MAX_FRAMES` frames are drawn (the samples are thinned evenly, both ends kept) at
:data:`FPS` frames per second, so a long run gives a short film; the file is written beside its
target and renamed into place (:func:`mechderive.scenes.output.atomic_output`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from .output import atomic_output, check_output_path

__all__ = ["ANIMATION_SUFFIXES", "MAX_FRAMES", "FPS", "check_animation_target", "animate_result", "frame_indices"]

ANIMATION_SUFFIXES = (".gif", ".mp4")
MAX_FRAMES = 60
FPS = 15


def check_animation_target(path: str | os.PathLike, model: Any) -> Path:
    """Refuse before solving what could not be drawn: a bad path or suffix, no matplotlib, no ffmpeg for
    ``.mp4``, a system without a body to draw."""
    path = check_output_path(path, ANIMATION_SUFFIXES, what="--animate")
    try:
        from matplotlib import animation
    except ImportError:
        raise InvalidInputError("--animate needs matplotlib: pip install 'mechderive[plot]'") from None
    if path.suffix.lower() == ".mp4" and not animation.writers.is_available("ffmpeg"):
        raise InvalidInputError(f"--animate {path.name}: an .mp4 needs ffmpeg on the PATH (not found); "
                                "install ffmpeg, or ask for a .gif (drawn with Pillow)")
    if type(model).motion_geometry is _base_geometry():
        raise InvalidInputError(f"--animate: system {model.name!r} has no body to draw (it gives no motion "
                                "geometry); --plot draws its quantities")
    return path


def _base_geometry() -> Any:
    from ..systems.base import System

    return System.motion_geometry


def frame_indices(n: int, frames: int = MAX_FRAMES) -> np.ndarray:
    """At most ``frames`` sample indices out of ``n``, evenly spread, the first and the last included."""
    return np.unique(np.round(np.linspace(0, n - 1, min(n, frames))).astype(int))


def _box_edges(half: tuple) -> np.ndarray:
    a = np.array(half)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * a
    pairs = [(i, j) for i in range(8) for j in range(i + 1, 8) if np.sum(corners[i] != corners[j]) == 1]
    return np.array([[corners[i], corners[j]] for i, j in pairs])


def _cone_edges(size: tuple, n: int = 16) -> np.ndarray:
    h, r = size
    ring = [(r * h * math.cos(2 * math.pi * k / n), r * h * math.sin(2 * math.pi * k / n), h) for k in range(n)]
    lines = [[(0.0, 0.0, 0.0), p] for p in ring[::2]] + [[ring[k], ring[(k + 1) % n]] for k in range(n)]
    return np.array(lines)


def animate_result(result: Any, path: str | os.PathLike, *, title: str | None = None,
                   frames: int = MAX_FRAMES) -> Path:
    """Draw ``result`` (a :class:`~mechderive.scenes.planner.RunResult`) as a film to ``path`` (.gif or .mp4)."""
    model = result.scene.model
    path = check_animation_target(path, model)
    geometry = model.motion_geometry(result)
    from matplotlib import animation
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    g = geometry
    index = frame_indices(len(g.t), frames)
    body_lines = _cone_edges(g.size) if g.shape == "cone" else _box_edges(g.size)  # body frame
    reach = 1.25 * max(max(g.size), 1.0)
    panels = 2 if g.polhode is not None else 1
    fig = Figure(figsize=(5.2 * panels, 5.0), dpi=80)  # a fixed layout: a constrained one is recomputed every frame
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.0, top=0.92, wspace=0.0)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, panels, 1, projection="3d")
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-reach, reach)
    ax.set_zlim(-reach, reach)
    ax.set_box_aspect((1, 1, 1))
    # no panes, grid or ticks: they are most of a 3D frame's drawing time, and the axes say enough
    ax.set_axis_off()
    for a, c in enumerate(("x̃", "ỹ", "z̃")):
        end = np.eye(3)[a] * reach
        ax.plot([0, end[0]], [0, end[1]], [0, end[2]], color="0.8", linewidth=0.6)
        ax.text(*(end * 1.05), c, color="0.5", fontsize="small")
    body = [ax.plot([], [], [], color="0.35", linewidth=0.9)[0] for _ in body_lines]
    axes_lines = [ax.plot([], [], [], color=c, linewidth=1.6, label=f"e{a + 1}")[0]
                  for a, c in enumerate(("C3", "C2", "C0"))]
    w_scale = reach * 0.9 / (float(np.max(np.linalg.norm(g.omega, axis=-1))) or 1.0)
    L_scale = reach * 0.9 / (float(np.max(np.linalg.norm(g.L, axis=-1))) or 1.0)
    omega_line = ax.plot([], [], [], color="C1", linewidth=2.0, label="ω")[0]
    L_line = ax.plot([], [], [], color="C4", linewidth=2.0, label="L")[0]
    traces = {name: ax.plot([], [], [], linewidth=0.9, alpha=0.8, label=name)[0] for name in g.traces}
    ax.legend(loc="upper left", fontsize="x-small")
    stamp = ax.text2D(0.98, 0.02, "", transform=ax.transAxes, ha="right", fontsize="small")
    if g.polhode is not None:
        from ..systems.figures import sphere_grid

        inset = fig.add_subplot(1, 2, 2, projection="3d")
        w = g.polhode
        two_t = float(np.mean(np.sum(np.asarray(g.moments) * w * w, axis=-1)))
        semi = [math.sqrt(two_t / m) for m in g.moments] if two_t > 0 else [1.0, 1.0, 1.0]
        inset.plot_wireframe(*sphere_grid(*semi), color="0.6", linewidth=0.3, alpha=0.4)
        inset.set_box_aspect(semi)  # equal scales: the ellipsoid's axes in their true proportions
        inset.plot(w[:, 0], w[:, 1], w[:, 2], color="C0", linewidth=0.6, alpha=0.5)
        marker = inset.plot([], [], [], "o", color="C1")[0]
        inset.set_title("polhode: ω in the body (ω1, ω2, ω3 to scale)", fontsize="small")
        inset.set_axis_off()
    if title:
        fig.suptitle(title)

    def draw(k: int) -> list:
        i = index[k]
        R = g.R[i]
        # a body point p (body components) is at Rᵀ p in space (e_a = R_ab ẽ_b)
        for line, (p, q) in zip(body, body_lines):
            a, b = R.T @ p, R.T @ q
            line.set_data_3d([a[0], b[0]], [a[1], b[1]], [a[2], b[2]])
        for a, line in enumerate(axes_lines):
            tip = R[a] * reach * 0.8
            line.set_data_3d([0, tip[0]], [0, tip[1]], [0, tip[2]])
        for line, v, s in ((omega_line, g.omega[i], w_scale), (L_line, g.L[i], L_scale)):
            line.set_data_3d([0, v[0] * s], [0, v[1] * s], [0, v[2] * s])
        for name, line in traces.items():
            pts = g.traces[name][: i + 1]
            line.set_data_3d(pts[:, 0], pts[:, 1], pts[:, 2])
        if g.polhode is not None:
            marker.set_data_3d([g.polhode[i, 0]], [g.polhode[i, 1]], [g.polhode[i, 2]])
        stamp.set_text(f"t = {g.t[i]:.3g} s")
        return []

    suffix = path.suffix.lower()
    with atomic_output(path, what="--animate") as tmp:
        if suffix == ".gif":
            # each frame drawn once, straight into Pillow (matplotlib's writer draws every frame twice)
            from PIL import Image

            canvas = fig.canvas
            images = []
            for k in range(len(index)):
                draw(k)
                canvas.draw()
                images.append(Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba(), "raw",
                                               "RGBA", 0, 1).convert("RGB").quantize(colors=64))
            images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                           duration=round(1000 / FPS), loop=0)
        else:
            film = animation.FuncAnimation(fig, draw, frames=len(index), blit=False)
            target = Path(str(tmp) + suffix)  # ffmpeg picks its container from the name
            film.save(str(target), writer=animation.FFMpegWriter(fps=FPS), dpi=fig.dpi)
            os.replace(target, tmp)
    return path
