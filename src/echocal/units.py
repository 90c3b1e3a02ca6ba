"""Parsing quantities with units at the user boundary (CLI and setup files).

Inside echocal everything is SI.  Users type ``"20 mm"``, ``"5MHz"`` or
``"12.7mm"``; :func:`parse_quantity` turns such text into SI floats and refuses
a unit of the wrong kind with a message naming the field.
"""

from __future__ import annotations

import math
import re

from echocal.errors import EchocalValueError

__all__ = [
    "SAMPLING_RANGE",
    "SOUND_SPEED_RANGE",
    "ULTRASONIC_RANGE",
    "format_frequency",
    "parse_angle",
    "parse_length",
    "parse_quantity",
    "plausible_frequency",
    "plausible_sampling_rate",
    "plausible_speed",
]

ULTRASONIC_RANGE = (20e3, 1e9)
"""[Hz] plausible centre frequencies of an ultrasonic probe or pulse (20 kHz to 1 GHz)."""

SAMPLING_RANGE = (20e3, 100e9)
"""[Hz] plausible sampling frequencies of a digitizer (20 kHz to 100 GHz)."""

SOUND_SPEED_RANGE = (100.0, 20_000.0)
"""[m/s] plausible sound speeds of a coupling medium or part (gases to diamond)."""

_SCALES: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "in": 0.0254},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9},
    "frequency": {"hz": 1.0, "khz": 1e3, "mhz": 1e6, "ghz": 1e9},
    "speed": {"m/s": 1.0, "mm/us": 1e3, "mm/µs": 1e3},
    "angle": {"deg": 1.0, "°": 1.0, "rad": 180.0 / math.pi},
    "density": {
        "kg/m3": 1.0,
        "kg/m^3": 1.0,
        "kg/m³": 1.0,
        "g/cm3": 1e3,
        "g/cm^3": 1e3,
        "g/cm³": 1e3,
    },
    # amplitude attenuation; 1 dB = 1/NEPER_TO_DB Np (20·log10(e) ≈ 8.686 dB per neper)
    "attenuation": {
        "np/m": 1.0,
        "np/cm": 1e2,
        "np/mm": 1e3,
        "db/m": math.log(10.0) / 20.0,
        "db/cm": 1e2 * math.log(10.0) / 20.0,
        "db/mm": 1e3 * math.log(10.0) / 20.0,
    },
}
_NUMBER_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\s\d].*)?\s*$")
_INFINITY = re.compile(r"^\s*([-+]?(?:infinity|inf))\b\s*([^\s\d].*)?\s*$", re.IGNORECASE)


def parse_quantity(
    field: str,
    text: str | float | int,
    kind: str,
    default_unit: str,
    *,
    allow_infinite: bool = False,
) -> float:
    """Parse ``text`` (number with optional unit) into SI for a quantity of ``kind``.

    Parameters
    ----------
    field : name used in error messages, e.g. ``"transducer.width"``.
    text : ``"12.7 mm"``, ``"5MHz"``, ``0.02`` (a bare number is in ``default_unit``).
    kind : one of ``length``, ``time``, ``frequency``, ``speed``, ``angle``, ``density``
        (kg/m3, g/cm3), ``attenuation`` (Np/m, dB/mm, ...: amplitude attenuation).
    default_unit : unit of a bare number, e.g. ``"mm"`` on the CLI, ``"m"`` in files.
    allow_infinite : accept ``inf``/``-inf`` (also as text, ``"inf"``, ``"-inf mm"``), e.g.
        for the limits of an unlimited axis.  NaN is always refused.

    Returns
    -------
    value in SI units (degrees for angles), finite unless ``allow_infinite``.
    """
    scales = _SCALES[kind]
    if isinstance(text, bool):
        raise EchocalValueError(f"{field} must be a {kind}; got {text!r}")
    if isinstance(text, int | float):
        number, unit = float(text), default_unit
    else:
        match = _NUMBER_UNIT.match(str(text))
        if match is None and allow_infinite:  # "inf", "-inf", "+inf mm": a number of ±inf
            match = _INFINITY.match(str(text))
        if match is None:
            raise EchocalValueError(
                f"{field} must be a number with an optional {kind} unit "
                f"({', '.join(scales)}); got {text!r}"
            )
        number = float(match.group(1))
        # the Greek letter mu (U+03BC) looks like the micro sign (U+00B5): accept both
        unit = (match.group(2) or default_unit).strip().replace("\u03bc", "\u00b5")
    value = number * scales[_unit_key(field, unit, kind, scales)]
    if math.isnan(value) or (math.isinf(value) and not allow_infinite):
        raise EchocalValueError(f"{field} must be finite; got {text!r}")
    return value


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"


