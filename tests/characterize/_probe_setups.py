"""Small setup files for the characterization tests (ray model, cheap A-scans)."""

from __future__ import annotations

from pathlib import Path

FLAT = """
name = "flat-probe-test"
seed = 0
[medium]
sound_speed = "1480 m/s"
[specimen]
builtin = "flat-plate"
[transducer]
width = "12.7 mm"
aperture = "circular"
n_h = 16
pinhole_distance = "1 m"
[transducer.directivity]
model = "piston"
[pulse]
name = "gabor"
center_frequency = "5 MHz"
bandwidth = 60
[window]
fs = "50 MHz"
start = "60 us"
n_samples = 512
[noise]
snr_db = 30
[echo]
reflection = "lambertian"
[positioner]
reference_position = ["0 mm", "0 mm", "50 mm"]
"""

SQUINT = (0.5, -0.3)  # [deg] the probe's squint in the bench tests

BENCH = f"""
[bench.probe]
squint = [{SQUINT[0]}, {SQUINT[1]}]
pivot_offset = [0, 0, "-30 mm"]
"""


def write_setup(folder: Path, text: str, name: str = "probe.toml") -> Path:
    """Write ``text`` as a setup file in ``folder`` and return its path."""
    path = folder / name
    path.write_text(text)
    return path
