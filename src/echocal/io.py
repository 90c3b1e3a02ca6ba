"""File output that never leaves a half-written result behind."""

from __future__ import annotations

import contextlib
import errno
import glob
import hashlib
import json
import math
import os
import re
import secrets
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from echocal.errors import DataFileError

__all__ = [
    "ChecksummedManifest",
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_out_dir",
    "file_in_the_way",
    "json_ready",
    "netcdf_bytes",
    "refuse_existing_output",
    "sha256_file",
]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    Whatever writer the caller uses (matplotlib, xarray, pandas) writes to the
    temporary file; if it raises, the temporary file is removed and ``path`` is
    untouched.
    """
    target = Path(path)
    if target.is_dir():
        raise DataFileError(f"cannot write {target}: it is a directory; give a file path")
    blocker = file_in_the_way(target)
    if blocker is not None:
        raise DataFileError(
            f"cannot write {target}: {blocker} is not a directory; choose another path"
        )
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        _remove_stale_temporaries(target)
        tmp = _create_unique(target)
    except OSError as exc:
        raise _unwritable(target, exc) from None
    try:
        try:
            yield tmp
        except DataFileError:
            raise
        except OSError as exc:  # the writer failed (file-size limit, disk full, ...)
            raise _unwritable(target, exc) from None
        try:
            os.replace(tmp, target)
        except OSError as exc:
            raise _unwritable(target, exc) from None
    finally:
        if tmp.exists():
            tmp.unlink()


def file_in_the_way(path: str | os.PathLike[str]) -> Path | None:
    """The nearest existing ancestor of ``path`` when it is not a directory (a file where a
    folder must be), else None."""
    for folder in Path(path).parents:
        if folder.exists():
            return None if folder.is_dir() else folder
    return None


def refuse_existing_output(out_dir: str | os.PathLike[str], *, overwrite: bool) -> Path:
    """The one rule of every command that writes an output folder: a folder that already
    holds files is refused unless ``overwrite`` — results are never replaced silently.
    Checks only (nothing is written): call it before measuring anything."""
    folder = Path(out_dir)
    if folder.exists() and not folder.is_dir():
        raise DataFileError(f"output folder {str(folder)!r} exists and is not a folder")
    blocker = file_in_the_way(folder)
    if blocker is not None:
        raise DataFileError(
            f"cannot write {str(folder)!r}: {blocker} is not a directory; choose another folder"
        )
    if folder.is_dir() and any(folder.iterdir()) and not overwrite:
        raise DataFileError(
            f"output folder {str(folder)!r} already holds results; choose another folder "
            "or pass overwrite=True (CLI: --overwrite) to replace them"
        )
    return folder


def check_out_dir(
    out_dir: str | os.PathLike[str], *, overwrite: bool, own_files: Iterable[str] = ()
) -> Path:
    """:func:`refuse_existing_output`, then make the folder ready: the files this command
    writes (``own_files``, names inside ``out_dir``) are removed, so none left by an
    earlier run (a plot the new run does not make, say) stays beside the new result —
    nothing else is touched — and the folder is created if needed.  Returns the folder."""
    folder = refuse_existing_output(out_dir, overwrite=overwrite)
    for name in own_files:
        stale = folder / name
        if stale.is_file() or stale.is_symlink():
            stale.unlink()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _unwritable(folder, exc) from None
    return folder


_WHY = {
    errno.EFBIG: "File too large (a file-size limit, `ulimit -f`, or the file system's "
    "maximum); free the limit or write elsewhere",
    errno.ENOSPC: "No space left on the device; free some space or write elsewhere",
}


def unwritable(target: str | os.PathLike[str], exc: OSError) -> DataFileError:
    """The one-line error of a write to ``target`` that failed with ``exc``: the file and
    the cause (a full disk, a file-size limit, permissions) with what to do."""
    return _unwritable(Path(target), exc)


def _unwritable(target: Path, exc: OSError) -> DataFileError:
    why = _WHY.get(exc.errno or 0)
    if why is None and "errno = 27" in str(exc):  # HDF5 reports EFBIG in its message
        why = _WHY[errno.EFBIG]
    if why is None:
        reason = exc.strerror or str(exc).split(" (", 1)[0]
        why = f"{reason}; choose a writable path"
    return DataFileError(f"cannot write {target}: {why}")


_TEMPORARY = re.compile(r"\.(\d+)-[0-9a-f]{12}\.partial")
"""The pid in a temporary's name: ``.NAME.<pid>-<12 hex>.partial<suffix>``."""


