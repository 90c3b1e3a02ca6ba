"""Figures of a surface scan: height, normals, errors, measurements per point, 3D view.

Each function only reads a :class:`~echocal.scanning.SurfaceScan` (and, for the 3D
view, optionally the specimen) and returns a matplotlib Figure; lengths in mm,
angles in degrees.  :func:`save_surface_figures` writes them all (PNG + SVG).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle
from matplotlib.ticker import MaxNLocator
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from numpy.typing import NDArray

from echocal.plots import save_figure
from echocal.plots._figure import new_figure, release
from echocal.plots.scene import _EDGE, _FACE, _grid_quads
from echocal.scanning.dataset import SurfaceScan
from echocal.specimen import Specimen

__all__ = [
    "error_maps_figure",
    "height_map_figure",
    "measurements_figure",
    "normal_map_figure",
    "save_surface_figures",
    "surface_3d_figure",
    "thickness_map_figure",
]

_MM = 1e3


def _extent(scan: SurfaceScan) -> tuple[float, float, float, float]:
    """[mm] (left, right, bottom, top) of the scan's raster, half a step beyond its points."""
    x, y = scan.dataset["x"].values * _MM, scan.dataset["y"].values * _MM
    dx = (x[1] - x[0]) / 2 if x.size > 1 else 0.5
    dy = (y[1] - y[0]) / 2 if y.size > 1 else 0.5
    return (float(x[0] - dx), float(x[-1] + dx), float(y[0] - dy), float(y[-1] + dy))


def _image(
    fig: Figure,
    ax: Axes,
    scan: SurfaceScan,
    values: NDArray,
    label: str,
    *,
    mark_missing: bool = True,
    **kw,
) -> None:
    """``values`` shape (n_y, n_x) as an image in mm with a colour bar ``label``; the points
    not found marked × on grey hatching (not white: white is zero on a diverging map),
    unless ``mark_missing`` is False, with a legend below the map, off the cells."""
    extent = _extent(scan)
    im = ax.imshow(np.ma.masked_invalid(values), origin="lower", extent=extent, **kw)
    missing = ~scan.found
    if mark_missing and np.any(missing):
        left, right, bottom, top = extent
        ax.add_patch(  # behind the image: seen only through the blank (missing) cells
            Rectangle(
                (left, bottom),
                right - left,
                top - bottom,
                facecolor="0.88",
                edgecolor="0.55",
                hatch="///",
                lw=0,
                zorder=-1,
            )
        )
        xx, yy = np.meshgrid(scan.dataset["x"].values * _MM, scan.dataset["y"].values * _MM)
        ax.plot(xx[missing], yy[missing], "x", color="k", ms=5, ls="", label="missing")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), fontsize="small")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_aspect("equal")
    # a single row is a thin strip: a colour bar beside it would crowd its (wider) title
    below = values.shape[0] == 1 and not (mark_missing and np.any(missing))
    fig.colorbar(im, ax=ax, label=label, location="bottom" if below else "right")


def _map_figure(
    scan: SurfaceScan, values: NDArray, label: str, title: str, **kw
) -> tuple[Figure, Any]:
    """One map of ``values`` (see :func:`_image`) titled ``title``; the figure and its axes."""
    fig = new_figure(figsize=(5.5, 4.5), layout="constrained")
    ax = fig.add_subplot()
    _image(fig, ax, scan, values, label, **kw)
    ax.set_title(title)
    return fig, ax


def height_map_figure(scan: SurfaceScan) -> Figure:
    """Measured surface height z [mm] per probe position."""
    z = scan.dataset["surface_z"].values * _MM
    return _map_figure(scan, z, "surface z [mm]", "surface height", cmap="viridis")[0]


def normal_map_figure(scan: SurfaceScan) -> Figure:
    """Surface normals: co-elevation [deg] as colour, the normal's x–y part as arrows."""
    ds = scan.dataset
    fig, ax = _map_figure(
        scan,
        ds["coelevation"].values,
        "co-elevation [deg]",
        "surface normal (arrows: n_x, n_y)",
        cmap="magma",
    )
    xx, yy = np.meshgrid(ds["x"].values * _MM, ds["y"].values * _MM)
    nx, ny = ds["normal_x"].values, ds["normal_y"].values
    if np.isfinite(nx).any():  # no point found: no arrows (quiver would average nothing)
        # white arrows with a dark edge: seen on the dark and the light end of the map
        ax.quiver(xx, yy, nx, ny, color="white", edgecolor="0.15", linewidth=0.5, pivot="mid")
    return fig


