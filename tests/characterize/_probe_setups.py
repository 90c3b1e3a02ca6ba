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


WATER_LIKE = (
    'material = { name = "water-like", density = "1000 kg/m3", '
    'longitudinal_speed = "1480 m/s", shear_speed = "10 m/s" }'
)


def pore_setup(width: str = "2 mm", focus: str | None = None, start: str = "65 us") -> str:
    """A probe over a 0.6 mm pore 20 mm deep in a water-like solid (c_L and density of
    water: no front-wall echo, no refraction), so the pore is a point target in water; a
    narrowband (10 %) pulse so the beam is the centre frequency's; wave model."""
    focused = "" if focus is None else f'focus = "{focus}"\n'
    return f"""
name = "pore-probe-test"
seed = 0
[medium]
sound_speed = "1480 m/s"
[specimen]
builtin = "flat-plate"
{WATER_LIKE}
thickness = "40 mm"
back_wall_echoes = 0
[[specimen.flaws]]
name = "ball"
kind = "pore"
position = [0, 0, "-20 mm"]
diameter = "0.6 mm"
[transducer]
width = "{width}"
aperture = "circular"
n_h = 16
pinhole_distance = "1 m"
{focused}[pulse]
name = "gabor"
center_frequency = "5 MHz"
bandwidth = 10
[window]
fs = "50 MHz"
start = "{start}"
n_samples = 2048
[echo]
reflection = "wave"
[positioner]
reference_position = ["0 mm", "0 mm", "40 mm"]
"""


PORE_TOP = (0.0, 0.0, -0.0197)  # [m] the pore's top (centre 20 mm deep, radius 0.3 mm)
