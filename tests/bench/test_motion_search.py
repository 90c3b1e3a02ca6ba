"""Motion-aware search: the posterior search weighs each candidate's move, and a
motion-aware objective predicts the moves from its bench's tilt axes."""

from __future__ import annotations

import numpy as np
from _bench_setups import bench_setup, timed_tilts

from echocal.calibrate.posterior_search import MOTION_TIE, EchoLikelihood, PosteriorSearch
from echocal.measurement import SourceObjective


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
