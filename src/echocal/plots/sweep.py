"""Sweep figures: reliability and cost of each configuration across SNR.

They read the tidy tables of a sweep (:mod:`echocal.experiments.runner`'s runs table:
``label``, ``snr_db`` [dB], ``success``, ``measurements_to_tol``, ``n_measurements``;
and :func:`echocal.experiments.summary.summarize`'s ``success_rate``) and return
matplotlib Figures:

* :func:`success_rate_figure` — success rate vs SNR, one line per configuration;
* :func:`measurements_figure` — distribution of measurements to the tolerance
  (successful runs) per configuration and SNR, as box plots;
* :func:`success_ecdf_figure` — fraction of *all* runs that reached the tolerance
  within m measurements, vs m (an ECDF that tops out at the success rate).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from echocal.plots._figure import new_figure
from echocal.plots._style import COLORS, series_style

__all__ = ["measurements_figure", "success_ecdf_figure", "success_rate_figure"]

_NOISELESS = "noiseless"
_STYLES = ("-", "--", ":", "-.")
"""ECDF line styles, one per SNR (the configuration has its colour and marker)."""


def _labels(frame: pd.DataFrame) -> list[str]:
    column = "label" if "label" in frame else "method"
    return list(dict.fromkeys(frame[column].astype(str)))


def _label_column(frame: pd.DataFrame) -> pd.Series:
    return frame["label" if "label" in frame else "method"].astype(str)


def _snr_positions(snrs: pd.Series) -> tuple[dict[float, float], list[str]]:
    """x position per SNR (NaN = noiseless drawn right of the finite ones) and tick labels."""
    finite = sorted({float(s) for s in snrs if not math.isnan(float(s))})
    pos = {s: s for s in finite}
    ticks = [f"{s:g}" for s in finite]
    if any(math.isnan(float(s)) for s in snrs):
        right = (finite[-1] + 10.0) if finite else 0.0
        pos[math.nan] = right
        ticks.append(_NOISELESS)
    return pos, ticks


def _x(pos: dict[float, float], snr: float) -> float:
    return pos[math.nan] if math.isnan(snr) else pos[snr]


def success_rate_figure(summary: pd.DataFrame, *, title: str | None = None) -> Figure:
    """Success rate [%] vs SNR [dB], one line per configuration (``label``).

    summary : one row per configuration and SNR with ``snr_db`` and ``success_rate``.
    """
    fig = new_figure(figsize=(8.0, 4.2), constrained_layout=True)
    ax = fig.add_subplot()
    pos, ticks = _snr_positions(summary["snr_db"])
    labels = _label_column(summary)
    for k, label in enumerate(_labels(summary)):
        sub = summary[labels == label]
        xs = [_x(pos, float(s)) for s in sub["snr_db"]]
        order = np.argsort(xs)
        ax.plot(
            np.asarray(xs)[order],
            100 * sub["success_rate"].to_numpy(dtype=float)[order],
            **series_style(k),  # colour, line style and marker: colour-blind safe
            mfc="none",  # open markers: configurations on the same point stay visible
            ms=10 - 1.5 * (k % 4),
            label=label,
        )
    ax.set_xticks(list(pos.values()), ticks)  # ascending: finite SNRs, then noiseless
    ax.set_xlabel("SNR [dB]")
    ax.set_ylabel("success rate [%]")
    ax.set_ylim(-5, 105)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the lines
    ax.set_title(title or "success rate vs SNR")
    return fig


def measurements_figure(runs: pd.DataFrame, *, title: str | None = None) -> Figure:
    """Box plots of measurements to the tolerance (successful runs) per configuration and SNR.

    An empty box slot means no run of that configuration reached the tolerance.
    """
    fig = new_figure(figsize=(max(6.8, 0.9 * len(runs.groupby(["label", "snr_db"]))), 4.4))
    fig.set_layout_engine("constrained")
    ax = fig.add_subplot()
    labels = _label_column(runs)
    snrs = sorted({float(s) for s in runs["snr_db"]}, key=lambda s: (math.isnan(s), -s))
    data, names, colors = [], [], []
    for k, label in enumerate(_labels(runs)):
        for snr in snrs:
            same = runs["snr_db"].isna() if math.isnan(snr) else runs["snr_db"] == snr
            sub = runs[(labels == label) & same]
            if sub.empty:
                continue
            ok = sub[sub["success"].astype(bool)]["measurements_to_tol"].dropna()
            data.append(ok.to_numpy(dtype=float))
            snr_text = _NOISELESS if math.isnan(snr) else f"{snr:g} dB"
            names.append(f"{label}\n{snr_text}")
            colors.append(COLORS[k % len(COLORS)])
    positions = np.arange(1, len(data) + 1)
    filled = [i for i, d in enumerate(data) if d.size]
    if filled:
        boxes = ax.boxplot(
            [data[i] for i in filled],
            positions=positions[filled],
            widths=0.6,
            patch_artist=True,
            medianprops={"color": "k", "lw": 1.6},  # black: seen on every box's colour
        )
        for patch, i in zip(boxes["boxes"], filled, strict=True):
            patch.set_facecolor(colors[i])
            patch.set_alpha(0.5)
    for i, d in enumerate(data):
        if not d.size:
            ax.text(
                positions[i],
                0.5,
                "none\nsucceeded",
                ha="center",
                va="bottom",
                fontsize=7,
                transform=ax.get_xaxis_transform(),
            )
    ax.set_xticks(positions, names, fontsize=7)
    ax.set_xlim(0.4, len(data) + 0.6)
    ax.set_ylabel("measurements to tolerance")
    ax.grid(alpha=0.3, axis="y")
    ax.set_title(title or "measurements to reach the tolerance (successful runs)")
    return fig


def success_ecdf_figure(runs: pd.DataFrame, *, title: str | None = None) -> Figure:
    """Fraction of all runs within tolerance after m measurements, vs m; one line per
    configuration, line style per SNR.  Each curve ends at that configuration's success rate."""
    fig = new_figure(figsize=(8.6, 4.4), constrained_layout=True)
    ax = fig.add_subplot()
    labels = _label_column(runs)
    snrs = sorted({float(s) for s in runs["snr_db"]}, key=lambda s: (math.isnan(s), -s))
    styles = _STYLES
    top = float(np.nanmax(runs["n_measurements"].to_numpy(dtype=float))) if len(runs) else 1.0
    for k, label in enumerate(_labels(runs)):
        for j, snr in enumerate(snrs):
            same = runs["snr_db"].isna() if math.isnan(snr) else runs["snr_db"] == snr
            sub = runs[(labels == label) & same]
            if sub.empty:
                continue
            ok = sub["success"].astype(bool)
            m = np.sort(sub.loc[ok, "measurements_to_tol"].dropna().to_numpy(dtype=float))
            xs = np.concatenate([[0.0], m, [top]])
            ys = np.concatenate([[0.0], np.arange(1, m.size + 1) / len(sub), [m.size / len(sub)]])
            snr_text = _NOISELESS if math.isnan(snr) else f"{snr:g} dB"
            style = series_style(k)  # the configuration: colour and marker; SNR: style
            ax.step(
                xs,
                100 * ys,
                where="post",
                color=style["color"],
                marker=style["marker"],
                ms=4,
                mfc="none" if j else style["color"],
                markevery=slice(1, -1),  # on each run's step, not on the frame's ends
                ls=styles[j % len(styles)],
                label=f"{label}, {snr_text}",
            )
    ax.set_xlabel("measurements")
    ax.set_ylabel("runs within tolerance [%]")
    ax.set_ylim(-3, 103)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the curves
    ax.set_title(title or "success vs measurements (ECDF over all runs)")
    return fig
