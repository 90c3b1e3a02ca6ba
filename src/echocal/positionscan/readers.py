"""Readers of foreign scan files into one raw form (:class:`RawScan`), private to import.

Each reader returns the A-scan array with the meaning of its axes, and whatever the file
itself says (a time vector, positions, a sampling rate); :func:`echocal.positionscan.
import_scan` then fills in the user's facts and checks everything.

* MATLAB v5 (``scipy.io.loadmat``) and v7.3 (HDF5, read with h5py and transposed back to
  MATLAB's axis order);
* NumPy ``.npy`` (one array) and ``.npz`` (named arrays, as a MATLAB file);
* CSV from oscilloscopes: a header row is optional; a time column or a sampling rate;
  one trace per column (or per row), or one trace per file;
* generic HDF5: the dataset the mapping names (or the only array of 2 or more axes).

Conventional variable names are recognized when the mapping names none: ``fs`` [Hz],
``t`` or ``time`` [s], ``x`` and ``y`` [m].
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.errors import DataFileError, EchocalValueError
from echocal.positionscan.facts import ScanFacts

__all__ = ["RawScan", "read_csv", "read_hdf5", "read_mat", "read_npy", "read_variables"]


@dataclass
class RawScan:
    """A-scans as a file holds them, before the user's facts are applied.

    ``axes`` names each axis of ``data`` (``"y"``, ``"x"``, ``"time"``); ``time``, ``x``,
    ``y`` [s, m] are vectors the file gave (None: not given); ``fs`` [Hz] a rate it gave.
    """

    data: NDArray[Any]
    axes: tuple[str, ...]
    fmt: str
    time: NDArray[np.float64] | None = None
    x: NDArray[np.float64] | None = None
    y: NDArray[np.float64] | None = None
    fs: float | None = None
    start_time: float | None = None
    scale_factor: float | None = None
    add_offset: float | None = None
    valid: NDArray[Any] | None = None
    said: dict[str, Any] = field(default_factory=dict)


def _numeric(name: str, value: Any) -> NDArray[Any]:
    arr = np.asarray(value)
    if arr.dtype.kind not in "biuf":
        raise DataFileError(f"{name}: not a numeric array (dtype {arr.dtype})")
    return arr


def _default_axes(data: NDArray[Any], facts: ScanFacts, time_len: int | None) -> tuple[str, ...]:
    """The axes of ``data``: the mapping's, or by the time vector's length, or the layout."""
    if facts.axes is not None:
        if len(facts.axes) != data.ndim:
            raise EchocalValueError(
                f"axes: {len(facts.axes)} names for an array of {data.ndim} axes "
                f"(shape {data.shape}); name each axis once"
            )
        return facts.axes
    if data.ndim == 3:
        return ("y", "x", "time")
    if data.ndim != 2:
        raise EchocalValueError(
            f"the A-scan array has shape {data.shape}; a scan is 2-D (traces × time) or 3-D "
            "(y × x × time): name its axes with axes = [...]"
        )
    if time_len is not None and data.shape[0] != data.shape[1]:
        if data.shape[0] == time_len:
            return ("time", "x")
        if data.shape[1] == time_len:
            return ("x", "time")
    return ("time", "x") if (facts.layout or "columns") == "columns" else ("x", "time")


def read_variables(variables: dict[str, Any], facts: ScanFacts, fmt: str) -> RawScan:
    """A scan from named arrays (a MATLAB or ``.npz`` file)."""
    arrays = {
        k: v
        for k, v in variables.items()
        if not k.startswith("__") and np.asarray(v).dtype.kind in "biuf"
    }
    wanted = facts.dataset or facts.variable
    if wanted is not None:
        if wanted not in arrays:
            raise EchocalValueError(
                f"dataset: no numeric variable {wanted!r} in the file; it has "
                f"{', '.join(sorted(arrays)) or 'none'}"
            )
        name = wanted
    else:
        big = [k for k, v in arrays.items() if np.asarray(v).ndim >= 2 and min(np.shape(v)) > 1]
        if len(big) != 1:
            raise EchocalValueError(
                "dataset: name the variable holding the A-scans (candidates: "
                f"{', '.join(sorted(big)) or 'none'})"
            )
        name = big[0]
    data = _numeric(name, arrays[name])

    def vector(key: str | None, *defaults: str) -> NDArray[np.float64] | None:
        for k in (key,) if key is not None else defaults:
            if k in arrays:
                return np.asarray(arrays[k], dtype=np.float64).reshape(-1)
            if key is not None:
                raise EchocalValueError(f"{k}: no variable {k!r} in the file")
        return None

    time = vector(facts.time, "t", "time")
    fs = None
    if "fs" in arrays and np.asarray(arrays["fs"]).size == 1:
        fs = float(np.asarray(arrays["fs"]).reshape(-1)[0])
    axes = _default_axes(data, facts, None if time is None else time.size)
    return RawScan(
        data=data,
        axes=axes,
        fmt=fmt,
        time=time,
        x=vector(facts.x, "x"),
        y=vector(facts.y, "y"),
        fs=fs,
        said={"dataset": name},
    )


def read_mat(path: Path, facts: ScanFacts) -> RawScan:
    """A MATLAB file: v7.3 (HDF5) with h5py, earlier versions with scipy.io."""
    import h5py

    if h5py.is_hdf5(path):
        with h5py.File(path, "r") as handle:
            variables = {
                name: np.asarray(obj[()]).T  # MATLAB is column-major: back to its axis order
                for name, obj in handle.items()
                if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "biuf"
            }
        return read_variables(variables, facts, "MATLAB v7.3 (HDF5)")
    import scipy.io

    try:
        variables = scipy.io.loadmat(path, squeeze_me=False)
    except (ValueError, TypeError, OSError, NotImplementedError) as exc:
        raise DataFileError(f"cannot read {path} as a MATLAB file: {exc}") from None
    return read_variables(variables, facts, "MATLAB v5")


def read_npy(path: Path, facts: ScanFacts) -> RawScan:
    """A NumPy ``.npy`` array (2-D or 3-D; 1-D: one trace) or an ``.npz`` archive."""
    try:
        loaded = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise DataFileError(f"cannot read {path} as a NumPy file: {exc}") from None
    if isinstance(loaded, np.lib.npyio.NpzFile):
        with loaded:
            return read_variables(dict(loaded.items()), facts, "NumPy .npz")
    data = _numeric(str(path), loaded)
    if data.ndim == 1:
        return RawScan(data=data[None, :], axes=("x", "time"), fmt="NumPy .npy")
    return RawScan(data=data, axes=_default_axes(data, facts, None), fmt="NumPy .npy")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_csv(path: Path, facts: ScanFacts) -> RawScan:
    """An oscilloscope CSV: optional header, optional time column, traces as columns
    (``layout = "rows"``: as rows).  A ragged row or a non-number is one line naming its
    row and column."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise DataFileError(f"cannot read {path} as text: {exc}") from None
    try:
        dialect = csv.Sniffer().sniff(text[:4096], delimiters=",;\t ")
    except csv.Error:
        dialect = csv.excel
    rows = [[c.strip() for c in r] for r in csv.reader(text.splitlines(), dialect) if any(r)]
    if not rows:
        raise DataFileError(f"{path}: the CSV file is empty")
    header: list[str] | None = None
    if not all(_is_number(c) for c in rows[0]):
        header, rows = rows[0], rows[1:]
    width = len(header) if header is not None else len(rows[0])
    values = np.empty((len(rows), width))
    for i, row in enumerate(rows):
        line = i + (2 if header is not None else 1)
        if len(row) != width:
            raise EchocalValueError(
                f"{path.name} line {line}: {len(row)} fields, expected {width}: the CSV is "
                "ragged (every row needs one value per column)"
            )
        for j, cell in enumerate(row):
            try:
                values[i, j] = float(cell)
            except ValueError:
                raise EchocalValueError(
                    f"{path.name} line {line}, column {j + 1}: {cell!r} is not a number"
                ) from None
            if not math.isfinite(values[i, j]):
                raise EchocalValueError(
                    f"{path.name} line {line}, column {j + 1}: {cell!r} is not finite; "
                    "a scan holds finite amplitudes"
                )
    if (facts.layout or "columns") == "rows":
        return RawScan(data=values, axes=("x", "time"), fmt="CSV")
    time_col = _time_column(header, facts, width, path)
    time = None
    if time_col is not None:
        time = values[:, time_col]
        values = np.delete(values, time_col, axis=1)
        if values.shape[1] == 0:
            raise EchocalValueError(f"{path.name}: only a time column, no trace")
    return RawScan(data=values, axes=("time", "x"), fmt="CSV", time=time)


