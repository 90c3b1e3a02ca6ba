"""Rigs: a positioner and a receiver from the lab's own stack, described in a rig file.

* :func:`connect_rig` / :func:`check_rig` — a ``[rig]`` TOML file (``echocal.rigs.config``)
  to a connected :class:`Rig` (a :class:`~echocal.measurement.HardwareSource`);
* :class:`VisaReceiver` — a SCPI oscilloscope through PyVISA, presets
  :data:`SCOPE_PRESETS` (Keysight, Tektronix, Rigol);
* :class:`VisaPositioner` — a SCPI-style motion controller, presets :data:`MOTION_PRESETS`;
* :mod:`echocal.rigs.ophyd_devices` and :mod:`echocal.rigs.plans` — Bluesky (``bluesky``
  extra): ophyd devices for the simulator and :func:`~echocal.rigs.plans.calibrate_plan`;
* :mod:`echocal.rigs.scpi_bench` — a simulated SCPI bench (motion controller and
  oscilloscope on TCP) serving the simulator's pose-dependent echoes to the VISA drivers
  through pyvisa-py.

PyVISA, Bluesky and ophyd are optional (extras ``visa`` and ``bluesky``); they are
imported on first use and a missing one is named with the extra to install.
"""

from echocal.rigs.config import RigConfig, load_rig_config
from echocal.rigs.connect import SIM_LIBRARY, Rig, RigCheck, check_rig, connect_rig, sim_library
from echocal.rigs.motion import MOTION_PRESETS, Axis, MotionPreset, VisaPositioner, motion_preset
from echocal.rigs.scope import SCOPE_PRESETS, ScopePreset, VisaReceiver, scope_preset
from echocal.rigs.visa_io import VisaInstrument

__all__ = [
    "MOTION_PRESETS",
    "SCOPE_PRESETS",
    "SIM_LIBRARY",
    "Axis",
    "MotionPreset",
    "Rig",
    "RigCheck",
    "RigConfig",
    "ScopePreset",
    "VisaInstrument",
    "VisaPositioner",
    "VisaReceiver",
    "check_rig",
    "connect_rig",
    "load_rig_config",
    "motion_preset",
    "scope_preset",
    "sim_library",
]
