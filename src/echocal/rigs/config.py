"""The rig file: a ``[rig]`` TOML table composing a positioner and a receiver from drivers.

.. code-block:: toml

    [rig]
    name = "tank-1"
    setup = "immersion-5mhz"       # optional: the setup whose [pulse] the rig transmits
    settle_time = "20 ms"          # wait after each move before acquiring

    [rig.positioner]
    driver = "visa"                # tcp | visa | python
    resource = "ASRL/dev/ttyUSB0::INSTR"
    preset = "newport-esp"         # see `echocal rig presets`
    [rig.positioner.axes]
    x = { id = "1" }               # scale: controller units per m (default 1000: mm)
    y = { id = "2" }
    z = { id = "3", limits = ["5 mm", "80 mm"] }
    azimuth = { id = "4" }         # scale default 1: degrees
    coelevation = { id = "5" }

    [rig.receiver]
    driver = "visa"
    resource = "TCPIP0::192.168.1.20::INSTR"
    preset = "keysight"
    channel = 1
    averages = 16

Every problem is reported with its field path (``rig.positioner.axes: missing ...``).
Bare numbers are SI (metres, seconds), text may carry a unit (``"20 mm"``); angles are
degrees.
"""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, ValidationError, field_validator, model_validator

from echocal.errors import ConfigError, DataFileError
from echocal.setups.fields import Time, _quantity
from echocal.setups.schema import _format_errors, _Model
from echocal.units import parse_quantity

__all__ = ["RigConfig", "load_rig_config"]

Seconds = Annotated[
    float, _quantity("time", plausible_max=3600.0), Field(gt=0, allow_inf_nan=False)
]
"""A duration [s] of instrument I/O (a timeout): > 0, at most an hour as a bare number."""
AXIS_NAMES = ("x", "y", "z", "azimuth", "coelevation")
_LINEAR = ("x", "y", "z")


def _value(axis: str, field: str, raw: Any) -> float:
    """A length [m] (x, y, z) or an angle [deg] from a number (SI) or text with a unit."""
    kind, unit = ("length", "m") if axis in _LINEAR else ("angle", "deg")
    return parse_quantity(f"{axis}.{field}", raw, kind, unit, allow_infinite=field == "limits")


class AxisConfig(_Model):
    """One axis: the controller's axis id and scale, or a fixed value."""

    id: str | None = None
    scale: float | None = Field(default=None, gt=0, allow_inf_nan=False)
    fixed: float | str | None = None
    limits: tuple[float | str, float | str] | None = None

    @field_validator("id", mode="before")
    @classmethod
    def _id_text(cls, value: Any) -> Any:
        return str(value) if isinstance(value, int) and not isinstance(value, bool) else value

    @model_validator(mode="after")
    def _one_of(self) -> AxisConfig:
        if (self.id is None) == (self.fixed is None):
            raise ValueError("give the controller's axis id, or a fixed value (not both)")
        return self


class AxesConfig(_Model):
    """All five axes; a missing one is refused (before anything moves)."""

    x: AxisConfig
    y: AxisConfig
    z: AxisConfig
    azimuth: AxisConfig
    coelevation: AxisConfig

    @model_validator(mode="before")
    @classmethod
    def _all_axes(cls, data: Any) -> Any:
        if isinstance(data, dict):
            missing = [a for a in AXIS_NAMES if a not in data]
            if missing:
                raise ValueError(
                    f"missing axis {', '.join(missing)}: a positioner needs all of "
                    f"{', '.join(AXIS_NAMES)} (map each to a controller axis id, or give "
                    "it a fixed value, e.g. azimuth = { fixed = 0 }); got "
                    + (", ".join(map(str, data)) or "none")
                )
        return data


class TcpDriver(_Model):
    """An instrument speaking echocal's TCP line protocol (the emulator, for tests/demos)."""

    driver: Literal["tcp"]
    address: str
    timeout: Seconds = 2.0
    retries: int = Field(default=3, ge=0)


