"""Kill and resume (issue 15, "Must show"): ``sweep run``, ``scan`` and ``record`` are
stopped by SIGINT (Ctrl-C), SIGTERM or SIGKILL in the middle of their work, then the same
command is run again; the result must equal the uninterrupted run's.  Also: SIGTERM and
SIGHUP during a calibration on a rig save every measurement, as Ctrl-C does, and a
killed sweep leaves no worker process behind.

Each command runs as a real process (``python -m echocal.cli``), so the signals, the exit
codes and the files on disk are the user's.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from cli_helpers import tiny_setup_toml
from echocal.measurement import InstrumentServer
from echocal.setups import load_setup

pytestmark = pytest.mark.slow

SIGNALS = {"SIGINT": 130, "SIGTERM": 143, "SIGKILL": -9}
"""Signal -> the exit status the interrupted command must end with (-9: killed)."""

SWEEP_RUNS = 24
"""12 seeds × 2 methods: the first part file appears after the first run, and the 23 left
take about 12 runs' time on 2 workers, so the signal always finds the sweep at work (with
8 runs, a loaded machine once finished the sweep first)."""
SWEEP = """
name = "tiny"
setup = "thesis"
budget = 24
max_iter = 30
tolerance = 0.5
seeds = 12
snr_db = [30]
[x0]
offset = [1, 3]
[[methods]]
name = "model-based"
[[methods]]
name = "spsa"
preset = "thesis"
"""


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # a test runner may ignore it: Python then would


def start(args: list[str], cwd: Path) -> subprocess.Popen:
    """``echocal ARGS`` as a process of its own session."""
    return subprocess.Popen(
        [sys.executable, "-m", "echocal.cli", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=_default_sigint,
    )


def finish(process: subprocess.Popen, timeout: float = 300) -> tuple[int, str, str]:
    out, err = process.communicate(timeout=timeout)
    return process.returncode, out, err


def run(args: list[str], cwd: Path) -> tuple[int, str, str]:
    return finish(start(args, cwd))


def wait_for(condition, process: subprocess.Popen, timeout: float = 600) -> None:
    """Poll ``condition()`` until true; fail if the process ends first (``timeout`` [s]:
    generous, it only turns a stuck command into a failure on a loaded machine)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return
        if process.poll() is not None:
            pytest.fail(f"the command ended before it could be interrupted: {finish(process)}")
        time.sleep(0.02)
    process.kill()
    pytest.fail(f"the command made no progress to interrupt in {timeout:g} s")


def interrupt(process: subprocess.Popen, name: str) -> tuple[int, str, str]:
    process.send_signal(getattr(signal, name))
    return finish(process)


# -- sweep --------------------------------------------------------------------------------
def _sweep_tables(out: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    runs = pd.read_parquet(out / "runs.parquet").drop(columns=["wall_time"])
    history = pd.read_parquet(out / "history.parquet")
    key = ["case_id"]
    return (
        runs.sort_values(key).reset_index(drop=True),
        history.sort_values([*key, "index"]).reset_index(drop=True),
    )


@pytest.fixture(scope="module")
def sweep_reference(tmp_path_factory) -> tuple[Path, tuple[pd.DataFrame, pd.DataFrame]]:
    folder = tmp_path_factory.mktemp("sweep")
    (folder / "tiny.toml").write_text(SWEEP)
    code, _, err = run(["sweep", "run", "tiny.toml", "--out", "ref", "--no-progress"], folder)
    assert code == 0, err
    return folder, _sweep_tables(folder / "ref")


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(c) for c in text.split()]


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("name", list(SIGNALS))
def test_sweep_killed_and_resumed_equals_the_uninterrupted_sweep(name, sweep_reference):
    folder, reference = sweep_reference
    out = folder / f"cut-{name}"
    args = ["sweep", "run", "tiny.toml", "--out", out.name, "--no-progress", "--workers", "2"]
    process = start(args, folder)
    parts = out / "parts"
    wait_for(lambda: parts.is_dir() and any(parts.glob("runs-*.parquet")), process)
    workers = _children(process.pid)
    code, _, err = interrupt(process, name)
    assert code == SIGNALS[name], err
    assert "Traceback" not in err
    if name == "SIGTERM":
        assert "aborted: terminated by SIGTERM" in err
    time.sleep(0.5)
    assert workers and not [w for w in workers if _alive(w)]  # no orphaned worker computes on
    kept = len(list(parts.glob("runs-*.parquet")))
    assert kept >= 1  # the finished runs are kept on disk
    code, stdout, err = run([*args, "--json"], folder)
    assert code == 0, err
    summary = json.loads(stdout)
    assert summary["n_skipped"] >= kept and summary["n_finished"] == SWEEP_RUNS
    runs, history = _sweep_tables(out)
    pd.testing.assert_frame_equal(runs, reference[0], check_exact=True)
    pd.testing.assert_frame_equal(history, reference[1], check_exact=True)


