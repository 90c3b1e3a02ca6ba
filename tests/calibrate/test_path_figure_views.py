"""Maps in both parameterizations: tilt angles for a tilt run; (azimuth, co-elevation) and
tilt angles side by side for an (azimuth, co-elevation) run, through the API and the CLI.

The tilts are computed here from the definitions (thesis eq. 8, n = [sinθ cosφ, sinθ sinφ,
cosθ]; gimbal tilts n = R_y(tilt_y) R_x(tilt_x) ẑ, so tilt_x = −asin(n_y) and tilt_y =
atan2(n_x, n_z)), not with echocal's conversion.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import run_main, tiny_setup_file
from echocal.calibrate import calibrate
from echocal.calibrate.objective import FunctionObjective
from echocal.evaluation import CostMap
from echocal.plots.calibration import map_views, path_figure

TRUTH_TILT = np.array([0.3, 0.2])
"""[deg] the lobe's peak, a third of a degree from the pole (co-elevation 0)."""
WIDTH = 0.5
"""[deg] the lobe's Gaussian width in beam angle."""


def tilts(azimuth, coelevation) -> np.ndarray:
    """[deg] (tilt_x, tilt_y) of the beams (azimuth, co-elevation) [deg], shape (..., 2)."""
    phi, theta = np.deg2rad(azimuth), np.deg2rad(coelevation)
    n = np.stack(
        np.broadcast_arrays(
            np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)
        ),
        axis=-1,
    )
    return np.rad2deg(np.stack([-np.arcsin(n[..., 1]), np.arctan2(n[..., 0], n[..., 2])], -1))


def lobe(points: np.ndarray) -> np.ndarray:
    """A Gaussian lobe about TRUTH_TILT of (azimuth, co-elevation) points (k, 2) [deg]."""
    t = tilts(points[:, 0], points[:, 1])
    return np.exp(-np.sum((t - TRUTH_TILT) ** 2, axis=-1) / (2 * WIDTH**2))


@pytest.fixture(scope="module")
def azcoel_run():
    """An (azimuth, co-elevation) run near the pole and its map: a square of ±60° in
    azimuth, ±3° in signed co-elevation about the truth."""
    # the truth in (azimuth, co-elevation): n from the tilts, then φ, θ (θ ≥ 0)
    ax, ay = np.deg2rad(TRUTH_TILT)
    n = np.array([np.sin(ay) * np.cos(ax), -np.sin(ax), np.cos(ay) * np.cos(ax)])
    truth = np.rad2deg([np.arctan2(n[1], n[0]), np.arccos(n[2])])
    objective = FunctionObjective(lobe, optimum=truth, parameterization="azimuth-coelevation")
    x0 = truth + np.array([40.0, 1.0])
    result = calibrate(objective, method="model-based", x0=x0, budget=40, rng=0, settle=None)
    a = np.linspace(truth[0] - 60.0, truth[0] + 60.0, 31)
    b = np.linspace(-3.0, 3.0, 25)
    grid = np.stack(np.meshgrid(a, b, indexing="ij"), axis=-1).reshape(-1, 2)
    cmap = CostMap(a, b, lobe(grid).reshape(31, 25), ("azimuth", "coelevation"))
    return result, cmap, truth


def test_map_views_are_tilt_alone_or_both():
    assert map_views("tilt") == ("tilt",)
    assert map_views("azimuth-coelevation") == ("azimuth-coelevation", "tilt")
    from echocal.errors import UnknownNameError

    with pytest.raises(UnknownNameError, match="parameterization"):
        map_views("polar")


def labels(ax) -> tuple[str, str]:
    return ax.get_xlabel(), ax.get_ylabel()


def test_a_tilt_run_is_drawn_in_tilt_angles_alone():
    objective = FunctionObjective(lobe, parameterization="tilt")
    result = calibrate(objective, method="model-based", x0=(2.0, 1.0), budget=12, rng=0)
    a = b = np.linspace(-4.0, 4.0, 9)
    cmap = CostMap(a, b, np.ones((9, 9)), ("tilt_x", "tilt_y"))
    for fig in (path_figure(cmap, {"m": result}), path_figure(None, {"m": result})):
        assert labels(fig.axes[0]) == ("tilt_x [deg]", "tilt_y [deg]")
        assert not any("azimuth" in label for ax in fig.axes for label in labels(ax))
    assert len(path_figure(cmap, {"m": result}).axes) == 2  # the map and its colour bar


def test_an_azimuth_coelevation_run_is_drawn_in_its_angles_and_in_tilts(azcoel_run):
    result, cmap, truth = azcoel_run
    fig = path_figure(cmap, {"run": result}, x0=result.iterates[0], truth=truth)
    native, tilt, bar = fig.axes
    assert labels(native) == ("azimuth [deg]", "coelevation [deg]")
    assert labels(tilt) == ("tilt_x [deg]", "tilt_y [deg]")
    assert bar.get_ylabel() == "metric / max [dB]"  # one colour bar for both panels
    assert "tilt" in tilt.get_title() and "azimuth" in native.get_title()
    # the path in tilts: the iterates converted (1e-9 deg: two float64 evaluations of
    # the same trigonometry)
    (path,) = [line for line in tilt.lines if line.get_label() == "run"]
    want = tilts(result.iterates[:, 0], result.iterates[:, 1])
    np.testing.assert_allclose(np.c_[path.get_xdata(), path.get_ydata()], want, atol=1e-9)
    (star,) = [line for line in tilt.lines if line.get_label() == "true solution"]
    np.testing.assert_allclose([star.get_xdata()[0], star.get_ydata()[0]], TRUTH_TILT, atol=1e-9)
    # the map on its grid's nodes converted: the same dB values, at the converted nodes
    native_mesh, tilt_mesh = native.collections[0], tilt.collections[0]
    np.testing.assert_allclose(tilt_mesh.get_array(), native_mesh.get_array(), atol=1e-12)
    nodes = tilts(*np.meshgrid(cmap.a, cmap.b, indexing="xy"))
    np.testing.assert_allclose(tilt_mesh.get_coordinates(), nodes, atol=1e-9)
    assert tilt.get_aspect() == 1.0  # a degree of tilt is a degree either way


