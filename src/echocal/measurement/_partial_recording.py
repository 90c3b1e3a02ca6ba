"""The sidecar of an unfinished recording (private): chunk files plus a manifest.

``<path>.partial/`` holds ``chunk-<start>.npy`` files of shape ``(count, n_samples)`` and
``manifest.json`` listing the finished chunks (each written atomically, with the SHA-256
of its file: an :class:`echocal.io.ChecksummedManifest`); see
:func:`echocal.measurement.recording.record`.  A damaged sidecar — a chunk missing,
unreadable, of another shape than the manifest says, whose bytes no longer match its
SHA-256, or holding a sample that is not finite — is refused in one line when the
recording resumes, before anything more is measured, and again before the final file
is written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.ascan import AScan
from echocal.errors import DataFileError, EchocalValueError
from echocal.io import ChecksummedManifest

PARTIAL_FORMAT = "replay-partial/1"
"""Format name in the manifest of a partial recording."""


class _Partial:
    """The sidecar directory: chunk files plus a manifest (private)."""

    def __init__(self, directory: Path, fingerprint: dict[str, Any]) -> None:
        self.dir = directory
        label, fix = "partial recording ", f"delete {directory} to record from the start"
        found = ChecksummedManifest.read(directory, "chunks", label=label, fix=fix)
        if found is not None:
            self.files = found
            differ = found.differing(fingerprint)
            if differ:
                raise DataFileError(
                    f"cannot resume: partial recording {directory} was made with a different "
                    f"{', '.join(differ)} (recorded {found.recorded(differ)}); "
                    "record to another path, pass overwrite=True (CLI: --overwrite) to discard "
                    "it, or delete the partial directory"
                )
            self.check_chunks()
        else:
            self.files = ChecksummedManifest.new(
                directory, PARTIAL_FORMAT, fingerprint, "chunks", label=label, fix=fix
            )
            try:
                directory.mkdir(parents=True, exist_ok=True)
                self._save()
            except OSError as exc:
                raise DataFileError(
                    f"cannot create the partial recording {directory}: {exc.strerror or exc}"
                ) from None

    @property
    def manifest(self) -> dict[str, Any]:
        """The manifest's data: format, fingerprint, chunks and the A-scans' format."""
        return self.files.data

    @property
    def n_done(self) -> int:
        return sum(int(c["count"]) for c in self.manifest["chunks"])

    def _save(self) -> None:
        self.files.save()

    def check_format(self, ascan: AScan, index: int) -> None:
        """Refuse an A-scan of another sampling format than the earlier ones, or with a
        sample that is not finite (a receiver fault: a recording holds finite A-scans)."""
        if not ascan.is_finite:
            n_bad = int(np.count_nonzero(~np.isfinite(ascan.samples)))
            raise EchocalValueError(
                f"measurement {index}: the source delivered an A-scan with {n_bad} sample(s) "
                "that are not finite (a receiver fault); the earlier measurements are kept: "
                "fix the receiver and run again to resume"
            )
        fmt = {"fs": ascan.fs, "start_time": ascan.start_time, "n_samples": ascan.n_samples}
        known = self.manifest.get("ascan")
        if known is None:
            self.manifest["ascan"] = fmt
        elif known != fmt:
            raise EchocalValueError(
                f"measurement {index} has fs/start_time/n_samples {fmt}; earlier ones had "
                f"{known} — a recording needs one sampling format"
            )

    def write_chunk(self, start: int, rows: list[NDArray[np.float64]]) -> None:
        """Save measurements ``start, start + 1, ...`` as a chunk; those already saved are
        skipped, so calling it again after an interruption (a signal inside the first call)
        never saves a measurement twice: the chunks stay contiguous."""
        done = self.n_done
        if start > done:
            raise DataFileError(f"partial recording {self.dir}: measurements {done}.. missing")
        rows = rows[done - start :]
        if rows:

            def write(tmp: Path) -> None:
                with tmp.open("wb") as fh:
                    np.save(fh, np.stack(rows))

            self.files.add(f"chunk-{done:09d}.npy", write, start=done, count=len(rows))
            return
        self._save()

    def check_chunks(self) -> None:
        """Refuse, in one line, a partial recording whose chunks are damaged: missing,
        unreadable, out of order, of another shape than the manifest says, changed since it
        was written (its SHA-256) or holding a sample that is not finite — before
        anything more is measured into it."""
        for chunk in self.manifest["chunks"]:
            self._chunk(chunk, mmap=True)

    def _chunk(self, chunk: dict[str, Any], *, mmap: bool = False) -> NDArray[np.float64]:
        path, fix = self.files.file(chunk), self.files.fix
        try:
            arr = np.load(path, mmap_mode="r" if mmap else None, allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            raise self.files.unreadable(path, exc) from None
        n_samples = (self.manifest.get("ascan") or {}).get("n_samples")
        expected = (int(chunk["count"]), n_samples if n_samples is not None else arr.shape[-1])
        if arr.shape != expected:
            raise DataFileError(
                f"partial recording {path} is damaged: it holds an array of shape "
                f"{arr.shape}, the manifest says {expected} (A-scans, samples); {fix}"
            )
        self.files.verify(chunk, digest_optional=True)  # manifests before digests have none
        bad = ~np.isfinite(arr)
        if bad.any():
            row, column = (int(v[0]) for v in np.nonzero(bad))
            raise DataFileError(
                f"partial recording {path} is damaged: {int(bad.sum())} sample(s) are not "
                f"finite (first: A-scan {int(chunk['start']) + row}, sample {column}: "
                f"{arr[row, column]}); {fix}"
            )
        return arr

    def load(self, total: int) -> NDArray[np.float64]:
        parts, expected = [], 0
        for chunk in self.manifest["chunks"]:
            if int(chunk["start"]) != expected:
                raise DataFileError(f"partial recording {self.dir}: chunks are not contiguous")
            parts.append(self._chunk(chunk))
            expected += int(chunk["count"])
        if expected != total:
            raise DataFileError(f"partial recording {self.dir} holds {expected} of {total} A-scans")
        return np.concatenate(parts, axis=0)