# -- record -------------------------------------------------------------------------------
RECORD = ["--azimuth", "-6:6:25", "--coelevation", "-6:6:25", "--batch-size", "16"]


@pytest.fixture(scope="module")
def record_reference(tmp_path_factory) -> tuple[Path, np.ndarray]:
    folder = tmp_path_factory.mktemp("record")
    (folder / "tiny.toml").write_text(tiny_setup_toml())
    args = ["record", "--setup", "tiny.toml", "--out", "ref.nc", *RECORD, "--no-progress"]
    code, _, err = run(args, folder)
    assert code == 0, err
    with xr.open_dataset(folder / "ref.nc", engine="h5netcdf") as ds:
        return folder, ds["samples"].values


def _chunks(out: Path) -> int:
    try:
        manifest = json.loads((out.with_name(out.name + ".partial") / "manifest.json").read_text())
    except (OSError, ValueError):
        return 0
    return len(manifest["chunks"])


@pytest.mark.parametrize("name", list(SIGNALS))
def test_record_killed_and_resumed_equals_the_uninterrupted_recording(name, record_reference):
    folder, reference = record_reference
    out = folder / f"cut-{name}.nc"
    args = ["record", "--setup", "tiny.toml", "--out", out.name, *RECORD, "--no-progress"]
    process = start(args, folder)
    wait_for(lambda: _chunks(out) >= 1, process)  # 256 of 625 A-scans are on disk
    code, _, err = interrupt(process, name)
    if code == 0:  # finished before the signal arrived: nothing to resume (rare)
        pytest.skip("the recording finished before the signal")
    assert code == SIGNALS[name], err
    assert "Traceback" not in err and not out.exists()
    code, _, err = run(args, folder)
    assert code == 0, err
    assert "resuming" in err
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        np.testing.assert_array_equal(ds["samples"].values, reference)  # bit for bit
    assert not list(folder.glob(f".{out.name}.*"))  # no hidden temporary or lock left


KILL_IN_FINAL_WRITE = """
import os, signal, sys, time
import echocal.io as io
real = io.atomic_write_bytes
def slow(path, data):
    with io.atomic_path(path) as tmp:
        tmp.write_bytes(data[: len(data) // 2])
        print("writing", flush=True)
        time.sleep(60)
io.atomic_write_bytes = slow
import echocal.measurement.recording as recording
recording.atomic_write_bytes = slow
sys.argv = ["echocal", *sys.argv[1:]]
from echocal.cli import main
main()
"""


