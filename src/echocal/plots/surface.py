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
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from numpy.typing import NDArray

from echocal.plots import save_figure
from echocal.plots.scene import _EDGE, _FACE, _equal_axes, _shape_polygons
from echocal.scanning.dataset import SurfaceScan
from echocal.specimen import Specimen

__all__ = [
    "error_maps_figure",
    "height_map_figure",
    "measurements_figure",
    "normal_map_figure",
    "save_surface_figures",
    "surface_3d_figure",
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
    not found marked ×, unless ``mark_missing`` is False."""
    im = ax.imshow(np.ma.masked_invalid(values), origin="lower", extent=_extent(scan), **kw)
    missing = ~scan.found
    if mark_missing and np.any(missing):
        xx, yy = np.meshgrid(scan.dataset["x"].values * _MM, scan.dataset["y"].values * _MM)
        ax.plot(xx[missing], yy[missing], "x", color="0.4", ms=4, label="missing")
        ax.legend(loc="upper right", fontsize="small")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_aspect("equal")
    fig.colorbar(im, ax=ax, label=label)


def _map_figure(
    scan: SurfaceScan, values: NDArray, label: str, title: str, **kw
) -> tuple[Figure, Any]:
    """One map of ``values`` (see :func:`_image`) titled ``title``; the figure and its axes."""
    fig = Figure(figsize=(5.5, 4.5), layout="constrained")
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
        ax.quiver(xx, yy, nx, ny, color="white", pivot="mid")
    return fig


def error_maps_figure(scan: SurfaceScan) -> Figure:
    """Normal error [deg] and height error [mm] against the truth (needs a truth)."""
    ds = scan.dataset
    if "normal_error" not in ds:
        from echocal.errors import EchocalValueError

        raise EchocalValueError("this scan has no truth: no normal_error / height_error")
    fig = Figure(figsize=(10, 4.2), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    _image(fig, ax1, scan, ds["normal_error"].values, "normal error [deg]", cmap="viridis")
    ax1.set_title("normal error")
    herr = ds["height_error"].values * _MM
    lim = float(np.nanmax(np.abs(herr))) if np.any(np.isfinite(herr)) else 1.0
    _image(fig, ax2, scan, herr, "height error [mm]", cmap="RdBu_r", vmin=-lim, vmax=lim)
    ax2.set_title("height error (measured − true)")
    return fig


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
    """Reconstructed surface points and normals over the specimen (if given), in 3D."""
    ds = scan.dataset
    fig = Figure(figsize=(7, 6), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    pts = scan.surface_points() * _MM
    if specimen is not None:
        polys = [p * _MM for s in specimen for p in _shape_polygons(s)]
        ax.add_collection3d(Poly3DCollection(polys, facecolor=_FACE, edgecolor=_EDGE, lw=0.2))
    normals = np.stack([ds[f"normal_{a}"].values for a in "xyz"], axis=-1)[scan.found]
    if len(pts):
        ax.scatter(*pts.T, color="tab:red", s=8, depthshade=False, label="measured points")
        length = (
            0.5
            * max(float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 1])), 1.0)
            / max(1.0, np.sqrt(len(pts)))
        )
        ax.quiver(*pts.T, *(normals * length).T, color="tab:orange", lw=0.8)
    probe = np.stack(
        [*np.meshgrid(ds["x"].values, ds["y"].values), ds["probe_z"].values], axis=-1
    ).reshape(-1, 3)
    ax.scatter(*(probe * _MM).T, color="0.5", s=3, marker=".", label="probe positions")
    ax.legend(loc="upper left")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    _equal_axes(ax, np.vstack([pts, probe * _MM]) if len(pts) else probe * _MM)
    ax.set_title("reconstructed surface points over the specimen")
    return fig


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
    written: list[Path] = []
    for name, fig in figures.items():
        written += save_figure(fig, folder / f"{name}.png", formats=formats)
    return written
