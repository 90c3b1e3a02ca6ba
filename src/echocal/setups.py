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
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import json
import math
import tomllib
import typing
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, Literal, NoReturn

import numpy as np
import pydantic
from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationError,
    model_validator,
)

from echocal.constants import DEFAULT_CENTER_FREQUENCY, SOUND_SPEED_WATER
from echocal.echo import echo_model_names
from echocal.errors import ConfigError, DataFileError, EchocalError, UnknownNameError
from echocal.material_config import (
    LOC_TAGS,
    MaterialSpec,
    Temperature,
    build_material,
    build_medium,
)
from echocal.measurement.limits import PositionerLimits, limit_problems
from echocal.measurement.virtual import (
    MAX_SIMULATED_SAMPLES,
    ReceiverSettings,
    VirtualSetup,
    check_sample_count,
)
from echocal.signal import Pulse, RecordingWindow, make_pulse, pulse_names
from echocal.signal.gates import INTERFACE_THRESHOLD, TimeGate, check_gate, gates_by_name
from echocal.signal.noise import SNR_DB_RANGE
from echocal.signal.pulses import parse_bandwidth, plausible_bandwidth, pulse_options
from echocal.signal.window import check_window
from echocal.specimen import (
    Cylinder,
    FinitePlane,
    Specimen,
    Sphere,
    TriangleMesh,
    builtin_specimen,
    specimen_names,
)
from echocal.specimen.interior import MAX_BACK_WALL_ECHOES, Flaw, Interior
from echocal.transducer import Transducer, directivity_names, make_directivity
from echocal.units import (
    parse_quantity,
    plausible_frequency,
    plausible_sampling_rate,
    plausible_speed,
)

__all__ = [
    "SetupConfig",
    "build_pulse",
    "builtin_setup_names",
    "load_setup",
    "load_setup_config",
    "load_setup_with_config",
    "setup_with_overrides",
    "validate_setup_file",
]


# ---------------------------------------------------------------- unit-aware fields
def _quantity(
    kind: str,
    plausible_max: float | None = None,
    *,
    allow_infinite: bool = False,
    check: Callable[[str, float], float] | None = None,
):
    """A BeforeValidator: text with a unit → SI; implausible numbers refused with a hint.

    ``plausible_max`` [SI] bounds bare numbers only (``12.7`` for a probe width was meant in
    mm; ``"2 m"`` is deliberate); ``check(field, value)`` — a plausible range, e.g. of
    frequencies — applies to every finite value.  Infinite values are left to the field
    (refused unless it allows them).
    """

    def parse(value: Any) -> Any:
        bare = not isinstance(value, str)
        if isinstance(value, str):
            value = parse_quantity(
                "value", value, kind, _SI_UNIT[kind], allow_infinite=allow_infinite
            )
        elif isinstance(value, bool):
            _refuse_bool(value)
        elif not isinstance(value, int | float):
            return value  # the field reports the wrong type
        if not math.isfinite(value):
            return value
        if bare and plausible_max is not None and abs(value) > plausible_max:
            raise ValueError(
                f"{value:g} {_SI_UNIT[kind]} is implausible here; numbers are SI "
                f"({_SI_UNIT[kind]}) — did you mean '{value:g} mm'?"
                if kind == "length"
                else f"{value:g} is implausible here; give a unit, e.g. "
                f"'{value:g} {_HINT_UNIT.get(kind, 'MHz')}'"
            )
        if check is not None:
            check("", value)
        return value

    return BeforeValidator(parse)


def _refuse_bool(value: Any) -> Any:
    """TOML's ``true``/``false`` where a number belongs: refused (pydantic would read 1/0)."""
    if isinstance(value, bool):
        raise ValueError(
            f"a number is expected, not the boolean {str(value).lower()}; give a value "
            "(with a unit where the field has one)"
        )
    return value


NotBool = BeforeValidator(_refuse_bool)
"""Marks a plain number field (no unit): a TOML boolean is refused, not read as 1 or 0."""


def _not_nan(value: float) -> float:
    if math.isnan(value):
        raise ValueError("must be a number or ±inf (unlimited), not NaN")
    return value


_HINT_UNIT = {"time": "us", "frequency": "MHz"}
"""The unit a bare number of each kind was probably meant in (the refusal's hint)."""
_SI_UNIT = {"length": "m", "time": "s", "frequency": "Hz", "speed": "m/s", "angle": "deg"}