def error_maps_figure(scan: SurfaceScan) -> Figure:
    """Normal error [deg] and height error [mm] against the truth (needs a truth)."""
    ds = scan.dataset
    if "normal_error" not in ds:
        from echocal.errors import EchocalValueError

        raise EchocalValueError("this scan has no truth: no normal_error / height_error")
    return _value_and_error_figure(
        scan,
        (ds["normal_error"].values, "normal error [deg]", "normal error"),
        (ds["height_error"].values * _MM, "height error [mm]", "height error (measured − true)"),
    )


def _value_and_error_figure(
    scan: SurfaceScan, left: tuple[NDArray, str, str], error: tuple[NDArray, str, str]
) -> Figure:
    """Two maps side by side: ``left`` = (values, colour-bar label, title) in viridis, and
    a signed ``error`` (same triple) in a diverging map centred on zero."""
    fig = new_figure(figsize=(10, 4.2), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    values, label, title = left
    _image(fig, ax1, scan, values, label, cmap="viridis")
    ax1.set_title(title)
    err, label, title = error
    lim = float(np.nanmax(np.abs(err))) if np.any(np.isfinite(err)) else 1.0
    _image(fig, ax2, scan, err, label, cmap="RdBu_r", vmin=-lim, vmax=lim)
    ax2.set_title(title)
    return fig


def thickness_map_figure(scan: SurfaceScan) -> Figure:
    """Wall thickness [mm] per probe position (a scan made with the part's c_L), and its
    error against the true thickness when the scan has one."""
    ds = scan.dataset
    if "thickness" not in ds:
        from echocal.errors import EchocalValueError

        raise EchocalValueError(
            "this scan has no thickness map: scan with the part's longitudinal speed "
            "(--longitudinal-speed, or a setup with a plate thickness and material)"
        )
    wall = ds["thickness"].values * _MM
    if "thickness_error" not in ds:
        return _map_figure(scan, wall, "thickness [mm]", "wall thickness", cmap="viridis")[0]
    return _value_and_error_figure(
        scan,
        (wall, "thickness [mm]", "wall thickness (front-to-back time of flight)"),
        (
            ds["thickness_error"].values * _MM,
            "thickness error [mm]",
            "thickness error (measured − true)",
        ),
    )


def measurements_figure(scan: SurfaceScan) -> Figure:
    """Measurements (A-scans) used per point."""
    s = scan.summary
    title = (
        f"measurements per point (total {s['measurements_total']}, "
        f"mean {s['measurements_per_point']:.1f})"
    )
    values = scan.dataset["n_measurements"].values
    fig, _ = _map_figure(scan, values, "measurements", title, mark_missing=False, cmap="cividis")
    return fig


def surface_3d_figure(scan: SurfaceScan, specimen: Specimen | None = None) -> Figure:
    """Reconstructed surface points and normals over the specimen (if given), in 3D [mm].

    The axes frame the scanned raster (x, y) and the heights from the lowest surface
    point to the probe, at equal scale on all three axes (a box of those proportions),
    and the specimen is drawn only inside that box (its surface sampled by vertical rays
    over the raster), so nothing spills over the tick labels.  Normals are arrows about
    one grid step long; points not found are marked × at their probe position.
    """
    ds = scan.dataset
    fig = new_figure(figsize=(7.5, 6.2), layout="constrained")
    ax = fig.add_subplot(projection="3d", computed_zorder=False)
    pts = scan.surface_points() * _MM
    probe = (
        np.stack([*np.meshgrid(ds["x"].values, ds["y"].values), ds["probe_z"].values], axis=-1)
        * _MM
    )  # (n_y, n_x, 3)
    left, right, bottom, top = _extent(scan)
    heights = np.concatenate([pts[:, 2], probe[..., 2].ravel()])
    heights = heights[np.isfinite(heights)]
    z_lo, z_hi = float(heights.min()), float(heights.max())
    step = min(right - left, top - bottom) / max(2, max(probe.shape[:2]))
    if specimen is not None:
        surface = _specimen_surface(specimen, (left, right, bottom, top), z_hi)
        inside = surface[..., 2] >= z_lo - 2 * step
        if np.any(inside):
            z_lo = min(z_lo, float(surface[..., 2][inside].min()))
        polys = [q for q in _grid_quads(surface) if np.all(np.isfinite(q))]
        polys = [q for q in polys if q[:, 2].min() >= z_lo]
        ax.add_collection3d(
            Poly3DCollection(polys, facecolor=_FACE, edgecolor=_EDGE, lw=0.15, zorder=1)
        )
    z_lo -= 0.5 * step
    z_hi += 0.5 * step
    found = scan.found
    probe_pts = probe.reshape(-1, 3)
    ax.scatter(
        *probe_pts[found.ravel()].T, color="0.5", s=3, marker=".", zorder=2, label="probe positions"
    )
    if len(pts):
        normals = np.stack([ds[f"normal_{a}"].values for a in "xyz"], axis=-1)[found]
        ax.scatter(
            *pts.T, color="tab:red", s=10, depthshade=False, zorder=3, label="measured points"
        )
        ax.quiver(
            *pts.T, *(normals * 1.2 * step).T, color="k", lw=1.3, arrow_length_ratio=0.3, zorder=4
        )
        ax.plot([], [], color="k", lw=1.3, label="measured normals")
    if np.any(~found):
        ax.scatter(
            *probe_pts[~found.ravel()].T,
            color="tab:purple",
            marker="x",
            s=30,
            zorder=5,
            label=f"missing ({int(np.sum(~found))}, at the probe)",
        )
    ax.set_xlim(left, right)
    ax.set_ylim(bottom, top)
    ax.set_zlim(z_lo, z_hi)
    ranges = (right - left, top - bottom, z_hi - z_lo)
    ax.set_box_aspect(ranges, zoom=0.85)
    for axis, size in zip((ax.xaxis, ax.yaxis, ax.zaxis), ranges, strict=True):
        # ticks in proportion to the axis's length: a narrow raster keeps legible labels
        axis.set_major_locator(MaxNLocator(nbins=max(2, round(6 * size / max(ranges)))))
    ax.legend(loc="upper left", fontsize=8)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    over = " over the specimen" if specimen is not None else ""
    ax.set_title(f"reconstructed surface points and normals{over}")
    return fig


def _specimen_surface(
    specimen: Specimen, extent: tuple[float, float, float, float], above: float, n: int = 41
) -> NDArray[np.float64]:
    """[mm] the specimen's upper surface over ``extent`` (mm), shape (n, n, 3): where a
    vertical ray from ``above`` [mm] first hits it; NaN where it misses."""
    from echocal.specimen.casting import cast

    left, right, bottom, top = extent
    xx, yy = np.meshgrid(np.linspace(left, right, n), np.linspace(bottom, top, n))
    origins = np.stack([xx, yy, np.full_like(xx, above + 1.0)], axis=-1).reshape(-1, 3) / _MM
    hits = cast(specimen, origins, np.array([0.0, 0.0, -1.0]))
    points = np.where(hits.hit[:, None], hits.point, np.nan) * _MM
    return points.reshape(n, n, 3)


def save_surface_figures(
    scan: SurfaceScan,
    folder: str | os.PathLike[str],
    *,
    specimen: Specimen | None = None,
    formats: tuple[str, ...] = ("png", "svg"),
) -> list[Path]:
    """Write every figure of ``scan`` into ``folder``; returns the paths written."""
    folder = Path(folder)
    figures = {
        "height": height_map_figure(scan),
        "normals": normal_map_figure(scan),
        "measurements": measurements_figure(scan),
        "surface-3d": surface_3d_figure(scan, specimen),
    }
    if "normal_error" in scan.dataset:
        figures["errors"] = error_maps_figure(scan)
    if "thickness" in scan.dataset:
        figures["thickness"] = thickness_map_figure(scan)
    written: list[Path] = []
    for name, fig in figures.items():
        written += save_figure(fig, folder / f"{name}.png", formats=formats)
        release(fig)
    return written
