"""Reader of the NDE open file format (Evident), version 4, single-element UT scans.

An ``.nde`` file is HDF5 with a JSON ``/Public/Setup`` dataset that describes the
inspection groups; each group lists its datasets (``path``, ``dataClass``,
``dimensions``, ``dataValue``).  What is read:

* the ``AScanAmplitude`` dataset of the chosen group (``dataset = "<group id>"`` in the
  mapping; default the first group that has one) whose dimensions are ``UCoordinate``,
  optionally ``VCoordinate``, and ``Ultrasound`` — a conventional UT line or raster scan;
  U becomes x and V becomes y, each at ``offset + index × resolution`` [m], and the
  Ultrasound axis gives the sampling rate 1/resolution and the start time (offset) [s];
* the amplitude scale of ``dataValue``: codes in [min, max] map linearly to
  [unitMin, unitMax] (``unit``, usually percent of full screen height), kept as a CF
  ``scale_factor``/``add_offset`` on the integer codes;
* the ``AScanStatus`` dataset's ``hasData`` bit, as the ``valid`` map.

Not read: phased-array and TFM data (``Beam`` axes, ``TfmValue``), C-scan datasets,
the ``Private`` group, and version 3 files (``/Domain/Setup``).  The JSON's specimen
velocities are not used as the coupling medium's speed: give ``sound_speed``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from echocal.errors import DataFileError, EchocalValueError
from echocal.positionscan.facts import ScanFacts
from echocal.positionscan.readers import RawScan

__all__ = ["is_nde", "read_nde"]

_AXES = {"UCoordinate": "x", "VCoordinate": "y", "Ultrasound": "time"}


def is_nde(path: Path) -> bool:
    """Whether ``path`` is an HDF5 file with the NDE format's ``/Public/Setup``."""
    import h5py

    if not h5py.is_hdf5(path):
        return False
    with h5py.File(path, "r") as handle:
        return "Public/Setup" in handle


def _setup(handle: Any, path: Path) -> dict[str, Any]:
    raw = handle["Public/Setup"][()]
    if isinstance(raw, np.ndarray):
        raw = raw.reshape(-1)[0]
    text = raw.decode("utf-8") if isinstance(raw, bytes) else str(raw)
    try:
        setup = json.loads(text)
    except json.JSONDecodeError as exc:
        raise DataFileError(f"{path.name}: /Public/Setup is not valid JSON ({exc})") from None
    if not isinstance(setup, dict):
        raise DataFileError(f"{path.name}: /Public/Setup is not a JSON object")
    return setup


def _group(setup: dict[str, Any], facts: ScanFacts, path: Path) -> dict[str, Any]:
    groups = [g for g in setup.get("groups", []) if isinstance(g, dict)]
    with_ascans = [
        g
        for g in groups
        if any(d.get("dataClass") == "AScanAmplitude" for d in g.get("datasets", []))
    ]
    if facts.dataset is not None:
        chosen = [g for g in with_ascans if str(g.get("id")) == facts.dataset]
        if not chosen:
            ids = ", ".join(str(g.get("id")) for g in with_ascans) or "none"
            raise EchocalValueError(
                f"dataset: no NDE group {facts.dataset!r} with A-scans in {path.name}; "
                f"groups with A-scans: {ids}"
            )
        return chosen[0]
    if not with_ascans:
        raise EchocalValueError(f"{path.name}: no group with an AScanAmplitude dataset")
    return with_ascans[0]


def read_nde(path: Path, facts: ScanFacts) -> RawScan:
    """Read a conventional UT scan of an NDE 4.x file (see the module docstring)."""
    import h5py

    with h5py.File(path, "r") as handle:
        setup = _setup(handle, path)
        version = str(setup.get("version", "?"))
        if not version.startswith("4"):
            raise DataFileError(
                f"{path.name}: NDE format version {version}; echocal reads version 4 files"
            )
        group = _group(setup, facts, path)
        datasets = group.get("datasets", [])
        amp = next(d for d in datasets if d.get("dataClass") == "AScanAmplitude")
        dims = amp.get("dimensions", [])
        axes: list[str] = []
        for dim in dims:
            name = dim.get("axis")
            if name not in _AXES:
                raise EchocalValueError(
                    f"{path.name}: axis {name!r} of group {group.get('id')} is not read "
                    "(echocal reads conventional UT scans: UCoordinate, VCoordinate, Ultrasound)"
                )
            axes.append(_AXES[name])
        if "time" not in axes or "x" not in axes:
            raise EchocalValueError(
                f"{path.name}: the A-scans need UCoordinate and Ultrasound axes"
            )
        location = amp.get("path")
        if not isinstance(location, str) or location not in handle:
            raise DataFileError(f"{path.name}: A-scan dataset {location!r} is missing")
        data = np.asarray(handle[location][()])
        if data.ndim != len(dims) or any(
            data.shape[i] != int(d.get("quantity", -1)) for i, d in enumerate(dims)
        ):
            raise DataFileError(
                f"{path.name}: dataset {location} has shape {data.shape}, the Setup's "
                f"dimensions say {tuple(d.get('quantity') for d in dims)}"
            )
        status = next((d for d in datasets if d.get("dataClass") == "AScanStatus"), None)
        valid = None
        if status is not None and status.get("path") in handle:
            bit = int(status.get("dataValue", {}).get("hasData", 1))
            flags = np.asarray(handle[status["path"]][()])
            valid = (flags & bit) != 0

    def axis_values(name: str) -> np.ndarray:
        d = dims[axes.index(name)]
        n, step = int(d["quantity"]), float(d["resolution"])
        return float(d.get("offset", 0.0)) + step * np.arange(n)

    scale = offset = None
    value = amp.get("dataValue", {})
    said: dict[str, Any] = {"nde_version": version, "group": group.get("id"), "dataset": location}
    if all(k in value for k in ("min", "max", "unitMin", "unitMax")):
        lo, hi = float(value["min"]), float(value["max"])
        ulo, uhi = float(value["unitMin"]), float(value["unitMax"])
        if hi != lo:
            scale = (uhi - ulo) / (hi - lo)
            offset = ulo - lo * scale
        said["amplitude_unit"] = value.get("unit")
    t = dims[axes.index("time")]
    resolution = float(t["resolution"])
    if not resolution > 0:
        raise EchocalValueError(
            f"{path.name}: Ultrasound resolution must be > 0 s; got {resolution:g}"
        )
    if valid is not None and valid.shape != data.shape[:-1]:
        valid = None
    return RawScan(
        data=data,
        axes=tuple(axes),
        fmt=f"NDE {version}",
        x=axis_values("x"),
        y=axis_values("y") if "y" in axes else None,
        fs=1.0 / resolution,
        start_time=float(t.get("offset", 0.0)),
        scale_factor=scale,
        add_offset=offset,
        valid=valid,
        said=said,
    )