ProbeLength = Annotated[
    float, _quantity("length", plausible_max=1.0), Field(gt=0, allow_inf_nan=False)
]
Position = Annotated[float, _quantity("length", plausible_max=10.0), Field(allow_inf_nan=False)]
LimitBound = Annotated[
    float, _quantity("length", plausible_max=10.0, allow_infinite=True), AfterValidator(_not_nan)
]
"""A positioner limit [m]: ``inf``/``-inf`` (bare or as text) means unlimited."""
Size = Annotated[float, _quantity("length", plausible_max=10.0), Field(gt=0, allow_inf_nan=False)]
Frequency = Annotated[
    float, _quantity("frequency", check=plausible_frequency), Field(gt=0, allow_inf_nan=False)
]
"""An ultrasonic frequency [Hz], 20 kHz to 1 GHz (5 Hz for 5 MHz is refused with a hint)."""
SamplingRate = Annotated[
    float, _quantity("frequency", check=plausible_sampling_rate), Field(gt=0, allow_inf_nan=False)
]
Time = Annotated[float, _quantity("time", plausible_max=1.0), Field(allow_inf_nan=False)]
Speed = Annotated[
    float, _quantity("speed", check=plausible_speed), Field(gt=0, allow_inf_nan=False)
]
Angle = Annotated[float, _quantity("angle"), Field(ge=-360, le=360, allow_inf_nan=False)]
"""An angle [deg] within one turn either side of 0 (every orientation)."""
Point = tuple[Position, Position, Position]


MAX_SCALE = 1e6
"""The largest scale factor a setup takes (a mesh's units to metres, the ADC's full scale as
a multiple of the reference echo): beyond it a value is a typo, not a setting."""


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
    caps: bool = False
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
    """Reflectors inside the part (need ``thickness``)."""


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


# ---------------------------------------------------------------- building
# Each part of a setup is built and checked on its own, so that one run reports every
# problem; a check that needs another part (the transducer's piston needs the pulse's
# frequency, the reference echo needs everything) runs only when that part is valid.

_PULSE_KINDS = {
    "center_frequency": "frequency",
    "fs": "frequency",
    "phase": "angle",
    "length": "time",
    "start_time": "time",
}
"""Unit kind of the pulse options that carry one (the rest: numbers, names, paths)."""


class _FileProblem(str):
    """A problem with a file the setup refers to (mesh, pulse samples): a
    :class:`~echocal.errors.DataFileError` when it is the only kind of problem."""


def _problem(field: str, exc: Exception | str, options: tuple[str, ...] = ()) -> str:
    """``field: message`` of an error (or a message), the one form of every setup problem.

    A message that already names the field keeps its path, with a colon after it
    (``"pulse.fs must be finite"`` → ``"pulse.fs: must be finite"``); an option named first
    moves into the path (``pulse`` + ``"phase must be finite"`` → ``pulse.phase: must be
    finite``).  A missing data file stays a file problem (:class:`DataFileError`)."""
    message = str(exc)
    kind = _FileProblem if isinstance(exc, DataFileError) else str
    if message.startswith(field + " "):
        return kind(f"{field}: {message[len(field) + 1 :]}")
    if message.startswith((field + ".", field + ":")):
        return kind(message)
    for option in options:
        for sep in (": ", " "):
            if message.startswith(option + sep):
                return kind(f"{field}.{option}: {message[len(option) + len(sep) :]}")
    return kind(f"{field}: {message}")


