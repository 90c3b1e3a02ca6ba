"""Judging a calibration run against the truth only the simulator knows.

A :class:`~echocal.calibrate.CalibrationResult` says what a method *measured*;
:func:`evaluate_run` adds what it *achieved*: the angular error of its
estimate and of every iterate against the true optimum, the noiseless metric
at every iterate (the thesis's "pseudo-energy vs iterations" curves), and how
many measurements it needed to get within a tolerance.  The angular error is
the angle between beam directions, so it means the same in either
parameterization.  None of this is visible to the calibration method.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal.calibrate.objective import PARAMETERIZATIONS
from echocal.calibrate.result import CalibrationResult
from echocal.geometry import angle_between, convert_angles, orientation_normal
from echocal.measurement.virtual import VirtualSetup
from echocal.signal.gates import TimeGate

__all__ = [
    "WIDE_MAP",
    "CostMap",
    "RunEvaluation",
    "angular_error",
    "cost_map",
    "evaluate_run",
    "map_resolution",
    "nearest_equivalent",
]

FloatArray = NDArray[np.float64]


def angular_error(points: ArrayLike, truth: ArrayLike, parameterization: str) -> FloatArray:
    """[deg] angle between the beams of ``points`` (shape (..., 2)) and ``truth`` (2,)."""
    pts = np.asarray(points, dtype=np.float64)
    az, coel = convert_angles(pts[..., 0], pts[..., 1], parameterization, "azimuth-coelevation")
    t = np.asarray(truth, dtype=np.float64)
    taz, tcoel = convert_angles(t[0], t[1], parameterization, "azimuth-coelevation")
    return angle_between(orientation_normal(az, coel), orientation_normal(taz, tcoel))


@dataclass(frozen=True, slots=True)
class CostMap:
    """A metric sampled on a grid of orientations (the heat-map background).

    Attributes
    ----------
    a, b : [deg] grid axes, shapes ``(n_a,)`` and ``(n_b,)``.
    values : metric at each grid orientation, shape ``(n_a, n_b)``.
    names : names of the two angles (e.g. ``("tilt_x", "tilt_y")``).
    """

    a: FloatArray
    b: FloatArray
    values: FloatArray
    names: tuple[str, str] = ("azimuth", "coelevation")


@dataclass(frozen=True)
class RunEvaluation:
    """A calibration result judged against the truth.

    Attributes
    ----------
    result : the run.
    truth : [deg] the true optimum in the run's parameterization, shape (2,).
    error : [deg] angle between the estimate's beam and the true optimum's.
    iterate_errors : [deg] the same for x0 and every iterate, shape (n_iterations + 1,).
    iterate_values : noiseless metric at x0 and every iterate, shape (n_iterations + 1,).
    optimum_value : noiseless metric at the true optimum.
    optima : [deg] every maximum within :data:`~echocal.measurement.truth.EQUAL_OPTIMUM_RATIO`
        of the global one, shape ``(k, 2)``, the global one first; ``truth`` is the one
        nearest the estimate, and every error is measured to the nearest of them.
    """

    result: CalibrationResult
    truth: FloatArray
    error: float
    iterate_errors: FloatArray
    iterate_values: FloatArray
    optimum_value: float
    optima: FloatArray

    @property
    def unique(self) -> bool:
        """Whether the optimum is unique (else the run is graded by the echo it reached:
        any of :attr:`optima` counts as found)."""
        return len(self.optima) == 1

    @property
    def echo_fraction(self) -> float:
        """Noiseless metric at the estimate over the global maximum's."""
        return float(self.iterate_values[-1] / self.optimum_value)

    def _first_inside(self, tolerance: float) -> int | None:
        """Index of the iterate from which all stay within ``tolerance`` [deg] (None: the
        final estimate misses it; ``len(iterate_errors)``: only the final estimate is in)."""
        if self.error > tolerance:
            return None
        outside = np.nonzero(self.iterate_errors > tolerance)[0]
        return 0 if outside.size == 0 else int(outside[-1]) + 1

    def iterations_to(self, tolerance: float) -> int | None:
        """Iterations after which the iterates came (and stayed) within ``tolerance`` [deg].

        None if the final estimate is not within the tolerance; ``n_iterations`` when only
        the final estimate (e.g. a model's recommendation) is.
        """
        first = self._first_inside(tolerance)
        return None if first is None else min(first, self.result.n_iterations)

    def measurements_to(self, tolerance: float) -> int | None:
        """Measurements used when the iterates first came (and stayed) within ``tolerance`` [deg].

        None if the final estimate is not within the tolerance; every measurement of the
        run when only the final estimate is.
        """
        first = self._first_inside(tolerance)
        if first is None:
            return None
        counts = self.result.iteration_measurements
        return int(self.result.n_measurements if first >= len(counts) else counts[first])


