"""Bit-reproducible linear algebra: one BLAS thread while a calibration runs.

OpenBLAS, which numpy and scipy ship, splits some routines over its thread pool, and a
split result is not bit-identical from call to call: the same least-squares fit of the
model-based method (``scipy.optimize.least_squares``, identical input) gave coefficients
differing in the 15th digit depending on what the process had computed before.  Over a
run, such a last-bit difference can move one proposed point by 4e-16°, and from there
the run's noise draws differ: 46 of 960 seeded re-runs inside one long-lived process
ended differently, while fresh processes agreed.  With one BLAS thread the same seeded
calibration gives the same numbers whatever ran before.  Calibration's linear algebra
works on matrices of a few dozen rows, where threads only cost time.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import ParamSpec, TypeVar

try:
    from threadpoolctl import threadpool_limits
except ImportError:  # pragma: no cover - a dependency; an install that predates it
    threadpool_limits = None

__all__ = ["one_blas_thread"]

_P = ParamSpec("_P")
_R = TypeVar("_R")


def one_blas_thread(func: Callable[_P, _R]) -> Callable[_P, _R]:
    """Run ``func`` with the BLAS thread pools (numpy's and scipy's) limited to one thread."""

    if threadpool_limits is None:  # pragma: no cover - reinstall echocal to get it
        return func

    @functools.wraps(func)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper
