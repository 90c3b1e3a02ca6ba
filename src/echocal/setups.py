"""Setup files: a complete virtual measurement setup in TOML, validated by pydantic.

A setup file describes the specimen (a built-in name, shapes, or a mesh file),
the transducer, the pulse, the recording window, the medium, the receiver's
noise and the positioner's limits.  Numbers are SI (metres, seconds, hertz,
degrees for angles); any quantity may instead be a string with a unit —
``"12.7 mm"``, ``"5 MHz"``, ``"20 us"``.  A bare length that is implausibly
large for its field (a 12.7 m probe) is refused with a hint that it was
probably meant in millimetres.

Built-in setups (``echocal setup show NAME``) live as TOML files in
``echocal/data/setups/``; copy one to start your own::

    setup = load_setup("immersion-5mhz")          # a name ...
    setup = load_setup("my-rig.toml", seed=3)      # ... or a file

:func:`validate_setup_file` reports every problem at once, each with its
field path: ``transducer.width: must be > 0, got -0.01``.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import json
import math
import tomllib
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError

from echocal.constants import SOUND_SPEED_WATER
from echocal.errors import ConfigError, DataFileError, EchocalError, UnknownNameError
from echocal.measurement.limits import PositionerLimits
from echocal.measurement.virtual import ReceiverSettings, VirtualSetup
from echocal.signal import RecordingWindow, make_pulse
from echocal.specimen import (
    Cylinder,
    FinitePlane,
    Specimen,
    Sphere,
    TriangleMesh,
    builtin_specimen,
    specimen_names,
)
from echocal.transducer import Transducer, make_directivity
from echocal.units import parse_quantity

__all__ = [
    "SetupConfig",
    "builtin_setup_names",
    "load_setup",
    "load_setup_config",
    "setup_with_overrides",
    "validate_setup_file",
]


# ---------------------------------------------------------------- unit-aware fields
def _quantity(kind: str, plausible_max: float | None = None):
    def parse(value: Any) -> Any:
        if isinstance(value, str):
            return parse_quantity("value", value, kind, _SI_UNIT[kind])
        if (
            plausible_max is not None
            and isinstance(value, int | float)
            and not isinstance(value, bool)
            and abs(value) > plausible_max
        ):
            raise ValueError(
                f"{value:g} {_SI_UNIT[kind]} is implausible here; numbers are SI "
                f"({_SI_UNIT[kind]}) — did you mean '{value:g} mm'?"
                if kind == "length"
                else f"{value:g} is implausible here; give a unit, e.g. '{value:g} MHz'"
            )
        return value

    return BeforeValidator(parse)


_SI_UNIT = {"length": "m", "time": "s", "frequency": "Hz", "speed": "m/s", "angle": "deg"}

ProbeLength = Annotated[
    float, _quantity("length", plausible_max=1.0), Field(gt=0, allow_inf_nan=False)
]
Position = Annotated[float, _quantity("length", plausible_max=10.0), Field(allow_inf_nan=False)]
Size = Annotated[float, _quantity("length", plausible_max=10.0), Field(gt=0, allow_inf_nan=False)]
Frequency = Annotated[float, _quantity("frequency"), Field(gt=0, allow_inf_nan=False)]
Time = Annotated[float, _quantity("time", plausible_max=1.0), Field(allow_inf_nan=False)]
Speed = Annotated[float, _quantity("speed"), Field(gt=0, allow_inf_nan=False)]
Angle = Annotated[float, _quantity("angle"), Field(allow_inf_nan=False)]
Point = tuple[Position, Position, Position]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class MediumConfig(_Model):
    """The coupling medium."""

    sound_speed: Speed = SOUND_SPEED_WATER


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


class SpecimenConfig(_Model):
    """Exactly one of: a built-in name, a list of shapes, or a mesh file (+ scale)."""

    builtin: str | None = None
    shapes: list[ShapeConfig] | None = None
    mesh: str | None = None
    mesh_scale: float = Field(default=1.0, gt=0)
    name: str | None = None


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
    n_h: int = Field(default=64, ge=1, le=1024)
    n_v: int | None = Field(default=None, ge=1, le=1024)
    focal_length: ProbeLength = 0.02
    aperture: Literal["rectangular", "circular"] = "rectangular"
    directivity: DirectivityConfig = DirectivityConfig()


class PulseConfig(BaseModel):
    """The transmitted pulse: ``name`` plus that pulse's parameters (units allowed)."""

    model_config = ConfigDict(extra="allow", frozen=True)
    name: str = "gabor"


