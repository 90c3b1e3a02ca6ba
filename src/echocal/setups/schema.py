"""The schema of setup files: one pydantic model per table, and the one-line messages of
its validation errors (see :mod:`echocal.setups`)."""

from __future__ import annotations

import math
import typing
from collections.abc import Mapping
from typing import Annotated, Any, Literal

import pydantic
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StrictBool,
    ValidationError,
    model_validator,
)

from echocal.constants import SOUND_SPEED_WATER
from echocal.material_config import (
    LOC_TAGS,
    MaterialSpec,
    Temperature,
)
from echocal.measurement.virtual import (
    MAX_SIMULATED_SAMPLES,
)
from echocal.setups.bench_schema import BenchConfig
from echocal.setups.fields import (
    MAX_SCALE,
    Angle,
    Frequency,
    LimitBound,
    NotBool,
    Point,
    ProbeLength,
    SamplingRate,
    Size,
    Speed,
    Time,
)
from echocal.signal.gates import INTERFACE_THRESHOLD
from echocal.signal.noise import SNR_DB_RANGE
from echocal.specimen.interior import MAX_BACK_WALL_ECHOES, MAX_SHEAR_LEGS


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    @pydantic.model_validator(mode="before")
    @classmethod
    def _no_bool(cls, data: Any) -> Any:
        """``true`` where a number belongs is refused (pydantic would read it as 1).

        A model-level check (a field validator on every field would also touch the
        discriminator fields of tagged unions, which pydantic forbids); the message names
        the field first and :func:`_format_errors` moves it into the path."""
        if not isinstance(data, dict):
            return data
        for name, value in data.items():
            field = cls.model_fields.get(name)
            if field is None or not isinstance(value, bool):
                continue
            annotation = field.annotation
            if annotation is not bool and bool not in typing.get_args(annotation):
                raise ValueError(f"{name}: must be a number; got {str(value).lower()}")
        return data


class MediumConfig(_Model):
    """The coupling medium: a fluid ``material`` (water by default) and its sound speed.

    The sound speed in effect is ``sound_speed`` (100 to 20 000 m/s) when given (a
    measured one); else the material's, if ``material`` or ``temperature`` is given (water
    at ``temperature`` [°C], 0 to 95); else the thesis's c₀ = 1480 m/s (water's density
    and attenuation still apply).
    """

    material: MaterialSpec = "water"
    sound_speed: Speed = SOUND_SPEED_WATER
    temperature: Temperature | None = None


class ShapeConfig(_Model):
    """One shape of a specimen; which fields apply depends on ``kind``."""

    kind: Literal["plane", "sphere", "cylinder"]
    center: Point = (0.0, 0.0, 0.0)
    width: Size | None = None
    height: Size | None = None
    radius: Size | None = None
    length: Size | None = None
    azimuth: Angle = 0.0
    coelevation: Angle = 0.0
    surface: Literal["outside", "inside"] = "outside"
    caps: StrictBool = False
    """A cylinder's end discs are part of its surface too (true or false only)."""
    name: str | None = None


_SHAPE_FIELDS = {
    "plane": ("width", "height", "azimuth", "coelevation"),
    "sphere": ("radius",),
    "cylinder": ("radius", "length", "azimuth", "coelevation", "surface", "caps"),
}


class FlawConfig(_Model):
    """A reflector inside the part (see :mod:`echocal.specimen.interior`)."""

    name: str
    kind: Literal["side-drilled-hole", "flat-bottom-hole", "pore"]
    position: Point
    diameter: Size
    length: Size | None = None
    axis: tuple[float, float, float] = (0.0, 1.0, 0.0)


class LayerConfig(_Model):
    """One layer of a layered plate (``[[specimen.layers]]``, top first): its material
    (a built-in name or an inline table) and thickness."""

    material: MaterialSpec
    thickness: Size


class GateConfig(_Model):
    """A named gate (``[[gates]]``): absolute (``start``) or triggered by the interface echo
    (``trigger = "interface"`` and ``delay``); see :mod:`echocal.signal.gates`."""

    name: str = Field(min_length=1)
    width: Annotated[Time, Field(gt=0)]
    start: Time | None = None
    trigger: Literal["interface"] | None = None
    delay: Time | None = None
    threshold: Annotated[float, NotBool] = Field(
        default=INTERFACE_THRESHOLD, gt=0, le=1, allow_inf_nan=False
    )

    @pydantic.model_validator(mode="after")
    def _one_kind(self) -> GateConfig:
        if self.trigger is None and (self.start is None or self.delay is not None):
            raise ValueError(
                "an absolute gate takes start and width; a gate that follows the front wall "
                'takes trigger = "interface", delay and width'
            )
        if self.trigger is not None and (self.delay is None or self.start is not None):
            raise ValueError(
                'a gate with trigger = "interface" takes delay (after the front-wall '
                "echo) and width, not start"
            )
        return self