def _pulse_params(name: str, extra: dict[str, Any], base_dir: Path) -> tuple[dict, list[str]]:
    """The pulse ``name``'s keyword parameters from the ``[pulse]`` table, in SI, and problems."""
    options = pulse_options(name)
    params: dict[str, Any] = {}
    problems = []
    for key, value in extra.items():
        field = f"pulse.{key}"
        if options is not None and key not in options:
            problems.append(f"{field}: unknown option for {name}; valid: {', '.join(options)}")
            continue
        try:
            if key == "file":  # relative to the setup file, as a mesh (absolute stays)
                params[key] = base_dir / Path(str(value))
            elif key == "bandwidth":
                continue  # after center_frequency: a percentage may refer to it
            elif key in _PULSE_KINDS and not isinstance(value, list):
                kind = _PULSE_KINDS[key]
                number = parse_quantity(field, value, kind, _SI_UNIT[kind])
                if key == "center_frequency":
                    plausible_frequency(field, number)
                elif key == "fs":
                    plausible_sampling_rate(field, number)
                params[key] = number
            else:
                params[key] = _parse_any(field, value) if isinstance(value, str) else value
        except EchocalError as exc:
            problems.append(_problem(field, exc))
    if "bandwidth" in extra and (options is None or "bandwidth" in options):
        value = extra["bandwidth"]
        fc = params.get("center_frequency", DEFAULT_CENTER_FREQUENCY)
        try:
            bandwidth = parse_bandwidth(name, value, fc, field="pulse.bandwidth")
            if isinstance(bandwidth, float):
                lobes = params.get("lobes", 4)
                plausible_bandwidth(
                    name,
                    bandwidth,
                    fc,
                    field="pulse.bandwidth",
                    bare=isinstance(value, int | float),
                    lobes=lobes if isinstance(lobes, int) and lobes > 0 else 4,
                )
            params["bandwidth"] = bandwidth
        except EchocalError as exc:
            problems.append(_problem("pulse.bandwidth", exc))
    return params, problems


def _parse_any(field: str, text: str) -> Any:
    """A string with any known unit → SI float; other strings (names, paths) unchanged."""
    for kind, default in _SI_UNIT.items():
        try:
            return parse_quantity(field, text, kind, default)
        except EchocalError:
            continue
    return text


def build_pulse(config: PulseConfig, base_dir: Path, *, where: str = "pulse") -> Pulse:
    """The pulse of a setup's ``[pulse]`` table, built as a setup builds it (file paths
    relative to ``base_dir``); every problem in one :class:`ConfigError` prefixed ``where``."""
    pulse, problems = _build_pulse(config, base_dir)
    if pulse is None:
        raise ConfigError(f"{where}: {'; '.join(problems)}")
    return pulse


def _build_pulse(config: PulseConfig, base_dir: Path) -> tuple[Pulse | None, list[str]]:
    if config.name not in pulse_names():
        return None, [
            f"pulse.name: unknown pulse {config.name!r}; choose one of: {', '.join(pulse_names())}"
        ]
    params, problems = _pulse_params(config.name, dict(config.model_extra or {}), base_dir)
    if problems:
        return None, problems
    try:
        return make_pulse(config.name, **params), []
    except EchocalError as exc:
        if isinstance(exc, DataFileError):  # the samples' file: missing or unreadable
            return None, [_FileProblem(f"pulse.file: {exc}")]
        return None, [_problem("pulse", exc, pulse_options(config.name) or ())]


def _ignored(field: str, reason: str) -> None:
    warnings.warn(f"{field} is ignored: {reason}", UserWarning, stacklevel=4)


def _build_specimen(config: SpecimenConfig, base_dir: Path) -> tuple[Specimen | None, list[str]]:
    given = [k for k in ("builtin", "shapes", "mesh") if getattr(config, k) is not None]
    if len(given) != 1:
        return None, [
            "specimen: give exactly one of builtin, shapes or mesh; "
            f"got {', '.join(given) if given else 'none'}"
        ]
    if "mesh_scale" in config.model_fields_set and config.mesh is None:
        _ignored("specimen.mesh_scale", f"it scales a mesh file; this specimen has {given[0]}")
    if config.builtin is not None:
        if config.builtin not in specimen_names():
            return None, [
                f"specimen.builtin: unknown specimen {config.builtin!r}; "
                f"choose one of: {', '.join(specimen_names())}"
            ]
        return builtin_specimen(config.builtin), []
    if config.mesh is not None:
        path = Path(config.mesh)
        path = path if path.is_absolute() else base_dir / path
        if not path.is_file():
            return None, [_FileProblem(f"specimen.mesh: mesh file not found: {path}")]
        try:
            mesh = TriangleMesh.load(path, scale=config.mesh_scale)
        except EchocalError as exc:
            return None, [_problem("specimen.mesh", exc)]
        return Specimen([mesh], name=config.name or path.stem), []
    shapes, problems = [], []
    if not config.shapes:
        problems.append("specimen.shapes: at least one shape is needed")
    for i, shape in enumerate(config.shapes or []):
        where = f"specimen.shapes.{i}"
        used = _SHAPE_FIELDS[shape.kind]
        for key in sorted(shape.model_fields_set - set(used) - {"kind", "center", "name"}):
            _ignored(f"{where}.{key}", f"a {shape.kind} takes {', '.join(used)}")
        kwargs: dict[str, Any] = {"center": shape.center, "name": shape.name or f"{shape.kind}{i}"}
        missing = [key for key in used if getattr(shape, key) is None]
        problems += [f"{where}.{key}: required for a {shape.kind}" for key in missing]
        if missing:
            continue
        kwargs.update({key: getattr(shape, key) for key in used})
        cls = {"plane": FinitePlane, "sphere": Sphere, "cylinder": Cylinder}[shape.kind]
        try:
            shapes.append(cls(**kwargs))
        except EchocalError as exc:
            problems.append(f"{where}: {exc}")
    if problems:
        return None, problems
    return Specimen(shapes, name=config.name or "custom"), []