class WindowConfig(_Model):
    """The receiver's recording window."""

    fs: Frequency = 100e6
    start: Time = 0.0
    n_samples: int = Field(default=4096, ge=16, le=1 << 22)


def _none_word(value: Any) -> Any:
    """TOML has no null: the word "none" (any case) stands for None."""
    return None if isinstance(value, str) and value.strip().lower() == "none" else value


class NoiseConfig(_Model):
    """Receiver noise: SNR of the reference echo (``"none"``: noiseless), ADC, saturation."""

    snr_db: Annotated[float | None, BeforeValidator(_none_word)] = Field(
        default=30.0, allow_inf_nan=False
    )
    adc_bits: int | None = Field(default=None, ge=1, le=32)
    full_scale: float | None = Field(default=None, gt=0)


class EchoConfig(_Model):
    """How rays become echoes and echoes an A-scan."""

    reflection: str = "lambertian"
    synthesis: Literal["fast", "direct"] = "fast"


class PositionerConfig(_Model):
    """Reference position (for the SNR) and the positioner's limits."""

    reference_position: Point = (0.0, 0.0, 0.02)
    x: tuple[Position, Position] = (-math.inf, math.inf)
    y: tuple[Position, Position] = (-math.inf, math.inf)
    z: tuple[Position, Position] = (-math.inf, math.inf)
    azimuth: tuple[Angle, Angle] = (-180.0, 180.0)
    coelevation: tuple[Angle, Angle] = (-60.0, 60.0)


class SetupConfig(_Model):
    """A complete virtual setup, as read from a TOML file."""

    name: str = "setup"
    description: str = ""
    seed: int | None = Field(default=None, ge=0)
    medium: MediumConfig = MediumConfig()
    specimen: SpecimenConfig = SpecimenConfig(builtin="flat-plate")
    transducer: TransducerConfig = TransducerConfig()
    pulse: PulseConfig = PulseConfig()
    window: WindowConfig = WindowConfig()
    noise: NoiseConfig = NoiseConfig()
    echo: EchoConfig = EchoConfig()
    positioner: PositionerConfig = PositionerConfig()


# ---------------------------------------------------------------- building
def _pulse_params(config: PulseConfig, base_dir: Path) -> dict[str, Any]:
    params: dict[str, Any] = {}
    for key, value in (config.model_extra or {}).items():
        if key == "file":  # a sampled pulse's file: relative to the setup file, as a mesh
            params[key] = base_dir / Path(str(value))  # (an absolute path stays as it is)
            continue
        params[key] = _parse_any(f"pulse.{key}", value) if isinstance(value, str) else value
    return params


def _parse_any(field: str, text: str) -> Any:
    """A string with any known unit → SI float; other strings (names, paths) unchanged."""
    for kind, default in _SI_UNIT.items():
        try:
            return parse_quantity(field, text, kind, default)
        except EchocalError:
            continue
    return text


def _build_specimen(config: SpecimenConfig, base_dir: Path) -> Specimen:
    given = [k for k in ("builtin", "shapes", "mesh") if getattr(config, k) is not None]
    if len(given) != 1:
        raise ConfigError(
            "specimen: give exactly one of builtin, shapes or mesh; "
            f"got {', '.join(given) if given else 'none'}"
        )
    if config.builtin is not None:
        if config.builtin not in specimen_names():
            raise ConfigError(
                f"specimen.builtin: unknown specimen {config.builtin!r}; "
                f"choose one of: {', '.join(specimen_names())}"
            )
        return builtin_specimen(config.builtin)
    if config.mesh is not None:
        path = Path(config.mesh)
        path = path if path.is_absolute() else base_dir / path
        if not path.is_file():
            raise DataFileError(f"specimen.mesh: mesh file not found: {path}")
        mesh = TriangleMesh.load(path, scale=config.mesh_scale)
        return Specimen([mesh], name=config.name or path.stem)
    shapes = []
    for i, shape in enumerate(config.shapes or []):
        kwargs: dict[str, Any] = {"center": shape.center, "name": shape.name or f"{shape.kind}{i}"}
        for key in _SHAPE_FIELDS[shape.kind]:
            value = getattr(shape, key)
            if value is None:
                raise ConfigError(f"specimen.shapes.{i}.{key}: required for a {shape.kind}")
            kwargs[key] = value
        cls = {"plane": FinitePlane, "sphere": Sphere, "cylinder": Cylinder}[shape.kind]
        shapes.append(cls(**kwargs))
    if not shapes:
        raise ConfigError("specimen.shapes: at least one shape is needed")
    return Specimen(shapes, name=config.name or "custom")


