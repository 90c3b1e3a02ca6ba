"""``--rig FILE`` on ``record``, ``scan`` and ``calibrate``, and ``echocal rig check``,
against the emulated rig (``InstrumentServer`` on loopback, in-process, backed by the tiny
8 x 8-ray setup of ``cli_helpers``) and against the shipped pyvisa-sim instruments.

What a rig measures is checked against the simulator itself: the same setup, seeded the
same way, measures the same A-scans (the emulator serves the simulator's own values, so a
recording through the rig equals one of the simulator, sample for sample).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cli_helpers import flat, run_main, tcp_rig_file, tiny_setup_toml
from echocal.geometry import Pose
from echocal.measurement import Faults, InstrumentServer
from echocal.setups import load_setup

pytest.importorskip("pyvisa_sim")


@pytest.fixture
def setup_file(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml(), encoding="utf-8")
    return path


@pytest.fixture
def emulator(setup_file: Path):
    """(rig file text, server): a TCP rig file for an emulator of the tiny setup."""
    start = Pose(0.0, 0.0, 0.016)  # the setup's reference position
    with InstrumentServer(load_setup(setup_file), initial_pose=start) as server:
        host, port = server.address
        yield server, f"{host}:{port}"


def _tcp_rig(tmp_path: Path, address: str, setup: Path | None, **extra: str) -> Path:
    return tcp_rig_file(tmp_path / "rig.toml", address, setup, **extra)


def test_rig_check_prints_identity_limits_and_one_ascan(
    emulator, setup_file, tmp_path, capsys, monkeypatch
):
    server, address = emulator
    rig = _tcp_rig(tmp_path, address, setup_file)
    code, out, err = run_main(["rig", "check", str(rig)], capsys, monkeypatch)
    assert code == 0, err
    text = flat(out)
    assert "echocal,instrument-server" in text
    assert "z [10, 40] mm" in text and "coelevation [-30, 30] deg" in text
    assert "256 samples at 50 MHz from 20 us" in text
    assert server.n_acquisitions == 1
    code, out, _ = run_main(["rig", "check", str(rig), "--json"], capsys, monkeypatch)
    report = json.loads(out)
    assert report["limits"]["z"] == [0.01, 0.04]
    assert report["ascan"]["n_samples"] == 256 and report["ascan"]["finite"]


def test_record_on_a_rig_equals_the_simulator_sample_for_sample(
    emulator, setup_file, tmp_path, capsys, monkeypatch
):
    _, address = emulator
    rig = _tcp_rig(tmp_path, address, setup_file)
    grid = ["--azimuth", "0", "--coelevation", "-4:4:3", "--position", "0,0,16"]
    on_rig, on_sim = tmp_path / "rig.nc", tmp_path / "sim.nc"
    code, _, err = run_main(
        ["record", "--rig", str(rig), "--out", str(on_rig), *grid, "--no-progress"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    assert "recorded 3 A-scans" in flat(err) and "rig emulated" in flat(err)
    # the simulator, seeded as the emulator's setup (its file's seed 4), one pose at a time
    code, _, err = run_main(
        ["record", "--setup", str(setup_file), "--out", str(on_sim), *grid, "--no-progress"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    with xr.open_dataset(on_rig) as a, xr.open_dataset(on_sim) as b:
        assert a["samples"].shape == b["samples"].shape == (1, 1, 3, 1, 256)
        np.testing.assert_array_equal(a["samples"].values, b["samples"].values)
        stored = json.loads(a.attrs["source_info"])
    assert stored["setup"]["rig"]["config"]["rig"]["positioner"]["driver"] == "tcp"
    assert stored["setup"]["config"]["pulse"]["name"] == "gabor"  # a replay finds its pulse


def test_scan_on_a_rig_maps_the_plate(emulator, setup_file, tmp_path, capsys, monkeypatch):
    _, address = emulator
    rig = _tcp_rig(tmp_path, address, setup_file)
    out = tmp_path / "scan"
    args = ["scan", "--rig", str(rig), "--grid", "-1:1:1,0:0:1", "--z", "16", "--out", str(out)]
    code, stdout, err = run_main(
        [*args, "--no-progress", "--no-figures", "--json", "--budget-per-point", "40"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    summary = json.loads(stdout)["scan"]
    assert summary["points"] == 3 and summary["found"] == 3
    with xr.open_dataset(out / "scan.nc") as data:
        heights = data["surface_z"].values.ravel()
        normal_z = data["normal_z"].values.ravel()
    # the flat plate at z = 0 faces straight up: every normal found is vertical within
    # 1 deg, every surface point at z = 0 within 0.3 mm (the time of flight, c0 = 1480 m/s)
    assert np.all(normal_z > np.cos(np.deg2rad(1.0)))
    np.testing.assert_allclose(heights, 0.0, atol=0.3e-3)


def test_calibrate_on_a_rig_file(emulator, setup_file, tmp_path, capsys, monkeypatch):
    _, address = emulator
    rig = _tcp_rig(tmp_path, address, setup_file)
    code, out, err = run_main(
        [
            "calibrate",
            "--rig",
            str(rig),
            "--position",
            "0,0,16",
            "--x0",
            "2,1",
            "--json",
            "--out",
            str(tmp_path / "cal"),
            "--no-plots",
        ],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    summary = json.loads(out)
    assert summary["source"]["kind"] == "rig" and summary["source"]["file"] == str(rig)
    assert summary["pulse"]["from"] == f"--setup {setup_file.as_posix()}"
    # the plate is flat: the echo is strongest firing straight down (tilt 0, 0)
    assert np.hypot(*summary["estimate_deg"]) < 0.5
    # the result file names the rig it came from: its file and the identity it reported
    stored = json.loads((tmp_path / "cal" / "result.json").read_text())["provenance"]
    assert stored["source"]["kind"] == "rig" and stored["source"]["file"] == str(rig)
    assert stored["source"]["description"]  # the instruments' identification, as reported


@pytest.mark.parametrize(
    ("mutate", "expected"),
    [
        (lambda t: t.replace('driver = "tcp"', 'driver = "gpib"', 1), ["rig.positioner", "tcp"]),
        (lambda t: t + "bogus = 1\n", ["unknown key"]),
    ],
)
def test_a_bad_rig_file_is_refused_in_lines_naming_the_field(
    emulator, setup_file, tmp_path, capsys, monkeypatch, mutate, expected
):
    server, address = emulator
    rig = _tcp_rig(tmp_path, address, setup_file)
    rig.write_text(mutate(rig.read_text()), encoding="utf-8")
    code, _, err = run_main(["rig", "check", str(rig)], capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    for word in expected:
        assert word in err
    assert server.n_commands == 0  # refused before anything was connected


def test_rig_needs_a_pulse_and_refuses_simulation_options(emulator, tmp_path, capsys, monkeypatch):
    _, address = emulator
    rig = _tcp_rig(tmp_path, address, None)
    cases = [
        (["calibrate", "--rig", str(rig), "--position", "0,0,16"], ["pulse", "--setup", "[rig]"]),
        (["calibrate", "--rig", str(rig)], ["--position", "required"]),
        (["calibrate", "--rig", str(rig), "--instrument", address], ["mutually exclusive"]),
        (
            [
                "record",
                "--rig",
                str(rig),
                "--out",
                str(tmp_path / "a.nc"),
                "--azimuth",
                "0",
                "--coelevation",
                "0",
            ],
            ["--position", "required"],
        ),
        (
            [
                "scan",
                "--rig",
                str(rig),
                "--grid",
                "0:0:1,0:0:1",
                "--out",
                str(tmp_path / "s"),
                "--snr",
                "20",
                "--setup",
                "thesis",
            ],
            ["--snr", "simulated setup only"],
        ),
        (
            ["record", "--out", str(tmp_path / "b.nc"), "--azimuth", "0", "--coelevation", "0"],
            ["--setup", "--rig"],
        ),
    ]
    for args, expected in cases:
        code, _, err = run_main(args, capsys, monkeypatch)
        assert code == 2, (args, err)
        assert len(err.strip().splitlines()) == 1, err
        for word in expected:
            assert word in err, (args, err)
    assert not (tmp_path / "a.nc").exists() and not (tmp_path / "s").exists()


# -- the shipped pyvisa-sim instruments ----------------------------------------------------
VISA_RIG = """
[rig]
name = "simulated-bench"
setup = "immersion-5mhz"
[rig.positioner]
driver = "visa"
resource = "ASRL1::INSTR"
library = "@echocal-sim"
[rig.positioner.axes]
x = {{ id = "X" }}
y = {{ id = "Y" }}
z = {{ id = "Z" }}
azimuth = {{ id = "AZ" }}
{coelevation}
[rig.receiver]
driver = "visa"
resource = "{scope}"
library = "@echocal-sim"
preset = "{preset}"
averages = 4
timeout = "0.2 s"
retries = 0
"""


def _visa_rig(tmp_path: Path, preset="keysight", scope=None, coel='coelevation = { id = "COEL" }'):
    text = VISA_RIG.format(
        coelevation=coel, preset=preset, scope=scope or f"TCPIP0::{preset}.sim::INSTR"
    )
    path = tmp_path / "visa-rig.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("preset", ["keysight", "tektronix", "rigol"])
def test_rig_check_on_simulated_visa_instruments(preset, tmp_path, capsys, monkeypatch):
    code, out, err = run_main(
        ["rig", "check", str(_visa_rig(tmp_path, preset)), "--json"], capsys, monkeypatch
    )
    assert code == 0, err
    report = json.loads(out)
    assert report["receiver"].startswith(preset.upper())
    assert report["positioner"].startswith("ECHOCAL,SIMULATED-STAGE")
    assert report["limits"]["coelevation"] == [-30.0, 30.0]
    assert report["limits"]["z"] == pytest.approx([0.005, 0.08])
    assert report["ascan"]["n_samples"] == 1000 and report["ascan"]["fs_hz"] == 100e6


@pytest.mark.parametrize(
    ("kwargs", "expected"),
    [
        ({"coel": ""}, ["rig.positioner.axes", "missing axis coelevation"]),
        (
            {"preset": "lecroy", "scope": "TCPIP0::keysight.sim::INSTR"},
            ["rig.receiver.preset", "lecroy", "keysight, rigol, tektronix"],
        ),
        ({"scope": "TCPIP0::nowhere.sim::INSTR"}, ["TCPIP0::nowhere.sim::INSTR"]),
        ({"scope": "TCPIP0::mute.sim::INSTR"}, [":WAVeform:DATA?", "timed out"]),
    ],
)
def test_rig_check_refuses_bad_visa_rigs_in_one_line(
    kwargs, expected, tmp_path, capsys, monkeypatch
):
    code, _out, err = run_main(
        ["rig", "check", str(_visa_rig(tmp_path, **kwargs))], capsys, monkeypatch
    )
    assert code == 2 and "Traceback" not in err
    message = flat(err)
    for word in expected:
        assert word in message, message
    if "missing" not in message:
        assert len(err.strip().splitlines()) == 1, err


# -- the python driver -----------------------------------------------------------------------
LAB_MODULE = '''
import numpy as np
from echocal.ascan import AScan
from echocal.measurement import PositionerLimits


class Stage:
    """A lab's own stage: remembers where it was sent."""

    def __init__(self, z_max):
        self.limits = PositionerLimits(z=(0.0, z_max))
        self.pose = None

    def move_to(self, pose):
        self.pose = pose
        return pose

    def position(self):
        from echocal.geometry import Pose
        return self.pose or Pose(0.0, 0.0, 0.0)

    def identify(self):
        return "LAB,STAGE,1"

    def close(self):
        pass


