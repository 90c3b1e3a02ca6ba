"""echocal — ray-traced ultrasonic immersion simulator and orientation calibration.

Units are SI (metres, seconds, hertz) everywhere in code; orientation angles are
degrees at every public boundary.  The main entry points::

    from echocal import load_setup, SourceObjective, evaluate_run
    from echocal.calibrate import calibrate

    setup = load_setup("immersion-5mhz", seed=0)          # the simulator (a source)
    objective = SourceObjective(setup, setup.reference_position, parameterization="tilt")
    result = calibrate(objective, method="auto", x0=(0.0, 0.0), rng=0)
    print(result.x, result.n_measurements, evaluate_run(setup, setup.reference_position,
                                                        result).error)

See the README for the architecture and the command line.  The function
``calibrate`` lives in :mod:`echocal.calibrate` and is deliberately not
re-exported here: the name would shadow that subpackage.
"""

from __future__ import annotations

from echocal.ascan import AScan
from echocal.calibrate import CalibrationResult, method_names
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
from echocal.evaluation import angular_error, evaluate_run
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
from echocal.measurement import (
    HardwareSource,
    MeasurementSource,
    PositionerLimits,
    ReplaySource,
    SourceObjective,
    VirtualSetup,
    record,
)
from echocal.raytrace import Hits, cast
from echocal.setups import builtin_setup_names, load_setup
from echocal.signal import (
    RecordingWindow,
    get_metric,
    make_pulse,
    metric_names,
    pseudo_energy,
    pulse_names,
    synthesize,
    time_of_flight,
)
from echocal.specimen import Specimen, builtin_specimen, specimen_names
from echocal.transducer import Transducer, make_directivity

__version__ = "0.1.0"

__all__ = [
    "MM",
    "SOUND_SPEED_WATER",
    "US",
    "AScan",
    "BudgetExhaustedError",
    "CalibrationResult",
    "ConfigError",
    "DataFileError",
    "EchocalError",
    "EchocalValueError",
    "GeometryError",
    "HardwareSource",
    "Hits",
    "InstrumentError",
    "LimitError",
    "MeasurementSource",
    "Pose",
    "PositionerLimits",
    "RecordingWindow",
    "ReplaySource",
    "SourceObjective",
    "Specimen",
    "Transducer",
    "UnknownNameError",
    "VirtualSetup",
    "__version__",
    "angle_between",
    "angular_error",
    "builtin_setup_names",
    "builtin_specimen",
    "cast",
    "evaluate_run",
    "get_metric",
    "load_setup",
    "make_directivity",
    "make_pulse",
    "method_names",
    "metric_names",
    "normal_to_orientation",
    "orientation_frame",
    "orientation_normal",
    "orientation_to_tilt",
    "pseudo_energy",
    "pulse_names",
    "record",
    "specimen_names",
    "synthesize",
    "tilt_normal",
    "tilt_to_orientation",
    "time_of_flight",
]
