"""Import a foreign scan file into a :class:`~echocal.positionscan.PositionScan`.

:func:`import_scan` picks the reader by the file (``.mat``, ``.csv``/``.txt``, ``.npy``/
``.npz``, ``.h5``/``.hdf5``, ``.nde`` or any HDF5 with ``/Public/Setup``), applies the
user's :class:`~echocal.positionscan.ScanFacts` where the file is silent, checks that
everything agrees, and records the source file, its SHA-256 and the facts the user
supplied.  Several files (or a folder) are one trace each, in name order.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.errors import DataFileError, EchocalValueError
from echocal.positionscan.dataset import PositionScan, position_scan
from echocal.positionscan.facts import ScanFacts
from echocal.positionscan.readers import (
    RawScan,
    read_csv,
    read_hdf5,
    read_mat,
    read_npy,
    stack_traces,
)

__all__ = ["import_scan", "reader_for"]

_SUFFIXES = {
    ".mat": read_mat,
    ".csv": read_csv,
    ".txt": read_csv,
    ".npy": read_npy,
    ".npz": read_npy,
    ".h5": read_hdf5,
    ".hdf5": read_hdf5,
    ".hdf": read_hdf5,
}


def reader_for(path: Path) -> Any:
    """The reader function of ``path`` (by its suffix; an NDE file by its content)."""
    from echocal.positionscan.nde import is_nde, read_nde

    if path.suffix.lower() == ".nde" or (path.suffix.lower() in (".h5", ".hdf5") and is_nde(path)):
        return read_nde
    reader = _SUFFIXES.get(path.suffix.lower())
    if reader is None:
        raise DataFileError(
            f"{path.name}: unknown scan file type {path.suffix!r}; echocal imports "
            f"{', '.join(sorted({*_SUFFIXES, '.nde'}))}"
        )
    return reader


def _files(source: str | os.PathLike[str] | Sequence[str | os.PathLike[str]]) -> list[Path]:
    if isinstance(source, str | os.PathLike):
        path = Path(source)
        if path.is_dir():
            files = sorted(
                p for p in path.iterdir() if p.is_file() and p.suffix.lower() in _SUFFIXES
            )
            if not files:
                raise DataFileError(f"{path}: no scan files ({', '.join(sorted(_SUFFIXES))}) in it")
            return files
        files = [path]
    else:
        files = [Path(p) for p in source]
    for f in files:
        if not f.is_file():
            raise DataFileError(f"scan file not found: {f}")
    if not files:
        raise DataFileError("no scan file given")
    return files


def _time_axis(raw: RawScan, facts: ScanFacts, n_time: int) -> tuple[float, float]:
    """(fs [Hz], start [s]) from the file's time vector or rate, or the user's facts."""
    fs = raw.fs
    start = raw.start_time
    if raw.time is not None:
        t = raw.time
        if t.size != n_time:
            raise EchocalValueError(
                f"time: {t.size} times for {n_time} samples per trace; give one time per sample"
            )
        if not np.all(np.isfinite(t)):
            raise EchocalValueError("time: the time column holds NaN or inf")
        steps = np.diff(t)
        step = float(np.mean(steps)) if steps.size else 0.0
        if not step > 0:
            raise EchocalValueError("time: the time axis must increase")
        if np.max(np.abs(steps - step)) > 1e-3 * step:
            raise EchocalValueError(
                "time: not evenly sampled (steps differ by more than 0.1 %); echocal needs a "
                "constant sampling rate"
            )
        fs, start = 1.0 / step, float(t[0])
    if facts.sampling_rate is not None:
        if fs is not None and abs(facts.sampling_rate - fs) > 1e-6 * fs:
            raise EchocalValueError(
                f"sampling_rate: given {facts.sampling_rate:g} Hz, the file says {fs:g} Hz; "
                "drop the option or correct it"
            )
        fs = facts.sampling_rate
    if fs is None:
        raise EchocalValueError(
            "sampling_rate: the file gives no time axis; give the sampling rate "
            "(--fs 100MHz, or sampling_rate in the mapping)"
        )
    if not fs > 0 or not np.isfinite(fs):
        raise EchocalValueError(f"sampling_rate must be a finite rate > 0 Hz; got {fs:g}")
    if facts.start_time is not None:
        if raw.time is not None and abs(facts.start_time - float(start or 0.0)) > 0.5 / fs:
            raise EchocalValueError(
                f"start_time: given {facts.start_time:g} s, the file's time axis starts at "
                f"{start:g} s"
            )
        start = facts.start_time
    return float(fs), float(start or 0.0)


def _positions(
    axis: str, given: NDArray[np.float64] | None, facts: ScanFacts, n: int, where: str
) -> NDArray[np.float64]:
    """[m] the ``n`` positions along ``axis``: the file's (``where``: its name), or
    start + step × index."""
    start = getattr(facts, f"{axis}_start")
    step = getattr(facts, f"{axis}_step")
    end = getattr(facts, f"{axis}_end")
    if given is not None and (start is not None or step is not None):
        raise EchocalValueError(
            f"{axis}_step: the file gives the {axis} positions; drop {axis}_start/{axis}_step"
        )
    if given is not None:
        if given.size != n:
            raise EchocalValueError(f"{axis}: {given.size} positions for {n} traces along {axis}")
        bad = np.flatnonzero(~np.isfinite(given))
        if bad.size:
            raise EchocalValueError(
                f"{where}: {axis} position {bad[0] + 1} of {n} is {given[bad[0]]} (a missing "
                f"position?); correct the file's {axis} positions"
            )
        return given
    if step is None:
        if n > 1:
            raise EchocalValueError(
                f"{axis}_step: the file gives no {axis} positions for its {n} traces; give "
                f"the scan step (--{axis}-step 0.5mm, or {axis}_step in the mapping)"
            )
        step = 0.0
    first = 0.0 if start is None else start
    values = first + step * np.arange(n)
    if end is not None and abs(values[-1] - end) > 1e-6 * max(abs(step), 1e-12) + 1e-12:
        expected = 1 + (end - first) / step if step else float("nan")
        raise EchocalValueError(
            f"{axis}_step: {n} traces from {first * 1e3:g} mm in steps of {step * 1e3:g} mm "
            f"end at {values[-1] * 1e3:g} mm, not {axis}_end = {end * 1e3:g} mm (that span "
            f"holds {expected:g} positions); correct the step, the span or the trace count"
        )
    return values


def import_scan(
    source: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    facts: ScanFacts | None = None,
) -> PositionScan:
    """Read a scan file (or one trace per file) into a :class:`PositionScan`.

    Parameters
    ----------
    source : a file, a folder (every scan file in it, one trace each, in name order) or
        a list of files (one trace each, in the given order).
    facts : what the file does not say (sampling rate, positions, medium speed, ...);
        see :class:`ScanFacts`.

    Raises
    ------
    DataFileError : a missing, unreadable or unknown file.
    EchocalValueError : inconsistent or missing facts, one line naming the field.
    """
    from echocal.provenance import file_digest

    facts = facts or ScanFacts()
    files = _files(source)
    if len(files) == 1:
        raw = reader_for(files[0])(files[0], facts)
    else:
        raw = stack_traces([reader_for(f)(f, facts) for f in files])
    order = [a for a in ("y", "x", "time") if a in raw.axes]
    data = np.transpose(raw.data, [raw.axes.index(a) for a in order])
    valid = None
    if raw.valid is not None:
        rest = [a for a in raw.axes if a != "time"]
        valid = np.transpose(raw.valid, [rest.index(a) for a in order[:-1]])
    n_time = data.shape[-1]
    fs, start = _time_axis(raw, facts, n_time)
    where = files[0].name if len(files) == 1 else f"{files[0].name} and {len(files) - 1} more"
    x = _positions("x", raw.x, facts, data.shape[-2], where)
    y = None
    if data.ndim == 3:
        y = _positions("y", raw.y, facts, data.shape[0], where)
    elif facts.y_start is not None:
        y = np.array([facts.y_start])
    scale = raw.scale_factor if facts.scale_factor is None else facts.scale_factor
    offset = raw.add_offset if facts.add_offset is None else facts.add_offset
    if data.dtype.kind == "f" and scale is not None:
        data = data * scale + (offset or 0.0)  # floats are stored as amplitudes
        scale = offset = None
    attrs: dict[str, Any] = {
        "source_file": ", ".join(str(f) for f in files),
        "source_sha256": ", ".join(file_digest(f) for f in files),
        "source_format": raw.fmt,
        "source_facts": raw.said or None,
        "user_facts": facts.given() or None,
        "sound_speed_m_s": facts.sound_speed,
        "probe_z_m": facts.probe_z,
        "tilt_x_deg": facts.tilt_x,
        "tilt_y_deg": facts.tilt_y,
        "probe": facts.probe or None,
    }
    return position_scan(
        data,
        fs=fs,
        start_time=start,
        x=x,
        y=y,
        scale_factor=scale,
        add_offset=offset,
        valid=valid,
        attrs=attrs,
    )
