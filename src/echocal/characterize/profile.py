"""The −6 dB beam width at several distances, and the focal distance, over a point target.

EN 12668-2 and ASTM E1065 measure a probe's beam profile over a small ball (or a
side-drilled hole) scanned across the beam: at each distance, the echo's envelope peak
against the probe's lateral offset is the pulse-echo beam profile, and its width where it
falls to half its largest value (−6 dB) is the beam width.  :func:`measure_beam_profile`
scans a straight line across the target in each of the probe's own lateral directions
(x', y' of the gimbal frame at the given tilts) at each distance, and interpolates the
−6 dB points linearly between the scan's points.  The on-axis echo against distance gives
the focal distance (:func:`focal_distance`): the vertex of a parabola through the largest
on-axis echo and its neighbours.

Uncertainties come from the receiver noise: its σ per sample is estimated from each line's
A-scans (1.4826 × the median absolute sample, the echo occupying a small part of the
record), and a −6 dB point moves by σ / |slope| of the profile there.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array, positive_float, positive_int
from echocal.characterize.axis import echo_peaks
from echocal.errors import EchocalValueError
from echocal.geometry import Pose, tilt_frame
from echocal.measurement.base import MeasurementSource
from echocal.signal.processing import envelope

__all__ = [
    "BeamProfile",
    "FocalScan",
    "focal_distance",
    "half_max_width",
    "measure_beam_profile",
    "measure_focus",
]

FloatArray = NDArray[np.float64]
_AXES = {"x": 0, "y": 1}


def half_max_width(
    offsets: ArrayLike, amplitude: ArrayLike, sigma: float = 0.0
) -> tuple[float, float, float]:
    """Width, centre and the width's 1-σ [units of ``offsets``] of a profile where it falls
    to half its largest value, each side's crossing interpolated linearly between points
    (``offsets`` increasing, both shape ``(n,)``; ``sigma`` the amplitude's noise).  NaN
    when the profile does not fall to half on both sides within the scan."""
    x = np.asarray(offsets, dtype=np.float64)
    a = np.asarray(amplitude, dtype=np.float64)
    peak = int(np.argmax(a))
    half = 0.5 * a[peak]
    below_left = np.flatnonzero(a[:peak] < half)
    below_right = np.flatnonzero(a[peak:] < half)
    if below_left.size == 0 or below_right.size == 0:
        return float("nan"), float("nan"), float("nan")
    i = int(below_left[-1])
    j = peak + int(below_right[0])
    slope_l = (a[i + 1] - a[i]) / (x[i + 1] - x[i])
    slope_r = (a[j] - a[j - 1]) / (x[j] - x[j - 1])
    left = x[i] + (half - a[i]) / slope_l
    right = x[j - 1] + (half - a[j - 1]) / slope_r
    spread = float(np.hypot(sigma / slope_l, sigma / slope_r))
    return float(right - left), float(0.5 * (left + right)), spread


@dataclass(frozen=True, kw_only=True)
class BeamProfile:
    """Beam widths at several distances over a point target.

    Attributes
    ----------
    target : [m] the target's point the distances are measured to, shape ``(3,)``.
    tilts_deg : [deg] the probe's gimbal tilts during the scans, shape ``(2,)``.
    distances : [m] probe face to target along the probe's axis, shape ``(d,)``.
    axes : the lateral directions scanned (``"x"``, ``"y"``: the probe's own x', y').
    offsets : [m] lateral offsets of each line, shape ``(p,)``.
    amplitude : [a.u.] envelope peak, shape ``(d, len(axes), p)``.
    width : [m] −6 dB width, shape ``(d, len(axes))`` (NaN: not inside the scan).
    width_sigma : [m] its 1-σ from the receiver noise, same shape.
    centre : [m] the −6 dB points' midpoint (where the beam's axis crosses the line).
    on_axis : [a.u.] the largest echo of each distance's lines, shape ``(d,)``.
    noise_sigma : [a.u.] the receiver noise's σ per sample estimated from the A-scans.
    """

    target: FloatArray
    tilts_deg: FloatArray
    distances: FloatArray
    axes: tuple[str, ...]
    offsets: FloatArray
    amplitude: FloatArray
    width: FloatArray
    width_sigma: FloatArray
    centre: FloatArray
    on_axis: FloatArray
    noise_sigma: float

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON (lengths in m)."""
        return {
            "target_m": self.target.tolist(),
            "tilts_deg": self.tilts_deg.tolist(),
            "distances_m": self.distances.tolist(),
            "axes": list(self.axes),
            "width_6db_m": self.width.tolist(),
            "width_6db_sigma_m": self.width_sigma.tolist(),
            "centre_m": self.centre.tolist(),
            "on_axis_amplitude": self.on_axis.tolist(),
            "points_per_line": len(self.offsets),
        }


def _scan_inputs(
    target: ArrayLike, distances: ArrayLike, tilts_deg: ArrayLike, repeats: int, least: int
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    """A point-target scan's inputs checked: the target [m] ``(3,)``, at least ``least``
    distances [m] > 0 ``(d,)``, the tilts [deg] ``(2,)`` and the repeats."""
    where = finite_array("target", target, shape_tail=(3,)).reshape(3)
    dist = finite_array("distances", distances).reshape(-1)
    if dist.size < least or np.any(dist <= 0):
        many = {1: "one", 3: "three"}.get(least, str(least))
        raise EchocalValueError(f"distances must be {many} or more lengths > 0")
    tilts = finite_array("tilts", tilts_deg, shape_tail=(2,)).reshape(2)
    return where, dist, tilts, positive_int("repeats", repeats)


def _noise_sigma(samples: FloatArray) -> float:
    return float(1.4826 * np.median(np.abs(samples - np.median(samples))))


def measure_beam_profile(
    source: MeasurementSource,
    target: ArrayLike,
    distances: ArrayLike,
    *,
    tilts_deg: ArrayLike = (0.0, 0.0),
    half_span: float = 0.01,
    points: int = 41,
    axes: Sequence[str] = ("x", "y"),
    repeats: int = 1,
) -> BeamProfile:
    """Scan lines across a point target at each distance; the −6 dB beam widths.

    Parameters
    ----------
    source : any :class:`~echocal.measurement.base.MeasurementSource`.
    target : [m] the point target (a ball's centre or top), shape ``(3,)``.
    distances : [m] probe face to target along the probe's axis, shape ``(d,)``.
    tilts_deg : [deg] gimbal tilts of the probe (normally the beam axis found over a flat
        reflector, so the lines cross the beam square to it).
    half_span : [m] each line runs from −half_span to +half_span across the target.
    points : points per line (odd: one over the target).
    axes : the probe's lateral directions to scan, ``"x"`` and/or ``"y"``.
    repeats : A-scans averaged per point.
    """
    where, dist, tilts, n_rep = _scan_inputs(target, distances, tilts_deg, repeats, 1)
    span = positive_float("half_span", half_span)
    n = positive_int("points", points)
    if n < 5:
        raise EchocalValueError(f"points must be >= 5; got {n}")
    names = tuple(axes)
    if not names or any(a not in _AXES for a in names):
        raise EchocalValueError(f"axes must be one or both of 'x', 'y'; got {list(names)}")
    frame = tilt_frame(*tilts)
    offsets = np.linspace(-span, span, n)
    positions = [
        where + d * frame[:, 2] + s * frame[:, _AXES[a]]
        for d in dist
        for a in names
        for s in offsets
    ]
    poses = [Pose.from_tilt(*p, *tilts) for p in positions for _ in range(n_rep)]
    scans = source.measure_many(poses)
    samples = np.array([s.samples for s in scans]).reshape(len(positions), n_rep, -1)
    noise = _noise_sigma(samples) / np.sqrt(n_rep)
    amp = envelope(samples.mean(axis=1)).max(axis=-1).reshape(dist.size, len(names), n)
    stats = np.array([[half_max_width(offsets, line, noise) for line in lines] for lines in amp])
    return BeamProfile(
        target=where,
        tilts_deg=tilts,
        distances=dist,
        axes=names,
        offsets=offsets,
        amplitude=amp,
        width=stats[..., 0],
        width_sigma=stats[..., 2],
        centre=stats[..., 1],
        on_axis=amp.max(axis=(1, 2)),
        noise_sigma=noise,
    )


def focal_distance(distances: ArrayLike, on_axis: ArrayLike) -> tuple[float, float]:
    """Distance [m] of the largest on-axis echo and its 1-σ [m]: the vertex of a parabola
    through the largest value and its two neighbours (``distances`` increasing, shape
    ``(d,)``).  NaN, NaN when the largest echo is at either end (no maximum inside)."""
    d = np.asarray(distances, dtype=np.float64)
    a = np.asarray(on_axis, dtype=np.float64)
    k = int(np.argmax(a))
    if k == 0 or k == d.size - 1:
        return float("nan"), float("nan")
    lo, hi = max(k - 2, 0), min(k + 3, d.size)
    x = d[lo:hi] - d[k]
    design = np.stack([x * x, x, np.ones_like(x)], axis=1)
    solution, *_ = np.linalg.lstsq(design, a[lo:hi], rcond=None)
    c = np.asarray(solution, dtype=np.float64)
    vertex = d[k] - c[1] / (2 * c[0])
    if hi - lo <= 3:
        return float(vertex), float("nan")
    s2 = float(np.sum((design @ c - a[lo:hi]) ** 2)) / (hi - lo - 3)
    cov = s2 * np.linalg.inv(design.T @ design)
    grad = np.array([c[1] / (2 * c[0] ** 2), -1 / (2 * c[0]), 0.0])
    return float(vertex), float(np.sqrt(grad @ cov @ grad))


@dataclass(frozen=True, kw_only=True)
class FocalScan:
    """The on-axis echo of a point target against distance, and its maximum.

    Attributes
    ----------
    distances : [m] probe face to target along the probe's axis, shape ``(d,)``.
    amplitude : [a.u.] envelope peak at each, shape ``(d,)``.
    focal_distance : [m] distance of the largest echo (parabola vertex; NaN if the
        largest echo is at an end of the scan).
    focal_sigma : [m] its 1-σ from the parabola's fit (NaN with only three points).
    """

    distances: FloatArray
    amplitude: FloatArray
    focal_distance: float
    focal_sigma: float

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON (lengths in m)."""
        return {
            "distances_m": self.distances.tolist(),
            "on_axis_amplitude": self.amplitude.tolist(),
            "focal_distance_m": self.focal_distance,
            "focal_distance_sigma_m": self.focal_sigma,
        }


def measure_focus(
    source: MeasurementSource,
    target: ArrayLike,
    distances: ArrayLike,
    *,
    tilts_deg: ArrayLike = (0.0, 0.0),
    repeats: int = 1,
) -> FocalScan:
    """The on-axis echo of a point target at each distance [m] (the probe moved along its
    axis, tilts ``tilts_deg``) and the focal distance: the vertex of a parabola through
    the largest echo and up to two neighbours on each side."""
    where, dist, tilts, n_rep = _scan_inputs(target, distances, tilts_deg, repeats, 3)
    dist = np.sort(dist)
    axis = tilt_frame(*tilts)[:, 2]
    amp = echo_peaks(source, [Pose.from_tilt(*(where + d * axis), *tilts) for d in dist], n_rep)
    focus, sigma = focal_distance(dist, amp)
    return FocalScan(distances=dist, amplitude=amp, focal_distance=focus, focal_sigma=sigma)
