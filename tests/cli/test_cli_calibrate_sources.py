"""``echocal calibrate --replay FILE`` and ``--instrument HOST:PORT``: the command line's
calibration on a recording and on a rig, against the truth the simulator knows.

The setup: a 60 x 60 mm plate whose normal is (azimuth 30 deg, co-elevation 20 deg) — the
analytic optimum for a plane, away from the pole of the recorder's (azimuth, co-elevation)
grid — seen by a 4 mm, 12 x 12-ray, 1 MHz probe 20 mm above it (512 samples, SNR 30 dB):
a beam about 3 x 10 deg wide (FWHM), a few milliseconds per A-scan.  The recording is made
with ``echocal record`` (which stores the setup, so its pulse can be rebuilt), the rig is
``InstrumentServer`` on loopback, in-process.  Bad input goes through the console-script
entry point (``run_main``): one ``error:`` line, exit 2, nothing written.
"""

from __future__ import annotations

import json
import socket
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from cli_helpers import flat, run_main
from echocal.calibrate import CalibrationResult
from echocal.cli import app
from echocal.evaluation import CostMap, angular_error
from echocal.geometry import convert_angles
from echocal.measurement import Faults, InstrumentServer, RecordingGrid, ReplaySource, record
from echocal.plots.calibration import measured_convergence_figure, path_figure
from echocal.setups import load_setup

runner = CliRunner()

PLATE = """
name = "plate20"
description = "60 mm plate tilted to (30, 20) deg under a 4 mm 1 MHz probe"
seed = 3

[[specimen.shapes]]
kind = "plane"
center = [0, 0, 0]
width = "60 mm"
height = "60 mm"
azimuth = 30
coelevation = 20

[transducer]
width = "4 mm"
n_h = 12
pinhole_distance = "200 mm"

[transducer.directivity]
model = "gaussian"
opening_angle = 10

[pulse]
name = "gabor"
center_frequency = "1 MHz"
bandwidth = 60

[window]          # echo at 2 x 20 mm / 1480 m/s = 27 us, inside [15, 40.6] us
fs = "20 MHz"
start = "15 us"
n_samples = 512

[noise]
snr_db = 30

[positioner]
reference_position = ["0 mm", "0 mm", "20 mm"]
z = ["10 mm", "40 mm"]
coelevation = [-30, 30]
"""
PLATE_NORMAL = (30.0, 20.0)  # [deg] (azimuth, co-elevation): the analytic optimum
POSITION = (0.0, 0.0, 0.02)  # [m]
AZ_STEP, COEL_STEP = 1.0, 0.5  # [deg] the recording's grid steps
GRID = ["--azimuth", "20:40:21", "--coelevation", "14:26:25"]  # 1 deg x 0.5 deg steps

# Tolerances [deg], the angle between the estimate's beam and the true optimum's.
# Live sources (simulator, rig) are noise-limited: at SNR 30 dB auto lands within ~0.02 deg
# on this setup (0.009 deg at seed 3); 0.1 deg is a 5x margin, 3 % of the narrowest FWHM.
NOISE_TOL = 0.1
# A recording knows the objective only on its grid: in "nearest" mode the objective is
# constant on each cell, so its maximizer is known to half a cell diagonal; in beam angle a
# cell is COEL_STEP by AZ_STEP * sin(coelevation) (<= 0.44 deg for coelevation <= 26 deg).
HALF_CELL = 0.5 * np.hypot(COEL_STEP, AZ_STEP * np.sin(np.deg2rad(26.0)))
REPLAY_TOL = HALF_CELL + NOISE_TOL  # 0.43 deg; doing nothing (x0) is >= 3 deg off


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("calibrate_sources")