class SpecimenConfig(_Model):
    """Exactly one of: a built-in name, a list of shapes, or a mesh file (+ scale)."""

    builtin: str | None = None
    shapes: list[ShapeConfig] | None = None
    mesh: str | None = None
    mesh_scale: Annotated[float, NotBool] = Field(
        default=1.0, gt=0, le=MAX_SCALE, allow_inf_nan=False
    )
    name: str | None = None
    material: MaterialSpec | None = None
    """The part's material; None: a perfect reflector (the thesis)."""
    thickness: Size | None = None
    """A plate's thickness below its front face (needs a solid material and the wave model);
    None: no interior (a half-space)."""
    back_wall_echoes: Annotated[int, NotBool] = Field(default=3, ge=0, le=MAX_BACK_WALL_ECHOES)
    """How many back-wall echoes (the back wall and its multiples) are simulated."""
    flaws: list[FlawConfig] | None = None
    """Reflectors inside the part (need ``thickness`` or ``layers``)."""
    layers: list[LayerConfig] | None = None
    """A layered plate, top first (instead of ``material`` and ``thickness``); its echo
    train holds every path up to order ``back_wall_echoes`` (2M − 1 reflections)."""
    shear_legs: Annotated[int, NotBool] = Field(default=0, ge=0, le=MAX_SHEAR_LEGS)
    """With layers: the most mode-converted (shear) legs an echo path may have; each such
    path is an echo of its own (0: longitudinal paths only)."""
    exact_stack: StrictBool = False
    """With layers, under a flat circular probe: the A-scan is the whole stack's exact
    plane-wave response (every multiple and mode conversion), the listed paths plus a
    ``stack-remainder`` echo; costlier (docs/layered-parts.md)."""


class DirectivityConfig(_Model):
    """Directivity model and its parameters (``opening_angle`` or piston ``radius``)."""

    model: str = "gaussian"
    opening_angle: Angle | None = None
    radius: ProbeLength | None = None
    frequency: Frequency | None = None


class TransducerConfig(_Model):
    """The probe (pinhole model, thesis §2.1.2)."""

    width: ProbeLength = 0.01
    height: ProbeLength | None = None
    n_h: Annotated[int, NotBool] = Field(default=64, ge=1, le=1024)
    n_v: Annotated[int | None, NotBool] = Field(default=None, ge=1, le=1024)
    pinhole_distance: ProbeLength = 0.02
    focus: ProbeLength | None = None
    aperture: Literal["rectangular", "circular"] = "rectangular"
    directivity: DirectivityConfig = DirectivityConfig()

    @model_validator(mode="before")
    @classmethod
    def _renamed_focal_length(cls, data: Any) -> Any:
        if isinstance(data, dict) and "focal_length" in data:
            raise ValueError(
                "focal_length was renamed: it is the ray model's pinhole_distance (it only "
                "spreads the rays); for a focused probe give its acoustic focal length in "
                "water as focus"
            )
        return data


class PulseConfig(BaseModel):
    """The transmitted pulse: ``name`` plus that pulse's parameters (units allowed)."""

    model_config = ConfigDict(extra="allow", frozen=True)
    name: str = "gabor"


class WindowConfig(_Model):
    """The receiver's recording window."""

    fs: SamplingRate = 100e6
    start: Time = 0.0
    n_samples: Annotated[int, NotBool] = Field(default=4096, ge=16, le=MAX_SIMULATED_SAMPLES)


def _none_word(value: Any) -> Any:
    """TOML has no null: the word "none" (any case) stands for None."""
    return None if isinstance(value, str) and value.strip().lower() == "none" else value


