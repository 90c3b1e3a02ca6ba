"""Wall thickness from the front-to-back time of flight: synthetic echo pairs with known
times, the simulated steel plate, and the thickness map of ``echocal scan``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from cli_helpers import flat, run_main
from echocal.cli import app
from echocal.errors import EchocalValueError
from echocal.geometry import tilt_frame
from echocal.scanning import SurfaceScan
from echocal.setups import load_setup
from echocal.signal import RecordingWindow
from echocal.signal.gates import resolve_gate
from echocal.signal.pulses import GaborPulse
from echocal.signal.thickness import echo_times, wall_thickness

C_L = 5900.0  # [m/s] steel, the value


@pytest.fixture(scope="module")
def plate():
    return load_setup("immersion-steel-plate")


def _pair(t_front: float, t_back: float, back: float = 0.1) -> tuple[np.ndarray, RecordingWindow]:
    """Two Gabor echoes (amplitudes 1 and ``back``, the second inverted as a water–steel–
    water back wall is not: the sign must not matter) on a 100 MHz window."""
    pulse = GaborPulse(center_frequency=5e6, bandwidth=50.0)
    window = RecordingWindow(fs=100e6, start=60e-6, n_samples=4096)
    t = window.times
    x = pulse.waveform(t - t_front) - back * pulse.waveform(t - t_back)
    return x, window


@pytest.mark.parametrize("thickness", [3e-3, 10e-3, 20e-3, 50e-3])
def test_thickness_of_two_echoes_at_known_times(thickness):
    # independent truth: the echoes are placed 2T/c_L apart by construction; the matched
    # peak is interpolated to well below a sample (10 ns = 30 µm of steel), tolerance 1 µm
    pulse = GaborPulse(center_frequency=5e6, bandwidth=50.0)
    t_front = 67.3456e-6
    x, window = _pair(t_front, t_front + 2 * thickness / C_L)
    got = wall_thickness(x, window, pulse, C_L)
    assert float(got) == pytest.approx(thickness, abs=1e-6)


def test_echo_times_find_the_front_and_back_echo_batched():
    pulse = GaborPulse(center_frequency=5e6, bandwidth=50.0)
    rows = [_pair(65e-6 + k * 1e-6, 72e-6 + k * 1.1e-6) for k in range(3)]
    x = np.stack([r[0] for r in rows])
    front, back = echo_times(x, rows[0][1], pulse)
    assert front.shape == back.shape == (3,)
    np.testing.assert_allclose(front, 65e-6 + np.arange(3) * 1e-6, atol=1e-10)
    np.testing.assert_allclose(back, 72e-6 + np.arange(3) * 1.1e-6, atol=1e-10)
    assert np.all(np.isnan(wall_thickness(np.zeros((2, 4096)), rows[0][1], pulse, C_L)))


@pytest.mark.parametrize("water_path", [0.045, 0.050, 0.055])
def test_the_simulated_plate_reads_its_thickness(plate, water_path):
    # the simulated plate is 20 mm of steel (c_L 5900 m/s) under water paths of 45–55 mm;
    # the back-wall echo passes through diffraction at a 4× longer equivalent path and
    # steel's attenuation, which move its matched peak by a few ns: tolerance 0.15 %
    position = np.array([0.0, 0.0, water_path])
    x = plate.ideal_samples(position[None], tilt_frame(np.array([0.0]), np.array([0.0])))
    assert plate.thickness == pytest.approx(0.02)
    c_l = plate.material.longitudinal_speed
    free = float(wall_thickness(x, plate.window, plate.pulse, c_l)[0])
    gate = resolve_gate(
        "back-wall", pulse=plate.pulse, thickness=plate.thickness, material=plate.material
    )
    gated = float(wall_thickness(x, plate.window, plate.pulse, c_l, gate)[0])
    assert free == pytest.approx(0.02, rel=1.5e-3)
    assert gated == pytest.approx(free, rel=1e-9)  # the strongest echo after the front wall


def test_bad_speed_is_refused_naming_it(plate):
    x, window = _pair(65e-6, 72e-6)
    for bad in (0.0, -5900.0, float("nan"), True):
        with pytest.raises(EchocalValueError, match="longitudinal_speed"):
            wall_thickness(x, window, plate.pulse, bad)


def test_scan_maps_the_plates_thickness(tmp_path):
    out = tmp_path / "scan"
    result = CliRunner().invoke(
        app,
        [
            "scan", "--setup", "immersion-steel-plate", "--grid", "-3:3:6,0:0:1",
            "--z", "50", "--out", str(out), "--no-progress", "--json",
        ],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout.strip().splitlines()[-1])["scan"]
    assert summary["found"] == 2
    assert summary["true_thickness_m"] == pytest.approx(0.02)
    # 30 dB noise on the back-wall echo (20 dB under the front wall): ≤ 0.05 mm
    assert summary["thickness_error_abs_m"]["max"] < 5e-5
    scan = SurfaceScan.load(out / "scan.nc")
    wall = scan.dataset["thickness"]
    assert wall.attrs["units"] == "m" and "thickness" in wall.attrs["long_name"]
    np.testing.assert_allclose(wall.values, 0.02, atol=5e-5)
    assert (out / "thickness.png").stat().st_size > 0


def test_the_simulated_pipe_reads_its_wall():
    """The 8-inch pipe (8.2 mm wall: a curved front face and back wall) at its top under
    water paths of 45–55 mm: the wall from the front-to-back time of flight of its
    noiseless A-scans within 0.05 mm (measured 0.010–0.024 mm:
    the back wall's diffraction through the curved face moves its matched peak), the back
    echo found after the front wall and inside the back-wall gate alike."""
    pipe = load_setup("immersion-steel-pipe")
    positions = np.array([[0.0, 0.0, z] for z in (0.045, 0.050, 0.055)])
    frames = tilt_frame(np.zeros(3), np.zeros(3))
    x = pipe.ideal_samples(positions, frames)
    c_l = pipe.material.longitudinal_speed
    free = wall_thickness(x, pipe.window, pipe.pulse, c_l)
    gate = resolve_gate(
        "back-wall", pulse=pipe.pulse, thickness=pipe.thickness, material=pipe.material
    )
    gated = wall_thickness(x, pipe.window, pipe.pulse, c_l, gate)
    assert pipe.thickness == pytest.approx(0.0082)
    np.testing.assert_allclose(free, 0.0082, atol=5e-5)
    np.testing.assert_allclose(gated, free, rtol=1e-9)


@pytest.mark.slow
def test_scan_maps_a_pipes_wall(tmp_path):
    """The 8-inch pipe (8.2 mm wall) at its top: the wall from the front-to-back time of
    flight of one noisy A-scan within 0.1 mm.  The noiseless reading is off by 0.016 mm
    (0.007–0.026 mm over −10…10 mm across the pipe: the back wall's diffraction through
    the curved face), and 30 dB noise moves one reading by σ = 0.016 mm (4,000 noise
    draws at this pose: 99 % within 0.053 mm, 99.9 % within 0.061 mm): the bias plus 5σ
    is 0.1 mm.  A wrong speed (shear for longitudinal) or the second back echo taken for
    the first is off by millimetres.

    Slow tier (about 20 CPU-s: 28 curved-wall A-scans): it joins two fast checks, the
    plate's thickness map through ``echocal scan`` above and the pipe's wall from its
    A-scans (``test_the_simulated_pipe_reads_its_wall``)."""
    out = tmp_path / "scan"
    result = CliRunner().invoke(
        app,
        [
            "scan", "--setup", "immersion-steel-pipe", "--grid", "0:0:1,0:0:1",
            "--z", "50", "--out", str(out), "--no-progress", "--json",
        ],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout.strip().splitlines()[-1])["scan"]
    assert summary["found"] == 1
    assert summary["true_thickness_m"] == pytest.approx(0.0082)
    assert summary["thickness_error_abs_m"]["max"] < 1e-4


def test_scan_refuses_a_bad_longitudinal_speed(tmp_path, capsys, monkeypatch):
    code, _out, err = run_main(
        [
            "scan", "--setup", "immersion-steel-plate", "--grid", "-3:3:6,0:0:1",
            "--z", "50", "--out", str(tmp_path / "s"), "--no-progress",
            "--longitudinal-speed", "-5900",
        ],
        capsys,
        monkeypatch,
    )  # fmt: skip
    assert code != 0
    assert "--longitudinal-speed must be > 0" in flat(err)
    assert "Traceback" not in err
    assert not (tmp_path / "s" / "scan.nc").exists()
