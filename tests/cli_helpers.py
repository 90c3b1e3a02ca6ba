"""Running the ``echocal`` entry point in-process, as a user's shell would (shared by tests)."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

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


SIMULATED_LAB_MODULE = """
from echocal.geometry import Pose

SOURCE = None  # the test's simulator (any measurement source), set before the rig is built
SERVED = []  # the samples of every A-scan the pulser delivered, in order
BREAK_AT = None  # the pulser fails at this acquisition (1-based), when set
POSE = Pose(0.0, 0.0, 0.016)  # where the stage was last sent


class Stage:
    \"\"\"A lab's own stage over the simulator: remembers where it was sent.\"\"\"

    def __init__(self):
        self.limits = SOURCE.limits

    def move_to(self, pose):
        global POSE
        POSE = self.limits.check(pose)
        return POSE

    def position(self):
        return POSE

    def close(self):
        pass


class Pulser:
    \"\"\"A lab's own pulser-receiver: one simulated A-scan at the stage's pose; fails as an
    unplugged scope would at acquisition BREAK_AT.\"\"\"

    def acquire(self):
        if BREAK_AT is not None and len(SERVED) + 1 >= BREAK_AT:
            raise OSError("scope unplugged")
        scan = SOURCE.measure(POSE)
        SERVED.append(scan.samples.copy())
        return scan

    def close(self):
        pass
"""
"""A lab's own python classes (a ``Stage`` and a ``Pulser``) over a simulator in this process,
for the rig's python driver."""


def simulated_lab(folder: Path, name: str, setup: Path) -> tuple[ModuleType, Path]:
    """Write :data:`SIMULATED_LAB_MODULE` as ``folder/name.py``, put ``folder`` first on the
    import path (the caller takes it off again), import it, and write ``folder/rig.toml``: a
    python-driver rig of its ``Stage`` and ``Pulser`` over ``setup``.  Returns the module (set
    its ``SOURCE`` before building the rig) and the rig file."""
    (folder / f"{name}.py").write_text(SIMULATED_LAB_MODULE, encoding="utf-8")
    sys.path.insert(0, str(folder))
    module = importlib.import_module(name)
    rig = folder / "rig.toml"
    rig.write_text(
        f'[rig]\nsetup = "{setup.as_posix()}"\n'
        f'[rig.positioner]\ndriver = "python"\nclass = "{name}:Stage"\n'
        f'[rig.receiver]\ndriver = "python"\nclass = "{name}:Pulser"\n',
        encoding="utf-8",
    )
    return module, rig


def tcp_rig_file(path: Path, address: str, setup: str | Path | None = None, **rig: object) -> Path:
    """Write ``path``: a rig file whose positioner and receiver are the TCP instrument at
    ``address`` (``host:port``; a 30 s timeout: the first simulation in a process compiles
    its kernels), naming ``setup`` (a built-in name or a file) and any other ``[rig]`` keys
    (written as given). Returns ``path``."""
    lines = ["[rig]", 'name = "emulated"']
    if setup is not None:
        lines.append(f'setup = "{setup.as_posix() if isinstance(setup, Path) else setup}"')
    lines += [f"{key} = {value}" for key, value in rig.items()]
    for part in ("positioner", "receiver"):
        lines += [f"[rig.{part}]", 'driver = "tcp"', f'address = "{address}"', "timeout = 30"]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