class NoiseConfig(_Model):
    """Receiver noise: SNR of the reference echo (``"none"``: noiseless), ADC, saturation."""

    snr_db: Annotated[float | None, NotBool, BeforeValidator(_none_word)] = Field(
        default=30.0, allow_inf_nan=False, ge=SNR_DB_RANGE[0], le=SNR_DB_RANGE[1]
    )
    adc_bits: Annotated[int | None, NotBool, BeforeValidator(_none_word)] = Field(
        default=None, ge=1, le=32
    )
    full_scale: Annotated[float | None, NotBool, BeforeValidator(_none_word)] = Field(
        default=None, gt=0, le=MAX_SCALE, allow_inf_nan=False
    )


class EchoConfig(_Model):
    """How the surface becomes echoes: the thesis's ray models or the wave model."""

    reflection: str = "lambertian"
    synthesis: Literal["fast", "direct"] = "fast"
    spacing: ProbeLength | None = None


class PositionerConfig(_Model):
    """Reference position (for the SNR) and the positioner's limits.

    Position limits [m] may be infinite (``inf``, ``-inf`` or ``"inf"``: unlimited); angle
    limits [deg] must lie within [-360, 360] (azimuth) and [-90, 90] (co-elevation).
    """

    reference_position: Point = (0.0, 0.0, 0.02)
    x: tuple[LimitBound, LimitBound] = (-math.inf, math.inf)
    y: tuple[LimitBound, LimitBound] = (-math.inf, math.inf)
    z: tuple[LimitBound, LimitBound] = (-math.inf, math.inf)
    azimuth: tuple[Angle, Angle] = (-180.0, 180.0)
    coelevation: tuple[Angle, Angle] = (-60.0, 60.0)


class SetupConfig(_Model):
    """A complete virtual setup, as read from a TOML file."""

    name: str = "setup"
    description: str = ""
    seed: Annotated[int | None, NotBool] = Field(default=None, ge=0)
    medium: MediumConfig = MediumConfig()
    specimen: SpecimenConfig = SpecimenConfig(builtin="flat-plate")
    transducer: TransducerConfig = TransducerConfig()
    pulse: PulseConfig = PulseConfig()
    window: WindowConfig = WindowConfig()
    noise: NoiseConfig = NoiseConfig()
    echo: EchoConfig = EchoConfig()
    positioner: PositionerConfig = PositionerConfig()
    gates: list[GateConfig] = []
    """Named measurement gates (``--gate NAME``), besides front-wall and back-wall."""
    bench: BenchConfig | None = None
    """The real bench (:mod:`echocal.bench`); None: the ideal bench."""


def _flaw_by_name(parts: list[str], raw: Mapping[str, Any] | None) -> list[str]:
    """``specimen.flaws.0.x`` → ``specimen.flaws.NAME.x`` when the raw file's flaw 0 has a
    name: flaws are named the same way here and in the interior's own checks."""
    if raw is None or parts[:2] != ["specimen", "flaws"] or len(parts) < 3:
        return parts
    if not parts[2].isdigit():
        return parts
    try:
        name = raw["specimen"]["flaws"][int(parts[2])]["name"]
    except (KeyError, IndexError, TypeError):
        return parts
    if not isinstance(name, str) or not name.strip():
        return parts
    return [*parts[:2], name, *parts[3:]]


def _format_errors(
    error: ValidationError,
    hint: str = "see `echocal setup show thesis`",
    raw: Mapping[str, Any] | None = None,
) -> list[str]:
    """One line per pydantic error: ``field.path: message, got value`` (``hint`` for typos);
    given the ``raw`` setup data, a flaw is named by its name (``specimen.flaws.sdh``)."""
    lines = []
    for item in error.errors():
        parts = [str(part) for part in item["loc"] if part not in LOC_TAGS]
        parts = _flaw_by_name(parts, raw)
        where = ".".join(parts) or "(top level)"
        message = item["msg"]
        if item["type"] == "extra_forbidden":
            message = f"unknown key (check the spelling; {hint})"
        elif item["type"] == "bool_type":  # a StrictBool switch given a word or a number
            message = f"must be true or false (unquoted: {parts[-1]} = true), got {item['input']!r}"
        elif (
            "input" in item
            and item["type"] not in ("missing",)
            and "got " not in message  # our own messages quote the value already
            and "implausible" not in message
        ):
            message = f"{message}, got {item['input']!r}"
        message = message.replace("Value error, ", "").replace("Input should be", "must be")
        field, sep, rest = message.partition(": ")
        if sep and field.isidentifier() and rest.startswith("must be a number"):
            where, message = f"{where}.{field}" if parts else field, rest  # see _Model._no_bool
        lines.append(f"{where}: {message}")
    return lines
