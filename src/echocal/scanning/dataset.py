"""The result of a surface scan: an xarray Dataset on dims (y, x), with units and summaries.

Variables (NaN where a point is missing; ``status`` says why):

=================  ======  ===================================================
name               units   meaning
=================  ======  ===================================================
probe_z            m       probe height
tilt_x, tilt_y     degree  estimated orientation as gimbal tilts
azimuth            degree  ... as azimuth (canonical: co-elevation >= 0)
coelevation        degree  ... as co-elevation
normal_x/_y/_z     1       unit surface normal n (the beam travels along −n)
tof                s       pulse-echo time of flight at the estimate
distance           m       c₀·tof/2, along the beam
surface_x/_y/_z    m       probe position + distance · (−n)
echo_snr           1       matched-envelope peak / its median (detection statistic)
n_measurements     1       A-scans used at the point (calibration + time of flight)
status             1       0 found, see ``flag_meanings``
message            -       why a point is missing ("" where found)
found              1       status == 0 (int8: 1 or 0)
warm               1       the point started from its neighbours (int8)
normal_error       degree  vs the true normal below the measured point (truth)
height_error       m       measured z − true surface z below the point (with a truth)
thickness          m       wall thickness c_L·(t_back − t_front)/2 (scans with a c_L)
thickness_error    m       measured minus true thickness (with a known thickness)
=================  ======  ===================================================

Summaries (in ``attrs`` and :attr:`SurfaceScan.summary`): points found/missing (by
status, with the most common message of each), total and per-point measurements,
median / p90 / max of both errors.

Written in echocal's NetCDF schema (:mod:`echocal.netcdf`, docs/netcdf-schema.md):
CF-1.10, ``long_name`` and UDUNITS ``units`` on every variable, compressed, checksummed.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import NDArray

from echocal.angle_columns import record_angles
from echocal.geometry import convert_angles, orientation_normal
from echocal.netcdf import NetcdfKind
from echocal.scanning.grid import ScanGrid
from echocal.specimen import Specimen

__all__ = ["FORMAT", "STATUS", "SurfaceScan", "surface_dataset"]

KIND = NetcdfKind(
    "surface-scan",
    2,
    what="surface scan",
    title="echocal surface scan: surface normal and distance per scan point",
    older=(1,),
    legacy_key="format",
)
"""How a surface scan is written and read (:class:`~echocal.netcdf.NetcdfKind`)."""

FORMAT = KIND.fmt
"""``echocal_format`` of a scan file (``surface-scan/1``, before echocal's NetCDF schema,
still loads)."""

STATUS: dict[str, int] = {
    "found": 0,
    "no-echo": 1,
    "weak-echo": 2,
    "at-limit": 3,
    "no-tof": 4,
    "source-error": 5,
    "unconverged": 6,
}
"""Per-point status codes: 0 found, else why the point is missing."""

_VARIABLES = {
    "probe_z": ("m", "probe height"),
    "tilt_x": ("degree", "estimated orientation: gimbal tilt about x"),
    "tilt_y": ("degree", "estimated orientation: gimbal tilt about y"),
    "azimuth": ("degree", "estimated orientation: azimuth"),
    "coelevation": ("degree", "estimated orientation: co-elevation"),
    "normal_x": ("1", "surface normal, x component"),
    "normal_y": ("1", "surface normal, y component"),
    "normal_z": ("1", "surface normal, z component"),
    "tof": ("s", "pulse-echo time of flight at the estimate"),
    "distance": ("m", "distance from the probe to the surface along the beam"),
    "surface_x": ("m", "surface point x"),
    "surface_y": ("m", "surface point y"),
    "surface_z": ("m", "surface point z"),
    "echo_snr": ("1", "echo detection statistic (matched-envelope peak / median)"),
    "n_measurements": ("1", "A-scans used at the point"),
    "status": ("1", "point status (0 found, else why it is missing)"),
    "found": ("1", "1 where the surface was found (status 0)"),
    "warm": ("1", "1 where the point started from its neighbours"),
    "normal_error": ("degree", "angle between the measured and the true normal"),
    "height_error": ("m", "measured minus true surface height"),
    "thickness": ("m", "wall thickness from the front-to-back time of flight"),
    "thickness_error": ("m", "measured minus true wall thickness"),
    "x": ("m", "probe position x"),
    "y": ("m", "probe position y"),
}
"""units (UDUNITS) and long_name of each variable of a scan file."""

FloatArray = NDArray[np.float64]


def _convert(
    a: FloatArray, b: FloatArray, source: str, target: str
) -> tuple[FloatArray, FloatArray]:
    """:func:`convert_angles` where both angles are finite; NaN elsewhere."""
    ok = np.isfinite(a) & np.isfinite(b)
    out_a, out_b = np.full(a.shape, np.nan), np.full(a.shape, np.nan)
    if np.any(ok):
        out_a[ok], out_b[ok] = convert_angles(a[ok], b[ok], source, target)
    return out_a, out_b


def _quantiles(values: FloatArray) -> dict[str, float | None]:
    v = values[np.isfinite(values)]
    if not v.size:
        return {"median": None, "p90": None, "max": None}
    return {
        "median": float(np.median(v)),
        "p90": float(np.percentile(v, 90)),
        "max": float(np.max(v)),
    }


def _most_common(messages: NDArray[Any]) -> str:
    """The most frequent of ``messages`` (the first seen among equals)."""
    values, first, counts = np.unique(messages.astype(str), return_index=True, return_counts=True)
    best = max(range(len(values)), key=lambda i: (counts[i], -first[i]))
    return str(values[best])


@dataclass(frozen=True)
class SurfaceScan:
    """A finished surface scan: the Dataset and its summary (plain data)."""

    dataset: xr.Dataset

    @property
    def summary(self) -> dict[str, Any]:
        """Points found/missing, measurements, error quantiles (JSON-ready)."""
        return json.loads(self.dataset.attrs["summary"])

    @property
    def found(self) -> NDArray[np.bool_]:
        """Which points were found, shape (n_y, n_x)."""
        return self.dataset["found"].values.astype(bool)

    def surface_points(self) -> FloatArray:
        """[m] found surface points, shape (n_found, 3)."""
        ds = self.dataset
        pts = np.stack([ds[f"surface_{a}"].values for a in "xyz"], axis=-1)
        return pts[self.found]

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the Dataset in echocal's NetCDF schema (compressed, checksummed), atomically."""
        source = str(self.dataset.attrs.get("source", "echocal scan"))
        return KIND.save(self.dataset, path, source=source)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> SurfaceScan:
        """Read a file written by :meth:`save` (or a ``surface-scan/1`` file of echocal
        before its NetCDF schema).  A damaged file is refused (checksums)."""
        data, version = KIND.load(path)
        return cls(_upgrade_v1(data) if version == 1 else data)


