"""What an everyday CLI call costs to start: CPU time of whole ``echocal`` processes.

Run from the repository root::

    python benchmarks/bench_start.py              # 3 repeats of each command
    python benchmarks/bench_start.py --repeats 5
    python benchmarks/bench_start.py --src /tmp/old/src   # another checkout's sources

Each command runs as a child process (``python -m echocal ...``, this checkout's sources
first on the path) in a temporary folder, after one untimed run that fills numba's
on-disk cache, so the numbers are those of a *second* call.  A child's CPU time is the
growth of ``resource.getrusage(RUSAGE_CHILDREN)`` (user + sys) across its run: it depends
much less on how busy the machine is than wall time.  The children may write bytecode
(``PYTHONDONTWRITEBYTECODE`` is removed from their environment), as an installed package
has: without ``.pyc`` files every call compiles echocal's hundred modules again.  The
reference row is ``python -c pass`` (the interpreter alone), measured in the same process;
the table gives the median CPU seconds and the ratio to that reference.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _common import markdown_table

ROOT = Path(__file__).resolve().parent.parent

COMMANDS: dict[str, list[str]] = {
    "python -c pass (reference)": ["-c", "pass"],
    "echocal info": ["-m", "echocal", "info"],
    "echocal simulate --setup immersion-5mhz": [
        "-m", "echocal", "simulate", "--setup", "immersion-5mhz", "--pose", "0,0,50",
        "--overwrite",
    ],
    "echocal calibrate --setup immersion-5mhz --no-plots": [
        "-m", "echocal", "calibrate", "--setup", "immersion-5mhz", "--no-plots",
        "--overwrite",
    ],
}  # fmt: skip


def child_cpu(args: list[str], cwd: str, src: Path) -> float:
    """[s] user + sys CPU time of one ``python ARGS`` child run in ``cwd``, ``src`` first
    on its path."""
    env = dict(os.environ, PYTHONPATH=str(src))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, *args], cwd=cwd, env=env, check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per command")
    parser.add_argument(
        "--src",
        type=Path,
        default=ROOT / "src",
        help="echocal sources to time (default: this checkout's)",
    )
    opts = parser.parse_args(argv)
    rows = []
    reference = None
    with tempfile.TemporaryDirectory() as cwd:
        for name, args in COMMANDS.items():
            child_cpu(args, cwd, opts.src)  # warm-up: fills the numba cache and the OS file cache
            cpu = statistics.median(
                child_cpu(args, cwd, opts.src) for _ in range(max(1, opts.repeats))
            )
            reference = cpu if reference is None else reference
            rows.append((name, f"{cpu:.2f}", f"{cpu / reference:.1f}"))
    print(markdown_table(("command (second call)", "CPU [s]", "× python -c pass"), rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