def test_a_kill_during_the_final_write_leaves_no_hidden_file(record_reference):
    """SIGKILL while the final file is being written: the half-written hidden temporary is
    removed by the next run, which resumes and writes the same file."""
    folder, reference = record_reference
    (folder / "slow_write.py").write_text(KILL_IN_FINAL_WRITE)
    out = folder / "final.nc"
    args = ["record", "--setup", "tiny.toml", "--out", out.name, *RECORD, "--no-progress"]
    process = subprocess.Popen(
        [sys.executable, "slow_write.py", *args],
        cwd=folder,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "writing"
    hidden = list(folder.glob(f".{out.name}.*.partial.nc"))
    assert len(hidden) == 1 and hidden[0].stat().st_size > 0
    process.kill()
    process.communicate()
    code, _, err = run(args, folder)
    assert code == 0, err
    assert not hidden[0].exists() and not list(folder.glob(f".{out.name}.*"))
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        np.testing.assert_array_equal(ds["samples"].values, reference)


def test_a_damaged_partial_chunk_is_one_line_on_resume(record_reference):
    folder, _ = record_reference
    out = folder / "damaged.nc"
    args = ["record", "--setup", "tiny.toml", "--out", out.name, *RECORD, "--no-progress"]
    process = start(args, folder)
    wait_for(lambda: _chunks(out) >= 1, process)
    code, _, _ = interrupt(process, "SIGKILL")
    sidecar = folder / "damaged.nc.partial"
    chunk = sorted(sidecar.glob("chunk-*.npy"))[0]
    np.save(chunk, np.zeros((3, 7)))  # a chunk of the wrong shape
    code, _, err = run(args, folder)
    assert code == 2 and err.count("error:") == 1 and "Traceback" not in err
    assert (
        chunk.name in err
        and "(3, 7)" in err
        and f"delete {sidecar.name}" in err.replace(str(folder) + "/", "")
    )


# -- scan ---------------------------------------------------------------------------------
SCAN = ["--setup", "scan-5mhz", "--specimen", "sphere", "--grid", "-6:6:3,-6:6:3"]
SCAN += ["--no-figures", "--no-progress"]


@pytest.fixture(scope="module")
def scan_reference(tmp_path_factory) -> tuple[Path, xr.Dataset]:
    folder = tmp_path_factory.mktemp("scan")
    code, _, err = run(["scan", *SCAN, "--out", "ref"], folder)
    assert code == 0, err
    with xr.open_dataset(folder / "ref" / "scan.nc", engine="h5netcdf") as ds:
        return folder, ds.load()


def _points(out: Path) -> int:
    try:
        return (out / "scan.nc.partial" / "points.jsonl").read_text().count("\n")
    except OSError:
        return 0


@pytest.mark.parametrize("name", list(SIGNALS))
def test_scan_killed_and_resumed_equals_the_uninterrupted_scan(name, scan_reference):
    folder, reference = scan_reference
    out = folder / f"cut-{name}"
    process = start(["scan", *SCAN, "--out", out.name], folder)
    wait_for(lambda: _points(out) >= 3, process)
    code, _, err = interrupt(process, name)
    assert code == SIGNALS[name], err
    assert "Traceback" not in err and not (out / "scan.nc").exists()
    code, _, err = run(["scan", *SCAN, "--out", out.name], folder)
    assert code == 0, err
    with xr.open_dataset(out / "scan.nc", engine="h5netcdf") as ds:
        for variable in reference.data_vars:
            np.testing.assert_array_equal(ds[variable].values, reference[variable].values)


# -- a calibration on a rig ---------------------------------------------------------------
@pytest.mark.parametrize(("name", "code"), [("SIGTERM", 143), ("SIGHUP", 129)])
def test_a_termination_signal_saves_a_rig_calibration_like_ctrl_c(name, code, tmp_path):
    (tmp_path / "tiny.toml").write_text(tiny_setup_toml())
    setup = load_setup(tmp_path / "tiny.toml", seed=3)
    with InstrumentServer(setup, move_time=0.05) as server:
        host, port = server.address
        args = ["calibrate", "--instrument", f"{host}:{port}", "--setup", "tiny.toml"]
        args += ["--position", "0,0,16", "--x0", "2,-1", "--no-plots", "--settle", "none"]
        args += ["--method", "model-based", "--budget", "200", "--out", "rig"]
        process = start(args, tmp_path)
        wait_for(lambda: server.n_acquisitions >= 6, process)  # one may be in flight
        got, _, err = interrupt(process, name)
        acquired = server.n_acquisitions
    assert got == code, err
    assert "Traceback" not in err and f"aborted: terminated by {name}" in err
    log = json.loads((tmp_path / "rig" / "partial_log.json").read_text())
    assert log["status"] == "interrupted" and log["error"] == f"terminated by {name}"
    # every A-scan the rig delivered is in the log (the one in flight may be lost with
    # the connection: it never reached echocal)
    assert acquired - 1 <= log["n_measurements"] <= acquired
    assert len(log["values"]) == len(log["poses"]) == log["n_measurements"] >= 5
    assert os.path.exists(tmp_path / "rig" / "partial_log.json")
