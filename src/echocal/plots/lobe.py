"""The echo lobe in dB beside the flat piston's analytic limits (:mod:`echocal.lobe`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from echocal.lobe import EchoLobe, far_field_lobe, near_field_lobe
from echocal.plots._figure import new_figure

__all__ = ["plot_lobe"]

_FLOOR_DB = -40.0


def _db(x: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return np.maximum(20.0 * np.log10(np.maximum(np.abs(x), 1e-300)), _FLOOR_DB - 5)


def plot_lobe(lobe: EchoLobe | Sequence[EchoLobe], *, title: str | None = None) -> Figure:
    """Envelope peak [dB re its value at the optimum] against tilt [deg] of one or more
    lobes (distinguished by colour and line style), with the deep-near-field limit D(2x)
    and the far-field limit D(x)² of the first lobe's probe (x = ka sinα; D = 2J₁(x)/x for
    a disc, sin x / x for a rectangle), and the −6 dB level."""
    lobes = [lobe] if isinstance(lobe, EchoLobe) else list(lobe)
    first = lobes[0]
    fig = new_figure(figsize=(10.0, 4.2), layout="constrained")
    ax = fig.subplots()
    styles = ["-", "--", "-.", ":"]
    for i, item in enumerate(lobes):
        width = item.minus6db_deg
        label = f"{item.model} model, −6 dB half-width {width:.3f}°"
        ax.plot(item.tilt_deg, item.relative_db, styles[i % 4], color=f"C{i}", lw=1.8, label=label)
    tilt = np.linspace(first.tilt_deg.min(), first.tilt_deg.max(), 801)
    d = "2J₁(x)/x" if first.aperture == "circular" else "sin x / x"
    ax.plot(
        tilt,
        _db(far_field_lobe(first.ka, tilt, first.aperture)),
        color="0.35",
        lw=1.0,
        ls=(0, (5, 2)),
        label=f"far field D(x)², D = {d}, x = ka sinα",
    )
    ax.plot(
        tilt,
        _db(near_field_lobe(first.ka, tilt, first.aperture)),
        color="0.55",
        lw=1.0,
        ls=(0, (1, 1.5)),
        label="deep near field D(2x)",
    )
    ax.axhline(-6.0, color="C3", lw=0.8, ls=(0, (3, 3)))
    ax.text(tilt[-1], -6.0, " −6 dB", va="bottom", ha="right", fontsize=8, color="C3")
    ax.set_ylim(_FLOOR_DB, 3.0)
    ax.set_xlim(tilt[0], tilt[-1])
    ax.set_xlabel("tilt away from the optimum α [deg]")
    ax.set_ylabel("echo envelope peak [dB re optimum]")
    where = f"{1e3 * first.distance_m:.0f} mm water path, ka = {first.ka:.0f}"
    ax.set_title(title or f"{first.setup}: echo lobe ({where})", fontsize=10)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # off the curves
    return fig
