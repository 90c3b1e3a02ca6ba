"""Figures: functions that only read data and return a :class:`matplotlib.figure.Figure`.

Figures are built with the object-oriented API (no pyplot state), so they work headless
and in parallel; inside IPython (a Jupyter notebook) they are made through pyplot, so the
notebook shows them inline when the cell ends.  :func:`save_figure` writes them atomically.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from matplotlib.figure import Figure

from echocal.errors import EchocalValueError
from echocal.io import atomic_path

__all__ = ["figure_formats", "plot_ascan", "plot_pulse", "save_figure", "supported_formats"]


def supported_formats() -> tuple[str, ...]:
    """File formats matplotlib can write here (``png``, ``svg``, ``pdf``, ...), sorted."""
    from matplotlib.backend_bases import FigureCanvasBase

    return tuple(sorted(FigureCanvasBase.get_supported_filetypes()))


def _check_formats(formats: Iterable[str], option: str = "format") -> tuple[str, ...]:
    supported = supported_formats()
    out = []
    for fmt in formats:
        name = str(fmt).lstrip(".").lower()
        if name not in supported:
            raise EchocalValueError(
                f"{option}: cannot write a figure as {name!r}; use one of "
                f"{', '.join(supported)} (e.g. .png, .svg, .pdf)"
            )
        if name not in out:
            out.append(name)
    return tuple(out)


def figure_formats(
    path: str | os.PathLike[str], extra: Iterable[str] = (), *, option: str = "--out"
) -> tuple[str, ...]:
    """The formats to write for an output ``path``: its suffix (``png`` if it has none),
    then ``extra``, without repeats — refused up front, before any work, if matplotlib
    cannot write one (``--out result.txt``), naming ``option`` and the supported formats.
    """
    suffix = Path(path).suffix.lstrip(".")
    return _check_formats((suffix or "png", *extra), option)


def save_figure(
    fig: Figure,
    path: str | os.PathLike[str],
    *,
    formats: Iterable[str] = ("png", "svg"),
    dpi: int = 150,
) -> list[Path]:
    """Write ``fig`` once per format beside ``path`` (its suffix replaced), atomically.

    ``save_figure(fig, "out/pulse.png")`` writes ``out/pulse.png`` and ``out/pulse.svg``.
    Returns the paths written.  A format matplotlib cannot write is refused before any
    file is written (:func:`figure_formats` checks a CLI's ``--out`` before the work).
    """
    base = Path(path)
    written = []
    chosen = _check_formats(formats)
    with _laid_out(fig) as crop:
        for fmt in chosen:
            target = base.with_suffix("." + fmt.lstrip("."))
            with atomic_path(target) as tmp:
                fig.savefig(tmp, format=fmt.lstrip("."), dpi=dpi, bbox_inches=crop)
            written.append(target)
    return written


@contextmanager
def _laid_out(fig: Figure) -> Iterator[str | None]:
    """Lay ``fig`` out once for all the files written inside the ``with``; yields the
    ``bbox_inches`` to write them with.

    A figure with a constrained layout is laid out here, once, and written with its layout
    engine off and its own size (the constrained layout already fits every decoration in
    the figure): matplotlib's ``savefig`` would otherwise, per file, draw the figure once
    without rendering to lay it out and again to render it, plus a tight-bbox pass — about
    twice the drawing.  Any other figure is written as before, cropped to its contents
    (``"tight"``).  The layout engine is restored afterwards."""
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    engine = fig.get_layout_engine()
    if not isinstance(engine, ConstrainedLayoutEngine) or not fig.axes:
        yield "tight"
        return
    engine.execute(fig)
    fig.set_layout_engine(None)  # not "none": savefig lays out any engine again
    try:
        yield None
    finally:
        fig.set_layout_engine(engine)


def __getattr__(name: str):  # lazy: importing echocal.plots stays cheap
    if name == "plot_pulse":
        from echocal.plots.pulses import plot_pulse

        return plot_pulse
    if name == "plot_ascan":
        from echocal.plots.ascan import plot_ascan

        return plot_ascan
    raise AttributeError(name)
