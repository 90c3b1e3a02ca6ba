"""The ``[medium]`` and ``material`` entries of setup files: a name or an inline table.

::

    [medium]
    material = "water"                  # a built-in fluid (the default)
    temperature = 22                    # [°C] water's speed and density at 22 °C

    [specimen]
    builtin = "flat-plate"
    material = "steel"                  # or an inline table:
    # material = { density = "7850 kg/m3", longitudinal_speed = "5900 m/s",
    #              shear_speed = "3230 m/s",
    #              attenuation = { alpha0 = "0.02 dB/mm", f_ref = "5 MHz", exponent = 1 } }

Quantities take units (``kg/m3``, ``g/cm3``; ``m/s``, ``mm/us``; ``Np/m``, ``dB/mm``;
``Hz``, ``MHz``); bare numbers are SI.  :func:`build_material` turns an entry into a
:class:`~echocal.materials.Material` and reports problems with their field path:
``specimen.material.shear_speed: must be below longitudinal_speed (5900 m/s); got
6000 m/s``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Discriminator, Field, Tag

from echocal.errors import EchocalError
from echocal.materials import Attenuation, Material, material, water
from echocal.units import SOUND_SPEED_RANGE, parse_quantity, plausible_speed

__all__ = [
    "LOC_TAGS",
    "AttenuationConfig",
    "MaterialConfig",
    "MaterialSpec",
    "build_material",
    "build_medium",
]


def _unit(
    kind: str, si_unit: str, check: Callable[[str, float], float] | None = None
) -> BeforeValidator:
    """Text with a unit → SI float; bools refused (pydantic would read ``true`` as 1.0);
    ``check(field, value)`` — a plausible range — applies to every finite number."""

    def parse(value: Any) -> Any:
        if isinstance(value, bool):
            raise ValueError(f"must be a number; got {str(value).lower()}")
        if isinstance(value, str) and kind:
            value = parse_quantity("value", value, kind, si_unit)
        if check is not None and isinstance(value, int | float) and math.isfinite(value):
            check("", value)
        return value

    return BeforeValidator(parse)


MAX_DENSITY = 25_000.0
"""[kg/m³] above every solid (osmium: 22 590 kg/m³)."""
MAX_ATTENUATION = 1.0e5
"""[Np/m] at the reference frequency: ~870 dB/mm, beyond any material an echo crosses."""
MAX_REFERENCE_FREQUENCY = 1.0e9
"""[Hz] an attenuation's reference frequency (1 GHz, acoustic microscopy's range)."""

Density = Annotated[
    float, _unit("density", "kg/m3"), Field(gt=0, le=MAX_DENSITY, allow_inf_nan=False)
]
SpeedValue = Annotated[
    float, _unit("speed", "m/s"), Field(ge=0, le=SOUND_SPEED_RANGE[1], allow_inf_nan=False)
]
PlausibleSpeed = Annotated[
    float, _unit("speed", "m/s", check=plausible_speed), Field(gt=0, allow_inf_nan=False)
]
"""A sound speed [m/s], 100 to 20 000 m/s (a bare 1.48 is refused: did you mean mm/us?)."""
Temperature = Annotated[float, _unit("", ""), Field(ge=0, le=95, allow_inf_nan=False)]
"""[°C] of liquid water."""
AlphaValue = Annotated[
    float, _unit("attenuation", "Np/m"), Field(ge=0, le=MAX_ATTENUATION, allow_inf_nan=False)
]
FrequencyValue = Annotated[
    float,
    _unit("frequency", "Hz"),
    Field(gt=0, le=MAX_REFERENCE_FREQUENCY, allow_inf_nan=False),
]
Exponent = Annotated[float, _unit("", ""), Field(ge=0, le=4, allow_inf_nan=False)]
"""A dimensionless power-law exponent (text is not parsed for a unit)."""


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class AttenuationConfig(_Model):
    """α(f) = alpha0·(f/f_ref)^exponent: alpha0 [Np/m or dB/mm ...] at f_ref [Hz]."""

    alpha0: AlphaValue = 0.0
    f_ref: FrequencyValue = 1.0e6
    exponent: Exponent = 2.0


class MaterialConfig(_Model):
    """An inline material: density, speeds (shear 0 for a fluid), attenuation."""

    name: str = "custom"
    density: Density
    longitudinal_speed: PlausibleSpeed
    shear_speed: SpeedValue = 0.0
    attenuation: AttenuationConfig | None = None
    shear_attenuation: AttenuationConfig | None = None


def _kind(value: Any) -> str | None:
    if isinstance(value, str):
        return "material-name"
    if isinstance(value, dict | MaterialConfig):
        return "material-table"
    return None  # neither: pydantic reports the wrong type


LOC_TAGS = frozenset({"material-name", "material-table"})
"""Tags pydantic puts into an error's location; error messages leave them out."""

