"""A process that used the wave model's thread pool can fork, and its children simulate.

A child forked (``multiprocessing``'s default start method on Linux) after the parent
used the pool inherits the pool object but none of its threads: without the fork hook in
:mod:`echocal.wave.threads` the child's first A-scan waited forever on work no thread
takes.  Here the parent simulates on the pool, forks, and the child simulates the same
pose again; the child's A-scan must equal the parent's bit for bit (the threads' grids
are summed in a fixed order).
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import sys

import numpy as np
import pytest

from echocal.geometry import tilt_frame
from echocal.setups import load_setup
from echocal.wave import threads

JOIN_TIMEOUT = 600.0
"""[s] how long the parent waits for the child: about 1 s of work, so only a hang (which
never ends) exceeds it, however loaded the machine."""


def _scan() -> np.ndarray:
    """One noiseless wave-model A-scan of the 12.7 mm 5 MHz probe tilted 6° over the plate:
    several hundred face nodes, which the image form splits over the pool when the test
    lowers the nodes per thread (the exact form: the plane's table would read its nodes
    from the disk cache that an earlier test filled, and use no pool)."""
    setup = load_setup("immersion-5mhz")
    setup.__dict__["wave_model"] = dataclasses.replace(setup.wave_model, tables=False)
    frame = tilt_frame(np.array([6.0]), np.array([2.0]))
    return setup.ideal_samples(np.asarray(setup.reference_position)[None, :], frame)[0]


def _child(queue: multiprocessing.Queue) -> None:  # type: ignore[type-arg]
    queue.put(_scan())


@pytest.mark.skipif(sys.platform != "linux", reason="the fork start method (Linux)")
def test_a_child_forked_after_the_pool_was_used_simulates(monkeypatch) -> None:
    monkeypatch.setattr(threads, "cores", lambda: 2)  # the pool even on a one-core runner
    monkeypatch.setattr(threads, "MIN_NODES_PER_THREAD", 64)  # and for this pose's nodes
    threads.pool.cache_clear()
    parent = _scan()
    assert threads.pool.cache_info().currsize >= 1, "the parent's A-scan did not use the pool"
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_child, args=(queue,))
    child.start()
    try:
        got = queue.get(timeout=JOIN_TIMEOUT)
    except Exception:  # queue.Empty: the child never answered
        child.kill()
        child.join()
        pytest.fail(
            f"the forked child did not finish one A-scan in {JOIN_TIMEOUT:g} s (about 1 s of "
            "work): it hangs on the thread pool it inherited"
        )
    child.join(JOIN_TIMEOUT)
    assert child.exitcode == 0
    np.testing.assert_array_equal(got, parent)
    assert np.max(np.abs(parent)) > 0.0