@pytest.fixture(scope="module")
def plate(folder: Path) -> Path:
    path = folder / "plate.toml"
    path.write_text(PLATE, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def truth(plate: Path) -> np.ndarray:
    """The simulator's true optimum (azimuth, co-elevation) [deg] at POSITION."""
    found = np.array(load_setup(plate).true_optimum(POSITION))
    # independent truth: for a plane, the beam along its normal; 1e-4 deg covers the
    # search tolerance of true_optimum (1e-5 deg)
    np.testing.assert_allclose(found, PLATE_NORMAL, atol=1e-4)
    return found


@pytest.fixture(scope="module")
def recording(plate: Path, folder: Path) -> Path:
    """``echocal record`` of the plate on a 21 x 25 grid around its normal (seed 5)."""
    out = folder / "plate.nc"
    args = ["record", "--setup", str(plate), "--out", str(out), *GRID, "--position", "0,0,20"]
    result = runner.invoke(app, [*args, "--seed", "5", "--no-progress"])
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module")
def bare(plate: Path, folder: Path) -> Path:
    """A recording made from Python without a setup (no pulse stored), at two positions."""
    grid = RecordingGrid.regular(
        azimuth=(28, 32, 3), coelevation=(18, 22, 3), positions=[POSITION, (0.001, 0.0, 0.02)]
    )
    return record(load_setup(plate), grid, folder / "bare.nc", progress=False, batch_size=64)


def calibrate_json(args: list[str], capsys, monkeypatch) -> dict:
    code, out, err = run_main(["calibrate", *args, "--json"], capsys, monkeypatch)
    assert code in (0, 3), err  # converged, or an estimate at the end of the budget
    summary = json.loads(out)
    assert summary["exit_code"] == code and summary["success"] is (code == 0)
    # the 90 % radius (a positive number when the run found an echo and knows its noise)
    # and the false alarms the local phase refuted
    assert summary["uncertainty_level"] == 0.9 and summary["false_alarms"] >= 0
    assert summary["uncertainty_deg"] is None or summary["uncertainty_deg"] > 0.0
    return summary


def beam_error(estimate, truth, parameterization: str = "azimuth-coelevation") -> float:
    return float(angular_error(np.asarray(estimate), np.asarray(truth), parameterization))


# -- replay -----------------------------------------------------------------------------------
def test_replay_finds_the_simulators_optimum(recording, truth, tmp_path, capsys, monkeypatch):
    x0 = (26.0, 17.0)
    assert beam_error(x0, truth) > 3.0  # the test can fail: doing nothing is 3 deg off
    out = tmp_path / "run"
    args = ["--replay", str(recording), "--x0", "26,17", "--out", str(out), "--no-plots"]
    summary = calibrate_json(args, capsys, monkeypatch)
    assert summary["source"] == {
        "kind": "replay",
        "file": str(recording),
        "mode": "nearest",  # the replay's default
        "description": summary["source"]["description"],
    }
    assert "plate20" in summary["source"]["description"]
    # the grid's own angles by default, its only position, the pulse `echocal record` stored
    assert summary["parameterization"] == "azimuth-coelevation"
    assert summary["position_m"] == list(POSITION)
    assert summary["pulse"]["center_frequency_hz"] == 1e6
    assert "recording's setup" in summary["pulse"]["from"]
    assert summary["truth_deg"] is None and summary["error_deg"] is None
    assert summary["success"] and summary["n_measurements"] > 0
    assert beam_error(summary["estimate_deg"], truth) < REPLAY_TOL
    # the recording's best grid pose is a grid point
    best = summary["recording_best_deg"]
    assert best[0] in np.arange(20.0, 41.0) and best[1] in np.arange(14.0, 26.5, 0.5)
    saved = CalibrationResult.load_json(out / "result.json")
    np.testing.assert_array_equal(saved.x, summary["estimate_deg"])
    assert saved.n_measurements == summary["n_measurements"] == len(saved.points)
    assert sorted(p.name for p in out.iterdir()) == ["ascan.nc", "result.json", "summary.json"]


def test_replay_in_tilts_interpolated_stays_on_the_recording(
    recording, truth, tmp_path, capsys, monkeypatch
):
    truth_tilt = np.array(convert_angles(*truth, "azimuth-coelevation", "tilt"))
    x0 = truth_tilt + np.array([2.5, -2.0])  # 3.2 deg off, as a coarse manual alignment
    args = ["--replay", str(recording), "--replay-mode", "interpolate", "--parameterization"]
    args += ["tilt", "--x0", f"{x0[0]},{x0[1]}", "--out", str(tmp_path / "t"), "--no-plots"]
    summary = calibrate_json(args, capsys, monkeypatch)
    assert summary["names"] == ["tilt_x", "tilt_y"] and summary["source"]["mode"] == "interpolate"
    # bilinear interpolation does no worse than the nearest grid pose
    assert beam_error(summary["estimate_deg"], truth_tilt, "tilt") < REPLAY_TOL
    # the tilt box lies inside the (azimuth, co-elevation) grid: no pose was refused, and
    # every measured pose is a recorded orientation
    points = CalibrationResult.load_json(tmp_path / "t" / "result.json").points
    az, coel = convert_angles(points[:, 0], points[:, 1], "tilt", "azimuth-coelevation")
    assert np.all((20.0 <= az) & (az <= 40.0) & (14.0 <= coel) & (coel <= 26.0))


def test_replay_plots_show_the_recordings_own_map(recording, tmp_path, capsys, monkeypatch):
    out = tmp_path / "plots"
    args = ["--replay", str(recording), "--x0", "26,17", "--out", str(out), "--budget", "20"]
    code, stdout, err = run_main(["calibrate", *args], capsys, monkeypatch)
    assert code in (0, 3), err  # converged, or an estimate at the end of the budget
    shown = flat(stdout)
    assert "estimate" in shown and "no truth is known" in shown and "echo found after" in shown
    assert {p.name for p in out.iterdir()} == {
        "result.json",
        "summary.json",
        "convergence.png",
        "path.png",
        "ascan.nc",
        "ascan.png",
    }
    assert all((out / name).stat().st_size > 10_000 for name in ("convergence.png", "path.png"))


def test_setup_pulse_overrides_the_recorded_one_with_a_warning(
    recording, tmp_path, capsys, monkeypatch
):
    args = ["--replay", str(recording), "--setup", "immersion-5mhz", "--budget", "8"]
    code, out, err = run_main(
        ["calibrate", *args, "--no-plots", "--out", str(tmp_path), "--json"], capsys, monkeypatch
    )
    # a 5 MHz template on a 1 MHz recording may see no echo at the estimate (exit 1)
    assert code in (0, 1, 3), err
    summary = json.loads(out)
    assert summary["pulse"] == {
        "name": "gabor",
        "center_frequency_hz": 5e6,
        "from": "--setup immersion-5mhz",
    }
    assert "warning:" in err and "differs" in err and "1 MHz" in err


def test_replay_with_several_positions_takes_the_one_asked_for(
    bare, plate, tmp_path, capsys, monkeypatch
):
    args = ["--replay", str(bare), "--setup", str(plate), "--position", "1mm,0,2cm"]
    summary = calibrate_json(
        [*args, "--budget", "8", "--no-plots", "--out", str(tmp_path)], capsys, monkeypatch
    )
    np.testing.assert_allclose(summary["position_m"], [0.001, 0.0, 0.02], atol=1e-12)
    assert summary["setup"] == str(plate)


# -- instrument -------------------------------------------------------------------------------
def test_instrument_reaches_the_simulated_estimate(plate, truth, tmp_path, capsys, monkeypatch):
    seed = 3
    common = ["--x0", "-7,15", "--seed", str(seed), "--no-plots"]
    direct = calibrate_json(
        ["--setup", str(plate), *common, "--out", str(tmp_path / "sim")], capsys, monkeypatch
    )
    with InstrumentServer(load_setup(plate, seed=seed)) as server:
        host, port = server.address
        args = ["--instrument", f"{host}:{port}", "--setup", str(plate), "--position", "0,0,20"]
        rig = calibrate_json([*args, *common, "--out", str(tmp_path / "rig")], capsys, monkeypatch)
        # every acquisition counted: ascan.nc is the run's final measurement at the estimate
        assert server.n_acquisitions == rig["n_measurements"]
    assert rig["source"]["kind"] == "instrument"
    assert rig["source"]["address"] == f"{host}:{port}"
    assert rig["truth_deg"] is None and rig["error_deg"] is None
    truth_tilt = np.array(convert_angles(*truth, "azimuth-coelevation", "tilt"))
    assert beam_error(rig["estimate_deg"], truth_tilt, "tilt") < NOISE_TOL
    assert direct["error_deg"] < NOISE_TOL
    # Over the socket nothing is lost (poses and float64 samples travel exactly) and the
    # rig has the simulator's noise seed: x0 and its first ring, measured before any model
    # acts, are the same measurements.  Beyond them the paths part: the simulator's lobe
    # template knows its echo's energy in its own units, a rig's twin does not.
    measured = CalibrationResult.load_json(tmp_path / "rig" / "result.json")
    simulated = CalibrationResult.load_json(tmp_path / "sim" / "result.json")
    np.testing.assert_array_equal(measured.points[:7], simulated.points[:7])
    np.testing.assert_array_equal(measured.values[:7], simulated.values[:7])


def test_instrument_plots_the_path_without_a_map(plate, tmp_path, capsys, monkeypatch):
    with InstrumentServer(load_setup(plate, seed=1)) as server:
        host, port = server.address
        args = ["--instrument", f"{host}:{port}", "--setup", str(plate), "--position", "0,0,20"]
        args += ["--x0", "-9,16", "--budget", "12", "--out", str(tmp_path)]
        code, out, err = run_main(["calibrate", *args], capsys, monkeypatch)
    assert code in (0, 3), err  # converged, or an estimate at the end of the budget
    assert "a rig does not know its optimum" in flat(out)
    # the rig's final measurement at the estimate: ascan.nc and its plot
    assert {p.name for p in tmp_path.iterdir()} == {
        "result.json",
        "summary.json",
        "convergence.png",
        "path.png",
        "ascan.nc",
        "ascan.png",
    }


# -- the rig fails mid-run -----------------------------------------------------------------------
RIG_ARGS = ["--position", "0,0,20", "--x0", "-7,15", "--seed", "3", "--no-plots"]


# The rig vanishes after 2 + 3 k commands (*IDN?, LIMITS?, then MOVE, POS?, ACQ? per pose):
# k A-scans.  The run measures a first batch of 7 poses, then one at a time: k = 5 cuts the
# first batch short (the objective has logged nothing), k = 7 stops between batches.  The
# simulated run is the rig's reference up to there: beyond, the simulator's lobe template
# knows its echo's energy in its own units and a rig's twin does not, so the paths part.
DROPS = [(5, 5), (7, 0)]  # (k, A-scans of the unfinished batch)


@pytest.mark.parametrize(("k", "unfinished"), DROPS, ids=["in-a-batch", "between-batches"])
def test_rig_failing_mid_run_saves_what_was_measured(
    k, unfinished, plate, tmp_path, capsys, monkeypatch
):
    """The measurements made before the fault are written to partial_log.json, one error
    line says how many and where, exit 2; they are the simulated run's first measurements
    (same seed)."""
    sim = calibrate_json(
        ["--setup", str(plate), *RIG_ARGS, "--out", str(tmp_path / "sim")], capsys, monkeypatch
    )
    simulated = CalibrationResult.load_json(tmp_path / "sim" / "result.json")
    out = tmp_path / "rig"
    faults = Faults(drop_after=2 + 3 * k, drop_forever=True)
    with InstrumentServer(load_setup(plate, seed=3), faults=faults) as server:
        host, port = server.address
        args = ["--instrument", f"{host}:{port}", "--setup", str(plate), *RIG_ARGS]
        code, stdout, err = run_main(["calibrate", *args, "--out", str(out)], capsys, monkeypatch)
        acquired = server.n_acquisitions
    assert code == 2, err
    assert "Traceback" not in err and err.count("error:") == 1, err
    assert len(err.strip().splitlines()) == 1, err
    assert stdout == ""
    assert acquired == k < sim["n_measurements"]  # the fault came mid-run
    assert "failed after 4 attempts" in err
    assert f"stopped after {acquired} measurements" in err
    assert str(out / "partial_log.json") in err
    # no result.json; the A-scans, for a resume
    assert {p.name for p in out.iterdir()} == {"partial_log.json", "partial_ascans"}
    assert len(list((out / "partial_ascans").glob("*.npz"))) == acquired
    log = json.loads((out / "partial_log.json").read_text())
    assert log["status"] == "interrupted" and "failed after 4 attempts" in log["error"]
    assert log["n_measurements"] == acquired == len(log["values"]) == len(log["times"])
    assert log["source"] == {
        "kind": "instrument",
        "address": f"{host}:{port}",
        "description": log["source"]["description"],
    }
    assert log["names"] == ["tilt_x", "tilt_y"] and log["x0_deg"] == [-7.0, 15.0]
    assert log["unfinished_batch"] == unfinished
    # the same points and values as the simulation's first measurements (the socket carries
    # float64 samples and the rig has the simulator's noise seed): the unfinished batch's
    # points come back from their poses (1e-9 deg: round-off of the angle conversion), its
    # values from the same matched filter by another call (1e-12 relative: round-off)
    np.testing.assert_allclose(log["points"], simulated.points[:acquired], rtol=0, atol=1e-9)
    np.testing.assert_allclose(log["values"], simulated.values[:acquired], rtol=1e-12)
    assert np.all(np.diff(log["times"]) >= 0)
    # each pose is the probe position and the point's tilts as (azimuth, co-elevation);
    # 1e-9 deg / 1e-12 m cover float round-off of the conversion
    poses = np.array(log["poses"])
    np.testing.assert_allclose(poses[:, :3], np.tile(POSITION, (acquired, 1)), atol=1e-12)
    for pose, point in zip(poses, log["points"], strict=True):
        angles = convert_angles(*point, "tilt", "azimuth-coelevation")
        assert beam_error(pose[3:], angles) < 1e-9
    best = int(np.argmax(log["values"]))
    assert log["best"]["index"] == best and log["best"]["point_deg"] == log["points"][best]
    a, b = log["points"][best]
    assert f"--x0 {a:.3f},{b:.3f}" in err


def test_rig_failing_before_any_measurement_writes_nothing(plate, tmp_path, capsys, monkeypatch):
    """Gone after *IDN? and LIMITS?: the first MOVE fails; nothing measured, nothing saved."""
    out = tmp_path / "rig"
    faults = Faults(drop_after=2, drop_forever=True)
    with InstrumentServer(load_setup(plate, seed=3), faults=faults) as server:
        host, port = server.address
        args = ["--instrument", f"{host}:{port}", "--setup", str(plate), *RIG_ARGS]
        code, _, err = run_main(["calibrate", *args, "--out", str(out)], capsys, monkeypatch)
        assert server.n_acquisitions == 0
    assert code == 2 and err.count("error:") == 1, err
    assert "MOVE" in err and "failed after 4 attempts" in err and "saved" not in err
    assert not out.exists()


def test_ctrl_c_on_a_rig_saves_what_was_measured(plate, tmp_path, capsys, monkeypatch):
    """Ctrl-C in the 6th measurement: the 5 made are saved, exit 130 (any Ctrl-C's)."""
    from echocal.measurement import SourceObjective

    evaluate = SourceObjective._evaluate
    calls = []

    def interrupted(self, points):
        calls.append(len(points))
        if len(calls) == 6:
            raise KeyboardInterrupt
        return evaluate(self, points)

    monkeypatch.setattr(SourceObjective, "_evaluate", interrupted)
    out = tmp_path / "rig"
    with InstrumentServer(load_setup(plate, seed=3)) as server:
        host, port = server.address
        args = ["--instrument", f"{host}:{port}", "--setup", str(plate), *RIG_ARGS]
        code, _, err = run_main(["calibrate", *args, "--out", str(out)], capsys, monkeypatch)
        acquired = server.n_acquisitions
    made = sum(calls[:5])
    assert code == 130, err
    assert acquired == made > 0
    assert "interrupted:" in err and f"stopped after {made} measurements" in err, err
    log = json.loads((out / "partial_log.json").read_text())
    assert log["status"] == "interrupted" and log["error"] == "interrupted (Ctrl-C)"
    assert log["n_measurements"] == made == len(log["points"])


# -- bad input ----------------------------------------------------------------------------------
def closed_port() -> int:
    """A local port nobody listens on (bound, then released)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


BAD = [
    (["--replay", "{rec}", "--instrument", "127.0.0.1:5025"], ["mutually exclusive"]),
    (["--replay", "{rec}", "--snr", "20"], ["--snr", "simulated setup only"]),
    (["--instrument", "127.0.0.1:5025", "--specimen", "sphere"], ["--specimen", "drop"]),
    (["--replay", "{missing}"], ["replay file not found"]),
    (["--replay", "{bare}"], ["2 positions", "(1, 0, 20)", "--position"]),
    (["--replay", "{bare}", "--position", "0,0,20"], ["no pulse", "--setup"]),
    (["--replay", "{rec}", "--position", "5,0,20"], ["not a position of", "(0, 0, 20)"]),
    (["--replay", "{rec}", "--replay-mode", "best"], ["--replay-mode", "interpolate"]),
    (["--replay-mode", "nearest"], ["--replay-mode applies only with --replay"]),
    (["--replay", "{rec}", "--x0", "0,0"], ["x0", "outside the bounds"]),
    (["--replay", "{rec}", "--parameterization", "tilt", "--x0", "0,0"], ["not an orientation"]),
    (["--instrument", "localhost"], ["HOST:PORT"]),
    (["--instrument", "localhost:0", "--position", "0,0,20"], ["HOST:PORT", "1-65535"]),
    (["--instrument", ":5025"], ["HOST:PORT"]),
    (["--instrument", "127.0.0.1:5025", "--setup", "{plate}"], ["--position", "required"]),
    (["--instrument", "127.0.0.1:5025", "--position", "0,0,20"], ["pulse", "--setup"]),
    (["--instrument", "127.0.0.1:{port}", "--position", "0,0,20", "--setup", "thesis"], ["*IDN?"]),
    (["--timeout", "1"], ["--timeout applies only with --instrument"]),
]


@pytest.mark.parametrize(("args", "fragments"), BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(
    args, fragments, recording, bare, plate, tmp_path, capsys, monkeypatch
):
    names = {"rec": recording, "bare": bare, "plate": plate, "missing": tmp_path / "no.nc"}
    filled = [a.format(port=closed_port(), **names) for a in args]
    out = tmp_path / "out"
    code, stdout, err = run_main(["calibrate", *filled, "--out", str(out)], capsys, monkeypatch)
    assert code == 2, err
    assert "Traceback" not in err and err.count("error:") == 1, err
    assert len(err.strip().splitlines()) == 1, err  # one line (no wrapping: soft_wrap)
    for fragment in fragments:
        assert fragment in err, err
    assert stdout == "" and not out.exists()


# -- the figures without a truth ------------------------------------------------------------------
@pytest.fixture(scope="module")
def replayed(recording: Path, plate: Path) -> CalibrationResult:
    """A short calibration on the recording (Python API), for the figure tests."""
    from echocal.calibrate import calibrate
    from echocal.measurement import SourceObjective

    with ReplaySource.open(recording) as source:
        objective = SourceObjective(source, POSITION, pulse=load_setup(plate).pulse)
        return calibrate(objective, method="auto", x0=(26.0, 17.0), budget=25, rng=0)


def test_path_figure_without_a_map_frames_every_point(replayed):
    fig = path_figure(None, {"auto": replayed}, x0=replayed.iterates[0], show_measurements=True)
    # the run's (azimuth, co-elevation) and tilt angles beside them; no colour bar: no map
    assert len(fig.axes) == 2 and fig.axes[1].get_xlabel() == "tilt_x [deg]"
    ax = fig.axes[0]
    (x_lo, x_hi), (y_lo, y_hi) = ax.get_xlim(), ax.get_ylim()
    points = np.vstack([replayed.points, replayed.iterates])
    assert np.all((x_lo < points[:, 0]) & (points[:, 0] < x_hi))
    assert np.all((y_lo < points[:, 1]) & (points[:, 1] < y_hi))
    assert ax.get_xlabel() == "azimuth [deg]"


def test_path_figure_leaves_an_uncovered_map_blank(replayed):
    a, b = np.linspace(20, 40, 5), np.linspace(14, 26, 4)
    values = np.ones((5, 4))
    values[0, 0] = np.nan  # an orientation the recording does not hold
    fig = path_figure(CostMap(a=a, b=b, values=values), {"auto": replayed}, db_floor=-40.0)
    shown = fig.axes[0].collections[0].get_array()
    assert np.ma.count_masked(shown) == 1 and np.allclose(shown.compressed(), 0.0)


def test_measured_convergence_figure_shows_what_was_measured(replayed):
    fig = measured_convergence_figure(replayed, scale=2.0, scale_label="two")
    measured, settling = fig.axes
    dots, best = measured.lines[0], measured.lines[1]
    np.testing.assert_allclose(dots.get_ydata(), replayed.values / 2.0)
    np.testing.assert_allclose(best.get_ydata(), np.maximum.accumulate(replayed.values) / 2.0)
    assert measured.get_ylabel() == "metric / two"
    # the settling panel: each iterate's beam angle to the final estimate (zeros left out)
    distance = angular_error(replayed.iterates, replayed.x, replayed.parameterization)
    np.testing.assert_allclose(settling.lines[0].get_ydata(), distance[distance > 0])
