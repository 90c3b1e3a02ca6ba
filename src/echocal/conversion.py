"""Rewrite an echocal NetCDF file of an older format in the current schema.

Above every module that writes a format (recordings, scans, A-scans): :mod:`echocal.netcdf`
holds the schema, this module the one operation that needs all the writers.
"""

from __future__ import annotations

import os

from echocal.errors import DataFileError
from echocal.netcdf import open_netcdf

__all__ = ["convert"]


def convert(source: str | os.PathLike[str], target: str | os.PathLike[str]) -> str:
    """Rewrite an echocal NetCDF file of an older format in the current schema.

    Reads ``source`` (``replay/1``, ``surface-scan/1``, ``ascan/1``, or already current)
    and writes ``target`` (compressed, checksummed).  Returns the format written.

    Raises
    ------
    DataFileError : ``source`` is missing, damaged, or not an echocal file.
    """
    import warnings

    with open_netcdf(source, what="file") as ds:
        attrs = dict(ds.attrs)
    kind = str(attrs.get("echocal_format") or attrs.get("format") or "").rpartition("/")[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the "no checksums" warning: we are adding them
        if kind == "replay":
            from echocal.measurement.recording import save_recording
            from echocal.measurement.replay import FORMAT, ReplaySource

            with ReplaySource.open(source) as replay:
                save_recording(replay._ds.load(), target)
            return FORMAT
        if kind == "surface-scan":
            from echocal.scanning.dataset import FORMAT as SCAN_FORMAT
            from echocal.scanning.dataset import SurfaceScan

            SurfaceScan.load(source).save(target)
            return SCAN_FORMAT
        if kind == "ascan":
            from echocal.ascan import ASCAN_FORMAT, load_ascan, save_ascan

            scan = load_ascan(source)
            save_ascan(scan, target, summary=scan.metadata["summary"])
            return ASCAN_FORMAT
    raise DataFileError(
        f"{source} is not an echocal replay, scan or A-scan file (attribute "
        "'echocal_format' is missing or unknown); there is nothing to convert"
    )