_DIRECTIVITY_PARAMS = {
    "none": (),
    "gaussian": ("opening_angle",),
    "piston": ("radius", "frequency"),
}


def _build_transducer(
    config: TransducerConfig, pulse_frequency: float, c0: float
) -> tuple[Transducer | None, list[str]]:
    d = config.directivity
    where = "transducer.directivity"
    if d.model not in directivity_names():
        return None, [
            f"{where}.model: unknown directivity model {d.model!r}; "
            f"choose one of: {', '.join(directivity_names())}"
        ]
    used = _DIRECTIVITY_PARAMS.get(d.model, ())
    for key in sorted(d.model_fields_set - set(used) - {"model"}):
        takes = ", ".join(used) if used else "no parameters"
        _ignored(f"{where}.{key}", f"the {d.model} directivity takes {takes}")
    params: dict[str, float] = {}
    if d.model == "gaussian" and d.opening_angle is not None:
        params["opening_angle"] = d.opening_angle
    if d.model == "piston":
        params = {
            "radius": d.radius if d.radius is not None else config.width / 2,
            "frequency": d.frequency if d.frequency is not None else pulse_frequency,
            "sound_speed": c0,
        }
    try:
        directivity = make_directivity(d.model, **params)
    except EchocalError as exc:
        return None, [_problem(where, exc, ("directivity",))]
    try:
        return Transducer(
            width=config.width,
            height=config.height if config.height is not None else config.width,
            n_h=config.n_h,
            n_v=config.n_v if config.n_v is not None else config.n_h,
            pinhole_distance=config.pinhole_distance,
            focus=config.focus,
            aperture=config.aperture,
            directivity=directivity,
        ), []
    except EchocalError as exc:
        return None, [str(exc)]


def _build_parts(
    config: SetupConfig, base_dir: Path, *, invalid: frozenset[str] = frozenset()
) -> tuple[dict[str, Any], list[str]]:
    """Every part of the setup that can be built, and every problem found on the way.

    ``invalid`` names the sections whose schema already failed: they (and the checks
    that need them) are skipped, the others are still checked.
    """
    parts: dict[str, Any] = {}
    problems: list[str] = []

    def run(section: str, build: Callable[[], tuple[Any, list[str]]]) -> None:
        if section in invalid:
            return
        part, found = build()
        problems.extend(found)
        if part is not None and not found:
            parts[section] = part

    run("medium", lambda: build_medium(config.medium))
    medium = parts.get("medium")
    c0 = medium.longitudinal_speed if medium is not None else config.medium.sound_speed
    if "specimen" not in invalid and config.specimen.material is not None:
        material, found = build_material("specimen.material", config.specimen.material)
        problems.extend(found)
        parts["material"] = material
    run("pulse", lambda: _build_pulse(config.pulse, base_dir))
    pulse = parts.get("pulse")
    # the piston's default frequency is the pulse's; a broken pulse leaves the default
    fc = pulse.center_frequency if pulse is not None else DEFAULT_CENTER_FREQUENCY
    run("specimen", lambda: _build_specimen(config.specimen, base_dir))
    run("transducer", lambda: _build_transducer(config.transducer, fc, c0))
    run("window", lambda: _wrap("window", lambda: RecordingWindow(**config.window.model_dump())))
    run(
        "noise",
        lambda: _wrap("noise", lambda: ReceiverSettings(**config.noise.model_dump())),
    )
    run("echo", lambda: _check_echo(config.echo))
    if "specimen" not in invalid and config.specimen.thickness is not None:
        run("interior", lambda: _build_interior(config, parts))
    run("positioner", lambda: _build_limits(config.positioner))
    if "pulse" in parts and "window" in parts:
        for check in (check_sample_count, lambda p, w: check_window(w, p)):
            try:
                check(parts["pulse"], parts["window"])
            except EchocalError as exc:
                problems.append(_problem("window", exc, ("fs",)))
                parts.pop("window")
                break
    if "specimen" in parts and "positioner" in parts:
        problems.extend(_reference_problems(parts["specimen"], config.positioner))
    run("gates", lambda: _build_gates(config.gates, parts.get("window")))
    return parts, problems


