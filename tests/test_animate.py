"""``mechderive run --animate`` (issue 14 §4): the film's frames, the geometry drawn (checked against the
kinematics independently: R of (3.54) from the Euler angles, L fixed in space for the free body), the
refusals before solving, and the warning for pictures with too few samples per period."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from PIL import Image

from mechderive.cli import main
from mechderive.errors import InvalidInputError
from mechderive.kinematics.rotations import rotation_matrix
from mechderive.scenes.animate import frame_indices
from mechderive.scenes.builtin import load_builtin, scene_text
from mechderive.scenes.planner import run_scene


def _with_geometry(name: str, samples: int | None = None):
    scene = load_builtin(name)
    extra = tuple(q for q in scene.model.animation_quantities + ("phi", "theta", "psi")
                  if q not in scene.quantities and q in scene.model.quantity_names())
    scene = dataclasses.replace(scene, quantities=scene.quantities + extra,
                                **({"samples": samples} if samples else {}))
    return run_scene(scene)


def test_heavy_top_geometry_is_the_rotation_of_its_euler_angles():
    result = _with_geometry("default", 201)
    g = result.scene.model.motion_geometry(result)
    c = result.columns
    R = rotation_matrix(c["phi"], c["theta"], c["psi"])  # (3.54), pure NumPy: independent of the solver's R
    assert np.max(np.abs(g.R - R)) < 1e-12  # phi, psi grow to ~160 rad: their rounding, a few 1e-14 each
    assert np.max(np.abs(np.einsum("nab,ncb->nac", g.R, g.R) - np.eye(3))) < 1e-13
    assert np.all(np.abs(np.linalg.det(g.R) - 1) < 1e-13)
    assert g.shape == "cone" and "apex" in g.traces
    # the apex trace is e3 (row 3 of R) at the cone's height
    assert np.allclose(g.traces["apex"], R[:, 2, :] * g.size[0], atol=1e-12)


def test_free_body_angular_momentum_is_fixed_in_space():
    result = _with_geometry("free_top_tumbling", 401)
    g = result.scene.model.motion_geometry(result)
    L0 = g.L[0]
    # L = Rᵀ I ω is conserved in space: the closed form to ~1e-15 relative per sample
    assert np.max(np.linalg.norm(g.L - L0, axis=-1)) < 1e-12 * np.linalg.norm(L0)
    # ω's tip moves in the invariable plane ⊥ L: ω·L = 2T is constant
    wL = np.einsum("na,na->n", g.omega, g.L)
    assert np.ptp(wL) < 1e-12 * abs(wL[0])
    assert g.shape == "box" and g.polhode is not None


def test_a_gif_with_its_frames(tmp_path, capsys):
    path = tmp_path / "top.toml"
    path.write_text(scene_text("default").replace("samples = 2001", "samples = 25").replace(
        "samples = 1001", "samples = 25"))
    film = tmp_path / "top.gif"
    assert main(["run", str(path), "--animate", str(film)]) == 0
    out = capsys.readouterr()
    assert f"drew {film}" in out.out
    with Image.open(film) as image:
        assert image.n_frames == len(frame_indices(25)) == 25
    # 25 samples over 10 nutation periods: too few to show the nutation, and said so
    assert "samples per period" in out.err and "too few" in out.err


def test_refusals_before_solving(tmp_path, capsys, monkeypatch):
    from matplotlib import animation

    monkeypatch.setattr(animation.writers, "is_available", lambda name: False)
    assert main(["run", "--animate", str(tmp_path / "x.mp4")]) == 2
    assert "needs ffmpeg on the PATH" in capsys.readouterr().err
    assert main(["run", "falling_cat", "--animate", str(tmp_path / "cat.gif")]) == 2
    assert "has no body to draw" in capsys.readouterr().err
    assert main(["run", "--animate", str(tmp_path / "x.avi")]) == 2
    assert "expected a suffix .gif or .mp4" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_enough_samples_draw_without_warning(tmp_path, capsys):
    assert main(["run", "--plot", str(tmp_path / "top.png")]) == 0  # the default: 2001 samples, 57 per period
    assert "too few" not in capsys.readouterr().err


def test_frame_indices_keep_both_ends():
    idx = frame_indices(1001, 60)
    assert idx[0] == 0 and idx[-1] == 1000 and len(idx) == 60 and np.all(np.diff(idx) > 0)
    with pytest.raises(InvalidInputError):
        from mechderive.scenes.animate import check_animation_target

        check_animation_target("/nonexistent-dir/x.gif", load_builtin("default").model)
