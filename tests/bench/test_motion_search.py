"""Motion-aware search: the posterior search weighs each candidate's move, and a
motion-aware objective predicts the moves from its bench's tilt axes."""

from __future__ import annotations

import dataclasses
import importlib.util
import warnings
from pathlib import Path

import numpy as np
from _bench_setups import bench_setup, timed_tilts

from echocal.calibrate import calibrate
from echocal.calibrate.posterior_search import MOTION_TIE, EchoLikelihood, PosteriorSearch
from echocal.measurement import ReceiverSettings, SourceObjective
from echocal.setups import load_setup
from echocal.setups.bench_schema import BenchConfig, build_bench


def _search() -> PosteriorSearch:
    """A synthetic echo (a Gaussian lobe of 1° peaking at 12 Rayleigh units, M = 300, a
    threshold of 6) searched within 20° of the origin."""
    angles = np.arange(0.0, 5.0 + 1e-9, 0.05)
    like = EchoLikelihood(
        angles=angles, echo=12.0 * np.exp(-(angles**2) / 2.0), n_cells=300.0, threshold=6.0
    )
    return PosteriorSearch(np.zeros(2), 20.0, like, np.array([[-30.0, 30.0], [-30.0, 30.0]]))


def test_the_next_point_is_the_soonest_reached_of_the_nearly_best():
    search = _search()
    search.update(np.array([[0.0, 0.0], [2.0, 0.0], [-2.0, 0.0]]), np.array([-0.5, 0.1, -1.0]))
    chance = search.detection_chances()
    here = np.array([9.0, 7.0])

    def move_time(points):  # 10°/s on both axes together, 50 ms of settling
        return np.abs(points - here).max(axis=1) / 10.0 + 0.05

    plain = search.next_point()
    aware = search.next_point(move_time)
    # by hand: every cell within MOTION_TIE of the best chance, the quickest to reach
    xs, ys = search._x[0], search._y[:, 0]
    gx, gy = np.meshgrid(xs, ys)
    good = chance >= (1.0 - MOTION_TIE) * chance.max()
    times = np.where(good, np.maximum(np.abs(gx - here[0]), np.abs(gy - here[1])), np.inf)
    i, j = np.unravel_index(np.argmin(times), times.shape)
    np.testing.assert_allclose(aware, [xs[j], ys[i]])
    assert move_time(aware[None])[0] < move_time(plain[None])[0]
    # a callable that knows no moves (None) leaves the plain choice
    np.testing.assert_allclose(search.next_point(lambda points: None), plain)


def test_a_motion_aware_objective_predicts_its_moves_from_the_bench(tmp_path):
    setup, _ = bench_setup(tmp_path, timed_tilts(10, "20 ms"))
    where = setup.reference_position
    plain = SourceObjective(setup, where, parameterization="tilt")
    aware = SourceObjective(setup, where, parameterization="tilt", motion_aware=True)
    points = np.array([[1.0, 0.0], [1.0, 2.0], [-1.0, 0.5]])
    assert aware.move_times(points) is None  # nothing measured yet: the probe is nowhere
    aware(np.array([[0.5, 0.5]]))
    plain(np.array([[0.5, 0.5]]))
    assert plain.move_times(points) is None  # not motion-aware: no weighing
    # by hand from (0.5, 0.5): max(0.5, 0.5)/10 + 0.02, max(0.5, 1.5)/10 + 0.02, ...
    np.testing.assert_allclose(aware.move_times(points), [0.07, 0.17, 0.17])
    ideal, _ = bench_setup(tmp_path)  # a bench whose moves take no time: no weighing
    timeless = SourceObjective(ideal, where, parameterization="tilt", motion_aware=True)
    timeless(np.array([[0.5, 0.5]]))
    assert timeless.move_times(points) is None