def _build_gates(
    gates: list[GateConfig], window: RecordingWindow | None
) -> tuple[tuple[TimeGate, ...] | None, list[str]]:
    """The setup's named gates: names unique and not built-in, absolute ones inside the
    recording window (when it is valid)."""
    built: list[TimeGate] = []
    problems: list[str] = []
    for i, g in enumerate(gates):
        where = f"gates.{i}"
        try:
            gate = TimeGate(
                name=g.name, width=g.width, start=g.start, delay=g.delay, threshold=g.threshold
            )
            if window is not None:
                check_gate(gate, window, field=f"{where} ({g.name})")
        except EchocalError as exc:
            problems.append(_problem(where, exc))
            continue
        built.append(gate)
    try:
        gates_by_name(built)
    except EchocalError as exc:
        problems.append(str(exc))
    return (None, problems) if problems else (tuple(built), [])


def _wrap(field: str, build: Callable[[], Any]) -> tuple[Any, list[str]]:
    try:
        return build(), []
    except EchocalError as exc:
        return None, [_problem(field, exc)]


def _build_interior(
    config: SetupConfig, parts: dict[str, Any]
) -> tuple[Interior | None, list[str]]:
    """The plate's thickness and flaws, checked against the front face and the models."""
    spec = config.specimen
    material = parts.get("material")
    if spec.material is not None and material is None:
        return None, []  # the material's own problem is reported
    if material is None or material.is_fluid:
        return None, [
            "specimen.thickness: an interior needs a solid specimen.material "
            '(e.g. material = "steel")'
        ]
    if config.echo.reflection != "wave":
        return None, [
            "specimen.thickness: echoes from inside the part need the wave model; "
            'set [echo] reflection = "wave"'
        ]
    specimen = parts.get("specimen")
    if specimen is None:
        return None, []
    if len(specimen) != 1 or not isinstance(specimen[0], FinitePlane):
        return None, [
            "specimen.thickness: an interior needs a plate: one plane shape as the front face "
            '(e.g. builtin = "flat-plate"); curved walls are not modelled'
        ]
    try:
        flaws = tuple(
            Flaw(
                name=f.name,
                kind=f.kind,
                position=np.asarray(f.position),
                diameter=f.diameter,
                length=f.length,
                axis=np.asarray(f.axis),
            )
            for f in spec.flaws or ()
        )
        assert spec.thickness is not None  # only called with a thickness
        interior = Interior(spec.thickness, spec.back_wall_echoes, flaws)
        interior.check_inside(specimen[0])
    except EchocalError as exc:
        return None, [_problem("specimen", exc)]
    return interior, []


def _check_echo(config: EchoConfig) -> tuple[EchoConfig | None, list[str]]:
    if config.reflection not in echo_model_names():
        return None, [
            f"echo.reflection: unknown echo model {config.reflection!r}; "
            f"choose one of: {', '.join(echo_model_names())}"
        ]
    if config.spacing is not None and config.reflection != "wave":
        _ignored(
            "echo.spacing",
            f"it sets the wave model's surface sampling; this is {config.reflection}",
        )
    return config, []


def _build_limits(config: PositionerConfig) -> tuple[PositionerLimits | None, list[str]]:
    axes = {n: getattr(config, n) for n in ("x", "y", "z", "azimuth", "coelevation")}
    problems = [f"positioner.{p}" for p in limit_problems(**axes)]
    return (None, problems) if problems else (PositionerLimits(**axes), [])