class _Visa(_Model):
    resource: str = Field(min_length=1)
    library: str = ""
    preset: str
    timeout: Seconds = 2.0
    retries: int = Field(default=2, ge=0)
    read_termination: str = "\n"
    write_termination: str = "\n"
    baud_rate: int | None = Field(default=None, gt=0)
    commands: dict[str, Any] = Field(default_factory=dict)


class VisaMotionDriver(_Visa):
    """A SCPI motion controller over VISA (serial, TCP, USB, GPIB)."""

    driver: Literal["visa"]
    preset: str = "scpi"
    axes: AxesConfig
    motion_timeout: Seconds = 60.0


class VisaScopeDriver(_Visa):
    """A SCPI oscilloscope or digitizer over VISA."""

    driver: Literal["visa"]
    channel: int = Field(default=1, ge=1)
    averages: int = Field(default=1, ge=1, le=65536)
    time_offset: Time = 0.0


class PythonDriver(_Model):
    """Any Python class (``module:Class``) implementing Positioner or Receiver."""

    driver: Literal["python"]
    class_: str = Field(alias="class", min_length=1)
    options: dict[str, Any] = Field(default_factory=dict)


PositionerDriver = Annotated[
    TcpDriver | VisaMotionDriver | PythonDriver, Field(discriminator="driver")
]
ReceiverDriver = Annotated[
    TcpDriver | VisaScopeDriver | PythonDriver, Field(discriminator="driver")
]


class RigSection(_Model):
    """``[rig]``: a name, the pulse's setup, the settle time and the two devices."""

    name: str = "rig"
    description: str = ""
    setup: str | None = None
    settle_time: Annotated[Time, Field(ge=0)] = 0.0
    positioner: PositionerDriver
    receiver: ReceiverDriver


class RigConfig(_Model):
    """A rig file: one ``[rig]`` table."""

    rig: RigSection


def axis_values(axis: str, config: AxisConfig) -> dict[str, Any]:
    """The :class:`~echocal.rigs.motion.Axis` keywords of ``config`` (SI, default scale)."""
    scale = config.scale if config.scale is not None else (1e3 if axis in _LINEAR else 1.0)
    limits = None
    if config.limits is not None:
        limits = tuple(_value(axis, "limits", v) for v in config.limits)
        if not limits[0] <= limits[1] or any(math.isnan(v) for v in limits):
            raise ValueError(f"{axis}.limits must be [low, high]; got {list(config.limits)}")
    fixed = None if config.fixed is None else _value(axis, "fixed", config.fixed)
    return {"name": axis, "id": config.id, "scale": scale, "fixed": fixed, "limits": limits}


def load_rig_config(path: str | Path) -> tuple[RigConfig, Path]:
    """Read and validate a rig file; return it and its folder.

    Raises :class:`~echocal.errors.ConfigError` listing every problem with its field path
    (:class:`~echocal.errors.DataFileError` if the file is missing).
    """
    path = Path(path)
    if not path.is_file():
        raise DataFileError(f"rig file not found: {path}")
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    try:
        config = RigConfig.model_validate(raw)
    except ValidationError as exc:
        problems = [
            re.sub(r"\.(tcp|visa|python)(?=[.:])", "", line, count=1)  # the driver's tag
            for line in _format_errors(exc, hint="see docs/rigs.md")
        ]
        raise ConfigError(
            f"{path}: {len(problems)} problem(s):\n  " + "\n  ".join(problems)
        ) from None
    positioner = config.rig.positioner
    if isinstance(positioner, VisaMotionDriver):
        problems = []
        for axis in AXIS_NAMES:
            try:
                axis_values(axis, getattr(positioner.axes, axis))
            except ValueError as exc:
                problems.append(f"rig.positioner.axes.{axis}: {exc}")
        if problems:
            raise ConfigError(f"{path}: {len(problems)} problem(s):\n  " + "\n  ".join(problems))
    return config, path.parent
