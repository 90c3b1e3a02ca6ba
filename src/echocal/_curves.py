"""Small numeric helpers on sampled curves, shared by modules of different layers."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["first_crossing", "increasing_root"]


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


def increasing_root(f: Callable[[float], float], lo: float, hi: float, xtol: float) -> float:
    """The root of ``f`` (increasing, ``f(lo) ≤ 0 ≤ f(hi)``) in [lo, hi], to ``xtol`` by
    bisection: the midpoint of the last bracket narrower than ``xtol``.

    Plain bisection rather than scipy.optimize.brentq: importing scipy.optimize costs a
    command-line start about 0.3 CPU-s for a root that needs about 40 evaluations.
    """
    while hi - lo > xtol:
        mid = 0.5 * (lo + hi)
        if f(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
