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
    result = calibrate(
        objective, method="model-based", x0=(1.5, 0.5), budget=30, rng=0, settle=None
    )
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


def _legend_clear_of(fig, ax) -> bool:
    """The figure's legends (its own and the axes') do not overlap the data area ``ax``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    area = ax.get_window_extent(renderer)
    legends = [*fig.legends, *(a.get_legend() for a in fig.axes if a.get_legend())]
    assert legends, "the figure has no legend"
    return not any(lg.get_window_extent(renderer).overlaps(area) for lg in legends)


def _distinct_without_colour(lines) -> None:
    """Every pair of series differs in line style or marker (not by colour alone), and in
    colour too."""
    keys = [(str(ln.get_linestyle()), str(ln.get_marker())) for ln in lines]
    assert len(set(keys)) == len(keys), keys
    colours = [ln.get_color() for ln in lines]
    assert len(set(colours)) == len(colours), colours


def test_paths_and_convergence_differ_without_colour_and_keep_legends_off_the_data(
    gauss_objective,
):
    from echocal.plots.calibration import convergence_figure

    objective = gauss_objective(bounds=[[-20.0, 20.0], [-20.0, 20.0]])
    methods = ("gradient", "spsa", "nesterov", "quasi-newton", "newton", "momentum")
    runs = {
        m: calibrate(objective, method=m, x0=(1.5, 0.5), budget=40, rng=0, settle=None)
        for m in methods
    }
    a = b = np.linspace(-5.0, 5.0, 21)
    grid = np.stack(np.meshgrid(a, b, indexing="ij"), axis=-1).reshape(-1, 2)
    cmap = CostMap(a=a, b=b, values=gaussian(grid).reshape(21, 21), names=("a", "b"))
    fig = path_figure(cmap, runs, x0=(1.5, 0.5), truth=OPT)
    ax = fig.axes[0]
    _distinct_without_colour([ln for ln in ax.get_lines() if ln.get_label() in runs])
    assert _legend_clear_of(fig, ax)
    values = {m: gaussian(r.iterates) for m, r in runs.items()}
    fig = convergence_figure(runs, values, optimum_value=3.7)
    for ax in fig.axes:
        lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 2]
        _distinct_without_colour(lines)
        assert _legend_clear_of(fig, ax)


def test_iteration_and_measurement_axes_have_whole_number_ticks(gauss_objective):
    # a short run: matplotlib alone would tick 0, 0.5, 1, 1.5, ... iterations
    from echocal.plots.calibration import convergence_figure, measured_convergence_figure

    objective = gauss_objective(bounds=[[-20.0, 20.0], [-20.0, 20.0]])
    result = calibrate(objective, method="gradient", x0=(1.5, 0.5), max_iter=3, rng=0)
    values = gaussian(result.iterates)
    figures = [
        convergence_figure({"gradient": result}, {"gradient": values}),
        measured_convergence_figure(result),
    ]
    for fig in figures:
        for ax in fig.axes:
            ticks = ax.get_xticks()
            low, high = ax.get_xlim()
            shown = ticks[(ticks >= low) & (ticks <= high)]
            assert len(shown) >= 2 and np.all(shown == np.round(shown)), shown
