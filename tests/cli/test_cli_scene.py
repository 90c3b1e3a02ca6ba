"""``echocal scene``: the picture of probe and part, and its errors."""

from __future__ import annotations

import subprocess
import sys

import pytest
from typer.testing import CliRunner

from echocal.cli import app
from echocal.geometry import Pose
from echocal.plots.scene import scene_figure
from echocal.setups import load_setup

runner = CliRunner()


def test_scene_writes_an_image(tmp_path):
    out = tmp_path / "scene.png"
    result = runner.invoke(
        app, ["scene", "--pose", "10,0,22,165,6", "--pose", "0,0,20", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob("*.partial*"))


def test_scene_figure_draws_every_pose_and_the_specimen():
    setup = load_setup("thesis")
    fig = scene_figure(
        setup.specimen, setup.transducer, [Pose(0.01, 0, 0.022, 165, 6), Pose(0, 0, 0.02)]
    )
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(labels) == 4  # two poses, the beam axis and the surface normal
    assert "beam axis" in labels and "surface normal at the beam's hit" in labels
    assert len(ax.collections) >= 3  # specimen polygons + one ray bundle per pose


def test_scene_draws_the_beam_axis_to_the_part_and_the_normal_there():
    import numpy as np

    from echocal.specimen import FinitePlane, Specimen

    # a flat plane at z = 0: the beam axis of a probe at 20 mm tilted 10° meets it at
    # 20 mm · tan 10° from below the probe, and the normal there is +z, 20/cos 10° long
    setup = load_setup("thesis")
    plane = Specimen([FinitePlane(center=(0, 0, 0), width=0.2, height=0.2)])
    pose = Pose(0.0, 0.0, 0.02, 0.0, 10.0)
    ax = scene_figure(plane, setup.transducer, [pose]).axes[0]
    axis = next(ln for ln in ax.get_lines() if ln.get_label() == "beam axis")
    xs, ys, zs = axis.get_data_3d()
    hit = np.array([xs[1], ys[1], zs[1]])
    np.testing.assert_allclose(np.hypot(hit[0], hit[1]), 20 * np.tan(np.radians(10)), rtol=1e-9)
    assert hit[2] == pytest.approx(0.0, abs=1e-9)
    quiver = [c for c in ax.collections if type(c).__name__ == "Line3DCollection"][-1]
    shaft = np.asarray(quiver._segments3d)[0]
    shaft = shaft[np.argsort(shaft[:, 2])]  # foot on the part, then the tip
    np.testing.assert_allclose(shaft[0], hit, atol=1e-9)
    np.testing.assert_allclose(
        shaft[1] - shaft[0], [0, 0, 20 / np.cos(np.radians(10))], rtol=1e-9, atol=1e-9
    )


def test_bad_pose_is_a_one_line_error_not_a_traceback():
    result = subprocess.run(
        [sys.executable, "-m", "echocal.cli", "scene", "--pose", "0,0,nan"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert "--pose z must be" in result.stderr
    assert "Traceback" not in result.stderr


def test_pose_outside_the_positioner_limits_is_drawn_with_a_warning(tmp_path):
    # 20 mm *below* the thesis block (limits z ∈ [5, 100] mm): a legal picture, but flagged
    out = tmp_path / "below.png"
    result = runner.invoke(app, ["scene", "--pose", "0,0,-20", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "out of the setup's positioner limits" in result.output
    assert "z = -20 mm outside [5, 100] mm" in result.output
    assert out.exists()


def test_error_text_in_brackets_is_printed_verbatim():
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "echocal.cli",
            "scene",
            "--pose",
            "0,0,20",
            "--setup",
            "no-[bold]such",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert "no-[bold]such" in result.stderr


def test_scene_draws_a_wave_model_setup(tmp_path):
    # the default setups use the wave model: its rays are drawn as its ray stage casts them
    out = tmp_path / "wave.png"
    result = runner.invoke(
        app, ["scene", "--setup", "immersion-5mhz", "--pose", "0,0,50,20,4", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert out.is_file() and out.stat().st_size > 0
