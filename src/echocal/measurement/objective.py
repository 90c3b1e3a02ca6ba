"""``SourceObjective``: any measurement source + a metric, as a calibration objective.

This is the seam between the two halves of echocal: calibration methods see
an :class:`~echocal.calibrate.Objective` of two angles [deg]; behind it any
:class:`~echocal.measurement.MeasurementSource` — the simulator, a replayed
recording or a rig — measures A-scans at a fixed position, and a metric
(pseudo-energy by default, thesis eq. 79) turns each A-scan into one value.
Counting, logging, budget, bounds and repeats are the base class's.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from echocal._validate import finite_array
from echocal.ascan import AScan
from echocal.calibrate.objective import Objective
from echocal.errors import EchocalValueError
from echocal.geometry import Pose, pose_from_angles
from echocal.measurement.base import MeasurementSource
from echocal.signal import Pulse, RecordingWindow, get_metric

__all__ = ["SourceObjective", "ascan_metric", "default_bounds"]


def default_bounds(source: MeasurementSource, parameterization: str) -> np.ndarray:
    """Angle bounds [deg], shape (2, 2), from the source's positioner limits.

    For (azimuth, co-elevation) these are the limits themselves; for tilts, the
    largest tilt box inside the co-elevation cone: |tilt| <= max |co-elevation|.
    """
    limits = source.limits
    if parameterization == "tilt":
        cone = max(abs(limits.coelevation[0]), abs(limits.coelevation[1]))
        return np.array([[-cone, cone], [-cone, cone]])
    return np.array([limits.azimuth, limits.coelevation], dtype=np.float64)


def ascan_metric(
    scan: AScan, metric: str, pulse: Pulse, window_length: float | None = None
) -> float:
    """One metric value of one A-scan; NaN for an A-scan with non-finite samples."""
    if not scan.is_finite:
        return float("nan")
    window = RecordingWindow(fs=scan.fs, start=scan.start_time, n_samples=scan.n_samples)
    fn = get_metric(metric)
    if window_length is not None and metric != "peak-amplitude":
        return float(fn(scan.samples, window, pulse, window_length))
    return float(fn(scan.samples, window, pulse))


class SourceObjective(Objective):
    """Calibration objective measuring a source at a fixed position.

    Parameters
    ----------
    source : any measurement source.
    position : [m] where the transducer stays while its orientation is calibrated, shape (3,).
    metric : metric name (``pseudo-energy``, ``peak-amplitude``, ``energy-db``).
    pulse : the transmitted pulse, the matched filter's template; defaults to
        ``source.pulse`` when the source has one (the simulator and replay files do).
    parameterization : ``"azimuth-coelevation"`` or ``"tilt"``.
    bounds : [deg] (2, 2) angle bounds; default from the source's limits.
    window_length : [s] pseudo-energy window; default tied to the pulse duration.
    budget, out_of_bounds, repeats : see :class:`~echocal.calibrate.Objective`.
    """

    def __init__(
        self,
        source: MeasurementSource,
        position: ArrayLike,
        *,
        metric: str = "pseudo-energy",
        pulse: Pulse | None = None,
        parameterization: str = "azimuth-coelevation",
        bounds: ArrayLike | None = None,
        window_length: float | None = None,
        budget: int | None = None,
        out_of_bounds: str = "clip",
        repeats: int = 1,
    ) -> None:
        get_metric(metric)  # unknown names fail here, listing the valid ones
        pulse = pulse if pulse is not None else getattr(source, "pulse", None)
        if pulse is None:
            raise EchocalValueError(
                "pulse is required: this source does not say which pulse it transmits "
                "(pass pulse=make_pulse(...) for the matched filter)"
            )
        super().__init__(
            bounds=default_bounds(source, parameterization) if bounds is None else bounds,
            budget=budget,
            out_of_bounds=out_of_bounds,
            repeats=repeats,
            parameterization=parameterization,
            description=f"{metric} of {source.description}",
        )
        self.source = source
        self.position = finite_array("position", position, shape_tail=(3,)).reshape(3)
        self.metric = metric
        self.pulse = pulse
        self.window_length = window_length

    def pose(self, a: float, b: float) -> Pose:
        """The pose measured for orientation ``(a, b)`` [deg]."""
        return pose_from_angles(self.position, float(a), float(b), self.parameterization)

    def _evaluate(self, points: np.ndarray) -> np.ndarray:
        poses = [self.pose(a, b) for a, b in points]
        scans = self.source.measure_many(poses)
        return np.array(
            [ascan_metric(s, self.metric, self.pulse, self.window_length) for s in scans]
        )
