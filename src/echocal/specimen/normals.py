"""Where a beam from a point meets a specimen's surface at normal incidence.

Over a smooth part the echo of a physical probe peaks where the beam meets the surface at
normal incidence, also inside a bore or off the axis of a sphere, where the surface
straight below would aim a search at a side lobe.  These directions seed the search for
the true optimum (:meth:`echocal.measurement.VirtualSetup.true_optimum`) and the
perpendicular starts of sweeps.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from echocal.errors import GeometryError
from echocal.geometry import tilt_normal
from echocal.specimen.casting import Hits, cast
from echocal.specimen.specimen import Specimen

__all__ = ["normal_incidence_directions", "perpendicular_start"]

FloatArray = NDArray[np.float64]

_HALF_SPAN = 60.0
"""[deg] the fan of beam directions searched: within this tilt of straight down."""


def _fan_hits(
    specimen: Specimen, position: FloatArray, step: float
) -> tuple[FloatArray, FloatArray, FloatArray, Hits]:
    """Tilts ``tx``, ``ty`` [deg] of a square fan of ``step`` [deg] within ±60° of straight
    down (grids ``(n, n)``), the beam directions ``(n·n, 3)`` and their closest hits."""
    grid = np.arange(-_HALF_SPAN, _HALF_SPAN + step / 2, step)
    tx, ty = np.meshgrid(grid, grid, indexing="ij")
    directions = -tilt_normal(tx.ravel(), ty.ravel())
    hits = cast(specimen, np.broadcast_to(position, directions.shape), directions)
    if not np.any(hits.hit):
        raise GeometryError(
            f"no surface within {_HALF_SPAN:g}° of straight down from position "
            f"({position[0]:g}, {position[1]:g}, {position[2]:g}) m; "
            "the optimum is undefined there"
        )
    return tx, ty, directions, hits


def normal_incidence_directions(
    specimen: Specimen, position: FloatArray, *, limit: int = 6
) -> FloatArray:
    """Tilts [deg], shape ``(n, 2)`` with n ≤ ``limit`` + 1, of the beam from ``position``
    [m] at normal incidence on the surface: the local maxima of |cos| of the angle of
    incidence over a 0.5° fan within ±60° of straight down, best first, then the nearest
    surface point (:func:`perpendicular_start`; alone when nothing is closer than 2° to
    normal).

    Raises
    ------
    GeometryError : no surface within ±60° of straight down.
    """
    tx, ty, directions, hits = _fan_hits(specimen, position, 0.5)
    n_x, n_y = int(tx.shape[0]), int(tx.shape[1])
    cosine = np.where(hits.hit, -np.sum(hits.normal * directions, axis=-1), -1.0)
    cosine = cosine.reshape(n_x, n_y)
    padded = np.pad(cosine, 1, constant_values=-1.0)
    peak = np.ones_like(cosine, dtype=bool)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            if dx or dy:  # a local maximum: not below any of its eight neighbours
                peak &= cosine >= padded[1 + dx : 1 + dx + n_x, 1 + dy : 1 + dy + n_y]
    peak &= cosine > math.cos(math.radians(2.0))
    order = np.argsort(-cosine[peak])
    found = np.stack([tx[peak], ty[peak]], axis=1)[order][:limit]
    nearest = perpendicular_start(specimen, position)
    return np.vstack([found, nearest[None]]) if found.size else nearest[None]


def perpendicular_start(specimen: Specimen, position: FloatArray) -> FloatArray:
    """Tilts [deg], shape ``(2,)``, of the beam from ``position`` [m] towards the nearest
    surface point within ±60° (1° fan): the distance to a smooth surface is stationary
    where the ray meets it at normal incidence.

    Raises
    ------
    GeometryError : no surface within ±60° of straight down.
    """
    tx, ty, _, hits = _fan_hits(specimen, position, 1.0)
    nearest = int(np.argmin(hits.distance))
    return np.array([tx.ravel()[nearest], ty.ravel()[nearest]])
