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

The names are imported on first use: ``import echocal.measurement.virtual`` (the
simulator alone) does not import the calibration package behind
:class:`SourceObjective`, nor the hardware and recording modules.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from echocal._lazy import lazy_attributes

if TYPE_CHECKING:  # the same names, eagerly, for type checkers and IDEs
    from echocal.measurement.base import BaseSource, MeasurementSource
    from echocal.measurement.hardware import HardwareSource, Positioner, TcpInstrument
    from echocal.measurement.hardware import Receiver as HardwareReceiver
    from echocal.measurement.instrument_server import Faults, InstrumentServer
    from echocal.measurement.limits import PositionerLimits
    from echocal.measurement.objective import SourceObjective
    from echocal.measurement.recording import (
        RecordingGrid,
        record,
        recording_dataset,
        save_recording,
    )
    from echocal.measurement.replay import ReplaySource
    from echocal.measurement.virtual import ReceiverSettings, VirtualSetup

_WHERE = {
    "BaseSource": "echocal.measurement.base",
    "MeasurementSource": "echocal.measurement.base",
    "HardwareSource": "echocal.measurement.hardware",
    "Positioner": "echocal.measurement.hardware",
    "TcpInstrument": "echocal.measurement.hardware",
    "HardwareReceiver": "echocal.measurement.hardware:Receiver",
    "Faults": "echocal.measurement.instrument_server",
    "InstrumentServer": "echocal.measurement.instrument_server",
    "PositionerLimits": "echocal.measurement.limits",
    "SourceObjective": "echocal.measurement.objective",
    "RecordingGrid": "echocal.measurement.recording",
    "record": "echocal.measurement.recording",
    "recording_dataset": "echocal.measurement.recording",
    "save_recording": "echocal.measurement.recording",
    "ReplaySource": "echocal.measurement.replay",
    "ReceiverSettings": "echocal.measurement.virtual",
    "VirtualSetup": "echocal.measurement.virtual",
}

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

__getattr__, __dir__ = lazy_attributes(__name__, _WHERE, __all__)
