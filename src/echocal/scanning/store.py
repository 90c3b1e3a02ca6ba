"""The resumable store of an unfinished scan: one JSON line per finished point.

Beside the output ``scan.nc`` lives ``scan.nc.partial/`` with

* ``manifest.json`` — format, the grid and the settings that define the scan,
  and their hash (written atomically once);
* ``points.jsonl`` — one record per finished point, appended and flushed to
  disk (``fsync``) as soon as the point is done; its angles [deg] are named for the
  scan's parameterization (``tilt_x_deg``, ``tilt_y_deg``: :mod:`echocal.angle_columns`;
  ``a``, ``b`` in a store of an older echocal, still resumed).

A resumed scan reads the records back and skips those points; a torn last line
(an interruption in the middle of a write) is ignored and that point measured
again.  A store made by a different scan (another grid, method, budget, source
...) is refused with a clear :class:`~echocal.errors.DataFileError`.  The final
NetCDF file is written atomically and only then the store removed.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any

from echocal.errors import DataFileError
from echocal.io import atomic_write_text, unwritable

__all__ = [
    "PARTIAL_FORMAT",
    "PointStore",
    "partial_path",
    "saved_points",
    "setting_differences",
    "settings_digest",
]

PARTIAL_FORMAT = "surface-scan-partial/1"
"""Format name in the manifest of an unfinished scan."""


def partial_path(path: str | os.PathLike[str]) -> Path:
    """The sidecar directory of an unfinished scan written to ``path``."""
    target = Path(path)
    return target.with_name(target.name + ".partial")


def settings_digest(settings: dict[str, Any]) -> str:
    """SHA-256 of a scan's settings (what defines the scan: grid, source, method, ...)."""
    text = json.dumps(settings, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def setting_differences(old: dict[str, Any] | None, new: dict[str, Any]) -> list[str]:
    """The names of the settings that differ between two scans (sorted; ``"all"`` when the
    old ones are unknown)."""
    if not isinstance(old, dict):
        return ["all"]
    same = json.loads(json.dumps(new, default=str))  # as stored: tuples become lists
    return sorted(k for k in old.keys() | same.keys() if old.get(k) != same.get(k))


def saved_points(out: str | os.PathLike[str]) -> int:
    """Points saved by an unfinished scan of ``out`` (0 if none), without checking that it
    is the same scan (:meth:`PointStore.open` does)."""
    try:
        with (partial_path(out) / "points.jsonl").open("rb") as fh:
            return sum(1 for line in fh if line.endswith(b"\n"))
    except OSError:
        return 0


class PointStore:
    """Append-only store of finished points of one scan (see module docstring).

    Parameters
    ----------
    out : the final NetCDF path; the store is ``<out>.partial/``.
    settings : JSON-ready description of the scan (grid, method, source, ...).
    """

    def __init__(self, out: str | os.PathLike[str], settings: dict[str, Any]) -> None:
        self.directory = partial_path(out)
        self.settings = settings
        self.digest = settings_digest(settings)
        self._manifest = self.directory / "manifest.json"
        self._points = self.directory / "points.jsonl"

    def open(self) -> list[dict[str, Any]]:
        """Create the store or reopen a matching one; return the records already saved.

        A store of another scan raises :class:`~echocal.errors.DataFileError` naming the
        settings that differ.
        """
        if self.directory.exists():
            try:
                manifest = json.loads(self._manifest.read_text(encoding="utf-8"))
            except (OSError, json.JSONDecodeError) as exc:
                raise DataFileError(
                    f"{self.directory}: unreadable partial scan ({exc}); delete it to start over"
                ) from None
            if manifest.get("format") != PARTIAL_FORMAT or manifest.get("digest") != self.digest:
                differ = setting_differences(manifest.get("settings"), self.settings)
                raise DataFileError(
                    f"{self.directory} holds a different unfinished scan (other "
                    f"{', '.join(differ)}); refusing to resume it — delete it or choose "
                    "another --out"
                )
            return self._read()
        self.directory.mkdir(parents=True)
        manifest = {"format": PARTIAL_FORMAT, "digest": self.digest, "settings": self.settings}
        atomic_write_text(self._manifest, json.dumps(manifest, indent=1, default=str))
        return []

    def _read(self) -> list[dict[str, Any]]:
        if not self._points.exists():
            return []
        records, good = [], 0
        with self._points.open("rb") as fh:
            for line in fh:
                if not line.endswith(b"\n"):
                    break  # a torn last line: that point is measured again
                try:
                    records.append(json.loads(line))
                except (json.JSONDecodeError, UnicodeDecodeError):
                    break
                good += len(line)
        if good != self._points.stat().st_size:
            with self._points.open("r+b") as fh:  # drop the torn tail before appending
                fh.truncate(good)
        return records

    def append(self, record: dict[str, Any]) -> None:
        """Save one finished point durably; a refused write (a full disk, a file-size
        limit) is a :class:`~echocal.errors.DataFileError` naming the file and the cause
        (a torn line it may leave is dropped on resume)."""
        try:
            with self._points.open("a", encoding="utf-8") as fh:
                fh.write(json.dumps(record, allow_nan=True) + "\n")
                fh.flush()
                os.fsync(fh.fileno())
        except OSError as exc:
            raise unwritable(self._points, exc) from None

    def remove(self) -> None:
        """Delete the store (after the final file is written)."""
        shutil.rmtree(self.directory, ignore_errors=True)
