"""A position scan: A-scans on a line or a raster at a fixed probe orientation.

The one kind of data every view, surface fit and layer measurement reads, whether
imported from a real instrument (:func:`echocal.positionscan.import_scan`) or recorded
on the simulator (:func:`echocal.positionscan.simulate_position_scan`).  An
``xarray.Dataset`` in echocal's NetCDF schema (:mod:`echocal.netcdf`), format
``position-scan/1``:

=========  ===================  ======  ===============================================
name       dims                 units   meaning
=========  ===================  ======  ===============================================
samples    (y, x, time)         1       received amplitude; integer ADC codes keep
           or (x, time)                 their type with CF ``scale_factor`` (and
                                        ``add_offset``): amplitude = code × scale + offset
x, y       (x,), (y,)           m       probe position (``projection_x/y_coordinate``)
time       (time,)              s       time after the transmit pulse (CF ``axis = T``;
                                        no ``standard_name``: CF's ``time`` needs an
                                        epoch, this is a delay)
valid      (y, x) or (x,)       1       1 where the instrument recorded the trace
=========  ===================  ======  ===============================================

Global attributes: ``sampling_rate_hz``, ``start_time_s``, ``sound_speed_m_s`` (the
coupling medium's, when known), ``probe_z_m``, ``tilt_x_deg``/``tilt_y_deg`` (the fixed
orientation; 0, 0 fires straight down), ``probe`` (JSON), ``source_file``,
``source_sha256``, ``source_format``, ``user_facts`` (JSON: what the user supplied because
the file did not say it) and ``provenance``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_float, positive_float
from echocal.errors import EchocalValueError
from echocal.netcdf import NetcdfKind
from echocal.signal.window import RecordingWindow

__all__ = ["FORMAT", "PositionScan", "position_scan"]

KIND = NetcdfKind(
    "position-scan",
    1,
    what="position scan",
    title="echocal position scan: A-scans on a line or raster at a fixed orientation",
    hint="; import foreign files with `echocal import`",
)
"""How a position scan is written and read (:class:`~echocal.netcdf.NetcdfKind`)."""

FORMAT = KIND.fmt
"""``echocal_format`` of a position-scan file."""

FloatArray = NDArray[np.float64]

_COORDS = {
    "x": ("m", "probe position x", "projection_x_coordinate"),
    "y": ("m", "probe position y", "projection_y_coordinate"),
}


def _axis(name: str, values: ArrayLike) -> FloatArray:
    """A coordinate [m]: finite, 1-D, strictly monotonic."""
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    if not np.all(np.isfinite(v)):
        raise EchocalValueError(f"{name} positions must be finite; got NaN or inf")
    if v.size > 1:
        d = np.diff(v)
        if not (np.all(d > 0) or np.all(d < 0)):
            raise EchocalValueError(
                f"{name} positions must increase (or decrease) strictly; give distinct, "
                "ordered positions"
            )
    return v


def position_scan(
    samples: ArrayLike,
    *,
    fs: float,
    start_time: float = 0.0,
    x: ArrayLike,
    y: ArrayLike | None = None,
    scale_factor: float | None = None,
    add_offset: float | None = None,
    valid: ArrayLike | None = None,
    attrs: dict[str, Any] | None = None,
) -> PositionScan:
    """Assemble a :class:`PositionScan` from arrays.

    Parameters
    ----------
    samples : shape ``(n_y, n_x, n_time)`` (raster) or ``(n_x, n_time)`` (line); float
        amplitudes, or integer ADC codes (kept as integers) with ``scale_factor``.
    fs : [Hz] sampling rate.
    start_time : [s] time of the first sample after the transmit pulse.
    x, y : [m] probe positions, shapes ``(n_x,)`` and ``(n_y,)`` (``y`` None for a line).
    scale_factor, add_offset : amplitude = code × scale_factor + add_offset (CF).
    valid : which traces were recorded, shape ``samples.shape[:-1]`` (default all).
    attrs : further global attributes (strings, numbers; others are stored as JSON).

    Raises
    ------
    EchocalValueError : one line naming the field (a NaN sample, a negative rate, a
        position count that does not match the traces, ...).
    """
    fs = positive_float("sampling rate (fs)", fs)
    start_time = finite_float("start time", start_time)
    data = np.asarray(samples)
    if data.dtype.kind not in "biuf":
        raise EchocalValueError(f"samples must be numbers; got dtype {data.dtype}")
    if data.ndim not in (2, 3) or data.shape[-1] < 2:
        raise EchocalValueError(
            "samples must have shape (n_x, n_time) or (n_y, n_x, n_time) with at least 2 "
            f"time samples; got shape {data.shape}"
        )
    if data.dtype.kind == "f" and not np.all(np.isfinite(data)):
        bad = np.argwhere(~np.isfinite(data))[0]
        raise EchocalValueError(
            f"samples: NaN or inf at trace {tuple(int(i) for i in bad[:-1])}, sample "
            f"{int(bad[-1])}; a position scan holds finite amplitudes (mark a missing "
            "trace with valid = 0 instead)"
        )
    if data.dtype.kind == "b":
        data = data.astype(np.int8)
    if data.dtype.kind in "iu" and scale_factor is None:
        scale_factor = 1.0
    x_axis = _axis("x", x)
    if x_axis.size != data.shape[-2]:
        raise EchocalValueError(
            f"x: {x_axis.size} positions for {data.shape[-2]} traces along x; give one "
            "position per trace (check the scan step and the trace count)"
        )
    coords: dict[str, Any] = {"x": ("x", x_axis)}
    dims: tuple[str, ...] = ("x", "time")
    if data.ndim == 3:
        if y is None:
            raise EchocalValueError("y: a raster (n_y, n_x, n_time) needs y positions")
        y_axis = _axis("y", y)
        if y_axis.size != data.shape[0]:
            raise EchocalValueError(
                f"y: {y_axis.size} positions for {data.shape[0]} rows of traces; give one "
                "position per row (check the index step and the row count)"
            )
        coords["y"] = ("y", y_axis)
        dims = ("y", "x", "time")
    elif y is not None:
        y_axis = _axis("y", y)
        if y_axis.size != 1:
            raise EchocalValueError(f"y: a line scan has one y position; got {y_axis.size}")
        attrs = {**(attrs or {}), "line_y_m": float(y_axis[0])}
    n_t = data.shape[-1]
    coords["time"] = ("time", start_time + np.arange(n_t) / fs)
    ok = np.ones(data.shape[:-1], dtype=np.int8)
    if valid is not None:
        v = np.asarray(valid)
        if v.shape != ok.shape:
            raise EchocalValueError(f"valid must have shape {ok.shape}; got {v.shape}")
        ok = (v != 0).astype(np.int8)
    ds = xr.Dataset({"samples": (dims, data), "valid": (dims[:-1], ok)}, coords=coords)
    ds["samples"].attrs.update(units="1", long_name="received amplitude (arbitrary units)")
    if scale_factor is not None:
        ds["samples"].attrs["scale_factor"] = finite_float("scale_factor", scale_factor)
    if add_offset is not None:
        ds["samples"].attrs["add_offset"] = finite_float("add_offset", add_offset)
    ds["valid"].attrs.update(
        units="1",
        long_name="1 where the trace was recorded",
        flag_values=np.array([0, 1], dtype=np.int8),
        flag_meanings="missing recorded",
    )
    for name in ("x", "y"):
        if name in ds.coords:
            unit, long_name, standard = _COORDS[name]
            ds[name].attrs.update(units=unit, long_name=long_name, standard_name=standard)
    ds["time"].attrs.update(units="s", long_name="time after the transmit pulse", axis="T")
    ds.attrs.update({"echocal_format": FORMAT, "sampling_rate_hz": fs, "start_time_s": start_time})
    for key, value in (attrs or {}).items():
        if value is None:
            continue
        ds.attrs[key] = (
            value
            if isinstance(value, int | float | str) and not isinstance(value, bool)
            else json.dumps(value, default=str)
        )
    return PositionScan(ds)


@dataclass(frozen=True)
class PositionScan:
    """A position scan (see the module docstring): the Dataset and what reads it."""

    dataset: xr.Dataset

    # ------------------------------------------------------------------ shape and axes
    @property
    def is_raster(self) -> bool:
        """True for dims (y, x, time), False for a line (x, time)."""
        return "y" in self.dataset["samples"].dims

    @property
    def x(self) -> FloatArray:
        """[m] probe positions along x, shape ``(n_x,)``."""
        return np.asarray(self.dataset["x"].values, dtype=np.float64)

    @property
    def y(self) -> FloatArray:
        """[m] probe positions along y, shape ``(n_y,)`` (one value for a line)."""
        if self.is_raster:
            return np.asarray(self.dataset["y"].values, dtype=np.float64)
        return np.array([float(self.dataset.attrs.get("line_y_m", 0.0))])

    @property
    def fs(self) -> float:
        """[Hz] sampling rate."""
        return float(self.dataset.attrs["sampling_rate_hz"])

    @property
    def start_time(self) -> float:
        """[s] time of the first sample."""
        return float(self.dataset.attrs["start_time_s"])

    @property
    def window(self) -> RecordingWindow:
        """The recording window (fs, start, n_samples)."""
        n = int(self.dataset.sizes["time"])
        return RecordingWindow(fs=self.fs, start=self.start_time, n_samples=n)

    @property
    def times(self) -> FloatArray:
        """[s] sample times, shape ``(n_time,)``."""
        return np.asarray(self.dataset["time"].values, dtype=np.float64)

    @property
    def raw(self) -> NDArray[Any]:
        """The stored samples as stored (integer codes or floats), time last."""
        return np.asarray(self.dataset["samples"].values)

    @property
    def samples(self) -> FloatArray:
        """[a.u.] amplitudes (codes × scale_factor + add_offset), shape ``(n_y, n_x,
        n_time)`` — a line scan as one row (n_y = 1)."""
        var = self.dataset["samples"]
        values = np.asarray(var.values, dtype=np.float64)
        scale = float(var.attrs.get("scale_factor", 1.0))
        offset = float(var.attrs.get("add_offset", 0.0))
        if scale != 1.0 or offset != 0.0:
            values = values * scale + offset
        return values if self.is_raster else values[None]

    @property
    def valid(self) -> NDArray[np.bool_]:
        """Which traces were recorded, shape ``(n_y, n_x)``."""
        v = np.asarray(self.dataset["valid"].values, dtype=bool)
        return v if self.is_raster else v[None]

    @property
    def sound_speed(self) -> float | None:
        """[m/s] the coupling medium's speed, if known."""
        value = self.dataset.attrs.get("sound_speed_m_s")
        return None if value is None else float(value)

    @property
    def probe_z(self) -> float | None:
        """[m] the probe's height (z of the face centre), if known."""
        value = self.dataset.attrs.get("probe_z_m")
        return None if value is None else float(value)

    def attr_json(self, key: str) -> Any:
        """A JSON global attribute parsed (None when absent)."""
        value = self.dataset.attrs.get(key)
        return None if value is None else json.loads(value)

    def trace_index(self, x: float, y: float | None = None) -> tuple[int, int]:
        """(iy, ix) of the trace nearest the position (x, y) [m]."""
        ix = int(np.argmin(np.abs(self.x - float(x))))
        iy = 0 if y is None or not self.is_raster else int(np.argmin(np.abs(self.y - float(y))))
        return iy, ix

    def with_samples(self, samples: ArrayLike) -> PositionScan:
        """The same scan (positions, times, attributes) holding float ``samples`` [a.u.],
        shape ``(n_y, n_x, n_time)`` (a line scan: n_y = 1)."""
        data = np.asarray(samples, dtype=np.float64)
        if data.shape != self.samples.shape:
            raise EchocalValueError(
                f"samples must have shape {self.samples.shape}; got {data.shape}"
            )
        keep = {
            k: v
            for k, v in self.dataset.attrs.items()
            if k not in ("echocal_format", "sampling_rate_hz", "start_time_s")
        }
        return position_scan(
            data if self.is_raster else data[0],
            fs=self.fs,
            start_time=self.start_time,
            x=self.x,
            y=self.y if self.is_raster else None,
            valid=self.valid if self.is_raster else self.valid[0],
            attrs=keep,
        )

    # ------------------------------------------------------------------ files
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the scan in echocal's NetCDF schema (compressed, checksummed), atomically."""
        source = str(self.dataset.attrs.get("source_format", "echocal"))
        return KIND.save(self.dataset, path, source=source)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> PositionScan:
        """Read a file written by :meth:`save`; integer samples come back as the integer
        codes they were stored as.  A damaged file is refused (checksums)."""
        data, _ = KIND.load(path)
        var = data["samples"]
        stored = var.encoding.get("dtype")
        if stored is not None and np.dtype(stored).kind in "iu" and "scale_factor" in var.encoding:
            scale = float(var.encoding["scale_factor"])
            offset = float(var.encoding.get("add_offset", 0.0))
            codes = np.rint((var.values - offset) / scale).astype(stored)
            attrs = {**var.attrs, "scale_factor": scale}
            if "add_offset" in var.encoding:
                attrs["add_offset"] = offset
            data["samples"] = (var.dims, codes, attrs)
        return cls(data)
