"""Setup files: a complete virtual measurement setup in TOML, validated by pydantic.

A setup file describes the specimen (a built-in name, shapes, or a mesh file),
the transducer, the pulse, the recording window, the medium, the receiver's
noise and the positioner's limits.  Numbers are SI (metres, seconds, hertz,
degrees for angles); any quantity may instead be a string with a unit —
``"12.7 mm"``, ``"5 MHz"``, ``"20 us"``.  A bare length that is implausibly
large for its field (a 12.7 m probe) is refused with a hint that it was
probably meant in millimetres; frequencies must be plausible (20 kHz to 1 GHz
for a probe or pulse, 20 kHz to 100 GHz for a sampling rate: ``5`` is refused
with "did you mean '5 MHz'?") and sound speeds 100 to 20 000 m/s.  Positioner
position limits may be infinite (``inf``, ``-inf`` or ``"inf"``: unlimited);
angle limits lie within [-360, 360] deg (azimuth) and [-90, 90] deg
(co-elevation).  A ``bandwidth`` is in % for gabor and B in Hz for sinc;
``"60%"`` works for both (sinc: 2B = 60 % of the centre frequency).  A setting
that does not apply (a piston's ``opening_angle``) is ignored with a warning.

Built-in setups (``echocal setup show NAME``) live as TOML files in
``echocal/data/setups/``; copy one to start your own::

    setup = load_setup("immersion-5mhz")          # a name ...
    setup = load_setup("my-rig.toml", seed=3)      # ... or a file

:func:`validate_setup_file` reports every problem at once — schema and build
problems (unknown names, pulse options, limits, a reference position inside the
part) together — each with its field path: ``transducer.width: must be > 0, got
-0.01``; :func:`load_setup` raises one :class:`~echocal.errors.ConfigError`
listing them all.

The package has one module per job: :mod:`~echocal.setups.fields` (unit-aware fields),
:mod:`~echocal.setups.schema` (the pydantic models), :mod:`~echocal.setups.build` (from a
validated configuration to a :class:`~echocal.measurement.VirtualSetup`) and
:mod:`~echocal.setups.reading` (names, files, validation, overrides).
"""

from echocal.setups.build import build_pulse, build_setup
from echocal.setups.reading import (
    builtin_setup_names,
    config_as_json,
    load_setup,
    load_setup_config,
    load_setup_with_config,
    setup_with_overrides,
    validate_setup_file,
)
from echocal.setups.schema import PulseConfig, SetupConfig

__all__ = [
    "PulseConfig",
    "SetupConfig",
    "build_pulse",
    "build_setup",
    "builtin_setup_names",
    "config_as_json",
    "load_setup",
    "load_setup_config",
    "load_setup_with_config",
    "setup_with_overrides",
    "validate_setup_file",
]