def _unit_key(field: str, unit: str, kind: str, scales: dict[str, float]) -> str:
    key = unit if unit in scales else unit.lower()
    if key not in scales:
        raise EchocalValueError(
            f"{field}: unit {unit!r} is not {_article(kind)} {kind} unit; "
            f"use one of {', '.join(scales)}"
        )
    return key


def _prefix(field: str) -> str:
    """``"field: "`` for a message, or nothing when the caller names the field itself."""
    return f"{field}: " if field else ""


def format_frequency(value: float) -> str:
    """``5e6`` → ``"5 MHz"``: a frequency [Hz] with the largest unit that keeps it >= 1."""
    for unit, scale in (("GHz", 1e9), ("MHz", 1e6), ("kHz", 1e3)):
        if abs(value) >= scale:
            return f"{value / scale:.4g} {unit}"
    return f"{value:.4g} Hz"


def _frequency_hint(value: float, low: float, high: float) -> str:
    """`` — did you mean '5 MHz'?`` when ``value`` [Hz] read in a larger unit is plausible."""
    if value <= 0 or value >= low:
        return ""
    for unit, scale in (("MHz", 1e6), ("kHz", 1e3), ("GHz", 1e9)):
        if low <= value * scale <= high:
            return f"; numbers without a unit are in Hz — did you mean '{value:g} {unit}'?"
    return ""


def plausible_frequency(
    field: str,
    value: float,
    *,
    plausible: tuple[float, float] = ULTRASONIC_RANGE,
    what: str = "an ultrasonic frequency",
) -> float:
    """Return ``value`` [Hz] if it lies in ``plausible``; otherwise refuse it with a hint.

    ``plausible_frequency("pulse.center_frequency", 5)`` refuses 5 Hz (``... is implausible
    for an ultrasonic frequency (20 kHz to 1 GHz); ... did you mean '5 MHz'?``).  A value
    outside the range would make the simulator sample seconds-long pulses at MHz rates
    (GiB of memory, hours of work).
    """
    low, high = plausible
    if not low <= value <= high:
        raise EchocalValueError(
            _prefix(field) + f"{format_frequency(value)} is implausible for {what} "
            f"({format_frequency(low)} to {format_frequency(high)})"
            + _frequency_hint(value, low, high)
        )
    return value


def plausible_sampling_rate(field: str, value: float) -> float:
    """:func:`plausible_frequency` for a digitizer's sampling rate [Hz] (:data:`SAMPLING_RANGE`)."""
    return plausible_frequency(field, value, plausible=SAMPLING_RANGE, what="a sampling rate")


def plausible_speed(field: str, value: float) -> float:
    """Return ``value`` [m/s] if it lies in :data:`SOUND_SPEED_RANGE`; else refuse it with a hint.

    ``1.48`` (km/s or mm/µs typed as m/s) suggests ``'1.48 mm/us'``.
    """
    low, high = SOUND_SPEED_RANGE
    if not low <= value <= high:
        hint = ""
        if low <= value * 1e3 <= high:
            hint = f"; numbers without a unit are in m/s — did you mean '{value:g} mm/us'?"
        raise EchocalValueError(
            _prefix(field) + f"{value:g} m/s is implausible for a sound speed "
            f"({low:g} to {high:g} m/s){hint}"
        )
    return value


def parse_length(field: str, text: str | float, default_unit: str = "mm") -> float:
    """Parse a length into metres (bare numbers in ``default_unit``, mm by default)."""
    return parse_quantity(field, text, "length", default_unit)


def parse_angle(field: str, text: str | float) -> float:
    """Parse an angle into degrees (bare numbers are degrees)."""
    return parse_quantity(field, text, "angle", "deg")