def test_a_lower_chance_is_taken_only_for_a_move_long_against_the_price():
    search = _search()
    search.update(np.array([[0.0, 0.0], [2.0, 0.0], [-2.0, 0.0]]), np.array([-0.5, 0.1, -1.0]))
    here = np.array([9.0, 7.0])

    def move_time(points):  # 10°/s on both axes together, 50 ms of settling
        return np.abs(points - here).max(axis=1) / 10.0 + 0.05

    plain = search.next_point()
    walk = search.next_point(move_time)  # price 0: any saving
    saved = move_time(plain[None])[0] - move_time(walk[None])[0]
    assert saved > 0.0
    # the walk's cell replaces the plain choice exactly when it saves more than
    # price / MOTION_TIE: just below that price it does, just above it does not
    threshold = saved * MOTION_TIE
    np.testing.assert_array_equal(search.next_point(move_time, 0.99 * threshold), walk)
    np.testing.assert_array_equal(search.next_point(move_time, 1.01 * threshold), plain)


def test_a_motion_aware_objective_prices_a_point_and_keeps_a_batch_that_saves_less(tmp_path):
    bench = '[bench.positioner]\nacquisition_time = "5 ms"\n' + timed_tilts(10, "20 ms")
    setup, _ = bench_setup(tmp_path, bench)
    where = setup.reference_position
    aware = SourceObjective(setup, where, parameterization="tilt", motion_aware=True, repeats=2)
    # by hand: two acquisitions of 5 ms and the tilt axes' 20 ms of settling
    np.testing.assert_allclose(aware.measurement_price(), 0.03)
    assert SourceObjective(setup, where, parameterization="tilt").measurement_price() is None
    # by hand, along tilt_x from 0°: 0.2°, 0.1°, 0.3° in the order asked cost 0.04 + 0.03 +
    # 0.04 s of motion and settling, the short order 0.1°, 0.2°, 0.3° 3 × 0.03 s: it saves
    # 0.02 s, less than the price of a point of one A-scan (0.025 s), so the order asked is
    # kept and the noise is drawn as a plain objective draws it
    batch = np.array([[0.0, 0.0], [0.2, 0.0], [0.1, 0.0], [0.3, 0.0]])
    values = []
    for motion_aware in (False, True):
        setup, _ = bench_setup(tmp_path, bench)
        objective = SourceObjective(
            setup, where, parameterization="tilt", motion_aware=motion_aware
        )
        values.append(objective(batch))
    np.testing.assert_array_equal(values[0], values[1])
    assert objective.bench_time_saved == 0.0


def _ray_bench_setup(snr_db: float, seed: int):
    """The 5 MHz probe on the ray model over the plate, on the calibration benchmark's
    realistic bench (``REAL_BENCH``: 10°/s and 50 ms of settling per tilt axis, 5 ms per
    A-scan, 0.05° of compensated backlash, squint, pivot offset, AR(1) noise)."""
    path = Path(__file__).resolve().parents[2] / "benchmarks" / "_calibration_cases.py"
    spec = importlib.util.spec_from_file_location("_calibration_cases", path)
    assert spec is not None and spec.loader is not None
    cases = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cases)
    bench = build_bench(BenchConfig.model_validate(cases.REAL_BENCH), None)
    setup = dataclasses.replace(load_setup("immersion-5mhz-ray", seed=seed), bench=bench)
    return dataclasses.replace(setup, receiver=ReceiverSettings(snr_db=snr_db))


def test_where_every_move_is_short_motion_aware_auto_asks_exactly_plain_autos_points():
    """A start 2° from the optimum at 20 dB: the search's moves are short against a
    measurement's price (55 ms), so the motion-aware run asks the plain run's points and
    measures the same values; with a price of 0 the same search walks elsewhere."""
    for seed in (2, 4):
        runs = []
        for motion_aware, options in ((False, {}), (True, {}), (True, {"measurement_price": 0.0})):
            setup = _ray_bench_setup(20.0, seed)
            where = np.asarray(setup.reference_position, dtype=float)
            truth = setup.true_optima(where, parameterization="tilt")[0]
            objective = SourceObjective(
                setup, where, parameterization="tilt", budget=25, motion_aware=motion_aware
            )
            x0 = truth + 2.0 * np.array([np.cos(seed), np.sin(seed)])
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                calibrate(
                    objective, method="auto", x0=x0, budget=25, settle=None, rng=seed, **options
                )
            runs.append((objective.log.points, objective.log.values, objective.bench_time))
        plain, aware, free = runs
        np.testing.assert_array_equal(aware[0], plain[0])
        np.testing.assert_array_equal(aware[1], plain[1])
        assert aware[2] == plain[2]
        assert not np.array_equal(free[0], plain[0])  # the price is what keeps the points
