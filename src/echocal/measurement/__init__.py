"""Measurement sources: the simulator, recorded data and real hardware behind one interface."""

from echocal.measurement.base import BaseSource, MeasurementSource
from echocal.measurement.limits import PositionerLimits

__all__ = ["BaseSource", "MeasurementSource", "PositionerLimits"]
