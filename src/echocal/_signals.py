"""Termination signals end a command the way Ctrl-C does (private).

A long command (a calibration on a rig, a recording, a scan, a sweep) already keeps what it
measured when Ctrl-C raises :class:`KeyboardInterrupt`.  SIGTERM (``kill``, a batch system,
systemd) and SIGHUP (a closed terminal or SSH session) would otherwise end the process at
once and lose it.  :func:`terminate_like_ctrl_c` makes them raise :class:`Terminated`, a
``KeyboardInterrupt``, so the same cleanup runs; the command then exits with the shell's
code for that signal (128 + its number: 130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP).

It also ignores SIGXFSZ, so writing past a file-size limit (``ulimit -f``) is an
``OSError`` (EFBIG) naming the file, not a killed process.

A signal never interrupts an import: one that arrives while a module is being imported
(numba's first kernel imports numba, a second or more, often during the first measurement
on a rig) is delivered again :data:`IMPORT_RETRY` later, once the import is over.  An
exception raised inside an import leaves the module half-imported, and the cleanup that
saves the measurements would then fail on it (``module 'numba' has no attribute 'core'``).
The same holds for Ctrl-C (SIGINT) while the context is active.

A signal whose exception is lost (Python ignores an exception raised inside a finalizer or a
weak-reference callback, where a handler can land when the garbage collector runs) still
stops the command: :func:`checkpoint`, called before every measurement on a rig (in
:meth:`echocal.measurement.HardwareSource.measure`, which every command's rig measurement
passes), raises it again.

Nor does a signal interrupt the saving of what was measured: inside :func:`saving` (a
partial recording's chunk being written) it is held, then raised the moment the section
ends, so a chunk is either written whole or not started.  Inside :func:`measuring` (one
measurement on a rig and the saving of its A-scan) the first signal is held the same way,
so the A-scan the rig is delivering is kept and never taken twice; a second signal stops
at once (a rig that hangs still stops on a second Ctrl-C).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType

__all__ = [
    "INTERRUPTED",
    "TERMINATION_SIGNALS",
    "Terminated",
    "checkpoint",
    "exit_code",
    "how",
    "measuring",
    "saving",
    "terminate_like_ctrl_c",
]

TERMINATION_SIGNALS: tuple[signal.Signals, ...] = tuple(
    getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)
)
"""The signals turned into :class:`Terminated` (those the platform has)."""

IMPORT_RETRY = 0.05
"""[s] delay after which a signal that arrived during an import is delivered again."""

INTERRUPTED = 128 + int(signal.SIGINT)
"""130: the exit code of a command stopped by Ctrl-C (and what typer returns for any
``KeyboardInterrupt``)."""


class Terminated(KeyboardInterrupt):
    """A termination signal arrived: handled exactly as Ctrl-C (``KeyboardInterrupt``)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = int(signum)

    def __str__(self) -> str:
        return f"terminated by {signal.Signals(self.signum).name}"


