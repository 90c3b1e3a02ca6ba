"""What the user tells the importer that the file does not say: :class:`ScanFacts`.

Given as keyword options (the CLI's ``--fs 100MHz``) or a small TOML mapping
(``--mapping scan.toml``)::

    sampling_rate = "100 MHz"      # or time = "t" (the variable/column holding the time axis)
    start_time = "60 us"
    x_start = "0 mm"               # or x = "xpos": a variable holding the positions
    x_step = "0.5 mm"
    x_end = "20 mm"                # optional: checked against the step and the trace count
    y_start = "0 mm"
    y_step = "1 mm"
    sound_speed = "1480 m/s"       # the coupling medium
    probe_z = "50 mm"              # the probe's height above z = 0
    scale_factor = 0.00048828125   # volts per ADC code
    probe = { name = "V309", center_frequency = "5 MHz", diameter = "12.7 mm" }

    dataset = "/scan/ascans"       # HDF5 / MATLAB: which array holds the A-scans
    axes = ["y", "x", "time"]      # ... and what each of its axes is
    layout = "columns"             # CSV/NumPy: one trace per column (or "rows")

Bare numbers are SI (Hz, s, m, m/s); text takes a unit.  Options override the mapping.
An unknown key or a malformed value is one line naming the key.
"""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from echocal.errors import ConfigError, DataFileError
from echocal.units import parse_quantity

__all__ = ["ScanFacts", "load_facts"]

_QUANTITIES = {
    "sampling_rate": ("frequency", "Hz"),
    "start_time": ("time", "s"),
    "x_start": ("length", "m"),
    "x_step": ("length", "m"),
    "x_end": ("length", "m"),
    "y_start": ("length", "m"),
    "y_end": ("length", "m"),
    "y_step": ("length", "m"),
    "sound_speed": ("speed", "m/s"),
    "probe_z": ("length", "m"),
    "tilt_x": ("angle", "deg"),
    "tilt_y": ("angle", "deg"),
}
_TEXTS = ("time", "x", "y", "dataset", "layout", "variable")


@dataclass(frozen=True, kw_only=True)
class ScanFacts:
    """Facts about a scan the file may not hold (None: unknown, ask the file).

    Attributes
    ----------
    sampling_rate : [Hz]; start_time : [s] first sample after the transmit pulse.
    x_start, x_step, y_start, y_step : [m] the raster (first position and step).
    x_end, y_end : [m] the last position, checked against the step and the trace count.
    x, y, time : names of variables/columns holding positions [m] or times [s].
    sound_speed : [m/s] the coupling medium's speed; probe_z : [m] the probe's height.
    tilt_x, tilt_y : [deg] the probe's fixed orientation (0, 0 fires straight down).
    scale_factor, add_offset : amplitude = code × scale + offset for integer samples.
    dataset : HDF5 dataset path or MATLAB variable with the A-scans.
    axes : the meaning of each axis of that array: ``"y"``, ``"x"``, ``"time"``.
    layout : CSV/NumPy matrices: ``"columns"`` (one trace per column) or ``"rows"``.
    probe : free description of the probe (name, frequency, diameter, ...).
    """

    sampling_rate: float | None = None
    start_time: float | None = None
    x_start: float | None = None
    x_step: float | None = None
    x_end: float | None = None
    y_start: float | None = None
    y_step: float | None = None
    y_end: float | None = None
    x: str | None = None
    y: str | None = None
    time: str | None = None
    sound_speed: float | None = None
    probe_z: float | None = None
    tilt_x: float | None = None
    tilt_y: float | None = None
    scale_factor: float | None = None
    add_offset: float | None = None
    dataset: str | None = None
    variable: str | None = None
    axes: tuple[str, ...] | None = None
    layout: str | None = None
    probe: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_mapping(cls, mapping: dict[str, Any], *, where: str = "mapping") -> ScanFacts:
        """Parse a TOML-like mapping (see the module docstring)."""
        known = {f.name for f in fields(cls)}
        values: dict[str, Any] = {}
        for key, value in mapping.items():
            name = f"{where}: {key}"
            if key not in known:
                raise ConfigError(f"{name} is not a scan fact; known: {', '.join(sorted(known))}")
            if key in _QUANTITIES:
                kind, unit = _QUANTITIES[key]
                values[key] = parse_quantity(name, value, kind, unit)
            elif key in ("scale_factor", "add_offset"):
                if isinstance(value, bool) or not isinstance(value, int | float):
                    raise ConfigError(f"{name} must be a number; got {value!r}")
                values[key] = float(value)
            elif key in _TEXTS:
                if not isinstance(value, str) or not value.strip():
                    raise ConfigError(f"{name} must be a non-empty text; got {value!r}")
                values[key] = value.strip()
            elif key == "axes":
                values[key] = _axes(name, value)
            elif key == "probe":
                if not isinstance(value, dict):
                    raise ConfigError(f'{name} must be a table, e.g. {{ name = "V309" }}')
                values[key] = dict(value)
        facts = cls(**values)
        facts.check(where)
        return facts

    def check(self, where: str = "scan facts") -> None:
        """Refuse impossible facts with one line naming the field."""
        if self.sampling_rate is not None and not self.sampling_rate > 0:
            raise ConfigError(f"{where}: sampling_rate must be > 0 Hz; got {self.sampling_rate:g}")
        for key in ("x_step", "y_step"):
            value = getattr(self, key)
            if value is not None and value == 0:
                raise ConfigError(f"{where}: {key} must not be 0 (positions must differ)")
        if self.sound_speed is not None and not self.sound_speed > 0:
            raise ConfigError(f"{where}: sound_speed must be > 0 m/s; got {self.sound_speed:g}")
        if self.scale_factor is not None and self.scale_factor == 0:
            raise ConfigError(f"{where}: scale_factor must not be 0")
        if self.layout is not None and self.layout not in ("columns", "rows"):
            raise ConfigError(f"{where}: layout must be 'columns' or 'rows'; got {self.layout!r}")

    def merged(self, **overrides: Any) -> ScanFacts:
        """These facts with the non-None ``overrides`` (command-line options) on top."""
        given = {k: v for k, v in overrides.items() if v is not None}
        if "axes" in given:
            given["axes"] = _axes("axes", given["axes"])
        facts = replace(self, **given)
        facts.check("options")
        return facts

    def given(self) -> dict[str, Any]:
        """The facts that were supplied (JSON-ready), for the file's provenance."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is not None and value != {}:
                out[f.name] = list(value) if isinstance(value, tuple) else value
        return out


def _axes(name: str, value: Any) -> tuple[str, ...]:
    if isinstance(value, str):
        value = [v.strip() for v in value.split(",")]
    allowed = {"y", "x", "time"}
    if (
        not isinstance(value, list | tuple)
        or not 2 <= len(value) <= 3
        or not set(value) <= allowed
        or len(set(value)) != len(value)
        or "time" not in value
        or "x" not in value
    ):
        raise ConfigError(
            f"{name} must list each array axis once as y, x or time (with x and time), e.g. "
            f"['y', 'x', 'time']; got {value!r}"
        )
    return tuple(value)


def load_facts(path: str | os.PathLike[str]) -> ScanFacts:
    """Read a TOML mapping file into :class:`ScanFacts`."""
    file = Path(path)
    try:
        mapping = tomllib.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataFileError(f"mapping file not found: {file}") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"mapping file {file} is not valid TOML: {exc}") from None
    return ScanFacts.from_mapping(mapping, where=str(file))
