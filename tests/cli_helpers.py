"""Running the ``echocal`` entry point in-process, as a user's shell would (shared by tests)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import echocal.cli


def run_main(
    args: list[str], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> tuple[int, str, str]:
    """Run the ``echocal`` entry point; return (exit code, stdout, stderr)."""
    monkeypatch.setattr(sys, "argv", ["echocal", *args])
    with pytest.raises(SystemExit) as exit_info:
        echocal.cli.main()
    out, err = capsys.readouterr()
    code = exit_info.value.code
    return (0 if code is None else int(code)), out, err


def flat(text: str) -> str:
    """``text`` with every run of whitespace (console line wrapping) made one space."""
    return " ".join(text.split())


TINY_PLATE = 'builtin = "flat-plate"'
"""The ``[specimen]`` body of :func:`tiny_setup_toml`'s default: a flat plate at z = 0."""


def tiny_setup_toml(specimen: str = TINY_PLATE, ref_z: str = "16 mm", z_min: str = "10 mm") -> str:
    """A tiny, fast setup file's text: 8 x 8 rays, 256 samples; the window [20, 25.1] us holds
    the plate's echo from z = 16 mm (21.6 us) but not from 40 mm (54 us)."""
    return f"""
name = "tiny"
seed = 4
[specimen]
{specimen}
[transducer]
width = "6 mm"
n_h = 8
pinhole_distance = "50 mm"
[pulse]
name = "gabor"
center_frequency = "5 MHz"
[window]
fs = "50 MHz"
start = "20 us"
n_samples = 256
[positioner]
reference_position = ["0 mm", "0 mm", "{ref_z}"]
z = ["{z_min}", "40 mm"]
coelevation = [-30, 30]
"""


TILTED_PLATE = """
[[specimen.shapes]]
kind = "plane"
center = [0, 0, 0]
width = "40 mm"
height = "40 mm"
azimuth = 30
coelevation = 4
"""
"""The ``[specimen]`` body of a 40 mm plate whose normal is azimuth 30°, co-elevation 4°."""


SPHERE_UNDER_REFERENCE = (
    '[[specimen.shapes]]\nkind = "sphere"\ncenter = [0, 0, "-20 mm"]\nradius = "30 mm"'
)
"""A sphere whose top is at z = 10 mm: the reference (26 mm) is 16 mm above it; z = 5 mm is
inside it."""


def tiny_setup_file(tmp_path: Path, specimen: str = TINY_PLATE, ref_z: str = "16 mm") -> Path:
    """:func:`tiny_setup_toml` (positioner z down to 0 mm) written to ``tmp_path/tiny.toml``."""
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml(specimen, ref_z, z_min="0 mm"), encoding="utf-8")
    return path
