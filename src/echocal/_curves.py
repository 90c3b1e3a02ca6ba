"""Small numeric helpers on sampled curves, shared by modules of different layers."""

from __future__ import annotations

import numpy as np

__all__ = ["first_crossing"]


def first_crossing(angles: np.ndarray, values: np.ndarray, level: float) -> float:
    """[deg] the largest angle up to which ``values`` (at ``angles`` [deg], ascending,
    shape ``(n,)``) stay ≥ ``level``: linear interpolation between the last angle above
    and the first below; 0 when the first falls short, ``angles[-1]`` when none does."""
    below = np.flatnonzero(values < level)
    if below.size == 0:
        return float(angles[-1])
    k = int(below[0])
    if k == 0:
        return 0.0
    a0, a1, v0, v1 = angles[k - 1], angles[k], values[k - 1], values[k]
    return float(a0 + (v0 - level) * (a1 - a0) / (v0 - v1))
