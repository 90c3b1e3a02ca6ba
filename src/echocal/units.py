"""Parsing quantities with units at the user boundary (CLI and setup files).

Inside echocal everything is SI.  Users type ``"20 mm"``, ``"5MHz"`` or
``"12.7mm"``; :func:`parse_quantity` turns such text into SI floats and refuses
a unit of the wrong kind with a message naming the field.
"""

from __future__ import annotations

import math
import re

from echocal.errors import EchocalValueError

__all__ = ["parse_angle", "parse_length", "parse_quantity"]

_SCALES: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "in": 0.0254},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9},
    "frequency": {"hz": 1.0, "khz": 1e3, "mhz": 1e6, "ghz": 1e9},
    "speed": {"m/s": 1.0, "mm/us": 1e3, "mm/µs": 1e3},
    "angle": {"deg": 1.0, "°": 1.0, "rad": 180.0 / math.pi},
}
_NUMBER_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\s\d].*)?\s*$")


def parse_quantity(field: str, text: str | float | int, kind: str, default_unit: str) -> float:
    """Parse ``text`` (number with optional unit) into SI for a quantity of ``kind``.

    Parameters
    ----------
    field : name used in error messages, e.g. ``"transducer.width"``.
    text : ``"12.7 mm"``, ``"5MHz"``, ``0.02`` (a bare number is in ``default_unit``).
    kind : one of ``length``, ``time``, ``frequency``, ``speed``, ``angle``.
    default_unit : unit of a bare number, e.g. ``"mm"`` on the CLI, ``"m"`` in files.

    Returns
    -------
    value in SI units (degrees for angles), finite.
    """
    scales = _SCALES[kind]
    if isinstance(text, bool):
        raise EchocalValueError(f"{field} must be a {kind}; got {text!r}")
    if isinstance(text, int | float):
        number, unit = float(text), default_unit
    else:
        match = _NUMBER_UNIT.match(str(text))
        if match is None:
            raise EchocalValueError(
                f"{field} must be a number with an optional {kind} unit "
                f"({', '.join(scales)}); got {text!r}"
            )
        number = float(match.group(1))
        # the Greek letter mu (U+03BC) looks like the micro sign (U+00B5): accept both
        unit = (match.group(2) or default_unit).strip().replace("\u03bc", "\u00b5")
    key = unit if unit in scales else unit.lower()
    if key not in scales:
        raise EchocalValueError(
            f"{field}: unit {unit!r} is not a {kind} unit; use one of {', '.join(scales)}"
        )
    value = number * scales[key]
    if not math.isfinite(value):
        raise EchocalValueError(f"{field} must be finite; got {text!r}")
    return value


def parse_length(field: str, text: str | float, default_unit: str = "mm") -> float:
    """Parse a length into metres (bare numbers in ``default_unit``, mm by default)."""
    return parse_quantity(field, text, "length", default_unit)


def parse_angle(field: str, text: str | float) -> float:
    """Parse an angle into degrees (bare numbers are degrees)."""
    return parse_quantity(field, text, "angle", "deg")
