"""One NetCDF schema for every file echocal writes: CF-1.10, compressed, checksummed.

Every NetCDF writer of echocal (a replay recording, a surface scan ``scan.nc``, an A-scan
``ascan.nc``) goes through :func:`write_netcdf`, and every reader through
:func:`open_netcdf`.  The schema (documented in ``docs/netcdf-schema.md``):

* global attributes ``Conventions = "CF-1.10"``, ``title``, ``institution``, ``source``
  (what made the data), ``history`` (when and by which echocal version),
  ``echocal_format`` (``"<kind>/<version>"``, e.g. ``"replay/2"``) and
  ``echocal_version``; a writer adds its own (e.g. ``sampling_rate_hz``); attribute
  names carry their unit as a suffix (``_hz``, ``_s``, ``_m_s``) because CF attributes
  have no ``units``;
* every variable has ``long_name`` and, when numeric, ``units`` in UDUNITS-2 spelling
  (``"m"``, ``"s"``, ``"degree"``, ``"1"`` for a dimensionless number);
* every numeric variable is stored zlib-compressed (level 4) with the shuffle filter and a
  Fletcher-32 checksum of each chunk (HDF5 filters), so a flipped bit is detected on read.

A file that fails its checksums, or is not readable as NetCDF-4/HDF5, is refused with one
:class:`~echocal.errors.DataFileError` line naming the file.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import os
import sys
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from echocal.errors import DataFileError
from echocal.io import atomic_write_bytes, netcdf_bytes

__all__ = [
    "CONVENTIONS",
    "ENCODING",
    "UDUNITS",
    "NetcdfKind",
    "format_version",
    "open_netcdf",
    "schema_problems",
    "verify_checksums",
    "write_netcdf",
]

CONVENTIONS = "CF-1.10"
"""The CF conventions version every echocal NetCDF file declares."""

ENCODING: dict[str, Any] = {"zlib": True, "complevel": 4, "shuffle": True, "fletcher32": True}
"""HDF5 filters on every numeric variable: deflate + shuffle + Fletcher-32 checksums."""

UDUNITS = frozenset({"1", "m", "s", "Hz", "degree", "m s-1"})
"""The UDUNITS-2 unit strings echocal writes (``"1"``: dimensionless)."""

INSTITUTION = "echocal (ultrasonic immersion simulator and calibration toolkit)"


def _numeric(values: Any) -> bool:
    return np.asarray(values).dtype.kind in "biuf"


def write_netcdf(
    dataset: Any,
    path: str | os.PathLike[str],
    *,
    fmt: str,
    title: str,
    source: str,
    attrs: Mapping[str, Any] | None = None,
) -> Path:
    """Write ``dataset`` (an ``xarray.Dataset``) to ``path`` in echocal's schema, atomically.

    Parameters
    ----------
    dataset : its variables must already carry ``long_name`` (and ``units`` when numeric).
    path : the ``.nc`` file; a failed write leaves nothing behind (and an old file intact).
    fmt : ``echocal_format`` value, ``"<kind>/<version>"``.
    title : CF ``title``: what the file holds, in a few words.
    source : CF ``source``: what produced the data (a simulator, a rig, a replay).
    attrs : further global attributes (strings or numbers), e.g. ``provenance``.

    Returns
    -------
    The path written.
    """
    import echocal

    missing = [
        str(name)
        for name, var in dataset.variables.items()
        if "long_name" not in var.attrs or (_numeric(var.values) and "units" not in var.attrs)
    ]
    if missing:  # a programming error of the caller, not bad input
        raise ValueError(f"variables without long_name/units: {', '.join(missing)}")
    now = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    out = dataset.copy()
    history = f"{now} written by echocal {echocal.__version__}"
    if dataset.attrs.get("history"):  # CF: the newest line first, earlier ones kept
        history += "\n" + str(dataset.attrs["history"])
    out.attrs = {
        "title": title,
        "institution": INSTITUTION,
        "source": source,
        **dataset.attrs,
        **dict(attrs or {}),
        "Conventions": CONVENTIONS,
        "history": history,
        "echocal_format": fmt,
        "echocal_version": echocal.__version__,
    }
    encoding = {
        str(name): dict(ENCODING)
        for name, var in out.variables.items()
        if _numeric(var.values) and var.ndim > 0
    }
    for name in out.dims:  # CF 2.5.1: a coordinate variable has no missing values
        if name in encoding:
            encoding[str(name)]["_FillValue"] = None
    target = Path(path)
    # in memory, then to disk: a refused write is an OSError naming the file, not a crash
    atomic_write_bytes(target, netcdf_bytes(out, encoding=encoding))
    return target


@contextlib.contextmanager
def _quiet_unraisable() -> Iterator[None]:
    """Silence exceptions raised in ``__del__`` while opening: a failed h5netcdf open leaves
    a half-built ``File`` whose finalizer raises ``AttributeError: _writable``, which Python
    would print as a second traceback after echocal's own one-line error."""
    previous = sys.unraisablehook
    sys.unraisablehook = lambda _info: None
    try:
        yield
    finally:
        sys.unraisablehook = previous


def open_netcdf(path: str | os.PathLike[str], *, what: str, verify: bool = True) -> Any:
    """Open ``path`` as an ``xarray.Dataset`` (lazily, h5netcdf engine).

    Parameters
    ----------
    what : what the file should be, for messages (``"replay file"``).
    verify : read every variable once first, so a checksum failure (a flipped bit) is
        reported here and not in the middle of a run.  The names of the variables
        without a checksum are then in ``dataset.encoding["unchecked_variables"]`` (None
        without ``verify``).

    Raises
    ------
    DataFileError : missing, not NetCDF-4/HDF5, a damaged header, or a failed checksum.
    """
    import gc

    import xarray as xr

    file = Path(path)
    if not file.is_file():
        raise DataFileError(f"{what} not found: {file}")
    unchecked = verify_checksums(file, what=what) if verify else None
    with _quiet_unraisable():
        try:
            ds = xr.open_dataset(file, engine="h5netcdf")
            ds.encoding["unchecked_variables"] = unchecked
            return ds
        except Exception as exc:  # any reader failure means "not readable as NetCDF-4"
            raise DataFileError(
                f"cannot read {what} {file} as NetCDF-4/HDF5 ({_reason(exc)}); "
                "is it damaged or not an echocal file?"
            ) from None
        finally:
            gc.collect()  # run the half-built File's finalizer while silenced


def _reason(exc: BaseException) -> str:
    text = str(exc).splitlines()[0] if str(exc) else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def verify_checksums(path: str | os.PathLike[str], *, what: str = "file") -> list[str]:
    """Read every dataset of the HDF5 file ``path``; return the names of those without a
    Fletcher-32 checksum (files written before the schema).

    Reading a chunk whose checksum fails raises in HDF5; that is reported as a
    :class:`~echocal.errors.DataFileError` naming the file and the variable.
    """
    import h5py

    file = Path(path)
    unchecked: list[str] = []
    with _quiet_unraisable():
        try:
            handle = h5py.File(file, "r")
        except Exception as exc:
            raise DataFileError(
                f"cannot read {what} {file} as NetCDF-4/HDF5 ({_reason(exc)}); "
                "is it damaged or not an echocal file?"
            ) from None
    with handle:
        names: list[str] = []
        name = "/"
        try:
            handle.visititems(lambda n, obj: names.append(n) if _is_variable(obj) else None)
            for name in names:
                dset = handle[name]
                if dset.dtype.kind in "biuf" and dset.shape:
                    for block in dset.iter_chunks() if dset.chunks else [()]:
                        dset[block]
                    if not dset.fletcher32:
                        unchecked.append(name)
        except Exception as exc:
            failed = "filter returned failure" in str(exc) or "checksum" in str(exc)
            problem = (
                "fails its Fletcher-32 checksum (or decompression)"
                if failed and name != "/"
                else f"is unreadable ({_reason(exc)})"
            )
            part = "its header" if name == "/" else f"variable {name!r}"
            raise DataFileError(
                f"{what} {file} is damaged: {part} {problem}; "
                "its data cannot be trusted: use an intact copy"
            ) from None
    return unchecked


def _is_variable(obj: Any) -> bool:
    """An HDF5 dataset that is a NetCDF variable (not a bare dimension scale)."""
    import h5py

    if not isinstance(obj, h5py.Dataset):
        return False
    name = obj.attrs.get("NAME", b"")
    text = name.decode() if isinstance(name, bytes) else str(name)
    return not text.startswith("This is a netCDF dimension but not a netCDF variable")


