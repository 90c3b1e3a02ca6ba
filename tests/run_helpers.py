"""Judging a calibration run in tests: how many measurements until it stays on target."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from echocal import angle_between, tilt_normal
from echocal.calibrate.result import CalibrationResult


def tilt_errors(result: CalibrationResult, truth: Sequence[float] | np.ndarray) -> list[float]:
    """[deg] the angle between each iterate's beam (x0 first; tilts [deg]) and the true
    optimum's ``truth`` (2,) [deg]."""
    return [float(angle_between(tilt_normal(*x), tilt_normal(*truth))) for x in result.iterates]


def measurements_to_stay_within(
    result: CalibrationResult, errors: Sequence[float] | np.ndarray, tolerance: float
) -> int | None:
    """The measurements after which every iterate's error (``errors`` [deg], one per
    iterate of ``result``, x0 first) stays below ``tolerance`` [deg]; None if never."""
    counts = list(result.iteration_measurements)
    return next((counts[i] for i in range(len(errors)) if max(errors[i:]) < tolerance), None)
