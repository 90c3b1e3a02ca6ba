"""A sphinx-gallery image scraper for the matplotlib ``Figure`` objects echocal returns.

echocal's plotting functions build figures with ``matplotlib.figure.Figure`` (no
pyplot state, so they are safe in threads and servers); sphinx-gallery's own matplotlib
scraper only sees pyplot figures.  This scraper saves every ``Figure`` that a code block
left in the example's namespace (and that was not shown before) and returns the reST
that shows it.  Figures made with pyplot are left to sphinx-gallery's own scraper (both
would show them, each figure twice).
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst


def figure_scraper(block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any]) -> str:
    """Save the new ``Figure`` objects of the example's globals; their reST image block."""
    shown: set[int] = block_vars.setdefault("_echocal_shown_figures", set())
    paths = []
    for value in list(block_vars["example_globals"].values()):
        if isinstance(value, Figure) and getattr(value.canvas, "manager", None) is not None:
            continue  # a pyplot figure: sphinx-gallery's matplotlib scraper shows it once
        if isinstance(value, Figure) and id(value) not in shown:
            shown.add(id(value))
            path = next(block_vars["image_path_iterator"])
            value.savefig(path, dpi=96)
            paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