def _remove_stale_temporaries(target: Path) -> None:
    """Delete temporaries of ``target`` left by a writer that was killed (its process is
    gone): a kill during a final write must not leave a hidden file behind for ever."""
    pattern = f".{glob.escape(target.name)}.*.partial{glob.escape(target.suffix)}"
    for tmp in target.parent.glob(pattern):
        found = _TEMPORARY.search(tmp.name[len(target.name) + 1 :])
        if found is not None and not _alive(int(found.group(1))):
            with contextlib.suppress(OSError):
                tmp.unlink()


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process (EPERM): alive
        return True
    return True


def _create_unique(target: Path) -> Path:
    """Create an empty, unique temporary file beside ``target`` with mode 0666 & ~umask.

    Not ``mkstemp`` + ``chmod``: its 0600 would need the umask, which can only be read by
    setting it — process-wide, racing other threads' file creation (Dask workers, the
    instrument server).  ``os.open`` with mode 0666 lets the kernel apply the umask.
    """
    for _ in range(100):  # the pid lets a later writer remove it if this process is killed
        name = f".{target.name}.{os.getpid()}-{secrets.token_hex(6)}.partial{target.suffix}"
        tmp = target.parent / name
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(f"no free temporary name beside {target}")  # pragma: no cover


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def netcdf_bytes(dataset: Any, **to_netcdf: Any) -> bytes:
    """``dataset`` (an ``xarray.Dataset``) as the bytes of a NetCDF-4 file (h5netcdf).

    Written in memory, then to disk with :func:`atomic_write_bytes`: a write that fails
    (a file-size limit, a full disk) is then a plain ``OSError`` naming the file — HDF5
    writing to the disk itself crashes the process (SIGSEGV) when the disk refuses.
    """
    data = dataset.to_netcdf(None, engine="h5netcdf", **to_netcdf)
    return bytes(data)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def atomic_write(path: str | os.PathLike[str], writer: Callable[[Path], object]) -> None:
    """Call ``writer(tmp_path)`` and move the result onto ``path`` atomically."""
    with atomic_path(path) as tmp:
        writer(tmp)


def json_ready(value: Any) -> Any:
    """``value`` as strict-JSON-ready plain data, recursively through dicts, lists, tuples.

    Numpy scalars and arrays become Python values, paths strings, and non-finite floats
    ``None`` (JSON has no NaN or inf: ``null`` reads "no value" or "unlimited").
    """
    import numpy as np

    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    return value


