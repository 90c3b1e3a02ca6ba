"""save_figure lays a constrained figure out once, keeps every decoration inside the file,
and leaves the figure as it found it."""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from PIL import Image

from echocal.plots import save_figure


def _busy_figure() -> Figure:
    """Two panels, a colorbar, a legend below both and one beside a panel: every
    decoration a constrained layout has to make room for."""
    fig = Figure(figsize=(6.0, 3.0), layout="constrained")
    left, right = fig.subplots(1, 2)
    mesh = left.pcolormesh(np.arange(12.0).reshape(3, 4))
    fig.colorbar(mesh, ax=left, label="a long colour-bar label [dB]")
    right.plot([0, 1], [0, 1], label="a line with a long legend entry")
    right.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.legend(["a figure legend under both panels"], loc="outside lower center")
    fig.suptitle("a title")
    return fig


def test_a_constrained_figure_is_written_at_its_size_with_every_decoration_inside(tmp_path):
    fig = _busy_figure()
    engine = fig.get_layout_engine()
    (png,) = save_figure(fig, tmp_path / "busy.png", formats=("png",), dpi=100)
    # written at the figure's own size (6 x 3 in at 100 dpi: 600 x 300 px), not cropped
    assert Image.open(png).size == (600, 300)
    assert fig.get_layout_engine() is engine  # the engine is back for the caller
    assert isinstance(engine, ConstrainedLayoutEngine)
    renderer = FigureCanvasAgg(fig).get_renderer()  # the positions the file was drawn at
    inside = fig.bbox.padded(0.5)  # half a pixel of rounding
    parts = [*fig.axes, *fig.legends, fig.axes[1].get_legend()]
    for part in parts:
        box = part.get_tightbbox(renderer)
        assert inside.x0 <= box.x0 and box.x1 <= inside.x1, part
        assert inside.y0 <= box.y0 and box.y1 <= inside.y1, part
    # the panels were moved off the decorations: the left panel's tick labels and the
    # legend beside the right panel do not overlap any other axes
    left, _, bar = fig.axes
    assert left.get_tightbbox(renderer).x1 <= bar.get_window_extent(renderer).x0 + 0.5
    assert fig.axes[1].get_legend().get_window_extent(renderer).x1 <= inside.x1


def test_a_figure_without_a_layout_engine_is_cropped_to_its_contents(tmp_path):
    fig = Figure(figsize=(6.0, 3.0))
    fig.add_subplot().plot([0, 1], [0, 1])
    fig.subplots_adjust(left=0.3, right=0.7)  # wide empty margins: the crop removes them
    (png,) = save_figure(fig, tmp_path / "plain.png", formats=("png",), dpi=100)
    width, _ = Image.open(png).size
    assert width < 600 and fig.get_layout_engine() is None
