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

import importlib
import importlib.metadata
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the same names, eagerly, for type checkers and IDEs
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
    from echocal.materials import (
        MATERIALS,
        WATER,
        Attenuation,
        Material,
        critical_angles,
        material,
        material_names,
        reflection_fluid_solid,
        reflection_normal,
        reflection_solid_fluid,
        transmission_fluid_solid,
        transmission_normal,
        transmission_solid_fluid,
        water,
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

_LAZY: dict[str, str] = {
    "MATERIALS": "echocal.materials",
    "WATER": "echocal.materials",
    "Attenuation": "echocal.materials",
    "Material": "echocal.materials",
    "critical_angles": "echocal.materials",
    "material": "echocal.materials",
    "material_names": "echocal.materials",
    "reflection_fluid_solid": "echocal.materials",
    "reflection_normal": "echocal.materials",
    "reflection_solid_fluid": "echocal.materials",
    "transmission_fluid_solid": "echocal.materials",
    "transmission_normal": "echocal.materials",
    "transmission_solid_fluid": "echocal.materials",
    "water": "echocal.materials",
    "AScan": "echocal.ascan",
    "BudgetExhaustedError": "echocal.errors",
    "CalibrationResult": "echocal.calibrate",
    "ConfigError": "echocal.errors",
    "DataFileError": "echocal.errors",
    "EchocalError": "echocal.errors",
    "EchocalValueError": "echocal.errors",
    "GeometryError": "echocal.errors",
    "HardwareSource": "echocal.measurement",
    "Hits": "echocal.raytrace",
    "InstrumentError": "echocal.errors",
    "LimitError": "echocal.errors",
    "MM": "echocal.constants",
    "MeasurementSource": "echocal.measurement",
    "Pose": "echocal.geometry",
    "PositionerLimits": "echocal.measurement",
    "RecordingWindow": "echocal.signal",
    "ReplaySource": "echocal.measurement",
    "SOUND_SPEED_WATER": "echocal.constants",
    "SourceObjective": "echocal.measurement",
    "Specimen": "echocal.specimen",
    "Transducer": "echocal.transducer",
    "US": "echocal.constants",
    "UnknownNameError": "echocal.errors",
    "VirtualSetup": "echocal.measurement",
    "angle_between": "echocal.geometry",
    "angular_error": "echocal.evaluation",
    "builtin_setup_names": "echocal.setups",
    "builtin_specimen": "echocal.specimen",
    "cast": "echocal.raytrace",
    "evaluate_run": "echocal.evaluation",
    "get_metric": "echocal.signal",
    "load_setup": "echocal.setups",
    "make_directivity": "echocal.transducer",
    "make_pulse": "echocal.signal",
    "method_names": "echocal.calibrate",
    "metric_names": "echocal.signal",
    "normal_to_orientation": "echocal.geometry",
    "orientation_frame": "echocal.geometry",
    "orientation_normal": "echocal.geometry",
    "orientation_to_tilt": "echocal.geometry",
    "pseudo_energy": "echocal.signal",
    "pulse_names": "echocal.signal",
    "record": "echocal.measurement",
    "specimen_names": "echocal.specimen",
    "synthesize": "echocal.signal",
    "tilt_normal": "echocal.geometry",
    "tilt_to_orientation": "echocal.geometry",
    "time_of_flight": "echocal.signal",
}
"""Public name -> the module that defines it, imported on first use (PEP 562): `import
echocal` and the command line's start stay fast."""

try:
    __version__: str = importlib.metadata.version("echocal")
except importlib.metadata.PackageNotFoundError:  # a source tree that was never installed
    __version__ = "0+unknown"
"""The installed distribution's version (one source: ``pyproject.toml``)."""

__all__ = [
    "MATERIALS",
    "MM",
    "SOUND_SPEED_WATER",
    "US",
    "WATER",
    "AScan",
    "Attenuation",
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
    "Material",
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
    "critical_angles",
    "evaluate_run",
    "get_metric",
    "load_setup",
    "make_directivity",
    "make_pulse",
    "material",
    "material_names",
    "method_names",
    "metric_names",
    "normal_to_orientation",
    "orientation_frame",
    "orientation_normal",
    "orientation_to_tilt",
    "pseudo_energy",
    "pulse_names",
    "record",
    "reflection_fluid_solid",
    "reflection_normal",
    "reflection_solid_fluid",
    "specimen_names",
    "synthesize",
    "tilt_normal",
    "tilt_to_orientation",
    "time_of_flight",
    "transmission_fluid_solid",
    "transmission_normal",
    "transmission_solid_fluid",
    "water",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'echocal' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
