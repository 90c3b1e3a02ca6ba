"""The A-scan: what a pulser-receiver returns for one pose."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal._validate import finite_float, positive_float
from echocal.errors import EchocalValueError
from echocal.geometry import Pose

__all__ = ["ASCAN_FORMAT", "AScan", "load_ascan", "save_ascan"]


@dataclass(frozen=True, eq=False)
class AScan:
    """One recorded or simulated A-scan.

    Attributes
    ----------
    samples : shape ``(n_samples,)`` received amplitude [arbitrary units, volts on a rig].
    fs : [Hz] sampling frequency.
    start_time : [s] time of the first sample after the transmit pulse (recording delay).
    pose : the pose actually reached when it was recorded (``None`` if unknown).
    metadata : free-form facts about the measurement (source, repeat index, SNR, ...).
    """

    samples: NDArray[np.float64]
    fs: float
    start_time: float = 0.0
    pose: Pose | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        samples = np.asarray(self.samples, dtype=np.float64)
        if samples is self.samples and samples.flags.writeable:
            samples = samples.copy()  # freeze a copy, never the caller's own array
        if samples.ndim != 1 or samples.size == 0:
            raise EchocalValueError(
                f"AScan.samples must be a non-empty 1-D array; got shape {samples.shape}"
            )
        samples.setflags(write=False)
        object.__setattr__(self, "samples", samples)
        object.__setattr__(self, "fs", positive_float("AScan.fs", self.fs))
        object.__setattr__(self, "start_time", finite_float("AScan.start_time", self.start_time))
        object.__setattr__(self, "metadata", MappingProxyType(dict(self.metadata)))

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.samples.size)

    @property
    def times(self) -> NDArray[np.float64]:
        """[s] time of each sample, shape ``(n_samples,)``."""
        return self.start_time + np.arange(self.n_samples) / self.fs

    @property
    def duration(self) -> float:
        """[s] length of the recording window."""
        return self.n_samples / self.fs

    @property
    def is_finite(self) -> bool:
        """True when every sample is finite (a receiver fault gives NaN)."""
        return bool(np.all(np.isfinite(self.samples)))


ASCAN_FORMAT = "ascan/2"
"""``echocal_format`` of an A-scan file (``ascan/1``, before echocal's NetCDF schema, still
loads)."""

_POSE_VARIABLES = (
    ("x", "m", "probe position x"),
    ("y", "m", "probe position y"),
    ("z", "m", "probe position z"),
    ("azimuth", "degree", "probe azimuth"),
    ("coelevation", "degree", "probe co-elevation"),
)


def save_ascan(
    scan: AScan, path: Any, *, summary: Mapping[str, Any] | None = None, title: str | None = None
) -> Any:
    """Write ``scan`` as a NetCDF file in echocal's schema (``ascan/2``), atomically.

    Variables: ``amplitude`` (time) [1], coordinate ``time`` [s], and the pose as scalar
    coordinates ``x``, ``y``, ``z`` [m], ``azimuth``, ``coelevation`` [degree] (when
    known).  Attributes: ``sampling_rate_hz``, ``start_time_s`` and ``summary`` (JSON:
    what was computed from it, e.g. time of flight and energy).  Returns the path.
    """
    import json

    import xarray as xr

    from echocal.io import json_ready
    from echocal.netcdf import write_netcdf

    coords: dict[str, Any] = {
        "time": ("time", scan.times, {"units": "s", "long_name": "time after the transmit pulse"})
    }
    if scan.pose is not None:
        for name, unit, long_name in _POSE_VARIABLES:
            coords[name] = (
                (),
                float(getattr(scan.pose, name)),
                {"units": unit, "long_name": long_name},
            )
    ds = xr.Dataset(
        {
            "amplitude": (
                "time",
                scan.samples,
                {"units": "1", "long_name": "received amplitude (arbitrary units)"},
            )
        },
        coords=coords,
        attrs={
            "sampling_rate_hz": scan.fs,
            "start_time_s": scan.start_time,
            "summary": json.dumps(json_ready(dict(summary or {})), allow_nan=False),
        },
    )
    source = str(scan.metadata.get("source", "echocal"))
    return write_netcdf(ds, path, fmt=ASCAN_FORMAT, title=title or "echocal A-scan", source=source)


def load_ascan(path: Any) -> AScan:
    """Read an A-scan file written by :func:`save_ascan` (or an ``ascan/1`` file).

    The file's ``summary`` becomes ``metadata["summary"]``.  Raises
    :class:`~echocal.errors.DataFileError` for a missing, damaged or foreign file.
    """
    import json

    from echocal.errors import DataFileError
    from echocal.netcdf import format_version, open_netcdf

    with open_netcdf(path, what="A-scan file") as ds:
        version = format_version(ds, "ascan")
        if version not in (1, 2) or "amplitude" not in ds.variables:
            raise DataFileError(f"{path}: not an echocal A-scan file ({ASCAN_FORMAT!r} expected)")
        samples = np.asarray(ds["amplitude"].values, dtype=np.float64)
        times = np.asarray(ds["time"].values, dtype=np.float64)
        fs = float(ds.attrs["sampling_rate_hz" if version == 2 else "fs_hz"])
        pose = None
        if all(name in ds.variables for name, _, _ in _POSE_VARIABLES):
            x, y, z, azimuth, coelevation = (float(ds[n].values) for n, _, _ in _POSE_VARIABLES)
            pose = Pose(x, y, z, azimuth, coelevation)
        summary = json.loads(ds.attrs.get("summary", "{}"))
    return AScan(samples, fs, float(times[0]), pose, {"summary": summary})
