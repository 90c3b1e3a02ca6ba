"""Local worker processes that die with their parent (private).

``sweep run`` computes runs in a :class:`~concurrent.futures.ProcessPoolExecutor`.  Killed
with SIGKILL, the parent cannot stop its workers, and they would go on computing runs no
one stores.  Each worker therefore asks Linux to send it SIGKILL when its parent dies
(``prctl(PR_SET_PDEATHSIG)``, through ctypes), and elsewhere watches its parent from a
thread.  Workers ignore SIGINT and take the default SIGTERM: the parent decides — on
Ctrl-C, SIGTERM or SIGHUP it keeps the finished runs and terminates the workers
(:func:`stop_workers`).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["die_with_parent", "stop_workers", "worker_pool"]

_PR_SET_PDEATHSIG = 1
_WATCH_INTERVAL = 0.5
"""[s] how often a worker without prctl checks that its parent lives."""


def _set_pdeathsig() -> bool:
    """Ask the kernel for SIGKILL when the parent dies (Linux); False where unavailable."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):  # pragma: no cover - no libc prctl
        return False


def _watch_parent(parent: int) -> None:  # pragma: no cover - only without prctl
    while os.getppid() == parent:
        time.sleep(_WATCH_INTERVAL)
    os._exit(1)


def die_with_parent(parent: int) -> None:
    """Worker initializer: end this process when process ``parent`` ends.

    Signals: SIGINT ignored (the parent handles Ctrl-C), SIGTERM and SIGHUP at their
    default (end the worker), whatever handlers were inherited by fork.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
    if not _set_pdeathsig():  # pragma: no cover - not Linux
        threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """A process pool whose workers die with this process (:func:`die_with_parent`)."""
    return ProcessPoolExecutor(
        max_workers=workers, initializer=die_with_parent, initargs=(os.getpid(),)
    )


def stop_workers(pool: ProcessPoolExecutor, *, interrupted: bool) -> None:
    """Shut ``pool`` down: wait for the runs in flight, or, ``interrupted`` (Ctrl-C, a
    termination signal, an error), cancel the queue and terminate the workers at once."""
    if not interrupted:
        pool.shutdown(wait=True, cancel_futures=True)
        return
    processes = list(getattr(pool, "_processes", {}).values())  # no public API before 3.14
    results = getattr(pool, "_result_queue", None)  # shutdown() forgets it
    manager = getattr(pool, "_executor_manager_thread", None)  # and this
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        with contextlib.suppress(OSError, ValueError):
            process.terminate()
    for process in processes:
        with contextlib.suppress(OSError, ValueError, AssertionError):
            process.join(timeout=5)
    _unblock_result_reader(results)
    # let the pool's manager thread end (and close its wake-up pipe) now: at exit,
    # concurrent.futures wakes every manager thread still alive, and one closing its pipe
    # meanwhile made that wake-up print "Exception ignored ... Bad file descriptor"
    if isinstance(manager, threading.Thread) and manager is not threading.current_thread():
        manager.join(timeout=5)


def _unblock_result_reader(results: object) -> None:
    """End the pool's manager thread's read of a result a terminated worker left half written.

    A worker killed in the middle of sending its result leaves a partial message in the
    result pipe; the pool's manager thread then waits in ``recv()`` for bytes that never
    come, and the interpreter, which joins that thread at exit, never ends (seen once in
    CI: an interrupted ``sweep run`` printed "aborted" and hung).  With every worker gone,
    this process holds the pipe's last write end: closing it turns the wait into
    end-of-file, which the manager handles as a broken pool and ends.
    """
    writer = getattr(results, "_writer", None)
    if writer is not None:
        with contextlib.suppress(OSError):
            writer.close()
