"""What the numba kernels buy: CPU time per A-scan with and without them.

Run from the repository root::

    python benchmarks/bench_numba.py              # immersion-5mhz (wave) and thesis (ray)
    python benchmarks/bench_numba.py --count 3    # fewer A-scans per case

Each case runs in a fresh child process (the kernels are chosen when echocal's modules
are imported): once with the compiled kernels, once with ``echocal._numba.USE_NUMBA``
set False before anything else is imported, which is what an install without numba runs.
A child measures ``--count`` A-scans at the setup's reference position (tilts 0, 0.2,
0.4, ... deg of co-elevation) after one untimed A-scan that loads the kernels, and
reports its CPU time per A-scan (``time.process_time``).  The ratio of the two is
printed per setup; the two children of a setup run back to back.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

CHILD = """
import sys, time
import echocal._numba as nb
nb.USE_NUMBA = sys.argv[1] == "numba"
from echocal import load_setup
from echocal.geometry import Pose
setup = load_setup(sys.argv[2], seed=0)
x, y, z = (float(v) for v in setup.reference_position)
setup.measure(Pose(x, y, z, 0.0, 0.0))
n = int(sys.argv[3])
t = time.process_time()
for i in range(n):
    setup.measure(Pose(x, y, z, 0.0, 0.2 * i))
print((time.process_time() - t) / n)
"""


def per_ascan(engine: str, setup: str, count: int) -> float:
    """[s] CPU time per A-scan of ``setup`` in a child process with ``engine``."""
    out = subprocess.run(
        [sys.executable, "-c", CHILD, engine, setup, str(count)],
        check=True,
        capture_output=True,
        text=True,
    )
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=5, help="A-scans timed per case")
    parser.add_argument("--setups", default="immersion-5mhz,thesis")
    args = parser.parse_args()
    print("setup              numba [ms]  numpy [ms]  numpy / numba")
    for setup in args.setups.split(","):
        fast = per_ascan("numba", setup, args.count)
        slow = per_ascan("numpy", setup, args.count)
        print(f"{setup:18s} {fast * 1e3:10.2f}  {slow * 1e3:10.2f}  {slow / fast:13.1f}")


if __name__ == "__main__":
    main()
