"""Ground truth of a surface scan, for sources that know their specimen (the simulator).

A surface map claims "the surface passes through q with normal n".  Both claims are
judged at the measured point itself:

* ``normal_error`` — the angle between the measured normal n and the true upward
  normal of the surface straight below q = (q_x, q_y);
* ``height_error`` — q_z minus the true surface height straight below (q_x, q_y).

Judging at the measured point (rather than against the orientation of maximum echo at
the probe position) stays meaningful where a probe position sees several surface
patches square-on — a faceted part where the beam may legitimately lock onto the
neighbouring facet.  On a curved part an orientation error δ also moves q sideways by
about d·δ (d the water path), which changes the true normal there by d·δ/R, so this
error is at most δ·(1 + d/R): conservative by that factor.

Why not ``VirtualSetup.true_optimum``: it costs a Nelder–Mead of full simulations per
point, and it starts from the normal straight *below* the probe, which over a curved
part can be several beam widths from the optimum, where a narrow beam's pulse-echo
directivity has side lobes that trap the search (seen with ``scan-5mhz`` over the
sphere at x = 10 mm: 14° off).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from echocal.geometry import angle_between
from echocal.specimen import Specimen

__all__ = ["height_errors", "normal_errors"]

FloatArray = NDArray[np.float64]


def _below(specimen: Specimen, points: FloatArray) -> tuple[FloatArray, FloatArray]:
    """True surface points and upward normals below ``points`` (k, 3); NaN where none."""
    out_p = np.full(points.shape, np.nan)
    out_n = np.full(points.shape, np.nan)
    ok = np.all(np.isfinite(points), axis=1)
    if np.any(ok):
        hits = specimen.surface_below(points[ok, 0], points[ok, 1])
        out_p[ok] = np.where(hits.hit[:, None], hits.point, np.nan)
        out_n[ok] = np.where(hits.hit[:, None], hits.normal, np.nan)
    return out_p, out_n


def normal_errors(specimen: Specimen, points: FloatArray, normals: FloatArray) -> FloatArray:
    """[deg] angle between measured unit ``normals`` (k, 3) and the true normal below the
    measured ``points`` [m] (k, 3), shape (k,); NaN where either is missing."""
    _, true_n = _below(specimen, points)
    out = np.full(len(points), np.nan)
    ok = np.all(np.isfinite(true_n), axis=1) & np.all(np.isfinite(normals), axis=1)
    if np.any(ok):
        out[ok] = angle_between(normals[ok], true_n[ok])
    return out


def height_errors(specimen: Specimen, points: FloatArray) -> FloatArray:
    """[m] measured z minus the true surface z below each measured point (k, 3) -> (k,)."""
    surface, _ = _below(specimen, points)
    return points[:, 2] - surface[:, 2]
