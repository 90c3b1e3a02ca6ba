"""One probe's characterization: the beam axis, then the spectrum at that axis."""

from __future__ import annotations

from dataclasses import dataclass

from numpy.typing import ArrayLike

from echocal._validate import positive_int
from echocal.characterize.axis import BeamAxis, measure_beam_axis
from echocal.characterize.spectrum import EchoSpectrum, measure_spectrum
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
    measurements : A-scans recorded in all.
    """

    source: str
    axis: BeamAxis
    spectrum: EchoSpectrum
    measurements: int

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "source": self.source,
            "beam_axis": self.axis.to_dict(),
            "spectrum": self.spectrum.to_dict(),
            "measurements": self.measurements,
        }


def characterize_probe(
    source: MeasurementSource,
    position: ArrayLike,
    *,
    reflector_tilts_deg: ArrayLike = (0.0, 0.0),
    span_deg: float = 3.0,
    coarse_points: int = 13,
    fine_points: int = 11,
    repeats: int = 1,
    n_ascans: int = 16,
) -> ProbeCharacterization:
    """Characterize the probe on ``source`` over a flat reflector below ``position`` [m]:
    :func:`~echocal.characterize.axis.measure_beam_axis` (its keyword arguments), then
    :func:`~echocal.characterize.spectrum.measure_spectrum` at the axis found, averaging
    ``n_ascans`` A-scans."""
    positive_int("n_ascans", n_ascans)  # refused before the scan, not after it
    axis = measure_beam_axis(
        source,
        position,
        reflector_tilts_deg=reflector_tilts_deg,
        span_deg=span_deg,
        coarse_points=coarse_points,
        fine_points=fine_points,
        repeats=repeats,
    )
    spectrum = measure_spectrum(source, axis.pose, n_ascans=n_ascans)
    return ProbeCharacterization(
        source=source.description,
        axis=axis,
        spectrum=spectrum,
        measurements=len(axis.amplitude) * repeats + spectrum.n_ascans,
    )
