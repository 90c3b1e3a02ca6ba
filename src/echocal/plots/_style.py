"""How figures tell series apart: colour, line style and marker together (private).

The colours are Okabe and Ito's palette, chosen to stay distinct under the common
colour-vision deficiencies (no red beside green); each series also gets its own pair of
line style and marker, so a print in grey or a reader who sees no colour at all still
tells the lines apart.
"""

from __future__ import annotations

from typing import Any

__all__ = ["COLORS", "FEW_TICKS", "LINE_STYLES", "MARKERS", "few_ticks", "series_style"]

COLORS = (
    "#0072B2",  # blue
    "#E69F00",  # orange
    "#009E73",  # bluish green
    "#D55E00",  # vermillion
    "#CC79A7",  # reddish purple
    "#56B4E9",  # sky blue
    "#000000",  # black
    "#B59B00",  # dark yellow (Okabe-Ito's yellow, darkened to show on white)
)
"""Okabe–Ito colours, in the order series take them."""

LINE_STYLES = ("-", "--", ":", "-.")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
"""Line styles and markers: series ``k`` takes style ``k % 4`` and marker ``k % 8``, so the
first eight series differ in marker alone, and in colour too."""


def series_style(k: int) -> dict[str, Any]:
    """Matplotlib keyword arguments (``color``, ``ls``, ``marker``) of series number ``k``
    (0, 1, ...): no two of the first eight share a colour or a marker, no two of the first
    four a line style."""
    return {
        "color": COLORS[k % len(COLORS)],
        "ls": LINE_STYLES[k % len(LINE_STYLES)],
        "marker": MARKERS[k % len(MARKERS)],
    }


FEW_TICKS = 5
"""At most this many intervals between major ticks on a figure's busy axes: every tick is a
label, a mark and a grid line to lay out and draw, most of a saved figure's cost."""


def few_ticks(*axes: Any, nbins: int = FEW_TICKS) -> None:
    """At most ``nbins`` intervals between the major ticks of each of ``axes`` (both of its
    axes; a colorbar's axes too), at matplotlib's usual round steps."""
    for ax in axes:
        ax.locator_params(nbins=nbins)
