"""The real bench: what a measurement bench adds to the ideal simulator.

A :class:`Bench` (a setup file's ``[bench]`` table, :doc:`/bench`) holds

- the probe's mount (:mod:`~echocal.bench.mount`): beam squint and pivot offset;
- the positioner (:mod:`~echocal.bench.positioner`): backlash, steps, repeatability,
  speed and settling per axis, acquisition time — and so the time every measurement costs;
- the receiver (:mod:`~echocal.bench.receiver`): coloured (AR) noise, a gain curve, timing
  jitter and the water's temperature drift;
- the part's grain noise (:mod:`~echocal.bench.grain`).

Everything defaults to the ideal bench, on which the simulator's A-scans are bit for bit
those of a simulator without a bench.
"""

from echocal.bench.grain import GrainField, GrainNoise
from echocal.bench.model import Bench
from echocal.bench.mount import ProbeMount
from echocal.bench.positioner import AXES, Axis, PositionerModel, PositionerState
from echocal.bench.receiver import BenchReceiver, ar_noise, water_sound_speed

__all__ = [
    "AXES",
    "Axis",
    "Bench",
    "BenchReceiver",
    "GrainField",
    "GrainNoise",
    "PositionerModel",
    "PositionerState",
    "ProbeMount",
    "ar_noise",
    "water_sound_speed",
]
