"""Views of a position scan as an ultrasonic inspector looks at it: B-scan, C-scan, A-scan.

Each function only reads a :class:`~echocal.positionscan.PositionScan` and returns a
matplotlib Figure; positions in mm, times in µs, amplitudes in dB re the scan's largest
envelope (sequential, colour-blind-safe colour maps: viridis for dB, cividis for times).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

from echocal.plots._figure import cell_edges
from echocal.plots._style import series_style
from echocal.positionscan.dataset import PositionScan
from echocal.signal.analytic import analytic_signal
from echocal.signal.gates import TimeGate

__all__ = ["ascan_figure", "bscan_figure", "cscan_figure", "gated_values", "residual_map_figure"]

_MM, _US = 1e3, 1e6


def _db(env: NDArray[np.float64], reference: float, floor_db: float) -> NDArray[np.float64]:
    with np.errstate(divide="ignore"):
        out = 20.0 * np.log10(env / reference) if reference > 0 else np.full(env.shape, -np.inf)
    return np.maximum(out, -abs(floor_db))


def bscan_figure(
    scan: PositionScan,
    *,
    y: float | None = None,
    along: str = "x",
    depth: bool = False,
    dynamic_range_db: float = 40.0,
) -> Figure:
    """B-scan: the envelope in dB (re the line's largest) vs position and time.

    Parameters
    ----------
    y : [m] for a raster, the line nearest this y (default: the middle row); with
        ``along = "y"`` this is the x of a column instead.
    along : ``"x"`` (a row of the raster) or ``"y"`` (a column).
    depth : show the water path c₀·t/2 [mm] instead of the time (needs the scan's
        ``sound_speed_m_s``).
    dynamic_range_db : [dB] the colour scale's span below the peak.
    """
    samples = scan.samples
    if along == "y":
        k = int(np.argmin(np.abs(scan.x - y))) if y is not None else scan.x.size // 2
        line, pos, where = samples[:, k, :], scan.y, f"x = {scan.x[k] * _MM:.4g} mm"
    elif along == "x":
        k = int(np.argmin(np.abs(scan.y - y))) if y is not None else scan.y.size // 2
        line, pos, where = samples[k], scan.x, f"y = {scan.y[k] * _MM:.4g} mm"
    else:
        raise ValueError(f"along must be 'x' or 'y'; got {along!r}")
    env = np.abs(analytic_signal(line))
    db = _db(env, float(env.max()), dynamic_range_db)
    t = scan.times
    if depth:
        c = scan.sound_speed
        if c is None:
            raise ValueError("depth needs the medium's sound speed: import with --sound-speed 1480")
        vertical, label = c * t / 2 * _MM, "water path c₀t/2 [mm]"
    else:
        vertical, label = t * _US, "time [µs]"
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    mesh = ax.pcolormesh(
        cell_edges(pos * _MM),
        cell_edges(vertical),
        db.T,
        cmap="viridis",
        vmin=-dynamic_range_db,
        vmax=0,
    )
    ax.invert_yaxis()
    ax.set_xlabel(f"probe position {along} [mm]")
    ax.set_ylabel(label)
    ax.set_title(f"B-scan at {where}" if scan.is_raster else "B-scan")
    fig.colorbar(mesh, ax=ax, label="envelope [dB re max]")
    return fig


def gated_values(scan: PositionScan, gate: TimeGate, value: str) -> NDArray[np.float64]:
    """Per trace, shape ``(n_y, n_x)``: the peak envelope inside ``gate`` (``value =
    "amplitude"``, a.u.) or the echo's time of flight there [s] (``"tof"``, sub-sample:
    :func:`~echocal.positionscan.front_wall_tof`; NaN where the gate is empty)."""
    x = scan.samples
    if value == "amplitude":
        env = np.abs(analytic_signal(x))
        return np.where(gate.masks(x, scan.window), env, 0.0).max(axis=-1)
    if value == "tof":
        from echocal.positionscan.tof import front_wall_tof

        return front_wall_tof(x, scan.window, gate=gate)
    raise ValueError(f"value must be 'amplitude' or 'tof'; got {value!r}")


def cscan_figure(
    scan: PositionScan,
    gate: TimeGate,
    *,
    value: str = "amplitude",
    dynamic_range_db: float = 30.0,
) -> Figure:
    """C-scan: per trace the gated peak amplitude [dB re the largest] or its time of
    flight [µs], over the raster (a line scan: vs x)."""
    values = gated_values(scan, gate, value)
    valid = scan.valid
    values = np.where(valid, values, np.nan)
    span: tuple[float | None, float | None]
    if value == "amplitude":
        shown = _db(values, float(np.nanmax(values)), dynamic_range_db)
        label, cmap, span = "gated peak [dB re max]", "viridis", (-dynamic_range_db, 0.0)
    else:
        shown = values * _US
        label, cmap, span = "time of flight [µs]", "cividis", (None, None)
    fig = Figure(figsize=(6.0, 4.8), layout="constrained")
    ax = fig.add_subplot()
    title = (
        f"C-scan: {'gated peak' if value == 'amplitude' else 'time of flight'}, gate {gate.name}"
    )
    if scan.is_raster:
        mesh = ax.pcolormesh(
            cell_edges(scan.x * _MM),
            cell_edges(scan.y * _MM),
            np.ma.masked_invalid(shown),
            cmap=cmap,
            vmin=span[0],
            vmax=span[1],
        )
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        fig.colorbar(mesh, ax=ax, label=label)
    else:
        ax.plot(scan.x * _MM, shown[0], **series_style(0), ms=3)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    ax.set_title(title)
    return fig


def ascan_figure(
    scan: PositionScan,
    x: float,
    y: float | None = None,
    *,
    gates: tuple[TimeGate, ...] = (),
) -> Figure:
    """A-scan: the trace nearest (x, y) [m] with its envelope and each gate's span (a
    triggered gate where this trace triggers it)."""
    iy, ix = scan.trace_index(x, y)
    trace = scan.samples[iy, ix]
    t = scan.times * _US
    fig = Figure(figsize=(7.0, 3.8), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(t, trace, color=series_style(0)["color"], lw=0.8, label="signal")
    env = np.abs(analytic_signal(trace))
    style = series_style(1)
    ax.plot(t, env, color=style["color"], ls=style["ls"], lw=1.0, label="envelope")
    for k, gate in enumerate(gates):
        lo, hi = (float(v) for v in gate.spans(trace, scan.window))
        if np.isfinite(lo):
            ax.axvspan(
                lo * _US,
                hi * _US,
                color=series_style(k + 2)["color"],
                alpha=0.2,
                label=f"gate {gate.name}",
            )
    where = f"x = {scan.x[ix] * _MM:.4g} mm"
    if scan.is_raster:
        where += f", y = {scan.y[iy] * _MM:.4g} mm"
    ax.set_title(f"A-scan at {where}")
    ax.set_xlabel("time [µs]")
    unit = (scan.attr_json("source_facts") or {}).get("amplitude_unit") or "a.u."
    ax.set_ylabel(f"amplitude [{unit}]")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize="small")
    return fig


def residual_map_figure(scan: PositionScan, fit: Any) -> Figure:
    """The residuals [µm] of a :class:`~echocal.positionscan.SurfaceFit` over the scan
    (diverging map centred on 0; outliers circled), with the estimates in the title."""
    res = np.where(fit.inliers, fit.residuals, np.nan) * _US  # m -> µm
    outliers = np.isfinite(fit.residuals) & ~fit.inliers
    lim = float(np.nanmax(np.abs(res))) if np.any(np.isfinite(res)) else 1.0
    fig = Figure(figsize=(6.0, 4.8), layout="constrained")
    ax = fig.add_subplot()
    p, s = fit.parameters, fit.sigma
    if fit.shape == "plane":
        head = f"plane: distance {p['distance'] * _MM:.4f} ± {s['distance'] * _MM:.4f} mm"
    else:
        head = f"{fit.shape}: radius {p['radius'] * _MM:.3f} ± {s['radius'] * _MM:.3f} mm"
    if scan.is_raster:
        mesh = ax.pcolormesh(
            cell_edges(scan.x * _MM),
            cell_edges(scan.y * _MM),
            np.ma.masked_invalid(res),
            cmap="RdBu_r",
            vmin=-lim,
            vmax=lim,
        )
        ax.set_facecolor("0.8")  # grey, not white (0 on the diverging map): no echo there
        xx, yy = np.meshgrid(scan.x * _MM, scan.y * _MM)
        if np.any(outliers):
            ax.plot(xx[outliers], yy[outliers], "o", mfc="none", mec="k", label="outlier")
            ax.legend(loc="upper right", fontsize="small")
        ax.set_aspect("equal")
        ax.set_ylabel("y [mm]")
        fig.colorbar(mesh, ax=ax, label="residual: measured − fitted water path [µm]")
    else:
        ax.plot(scan.x * _MM, res[0], **series_style(0), ms=3, label="residual")
        if np.any(outliers[0]):
            ax.plot(
                scan.x[outliers[0]] * _MM,
                fit.residuals[0][outliers[0]] * _US,
                "x",
                color="k",
                label="outlier",
            )
        ax.set_ylabel("residual [µm]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize="small")
    ax.set_xlabel("x [mm]")
    ax.set_title(f"{head}, rms {fit.rms * _US:.2f} µm", fontsize="medium")
    return fig
