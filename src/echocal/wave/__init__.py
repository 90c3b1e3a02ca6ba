"""The wave echo model: diffraction-correct echoes of piston probes (see ``echocal.wave.model``)."""

from echocal.wave.model import WaveEchoModel
from echocal.wave.probe import (
    Aperture,
    PistonProbe,
    RectangularProbe,
    curvature_for_focus,
    oneil_on_axis,
)

__all__ = [
    "Aperture",
    "PistonProbe",
    "RectangularProbe",
    "WaveEchoModel",
    "curvature_for_focus",
    "oneil_on_axis",
]