MaterialSpec = Annotated[
    Annotated[str, Tag("material-name")] | Annotated[MaterialConfig, Tag("material-table")],
    Discriminator(
        _kind,
        custom_error_type="material",
        custom_error_message="must be a material name (e.g. 'steel') or a table with "
        "density, longitudinal_speed, shear_speed, attenuation",
    ),
]
"""A setup file's ``material``: a built-in name or an inline table."""


def build_medium(config: Any) -> tuple[Material | None, list[str]]:
    """The fluid of a setup's ``[medium]`` (``material``, ``sound_speed``, ``temperature``)
    with the sound speed in effect, and its problems, each with its field path.

    The sound speed in effect is ``sound_speed`` when given; else the material's, if
    ``material`` or ``temperature`` is given (water at ``temperature`` [°C]:
    :func:`~echocal.materials.water`); else the file's default (the thesis's c₀).
    """
    given = config.model_fields_set
    if config.temperature is not None:
        if not (isinstance(config.material, str) and config.material.strip().lower() == "water"):
            return None, [
                "medium.temperature: applies to the built-in water only; for another fluid "
                "give its sound_speed (or a material table)"
            ]
        medium: Material | None = water(config.temperature)
        problems: list[str] = []
    else:
        medium, problems = build_material("medium.material", config.material)
    if medium is None:
        return None, problems
    if not medium.is_fluid:
        return None, [
            f"medium.material: {medium.name!r} is a solid (shear_speed {medium.shear_speed:g} "
            "m/s); the coupling medium must be a fluid (shear_speed 0)"
        ]
    if "sound_speed" in given or not given & {"material", "temperature"}:
        medium = replace(medium, longitudinal_speed=config.sound_speed)
    return medium, []


def _attenuation(config: AttenuationConfig | None) -> Attenuation | None:
    return None if config is None else Attenuation(**config.model_dump())


def build_material(where: str, spec: MaterialSpec) -> tuple[Material | None, list[str]]:
    """The :class:`Material` of a setup entry at ``where`` (e.g. ``"specimen.material"``)
    and its problems, each ``where.field: message``."""
    if isinstance(spec, str):
        try:
            return material(spec), []
        except EchocalError as exc:
            return None, [f"{where}: {exc}"]
    kwargs: dict[str, Any] = spec.model_dump(exclude={"attenuation", "shear_attenuation"})
    problems = []
    for key in ("attenuation", "shear_attenuation"):
        try:
            value = _attenuation(getattr(spec, key))
        except EchocalError as exc:
            problems.append(_field_message(f"{where}.{key}", str(exc)))
            continue
        if value is not None:
            kwargs[key] = value
    if problems:
        return None, problems
    try:
        return Material(**kwargs), []
    except EchocalError as exc:
        return None, [_field_message(where, str(exc))]


def _field_message(where: str, message: str) -> str:
    """``"density must be > 0; got -1"`` at ``where`` → ``"where.density: must be > 0; ..."``;
    a message naming its field with a colon (``"shear_attenuation: ..."``) likewise."""
    head, _, rest = message.partition(" ")
    name = head.rstrip(":")
    if name.isidentifier() and rest:
        return f"{where}.{name}: {rest}"
    return f"{where}: {message}"