def format_version(dataset: Any, kind: str, *, legacy_key: str | None = None) -> int:
    """The version ``N`` of ``echocal_format = "<kind>/N"`` (0 if the attribute is missing).

    ``legacy_key``: an older attribute that held the format (``"format"`` in scan files).
    """
    fmt = dataset.attrs.get("echocal_format")
    if fmt is None and legacy_key is not None:
        fmt = dataset.attrs.get(legacy_key)
    if not isinstance(fmt, str) or "/" not in fmt:
        return 0
    name, _, version = fmt.rpartition("/")
    if name != kind or not version.isdigit():
        return 0
    return int(version)


@dataclass(frozen=True)
class NetcdfKind:
    """One kind of echocal NetCDF file (a surface scan, a position scan): written as
    ``"<kind>/<version>"`` through :func:`write_netcdf`, read back checked.

    Attributes
    ----------
    kind : the ``echocal_format`` kind, ``"position-scan"``.
    version : the version written (and read).
    what : the kind in messages, ``"position scan"``.
    title : the CF ``title`` of every file of this kind.
    older : further versions :meth:`load` accepts (the caller upgrades them).
    legacy_key : an older global attribute that held the format (see :func:`format_version`).
    hint : appended to the refusal of a file of another kind, ``"; import it first"``.
    """

    kind: str
    version: int
    what: str
    title: str
    older: tuple[int, ...] = ()
    legacy_key: str | None = None
    hint: str = ""

    @property
    def fmt(self) -> str:
        """The ``echocal_format`` written: ``"<kind>/<version>"``."""
        return f"{self.kind}/{self.version}"

    def save(self, dataset: Any, path: str | os.PathLike[str], *, source: str) -> Path:
        """Write ``dataset`` to ``path`` as this kind (compressed, checksummed), atomically;
        ``source``: the CF ``source`` (what produced the data).  Returns the path."""
        return write_netcdf(dataset, path, fmt=self.fmt, title=self.title, source=source)

    def load(self, path: str | os.PathLike[str]) -> tuple[Any, int]:
        """``(dataset, version)``: the whole file at ``path``, in memory and closed.

        Raises
        ------
        DataFileError : missing, unreadable, a failed checksum, or a file of another kind
            or version (neither :attr:`version` nor one of :attr:`older`).
        """
        try:
            with open_netcdf(path, what=self.what) as ds:
                data = ds.load()
        except (OSError, ValueError) as exc:
            raise DataFileError(f"cannot read {self.what} {str(path)!r}: {exc}") from None
        version = format_version(data, self.kind, legacy_key=self.legacy_key)
        if version != self.version and version not in self.older:
            raise DataFileError(
                f"{path}: not a {self.what} (format {self.fmt!r} expected{self.hint})"
            )
        return data, version


def schema_problems(path: str | os.PathLike[str]) -> list[str]:
    """What in the file ``path`` departs from echocal's NetCDF schema (empty if nothing).

    Checks the global attributes, ``long_name`` and UDUNITS ``units`` of every variable,
    no ``_FillValue`` on a coordinate variable (CF 2.5.1: coordinates have no missing
    values), and a verified Fletcher-32 checksum with deflate on every numeric variable.
    """
    import h5py

    problems = []
    try:
        unchecked = verify_checksums(path)
    except DataFileError as exc:
        return [str(exc)]
    for name in unchecked:
        problems.append(f"{name}: no Fletcher-32 checksum")
    ds = open_netcdf(path, what="file", verify=False)
    with ds:
        dims = {str(d) for d in ds.dims}
        if ds.attrs.get("Conventions") != CONVENTIONS:
            problems.append(f"Conventions is {ds.attrs.get('Conventions')!r}, not {CONVENTIONS!r}")
        for key in ("title", "institution", "source", "history", "echocal_format"):
            if not ds.attrs.get(key):
                problems.append(f"global attribute {key!r} is missing")
        for name, var in ds.variables.items():
            if not var.attrs.get("long_name"):
                problems.append(f"{name}: no long_name")
            if var.dtype.kind in "biuf" and "flag_values" not in var.attrs:
                unit = var.attrs.get("units")
                if unit not in UDUNITS:
                    problems.append(f"{name}: units {unit!r} is not one of {sorted(UDUNITS)}")
    with h5py.File(path, "r") as handle:
        for name, dset in handle.items():
            if name in dims and "_FillValue" in dset.attrs:
                problems.append(f"{name}: a coordinate variable with a _FillValue (CF 2.5.1)")
            if _is_variable(dset) and dset.dtype.kind in "biuf" and dset.shape:
                if dset.compression != "gzip" or not dset.shuffle:
                    problems.append(f"{name}: not deflate+shuffle compressed")
    return problems
