"""Probe characterization on a bench (EN 12668-2 / ASTM E1065 style measurements).

- :func:`~echocal.characterize.axis.measure_beam_axis`: the beam axis over a flat
  reflector and its squint against the mechanical axis;
- :func:`~echocal.characterize.spectrum.measure_spectrum`: centre frequency and −6 dB
  bandwidth from the front-wall echo's spectrum;
- :func:`~echocal.characterize.profile.measure_beam_profile`: the −6 dB beam width at
  several distances from lateral scans over a point target (a ball);
- :func:`~echocal.characterize.profile.measure_focus`: the on-axis echo against distance
  and the focal distance;
- :func:`~echocal.characterize.probe.characterize_probe`: all of them, one report.

Every function takes any :class:`~echocal.measurement.base.MeasurementSource`, so the
same code characterizes a simulated probe and one on a rig.
"""

from echocal.characterize.axis import AxisScan, BeamAxis, measure_beam_axis, squint_of
from echocal.characterize.probe import ProbeCharacterization, characterize_probe
from echocal.characterize.profile import (
    BeamProfile,
    FocalScan,
    half_max_width,
    measure_beam_profile,
    measure_focus,
)
from echocal.characterize.spectrum import EchoSpectrum, measure_spectrum, spectrum_band

__all__ = [
    "AxisScan",
    "BeamAxis",
    "BeamProfile",
    "EchoSpectrum",
    "FocalScan",
    "ProbeCharacterization",
    "characterize_probe",
    "half_max_width",
    "measure_beam_axis",
    "measure_beam_profile",
    "measure_focus",
    "measure_spectrum",
    "spectrum_band",
    "squint_of",
]
