"""``echocal setup``, ``echocal record`` and ``echocal instrument-server``.

Happy paths go through typer's CliRunner; error paths through ``echocal.cli.main``
(the console-script entry point, whose ``run_cli`` turns echocal errors into one
line and exit code 2) so that "no traceback" is what is tested.  The server runs
as a real subprocess on a free port and is stopped with SIGINT, like Ctrl-C.
"""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from typer.testing import CliRunner

from cli_helpers import run_main, tiny_setup_toml
from echocal.cli import app
from echocal.geometry import Pose
from echocal.measurement import HardwareSource, ReplaySource, VirtualSetup
from echocal.setups import builtin_setup_names, load_setup, load_setup_config

runner = CliRunner()

# Five problems, each in a different field (one of them an unknown key).
BAD = """
name = "bad"
colour = "red"
[transducer]
width = -0.01
n_h = 0
pinhole_distance = "20 kg"
[window]
n_samples = 4
"""


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml(), encoding="utf-8")
    return path


def assert_clean_error(err: str) -> None:
    """One error message, no traceback."""
    assert "Traceback" not in err
    assert err.strip(), "an error must say something"


# -- setup --------------------------------------------------------------------------------
def test_setup_list_names_every_builtin_with_its_description() -> None:
    result = runner.invoke(app, ["setup", "list"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.strip().splitlines()
    assert len(lines) == len(builtin_setup_names())
    for name, line in zip(builtin_setup_names(), lines, strict=True):
        assert line.split()[0] == name
        assert line.endswith(load_setup_config(name)[0].description)
    data = json.loads(runner.invoke(app, ["setup", "list", "--json"]).stdout)
    assert set(data["setups"]) == set(builtin_setup_names()) >= {"thesis", "immersion-5mhz"}


def test_setup_show_prints_toml_that_loads_back_to_the_same_setup(tmp_path: Path) -> None:
    result = runner.invoke(app, ["setup", "show", "thesis"])
    assert result.exit_code == 0, result.output
    original = load_setup("thesis")
    assert result.stdout.splitlines()[0] == f"# {original.description}"
    shown = tomllib.loads(result.stdout)
    # SI values: "4 mm", "20 us", "1 MHz" in the built-in file
    assert shown["transducer"]["width"] == 0.004
    assert shown["window"]["start"] == pytest.approx(20e-6, rel=1e-15)  # 15 digits printed
    assert shown["pulse"]["center_frequency"] == 1e6
    assert shown["positioner"]["x"] == [-0.04, 0.04]
    copy = tmp_path / "copy.toml"
    copy.write_text(result.stdout, encoding="utf-8")
    again = load_setup(copy)
    assert again.description == original.description
    # values are printed to 15 significant digits (2e-05, not 1.9999999999999998e-05):
    # a round trip is exact to 1 ulp
    assert (again.window.fs, again.window.n_samples) == (original.window.fs, 1024)
    assert again.window.start == pytest.approx(original.window.start, rel=1e-15)
    assert again.pulse.parameters() == original.pulse.parameters()
    assert again.limits == original.limits
    np.testing.assert_array_equal(again.reference_position, original.reference_position)


def test_setup_show_json_has_si_values_and_null_for_unlimited(tiny: Path) -> None:
    result = runner.invoke(app, ["setup", "show", str(tiny), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["description"] == load_setup(tiny).description
    config = data["config"]
    assert config["window"] == {"fs": 50e6, "start": pytest.approx(20e-6), "n_samples": 256}
    assert config["transducer"]["n_v"] == 8  # resolved: defaults to n_h
    assert config["positioner"]["x"] == [None, None]  # unlimited (inf) -> null
    assert config["positioner"]["z"] == pytest.approx([0.01, 0.04])


def test_setup_validate_reports_every_problem_with_its_field(
    tmp_path: Path, tiny: Path, capsys: pytest.CaptureFixture[str], monkeypatch
) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(BAD, encoding="utf-8")
    code, out, err = run_main(["setup", "validate", str(bad)], capsys, monkeypatch)
    assert code == 1
    fields = sorted(line.split(":")[0] for line in out.strip().splitlines())
    assert fields == [
        "colour",
        "transducer.n_h",
        "transducer.pinhole_distance",
        "transducer.width",
        "window.n_samples",
    ]
    assert "5 problem(s)" in err
    code, out, _ = run_main(["setup", "validate", str(tiny)], capsys, monkeypatch)
    assert (code, out) == (0, "valid\n")
    code, out, _ = run_main(["setup", "validate", str(tmp_path / "gone.toml")], capsys, monkeypatch)
    assert code == 1 and "not found" in out
    code, out, _ = run_main(["setup", "validate", str(bad), "--json"], capsys, monkeypatch)
    assert code == 1 and len(json.loads(out)["problems"]) == 5


def test_setup_show_unknown_name_lists_the_builtins(capsys, monkeypatch) -> None:
    code, _, err = run_main(["setup", "show", "thesys"], capsys, monkeypatch)
    assert code == 2
    assert_clean_error(err)
    assert "thesys" in err and "thesis" in err and "immersion-5mhz" in err


# -- record -------------------------------------------------------------------------------
GRID = ["--azimuth", "-20:20:3", "--coelevation", "0:10:3"]


def test_record_writes_a_replay_file_of_the_grid(tiny: Path, tmp_path: Path) -> None:
    out = tmp_path / "rec.nc"
    args = ["record", "--setup", str(tiny), "--out", str(out), *GRID]
    args += ["--position", "0,0,16", "--position", "2mm,1,1.8cm", "--repeats", "2"]
    result = runner.invoke(app, [*args, "--snr", "none", "--no-progress", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["n_ascans"] == 2 * 3 * 3 * 2
    assert summary["resumed_after"] == 0
    with ReplaySource.open(out) as replay:
        np.testing.assert_array_equal(replay.azimuths, [-20.0, 0.0, 20.0])
        np.testing.assert_array_equal(replay.coelevations, [0.0, 5.0, 10.0])
        # mm by default, units honoured
        np.testing.assert_allclose(replay.positions, [[0, 0, 0.016], [0.002, 0.001, 0.018]])
        assert replay.n_repeats == 2
        assert replay.source_info["setup"]["config"]["name"] == "tiny"
        pose = Pose(0.002, 0.001, 0.018, 20.0, 5.0)
        got = replay.measure(pose).samples
    # independent truth: the noiseless simulation of the same setup at that pose
    want = load_setup(tiny).simulate([pose], noise=False)[0]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--azimuth", "-10:10", "--coelevation", "0"], "--azimuth takes FIRST:LAST:COUNT"),
        (["--azimuth", "0", "--coelevation", "0:10:many"], "--coelevation takes"),
        (["--azimuth", "10:-10:3", "--coelevation", "0"], "LAST must be greater"),
        (["--azimuth", "0:1:0", "--coelevation", "0"], "COUNT must be >= 1"),
        (["--azimuth", "0", "--coelevation", "0", "--position", "1,2"], "--position takes"),
        (["--azimuth", "0", "--coelevation", "0:90:3"], "outside [-30, 30]"),
    ],
)
def test_record_bad_grid_is_a_one_line_error(
    tiny: Path, tmp_path: Path, args: list[str], expected: str, capsys, monkeypatch
) -> None:
    base = ["record", "--setup", str(tiny), "--out", str(tmp_path / "x.nc"), "--no-progress"]
    code, _, err = run_main([*base, *args], capsys, monkeypatch)
    assert code == 2
    assert_clean_error(err)
    assert expected in " ".join(re.sub(r"[│╭╮╰╯─]", " ", err).split())
    assert not (tmp_path / "x.nc").exists()


def test_record_unknown_setup_and_existing_file(tiny: Path, tmp_path: Path, capsys, monkeypatch):
    out = tmp_path / "r.nc"
    code, _, err = run_main(
        ["record", "--setup", "nope", "--out", str(out), "--azimuth", "0", "--coelevation", "0"],
        capsys,
        monkeypatch,
    )
    assert code == 2 and "thesis" in err
    assert_clean_error(err)
    args = ["record", "--setup", str(tiny), "--out", str(out), *GRID, "--no-progress"]
    assert run_main(args, capsys, monkeypatch)[0] == 0
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 2 and "--overwrite" in err
    assert run_main([*args, "--overwrite"], capsys, monkeypatch)[0] == 0


def test_record_interrupted_then_resumed(tiny: Path, tmp_path: Path, capsys, monkeypatch):
    """Ctrl-C keeps the batches measured; the same command resumes without re-measuring."""
    calls = []
    original = VirtualSetup.measure_many

    def interrupted(self, poses):
        calls.append(len(poses))
        if len(calls) == 3:
            raise KeyboardInterrupt
        return original(self, poses)

    # one pose measured 12 times: with a naive restart of the noise generator, the resumed
    # measurements would repeat the noise of the first ones exactly
    out = tmp_path / "r.nc"
    args = ["record", "--setup", str(tiny), "--out", str(out), "--azimuth", "0"]
    args += ["--coelevation", "0", "--repeats", "12", "--batch-size", "4", "--no-progress"]
    monkeypatch.setattr(VirtualSetup, "measure_many", interrupted)
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 130
    assert "8 of 12 measurements are saved" in err and "run the same command again" in err
    assert not out.exists()
    monkeypatch.setattr(VirtualSetup, "measure_many", original)
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 0, err
    assert "resuming" in err and "8 of 12" in err and "resumed after 8" in err
    assert calls == [4, 4, 4]  # the resumed run went through the original: no more calls

    setup = load_setup(tiny)
    ideal = setup.simulate([Pose(0.0, 0.0, 0.016)], noise=False)[0]
    with xr.open_dataset(out, engine="h5netcdf") as ds:  # the replay/1 file format
        noise = ds["samples"].values[0, 0, 0] - ideal  # (repeat, time)
    first_run = setup.simulate([Pose(0.0, 0.0, 0.016)] * 8) - ideal
    np.testing.assert_allclose(noise[:8], first_run, atol=1e-12)  # saved part kept as measured
    for later in noise[8:]:  # re-seeded on resume: no noise vector repeats an earlier one
        assert not np.any(np.all(np.isclose(noise[:8], later, atol=1e-12), axis=1))


# -- instrument-server --------------------------------------------------------------------
def test_instrument_server_serves_the_setup_and_stops_on_ctrl_c(tiny: Path) -> None:
    command = [sys.executable, "-m", "echocal.cli", "instrument-server"]
    command += ["--setup", str(tiny), "--port", "0", "--seed", "9"]
    # a child inherits an ignored SIGINT (a test runner's worker started in the background
    # has SIGINT ignored), and Python then installs no Ctrl-C handler: the server never saw
    # the signal and the test hung.  Ctrl-C as a terminal sends it: the default handling.
    proc = subprocess.Popen(
        command,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        line = proc.stderr.readline()
        match = re.search(r"listening on (\S+):(\d+)", line)
        assert match, line
        pose = Pose(0.001, 0.0, 0.016, 10.0, 3.0)
        with HardwareSource.connect(match[1], int(match[2]), timeout=5.0) as source:
            assert "tiny" in source.description
            scan = source.measure(pose)
        # the same setup and seed, simulated here: the first noise draw is the same
        np.testing.assert_array_equal(scan.samples, load_setup(tiny, seed=9).measure(pose).samples)
    finally:
        proc.send_signal(signal.SIGINT)
        _, rest = proc.communicate(timeout=300)  # a hang, not a slow machine, exceeds it
    assert proc.returncode == 0
    assert "stopped" in rest and "Traceback" not in rest


def test_instrument_server_errors_are_one_line(tiny: Path, capsys, monkeypatch) -> None:
    import socket

    code, _, err = run_main(["instrument-server", "--setup", "nope"], capsys, monkeypatch)
    assert code == 2 and "thesis" in err
    assert_clean_error(err)
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        args = ["instrument-server", "--setup", str(tiny), "--port", str(port)]
        code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 2 and f"cannot listen on 127.0.0.1:{port}" in err
    assert_clean_error(err)