def _interrupt(exc: BaseException | None) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt behind ``exc`` (itself, or the cause of click's ``Abort``)."""
    seen = 0
    while exc is not None and seen < 8:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


def exit_code(exc: BaseException | None = None) -> int:
    """The shell's exit code for the interruption behind ``exc``: 128 + the signal number
    (130 for Ctrl-C / SIGINT, 143 for SIGTERM, 129 for SIGHUP)."""
    found = _interrupt(exc)
    signum = found.signum if isinstance(found, Terminated) else int(signal.SIGINT)
    return 128 + signum


def how(exc: BaseException | None = None) -> str:
    """``"interrupted (Ctrl-C)"`` or ``"terminated by SIGTERM"``: what stopped a run."""
    found = _interrupt(exc)
    return str(found) if isinstance(found, Terminated) else "interrupted (Ctrl-C)"


def importing(frame: FrameType | None) -> bool:
    """Whether ``frame`` or a frame calling it runs Python's import machinery (a module is
    being imported)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib._bootstrap"):
            return True
        frame = frame.f_back
    return False


def _deliver_later(signum: int) -> None:
    """Send ``signum`` to this process again after :data:`IMPORT_RETRY`."""
    timer = threading.Timer(IMPORT_RETRY, os.kill, (os.getpid(), signum))
    timer.daemon = True
    timer.start()


_stopped: list[int] = []
"""The stop signal received while :func:`terminate_like_ctrl_c` is active (at most one)."""


def checkpoint() -> None:
    """Raise again the stop signal already received, if any (a point where stopping is safe:
    before a measurement).  Normally the signal's exception has ended the work long before;
    this catches one that Python swallowed (raised inside a finalizer or weakref callback)."""
    if _stopped:
        signum = _stopped[0]
        raise KeyboardInterrupt if signum == int(signal.SIGINT) else Terminated(signum)


_held: list[int] = []
"""Signals that arrived inside :func:`saving` or :func:`measuring`, raised again when the
outermost section ends (main thread)."""
_sections: list[str] = []
"""The open sections, outermost first: ``"saving"`` or ``"measuring"`` (handlers run in the
main thread only)."""

HELD_MESSAGE = (
    b"echocal: stopping after the measurement in progress (it is kept); "
    b"press Ctrl-C again to stop at once\n"
)
"""What stderr says when a signal waits for the measurement in progress."""


@contextlib.contextmanager
def _section(kind: str) -> Iterator[None]:
    """A section of ``kind`` in which :func:`_hold` keeps the signals of
    :func:`terminate_like_ctrl_c`; the one held is raised again as soon as the outermost
    section ends normally (if it ends by an exception, that exception stands)."""
    _sections.append(kind)
    try:
        yield
    finally:
        _sections.pop()
        held = [] if _sections else list(_held)
        if not _sections:
            _held.clear()
    if held and sys.exc_info()[1] is None:
        signal.raise_signal(held[0])  # its handler raises here, now that the data is safe


def saving() -> contextlib.AbstractContextManager[None]:
    """A section that no signal of :func:`terminate_like_ctrl_c` interrupts (writing what
    was measured): a signal that arrives meanwhile is raised again as soon as the section
    ends normally (if it ends by an exception, that exception stands)."""
    return _section("saving")


def measuring() -> contextlib.AbstractContextManager[None]:
    """A section for one measurement on a rig and the saving of its A-scan: the first
    signal of :func:`terminate_like_ctrl_c` waits for its end, as in :func:`saving` (the
    A-scan being delivered is kept, never measured twice); a second one, outside any
    :func:`saving` section, is raised at once (a hung instrument still stops)."""
    return _section("measuring")


def _hold(signum: int) -> bool:
    """Keep ``signum`` for the end of the open section; False when none is open, or when a
    signal already waits for a measurement (a second Ctrl-C stops at once)."""
    if not _sections:
        return False
    if _held:
        return "saving" in _sections  # a second signal: held only while data is written
    _held.append(signum)
    if "saving" not in _sections:
        with contextlib.suppress(OSError):
            os.write(2, HELD_MESSAGE)  # async-signal-safe, unlike print()
    return True


@contextlib.contextmanager
def terminate_like_ctrl_c() -> Iterator[list[int]]:
    """While active, SIGTERM and SIGHUP raise :class:`Terminated` in the main thread and
    SIGXFSZ is ignored; the previous handlers are restored on exit.

    Yields the list of termination signals received (empty, or the one that stopped the
    command: a caller that only sees an exit code, typer's 130 for any interrupt, learns
    which signal it was).  The first termination signal raises; further ones while the
    command cleans up (saving what it measured) are ignored — SIGKILL still ends the
    process.  Ctrl-C (SIGINT) raises :class:`KeyboardInterrupt` as usual.  No signal
    raises inside an import: it is delivered again once the import is over.  Outside the
    main thread (where Python cannot set handlers) this does nothing.
    """
    fired: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield fired
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        if fired:
            return  # already stopping: let the cleanup finish
        if _hold(signum):
            return  # raised when the measurements are saved
        if importing(frame):
            _deliver_later(signum)  # never leave a module half-imported
            return
        fired.append(signum)
        _stopped.append(signum)
        raise Terminated(signum)

    def interrupt(signum: int, frame: FrameType | None) -> None:
        if _hold(signum):
            return
        if importing(frame):
            _deliver_later(signum)
            return
        if not _stopped:
            _stopped.append(signum)
        raise KeyboardInterrupt

    previous = {sig: signal.signal(sig, handler) for sig in TERMINATION_SIGNALS}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, interrupt)
    if hasattr(signal, "SIGXFSZ"):
        previous[signal.SIGXFSZ] = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    _stopped.clear()
    try:
        yield fired
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
        _stopped.clear()
