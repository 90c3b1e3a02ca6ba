"""The `settle` stopping rule: converged recommendations stop a run; pure noise does not."""

from __future__ import annotations

import numpy as np
import pytest

from echocal import EchocalValueError
from echocal.calibrate import FunctionObjective, calibrate


def gaussian_peak(points):
    # A 1°-wide peak of height 10 at (0.3, -0.2) deg.
    d2 = np.sum((np.asarray(points) - [0.3, -0.2]) ** 2, axis=1)
    return 10.0 * np.exp(-d2 / (2 * 0.5**2))


def test_settles_near_the_optimum_with_few_measurements():
    objective = FunctionObjective(gaussian_peak, noise_sigma=10 / np.sqrt(1000), rng=3)
    result = calibrate(objective, "model-based", x0=(1.0, 1.0), settle=(0.01, 8), rng=3)
    assert result.status == 7 and result.success
    assert np.hypot(*(result.x - [0.3, -0.2])) < 0.05  # 30 dB: a few hundredths of a degree
    assert result.n_measurements < 60  # the 100-iteration default would use > 100


def test_does_not_settle_on_pure_noise_when_the_noise_floor_is_known():
    # No echo anywhere: the values are noise around a known floor, so the rule must not fire.
    objective = FunctionObjective(
        lambda p: np.zeros(len(p)), noise_sigma=0.1, noise_floor=0.0, rng=1
    )
    result = calibrate(objective, "model-based", x0=(0.0, 0.0), settle=(10.0, 3), max_iter=30)
    assert result.status != 7


@pytest.mark.parametrize("bad", [(0.0, 8), (0.01, 0), (0.01,), "fast"])
def test_bad_settle_names_the_option(bad):
    objective = FunctionObjective(gaussian_peak)
    with pytest.raises(EchocalValueError, match="settle"):
        calibrate(objective, "model-based", x0=(0.0, 0.0), settle=bad)
