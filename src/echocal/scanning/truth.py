"""Ground truth of a surface scan, for sources that know their specimen (the simulator).

For each probe position p the *true* surface normal is the normal at the foot of the
perpendicular from p onto the surface — the surface point q* nearest to p, where the
normal points back at the probe.  Firing along that normal is the orientation of
maximum echo for a beam that is narrow compared with the curvature (by symmetry exact
on planes, spheres and cylinders).  q* is found by a local search over (x, y) of the
points below, started where the scan says the surface is.

Why not ``VirtualSetup.true_optimum``: it costs a Nelder–Mead of full simulations per
point, and it starts from the normal straight *below* p, which over a curved part can
be several beam widths away from the optimum, where a narrow beam's pulse-echo
directivity has side lobes that trap the search.

The height error compares the measured surface point with the true surface straight
below it: ``z_measured − z_surface(x_measured, y_measured)``.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize
from numpy.typing import NDArray

from echocal.geometry import angle_between
from echocal.specimen import Specimen

__all__ = ["height_errors", "normal_errors", "perpendicular_foot"]

FloatArray = NDArray[np.float64]


def _surface(specimen: Specimen, xy: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(points (k, 3), upward normals (k, 3)) below ``xy`` (k, 2); NaN where nothing."""
    hits = specimen.surface_below(xy[:, 0], xy[:, 1])
    point = np.where(hits.hit[:, None], hits.point, np.nan)
    normal = np.where(hits.hit[:, None], hits.normal, np.nan)
    return point, normal


def perpendicular_foot(
    specimen: Specimen, position: FloatArray, start: FloatArray, *, tol: float = 1e-9
) -> tuple[FloatArray, FloatArray]:
    """Surface point [m] nearest to ``position`` (3,) and its upward normal, searched from
    ``start`` [m] (2,) = (x, y); NaN if no surface is found near ``start``."""
    x0 = np.asarray(start, dtype=np.float64)

    def squared(xy: FloatArray) -> float:
        point, _ = _surface(specimen, xy[None, :])
        if not np.all(np.isfinite(point)):
            return 1e6  # off the part: far worse than any real distance [m²]
        return float(np.sum((point[0] - position) ** 2))

    if squared(x0) >= 1e6:
        return np.full(3, np.nan), np.full(3, np.nan)
    step = 1e-3
    simplex = x0 + np.array([[0.0, 0.0], [step, 0.0], [0.0, step]])
    best = scipy.optimize.minimize(
        squared,
        x0,
        method="Nelder-Mead",
        options={"xatol": tol, "fatol": 0.0, "initial_simplex": simplex, "maxiter": 2000},
    )
    point, normal = _surface(specimen, best.x[None, :])
    return point[0], normal[0]


def normal_errors(
    specimen: Specimen, positions: FloatArray, points: FloatArray, normals: FloatArray
) -> FloatArray:
    """[deg] angle between measured ``normals`` and the true normal at the perpendicular
    foot of each probe position, shape (k,); NaN where the measurement is missing.

    positions : [m] probe positions (k, 3); points : [m] measured surface points (k, 3)
    (where each search starts); normals : measured unit normals (k, 3).
    """
    out = np.full(len(positions), np.nan)
    for i, (p, q, n) in enumerate(zip(positions, points, normals, strict=True)):
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(n))):
            continue
        _, true_n = perpendicular_foot(specimen, p, q[:2])
        if np.all(np.isfinite(true_n)):
            out[i] = float(angle_between(n, true_n))
    return out


def height_errors(specimen: Specimen, points: FloatArray) -> FloatArray:
    """[m] measured z minus the true surface z below each measured point (k, 3) -> (k,)."""
    out = np.full(len(points), np.nan)
    ok = np.all(np.isfinite(points), axis=1)
    if np.any(ok):
        surface, _ = _surface(specimen, points[ok, :2])
        out[ok] = points[ok, 2] - surface[:, 2]
    return out