def _build_transducer(config: TransducerConfig, pulse_frequency: float, c0: float) -> Transducer:
    d = config.directivity
    params: dict[str, float] = {}
    if d.model == "gaussian" and d.opening_angle is not None:
        params["opening_angle"] = d.opening_angle
    if d.model == "piston":
        params = {
            "radius": d.radius if d.radius is not None else config.width / 2,
            "frequency": d.frequency if d.frequency is not None else pulse_frequency,
            "sound_speed": c0,
        }
    return Transducer(
        width=config.width,
        height=config.height if config.height is not None else config.width,
        n_h=config.n_h,
        n_v=config.n_v if config.n_v is not None else config.n_h,
        focal_length=config.focal_length,
        aperture=config.aperture,
        directivity=make_directivity(d.model, **params),
    )


def build_setup(config: SetupConfig, *, base_dir: Path | None = None, seed: int | None = None):
    """A :class:`~echocal.measurement.virtual.VirtualSetup` from a validated config.

    ``seed`` overrides the file's seed (noise reproducibility).
    """
    base_dir = Path.cwd() if base_dir is None else base_dir
    try:
        pulse = make_pulse(config.pulse.name, **_pulse_params(config.pulse, base_dir))
    except UnknownNameError as exc:
        raise ConfigError(f"pulse.name: {exc}") from None
    except EchocalError as exc:
        raise ConfigError(f"pulse: {exc}") from None
    c0 = config.medium.sound_speed
    p = config.positioner
    try:
        return VirtualSetup(
            specimen=_build_specimen(config.specimen, base_dir),
            transducer=_build_transducer(config.transducer, pulse.center_frequency, c0),
            pulse=pulse,
            window=RecordingWindow(
                fs=config.window.fs, start=config.window.start, n_samples=config.window.n_samples
            ),
            receiver=ReceiverSettings(
                snr_db=config.noise.snr_db,
                adc_bits=config.noise.adc_bits,
                full_scale=config.noise.full_scale,
            ),
            reference_position=p.reference_position,
            sound_speed=c0,
            reflection=config.echo.reflection,
            synthesis=config.echo.synthesis,
            limits=PositionerLimits(
                x=p.x, y=p.y, z=p.z, azimuth=p.azimuth, coelevation=p.coelevation
            ),
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
        where = ".".join(str(part) for part in item["loc"]) or "(top level)"
        message = item["msg"]
        if item["type"] == "extra_forbidden":
            message = f"unknown key (check the spelling; {hint})"
        elif "input" in item and item["type"] not in ("missing",):
            message = f"{message}, got {item['input']!r}"
        message = message.replace("Value error, ", "").replace("Input should be", "must be")
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


def load_setup(name_or_path: str | Path, *, seed: int | None = None) -> VirtualSetup:
    """The :class:`~echocal.measurement.virtual.VirtualSetup` of a built-in name or TOML file."""
    config, base_dir = load_setup_config(name_or_path)
    return build_setup(config, base_dir=base_dir, seed=seed)


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

    Schema problems are all reported together; if the schema is valid the setup
    is also built (meshes loaded, pulse made, reference echo simulated) so that
    problems only visible then are reported too.
    """
    try:
        config, base_dir = load_setup_config(name_or_path)
        setup = build_setup(config, base_dir=base_dir)
        _ = setup.noise_sigma  # simulates the reference echo: catches an empty window
    except ConfigError as exc:
        lines = str(exc).splitlines()
        return [line.strip() for line in lines[1:]] if len(lines) > 1 else lines
    except EchocalError as exc:
        return [str(exc)]
    return []


def config_as_json(config: SetupConfig) -> str:
    """The resolved setup as pretty JSON (SI units, degrees)."""
    return json.dumps(config.model_dump(mode="json"), indent=2)