def nearest_equivalent(angles: ArrayLike, near: ArrayLike, parameterization: str) -> FloatArray:
    """The representation of orientation ``angles`` [deg] closest to ``near`` [deg].

    (φ, θ), (φ ± 180°, −θ) and (φ ± 360°, θ) are the same beam; tilts are unique.
    """
    angles = np.asarray(angles, dtype=np.float64)
    if parameterization == "tilt":
        return angles
    az, coel = angles
    candidates = np.array([(az + k * 180.0, coel if k % 2 == 0 else -coel) for k in range(-3, 4)])
    distance = np.hypot(*(candidates - np.asarray(near, dtype=np.float64)).T)
    return candidates[int(np.argmin(distance))]


def evaluate_run(
    setup: VirtualSetup,
    position: ArrayLike,
    result: CalibrationResult,
    *,
    metric: str = "pseudo-energy",
    gate: TimeGate | None = None,
) -> RunEvaluation:
    """Judge ``result`` (measured at ``position`` [m]) against ``setup``'s truth: the
    optimum of ``metric`` inside ``gate`` (the whole recording without one).

    Where the optimum is not unique (:meth:`VirtualSetup.true_optima`: maxima within
    2 % of each other, a rod's two humps) every error is the distance to the nearest of
    them, so a run is graded by the echo it reached, not by which hump it chose.
    """
    param = result.parameterization
    optima = setup.true_optima(position, parameterization=param, metric=metric, gate=gate)
    optima = np.array([nearest_equivalent(o, result.x, param) for o in optima])
    iterates = np.asarray(result.iterates, dtype=np.float64)

    def metric_at(a: ArrayLike, b: ArrayLike) -> FloatArray:
        return setup.metric_values(position, a, b, parameterization=param, metric=metric, gate=gate)

    def error_to_nearest(points: FloatArray) -> FloatArray:
        return np.min([angular_error(points, o, param) for o in optima], axis=0)

    nearest = int(np.argmin([angular_error(result.x, o, param) for o in optima]))
    values = metric_at(iterates[:, 0], iterates[:, 1])
    optimum = float(metric_at(optima[0, 0], optima[0, 1]))
    return RunEvaluation(
        result=result,
        truth=optima[nearest],
        error=float(error_to_nearest(np.asarray(result.x, dtype=np.float64))),
        iterate_errors=error_to_nearest(iterates),
        iterate_values=values,
        optimum_value=optimum,
        optima=optima,
    )


WIDE_MAP = 4.0
"""[deg] a cost map reaching farther than this from its centre is drawn coarser on the wave
model: its far cells lie at large tilts, where the two-way Nyquist spacing makes a wave
A-scan 10–100× costlier than at normal incidence."""


def map_resolution(setup: VirtualSetup, half_span: float = 0.0) -> int:
    """Grid points per axis of a cost map of ``setup`` reaching ``half_span`` [deg] from its
    centre: 61 on the ray model (< 1 ms per pose); on the wave model 41, or 21 beyond
    :data:`WIDE_MAP`; with an interior (each back-wall echo costs as much again) 25, or 15;
    inside a curved wall (a pipe or a shell: 0.1–1 s per pose) 11, or 9.  A map takes
    seconds to a minute or two, not many minutes; it is a picture, and smooth shading hides
    the coarser grid."""
    if getattr(setup, "reflection", None) != "wave":
        return 61
    wide = half_span > WIDE_MAP
    if getattr(setup, "interior", None) is not None:
        if any(shape.kind != "plane" for shape in setup.specimen):
            return 9 if wide else 11
        return 15 if wide else 25
    return 21 if wide else 41


def cost_map(
    setup: VirtualSetup,
    position: ArrayLike,
    *,
    parameterization: str = "tilt",
    a_range: tuple[float, float] = (-20.0, 20.0),
    b_range: tuple[float, float] = (-20.0, 20.0),
    n: int | None = None,
    metric: str = "pseudo-energy",
    gate: TimeGate | None = None,
) -> CostMap:
    """Noiseless metric (inside ``gate``, if given) on an ``n × n`` grid of orientations
    [deg] (one batched simulation); ``n`` defaults to :func:`map_resolution`."""
    half_span = 0.5 * max(a_range[1] - a_range[0], b_range[1] - b_range[0])
    n = map_resolution(setup, half_span) if n is None else n
    a = np.linspace(*a_range, n)
    b = np.linspace(*b_range, n)
    values = setup.metric_values(
        position,
        a[:, None],
        b[None, :],
        parameterization=parameterization,
        metric=metric,
        gate=gate,
    )
    return CostMap(a=a, b=b, values=values, names=PARAMETERIZATIONS[parameterization])
