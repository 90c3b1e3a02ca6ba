"""The positioner: backlash by approach direction, steps, repeatability, move times."""

from __future__ import annotations

import numpy as np
from _bench_setups import bench_setup

from echocal.bench import Axis, PositionerModel, PositionerState
from echocal.geometry import Pose


def _tilt_x_commands(values):
    commands = np.zeros((len(values), 5))
    commands[:, 3] = values
    return commands


def test_backlash_offsets_the_approach_from_above_by_the_backlash():
    state = PositionerState(PositionerModel(tilt_x=Axis(backlash=0.04)))
    # 1.0 from below, 1.0 from above (via 2.0), then from below again (via 0.0)
    reached, _, _ = state.move(
        _tilt_x_commands([0.0, 1.0, 2.0, 1.0, 0.0, 1.0]), np.random.default_rng(0)
    )
    from_below, from_above, again = reached[1, 3], reached[3, 3], reached[5, 3]
    assert from_below == 1.0 and again == 1.0
    np.testing.assert_allclose(from_above - from_below, 0.04, rtol=1e-12)


def test_a_controller_that_approaches_from_below_has_no_backlash_offset_but_travels_more():
    model = PositionerModel(tilt_x=Axis(backlash=0.04, speed=1.0), approach="positive")
    commands = _tilt_x_commands([0.0, 1.0, 2.0, 1.0, 0.0, 1.0])
    reached, motion, _ = PositionerState(model).move(commands, np.random.default_rng(0))
    np.testing.assert_array_equal(reached[:, 3], commands[:, 3])
    # a move down overshoots by the backlash and returns, two reversals' lost motion
    # besides: 4 × 0.04° more travel at 1°/s; moves up travel their distance
    np.testing.assert_allclose(motion, [0.0, 1.0, 1.0, 1.16, 1.16, 1.0], rtol=1e-12)
    assert model.tilt_error == 0.0  # no repeatability, no steps: the backlash is gone


def test_steps_round_and_repeatability_scatters_with_its_sigma():
    state = PositionerState(PositionerModel(tilt_x=Axis(step=0.01, repeatability=0.003)))
    # 20,000 moves alternating between 0.123 and 1.0: each ends at its step (0.12, 1.0)
    # plus a fresh N(0, 0.003²) draw; the sample σ of 10,000 draws is within 3 % (5 σ)
    commands = _tilt_x_commands(np.tile([0.123, 1.0], 10000))
    reached, _, _ = state.move(commands, np.random.default_rng(1))
    lows = reached[2::2, 3]  # every visit to 0.123 after the first (the start: no move)
    np.testing.assert_allclose(lows.mean(), 0.12, atol=5 * 0.003 / np.sqrt(lows.size))
    np.testing.assert_allclose(lows.std(), 0.003, rtol=0.03)
    # an axis that does not move stays where it was: the other axes never drew
    assert np.all(reached[:, [0, 1, 2, 4]] == 0.0)


def test_the_rms_error_of_random_moves_is_the_positioners_stated_error():
    b, s, sigma = 0.05, 0.01, 0.004
    model = PositionerModel(tilt_x=Axis(backlash=b, step=s, repeatability=sigma))
    commands = _tilt_x_commands(np.random.default_rng(4).uniform(-5.0, 5.0, 40000))
    reached, _, _ = PositionerState(model).move(commands, np.random.default_rng(5))
    error = reached[1:, 3] - commands[1:, 3]
    # closed form: repeatability σ², rounding s²/12, and 0 or b half the time (b²/2)
    expected = np.sqrt(sigma**2 + s**2 / 12 + b**2 / 2)
    np.testing.assert_allclose(model.tilt_x.rms_error, expected, rtol=1e-12)
    # 40,000 moves: the RMS to within 2 %
    np.testing.assert_allclose(np.sqrt(np.mean(error**2)), expected, rtol=0.02)
    assert model.tilt_error == model.tilt_x.rms_error  # tilt_y is exact


def test_move_time_is_the_slowest_axis_plus_settling_and_reversals_travel_the_backlash():
    model = PositionerModel(
        tilt_x=Axis(speed=10.0, settling=0.1, backlash=0.5),
        tilt_y=Axis(speed=2.0, settling=0.3),
    )
    state = PositionerState(model)
    commands = np.zeros((3, 5))
    commands[1, 3:] = [5.0, 1.0]  # tilt_x 0.5 s, tilt_y 0.5 s; both settle: 0.3 s
    commands[2, 3:] = [1.0, 1.0]  # tilt_x reverses: (4 + 0.5) / 10 s, settles 0.1 s
    _, motion, settling = state.move(commands, np.random.default_rng(2))
    np.testing.assert_allclose(motion, [0.0, 0.5, 0.45], rtol=1e-12)
    np.testing.assert_allclose(settling, [0.0, 0.3, 0.1], rtol=1e-12)


def test_the_simulator_reports_the_pose_it_reached_and_the_backlash_moves_the_echo(tmp_path):
    setup, _ = bench_setup(
        tmp_path, "[bench.positioner.tilt_x]\nbacklash = 0.5\n", noise="snr_db = 'none'"
    )
    ideal, _ = bench_setup(tmp_path, noise="snr_db = 'none'")
    x, y, z = setup.reference_position
    poses = [Pose.from_tilt(x, y, z, t, 0.0) for t in (0.0, 3.0, 6.0, 3.0)]
    scans = setup.measure_many(poses)
    reached = [scan.metadata["reached_pose"][3] for scan in scans]
    np.testing.assert_allclose(reached, [0.0, 3.0, 6.0, 3.5], atol=1e-12)
    # the A-scan from above is the ideal A-scan at 3.5°, not at 3°
    np.testing.assert_allclose(
        scans[3].samples, ideal.measure(Pose.from_tilt(x, y, z, 3.5, 0.0)).samples, atol=1e-15
    )
