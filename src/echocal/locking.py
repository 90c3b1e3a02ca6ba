"""Advisory locks on output folders and files: one writer at a time.

Two commands writing into one place would mix or replace each other's results (two sweeps
deleting each other's temporary parts, the second scan replacing the first's file, two
recordings racing for one sidecar).  Every echocal writer holds an exclusive advisory lock
(``fcntl.flock``) while it writes; a second writer is refused at once with one line
(:class:`OutputLockedError`) instead of waiting or corrupting.

* A **folder** (``sweep run --out``, ``scan --out``, ``calibrate --out``) is locked by
  flocking the folder itself: no lock file is left in it (a folder the lock created is
  removed again if the writer leaves it empty).
* A **file** (``record --out grid.nc``) is locked through a hidden lock file beside it,
  ``.grid.nc.lock``, removed when the lock is released.

The lock is released when the writer ends, however it ends (the kernel drops a killed
process's locks), so a stale lock never blocks the next run.  Advisory: only echocal
processes honour it.  On a platform or file system without ``flock`` the writer proceeds
unlocked.
"""

from __future__ import annotations

import contextlib
import errno
import os
from collections.abc import Iterator
from pathlib import Path

from echocal.errors import DataFileError
from echocal.io import file_in_the_way

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None  # type: ignore[assignment]

__all__ = ["OutputLockedError", "hold_output_lock", "output_lock", "release_held_locks"]


class OutputLockedError(DataFileError):
    """Another process is writing the same output folder or file."""


_BUSY = (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES)
_UNSUPPORTED = (errno.ENOLCK, errno.EOPNOTSUPP, errno.EINVAL, errno.EBADF)


def _refuse(path: Path, option: str) -> OutputLockedError:
    return OutputLockedError(
        f"{option} {path} is being written by another echocal process; wait for it to "
        f"finish or choose another {option}"
    )


def _try_flock(fd: int, path: Path, option: str) -> bool:
    """Lock ``fd`` exclusively without waiting: True if locked, False if the platform
    cannot lock; :class:`OutputLockedError` if another process holds it."""
    if fcntl is None:  # pragma: no cover - not POSIX
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        if exc.errno in _BUSY:
            raise _refuse(path, option) from None
        if exc.errno in _UNSUPPORTED:
            return False
        raise
    return True


@contextlib.contextmanager
def _folder_lock(folder: Path, option: str) -> Iterator[None]:
    created = not folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError as exc:
        raise DataFileError(
            f"cannot write {option} {folder}: {exc.strerror or exc}; choose a writable folder"
        ) from None
    try:
        _try_flock(fd, folder, option)
        yield
    finally:
        if created:  # a run refused or stopped before writing leaves no empty folder
            with contextlib.suppress(OSError):
                folder.rmdir()
        os.close(fd)  # closing the descriptor releases the lock


def lock_file_path(path: str | os.PathLike[str]) -> Path:
    """The hidden lock file of an output file: ``.NAME.lock`` beside it."""
    target = Path(path)
    return target.with_name(f".{target.name}.lock")


@contextlib.contextmanager
def _file_lock(target: Path, option: str) -> Iterator[None]:
    lock = lock_file_path(target)
    blocker = file_in_the_way(lock)
    if blocker is not None:
        raise DataFileError(
            f"cannot write {option} {target}: {blocker} is not a directory; choose a path "
            "in a folder"
        )
    try:
        lock.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DataFileError(
            f"cannot write {option} {target}: {exc.strerror or exc}; choose a writable path"
        ) from None
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            raise DataFileError(
                f"cannot write {option} {target}: {exc.strerror or exc}; choose a writable path"
            ) from None
        try:
            locked = _try_flock(fd, target, option)
            # the holder before us may have removed the file after we opened it: then our
            # lock is on a dead inode and another process may lock a new file — retry
            if locked and not _same_file(fd, lock):
                os.close(fd)
                continue
        except BaseException:
            os.close(fd)
            raise
        break
    try:
        yield
    finally:
        if locked:
            with contextlib.suppress(OSError):
                lock.unlink()  # while still holding it: see the retry above
        os.close(fd)


def _same_file(fd: int, path: Path) -> bool:
    try:
        a, b = os.fstat(fd), os.stat(path)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


@contextlib.contextmanager
def output_lock(
    path: str | os.PathLike[str], *, folder: bool = True, option: str = "--out"
) -> Iterator[Path]:
    """Hold an exclusive advisory lock on the output ``path`` while the block runs.

    Parameters
    ----------
    path : the output folder (``folder=True``: created if missing, then locked itself) or
        the output file (``folder=False``: locked through ``.NAME.lock`` beside it).
    option : how the caller names the path in the refusal (``--out``).

    Re-entrant within a process: a lock this process already holds is not taken again.

    Raises
    ------
    OutputLockedError : another process holds the lock (nothing is written).
    DataFileError : the folder cannot be created or opened.
    """
    target = Path(path)
    key = (str(target.resolve()), folder)
    if key in _mine:  # this process holds it already (a command and the library it calls)
        yield target
        return
    with _folder_lock(target, option) if folder else _file_lock(target, option):
        _mine.add(key)
        try:
            yield target
        finally:
            _mine.discard(key)


_mine: set[tuple[str, bool]] = set()
"""The locks this process holds: taking one again is a no-op (re-entrant per process)."""


_held = contextlib.ExitStack()


def _command_context() -> object | None:
    """The running click command's context (typer runs on click), or None."""
    import importlib

    for module in ("typer._click.globals", "click"):  # recent typer vendors click
        try:
            get = importlib.import_module(module).get_current_context
        except (ImportError, AttributeError):
            continue
        context = get(silent=True)
        if context is not None:
            return context
    return None


def hold_output_lock(
    path: str | os.PathLike[str], *, folder: bool = True, option: str = "--out"
) -> Path:
    """Take :func:`output_lock` for the rest of the current command: released when the
    command's click context closes, or by :func:`release_held_locks` outside a command."""
    lock = output_lock(path, folder=folder, option=option)
    context = _command_context()
    if context is not None:
        return context.with_resource(lock)  # type: ignore[attr-defined]
    return _held.enter_context(lock)


def release_held_locks() -> None:
    """Release every lock taken with :func:`hold_output_lock` outside a command."""
    _held.close()
