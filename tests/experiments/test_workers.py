"""The sweep's worker pool stops at once when interrupted, and the process can then end
(:mod:`echocal.experiments._workers`).

Regression (CI, session 10): an interrupted ``sweep run`` printed "aborted" and never
exited.  A worker terminated while it was sending its result left half a message in the
result pipe; the pool's manager thread waited for the rest forever, and the interpreter
joins that thread at exit.  Large results make the window wide: each worker here is
killed in the middle of sending 50 MB.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

SCRIPT = textwrap.dedent(
    """
    import time
    from echocal.experiments._workers import stop_workers, worker_pool

    def large(i):
        return bytes(50_000_000)

    if __name__ == "__main__":
        pool = worker_pool(2)
        for i in range(200):  # no future kept: each 50 MB result is dropped once read
            pool.submit(large, i)
        time.sleep(0.5)  # the workers are sending results; the parent is reading them
        stop_workers(pool, interrupted=True)
        print("stopped", flush=True)
    """
)


@pytest.mark.skipif(sys.platform == "win32", reason="fork start method")
def test_a_pool_stopped_while_workers_send_results_lets_the_process_end(tmp_path):
    script = tmp_path / "stop_mid_result.py"
    script.write_text(SCRIPT)
    try:
        done = subprocess.run(
            [sys.executable, str(script)], capture_output=True, text=True, timeout=600
        )  # a hang never ends; the script takes about a second (generous on a loaded machine)
    except subprocess.TimeoutExpired:
        pytest.fail("the process hung at exit after its worker pool was stopped (600 s)")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "stopped"
