"""Where a result came from: the provenance record every result file carries.

A provenance record is plain JSON-ready data::

    {
      "format": "echocal-provenance/1",
      "command": "calibrate",                      # what produced the file
      "argv": ["echocal", "calibrate", ...],       # the command line, as typed
      "cwd": "/home/me/study",
      "started": "2026-11-23T21:40:00.123456Z",    # UTC, ISO 8601
      "finished": "2026-11-23T21:40:03.456789Z",
      "setup": {"name": "immersion-5mhz", "sha256": "…"},   # of the resolved setup
      "source": {"kind": "simulator"} | {"kind": "replay", "file": …, "sha256": …}
                | {"kind": "instrument", "address": …, "identification": …},
      "position_m": [x, y, z], "seed": 0,
      "method": {"name": "auto", "options": {…every option…}},
      "versions": {"echocal": …, "echocal_git": "<commit>[-dirty]", "python": …,
                   "numpy": …, "scipy": …, …},
      "parameters": {…}                            # what a rerun needs (command-specific)
    }

:func:`start` opens one (time and command line); :meth:`Provenance.finish` adds what the
run learned and the end time.  ``result.json`` holds it under ``"provenance"``; NetCDF
files (``scan.nc``, recordings) as the global attribute ``provenance`` (a JSON string);
a sweep's ``runs.parquet`` in its key-value metadata (pandas ``attrs``) and beside it in
``provenance.json``.  ``echocal calibrate --from result.json`` reruns a calibration from
its ``parameters`` after checking the setup's and the recording's digests.
"""

from __future__ import annotations

import datetime as _dt
import functools
import hashlib
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from echocal.errors import DataFileError
from echocal.io import json_ready

__all__ = [
    "FORMAT",
    "Provenance",
    "file_digest",
    "git_commit",
    "read_provenance",
    "start",
    "versions",
]

FORMAT = "echocal-provenance/1"
"""Format name of a provenance record."""

DEPENDENCIES = (
    "numpy",
    "scipy",
    "xarray",
    "pandas",
    "pyarrow",
    "h5py",
    "h5netcdf",
    "pydantic",
    "numba",
    "trimesh",
    "matplotlib",
)
"""The main dependencies whose versions a record lists (those installed)."""


def now() -> str:
    """The current time, UTC, ISO 8601 with microseconds and a ``Z``."""
    return _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


@functools.cache
def git_commit() -> str | None:
    """The git commit of echocal's source when it runs from a git checkout (an editable
    install), with ``-dirty`` when tracked files differ from it; None otherwise (a wheel,
    or no git)."""
    import echocal

    where = Path(echocal.__file__).resolve().parent

    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(
                ["git", "-C", str(where), *args], capture_output=True, text=True, timeout=10
            )
        except (OSError, subprocess.SubprocessError):
            return None
        return done.stdout.strip() if done.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    if not commit:
        return None
    changed = git("status", "--porcelain", "--untracked-files=no", "--", ".")
    return f"{commit}-dirty" if changed else commit


def versions() -> dict[str, str]:
    """echocal's, Python's and the main dependencies' versions (installed ones only), and
    echocal's git commit (``echocal_git``) when it runs from a checkout."""
    import echocal

    out = {"echocal": echocal.__version__, "python": platform.python_version()}
    commit = git_commit()
    if commit is not None:
        out["echocal_git"] = commit
    for name in DEPENDENCIES:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            continue
    out["platform"] = platform.platform()
    return out