def _reference_problems(specimen: Specimen, config: PositionerConfig) -> list[str]:
    """The reference position must be outside every closed shape and above the part."""
    ref = np.asarray(config.reference_position, dtype=np.float64)
    where = "positioner.reference_position"
    shown = ", ".join(f"{1e3 * v:g}" for v in ref)
    inside = int(specimen.containing(ref[None])[0])
    if inside >= 0:
        shape = specimen[inside]
        return [
            f"{where}: ({shown}) mm is inside {shape.kind} {shape.name!r} of specimen "
            f"{specimen.name!r}; the probe must be outside the part — move it above the surface"
        ]
    if not bool(specimen.surface_below(ref[0], ref[1]).hit):
        return [
            f"{where}: ({shown}) mm is not above the specimen {specimen.name!r}; "
            "move it over the part"
        ]
    return []


def build_setup(config: SetupConfig, *, base_dir: Path | None = None, seed: int | None = None):
    """A :class:`~echocal.measurement.virtual.VirtualSetup` from a validated config.

    ``seed`` overrides the file's seed (noise reproducibility).  Raises
    :class:`~echocal.errors.ConfigError` listing every problem with its field path.
    """
    base_dir = Path.cwd() if base_dir is None else base_dir
    parts, problems = _build_parts(config, base_dir)
    if problems:
        _raise_problems(config.name, problems)
    return _assemble(config, parts, seed)


def _assemble(config: SetupConfig, parts: dict[str, Any], seed: int | None) -> VirtualSetup:
    try:
        return VirtualSetup(
            specimen=parts["specimen"],
            transducer=parts["transducer"],
            pulse=parts["pulse"],
            window=parts["window"],
            receiver=parts["noise"],
            reference_position=config.positioner.reference_position,
            sound_speed=parts["medium"].longitudinal_speed,
            medium=parts["medium"],
            material=parts.get("material"),
            interior=parts.get("interior"),
            reflection=config.echo.reflection,
            synthesis=config.echo.synthesis,
            wave_spacing=config.echo.spacing,
            limits=parts["positioner"],
            gates=parts.get("gates", ()),
            rng=seed if seed is not None else config.seed,
            name=config.name,
        )
    except (ConfigError, DataFileError):
        raise
    except EchocalError as exc:
        raise ConfigError(f"{config.name}: {exc}") from None


# ---------------------------------------------------------------- reading
def builtin_setup_names() -> tuple[str, ...]:
    """Names of the setups shipped with echocal."""
    folder = importlib.resources.files("echocal") / "data" / "setups"
    return tuple(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))


def _format_errors(
    error: ValidationError, hint: str = "see `echocal setup show thesis`"
) -> list[str]:
    """One line per pydantic error: ``field.path: message, got value`` (``hint`` for typos)."""
    lines = []
    for item in error.errors():
        parts = [str(part) for part in item["loc"] if part not in LOC_TAGS]
        where = ".".join(parts) or "(top level)"
        message = item["msg"]
        if item["type"] == "extra_forbidden":
            message = f"unknown key (check the spelling; {hint})"
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


