"""Figures: functions that only read data and return a :class:`matplotlib.figure.Figure`.

Figures are built with the object-oriented API (no pyplot state), so they work headless
and in parallel; :func:`save_figure` writes them atomically.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from matplotlib.figure import Figure

from echocal.io import atomic_path

__all__ = ["plot_ascan", "plot_pulse", "save_figure"]


def save_figure(
    fig: Figure,
    path: str | os.PathLike[str],
    *,
    formats: Iterable[str] = ("png", "svg"),
    dpi: int = 150,
) -> list[Path]:
    """Write ``fig`` once per format beside ``path`` (its suffix replaced), atomically.

    ``save_figure(fig, "out/pulse.png")`` writes ``out/pulse.png`` and ``out/pulse.svg``.
    Returns the paths written.
    """
    base = Path(path)
    written = []
    for fmt in formats:
        target = base.with_suffix("." + fmt.lstrip("."))
        with atomic_path(target) as tmp:
            fig.savefig(tmp, format=fmt.lstrip("."), dpi=dpi, bbox_inches="tight")
        written.append(target)
    return written


def __getattr__(name: str):  # lazy: importing echocal.plots stays cheap
    if name == "plot_pulse":
        from echocal.plots.pulses import plot_pulse

        return plot_pulse
    if name == "plot_ascan":
        from echocal.plots.ascan import plot_ascan

        return plot_ascan
    raise AttributeError(name)
