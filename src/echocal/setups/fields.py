"""Unit-aware fields of setup files: a number (SI) or a string with a unit, checked for
plausibility, never a boolean or NaN (see :mod:`echocal.setups`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Annotated, Any

from pydantic import (
    AfterValidator,
    BeforeValidator,
    Field,
)

from echocal.units import (
    parse_quantity,
    plausible_frequency,
    plausible_sampling_rate,
    plausible_speed,
)


# ---------------------------------------------------------------- unit-aware fields
def _quantity(
    kind: str,
    plausible_max: float | None = None,
    *,
    allow_infinite: bool = False,
    check: Callable[[str, float], float] | None = None,
    positive_in: str | None = None,
):
    """A BeforeValidator: text with a unit → SI; implausible numbers refused with a hint.

    ``plausible_max`` [SI] bounds bare numbers only (``12.7`` for a probe width was meant in
    mm; ``"2 m"`` is deliberate); ``check(field, value)`` — a plausible range, e.g. of
    frequencies — applies to every finite value.  Infinite values are left to the field
    (refused unless it allows them); with ``positive_in`` (the unit users write, ``"mm"``)
    a NaN or infinite value is refused as "must be a finite number > 0 [mm]".
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
            if positive_in is not None:
                raise ValueError(f"must be a finite number > 0 [{positive_in}]")
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
    float,
    _quantity("length", plausible_max=1.0, positive_in="mm"),
    Field(gt=0, allow_inf_nan=False),
]
Position = Annotated[float, _quantity("length", plausible_max=10.0), Field(allow_inf_nan=False)]
LimitBound = Annotated[
    float, _quantity("length", plausible_max=10.0, allow_infinite=True), AfterValidator(_not_nan)
]
"""A positioner limit [m]: ``inf``/``-inf`` (bare or as text) means unlimited."""
Size = Annotated[
    float,
    _quantity("length", plausible_max=10.0, positive_in="mm"),
    Field(gt=0, allow_inf_nan=False),
]
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
