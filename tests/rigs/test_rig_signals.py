"""Every signal keeps every measurement, on every driver: ``record --rig`` through the TCP
driver (the emulator), the VISA drivers (the simulated SCPI bench, pyvisa-py) and the
python driver (a lab's own classes, here over the simulator in this process) is stopped
by SIGINT, SIGTERM or SIGHUP after a few A-scans, then run again: it resumes and the file
holds every A-scan the rig delivered, once, in order.

The instruments serve from a recording proxy of the simulator, so the test knows every
A-scan the rig sent; the proxy itself sends the signal to this process (the CLI runs
in-process in the main thread, where the handlers are) as it serves the third A-scan.
"""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr

from cli_helpers import flat, run_main, simulated_lab, tcp_rig_file, tiny_setup_toml
from echocal.geometry import Pose
from echocal.measurement import InstrumentServer
from echocal.setups import load_setup

pytest.importorskip("pyvisa_py")
from echocal.rigs.scpi_bench import ScpiBench, rig_file_text

GRID = ["--azimuth", "0", "--coelevation", "-3:3:7", "--position", "0,0,16"]
STOP_AFTER = 3  # A-scans the instrument delivers before the signal
EXIT = {"SIGINT": 130, "SIGTERM": 143, "SIGHUP": 129}


class Served:
    """A measurement source that keeps every A-scan it serves (delegates the rest), and
    sends its process a signal once :data:`STOP_AFTER` A-scans are served (``stop_with``):
    from the serving thread, right then, so the command is always stopped mid-run however
    loaded the machine is (a watching thread may only get to run after the last one)."""

    def __init__(self, source: Any) -> None:
        self._source = source
        self.samples: list[np.ndarray] = []
        self.stop_with: str | None = None  # the signal's name

    def __getattr__(self, name: str) -> Any:
        return getattr(self._source, name)

    def measure(self, pose: Pose) -> Any:
        return self.measure_many([pose])[0]

    def measure_many(self, poses: list[Pose]) -> list[Any]:
        scans = self._source.measure_many(poses)
        self.samples += [np.asarray(s.samples) for s in scans]
        if self.stop_with is not None and len(self.samples) >= STOP_AFTER:
            name, self.stop_with = self.stop_with, None
            os.kill(os.getpid(), getattr(signal, name))
        return scans


def run_until_signal(
    served: Served, name: str, args: list[str], capsys: Any, monkeypatch: Any
) -> tuple[int, str, str]:
    """Run the CLI in this process (its main thread holds the handlers) with ``name`` sent
    once ``served`` has delivered :data:`STOP_AFTER` A-scans."""
    served.stop_with = name
    return run_main(args, capsys, monkeypatch)


def _tcp(source: Served, tmp_path: Path, setup: Path) -> tuple[Any, Path, float]:
    server = InstrumentServer(source, initial_pose=Pose(0.0, 0.0, 0.016), move_time=0.02)
    host, port = server.address
    rig = tcp_rig_file(tmp_path / "tcp-rig.toml", f"{host}:{port}", setup)
    return server, rig, 0.0  # the line protocol sends float64: exact


def _visa(source: Served, tmp_path: Path, setup: Path) -> tuple[Any, Path, float]:
    bench = ScpiBench(source)
    rig = tmp_path / "visa-rig.toml"
    rig.write_text(rig_file_text(bench.resource, setup=setup.as_posix()), encoding="utf-8")
    return bench, rig, 0.51 * bench.y_increment  # 16-bit codes: half a code


class _InProcess:
    """The python driver's devices live in this process: nothing to serve; on exit the
    lab's module leaves the import path."""

    def __init__(self, module: Any, folder: str) -> None:
        self._served = module.SOURCE
        self._folder = folder

    def __enter__(self) -> _InProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._folder in sys.path:
            sys.path.remove(self._folder)


def _python(source: Served, tmp_path: Path, setup: Path) -> tuple[Any, Path, float]:
    module, rig = simulated_lab(tmp_path, f"lab_sim_devices_{tmp_path.name}", setup)
    module.SOURCE = source
    return _InProcess(module, str(tmp_path)), rig, 0.0  # in process: the very samples


def _count(instrument: Any) -> int:
    return len(instrument._served.samples)