def _upgrade_v1(data: xr.Dataset) -> xr.Dataset:
    """A ``surface-scan/1`` Dataset in the names and units of ``surface-scan/2``."""
    attrs = {k: v for k, v in data.attrs.items() if k not in ("format", "sound_speed")}
    attrs["echocal_format"] = FORMAT
    if "sound_speed" in data.attrs:
        attrs["sound_speed_m_s"] = data.attrs["sound_speed"]
    data.attrs = attrs
    for name, (unit, long_name) in _VARIABLES.items():
        if name in data.variables:
            data[name].attrs.update(units=unit, long_name=long_name)
    return data


def surface_dataset(
    grid: ScanGrid,
    records: dict[tuple[int, int], dict[str, Any]],
    *,
    parameterization: str,
    sound_speed: float,
    truth: Specimen | None = None,
    attrs: dict[str, Any] | None = None,
    thickness: bool = False,
    true_thickness: float | None = None,
) -> SurfaceScan:
    """Assemble per-point ``records`` (keyed (iy, ix)) into a :class:`SurfaceScan`;
    with ``thickness`` also the wall-thickness map (and its error against
    ``true_thickness`` [m] when given)."""
    from echocal.scanning.truth import height_errors, normal_errors

    shape = grid.shape
    nan = np.full(shape, np.nan)
    a, b, tof, snr = nan.copy(), nan.copy(), nan.copy(), nan.copy()
    n_meas = np.zeros(shape, dtype=np.int64)
    status = np.full(shape, -1, dtype=np.int64)
    warm = np.zeros(shape, dtype=bool)
    message = np.full(shape, "", dtype=object)
    for (iy, ix), rec in records.items():
        status[iy, ix] = int(rec["status"])
        if rec["status"] != 0:
            message[iy, ix] = str(rec.get("message") or "")
        n_meas[iy, ix] = int(rec["n_measurements"])
        warm[iy, ix] = bool(rec.get("warm", False))
        snr[iy, ix] = rec["snr"] if rec["snr"] is not None else np.nan
        if rec["status"] == 0:
            (a[iy, ix], b[iy, ix]), tof[iy, ix] = record_angles(rec, parameterization), rec["tof"]
    az, coel = _convert(a, b, parameterization, "azimuth-coelevation")
    # canonical (azimuth, co-elevation): co-elevation >= 0
    flip = coel < 0
    az = np.where(flip, (az + 360.0) % 360.0 - 180.0, az)
    coel = np.abs(coel)
    tx, ty = _convert(az, coel, "azimuth-coelevation", "tilt")
    normal = orientation_normal(az, coel)  # (n_y, n_x, 3), NaN where missing
    dist = tof * sound_speed / 2.0
    probe = grid.positions()
    surface = probe - dist[..., None] * normal
    found = status == 0
    dims = ("y", "x")
    data: dict[str, Any] = {
        "probe_z": (dims, probe[..., 2]),
        "tilt_x": (dims, tx),
        "tilt_y": (dims, ty),
        "azimuth": (dims, az),
        "coelevation": (dims, coel),
        "normal_x": (dims, normal[..., 0]),
        "normal_y": (dims, normal[..., 1]),
        "normal_z": (dims, normal[..., 2]),
        "tof": (dims, tof),
        "distance": (dims, dist),
        "surface_x": (dims, surface[..., 0]),
        "surface_y": (dims, surface[..., 1]),
        "surface_z": (dims, surface[..., 2]),
        "echo_snr": (dims, snr),
        "n_measurements": (dims, n_meas),
        "status": (dims, status),
        "message": (dims, message.astype(str)),
        "found": (dims, found.astype(np.int8)),
        "warm": (dims, warm.astype(np.int8)),
    }
    if thickness:
        wall = np.full(shape, np.nan)
        for (iy, ix), rec in records.items():
            if rec["status"] == 0 and rec.get("thickness") is not None:
                wall[iy, ix] = rec["thickness"]
        data["thickness"] = (dims, wall)
    n_found = int(found.sum())
    summary: dict[str, Any] = {
        "points": grid.size,
        "found": n_found,
        "missing": int(grid.size - n_found),
        "missing_by_status": {
            name: int(np.count_nonzero(status == code))
            for name, code in STATUS.items()
            if code and np.any(status == code)
        },
        "missing_messages": {
            name: _most_common(message[status == code])
            for name, code in STATUS.items()
            if code and np.any(status == code)
        },
        "measurements_total": int(n_meas.sum()),
        "measurements_per_point": float(n_meas.mean()) if grid.size else 0.0,
        "measurements_per_point_median": float(np.median(n_meas)) if grid.size else 0.0,
    }
    if truth is not None:
        flat = found.reshape(-1)
        nerr, herr = np.full(grid.size, np.nan), np.full(grid.size, np.nan)
        pts = surface.reshape(-1, 3)[flat]
        nerr[flat] = normal_errors(truth, pts, normal.reshape(-1, 3)[flat])
        herr[flat] = height_errors(truth, pts)
        data["normal_error"] = (dims, nerr.reshape(shape))
        data["height_error"] = (dims, herr.reshape(shape))
        summary["normal_error_deg"] = _quantiles(nerr)
        summary["height_error_abs_m"] = _quantiles(np.abs(herr))
        summary["truth"] = truth.name
    if thickness:
        summary["thickness_m"] = _quantiles(data["thickness"][1])
        if true_thickness is not None:
            terr = data["thickness"][1] - float(true_thickness)
            data["thickness_error"] = (dims, terr)
            summary["thickness_error_abs_m"] = _quantiles(np.abs(terr))
            summary["true_thickness_m"] = float(true_thickness)
    ds = xr.Dataset(data, coords={"x": ("x", np.array(grid.x)), "y": ("y", np.array(grid.y))})
    for name, (unit, long_name) in _VARIABLES.items():
        if name in ds.variables:
            ds[name].attrs.update(units=unit, long_name=long_name)
    ds["status"].attrs["flag_values"] = np.array(list(STATUS.values()), dtype=np.int64)
    ds["status"].attrs["flag_meanings"] = " ".join(n.replace("-", "_") for n in STATUS)
    ds["message"].attrs["long_name"] = "why the point is missing (empty where found)"
    ds.attrs.update(
        {
            "echocal_format": FORMAT,
            "parameterization": parameterization,
            "sound_speed_m_s": float(sound_speed),
            "grid": json.dumps(grid.to_dict()),
            "summary": json.dumps(summary),
        }
    )
    for key, value in (attrs or {}).items():
        if key in ds.attrs:
            continue
        ds.attrs[key] = (
            value
            if isinstance(value, int | float | str) and not isinstance(value, bool)
            else json.dumps(value, default=str)
        )
    return SurfaceScan(ds)