def file_digest(path: str | os.PathLike[str]) -> str:
    """SHA-256 [hex] of a file's bytes (read in 1 MiB blocks)."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            while block := fh.read(1 << 20):
                digest.update(block)
    except OSError as exc:
        raise DataFileError(f"cannot read {path}: {exc.strerror or exc}") from None
    return digest.hexdigest()


@dataclass
class Provenance:
    """A provenance record being filled (see the module docstring)."""

    command: str
    started: str
    argv: list[str]
    cwd: str
    parameters: dict[str, Any] = field(default_factory=dict)
    rerun: dict[str, Any] | None = None
    """For a run repeated from a result file: that file and which setup it ran on."""

    def finish(self, **facts: Any) -> dict[str, Any]:
        """The complete record: these ``facts`` (setup, source, position_m, seed, method,
        …) plus the versions and the end time (now).  JSON-ready."""
        record = {
            "format": FORMAT,
            "command": self.command,
            "argv": self.argv,
            "cwd": self.cwd,
            "started": self.started,
            "finished": now(),
            **{k: v for k, v in facts.items() if v is not None},
            "versions": versions(),
            "parameters": self.parameters,
        }
        if self.rerun is not None:
            record["rerun"] = self.rerun
        return _plain(json_ready(record))

    def finish_json(self, **facts: Any) -> str:
        """:meth:`finish` as one JSON string (a NetCDF or Parquet attribute)."""
        return json.dumps(self.finish(**facts), sort_keys=True)


def _plain(value: Any) -> Any:
    """JSON-ready ``value`` with anything JSON cannot hold (a callable option such as a
    detector) named instead: ``"<function ascan_detector>"``."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if value is None or isinstance(value, str | int | float | bool):
        return value
    name = getattr(value, "__qualname__", None) or type(value).__name__
    return f"<{'function' if callable(value) else 'object'} {name}>"


def _program() -> str:
    """The command's name as typed: ``python -m echocal`` runs ``__main__.py``, the same
    command as ``echocal``."""
    name = Path(sys.argv[0]).name
    return "echocal" if name == "__main__.py" else name


def start(command: str, parameters: Mapping[str, Any] | None = None) -> Provenance:
    """Open the provenance record of ``command`` now (``parameters``: what a rerun needs)."""
    return Provenance(
        command=command,
        started=now(),
        argv=[_program(), *sys.argv[1:]] if sys.argv else [],
        cwd=os.getcwd(),
        parameters=_plain(json_ready(dict(parameters or {}))),
    )


def stamped(metadata: Mapping[str, Any] | None) -> dict[str, Any]:
    """``metadata`` with a :class:`Provenance` value under ``"provenance"`` finished now and
    written as JSON (for a writer that learns its end time only when it writes)."""
    out = dict(metadata or {})
    value = out.get("provenance")
    if value is None:
        out.pop("provenance", None)  # no record: no attribute (NetCDF has no null)
    elif isinstance(value, Provenance):
        out["provenance"] = value.finish_json()
    elif isinstance(value, dict):
        out["provenance"] = json.dumps({**value, "finished": now()}, sort_keys=True)
    return out


def read_provenance(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The provenance record of a result file: ``result.json``, a NetCDF file (its
    ``provenance`` attribute), a sweep folder or its ``runs.parquet``.

    Raises :class:`~echocal.errors.DataFileError` when the file has none.
    """
    target = Path(path)
    if target.is_dir():
        target = target / "provenance.json"
    try:
        if target.suffix == ".nc":
            import xarray as xr

            with xr.open_dataset(target, engine="h5netcdf") as ds:
                text = ds.attrs.get("provenance")
            record = json.loads(text) if text else None
        elif target.suffix == ".parquet":
            import pyarrow.parquet as pq

            meta = pq.read_schema(target).metadata or {}
            attrs = json.loads(meta.get(b"PANDAS_ATTRS", b"{}"))
            record = json.loads(attrs["provenance"]) if "provenance" in attrs else None
        else:
            data = json.loads(target.read_text(encoding="utf-8"))
            record = data.get("provenance", data) if isinstance(data, dict) else None
    except (OSError, ValueError, KeyError) as exc:
        raise DataFileError(f"{target}: cannot read its provenance ({exc})") from None
    if not isinstance(record, dict) or record.get("format") != FORMAT:
        raise DataFileError(
            f"{target} records no provenance (written by an older echocal, or not a result "
            "file); rerun the original command instead"
        )
    return record
