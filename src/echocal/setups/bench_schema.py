"""The ``[bench]`` table of a setup file (:mod:`echocal.bench`): its pydantic models and
the :class:`~echocal.bench.Bench` it builds.  Every field defaults to the ideal bench.

Units: positions [m] and tilts [deg] (text with a unit allowed: ``"0.1 mm"``), speeds
[m/s] and [deg/s], times [s] (``"50 ms"``), gains [dB], the temperature drift [°C/h]."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from echocal.bench import Axis, Bench, BenchReceiver, GrainNoise, PositionerModel, ProbeMount
from echocal.bench.grain import MAX_SCATTERERS
from echocal.setups.fields import Angle, NotBool, Position, Size, Time

__all__ = [
    "BenchAxisConfig",
    "BenchConfig",
    "BenchGrainConfig",
    "BenchPositionerConfig",
    "BenchProbeConfig",
    "BenchReceiverConfig",
    "build_bench",
]

_Amount = Annotated[float, NotBool, Field(ge=0, le=10, allow_inf_nan=False)]
"""A size on an axis's own unit ([m] or [deg]), 0 to 10 (beyond: a typo, not a bench)."""
_Wait = Annotated[Time, Field(ge=0)]


class _BenchModel(BaseModel):
    """Unknown keys refused, values frozen; every number refuses a TOML boolean (NotBool or
    a unit-aware field)."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class BenchAxisConfig(_BenchModel):
    """One positioner axis: [m] and [m/s] for x, y, z; [deg] and [deg/s] for the tilts."""

    backlash: _Amount = 0.0
    step: _Amount = 0.0
    repeatability: _Amount = 0.0
    speed: Annotated[float, NotBool, Field(gt=0)] = math.inf
    settling: _Wait = 0.0


class BenchProbeConfig(_BenchModel):
    """The probe's squint (two angles [deg]) and pivot offset ([m], probe frame)."""

    squint: tuple[Angle, Angle] = (0.0, 0.0)
    pivot_offset: tuple[Position, Position, Position] = (0.0, 0.0, 0.0)


class BenchPositionerConfig(_BenchModel):
    """The positioner's five axes, the acquisition time of one A-scan [s] and how moves end
    (``"both"``: from either side; ``"positive"``: backlash compensated)."""

    x: BenchAxisConfig = BenchAxisConfig()
    y: BenchAxisConfig = BenchAxisConfig()
    z: BenchAxisConfig = BenchAxisConfig()
    tilt_x: BenchAxisConfig = BenchAxisConfig()
    tilt_y: BenchAxisConfig = BenchAxisConfig()
    acquisition_time: _Wait = 0.0
    approach: Literal["both", "positive"] = "both"


class BenchReceiverConfig(_BenchModel):
    """Coloured noise (AR coefficients), gain curve ([time, dB] points), jitter [s] and the
    water's temperature drift [°C/h] (from ``[medium] temperature``, 20 °C if not given)."""

    noise_ar: list[Annotated[float, NotBool, Field(allow_inf_nan=False)]] = []
    gain_curve: list[tuple[Time, Annotated[float, NotBool, Field(allow_inf_nan=False)]]] = []
    jitter: _Wait = 0.0
    temperature_drift: Annotated[float, NotBool, Field(ge=-100, le=100, allow_inf_nan=False)] = 0.0


class BenchGrainConfig(_BenchModel):
    """Grain noise: its level [dB re the reference echo], the grains and their seed."""

    level_db: Annotated[float, NotBool, Field(allow_inf_nan=False, le=40)]
    scatterers: Annotated[int, NotBool, Field(ge=1, le=MAX_SCATTERERS)] = 400
    depth: Size = 0.01
    width: Size = 0.02
    seed: Annotated[int, NotBool, Field(ge=0)] = 0


class BenchConfig(_BenchModel):
    """The ``[bench]`` table."""

    probe: BenchProbeConfig = BenchProbeConfig()
    positioner: BenchPositionerConfig = BenchPositionerConfig()
    receiver: BenchReceiverConfig = BenchReceiverConfig()
    grain: BenchGrainConfig | None = None


def build_bench(config: BenchConfig, temperature: float | None) -> Bench:
    """The :class:`~echocal.bench.Bench` of a validated ``[bench]`` table; ``temperature``
    [°C] is the water's at the start (``[medium] temperature``; None: 20 °C)."""
    positioner = config.positioner
    axes = {
        name: Axis(**getattr(positioner, name).model_dump())
        for name in ("x", "y", "z", "tilt_x", "tilt_y")
    }
    receiver = config.receiver
    return Bench(
        probe=ProbeMount(squint=config.probe.squint, pivot_offset=config.probe.pivot_offset),
        positioner=PositionerModel(
            **axes, acquisition_time=positioner.acquisition_time, approach=positioner.approach
        ),
        receiver=BenchReceiver(
            noise_ar=tuple(receiver.noise_ar),
            gain_curve=tuple(receiver.gain_curve),
            jitter=receiver.jitter,
            temperature=20.0 if temperature is None else temperature,
            temperature_drift=receiver.temperature_drift / 3600.0,
        ),
        grain=None if config.grain is None else GrainNoise(**config.grain.model_dump()),
    )
