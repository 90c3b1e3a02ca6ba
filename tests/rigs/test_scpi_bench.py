"""The simulated SCPI bench (``ScpiBench``): the shipped VISA drivers, through PyVISA and
pyvisa-py over a raw TCP socket, measure pose-dependent echoes from the simulator.

The truth is the simulator's own (``VirtualSetup.true_optimum``: a noiseless search kept
apart from measuring), and what the bench sends is checked against the simulator's A-scans
at the same pose (the 16-bit codes quantize by full-scale / 32767).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import TILTED_PLATE as TILTED
from cli_helpers import flat, run_main, tiny_setup_toml
from echocal.geometry import Pose
from echocal.setups import load_setup

pytest.importorskip("pyvisa")
pytest.importorskip("pyvisa_py")
from echocal.rigs import connect_rig
from echocal.rigs.scpi_bench import ScpiBench, rig_file_text

POSITION = (0.001, -0.0005, 0.016)  # [m]


@pytest.fixture
def tilted(tmp_path: Path) -> Path:
    path = tmp_path / "tilted.toml"
    path.write_text(tiny_setup_toml(specimen=TILTED), encoding="utf-8")  # 30 dB SNR
    return path


def test_the_echo_follows_the_pose_as_the_simulator_says(tmp_path: Path):
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml() + '[noise]\nsnr_db = "none"\n', encoding="utf-8")
    virtual = load_setup(path)
    with ScpiBench(load_setup(path)) as bench:
        rig_file = tmp_path / "rig.toml"
        rig_file.write_text(rig_file_text(bench.resource, setup=path.as_posix()), encoding="utf-8")
        with connect_rig(rig_file) as rig:
            peaks = []
            for coelevation in (0.0, 2.0, 4.0, 12.0):
                pose = Pose(0.0, 0.0, 0.016, 0.0, coelevation)
                measured = rig.measure(pose)
                truth = virtual.measure(pose)
                assert measured.fs == truth.fs
                assert measured.start_time == pytest.approx(truth.start_time, rel=1e-12)
                # noiseless: equal to the quantization (half a code)
                np.testing.assert_allclose(
                    measured.samples, truth.samples, rtol=0, atol=0.51 * bench.y_increment
                )
                peaks.append(np.max(np.abs(measured.samples)))
        # the echo fades as the beam tilts away from the plate's normal
        assert peaks[0] > peaks[1] > peaks[2] and max(peaks[2:]) < 0.2 * peaks[0]
        assert bench.n_acquisitions == 4


@pytest.mark.slow  # about 15 s: a calibration over a socket, one pose at a time
def test_calibrate_on_the_visa_bench_reaches_the_simulators_truth(
    tilted, tmp_path, capsys, monkeypatch
):
    truth = load_setup(tilted).true_optimum(POSITION, parameterization="tilt")
    with ScpiBench(load_setup(tilted)) as bench:
        rig_file = tmp_path / "rig.toml"
        rig_file.write_text(
            rig_file_text(bench.resource, setup=tilted.as_posix()), encoding="utf-8"
        )
        code, out, err = run_main(
            [
                "calibrate",
                "--rig",
                str(rig_file),
                "--position",
                "1,-0.5,16",
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
    # the bar: within 0.05 deg of the truth at 30 dB (the setup's SNR), through
    # the real driver path (16-bit codes, SCPI text, pyvisa-py's socket)
    assert np.hypot(*(np.asarray(summary["estimate_deg"]) - np.asarray(truth))) < 0.05


def test_rig_check_and_record_on_the_visa_bench(tmp_path, capsys, monkeypatch):
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    with ScpiBench(load_setup(setup)) as bench:
        rig_file = tmp_path / "rig.toml"
        rig_file.write_text(rig_file_text(bench.resource, setup=setup.as_posix()), encoding="utf-8")
        code, out, err = run_main(["rig", "check", str(rig_file), "--json"], capsys, monkeypatch)
        assert code == 0, err
        report = json.loads(out)
        assert report["receiver"].startswith("ECHOCAL,SIMULATED-SCPI-BENCH")
        assert report["limits"]["z"] == pytest.approx([0.01, 0.04])
        assert report["ascan"]["n_samples"] == 256 and report["ascan"]["fs_hz"] == 50e6
        grid = ["--azimuth", "0", "--coelevation", "-4:4:3", "--position", "0,0,16"]
        out_file = tmp_path / "rig.nc"
        code, _, err = run_main(
            ["record", "--rig", str(rig_file), *grid, "--out", str(out_file)], capsys, monkeypatch
        )
        assert code == 0, err
    import xarray as xr

    with xr.open_dataset(out_file) as recorded:
        peaks = np.max(np.abs(recorded["samples"].values), axis=-1).ravel()
    # the echo at normal incidence (coelevation 0) is the strongest of the three
    assert peaks[1] > 1.5 * max(peaks[0], peaks[2])


def test_scan_on_the_visa_bench_follows_the_plate_as_the_simulators_scan(
    tilted, tmp_path, capsys, monkeypatch
):
    """``scan --rig`` through the VISA drivers (pyvisa-py's socket, SCPI text, 16-bit
    codes) maps the tilted plate as ``scan --setup`` does on the same points."""
    import xarray as xr

    args = ["--grid", "-1:1:1,0:0:1", "--z", "16", "--budget-per-point", "40"]
    args += ["--no-progress", "--no-figures", "--json"]
    with ScpiBench(load_setup(tilted)) as bench:
        rig_file = tmp_path / "rig.toml"
        rig_file.write_text(
            rig_file_text(bench.resource, setup=tilted.as_posix()), encoding="utf-8"
        )
        code, out, err = run_main(
            ["scan", "--rig", str(rig_file), "--out", str(tmp_path / "rig"), *args],
            capsys,
            monkeypatch,
        )
        assert code == 0, err
        summary = json.loads(out)["scan"]
        assert summary["found"] == 3
        assert bench.n_acquisitions == summary["measurements_total"]  # each one a :DIGitize
    code, _, err = run_main(
        ["scan", "--setup", str(tilted), "--out", str(tmp_path / "sim"), *args], capsys, monkeypatch
    )
    assert code == 0, err
    maps = {}
    for name in ("rig", "sim"):
        with xr.open_dataset(tmp_path / name / "scan.nc") as data:
            maps[name] = {
                key: data[key].values.ravel()
                for key in (
                    "normal_x",
                    "normal_y",
                    "normal_z",
                    "surface_x",
                    "surface_y",
                    "surface_z",
                )
            }
    rig, sim = maps["rig"], maps["sim"]
    normal = lambda m: np.stack([m["normal_x"], m["normal_y"], m["normal_z"]], axis=-1)  # noqa: E731
    # the plate's normal (azimuth 30 deg, co-elevation 4 deg), written out here
    a, c = np.deg2rad(30.0), np.deg2rad(4.0)
    plate = np.array([np.sin(c) * np.cos(a), np.sin(c) * np.sin(a), np.cos(c)])
    angle = lambda u, v: np.rad2deg(np.arccos(np.clip(np.sum(u * v, axis=-1), -1, 1)))  # noqa: E731
    # pose-dependent echoes: each point finds the plate's tilt (a pose-blind bench, as the
    # pyvisa-sim files are, returns one trace everywhere and finds no tilt) and the
    # surface drops along x as the plane n . p = 0 says.  At 30 dB the normals scatter
    # by about 0.002 deg and the heights by about 1 um, so 0.05 deg and 5 um are safe.
    assert np.all(angle(normal(rig), plate) < 0.05)
    plane_z = -(plate[0] * rig["surface_x"] + plate[1] * rig["surface_y"]) / plate[2]
    np.testing.assert_allclose(np.diff(rig["surface_z"]), np.diff(plane_z), atol=5e-6)
    assert rig["surface_z"][0] - rig["surface_z"][-1] > 100e-6  # 121 um over the 2 mm
    # the same map as the simulator's: the codes quantize by 1/32767 of 4 reference
    # peaks (1e-4 of the echo), far below the noise, so the two differ by the noise's
    # scatter only (measured: 0.002 deg, 1 um)
    assert np.all(angle(normal(rig), normal(sim)) < 0.02)
    np.testing.assert_allclose(rig["surface_z"], sim["surface_z"], rtol=0, atol=5e-6)


def test_instrument_server_serves_the_bench_and_writes_its_rig_file(tmp_path, capsys, monkeypatch):
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    rig_file = tmp_path / "bench.toml"
    measured = {}

    def serve_once(bench):  # instead of serving until Ctrl-C: one client, then stop
        bench.start()
        with connect_rig(rig_file) as rig:
            measured["ascan"] = rig.measure(Pose(0.0, 0.0, 0.016, 0.0, 0.0))

    monkeypatch.setattr(ScpiBench, "serve_forever", serve_once)
    rig = ["--rig-file", str(rig_file)]
    code, out, err = run_main(
        ["instrument-server", "--protocol", "scpi", "--setup", str(setup), "--port", "0", *rig],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    said = flat(out + err)
    assert "::SOCKET" in said and str(rig_file) in said
    assert np.max(np.abs(measured["ascan"].samples)) > 0.1


@pytest.mark.parametrize(
    "extra", [["--host", "0.0.0.0"], ["--token", "s3cret-token-42"]], ids=["remote", "token"]
)
def test_the_scpi_bench_refuses_to_serve_beyond_loopback(extra, capsys, monkeypatch):
    code, _, err = run_main(
        ["instrument-server", "--protocol", "scpi", "--port", "0", *extra], capsys, monkeypatch
    )
    assert code == 2 and err.count("error:") == 1 and "loopback only" in flat(err)
