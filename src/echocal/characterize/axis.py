"""The beam axis and its squint: a tilt scan over a flat reflector, a paraboloid fit.

EN 12668-2 and ASTM E1065 find a probe's beam axis as the orientation of the largest echo
from a flat reflector.  :func:`measure_beam_axis` scans a coarse square grid of gimbal
tilts around the reflector's normal, then a fine grid around the coarse maximum, and fits
a 2-D paraboloid to the log of the echo's envelope peak over the fine points within −6 dB
of the largest; its vertex is the beam axis, with a 1-σ uncertainty propagated from the
fit's residuals.  The squint is the acoustic axis's rotation in the probe's own frame
(the bench model's convention, :mod:`echocal.bench.mount`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array, positive_float, positive_int
from echocal.errors import EchocalValueError
from echocal.geometry import Pose, normal_to_tilt, tilt_frame, tilt_normal
from echocal.measurement.base import MeasurementSource
from echocal.signal.processing import envelope

__all__ = ["AxisScan", "BeamAxis", "echo_peaks", "measure_beam_axis", "squint_of"]

FloatArray = NDArray[np.float64]


def echo_peaks(source: MeasurementSource, poses: list[Pose], repeats: int = 1) -> FloatArray:
    """Envelope peak [a.u.] of the A-scan at each pose, the mean of ``repeats`` A-scans
    averaged sample by sample; shape ``(len(poses),)``."""
    scans = source.measure_many([p for p in poses for _ in range(repeats)])
    samples = np.array([s.samples for s in scans]).reshape(len(poses), repeats, -1)
    return envelope(samples.mean(axis=1)).max(axis=-1)


def squint_of(tilts_deg: ArrayLike, reflector_tilts_deg: ArrayLike) -> FloatArray:
    """Squint ``(s_x, s_y)`` [deg] of a probe whose beam is normal to a reflector of
    normal ``tilt_normal(*reflector_tilts_deg)`` at the positioner tilts ``tilts_deg``:
    the ``S`` of the acoustic frame ``F·S`` with ``S ẑ = Fᵀ n``; shape ``(2,)``."""
    t = np.asarray(tilts_deg, dtype=np.float64)
    frame = tilt_frame(t[0], t[1])
    sx, sy = normal_to_tilt(frame.T @ tilt_normal(*np.asarray(reflector_tilts_deg, float)))
    return np.array([float(sx), float(sy)])


@dataclass(frozen=True, kw_only=True)
class BeamAxis:
    """The beam axis found over a flat reflector.

    Attributes
    ----------
    position : [m] probe position of the scan, shape ``(3,)``.
    reflector_tilts_deg : [deg] gimbal tilts of the reflector's normal, shape ``(2,)``.
    tilts_deg : [deg] positioner tilts (tilt_x, tilt_y) of the beam axis, shape ``(2,)``.
    tilts_sigma_deg : [deg] their 1-σ uncertainties from the fit, shape ``(2,)``.
    squint_deg : [deg] squint ``(s_x, s_y)`` against the mechanical axis, shape ``(2,)``.
    squint_sigma_deg : [deg] its 1-σ uncertainties, shape ``(2,)``.
    grid_deg : [deg] every tilt measured (coarse then fine), shape ``(n, 2)``.
    amplitude : [a.u.] the envelope peak at each, shape ``(n,)``.
    fit_points : how many fine points entered the fit.
    peak_amplitude : [a.u.] the fitted paraboloid's value at its vertex.
    """

    position: FloatArray
    reflector_tilts_deg: FloatArray
    tilts_deg: FloatArray
    tilts_sigma_deg: FloatArray
    squint_deg: FloatArray
    squint_sigma_deg: FloatArray
    grid_deg: FloatArray
    amplitude: FloatArray
    fit_points: int
    peak_amplitude: float

    @property
    def pose(self) -> Pose:
        """The pose of the beam axis at the scan's position."""
        return Pose.from_tilt(*self.position, *self.tilts_deg)

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON (angles in deg, lengths in m)."""
        return {
            "position_m": self.position.tolist(),
            "reflector_tilts_deg": self.reflector_tilts_deg.tolist(),
            "axis_tilts_deg": self.tilts_deg.tolist(),
            "axis_tilts_sigma_deg": self.tilts_sigma_deg.tolist(),
            "squint_deg": self.squint_deg.tolist(),
            "squint_sigma_deg": self.squint_sigma_deg.tolist(),
            "points_measured": len(self.amplitude),
            "fit_points": self.fit_points,
            "peak_amplitude": self.peak_amplitude,
        }


def _square(center: FloatArray, half: float, n: int) -> FloatArray:
    steps = np.linspace(-half, half, n)
    u, v = np.meshgrid(steps, steps, indexing="ij")
    return center + np.stack([u.ravel(), v.ravel()], axis=1)


def _design(uv: FloatArray) -> FloatArray:
    u, v = uv[:, 0], uv[:, 1]
    return np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=1)


def _vertex(c: FloatArray) -> FloatArray:
    hessian = np.array([[2 * c[3], c[4]], [c[4], 2 * c[5]]])
    return np.asarray(np.linalg.solve(hessian, -c[1:3]), dtype=np.float64)


def fit_paraboloid(uv: FloatArray, log_amp: FloatArray) -> tuple[FloatArray, FloatArray, float]:
    """Least-squares paraboloid ``c₀ + c₁u + c₂v + c₃u² + c₄uv + c₅v²`` through ``log_amp``
    at ``uv`` ``(n, 2)`` [deg]; return its vertex ``(2,)``, the vertex's covariance
    ``(2, 2)`` [deg²] (the parameters' covariance s²(AᵀA)⁻¹, s² the residuals' variance,
    propagated by the vertex's Jacobian) and its value.  Raises
    :class:`~echocal.errors.EchocalValueError` when the points have no maximum."""
    design = _design(uv)
    solution, *_ = np.linalg.lstsq(design, log_amp, rcond=None)
    c = np.asarray(solution, dtype=np.float64)
    hessian = np.array([[2 * c[3], c[4]], [c[4], 2 * c[5]]])
    if np.any(np.linalg.eigvalsh(hessian) >= 0.0):
        raise EchocalValueError(
            "the echo has no maximum inside the scanned tilts: widen span or move the "
            "scan's centre (reflector_tilts) towards the beam"
        )
    vertex = _vertex(c)
    dof = max(len(log_amp) - 6, 1)
    s2 = float(np.sum((design @ c - log_amp) ** 2)) / dof
    cov_c = s2 * np.linalg.pinv(design.T @ design)
    jac = np.empty((2, 6))
    for k in range(6):
        h = 1e-6 * max(1.0, abs(c[k]))
        dc = np.zeros(6)
        dc[k] = h
        jac[:, k] = (_vertex(c + dc) - _vertex(c - dc)) / (2 * h)
    value = float(_design(vertex[None, :])[0] @ c)
    return vertex, jac @ cov_c @ jac.T, value


@dataclass(frozen=True, kw_only=True)
class AxisScan:
    """How :func:`measure_beam_axis` scans the tilts (validated at construction).

    Attributes
    ----------
    reflector_tilts_deg : [deg] gimbal tilts of the reflector's normal: the probe's
        mechanical axis is normal to the reflector there; the coarse grid is centred on it,
        shape ``(2,)``.
    span_deg : [deg] half-width of the coarse square grid (> 0).
    coarse_points, fine_points : grid points per side (odd: one at the centre; at least 3
        and 5).  The fine grid spans one coarse step either side of the coarse maximum.
    """

    reflector_tilts_deg: ArrayLike = (0.0, 0.0)
    span_deg: float = 3.0
    coarse_points: int = 13
    fine_points: int = 11

    def __post_init__(self) -> None:
        reflector = finite_array("reflector_tilts", self.reflector_tilts_deg, shape_tail=(2,))
        object.__setattr__(self, "reflector_tilts_deg", reflector.reshape(2))
        object.__setattr__(self, "span_deg", positive_float("span", self.span_deg))
        coarse = positive_int("coarse_points", self.coarse_points)
        fine = positive_int("fine_points", self.fine_points)
        if coarse < 3 or fine < 5:
            raise EchocalValueError("coarse_points must be >= 3 and fine_points >= 5")
        object.__setattr__(self, "coarse_points", coarse)
        object.__setattr__(self, "fine_points", fine)

    @property
    def reflector(self) -> FloatArray:
        """[deg] the reflector's normal as gimbal tilts, shape ``(2,)``."""
        return np.asarray(self.reflector_tilts_deg, dtype=np.float64)


def measure_beam_axis(
    source: MeasurementSource,
    position: ArrayLike,
    scan_plan: AxisScan | None = None,
    *,
    repeats: int = 1,
) -> BeamAxis:
    """Find the beam axis over a flat reflector and the squint against the mechanical axis.

    Parameters
    ----------
    source : any :class:`~echocal.measurement.base.MeasurementSource` (simulator or rig).
    position : [m] probe position (face centre at zero tilt), shape ``(3,)``.
    scan_plan : the reflector's tilts and the grids (:class:`AxisScan`); None: its defaults
        (a reflector normal to the untilted probe, ±3°, 13 then 11 points per side).
    repeats : A-scans averaged at each tilt.
    """
    where = finite_array("position", position, shape_tail=(3,)).reshape(3)
    plan = AxisScan() if scan_plan is None else scan_plan
    reflector, span = plan.reflector, plan.span_deg
    n_coarse, n_fine = plan.coarse_points, plan.fine_points
    n_rep = positive_int("repeats", repeats)

    def scan(tilts: FloatArray) -> FloatArray:
        return echo_peaks(source, [Pose.from_tilt(*where, *t) for t in tilts], n_rep)

    coarse = _square(reflector, span, n_coarse)
    coarse_amp = scan(coarse)
    step = 2.0 * span / (n_coarse - 1)
    fine = _square(coarse[int(np.argmax(coarse_amp))], step, n_fine)
    fine_amp = scan(fine)
    if not np.any(fine_amp > 0):
        raise EchocalValueError("no echo over the scanned tilts: check position and span")
    keep = fine_amp >= 0.5 * fine_amp.max()
    if keep.sum() < 9:  # a 3 x 3 patch at least; refit on the −12 dB points
        keep = fine_amp >= 0.25 * fine_amp.max()
    centre = fine[int(np.argmax(fine_amp))]
    vertex, cov, value = fit_paraboloid(fine[keep] - centre, np.log(fine_amp[keep]))
    tilts = centre + vertex
    sigma = np.sqrt(np.diag(cov))
    squint = squint_of(tilts, reflector)
    # the squint's covariance through its (near-identity) Jacobian in the tilts
    jac = np.empty((2, 2))
    for k in range(2):
        d = np.zeros(2)
        d[k] = 1e-5
        jac[:, k] = (squint_of(tilts + d, reflector) - squint_of(tilts - d, reflector)) / 2e-5
    squint_sigma = np.sqrt(np.diag(jac @ cov @ jac.T))
    return BeamAxis(
        position=where,
        reflector_tilts_deg=reflector,
        tilts_deg=tilts,
        tilts_sigma_deg=sigma,
        squint_deg=squint,
        squint_sigma_deg=squint_sigma,
        grid_deg=np.concatenate([coarse, fine]),
        amplitude=np.concatenate([coarse_amp, fine_amp]),
        fit_points=int(keep.sum()),
        peak_amplitude=float(np.exp(value)),
    )
