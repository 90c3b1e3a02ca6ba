"""File output that never leaves a half-written result behind."""

from __future__ import annotations

import contextlib
import math
import os
import secrets
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from echocal.errors import DataFileError

__all__ = [
    "atomic_path",
    "atomic_write_text",
    "check_out_dir",
    "file_in_the_way",
    "json_ready",
    "refuse_existing_output",
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
        tmp = _create_unique(target)
    except OSError as exc:
        raise _unwritable(target, exc) from None
    try:
        yield tmp
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


def _unwritable(target: Path, exc: OSError) -> DataFileError:
    return DataFileError(f"cannot write {target}: {exc.strerror or exc}; choose a writable path")


def _create_unique(target: Path) -> Path:
    """Create an empty, unique temporary file beside ``target`` with mode 0666 & ~umask.

    Not ``mkstemp`` + ``chmod``: its 0600 would need the umask, which can only be read by
    setting it — process-wide, racing other threads' file creation (Dask workers, the
    instrument server).  ``os.open`` with mode 0666 lets the kernel apply the umask.
    """
    for _ in range(100):
        name = f".{target.name}.{secrets.token_hex(6)}.partial{target.suffix}"
        tmp = target.parent / name
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(f"no free temporary name beside {target}")  # pragma: no cover


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
