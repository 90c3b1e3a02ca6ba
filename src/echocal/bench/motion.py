"""Motion-aware ordering: visit a batch of orientations along a short path.

A positioner's axes move together, so going from one orientation to the next takes the
longer axis's travel / speed plus the settling of the axes that moved (see
:mod:`echocal.bench.positioner`).  :func:`short_order` orders a batch greedily — always
the point reached soonest from where the probe is — and :func:`move_times` predicts what
an order costs; their difference against the batch's plain order is the bench time the
ordering saves.  Tilts [deg], shapes ``(k, 2)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["move_times", "reach_times", "short_order"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


def _step_costs(origin: FloatArray, targets: FloatArray, speeds: FloatArray, settling: FloatArray):
    """[s] the moves from ``origin`` ``(..., 2)`` to ``targets`` ``(..., 2)``."""
    delta = np.abs(targets - origin)
    moved = delta > 0.0
    travel = np.where(moved, delta / speeds, 0.0).max(axis=-1)
    return travel + np.where(moved, settling, 0.0).max(axis=-1)


def reach_times(
    origin: FloatArray, targets: FloatArray, speeds: FloatArray, settling: FloatArray
) -> FloatArray:
    """[s] the move from ``origin`` [deg] ``(2,)`` to each of ``targets`` [deg] ``(k, 2)``,
    ``(k,)``: the longer axis's travel / ``speeds`` [deg/s] ``(2,)`` plus the longest
    ``settling`` [s] ``(2,)`` of the axes that move (0 for the origin itself)."""
    origin = np.asarray(origin, dtype=np.float64)[None]
    return np.asarray(_step_costs(origin, targets, speeds, settling), dtype=np.float64)


def move_times(
    tilts: FloatArray, start: FloatArray | None, speeds: FloatArray, settling: FloatArray
) -> FloatArray:
    """[s] each visit's move, ``(k,)``, visiting ``tilts`` [deg] ``(k, 2)`` in order from
    ``start`` [deg] ``(2,)`` (None: from the first point, which costs nothing), the
    (tilt_x, tilt_y) axes at ``speeds`` [deg/s] ``(2,)`` with ``settling`` [s] ``(2,)``."""
    origin = tilts[:1] if start is None else np.asarray(start, dtype=np.float64)[None]
    previous = np.vstack([origin, tilts[:-1]])
    return np.asarray(_step_costs(previous, tilts, speeds, settling), dtype=np.float64)


def short_order(
    tilts: FloatArray, start: FloatArray | None, speeds: FloatArray, settling: FloatArray
) -> IntArray:
    """The order ``(k,)`` in which to visit ``tilts`` [deg] ``(k, 2)`` from ``start`` [deg]
    ``(2,)`` (None: from the first point): greedily the point reached soonest next; among
    equally quick ones the nearest in angle, then the earlier (so a batch already in a
    short order keeps it)."""
    k = len(tilts)
    left = np.ones(k, dtype=bool)
    order = np.empty(k, dtype=np.intp)
    here = tilts[0] if start is None else np.asarray(start, dtype=np.float64)
    for i in range(k):
        cost = _step_costs(here, tilts, speeds, settling)
        # among equally quick moves (the axes move together) the shortest in angle
        distance = np.hypot(*(tilts - here).T)
        key = np.lexsort((np.arange(k), distance, np.where(left, cost, np.inf)))
        nearest = int(key[0])
        order[i] = nearest
        left[nearest] = False
        here = tilts[nearest]
    return order