def _read_toml(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise DataFileError(f"setup file not found: {path}")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None


def _resolve(name_or_path: str | Path) -> tuple[dict[str, Any], Path]:
    text = str(name_or_path)
    if text in builtin_setup_names():
        resource = importlib.resources.files("echocal") / "data" / "setups" / f"{text}.toml"
        return tomllib.loads(resource.read_text(encoding="utf-8")), Path.cwd()
    path = Path(text)
    if path.suffix != ".toml" and not path.exists():
        raise UnknownNameError(
            f"unknown setup {text!r}: not a built-in ({', '.join(builtin_setup_names())}) "
            "and no such .toml file"
        )
    return _read_toml(path), path.parent


def load_setup_config(name_or_path: str | Path) -> tuple[SetupConfig, Path]:
    """Read and validate a setup (built-in name or TOML path); return it and its folder.

    Raises :class:`~echocal.errors.ConfigError` listing every problem with its field path.
    """
    raw, base_dir = _resolve(name_or_path)
    try:
        return SetupConfig.model_validate(raw), base_dir
    except ValidationError as exc:
        problems = _format_errors(exc)
        raise ConfigError(
            f"{name_or_path}: {len(problems)} problem(s):\n  " + "\n  ".join(problems)
        ) from None


def _check(
    name_or_path: str | Path,
) -> tuple[SetupConfig | None, Path, dict[str, Any], list[str]]:
    """Config, folder, built parts and EVERY problem of a setup (schema and build together).

    Sections whose schema fails are left out of the build checks (and so are the checks
    needing them); all other sections are still built and checked.
    """
    raw, base_dir = _resolve(name_or_path)
    try:
        config = SetupConfig.model_validate(raw)
    except ValidationError as exc:
        problems = _format_errors(exc)
        invalid = frozenset(str(item["loc"][0]) for item in exc.errors() if item["loc"])
    else:
        return config, base_dir, *_build_parts(config, base_dir)
    try:
        config = SetupConfig.model_validate({k: v for k, v in raw.items() if k not in invalid})
    except ValidationError:  # a top-level problem the schema could not pin to a key
        return None, base_dir, {}, problems
    parts, found = _build_parts(config, base_dir, invalid=invalid)
    return config, base_dir, parts, problems + found


def _raise_problems(name_or_path: str | Path, problems: list[str]) -> NoReturn:
    only_files = problems and all(isinstance(p, _FileProblem) for p in problems)
    raise (DataFileError if only_files else ConfigError)(
        f"{name_or_path}: {len(problems)} problem(s):\n  " + "\n  ".join(problems)
    )


def load_setup(name_or_path: str | Path, *, seed: int | None = None) -> VirtualSetup:
    """The :class:`~echocal.measurement.virtual.VirtualSetup` of a built-in name or TOML file.

    Raises :class:`~echocal.errors.ConfigError` listing every problem with its field path.
    """
    return load_setup_with_config(name_or_path, seed=seed)[2]


def load_setup_with_config(
    name_or_path: str | Path, *, seed: int | None = None
) -> tuple[SetupConfig, Path, VirtualSetup]:
    """:func:`load_setup`, also returning the validated config and the setup's folder."""
    config, base_dir, parts, problems = _check(name_or_path)
    if problems or config is None:
        _raise_problems(name_or_path, problems)
    return config, base_dir, _assemble(config, parts, seed)


_KEEP: Any = object()


def setup_with_overrides(
    name_or_path: str | Path,
    *,
    specimen: str | None = None,
    snr_db: float | None = _KEEP,
    seed: int | None = None,
) -> VirtualSetup:
    """:func:`load_setup` with the usual overrides applied.

    Parameters
    ----------
    specimen : a built-in specimen name replacing the setup's specimen.
    snr_db : [dB] the receiver SNR; ``None`` for a noiseless receiver; omitted: the file's.
    seed : noise seed (overrides the file's).
    """
    virtual = load_setup(name_or_path, seed=seed)
    changes: dict[str, Any] = {}
    if specimen is not None:
        changes["specimen"] = builtin_specimen(specimen)
    if snr_db is not _KEEP:
        changes["receiver"] = dataclasses.replace(virtual.receiver, snr_db=snr_db)
    if not changes:
        return virtual
    return dataclasses.replace(virtual, rng=seed if seed is not None else virtual.rng, **changes)


def validate_setup_file(name_or_path: str | Path) -> list[str]:
    """Every problem of a setup file, one line each with its field path (empty if valid).

    Schema problems and build problems (unknown names, pulse parameters, positioner
    limits, a reference position inside the part, ...) are all reported together; a
    check that needs another, broken part is skipped.  If there is no problem the
    reference echo is simulated too, so that an empty recording window is reported.
    Warnings (a setting that is ignored) are issued with :func:`warnings.warn`.
    """
    try:
        config, _, parts, problems = _check(name_or_path)
        if problems or config is None:
            return problems
        _ = _assemble(config, parts, None).noise_sigma  # simulates the reference echo
    except ConfigError as exc:
        lines = str(exc).splitlines()
        return [line.strip() for line in lines[1:]] if len(lines) > 1 else lines
    except EchocalError as exc:
        return [str(exc)]
    return []


def config_as_json(config: SetupConfig) -> str:
    """The resolved setup as pretty JSON (SI units, degrees)."""
    return json.dumps(config.model_dump(mode="json"), indent=2)