def sha256_file(path: str | os.PathLike[str]) -> str:
    """The SHA-256 (hex) of the file at ``path``, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with Path(path).open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


class ChecksummedManifest:
    """A folder of files that a run writes one by one, each listed with its SHA-256 in the
    folder's ``manifest.json`` beside the run's *fingerprint* (what makes it the same run),
    so that the same run can later resume from them and a file changed after it was
    written is refused.

    ``data`` is the whole manifest: ``{"format": ..., "fingerprint": {...}, key: [entry,
    ...], ...}`` (``key`` names the list; an entry is ``{"file": name, "sha256": hex, ...}``;
    the caller may keep more fields in ``data``).  Every file and every manifest is
    written atomically: an interrupted write leaves the previous manifest and no
    half-written file.  :meth:`add` rewrites the whole manifest, O(n) in the entries per
    file: fine for the hundreds of files of a calibration or a recording's chunks.

    ``label`` starts every error's message (``"cannot resume: "``, ``"partial recording
    "``), and ``fix`` ends it (what to do: ``"delete FOLDER to start over"``); each error
    is one line (:class:`~echocal.errors.DataFileError`).
    """

    def __init__(self, folder: Path, data: dict[str, Any], key: str, *, label: str, fix: str):
        self.folder = folder
        self.path = folder / "manifest.json"
        self.data = data
        self.key = key
        self.label = label
        self.fix = fix

    @classmethod
    def new(
        cls, folder: Path, fmt: str, fingerprint: dict[str, Any], key: str, *, label: str, fix: str
    ) -> ChecksummedManifest:
        """An empty manifest (nothing written until :meth:`save` or :meth:`add`)."""
        data = {"format": fmt, "fingerprint": fingerprint, key: []}
        return cls(folder, data, key, label=label, fix=fix)

    @classmethod
    def read(cls, folder: Path, key: str, *, label: str, fix: str) -> ChecksummedManifest | None:
        """The manifest in ``folder``; None when there is none; a one-line
        :class:`~echocal.errors.DataFileError` when it is unreadable or lacks its
        fingerprint or list."""
        path = folder / "manifest.json"
        if not path.exists():
            return None
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            if not isinstance(data["fingerprint"], dict) or not isinstance(data[key], list):
                raise TypeError(f"no fingerprint or {key} list")
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise DataFileError(f"{label}{path} is unreadable ({exc}); {fix}") from None
        return cls(folder, data, key, label=label, fix=fix)

    @property
    def entries(self) -> list[dict[str, Any]]:
        """The files listed so far, in the order they were added."""
        return list(self.data[self.key])

    def differing(self, fingerprint: dict[str, Any]) -> list[str]:
        """The keys (sorted) whose values differ between ``fingerprint`` and the recorded
        one (a key missing on one side counts as None there)."""
        old = self.data["fingerprint"]
        keys = fingerprint.keys() | old.keys()
        return sorted(k for k in keys if fingerprint.get(k) != old.get(k))

    def recorded(self, keys: list[str], limit: int = 60) -> str:
        """The recorded fingerprint's values of ``keys``, for a message: ``"k=value;
        k=value"``, each value as JSON (``repr`` where JSON has none) cut to ``limit``
        characters (a grid's angle lists run to kilobytes)."""
        old = self.data["fingerprint"]

        def short(value: Any) -> str:
            text = json.dumps(value, sort_keys=True, default=repr)
            return text if len(text) <= limit else text[: limit - 1] + "…"

        return "; ".join(f"{k}={short(old.get(k))}" for k in keys)

    def save(self) -> None:
        """Write the manifest atomically."""
        atomic_write_text(self.path, json.dumps(self.data, indent=1))

    def add(self, name: str, writer: Callable[[Path], object], **fields: Any) -> dict[str, Any]:
        """Write file ``name`` in the folder atomically with ``writer(tmp_path)``, list it
        with its SHA-256 and ``fields``, and write the manifest again; returns its entry."""
        with atomic_path(self.folder / name) as tmp:
            writer(tmp)
            digest = sha256_file(tmp)
        entry = {"file": name, **fields, "sha256": digest}
        self.data[self.key].append(entry)
        self.save()
        return entry

    def file(self, entry: dict[str, Any]) -> Path:
        """The path of ``entry``'s file."""
        return self.folder / str(entry.get("file"))

    def verify(self, entry: dict[str, Any], *, digest_optional: bool = False) -> Path:
        """``entry``'s file, checked against its SHA-256; a one-line
        :class:`~echocal.errors.DataFileError` when it is unreadable, changed after it was
        written, or listed without a SHA-256 (unless ``digest_optional``: an older
        manifest's entry, then not checked)."""
        path = self.file(entry)
        expected = entry.get("sha256")
        if expected is None and digest_optional:
            return path
        try:
            digest = sha256_file(path)
        except OSError as exc:
            raise self.unreadable(path, exc.strerror or exc) from None
        if digest != expected:
            raise DataFileError(
                f"{self.label}{path} is damaged: its SHA-256 is {digest[:12]}…, the manifest "
                f"says {str(expected)[:12]}… (the file changed after it was written); {self.fix}"
            )
        return path

    def unreadable(self, path: Path, why: object) -> DataFileError:
        """The one-line error of a listed file ``path`` that cannot be read (``why``)."""
        return DataFileError(f"{self.label}{path} is unreadable ({why}); {self.fix}")