def test_a_map_with_blank_cells_is_drawn_in_tilts_between_converted_edges(azcoel_run):
    # a lobe-profile map is blank beyond its reach: flat cells between the grid's cell
    # edges converted (matplotlib cannot infer a curved grid's edges, and warns when asked)
    import warnings

    result, cmap, truth = azcoel_run
    values = np.array(cmap.values, dtype=np.float64)
    values[:, :3] = np.nan
    blank = CostMap(cmap.a, cmap.b, values, cmap.names)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = path_figure(blank, {"run": result}, truth=truth)
    tilt_mesh = fig.axes[1].collections[0]
    step_a, step_b = np.diff(cmap.a)[0], np.diff(cmap.b)[0]
    a_edges = np.r_[cmap.a - step_a / 2, cmap.a[-1] + step_a / 2]
    b_edges = np.r_[cmap.b - step_b / 2, cmap.b[-1] + step_b / 2]
    edges = tilts(*np.meshgrid(a_edges, b_edges, indexing="xy"))
    np.testing.assert_allclose(tilt_mesh.get_coordinates(), edges, atol=1e-9)
    # the panel frames the map and the paths (with small margins), not a mesh of guessed
    # cells: every point drawn is inside, and the frame is at most 1.2x their span + 1 deg
    # along one axis (equal aspect widens the other to the panel's shape)
    tilt = fig.axes[1]
    drawn = np.vstack([np.c_[line.get_xdata(), line.get_ydata()] for line in tilt.lines])
    # the drawn cells' corners: co-elevation rows 3 on (rows 0-2 are blank)
    drawn = np.vstack([drawn, tilt_mesh.get_coordinates()[3:].reshape(-1, 2)])
    for limits, values in ((tilt.get_xlim(), drawn[:, 0]), (tilt.get_ylim(), drawn[:, 1])):
        assert limits[0] <= values.min() and values.max() <= limits[1]
    spans = np.ptp([tilt.get_xlim(), tilt.get_ylim()], axis=1)
    assert np.min(spans - 1.2 * np.ptp(drawn, axis=0)) <= 1.0


def test_near_the_pole_the_tilt_panel_shows_the_path_at_its_true_size(azcoel_run):
    # the issue this answers: near the pole a fraction of a degree of beam spans tens of
    # degrees of azimuth; the tilt panel draws the path at its size in beam angle
    result, cmap, truth = azcoel_run
    fig = path_figure(cmap, {"run": result}, truth=truth)
    native, tilt = fig.axes[:2]
    (in_azcoel,) = [line for line in native.lines if line.get_label() == "run"]
    (in_tilts,) = [line for line in tilt.lines if line.get_label() == "run"]
    span_azimuth = np.ptp(in_azcoel.get_xdata())
    shown = np.c_[in_tilts.get_xdata(), in_tilts.get_ydata()]
    beam = tilts(result.iterates[:, 0], result.iterates[:, 1])
    reach = float(np.max(np.hypot(*(beam - TRUTH_TILT).T)))  # [deg] of beam, from the truth
    assert span_azimuth > 20.0 and reach < 2.0  # the test can fail: the views really differ
    assert float(np.max(np.hypot(*(shown - TRUTH_TILT).T))) == pytest.approx(reach, abs=1e-9)


def test_the_tilt_panel_can_be_left_out(azcoel_run):
    result, cmap, truth = azcoel_run
    fig = path_figure(cmap, {"run": result}, truth=truth, tilt_view=False)
    assert len(fig.axes) == 2 and labels(fig.axes[0]) == ("azimuth [deg]", "coelevation [deg]")


def test_the_cli_draws_an_azimuth_coelevation_run_in_both(tmp_path, capsys, monkeypatch):
    import echocal.plots

    figures = {}

    def keep(fig, path, *a, **k):  # keep the figure, draw none (the labels are checked)
        figures[Path(path).name] = fig
        return [Path(path)]

    monkeypatch.setattr(echocal.plots, "save_figure", keep)
    setup = tiny_setup_file(tmp_path)
    args = ["calibrate", "--setup", str(setup), "--x0", "30,4", "--snr", "none"]
    args += ["--parameterization", "azimuth-coelevation", "--out", str(tmp_path / "o"), "--json"]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code in (0, 3), err
    native, tilt = figures["path.png"].axes[:2]
    assert labels(native) == ("azimuth [deg]", "coelevation [deg]")
    assert labels(tilt) == ("tilt_x [deg]", "tilt_y [deg]")


def test_drawing_the_tilt_panel_logs_no_limit_notice(azcoel_run, caplog):
    # the tilt panel widens its set limits to keep a degree a degree (by design):
    # matplotlib's notice of that ("Ignoring fixed x limits ...") reached the demo's screen
    import io
    import logging

    result, cmap, truth = azcoel_run
    fig = path_figure(cmap, {"run": result}, x0=result.iterates[0], truth=truth)
    with caplog.at_level(logging.INFO, logger="matplotlib"):
        fig.savefig(io.BytesIO(), format="png")
    assert not [r for r in caplog.records if "fixed data aspect" in r.getMessage()]
