"""One probe's characterization: the beam axis, the spectrum at that axis, and over a point
target the beam widths and the focal distance."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from echocal._validate import positive_int
from echocal.characterize.axis import AxisScan, BeamAxis, measure_beam_axis
from echocal.characterize.profile import (
    BeamProfile,
    FocalScan,
    measure_beam_profile,
    measure_focus,
)
from echocal.characterize.spectrum import EchoSpectrum, measure_spectrum
from echocal.errors import EchocalValueError
from echocal.measurement.base import MeasurementSource

__all__ = ["ProbeCharacterization", "characterize_probe"]


@dataclass(frozen=True, kw_only=True)
class ProbeCharacterization:
    """What :func:`characterize_probe` measured.

    Attributes
    ----------
    source : the source's one-line description.
    axis : the beam axis and squint (:class:`~echocal.characterize.axis.BeamAxis`).
    spectrum : the echo's spectrum at the axis
        (:class:`~echocal.characterize.spectrum.EchoSpectrum`).
    profile : beam widths over the point target
        (:class:`~echocal.characterize.profile.BeamProfile`), or None.
    focus : the on-axis echo against distance
        (:class:`~echocal.characterize.profile.FocalScan`), or None.
    measurements : A-scans recorded in all.
    """

    source: str
    axis: BeamAxis
    spectrum: EchoSpectrum
    profile: BeamProfile | None = None
    focus: FocalScan | None = None
    measurements: int

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "source": self.source,
            "beam_axis": self.axis.to_dict(),
            "spectrum": self.spectrum.to_dict(),
            "beam_profile": None if self.profile is None else self.profile.to_dict(),
            "focus": None if self.focus is None else self.focus.to_dict(),
            "measurements": self.measurements,
        }


def characterize_probe(
    source: MeasurementSource,
    position: ArrayLike,
    *,
    axis_scan: AxisScan | None = None,
    repeats: int = 1,
    n_ascans: int = 16,
    point_source: MeasurementSource | None = None,
    target: ArrayLike | None = None,
    distances: ArrayLike = (),
    half_span: float = 0.01,
    line_points: int = 41,
    axes: Sequence[str] = ("x", "y"),
    focus_distances: ArrayLike = (),
) -> ProbeCharacterization:
    """Characterize the probe on ``source`` over a flat reflector below ``position`` [m]:
    :func:`~echocal.characterize.axis.measure_beam_axis` (the tilts ``axis_scan`` plans,
    :class:`~echocal.characterize.axis.AxisScan`; None: its defaults), then
    :func:`~echocal.characterize.spectrum.measure_spectrum` at the axis found, averaging
    ``n_ascans`` A-scans; ``repeats`` A-scans averaged at every point of every scan.
    With a ``target`` [m] (a point target on ``point_source``, ``source`` itself by
    default), at the beam axis's tilts:
    :func:`~echocal.characterize.profile.measure_beam_profile` at ``distances`` [m] (lines
    of ``line_points`` over ±``half_span`` [m] along ``axes``) and
    :func:`~echocal.characterize.profile.measure_focus` at ``focus_distances`` [m] (either
    may be empty)."""
    positive_int("n_ascans", n_ascans)  # refused before the scan, not after it
    dist = np.asarray(distances, dtype=np.float64).reshape(-1)
    focal = np.asarray(focus_distances, dtype=np.float64).reshape(-1)
    if target is None and (dist.size or focal.size):
        raise EchocalValueError("target: give the point target's position for the distances")
    axis = measure_beam_axis(source, position, axis_scan, repeats=repeats)
    spectrum = measure_spectrum(source, axis.pose, n_ascans=n_ascans)
    count = len(axis.amplitude) * repeats + spectrum.n_ascans
    points = source if point_source is None else point_source
    profile = focus = None
    if target is not None and dist.size:
        profile = measure_beam_profile(
            points,
            target,
            dist,
            tilts_deg=axis.tilts_deg,
            half_span=half_span,
            points=line_points,
            axes=axes,
            repeats=repeats,
        )
        count += profile.amplitude.size * repeats
    if target is not None and focal.size:
        focus = measure_focus(points, target, focal, tilts_deg=axis.tilts_deg, repeats=repeats)
        count += focus.amplitude.size * repeats
    return ProbeCharacterization(
        source=source.description,
        axis=axis,
        spectrum=spectrum,
        profile=profile,
        focus=focus,
        measurements=count,
    )
