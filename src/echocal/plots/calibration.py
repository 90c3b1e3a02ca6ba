"""Calibration figures: convergence (vs iteration and vs measurements) and paths over a cost map.

These reproduce the two figures of every thesis scenario (pseudo-energy vs
iterations; the path over the cost-function heat map with initial guess and
true solution marked) and add the view that matters on a rig: the same
against the number of measurements.  Where no truth is known (a recording, a
rig), :func:`measured_convergence_figure` shows what was measured and how the
estimate settled, and :func:`path_figure` draws over a recording's own metric map
or over no map at all.  They only read results.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib import patheffects
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

from echocal.calibrate.result import CalibrationResult
from echocal.evaluation import CostMap
from echocal.plots._figure import cell_edges, new_figure
from echocal.plots._style import FEW_TICKS, few_ticks, series_style

__all__ = [
    "MAP_DB_FLOOR",
    "CostMap",
    "convergence_figure",
    "map_views",
    "measured_convergence_figure",
    "path_figure",
    "relative_db",
]

FloatArray = NDArray[np.float64]


def _integer_ticks(*axes: Any) -> None:
    """Whole-number ticks on the x axis (iterations and measurement counts)."""
    from matplotlib.ticker import MaxNLocator

    for ax in axes:
        ax.xaxis.set_major_locator(MaxNLocator(nbins=FEW_TICKS + 1, integer=True))


def convergence_figure(
    runs: Mapping[str, CalibrationResult],
    iterate_values: Mapping[str, ArrayLike],
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
    fig = new_figure(figsize=(11, 4.2 + 0.2 * ((len(runs) + 3) // 4)), constrained_layout=True)
    by_iter, by_meas = fig.subplots(1, 2, sharey=True)
    for i, (label, result) in enumerate(runs.items()):
        values = np.asarray(iterate_values[label], dtype=float)
        iterations = np.arange(len(values))
        # colour, line style and marker together: series differ for colour-blind readers
        style = series_style(i) | {"ms": 4, "mfc": "none", "lw": 1.3}
        style["markevery"] = max(1, len(values) // 15)  # markers stay apart on long runs
        by_iter.plot(iterations, values, **style)
        by_meas.plot(
            result.iteration_measurements[: len(values)],
            values,
            **style,
            label=f"{label} ({result.n_measurements} meas.)",
        )
    for ax in (by_iter, by_meas):
        if optimum_value is not None:
            ax.axhline(optimum_value, color="0.35", ls=(0, (2, 2)), lw=0.8, label="true optimum")
        ax.grid(alpha=0.3)
    by_iter.set_xlabel("iteration")
    by_meas.set_xlabel("measurements used")
    _integer_ticks(by_iter, by_meas)
    by_iter.set_ylabel(ylabel)
    # below both panels, never over a curve
    handles, names = by_meas.get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncols=min(4, len(names)), fontsize=8)
    if title:
        fig.suptitle(title)
    return fig


def measured_convergence_figure(
    result: CalibrationResult,
    *,
    label: str | None = None,
    scale: float | None = None,
    scale_label: str = "largest value measured",
    iterate_values: Sequence[float] | None = None,
    iterate_label: str = "metric at the estimate",
    title: str | None = None,
) -> Figure:
    """Convergence of a run whose true optimum is unknown (a recording, a rig).

    Left: every measured value vs measurement number, with the best value measured so
    far, divided by ``scale`` (default: the largest value measured) — what the run saw,
    noise included.  Right: the angle [deg] between the beam of each iterate and that
    of the final estimate vs the measurements used — how the estimate settled (not
    its error: no truth is known).

    Parameters
    ----------
    result : the run.
    label : the run's name in the legends (default ``result.method``).
    scale : [metric units] the values are divided by this (> 0); ``scale_label`` says
        what it is (shown in the y label).
    iterate_values : optional metric at x0 and each iterate, shape (n_iterations + 1,),
        e.g. a recording's repeat-averaged metric interpolated there; drawn on the left
        vs the measurements used, labelled ``iterate_label``.
    """
    from echocal.evaluation import angular_error

    label = result.method if label is None else label
    values = np.asarray(result.values, dtype=float)
    finite = values[np.isfinite(values)]
    if scale is None:
        scale = float(np.max(finite)) if finite.size and np.max(finite) > 0 else 1.0
        scale_label = "largest value measured"
    if not scale > 0:
        from echocal.errors import EchocalValueError

        raise EchocalValueError(f"scale must be > 0; got {scale}")
    fig = new_figure(figsize=(11, 4.2), constrained_layout=True)
    measured, settling = fig.subplots(1, 2)
    count = np.arange(1, len(values) + 1)
    measured.plot(count, values / scale, ls="", marker=".", ms=4, color="0.55", label="measured")
    if len(values):
        best = np.fmax.accumulate(np.where(np.isfinite(values), values, -np.inf)) / scale
        measured.step(count, best, where="post", color="C0", lw=1.2, label="best measured so far")
    steps = np.asarray(result.iteration_measurements)
    if iterate_values is not None:
        shown = np.asarray(iterate_values, dtype=float)[: len(steps)]
        measured.plot(
            steps[: len(shown)], shown / scale, marker=".", ms=4, color="C1", label=iterate_label
        )
    measured.set_xlabel("measurement")
    measured.set_ylabel(f"metric / {scale_label}")
    measured.legend(fontsize=8, loc="lower right")
    distance = angular_error(result.iterates, result.x, result.parameterization)
    # the last iterate is usually the estimate itself (distance 0): a log axis shows the rest
    shown_at = distance > 0
    settling.semilogy(
        steps[shown_at],
        distance[shown_at],
        marker=".",
        ms=4,
        color="C0",
        label=f"{label} ({result.n_measurements} meas.)",
    )
    settling.set_xlabel("measurements used")
    settling.set_ylabel("angle to the final estimate [deg]")
    settling.set_title("how the estimate settled (no truth known)", fontsize=9)
    settling.legend(fontsize=8, loc="upper right")
    for ax in (measured, settling):
        ax.grid(alpha=0.3)
    _integer_ticks(measured, settling)
    if title:
        fig.suptitle(title)
    return fig


MAP_DB_FLOOR = -40.0
"""[dB] the floor every metric map is drawn down to (relative to its maximum)."""


def relative_db(values: ArrayLike, floor: float = MAP_DB_FLOOR) -> NDArray[np.float64]:
    """10·log10(values / max) [dB], clipped at ``floor`` [dB, < 0]; shape of ``values``.

    The one way echocal draws a metric map (path figures of ``calibrate``, scenarios and
    the demo): a narrow main lobe and its side lobes stay visible on a map many lobe
    widths wide.  NaN stays NaN (orientations the map does not cover); a map without a
    positive value is all at the floor.
    """
    if not floor < 0.0:
        from echocal.errors import EchocalValueError

        raise EchocalValueError(f"db_floor must be a negative level in dB; got {floor}")
    v = np.asarray(values, dtype=np.float64)
    peak = float(np.nanmax(v)) if np.any(np.isfinite(v)) else 0.0
    if not peak > 0.0:
        return np.where(np.isnan(v), np.nan, floor)
    with np.errstate(invalid="ignore"):
        ratio = np.clip(v / peak, 10.0 ** (floor / 10.0), None)
    return np.asarray(10.0 * np.log10(ratio), dtype=np.float64)


_ESTIMATE: dict[str, Any] = {
    "marker": "X", "mfc": "w", "mec": "k", "ms": 8, "mew": 1.0, "ls": "", "zorder": 3
}  # fmt: skip
"""How a run's final estimate is marked on a path figure."""


