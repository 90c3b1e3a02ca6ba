"""The simulator's ground truth: the orientation of maximum echo, found without the noise
or the counting that calibration methods live with (:meth:`VirtualSetup.true_optimum`).

Kept apart from measuring: an algorithm under test cannot peek.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.optimize
from numpy.typing import NDArray

from echocal.geometry import orientation_frame, orientation_to_tilt, tilt_frame, tilt_to_orientation

__all__ = ["pose_arrays", "search_optimum"]

FloatArray = NDArray[np.float64]

_SIMPLEX_SIZE = 0.25
"""[deg] the first Nelder–Mead simplex's edge around the best candidate."""
_XATOL = 1e-5
"""[deg] Nelder–Mead's tolerance on the optimum."""


def search_optimum(
    metric: Callable[[FloatArray, FloatArray], FloatArray], candidates: FloatArray
) -> tuple[float, float]:
    """Tilts (tx, ty) [deg] of the maximum of ``metric(tx, ty)`` (noiseless, vectorized over
    arrays of tilts [deg]): the best of ``candidates`` ``(n, 2)`` [deg] (the directions of
    normal incidence on the surface: every local maximum of a smooth surface's echo lies
    near one), refined by Nelder–Mead to 1e-5° in gimbal tilts (smooth at the pole, where
    most optima lie)."""
    scores = metric(candidates[:, 0], candidates[:, 1])
    start = candidates[int(np.argmax(scores))]

    def negative(v: FloatArray) -> float:
        return -float(metric(np.asarray(v[0]), np.asarray(v[1])))

    best = scipy.optimize.minimize(
        negative,
        start,
        method="Nelder-Mead",
        options={
            "xatol": _XATOL,
            "fatol": 0.0,
            "initial_simplex": start
            + np.array([[0.0, 0.0], [_SIMPLEX_SIZE, 0.0], [0.0, _SIMPLEX_SIZE]]),
        },
    )
    return float(best.x[0]), float(best.x[1])


def pose_arrays(
    position: FloatArray, a: FloatArray, b: FloatArray, parameterization: str
) -> tuple[FloatArray, FloatArray]:
    """Positions ``(P, 3)`` [m] and frames ``(P, 3, 3)`` of orientations ``(a, b)`` [deg],
    ``(P,)``, at one ``position`` ``(3,)`` [m].

    The vectorized equivalent of ``poses_to_arrays([pose_from_angles(...), ...])``: a tilt
    pose goes through the same (azimuth, co-elevation) round trip as ``Pose.from_tilt``.
    """
    positions = np.broadcast_to(position, (a.size, 3))
    if parameterization == "tilt":
        azimuth, coelevation = tilt_to_orientation(a, b)
        return positions, tilt_frame(*orientation_to_tilt(azimuth, coelevation))
    return positions, orientation_frame(a, b)
