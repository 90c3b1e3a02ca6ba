"""Termination signals (``echocal._signals``): a signal never interrupts an import.

A signal raised inside an import leaves the module half-imported; numba's lazy import on
the first measurement of a rig run made the cleanup fail (``module 'numba' has no
attribute 'core'``) and lose the measurements.  Here a module sends the signal to its
own process in the middle of being imported: the import completes, then the signal
arrives as the same exception as before.
"""

from __future__ import annotations

import importlib
import signal
import sys
import time
from pathlib import Path

import pytest

from echocal._signals import Terminated, terminate_like_ctrl_c

SELF_SIGNALLING = """
import os, signal, time
os.kill(os.getpid(), signal.{name})
deadline = time.monotonic() + 0.2
while time.monotonic() < deadline:  # the handler runs here, inside the import
    pass
COMPLETE = True
"""


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")
@pytest.mark.parametrize(
    ("name", "expected"),
    [("SIGHUP", Terminated), ("SIGTERM", Terminated), ("SIGINT", KeyboardInterrupt)],
)
def test_a_signal_during_an_import_arrives_after_it(name, expected, tmp_path: Path, monkeypatch):
    module = f"echocal_test_self_signalling_{name.lower()}"
    (tmp_path / f"{module}.py").write_text(SELF_SIGNALLING.format(name=name), encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    # Ctrl-C is taken over only from Python's default handler (a pytest-xdist worker
    # ignores SIGINT): give the test process the default, as a command line has
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _raise_after_import(module, expected, name)
    finally:
        signal.signal(signal.SIGINT, previous)


def _raise_after_import(module: str, expected: type[BaseException], name: str) -> None:
    imported = None
    with pytest.raises(expected), terminate_like_ctrl_c() as fired:
        imported = importlib.import_module(module)
        time.sleep(5.0)  # the signal is delivered again 50 ms after the import: ends this
    assert imported is not None and imported.COMPLETE  # the import was not interrupted
    assert module in sys.modules and sys.modules[module].COMPLETE
    if expected is Terminated:
        assert fired == [getattr(signal, name)]
    del sys.modules[module]


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")
@pytest.mark.parametrize(
    ("name", "expected"),
    [("SIGHUP", Terminated), ("SIGTERM", Terminated), ("SIGINT", KeyboardInterrupt)],
)
def test_a_signal_while_saving_arrives_when_the_data_is_safe(name, expected) -> None:
    # a partial recording's chunk is written whole: the signal waits for the section's end
    import os

    from echocal._signals import saving

    written: list[int] = []
    # Python's default Ctrl-C handler, as a command line has (an xdist worker ignores it)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(expected), terminate_like_ctrl_c():
            with saving():
                os.kill(os.getpid(), getattr(signal, name))
                deadline = time.monotonic() + 0.2
                while time.monotonic() < deadline:  # the handler runs here: it must hold
                    pass
                written.append(1)
            written.append(2)  # never reached: the held signal is raised as the section ends
    finally:
        signal.signal(signal.SIGINT, previous)
    assert written == [1]


def test_saving_that_ends_by_an_exception_keeps_that_exception() -> None:
    import os

    from echocal._signals import saving

    with pytest.raises(OSError, match="disk full"), terminate_like_ctrl_c():
        with saving():
            os.kill(os.getpid(), signal.SIGTERM)
            deadline = time.monotonic() + 0.2
            while time.monotonic() < deadline:
                pass
            raise OSError("disk full")


class _SignalsWhenCollected:
    """An object whose finalizer receives the signal: Python ignores an exception raised
    there ("Exception ignored in ..."), as it did for a weakref callback on a rig run."""

    def __init__(self, signum: int) -> None:
        self.signum = signum

    def __del__(self) -> None:
        import os

        os.kill(os.getpid(), self.signum)
        deadline = time.monotonic() + 0.2
        while time.monotonic() < deadline:  # the handler runs here, inside the finalizer
            pass


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")
@pytest.mark.parametrize(
    ("name", "expected"),
    [("SIGHUP", Terminated), ("SIGTERM", Terminated), ("SIGINT", KeyboardInterrupt)],
)
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_signal_lost_in_a_finalizer_stops_the_work_at_the_next_checkpoint(name, expected) -> None:
    from echocal._signals import checkpoint

    measured: list[int] = []
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(expected), terminate_like_ctrl_c():
            for k in range(3):
                checkpoint()  # before each measurement
                measured.append(k)
                if k == 0:
                    obj = _SignalsWhenCollected(getattr(signal, name))
                    del obj  # the signal's exception is swallowed in __del__
    finally:
        signal.signal(signal.SIGINT, previous)
    assert measured == [0]  # the second measurement never started
    checkpoint()  # outside the context nothing is pending


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")
@pytest.mark.parametrize(
    ("name", "expected"),
    [("SIGHUP", Terminated), ("SIGTERM", Terminated), ("SIGINT", KeyboardInterrupt)],
)
def test_a_signal_during_a_measurement_waits_for_it_and_a_second_stops_at_once(
    name, expected
) -> None:
    import os

    from echocal._signals import measuring

    done: list[str] = []

    def wait_for_the_handler() -> None:
        deadline = time.monotonic() + 0.2
        while time.monotonic() < deadline:  # the handler runs here
            pass

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(expected), terminate_like_ctrl_c():
            with measuring():  # the first signal waits for the measurement's end
                os.kill(os.getpid(), getattr(signal, name))
                wait_for_the_handler()
                done.append("measured and saved")
            done.append("next measurement")  # never reached
        with pytest.raises(expected), terminate_like_ctrl_c():
            with measuring():  # a rig that hangs: the second signal stops at once
                os.kill(os.getpid(), getattr(signal, name))
                wait_for_the_handler()
                os.kill(os.getpid(), getattr(signal, name))
                wait_for_the_handler()
                done.append("never measured")
    finally:
        signal.signal(signal.SIGINT, previous)
    assert done == ["measured and saved"]