def map_views(parameterization: str) -> tuple[str, ...]:
    """The parameterizations a map of a run in ``parameterization`` is drawn in, one panel
    each: ``("tilt",)`` for a tilt run (no pole); ``("azimuth-coelevation", "tilt")`` for
    an (azimuth, co-elevation) run — its own angles, and the tilts beside them, where a
    fraction of a degree near the pole (co-elevation 0, where the azimuth turns freely)
    stays a fraction of a degree."""
    from echocal._validate import one_of
    from echocal.calibrate.objective import PARAMETERIZATIONS

    one_of("parameterization", parameterization, PARAMETERIZATIONS)
    return ("tilt",) if parameterization == "tilt" else (parameterization, "tilt")


_VIEW_TITLES = {
    "tilt": "in tilt angles (no pole)",
    "azimuth-coelevation": "in azimuth, co-elevation (the run's angles)",
}


def path_figure(
    cost_map: CostMap | None,
    runs: Mapping[str, CalibrationResult],
    *,
    x0: ArrayLike | None = None,
    truth: ArrayLike | None = None,
    truth_label: str = "true solution",
    title: str | None = None,
    db_floor: float = MAP_DB_FLOOR,
    show_measurements: bool = False,
    parameterization: str | None = None,
    tilt_view: bool = True,
) -> Figure:
    """Paths of the iterates over the cost-function heat map, x0 and truth marked.

    The map is drawn in dB relative to its maximum, clipped at ``db_floor`` [dB, < 0]
    (:func:`relative_db`).  ``show_measurements``: also mark every measured pose (an
    acquisition's search pattern, finite-difference stencils).  NaN in the map
    (orientations it does not cover) is left blank.  ``cost_map=None`` draws the paths
    alone (a rig: no map is known), framed to every point drawn.  ``truth_label`` names
    the ``truth`` marker (e.g. a recording's best grid pose).  ``x0`` [deg]: one initial
    guess, shape (2,), or several, shape (k, 2).

    Every angle given (the map's axes, the runs, ``x0``, ``truth``) is in
    ``parameterization`` (default: the map's, named by its axes, else the first run's).
    A tilt figure has one panel; an (azimuth, co-elevation) one has two
    (:func:`map_views`): the run's own angles (``fig.axes[0]``), and, unless
    ``tilt_view`` is False, everything converted to tilt angles beside it (the map on its
    grid's nodes, converted), under one colour bar.
    """
    frame = _frame(cost_map, runs, parameterization)
    views = (frame,) if frame is None or not tilt_view else map_views(frame)
    wide = len(views) > 1
    tall = 5.9 + 0.2 * ((len(runs) + 4) // 3)
    fig = new_figure(figsize=(11.6 if wide else 6.8, tall), constrained_layout=True)
    axes = fig.subplots(1, len(views), squeeze=False)[0]
    values = None if cost_map is None else relative_db(cost_map.values.T, db_floor)
    if cost_map is None:
        relative_db([1.0], db_floor)  # the same check of db_floor with or without a map
    mesh = None
    for ax, view in zip(axes, views, strict=True):
        if cost_map is not None and values is not None:
            mesh = _draw_map(ax, cost_map, values, frame, view)
        _draw_paths(ax, runs, x0, truth, truth_label, show_measurements, cost_map, frame, view)
        few_ticks(ax)
        if wide:
            ax.set_title(_VIEW_TITLES.get(str(view), str(view)), fontsize=9)
    if mesh is not None:
        few_ticks(fig.colorbar(mesh, ax=list(axes), label="metric / max [dB]").ax)
    # below the map, never over a path (a map is light where the paths go)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(3, len(labels)), fontsize=8)
    if title:
        (fig.suptitle if wide else axes[0].set_title)(title)
    return fig


def _frame(
    cost_map: CostMap | None, runs: Mapping[str, CalibrationResult], given: str | None
) -> str | None:
    """The parameterization of a path figure's angles: ``given``, else the map's (by its
    axes' names), else the first run's; None when nothing names one (a map whose axes
    have other names: drawn as given, in one panel)."""
    from echocal._validate import one_of
    from echocal.calibrate.objective import PARAMETERIZATIONS

    if given is not None:
        return one_of("parameterization", given, PARAMETERIZATIONS)
    by_names = {names: key for key, names in PARAMETERIZATIONS.items()}
    if cost_map is not None:
        a, b = cost_map.names
        return by_names.get((str(a), str(b)))
    first = next(iter(runs.values()), None)
    return None if first is None else first.parameterization


def _to_view(points: ArrayLike, frame: str | None, view: str | None) -> FloatArray:
    """[deg] orientations ``points`` (..., 2) in ``frame``, converted to ``view``."""
    p = np.asarray(points, dtype=np.float64)
    if frame is None or view is None or frame == view:
        return p
    from echocal.geometry import convert_angles

    a, b = convert_angles(p[..., 0], p[..., 1], frame, view)
    return np.stack([np.asarray(a), np.asarray(b)], axis=-1)


def _view_names(cost_map: CostMap | None, runs: Mapping[str, Any], view: str | None):
    """The names of the axes of a panel in ``view``."""
    from echocal.calibrate.objective import PARAMETERIZATIONS

    if view is not None:
        return PARAMETERIZATIONS[view]
    if cost_map is not None:
        return cost_map.names
    first = next(iter(runs.values()), None)
    return first.names if first is not None else ("a", "b")


def _draw_map(ax: Any, cost_map: CostMap, values: FloatArray, frame: str | None, view: str | None):
    """The map (``values``: dB, shape (n_b, n_a)) on ``ax`` in ``view``: on its own grid,
    or on its grid's nodes converted from ``frame`` (a curvilinear mesh); framed to it."""
    smooth = bool(np.all(np.isfinite(values)))
    # smooth shading between grid points (a coarse wave-model map stays a picture of
    # the lobe, not a mosaic); flat cells where some are missing
    shading = "gouraud" if smooth else "auto"
    if frame is None or view is None or frame == view:
        x, y = cost_map.a, cost_map.b
    else:
        # a curvilinear mesh: smooth shading on the grid's nodes converted, or flat cells
        # between its cell edges converted (matplotlib cannot infer a curved grid's edges)
        a, b = (
            (cost_map.a, cost_map.b) if smooth else (cell_edges(cost_map.a), cell_edges(cost_map.b))
        )
        nodes = np.stack(np.meshgrid(a, b, indexing="xy"), axis=-1)
        x, y = np.moveaxis(_to_view(nodes, frame, view), -1, 0)
        shading = "gouraud" if smooth else "flat"
    mesh = ax.pcolormesh(x, y, np.ma.masked_invalid(values), shading=shading, cmap="viridis")
    # framed to the map's drawn cells (a lobe-profile map is blank beyond its reach): the
    # corners of every finite cell, in the view; the paths widen it (_draw_paths)
    edges = np.stack(np.meshgrid(cell_edges(cost_map.a), cell_edges(cost_map.b), indexing="xy"), -1)
    corners = _to_view(edges, frame, view)
    finite = np.isfinite(values) if np.any(np.isfinite(values)) else np.ones(values.shape, bool)
    shown = np.vstack(
        [corners[i : i + finite.shape[0], j : j + finite.shape[1]][finite]
         for i in (0, 1) for j in (0, 1)]
    )  # fmt: skip
    ax.set_xlim(float(np.min(shown[:, 0])), float(np.max(shown[:, 0])))
    ax.set_ylim(float(np.min(shown[:, 1])), float(np.max(shown[:, 1])))
    if view == "tilt" and frame != view:
        # a degree of tilt is a degree each way: the panel keeps its size, the limits grow
        ax.set_aspect("equal", adjustable="datalim")
    return mesh


class _AspectNotice(logging.Filter):
    """Drops matplotlib's notice "Ignoring fixed x limits to fulfill fixed data aspect with
    adjustable data limits": the tilt view asks exactly that (its limits are set to the
    map's cells, then widened so a degree of tilt is a degree each way), so on a report's
    or the demo's screen it reads as a fault that is not there.  Every other matplotlib
    message passes."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "to fulfill fixed data aspect" not in record.getMessage()


logging.getLogger("matplotlib.axes._base").addFilter(_AspectNotice())


def _draw_paths(
    ax: Any,
    runs: Mapping[str, CalibrationResult],
    x0: ArrayLike | None,
    truth: ArrayLike | None,
    truth_label: str,
    show_measurements: bool,
    cost_map: CostMap | None,
    frame: str | None,
    view: str | None,
) -> None:
    """The runs' paths, estimates (and measured poses), ``x0`` and ``truth`` on ``ax``,
    converted from ``frame`` to ``view``; the axes' labels; a panel without a map is
    framed to every point drawn."""
    on_map = cost_map is not None
    # on a map every path has a thin dark outline, so it shows on the bright lobe as on
    # the dark floor; the markers have dark edges and white faces, visible on both
    dots = "0.85" if on_map else "0.6"
    halo = [patheffects.withStroke(linewidth=3.0, foreground="w", alpha=0.7)] if on_map else []
    drawn = []
    for i, (name, result) in enumerate(runs.items()):
        if show_measurements and len(result.points):
            points = _to_view(result.points, frame, view)
            ax.plot(*points.T, ls="", marker=".", ms=2.5, color=dots, alpha=0.8)
            drawn.append(points)
        path = _to_view(result.iterates, frame, view)
        # colour, line style and marker together: paths differ for colour-blind readers
        style = series_style(i) | {"ms": 4.5, "lw": 1.3, "mec": "0.1", "mew": 0.6}
        style["markevery"] = max(1, len(path) // 15)
        if on_map and style["color"] == "#000000":
            style["color"] = "w"  # black would vanish into the map's dark floor
        ax.plot(path[:, 0], path[:, 1], label=name, path_effects=halo, **style)
        estimate = _to_view(result.x, frame, view)
        ax.plot(*estimate, **_ESTIMATE)
        drawn += [path, estimate[None, :]]
    if show_measurements:
        ax.plot([], [], ls="", marker=".", color=dots, label="measured poses")
    if runs:
        ax.plot([], [], label="final estimate", **_ESTIMATE)
    if x0 is not None:
        starts = _to_view(np.reshape(np.asarray(x0, dtype=np.float64), (-1, 2)), frame, view)
        ax.plot(
            *starts.T, marker="o", mfc="w", mec="k", ms=9, mew=1.2, ls="", zorder=1.9,
            label="initial guess" if len(starts) == 1 else "initial guesses",
        )  # fmt: skip
        drawn.append(starts)
    if truth is not None:
        t = _to_view(truth, frame, view)
        star: dict[str, Any] = {"marker": "*", "color": "r", "mec": "k", "mew": 0.6, "ms": 14}
        ax.plot(t[0], t[1], ls="", label=truth_label, **star)
        drawn.append(t[None, :])
    if drawn:  # frame every point drawn, with a margin (at least 0.5 deg), and the map
        points = np.vstack(drawn)
        low, high = points.min(axis=0), points.max(axis=0)
        pad = np.maximum(0.08 * (high - low), 0.5)
        low, high = low - pad, high + pad
        if on_map:
            (x_low, x_high), (y_low, y_high) = ax.get_xlim(), ax.get_ylim()
            low = np.minimum(low, [x_low, y_low])
            high = np.maximum(high, [x_high, y_high])
        ax.set_xlim(low[0], high[0])
        ax.set_ylim(low[1], high[1])
    if not on_map:
        ax.grid(alpha=0.3)
    names = _view_names(cost_map, runs, view)
    ax.set_xlabel(f"{names[0]} [deg]")
    ax.set_ylabel(f"{names[1]} [deg]")