def _time_column(header: list[str] | None, facts: ScanFacts, width: int, path: Path) -> int | None:
    """The index of the time column: the one the mapping names, or a header 't'/'time...'."""
    if facts.time is not None:
        if header is not None and facts.time in header:
            return header.index(facts.time)
        if facts.time.isdigit() and 1 <= int(facts.time) <= width:
            return int(facts.time) - 1
        raise EchocalValueError(
            f"time: no column {facts.time!r} in {path.name} (give its header name or its "
            "number, 1 for the first)"
        )
    if header is not None:
        for j, name in enumerate(header):
            low = name.lower()
            if low == "t" or low.startswith("time") or low.startswith("t ("):
                return j
    return None


def read_hdf5(path: Path, facts: ScanFacts) -> RawScan:
    """A generic HDF5 file: the dataset the mapping names (``dataset``), or its only
    array of 2 or more axes; ``time``, ``x``, ``y`` name datasets of vectors."""
    import h5py

    with h5py.File(path, "r") as handle:
        found: list[str] = []
        handle.visititems(
            lambda n, o: (
                found.append(n)
                if isinstance(o, h5py.Dataset) and o.ndim >= 2 and o.dtype.kind in "biuf"
                else None
            )
        )
        name = facts.dataset
        if name is None:
            if len(found) != 1:
                raise EchocalValueError(
                    "dataset: name the HDF5 dataset holding the A-scans (candidates: "
                    f"{', '.join(found) or 'none'})"
                )
            name = found[0]
        if name not in handle or not isinstance(handle[name], h5py.Dataset):
            raise EchocalValueError(f"dataset: no HDF5 dataset {name!r} in {path.name}")
        data = _numeric(name, handle[name][()])

        def vector(key: str | None) -> NDArray[np.float64] | None:
            if key is None:
                return None
            if key not in handle:
                raise EchocalValueError(f"{key}: no HDF5 dataset {key!r} in {path.name}")
            return np.asarray(handle[key][()], dtype=np.float64).reshape(-1)

        time = vector(facts.time)
        raw = RawScan(
            data=data,
            axes=_default_axes(data, facts, None if time is None else time.size),
            fmt="HDF5",
            time=time,
            x=vector(facts.x),
            y=vector(facts.y),
            said={"dataset": name},
        )
    return raw


def stack_traces(raws: list[RawScan]) -> RawScan:
    """One line scan from several files of one trace each (in the given order)."""
    traces: list[NDArray[Any]] = []
    time: NDArray[np.float64] | None = None
    for raw in raws:
        data = np.moveaxis(raw.data, raw.axes.index("time"), -1).reshape(
            -1, raw.data.shape[raw.axes.index("time")]
        )
        if data.shape[0] != 1:
            raise EchocalValueError(
                f"one trace per file expected when importing several files; a file holds "
                f"{data.shape[0]}"
            )
        if traces and data.shape[1] != traces[0].size:
            raise EchocalValueError(
                f"trace {len(traces) + 1} has {data.shape[1]} samples, the first "
                f"{traces[0].size}: every file needs the same number of samples"
            )
        if raw.time is not None:
            if time is not None and not np.allclose(raw.time, time, rtol=0, atol=1e-12):
                raise EchocalValueError(
                    f"time: trace {len(traces) + 1} has another time axis than the first"
                )
            time = raw.time
        traces.append(data[0])
    first = raws[0]
    return RawScan(
        data=np.stack(traces),
        axes=("x", "time"),
        fmt=f"{first.fmt} (one trace per file)",
        time=time,
        fs=first.fs,
    )
