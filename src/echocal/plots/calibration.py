"""Calibration figures: convergence (vs iteration and vs measurements) and paths over a cost map.

These reproduce the two figures of every thesis scenario (pseudo-energy vs
iterations; the path over the cost-function heat map with initial guess and
true solution marked) and add the view that matters on a rig: the same
against the number of measurements.  They only read results.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

from echocal.calibrate.result import CalibrationResult
from echocal.evaluation import CostMap

__all__ = ["CostMap", "convergence_figure", "path_figure"]

FloatArray = NDArray[np.float64]


def convergence_figure(
    runs: Mapping[str, CalibrationResult],
    iterate_values: Mapping[str, Sequence[float]],
    *,
    optimum_value: float | None = None,
    ylabel: str = "pseudo-energy (normalized)",
    title: str | None = None,
) -> Figure:
    """Metric of the estimate vs iteration (left) and vs measurements used (right).

    Parameters
    ----------
    runs : label → result.
    iterate_values : label → metric at each iterate (``len == n_iterations + 1``),
        e.g. the noiseless simulated metric at the iterates.
    optimum_value : the metric at the true optimum, drawn as a dashed line.
    """
    fig = Figure(figsize=(11, 4.2), constrained_layout=True)
    by_iter, by_meas = fig.subplots(1, 2, sharey=True)
    for label, result in runs.items():
        values = np.asarray(iterate_values[label], dtype=float)
        iterations = np.arange(len(values))
        line = by_iter.plot(iterations, values, marker=".", ms=4, label=label)[0]
        by_meas.plot(
            result.iteration_measurements[: len(values)],
            values,
            marker=".",
            ms=4,
            color=line.get_color(),
            label=f"{label} ({result.n_measurements} meas.)",
        )
    for ax in (by_iter, by_meas):
        if optimum_value is not None:
            ax.axhline(optimum_value, color="k", ls="--", lw=0.8, label="true optimum")
        ax.grid(alpha=0.3)
    by_iter.set_xlabel("iteration")
    by_meas.set_xlabel("measurements used")
    by_iter.set_ylabel(ylabel)
    by_meas.legend(fontsize=8, loc="lower right")
    if title:
        fig.suptitle(title)
    return fig


def path_figure(
    cost_map: CostMap,
    runs: Mapping[str, CalibrationResult],
    *,
    x0: Sequence[float] | None = None,
    truth: Sequence[float] | None = None,
    title: str | None = None,
    db_floor: float | None = None,
    show_measurements: bool = False,
) -> Figure:
    """Paths of the iterates over the cost-function heat map, x0 and truth marked.

    ``db_floor`` [dB, < 0]: draw the map as 10·log10(value / max), clipped at this floor —
    a narrow main lobe and its side lobes stay visible on a map many lobe widths wide
    (default: the linear metric, as in the thesis's figures).  ``show_measurements``: also
    mark every measured pose (an acquisition's search pattern, finite-difference stencils).
    """
    fig = Figure(figsize=(6.8, 5.6), constrained_layout=True)
    ax = fig.add_subplot()
    values, label = cost_map.values.T, "metric"
    if db_floor is not None:
        if not db_floor < 0.0:
            from echocal.errors import EchocalValueError

            raise EchocalValueError(f"db_floor must be a negative level in dB; got {db_floor}")
        peak = float(np.nanmax(values))
        ratio = np.clip(values / peak, 10.0 ** (db_floor / 10.0), None) if peak > 0 else values
        values, label = 10.0 * np.log10(ratio), "metric / max [dB]"
    mesh = ax.pcolormesh(cost_map.a, cost_map.b, values, shading="auto", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=label)
    for name, result in runs.items():
        if show_measurements and len(result.points):
            ax.plot(*result.points.T, ls="", marker=".", ms=2.5, color="0.85", alpha=0.8)
        path = result.iterates
        ax.plot(path[:, 0], path[:, 1], marker=".", ms=4, lw=1.2, label=name)
        ax.plot(*result.x, marker="x", color="w", ms=6)
    if show_measurements:
        ax.plot([], [], ls="", marker=".", color="0.85", label="measured poses")
    if x0 is not None:
        ax.plot(*x0, marker="o", mfc="none", mec="w", ms=10, mew=1.5, ls="", label="initial guess")
    if truth is not None:
        ax.plot(*truth, marker="*", color="r", ms=14, ls="", label="true solution")
    ax.set_xlim(cost_map.a[0], cost_map.a[-1])
    ax.set_ylim(cost_map.b[0], cost_map.b[-1])
    ax.set_xlabel(f"{cost_map.names[0]} [deg]")
    ax.set_ylabel(f"{cost_map.names[1]} [deg]")
    ax.legend(fontsize=8, loc="upper right", framealpha=0.6)
    if title:
        ax.set_title(title)
    return fig
