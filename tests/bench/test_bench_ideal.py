"""The ideal bench changes nothing: with every field at its default (an explicit, empty
``[bench]`` table) the A-scans and a whole calibration are bit for bit those of the same
setup without one; a bench that only costs time measures the same A-scans too."""

from __future__ import annotations

import numpy as np
from _bench_setups import bench_setup, timed_tilts

from echocal.calibrate import calibrate
from echocal.geometry import Pose
from echocal.measurement import SourceObjective

IDEAL = """
[bench.probe]
squint = [0, 0]
[bench.positioner.tilt_x]
backlash = 0
[bench.receiver]
noise_ar = []
"""
TIMED = '[bench.positioner]\nacquisition_time = "2 ms"\n' + timed_tilts(20, "50 ms")


def _poses(setup):
    x, y, z = setup.reference_position
    return [Pose.from_tilt(x, y, z, tx, ty) for tx, ty in [(0, 0), (2, -1), (-3, 0.5), (2, -1)]]


def test_an_ideal_bench_table_measures_bit_for_bit_what_no_bench_does(tmp_path):
    plain, _ = bench_setup(tmp_path)
    ideal, _ = bench_setup(tmp_path, IDEAL)
    assert ideal.bench is None  # the ideal bench is the plain simulator
    a = np.stack([s.samples for s in plain.measure_many(_poses(plain))])
    b = np.stack([s.samples for s in ideal.measure_many(_poses(ideal))])
    np.testing.assert_array_equal(a, b)


def test_a_bench_that_only_costs_time_measures_the_same_scans_and_counts_the_time(tmp_path):
    plain, _ = bench_setup(tmp_path)
    timed, _ = bench_setup(tmp_path, TIMED)
    scans = timed.measure_many(_poses(timed))
    a = np.stack([s.samples for s in plain.measure_many(_poses(plain))])
    np.testing.assert_array_equal(a, np.stack([s.samples for s in scans]))
    # expected, by hand: the axes move together (the longer travel / 20 deg/s), settle
    # 50 ms after any move, acquire 2 ms; the first pose is where the positioner starts
    travel = [0.0, 2.0, 5.0, 5.0]  # max |Δtilt| of each visit [deg]
    expected = [t / 20.0 + (0.05 if t else 0.0) + 0.002 for t in travel]
    np.testing.assert_allclose([s.metadata["bench_time"] for s in scans], expected, rtol=1e-12)
    np.testing.assert_allclose(scans[-1].metadata["bench_clock"], sum(expected), rtol=1e-12)


def test_a_calibration_on_a_timed_bench_is_unchanged_and_reports_its_time(tmp_path):
    # (the ideal table builds the plain simulator itself: see the first test)
    runs = []
    for bench in ("", TIMED):
        setup, _ = bench_setup(tmp_path, bench, seed=11)
        objective = SourceObjective(setup, setup.reference_position, parameterization="tilt")
        runs.append(calibrate(objective, method="auto", x0=[1.5, -1.0], rng=5))
    plain, timed = runs
    np.testing.assert_array_equal(timed.x, plain.x)
    np.testing.assert_array_equal(timed.points, plain.points)
    assert timed.n_measurements == plain.n_measurements
    assert plain.bench_time is None
    assert timed.bench_time is not None
    # at least the acquisition time of every measurement, and motion besides
    assert timed.bench_time > 0.002 * timed.n_measurements
