"""The scan's 3-D view stays inside its axes, draws visible normals and marks missing points."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from echocal.plots.surface import surface_3d_figure
from echocal.scanning import ScanGrid, scan_surface
from echocal.setups import load_setup
from echocal.specimen import builtin_specimen

MM = 1e-3


@pytest.fixture(scope="module")
def rod_end():
    # the rod ends at y = 50 mm: the last row of points is missing
    specimen = builtin_specimen("cylinder")
    setup = dataclasses.replace(load_setup("scan-5mhz", seed=2), specimen=specimen, rng=2)
    grid = ScanGrid.regular(x=(-2 * MM, 2 * MM, 2 * MM), y=(40 * MM, 70 * MM, 15 * MM), z=25 * MM)
    scan = scan_surface(setup, grid, rng=2, progress=False)
    assert int(np.sum(~scan.found)) >= 1
    return scan, specimen


def test_the_specimen_is_drawn_inside_the_axes_box(rod_end):
    scan, specimen = rod_end
    ax = surface_3d_figure(scan, specimen).axes[0]
    (x0, x1), (y0, y1), (z0, z1) = ax.get_xlim(), ax.get_ylim(), ax.get_zlim()
    # the box is the raster, half a step beyond its outer points, in mm
    assert (x0, x1) == pytest.approx((-3.0, 3.0)) and (y0, y1) == pytest.approx((32.5, 77.5))
    polys = [c for c in ax.collections if isinstance(c, Poly3DCollection)]
    assert polys
    verts = np.asarray(polys[0]._faces).reshape(-1, 3)  # the 3-D quads [mm]
    eps = 1e-9
    assert np.all((verts[:, 0] >= x0 - eps) & (verts[:, 0] <= x1 + eps))
    assert np.all((verts[:, 1] >= y0 - eps) & (verts[:, 1] <= y1 + eps))
    assert np.all((verts[:, 2] >= z0 - eps) & (verts[:, 2] <= z1 + eps))
    # equal scale: the box's proportions are the data ranges'
    aspect = np.asarray(ax.get_box_aspect())
    ranges = np.array([x1 - x0, y1 - y0, z1 - z0])
    np.testing.assert_allclose(aspect / aspect[0], ranges / ranges[0], rtol=1e-6)


def test_normals_are_visible_and_missing_points_marked(rod_end):
    scan, specimen = rod_end
    ax = surface_3d_figure(scan, specimen).axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert f"missing ({int(np.sum(~scan.found))}, at the probe)" in labels
    assert "measured normals" in labels
    # each normal arrow is about a grid step long (2 mm here): visible at this scale
    quiver = [c for c in ax.collections if type(c).__name__ == "Line3DCollection"][-1]
    shafts = np.asarray(quiver._segments3d)[: int(np.sum(scan.found))]  # 3-D segments
    lengths = np.linalg.norm(shafts[:, 1] - shafts[:, 0], axis=-1)
    assert np.all(lengths > 1.0)


def test_missing_cells_are_hatched_not_white_and_the_key_is_off_the_map(rod_end):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from echocal.plots.surface import error_maps_figure

    scan, _ = rod_end
    fig = error_maps_figure(scan)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    for ax in fig.axes[:2]:  # the two maps (their colour bars come after them)
        # white is zero error on the diverging map: a missing cell shows grey hatching
        hatched = [p for p in ax.patches if p.get_hatch()]
        assert hatched and hatched[0].get_zorder() < ax.images[0].get_zorder()
        legend = ax.get_legend()
        assert [t.get_text() for t in legend.get_texts()] == ["missing"]
        assert not legend.get_window_extent(renderer).overlaps(ax.get_window_extent(renderer))


def test_the_report_says_in_words_why_points_are_missing(rod_end, tmp_path):
    from echocal.experiments._report_results import scan_section

    scan, _ = rod_end
    folder = tmp_path / "scan"
    folder.mkdir()
    scan.save(folder / "scan.nc")
    page, _ = scan_section(folder, "s0")
    row = page.split("why points are missing</td><td>")[1].split("</td>")[0]
    counts = scan.summary["missing_by_status"]
    assert counts and all(f"{status} ({n} points): " in row for status, n in counts.items())
    assert "{" not in row and "&quot;" not in row  # not a JSON dump


def test_a_single_row_map_keeps_its_title_clear_of_the_colour_bar(tmp_path):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from cli_helpers import tiny_setup_file
    from echocal.plots.surface import height_map_figure

    setup = load_setup(tiny_setup_file(tmp_path), seed=0)
    grid = ScanGrid.regular(x=(-2 * MM, 2 * MM, 2 * MM), y=(0.0, 0.0, 1 * MM), z=16 * MM)
    scan = scan_surface(setup, grid, rng=0, progress=False)
    fig = height_map_figure(scan)
    fig.axes[0].set_title("a title much wider than the thin strip of one row of points")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    title = fig.axes[0].title.get_window_extent(renderer)
    bar = fig.axes[1].get_window_extent(renderer)  # the colour bar, below the strip
    assert not title.overlaps(bar)
    assert bar.y1 < fig.axes[0].get_window_extent(renderer).y0
