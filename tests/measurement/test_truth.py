"""The simulator's truth is the global maximum of the metric, and a run over a part with two
equal maxima is graded by the echo it reached (issue 44)."""

from __future__ import annotations

import numpy as np
import pytest

from echocal.calibrate import FunctionObjective, calibrate
from echocal.evaluation import evaluate_run
from echocal.measurement.truth import EQUAL_OPTIMUM_RATIO, search_optima, search_optimum

WEAK = np.array([0.0, 1.8])
"""[deg] the weaker hump, nearest the candidate (as a rod's hump nearest its normal)."""
STRONG = np.array([0.0, 4.8])
"""[deg] the stronger hump, 3° farther out."""


def two_humps(tx: np.ndarray, ty: np.ndarray, *, weak: float = 0.9) -> np.ndarray:
    """Two Gaussian humps 0.6° wide: ``weak`` at :data:`WEAK`, 1 at :data:`STRONG`."""
    p = np.stack(np.broadcast_arrays(np.asarray(tx, float), np.asarray(ty, float)), axis=-1)

    def hump(at: np.ndarray) -> np.ndarray:
        return np.exp(-np.sum((p - at) ** 2, axis=-1) / (2 * 0.6**2))

    return weak * hump(WEAK) + hump(STRONG)


def test_the_global_maximum_wins_over_the_hump_the_candidate_points_at():
    # the normal-incidence candidate lies between the humps, nearer the weaker one:
    # a climb from it alone ends on the weaker hump (the fault the audit found over a rod)
    candidate = np.array([[0.0, 2.6]])
    optima, values = search_optima(two_humps, candidate)
    # the global maximum is refined to 1e-5°, the weaker hump (0.9 of it) to 0.01° only
    np.testing.assert_allclose(optima[0], STRONG, atol=2e-3)
    np.testing.assert_allclose(optima[1], WEAK, atol=2e-2)
    # each hump's value is its height plus the other's tail, computed here exactly; 0.02°
    # off a 0.6°-wide top costs at most (0.02 / 0.6)² / 2 = 6e-4 of it
    np.testing.assert_allclose(values, two_humps(*np.stack([STRONG, WEAK]).T), rtol=6e-4)
    assert values[0] > values[1]
    np.testing.assert_allclose(search_optimum(two_humps, candidate), STRONG, atol=2e-3)


def test_one_hump_gives_one_optimum():
    def one(tx, ty):
        return np.exp(-((np.asarray(tx) - 0.3) ** 2 + (np.asarray(ty) + 0.2) ** 2) / 0.5)

    optima, values = search_optima(one, np.array([[0.0, 0.0]]))
    assert optima.shape == (1, 2)
    np.testing.assert_allclose(optima[0], [0.3, -0.2], atol=1e-4)
    assert values[0] == pytest.approx(1.0, abs=1e-9)


class _TwinHumpSetup:
    """The two calls :func:`evaluate_run` makes of a setup, over two humps in tilts."""

    def __init__(self, weak: float) -> None:
        self.weak = weak

    def metric_values(self, position, a, b, *, parameterization, metric, gate):
        assert parameterization == "tilt"
        return two_humps(np.asarray(a), np.asarray(b), weak=self.weak)

    def true_optima(self, position, *, parameterization, metric, gate):
        optima, values = search_optima(
            lambda a, b: two_humps(a, b, weak=self.weak), np.array([[0.0, 2.6]])
        )
        return optima[values >= EQUAL_OPTIMUM_RATIO * values[0]]


def _run_ending_near(hump: np.ndarray, weak: float):
    objective = FunctionObjective(
        lambda p: two_humps(p[:, 0], p[:, 1], weak=weak), optimum=STRONG, parameterization="tilt"
    )
    return calibrate(objective, method="model-based", x0=hump + np.array([0.3, 0.2]), rng=0)


def test_a_run_on_the_weaker_of_two_equal_humps_is_graded_by_its_echo():
    # humps within 2 % of each other: both are the optimum, either one counts as found
    setup = _TwinHumpSetup(weak=0.995)
    result = _run_ending_near(WEAK, weak=0.995)
    evaluation = evaluate_run(setup, np.zeros(3), result)  # type: ignore[arg-type]
    assert not evaluation.unique
    assert evaluation.error < 0.05
    np.testing.assert_allclose(evaluation.truth, WEAK, atol=0.05)
    assert evaluation.echo_fraction > EQUAL_OPTIMUM_RATIO


def test_a_run_on_a_clearly_weaker_hump_is_a_miss():
    setup = _TwinHumpSetup(weak=0.9)
    result = _run_ending_near(WEAK, weak=0.9)
    evaluation = evaluate_run(setup, np.zeros(3), result)  # type: ignore[arg-type]
    assert evaluation.unique
    assert evaluation.error == pytest.approx(3.0, abs=0.05)  # the strong hump is 3° away
    assert evaluation.echo_fraction < 0.95
