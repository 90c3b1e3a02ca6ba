"""The sidecar of an unfinished recording (private): chunk files plus a manifest.

``<path>.partial/`` holds ``chunk-<start>.npy`` files of shape ``(count, n_samples)`` and
``manifest.json`` listing the finished chunks (each written atomically, with the SHA-256
of its file); see :func:`echocal.measurement.recording.record`.  A damaged sidecar — a
chunk missing, unreadable, of another shape than the manifest says, whose bytes no longer
match its SHA-256, or holding a sample that is not finite — is refused in one line when
the recording resumes, before anything more is measured, and again before the final file
is written.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.ascan import AScan
from echocal.errors import DataFileError, EchocalValueError
from echocal.io import atomic_path, atomic_write_text

PARTIAL_FORMAT = "replay-partial/1"
"""Format name in the manifest of a partial recording."""


def _short(value: Any, limit: int = 60) -> str:
    """``repr(value)``, cut to ``limit`` characters (a grid's angle lists run to kilobytes)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


class _Partial:
    """The sidecar directory: chunk files plus a manifest (private)."""

    def __init__(self, directory: Path, fingerprint: dict[str, Any]) -> None:
        self.dir = directory
        self.manifest_path = directory / "manifest.json"
        if self.manifest_path.exists():
            try:
                self.manifest = json.loads(self.manifest_path.read_text(encoding="utf-8"))
                old = self.manifest["fingerprint"]
            except (OSError, ValueError, KeyError) as exc:
                raise DataFileError(
                    f"partial recording {directory} is unreadable ({exc}); delete it to start over"
                ) from None
            differ = sorted(
                k for k in fingerprint.keys() | old.keys() if fingerprint.get(k) != old.get(k)
            )
            if differ:
                recorded = ", ".join(f"{k}={_short(old.get(k))}" for k in differ)
                raise DataFileError(
                    f"cannot resume: partial recording {directory} was made with a different "
                    f"{', '.join(differ)} (recorded {recorded}); "
                    "record to another path, pass overwrite=True (CLI: --overwrite) to discard "
                    "it, or delete the partial directory"
                )
            self.check_chunks()
        else:
            self.manifest = {"format": PARTIAL_FORMAT, "fingerprint": fingerprint, "chunks": []}
            try:
                directory.mkdir(parents=True, exist_ok=True)
                self._save()
            except OSError as exc:
                raise DataFileError(
                    f"cannot create the partial recording {directory}: {exc.strerror or exc}"
                ) from None

    @property
    def n_done(self) -> int:
        return sum(int(c["count"]) for c in self.manifest["chunks"])

    def _save(self) -> None:
        atomic_write_text(self.manifest_path, json.dumps(self.manifest, indent=1))

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
            name = f"chunk-{done:09d}.npy"
            with atomic_path(self.dir / name) as tmp:
                with tmp.open("wb") as fh:
                    np.save(fh, np.stack(rows))
                digest = _sha256(tmp)
            self.manifest["chunks"].append(
                {"file": name, "start": done, "count": len(rows), "sha256": digest}
            )
        self._save()

    def check_chunks(self) -> None:
        """Refuse, in one line, a partial recording whose chunks are damaged: missing,
        unreadable, out of order, of another shape than the manifest says, changed since it
        was written (its SHA-256) or holding a sample that is not finite — before
        anything more is measured into it."""
        for chunk in self.manifest["chunks"]:
            self._chunk(chunk, mmap=True)

    def _chunk(self, chunk: dict[str, Any], *, mmap: bool = False) -> NDArray[np.float64]:
        path = self.dir / str(chunk.get("file"))
        fix = f"delete {self.dir} to record from the start"
        try:
            arr = np.load(path, mmap_mode="r" if mmap else None, allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            raise DataFileError(f"partial recording {path} is unreadable ({exc}); {fix}") from None
        n_samples = (self.manifest.get("ascan") or {}).get("n_samples")
        expected = (int(chunk["count"]), n_samples if n_samples is not None else arr.shape[-1])
        if arr.shape != expected:
            raise DataFileError(
                f"partial recording {path} is damaged: it holds an array of shape "
                f"{arr.shape}, the manifest says {expected} (A-scans, samples); {fix}"
            )
        expected_digest = chunk.get("sha256")
        if expected_digest is not None:
            try:
                digest = _sha256(path)
            except OSError as exc:
                raise DataFileError(
                    f"partial recording {path} is unreadable ({exc.strerror or exc}); {fix}"
                ) from None
            if digest != expected_digest:
                raise DataFileError(
                    f"partial recording {path} is damaged: its SHA-256 is {digest[:12]}…, "
                    f"the manifest says {str(expected_digest)[:12]}… (the file changed after "
                    f"it was written); {fix}"
                )
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


def _sha256(path: Path) -> str:
    """The SHA-256 (hex) of the file at ``path``."""
    digest = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()
