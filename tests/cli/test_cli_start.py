"""The command line starts light: `echocal --help` and `echocal info` import no physics.

A module-level import of the measurement package from a CLI module once made every
command start by importing scipy.signal and the calibration methods (3.1 CPU-s instead of
0.8 for `echocal info`); this guards the laziness, not a time.
"""

from __future__ import annotations

import subprocess
import sys

HEAVY = ("echocal.measurement", "echocal.calibrate", "echocal.wave", "scipy.signal", "numba")


def test_importing_the_cli_imports_no_physics():
    code = f"import sys, echocal.cli; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "", f"imported at CLI start: {done.stdout.strip()}"