@pytest.mark.slow  # six record runs and six resumes over sockets: about 25 s
@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")
@pytest.mark.parametrize("driver", [_tcp, _visa, _python], ids=["tcp", "visa", "python"])
@pytest.mark.parametrize("name", list(EXIT))
def test_a_signal_keeps_every_ascan_and_the_run_resumes(
    name, driver, tmp_path, capsys, monkeypatch
):
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    served = Served(load_setup(setup))
    instrument, rig, atol = driver(served, tmp_path, setup)
    out = tmp_path / "rec.nc"
    args = ["record", "--rig", str(rig), *GRID, "--out", str(out), "--no-progress"]

    with instrument:
        code, _, err = run_until_signal(served, name, args, capsys, monkeypatch)
        first = list(served.samples)
        assert code == EXIT[name], err
        assert "Traceback" not in err and "run the same command again to resume" in flat(err)
        assert not out.exists()
        first_err = err
        code, _, err = run_main(args, capsys, monkeypatch)
        assert code == 0, err
    assert "resumed after" in err, (first_err, err)
    resumed_after = int(flat(err).split("resumed after ")[1].split(")")[0])
    # every A-scan delivered is kept: the signal waits for the one in flight
    assert resumed_after == len(first) >= STOP_AFTER
    expected = first[:resumed_after] + served.samples[len(first) :]
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        stored = ds["samples"].values.reshape(-1, ds.sizes["time"])
    assert len(stored) == len(expected) == 7
    for got, sent in zip(stored, expected, strict=True):
        np.testing.assert_allclose(got, sent, rtol=0, atol=atol)


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")
@pytest.mark.parametrize("driver", [_tcp, _visa, _python], ids=["tcp", "visa", "python"])
@pytest.mark.parametrize("name", list(EXIT))
def test_a_signal_during_calibrate_on_a_rig_saves_every_measurement(
    name, driver, tmp_path, capsys, monkeypatch
):
    """Each signal during ``calibrate --rig`` on each driver keeps what was measured in
    partial_log.json.  SIGHUP is the reported case (exit 1 with a traceback from numba's
    interrupted first import, and no partial_log.json)."""
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    served = Served(load_setup(setup))
    instrument, rig, _ = driver(served, tmp_path, setup)
    args = ["calibrate", "--rig", str(rig), "--position", "0,0,16", "--x0", "2,-1"]
    args += ["--method", "model-based", "--budget", "200", "--no-plots", "--out", "cal"]
    monkeypatch.chdir(tmp_path)

    with instrument:
        code, _, err = run_until_signal(served, name, args, capsys, monkeypatch)
    assert code == EXIT[name], err
    assert "Traceback" not in err
    log = json.loads((tmp_path / "cal" / "partial_log.json").read_text())
    said = {"SIGINT": "interrupted (Ctrl-C)"}.get(name, f"terminated by {name}")
    assert log["status"] == "interrupted" and log["error"] == said
    delivered = len(served.samples)
    # the signal waits for the measurement in flight: every A-scan delivered is kept
    assert log["n_measurements"] == delivered == len(log["values"]) >= STOP_AFTER


CALIBRATE = ["--position", "0,0,16", "--x0", "2,-1", "--method", "model-based"]
CALIBRATE += ["--budget", "200", "--no-plots", "--json"]


def _calibrate(served: Served, driver: Any, folder: Path, setup: Path, capsys, monkeypatch):
    """An uninterrupted ``calibrate --rig`` on ``served`` behind ``driver``: (exit code,
    result.json)."""
    folder.mkdir()
    instrument, rig, _ = driver(served, folder, setup)
    with instrument:
        code, _, err = run_main(
            ["calibrate", "--rig", str(rig), *CALIBRATE, "--out", str(folder / "cal")],
            capsys,
            monkeypatch,
        )
    assert code in (0, 3), err
    return code, json.loads((folder / "cal" / "result.json").read_text())


RESUME_CASES = [
    pytest.param(
        name,
        driver,
        id=f"{name}-{label}",
        # SIGTERM on the python driver in the fast tier (3 s); all nine: about 90 s
        marks=() if (name, label) == ("SIGTERM", "python") else pytest.mark.slow,
    )
    for name in EXIT
    for driver, label in ((_tcp, "tcp"), (_visa, "visa"), (_python, "python"))
]


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")
@pytest.mark.parametrize(("name", "driver"), RESUME_CASES)
def test_calibrate_on_a_rig_resumes_after_a_signal_with_nothing_measured_twice(
    name, driver, tmp_path, capsys, monkeypatch
):
    """``calibrate --rig`` stopped by each signal on each driver, then run again: it
    resumes from the saved A-scans, the rig serves every A-scan once (the runs together
    serve exactly the uninterrupted run's A-scans), and the result is the uninterrupted
    run's, measurement for measurement."""
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    reference = Served(load_setup(setup))  # the same simulator, seed and noise stream
    ref_code, expected = _calibrate(
        reference, driver, tmp_path / f"{tmp_path.name}_ref", setup, capsys, monkeypatch
    )
    served = Served(load_setup(setup))
    folder = tmp_path / f"{tmp_path.name}_run"
    folder.mkdir()
    instrument, rig, _ = driver(served, folder, setup)
    out = folder / "cal"
    args = ["calibrate", "--rig", str(rig), *CALIBRATE, "--out", str(out)]

    with instrument:
        code, _, err = run_until_signal(served, name, args, capsys, monkeypatch)
        first = len(served.samples)
        assert code == EXIT[name], err
        assert "Traceback" not in err and "run the same command again to resume" in flat(err)
        log = json.loads((out / "partial_log.json").read_text())
        # every A-scan the rig delivered is kept, the one in flight at the signal too
        assert log["n_measurements"] == first >= STOP_AFTER
        assert len(list((out / "partial_ascans").glob("*.npz"))) == first
        code, stdout, err = run_main(args, capsys, monkeypatch)
    assert code == ref_code, err
    assert f"resuming: {first} measurements" in flat(err)
    # the rig served no A-scan twice: both runs together served the uninterrupted run's
    assert len(served.samples) == len(reference.samples) > first
    for got, sent in zip(served.samples, reference.samples, strict=True):
        np.testing.assert_array_equal(got, sent)
    result = json.loads((out / "result.json").read_text())
    for key in ("x", "n_measurements", "status", "success", "values", "points", "message"):
        assert result[key] == expected[key], key
    said = json.loads(stdout)
    now = len(served.samples) - first
    assert said["resumed"] == {"measurements_from_log": first, "measured_now": now}
    assert result["provenance"]["resumed"] == said["resumed"]
    assert not (out / "partial_log.json").exists() and not (out / "partial_ascans").exists()
