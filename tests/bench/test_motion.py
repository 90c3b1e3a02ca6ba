"""Motion-aware ordering: a short path through each batch, and the bench time it saves."""

from __future__ import annotations

import numpy as np
from _bench_setups import bench_setup, timed_tilts

from echocal.bench.motion import move_times, short_order
from echocal.calibrate import calibrate
from echocal.measurement import SourceObjective

AXES = timed_tilts(10, "20 ms")


def test_move_times_by_hand_and_a_raster_becomes_a_serpentine():
    speeds, settling = np.array([10.0, 5.0]), np.array([0.02, 0.05])
    tilts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [1.0, 1.0]])
    # by hand: no move; tilt_x 1° at 10°/s + 20 ms; tilt_y 1° at 5°/s + 50 ms; no move
    np.testing.assert_allclose(move_times(tilts, None, speeds, settling), [0, 0.12, 0.25, 0])
    # two rows of a raster, both left to right, from the start of the first
    row = np.arange(4.0)
    raster = np.concatenate(
        [np.column_stack([row, np.zeros(4)]), np.column_stack([row, np.ones(4)])]
    )
    order = short_order(raster, raster[0], np.ones(2), np.zeros(2))
    np.testing.assert_array_equal(order, [0, 1, 2, 3, 7, 6, 5, 4])


def test_a_motion_aware_grid_finds_the_same_optimum_in_less_bench_time(tmp_path):
    runs = []
    for aware in (False, True):
        setup, _ = bench_setup(tmp_path, AXES, seed=2)
        objective = SourceObjective(
            setup, setup.reference_position, parameterization="tilt", motion_aware=aware
        )
        runs.append(calibrate(objective, method="grid", x0=[0.0, 0.0], span=2.0, step=0.5, rng=1))
    plain, aware = runs
    assert aware.n_measurements == plain.n_measurements
    np.testing.assert_allclose(aware.x, plain.x, atol=1e-12)  # the same grid's best point
    assert plain.bench_time_saved is None
    # the rows are 9 points (4° wide at 10°/s); the plain raster flies back 4° per row,
    # the serpentine steps 0.5°: 8 × (0.4 − 0.05) s saved, predicted and measured alike
    np.testing.assert_allclose(aware.bench_time_saved, 8 * 0.35, rtol=1e-9)
    np.testing.assert_allclose(plain.bench_time - aware.bench_time, 8 * 0.35, rtol=1e-9)
    assert aware.bench_time < 0.7 * plain.bench_time
