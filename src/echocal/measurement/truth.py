"""The simulator's ground truth: the orientation of maximum echo, found without the noise
or the counting that calibration methods live with (:meth:`VirtualSetup.true_optimum`).

Kept apart from measuring: an algorithm under test cannot peek.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from echocal.errors import EchocalValueError
from echocal.geometry import orientation_frame, orientation_to_tilt, tilt_frame, tilt_to_orientation

__all__ = ["EQUAL_OPTIMUM_RATIO", "pose_arrays", "search_optima", "search_optimum"]

FloatArray = NDArray[np.float64]

EQUAL_OPTIMUM_RATIO = 0.98
"""A maximum reaching this fraction of the global one is an optimum too: the optimum is
not unique (a rod's two humps), and a run that ends on either has found it."""
_SIMPLEX_SIZE = 0.25
"""[deg] the first Nelder–Mead simplex's edge around a start."""
_XATOL = 1e-5
"""[deg] Nelder–Mead's tolerance on the optimum."""
_SCOUT_RADII = (1.0, 2.0, 3.0)
"""[deg] rings scouted around each candidate: a curved part's humps lie a few degrees
either side of normal incidence (a 12.7 mm probe over a 20 mm rod: 1.8° and 5.2°)."""
_SCOUT_DIRECTIONS = 12
"""Points per scouted ring."""
_SCOUTED_CANDIDATES = 3
"""The best candidates whose surroundings are scouted."""
_BASIN = 1.5
"""[deg] a start this close to a found optimum (or to the start that found it) is taken
to climb the same hump."""
_WORTH_CLIMBING = 0.5
"""A start below this fraction of the best optimum found is not refined."""
_MAX_CLIMBS = 4
"""At most this many Nelder–Mead refinements."""
_SCOUT_XATOL = 0.01
"""[deg] the short climb's tolerance on a side hump (a ring, a second hump)."""
_SCOUT_EVALUATIONS = 60
"""The short climb's metric calls: a side hump below :data:`EQUAL_OPTIMUM_RATIO` of the
best costs no more; one above it is refined to :data:`_XATOL`."""
_SAME_OPTIMUM = 0.01
"""[deg] two refinements ending closer than this found the same optimum."""


def _scout_points(candidates: FloatArray) -> FloatArray:
    """Tilts [deg] ``(n, 2)``: ``candidates`` ``(c, 2)`` and rings of :data:`_SCOUT_RADII`
    around the first :data:`_SCOUTED_CANDIDATES` of them."""
    angle = np.linspace(0.0, 2.0 * np.pi, _SCOUT_DIRECTIONS, endpoint=False)
    ring = np.concatenate(
        [r * np.stack([np.cos(angle), np.sin(angle)], axis=1) for r in _SCOUT_RADII]
    )
    around = candidates[:_SCOUTED_CANDIDATES, None, :] + ring[None, :, :]
    return np.concatenate([candidates, around.reshape(-1, 2)])


def _scores(
    metric: Callable[[FloatArray, FloatArray], FloatArray], points: FloatArray
) -> FloatArray:
    """``metric`` at ``points`` ``(n, 2)`` [deg] in one call; where the batch is refused (a
    scouted direction whose echo misses the recording window), point by point, a refused
    point scoring −inf; when every point is refused (a position inside the part), the batch's
    refusal is raised."""
    try:
        return np.asarray(metric(points[:, 0], points[:, 1]), dtype=np.float64)
    except EchocalValueError as refused:
        out = np.full(len(points), -np.inf)
        for i, (a, b) in enumerate(points):
            try:
                out[i] = float(metric(np.asarray(a), np.asarray(b)))
            except EchocalValueError:
                continue
        if not np.isfinite(out).any():
            raise refused from None
        return out


def _climb(
    metric: Callable[[FloatArray, FloatArray], FloatArray],
    start: FloatArray,
    xatol: float = _XATOL,
    max_evaluations: int | None = None,
) -> tuple[FloatArray, float]:
    """Nelder–Mead from ``start`` [deg] to ``xatol`` [deg] (within ``max_evaluations``
    metric calls, if given): (top [deg] (2,), its value)."""
    import scipy.optimize  # lazy: costs a CLI start 0.3 CPU-s

    def negative(v: FloatArray) -> float:
        return -float(metric(np.asarray(v[0]), np.asarray(v[1])))

    best = scipy.optimize.minimize(
        negative,
        start,
        method="Nelder-Mead",
        options={
            "xatol": xatol,
            "fatol": 0.0,
            "maxfev": max_evaluations,
            "initial_simplex": start
            + np.array([[0.0, 0.0], [_SIMPLEX_SIZE, 0.0], [0.0, _SIMPLEX_SIZE]]),
        },
    )
    return np.asarray(best.x, dtype=np.float64), -float(best.fun)


def search_optima(
    metric: Callable[[FloatArray, FloatArray], FloatArray], candidates: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Every distinct maximum of ``metric(tx, ty)`` (noiseless, vectorized over arrays of
    tilts [deg]) found near ``candidates`` ``(c, 2)`` [deg], best first: tilts ``(m, 2)``
    [deg] and values ``(m,)``.

    The candidates (the directions of normal incidence on the surface, best first) and
    rings 1–3° around the best three are evaluated in one call. Then, repeatedly, the best
    start not within :data:`_BASIN` of a hump already climbed is refined by Nelder–Mead
    to 1e-5° in gimbal tilts (smooth at the pole), while it is worth
    :data:`_WORTH_CLIMBING` of the best maximum found (at most :data:`_MAX_CLIMBS`
    times); a hump after the first is climbed to 0.01° only, unless it reaches
    :data:`EQUAL_OPTIMUM_RATIO` of the best (a ring around a ball's central peak costs a
    short climb). A part with two humps near one normal (a rod under an off-axis probe) so
    yields both, and the global maximum is the first, whichever the candidate pointed at.
    """
    starts = _scout_points(np.asarray(candidates, dtype=np.float64).reshape(-1, 2))
    scores = _scores(metric, starts)
    order = np.argsort(-scores, kind="stable")
    starts, scores = starts[order], scores[order]
    optima: list[FloatArray] = []
    values: list[float] = []
    climbed: list[FloatArray] = []
    for _ in range(_MAX_CLIMBS):
        taken = np.vstack([*optima, *climbed]) if climbed else np.empty((0, 2))
        far = np.all(
            np.hypot(*(starts[:, None, :] - taken[None, :, :]).transpose(2, 0, 1)) > _BASIN, axis=1
        )
        if not far.any():
            break
        i = int(np.argmax(far))  # the best start outside every climbed basin
        if not np.isfinite(scores[i]) or (values and scores[i] < _WORTH_CLIMBING * max(values)):
            break
        if values:  # a side hump: a short climb tells whether it rivals the best one
            top, value = _climb(metric, starts[i], _SCOUT_XATOL, _SCOUT_EVALUATIONS)
            if value >= EQUAL_OPTIMUM_RATIO * max(values):
                top, value = _climb(metric, top)
        else:
            top, value = _climb(metric, starts[i])
        climbed.append(starts[i])
        if all(np.hypot(*(top - o)) > _SAME_OPTIMUM for o in optima):
            optima.append(top)
            values.append(value)
    rank = np.argsort(-np.asarray(values), kind="stable")
    return np.asarray(optima)[rank], np.asarray(values)[rank]


def search_optimum(
    metric: Callable[[FloatArray, FloatArray], FloatArray], candidates: FloatArray
) -> tuple[float, float]:
    """Tilts (tx, ty) [deg] of the global maximum of ``metric`` found by
    :func:`search_optima` from ``candidates`` ``(c, 2)`` [deg]."""
    optima, _ = search_optima(metric, candidates)
    return float(optima[0, 0]), float(optima[0, 1])


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
