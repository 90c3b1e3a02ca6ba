"""``echocal scene``: the picture of probe and part, and its errors."""

from __future__ import annotations

import subprocess
import sys

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
    assert len(ax.get_legend().get_texts()) == 2
    assert len(ax.collections) >= 3  # specimen polygons + one ray bundle per pose


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
