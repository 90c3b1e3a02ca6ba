"""Objective: counting, logging, budget, bounds, repeats and NaN bookkeeping."""

from __future__ import annotations

import numpy as np
import pytest

from echocal.calibrate import FunctionObjective, Objective
from echocal.errors import BudgetExhaustedError, EchocalValueError, LimitError


def _sum(points):
    return points[:, 0] + 10.0 * points[:, 1]


def test_counts_and_logs_every_measurement_in_order():
    obj = FunctionObjective(_sum)
    v1 = obj([[1.0, 2.0], [3.0, 4.0]])
    v2 = obj([5.0, 6.0])
    np.testing.assert_array_equal(v1, [21.0, 43.0])
    np.testing.assert_array_equal(v2, [65.0])
    log = obj.log
    assert obj.n_measurements == 3
    np.testing.assert_array_equal(log.points, [[1, 2], [3, 4], [5, 6]])
    np.testing.assert_array_equal(log.values, [21, 43, 65])
    assert log.times.shape == (3,) and np.all(np.diff(log.times) >= 0)


def test_budget_refuses_a_partial_batch_and_measures_nothing_of_it():
    obj = FunctionObjective(_sum, budget=3)
    obj([[0.0, 0.0], [1.0, 1.0]])
    with pytest.raises(BudgetExhaustedError, match="budget=3"):
        obj([[0.0, 0.0], [1.0, 1.0]])
    assert obj.n_measurements == 2 and obj.remaining == 1
    obj([[2.0, 2.0]])
    assert obj.remaining == 0


def test_bounds_clip_and_error_modes():
    bounds = [[-1.0, 1.0], [-2.0, 2.0]]
    clip = FunctionObjective(_sum, bounds=bounds)
    assert clip([[5.0, -5.0]])[0] == 1.0 - 20.0
    np.testing.assert_array_equal(clip.log.points, [[1.0, -2.0]])
    err = FunctionObjective(_sum, bounds=bounds, out_of_bounds="error")
    with pytest.raises(LimitError, match=r"azimuth=5.*outside"):
        err([[5.0, 0.0]])
    assert err.n_measurements == 0


def test_repeats_are_averaged_and_each_counted():
    obj = FunctionObjective(_sum, noise_sigma=1.0, rng=3, repeats=4)
    val = obj([[0.0, 0.0]])
    assert obj.n_measurements == 4
    # the returned value is exactly the mean of the 4 logged repeats
    np.testing.assert_allclose(val[0], obj.log.values.mean(), rtol=1e-12)
    with pytest.raises(BudgetExhaustedError):
        FunctionObjective(_sum, repeats=4, budget=6)([[0.0, 0.0], [1.0, 1.0]])


def test_nan_values_are_counted_and_logged():
    obj = FunctionObjective(lambda p: np.where(p[:, 0] > 0, np.nan, 1.0))
    out = obj([[1.0, 0.0], [-1.0, 0.0]])
    assert np.isnan(out[0]) and out[1] == 1.0
    assert obj.n_nan == 1 and np.isnan(obj.log.values[0])


def test_noise_is_seeded():
    a = FunctionObjective(_sum, noise_sigma=0.5, rng=7)([[0.0, 0.0]] * 5)
    b = FunctionObjective(_sum, noise_sigma=0.5, rng=7)([[0.0, 0.0]] * 5)
    np.testing.assert_array_equal(a, b)
    assert np.std(a) > 0


def test_bad_inputs_name_the_field():
    with pytest.raises(EchocalValueError, match="points must have shape"):
        FunctionObjective(_sum)(np.zeros((3, 3)))
    with pytest.raises(EchocalValueError, match="bounds must have shape"):
        FunctionObjective(_sum, bounds=[1.0, 2.0])
    with pytest.raises(EchocalValueError, match="budget"):
        FunctionObjective(_sum, budget=0)
    with pytest.raises(KeyError, match="out_of_bounds"):
        FunctionObjective(_sum, out_of_bounds="wrap")

    class Bad(Objective):
        def _evaluate(self, points):
            return np.zeros(len(points) + 1)

    with pytest.raises(EchocalValueError, match="_evaluate must return shape"):
        Bad()([[0.0, 0.0]])


def test_parameterization_names():
    obj = FunctionObjective(_sum, parameterization="tilt")
    assert obj.names == ("tilt_x", "tilt_y")
    with pytest.raises(KeyError, match="azimuth-coelevation"):
        FunctionObjective(_sum, parameterization="euler")
