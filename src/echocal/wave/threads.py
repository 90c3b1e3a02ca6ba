"""The two-way SIR correlation of many surface samples, split over the machine's cores.

:func:`echocal.wave.sir.accumulate_two_way` releases the GIL (numba ``nogil``), so
interleaved shares of the samples run on a few threads at once, each into its own grid;
the grids are summed in a fixed order, so the result does not depend on the thread timing.
Small jobs (fewer than :data:`MIN_SAMPLES_PER_THREAD` samples a thread) run in the calling
thread: a thread's start costs about 20 µs, one sample 5–10 µs.

The pools are fork-safe: a child forked after the parent used one (``multiprocessing``'s
default start method on Linux) starts with none of the parent's threads, so its inherited
pool would queue work that no thread ever takes; the child forgets the pools at the fork
(``os.register_at_fork``) and makes its own on first use.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import cache

import numpy as np
from numpy.typing import NDArray

from echocal.wave import sir

__all__ = [
    "MAX_THREADS",
    "MIN_NODES_PER_THREAD",
    "MIN_SAMPLES_PER_THREAD",
    "PAIRS_PER_NODE",
    "cores",
    "one_way_grid",
    "pool",
    "split",
    "two_way_grid",
]

FloatArray = NDArray[np.float64]

MAX_THREADS = 4
"""At most this many threads share one A-scan (fewer on a machine with fewer cores)."""
MIN_SAMPLES_PER_THREAD = 128
"""A thread is worth starting for at least this many surface samples (two-way kernel)."""
MIN_NODES_PER_THREAD = 1024
"""The same for the one-way kernel of the image form, 4–5 times cheaper per point."""
PAIRS_PER_NODE = 2
"""The image form's pair rule (:mod:`echocal.wave.pairs`) starts a thread for this many
times :data:`MIN_NODES_PER_THREAD` pairs: a pair costs 0.2–0.7 µs, a face node 1–7 µs."""


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS, Windows
        return os.cpu_count() or 1


@cache
def pool(workers: int) -> ThreadPoolExecutor:
    """One shared pool of ``workers`` threads (made once per size)."""
    return ThreadPoolExecutor(max_workers=workers, thread_name_prefix="echocal-wave")


def _forget_pools() -> None:
    """In a forked child: drop the parent's pools (their threads did not survive the fork)."""
    pool.cache_clear()


if hasattr(os, "register_at_fork"):  # not on Windows, which never forks
    os.register_at_fork(after_in_child=_forget_pools)


def two_way_grid(
    kind: int,
    prm: FloatArray,
    points: FloatArray,
    unit_m: FloatArray,
    weights: FloatArray,
    delays: FloatArray,
    c: float,
    t0: float,
    dt: float,
    n_grid: int,
    n_scratch: int,
) -> tuple[FloatArray, float, float]:
    """Σₛ wₛ·(h̄ₛ * h̄_m,ₛ) on a grid of ``n_grid`` points (the arguments and the two sums
    returned after the grid are those of :func:`echocal.wave.sir.accumulate_two_way`;
    ``n_scratch`` from :func:`echocal.wave.sir.scratch_bins`).

    Returns
    -------
    grid : ``(n_grid,)``; Σₛ |wₛ|·(two-way time of s) [s·weight]; Σₛ |wₛ|.
    """

    def kernel(grid: FloatArray, share: NDArray[np.intp]) -> tuple[float, float]:
        scratch = np.zeros((5, 2 * n_scratch))
        return sir.accumulate_two_way(
            kind,
            prm,
            np.ascontiguousarray(points[:, share]),
            np.ascontiguousarray(unit_m[:, share]),
            np.ascontiguousarray(weights[share]),
            np.ascontiguousarray(delays[share], dtype=np.float64),
            c,
            t0,
            dt,
            grid,
            scratch,
        )

    return split(weights, n_grid, kernel, MIN_SAMPLES_PER_THREAD)


def split(
    weights: FloatArray,
    n_grid: int,
    kernel: Callable[[FloatArray, NDArray[np.intp]], tuple[float, float]],
    per_thread: int,
) -> tuple[FloatArray, float, float]:
    """Run ``kernel(grid, share)`` on interleaved shares of the samples with non-zero
    weight, each share into its own grid of ``n_grid`` points on its own thread (one share,
    in this thread, for fewer than ``per_thread`` samples a thread); sum the grids in a
    fixed order and the two sums."""
    active = np.flatnonzero(weights)
    n_threads = max(1, min(MAX_THREADS, cores(), active.size // per_thread))

    def run(share: NDArray[np.intp]) -> tuple[FloatArray, float, float]:
        grid = np.zeros(n_grid)
        swt, sw = kernel(grid, share)
        return grid, float(swt), float(sw)

    shares = [active[i::n_threads] for i in range(n_threads)]
    if n_threads == 1:
        return run(shares[0])
    results = list(pool(n_threads).map(run, shares))
    grid = results[0][0]
    for other, _, _ in results[1:]:
        grid += other
    return grid, sum(r[1] for r in results), sum(r[2] for r in results)


def one_way_grid(
    kind: int,
    prm: FloatArray,
    points: FloatArray,
    weights: FloatArray,
    delays: FloatArray,
    c: float,
    t0: float,
    dt: float,
    n_grid: int,
) -> tuple[FloatArray, float, float]:
    """Σₛ wₛ·h̄ₛ on a grid of ``n_grid`` points (the arguments and the two sums returned
    after the grid are those of :func:`echocal.wave.sir.accumulate_one_way`), split over
    threads like :func:`two_way_grid`.

    Returns
    -------
    grid : ``(n_grid,)``; Σₛ |wₛ|·(time of s) [s·weight]; Σₛ |wₛ|.
    """
    n_scratch = sir.scratch_bins(c, dt, 2.0 * float(prm[0]))

    def kernel(grid: FloatArray, share: NDArray[np.intp]) -> tuple[float, float]:
        scratch = np.zeros((4, n_scratch))
        return sir.accumulate_one_way(
            kind,
            prm,
            np.ascontiguousarray(points[:, share]),
            np.ascontiguousarray(weights[share]),
            np.ascontiguousarray(delays[share], dtype=np.float64),
            c,
            t0,
            dt,
            grid,
            scratch,
        )

    return split(weights, n_grid, kernel, MIN_NODES_PER_THREAD)
