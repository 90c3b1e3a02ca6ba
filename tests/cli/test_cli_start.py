"""The command line starts light: `echocal --help` and `echocal info` import no physics, and
the simulator alone imports no calibration, scipy.signal, scipy.stats or scipy.optimize.

A module-level import of the measurement package from a CLI module once made every
command start by importing scipy.signal and the calibration methods (3.1 CPU-s instead of
0.8 for `echocal info`); the measurement package's eager ``__init__`` made the simulator
import the calibration methods, and module-level scipy imports made it import
scipy.signal, scipy.stats and scipy.optimize (`echocal simulate` 3.9 -> 3.0 CPU-s), and
`echocal lobe`'s module-level import of the echo models made every command import
scipy.special (`echocal info` 0.69 -> 0.44 CPU-s with the above; benchmarks/bench_start.py).
These tests guard the laziness, not a time.
"""

from __future__ import annotations

import subprocess
import sys

HEAVY = (
    "echocal.measurement",
    "echocal.calibrate",
    "echocal.wave",
    "echocal.echo",
    "scipy.signal",
    "scipy.special",
    "numba",
)

NOT_FOR_SIMULATING = (
    "echocal.calibrate",
    "echocal.measurement.objective",
    "echocal.measurement.hardware",
    "echocal.measurement.recording",
    "scipy.signal",
    "scipy.stats",
    "scipy.optimize",
    "scipy.ndimage",
)


def _imported(statement: str, names: tuple[str, ...]) -> str:
    """The modules among ``names`` that ``statement`` imports, comma-separated."""
    code = f"import sys; {statement}; print(','.join(m for m in {names!r} if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return done.stdout.strip()


def test_importing_the_cli_imports_no_physics():
    imported = _imported("import echocal.cli", HEAVY)
    assert imported == "", f"imported at CLI start: {imported}"


def test_loading_a_setup_and_simulating_imports_no_calibration_and_no_heavy_scipy():
    # what `echocal simulate --setup immersion-5mhz` does before it plots
    statement = (
        "from echocal import load_setup; from echocal.geometry import Pose; "
        "s = load_setup('immersion-5mhz', seed=0); s.measure(Pose(0, 0, 0.05, 0, 0))"
    )
    imported = _imported(statement, NOT_FOR_SIMULATING)
    assert imported == "", f"imported to simulate one A-scan: {imported}"


def test_the_measurement_package_still_offers_every_name():
    import echocal.measurement as m

    for name in m.__all__:
        assert getattr(m, name) is not None
    assert m.HardwareReceiver.__name__ == "Receiver"
    assert set(m.__all__) <= set(dir(m))