class Pulser:
    def __init__(self, n):
        self.n = n

    def acquire(self):
        return AScan(samples=np.arange(self.n, dtype=float), fs=1e8, start_time=1e-6)

    def close(self):
        pass
'''


def test_python_driver_builds_the_labs_own_classes(tmp_path, capsys, monkeypatch):
    (tmp_path / "lab_devices.py").write_text(LAB_MODULE, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    rig = tmp_path / "rig.toml"
    rig.write_text(
        '[rig]\nname = "own"\n'
        '[rig.positioner]\ndriver = "python"\nclass = "lab_devices:Stage"\n'
        "options = { z_max = 0.1 }\n"
        '[rig.receiver]\ndriver = "python"\nclass = "lab_devices.Pulser"\noptions = { n = 64 }\n',
        encoding="utf-8",
    )
    code, out, err = run_main(["rig", "check", str(rig), "--json"], capsys, monkeypatch)
    assert code == 0, err
    report = json.loads(out)
    assert report["positioner"] == "LAB,STAGE,1" and report["receiver"] == "Pulser"
    assert report["limits"]["z"] == [0.0, 0.1] and report["ascan"]["n_samples"] == 64
    good = rig.read_text()
    rig.write_text(
        good.replace(
            '"lab_devices.Pulser"\noptions = { n = 64 }',
            '"lab_devices:Stage"\noptions = { z_max = 0.2 }',
        )
    )
    code, _, err = run_main(["rig", "check", str(rig)], capsys, monkeypatch)
    assert code == 2 and "rig.receiver.class: lab_devices:Stage is not a Receiver" in flat(err)
    # the lab's own failure is one line naming its class and call, not a traceback
    rig.write_text(good.replace("z_max = 0.1", "z_max = -1"))
    code, _, err = run_main(["rig", "check", str(rig)], capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_record_on_a_rig_that_dies_keeps_what_was_measured_and_resumes(
    setup_file, tmp_path, capsys, monkeypatch
):
    """The rig goes away after three A-scans: the recording keeps them and says so; the
    same command, with the rig back, measures only the two missing ones."""
    grid = ["--azimuth", "0", "--coelevation", "-4:4:5", "--position", "0,0,16"]
    out = tmp_path / "rig.nc"
    start = Pose(0.0, 0.0, 0.016)
    # each A-scan is MOVE + POS? + ACQ?; connecting is *IDN? + LIMITS? (twice: both devices)
    faults = Faults(drop_after=4 + 3 * 3, drop_forever=True)
    with InstrumentServer(load_setup(setup_file), initial_pose=start, faults=faults) as dying:
        rig = _tcp_rig(tmp_path, ":".join(map(str, dying.address)), setup_file)
        rig.write_text(rig.read_text().replace("timeout = 30", "timeout = 30\nretries = 1"))
        args = ["record", "--rig", str(rig), "--out", str(out), *grid, "--batch-size", "1"]
        code, _, err = run_main([*args, "--no-progress"], capsys, monkeypatch)
    assert code == 2 and not out.exists()
    assert "3 of 5 measurements are saved" in flat(err) and "run the same command again" in err
    with InstrumentServer(load_setup(setup_file), initial_pose=start) as back:
        text = rig.read_text()
        rig.write_text(
            text.replace(
                text.split('address = "')[1].split('"')[0], ":".join(map(str, back.address))
            )
        )
        code, _, err = run_main([*args, "--no-progress"], capsys, monkeypatch)
        assert code == 0, err
        assert "resuming" in err and "resumed after 3" in flat(err)
        assert back.n_acquisitions == 2  # only the two missing A-scans were measured
    with xr.open_dataset(out) as data:
        assert data["samples"].shape == (1, 1, 5, 1, 256)
        assert np.all(np.isfinite(data["samples"].values))


def test_calibrate_on_a_rig_that_dies_saves_what_it_measured(
    setup_file, tmp_path, capsys, monkeypatch
):
    # connecting asks *IDN? twice (one per device) and LIMITS?; each A-scan is MOVE, POS?,
    # ACQ?: the rig is gone after 5 A-scans
    faults = Faults(drop_after=3 + 3 * 5, drop_forever=True)
    start = Pose(0.0, 0.0, 0.016)
    with InstrumentServer(load_setup(setup_file), initial_pose=start, faults=faults) as dying:
        rig = _tcp_rig(tmp_path, ":".join(map(str, dying.address)), setup_file)
        rig.write_text(rig.read_text().replace("timeout = 30", "timeout = 30\nretries = 1"))
        out = tmp_path / "cal"
        code, _, err = run_main(
            ["calibrate", "--rig", str(rig), "--position", "0,0,16", "--out", str(out)],
            capsys,
            monkeypatch,
        )
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert "the run stopped after 5 measurements" in flat(err) and "partial_log.json" in err
    log = json.loads((out / "partial_log.json").read_text())
    assert log["n_measurements"] == 5 and log["source"]["kind"] == "rig"
    assert log["source"]["file"] == str(rig) and len(log["values"]) == 5
    assert not (out / "result.json").exists()
