"""Measurement sources: the simulator, recorded data and real hardware behind one interface.

* :class:`MeasurementSource` — the protocol (``measure``, ``measure_many``, ``limits``,
  ``description``, ``close``); :class:`BaseSource` — a convenience base class.
* :class:`VirtualSetup` — the ray-traced simulator (with :class:`ReceiverSettings`).
* :class:`ReplaySource` — A-scans recorded on a pose grid by :func:`record`
  (:class:`RecordingGrid`), replayed from a NetCDF file.
* :class:`HardwareSource` — a :class:`Positioner` and a :class:`HardwareReceiver`
  composed into a source; :class:`TcpInstrument` speaks the line protocol and
  :class:`InstrumentServer` emulates a rig on TCP (with injected :class:`Faults`).
* :class:`SourceObjective` — any source + a metric as a calibration objective.

``HardwareReceiver`` is :class:`echocal.measurement.hardware.Receiver` (the device
that acquires an A-scan), renamed here so it does not clash with
:class:`echocal.signal.Receiver` (the noise/ADC model of the simulator).
"""

from echocal.measurement.base import BaseSource, MeasurementSource
from echocal.measurement.hardware import HardwareSource, Positioner, TcpInstrument
from echocal.measurement.hardware import Receiver as HardwareReceiver
from echocal.measurement.instrument_server import Faults, InstrumentServer
from echocal.measurement.limits import PositionerLimits
from echocal.measurement.objective import SourceObjective
from echocal.measurement.recording import RecordingGrid, record, recording_dataset, save_recording
from echocal.measurement.replay import ReplaySource
from echocal.measurement.virtual import ReceiverSettings, VirtualSetup

__all__ = [
    "BaseSource",
    "Faults",
    "HardwareReceiver",
    "HardwareSource",
    "InstrumentServer",
    "MeasurementSource",
    "Positioner",
    "PositionerLimits",
    "ReceiverSettings",
    "RecordingGrid",
    "ReplaySource",
    "SourceObjective",
    "TcpInstrument",
    "VirtualSetup",
    "record",
    "recording_dataset",
    "save_recording",
]
