"""path_figure: the dB view of a narrow lobe and the measured-pose overlay."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import OPT, gaussian
from echocal.calibrate import calibrate
from echocal.errors import EchocalValueError
from echocal.evaluation import CostMap
from echocal.plots.calibration import path_figure


@pytest.fixture
def run_and_map(gauss_objective):
    objective = gauss_objective(bounds=[[-20.0, 20.0], [-20.0, 20.0]])
    result = calibrate(objective, method="model-based", x0=(1.5, 0.5), budget=30, rng=0)
    a = b = np.linspace(-10.0, 10.0, 41)
    grid = np.stack(np.meshgrid(a, b, indexing="ij"), axis=-1).reshape(-1, 2)
    values = gaussian(grid, width=0.3).reshape(41, 41)  # a lobe far narrower than the map
    return result, CostMap(a=a, b=b, values=values, names=("tilt_x", "tilt_y"))


def test_db_map_is_relative_to_the_peak_and_clipped_at_the_floor(run_and_map):
    result, cmap = run_and_map
    fig = path_figure(cmap, {"model-based": result}, truth=OPT, db_floor=-40.0)
    shown = fig.axes[0].collections[0].get_array()
    # 0 dB at the sampled maximum, nothing below the floor; far from a 0.3° Gaussian the
    # linear map is ~0 everywhere, the dB map sits exactly at the floor there
    assert np.nanmax(shown) == pytest.approx(0.0, abs=1e-12)
    assert np.nanmin(shown) == pytest.approx(-40.0, abs=1e-9)
    assert fig.axes[1].get_ylabel() == "metric / max [dB]"


def test_every_path_map_is_in_db_by_default(run_and_map):
    # the scenarios and the demo call path_figure without db_floor: the same dB map
    result, cmap = run_and_map
    fig = path_figure(cmap, {"model-based": result}, truth=OPT)
    shown = np.asarray(fig.axes[0].collections[0].get_array())
    peak = float(np.max(cmap.values))
    want = 10.0 * np.log10(np.clip(cmap.values.T / peak, 1e-4, None))  # -40 dB floor
    np.testing.assert_allclose(shown.reshape(want.shape), want, atol=1e-9)
    assert fig.axes[1].get_ylabel() == "metric / max [dB]"


def test_relative_db_keeps_uncovered_poses_blank():
    from echocal.plots.calibration import relative_db

    out = relative_db([[np.nan, 0.0], [1.0, 0.1]], -30.0)
    np.testing.assert_allclose(out, [[np.nan, -30.0], [0.0, -10.0]], atol=1e-12)
    np.testing.assert_allclose(relative_db([0.0, np.nan]), [-40.0, np.nan])


def test_measured_poses_are_drawn_when_asked(run_and_map):
    result, cmap = run_and_map
    plain = path_figure(cmap, {"m": result})
    marked = path_figure(cmap, {"m": result}, show_measurements=True)
    dots = [ln for ln in marked.axes[0].lines if len(ln.get_xdata()) == len(result.points)]
    assert dots and np.allclose(dots[0].get_xdata(), result.points[:, 0])
    assert len(marked.axes[0].lines) == len(plain.axes[0].lines) + 2  # the dots and their key


def test_db_floor_must_be_negative(run_and_map):
    result, cmap = run_and_map
    with pytest.raises(EchocalValueError, match="db_floor"):
        path_figure(cmap, {"m": result}, db_floor=3.0)
