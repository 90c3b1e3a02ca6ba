"""echocal — ray-traced ultrasonic immersion simulator and orientation calibration.

Units are SI (metres, seconds, hertz) everywhere in code; orientation angles are
degrees at every public boundary.  See the README for the architecture.
"""

from __future__ import annotations

from echocal.constants import MM, SOUND_SPEED_WATER, US
from echocal.errors import (
    BudgetExhaustedError,
    ConfigError,
    DataFileError,
    EchocalError,
    EchocalValueError,
    GeometryError,
    InstrumentError,
    LimitError,
    UnknownNameError,
)
from echocal.geometry import (
    Pose,
    angle_between,
    normal_to_orientation,
    orientation_frame,
    orientation_normal,
    orientation_to_tilt,
    tilt_normal,
    tilt_to_orientation,
)

__version__ = "0.1.0"

__all__ = [
    "MM",
    "SOUND_SPEED_WATER",
    "US",
    "BudgetExhaustedError",
    "ConfigError",
    "DataFileError",
    "EchocalError",
    "EchocalValueError",
    "GeometryError",
    "InstrumentError",
    "LimitError",
    "Pose",
    "UnknownNameError",
    "__version__",
    "angle_between",
    "normal_to_orientation",
    "orientation_frame",
    "orientation_normal",
    "orientation_to_tilt",
    "tilt_normal",
    "tilt_to_orientation",
]
