"""Probe characterization on a bench (EN 12668-2 / ASTM E1065 style measurements).

- :func:`~echocal.characterize.axis.measure_beam_axis`: the beam axis over a flat
  reflector and its squint against the mechanical axis;
- :func:`~echocal.characterize.spectrum.measure_spectrum`: centre frequency and −6 dB
  bandwidth from the front-wall echo's spectrum;
- :func:`~echocal.characterize.probe.characterize_probe`: both, one report.

Every function takes any :class:`~echocal.measurement.base.MeasurementSource`, so the
same code characterizes a simulated probe and one on a rig.
"""

from echocal.characterize.axis import BeamAxis, measure_beam_axis, squint_of
from echocal.characterize.probe import ProbeCharacterization, characterize_probe
from echocal.characterize.spectrum import EchoSpectrum, measure_spectrum, spectrum_band

__all__ = [
    "BeamAxis",
    "EchoSpectrum",
    "ProbeCharacterization",
    "characterize_probe",
    "measure_beam_axis",
    "measure_spectrum",
    "spectrum_band",
    "squint_of",
]
