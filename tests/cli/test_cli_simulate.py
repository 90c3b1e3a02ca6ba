"""``echocal simulate``: ToF, distance and pseudo-energy of one A-scan, saved as CSV or NetCDF."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from typer.testing import CliRunner

from echocal.cli import app

runner = CliRunner()


def run(*args):
    result = runner.invoke(app, ["simulate", *args])
    assert result.exit_code == 0, result.output
    return result


def test_json_reports_time_of_flight_matching_the_geometry(tmp_path):
    # Straight down onto the flat plate from 20 mm, noiseless: τ = 2·20 mm / 1480 m/s.
    out = run(
        "--pose",
        "0,0,20",
        "--specimen",
        "flat-plate",
        "--snr",
        "none",
        "--json",
        "--out",
        str(tmp_path),
    )
    summary = json.loads(out.stdout)
    assert summary["tof_s"] == pytest.approx(2 * 0.02 / 1480.0, abs=0.05 / 20e6)
    assert summary["distance_m"] == pytest.approx(0.02, abs=1e-5)
    assert summary["pseudo_energy"] > 0
    data = np.loadtxt(tmp_path / "ascan.csv", delimiter=",", comments="#", skiprows=2)
    assert data.shape[1] == 2 and np.all(np.diff(data[:, 0]) > 0)
    assert (tmp_path / "ascan.png").exists() and (tmp_path / "ascan.svg").exists()


def test_netcdf_output_has_units(tmp_path):
    run("--pose", "0,0,20", "--format", "nc", "--out", str(tmp_path))
    with xr.open_dataset(tmp_path / "ascan.nc", engine="h5netcdf") as ds:
        assert ds["time"].attrs["units"] == "s"
        assert ds.attrs["echocal_format"] == "ascan/2"
        assert ds.attrs["Conventions"] == "CF-1.10"
        assert json.loads(ds.attrs["summary"])["setup"] == "thesis"


def test_same_seed_same_ascan(tmp_path):
    run("--pose", "0,0,20", "--seed", "4", "--out", str(tmp_path / "a"))
    run("--pose", "0,0,20", "--seed", "4", "--out", str(tmp_path / "b"))
    assert (tmp_path / "a/ascan.csv").read_text() == (tmp_path / "b/ascan.csv").read_text()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--pose", "0,0,20", "--snr", "nan"], "--snr must be finite"),
        (["--pose", "0,0,20", "--setup", "nowhere"], "unknown setup"),
        (["--pose", "0,0,20", "--format", "xlsx"], "--format must be csv or nc"),
        (["--pose", "0,0,20MHz"], "not a length unit"),
        (["--pose", "0,0,20", "--gate", "500,1"], "outside the recording window"),
    ],
)
def test_bad_input_is_named(tmp_path, args, message):
    result = runner.invoke(app, ["simulate", *args, "--out", str(tmp_path)])
    assert result.exit_code != 0
    assert message in result.output + str(result.exception)


def test_gate_restricts_the_time_of_flight(tmp_path):
    # Noiseless flat plate from 20 mm: the echo is at 2·20 mm / 1480 m/s ≈ 27.03 µs.  A gate
    # [27.2, 30.2] µs holds only its tail, so the reported time of flight must lie inside the
    # gate.  (A gate holding no echo at all is refused: test_cli_simulate_no_echo.py.)
    summary = json.loads(
        run(
            *("--pose", "0,0,20", "--specimen", "flat-plate", "--snr", "none", "--json"),
            *("--gate", "27.2,3", "--out", str(tmp_path)),
        ).stdout
    )
    assert 27.2e-6 <= summary["tof_s"] <= 30.2e-6
    assert summary["gate_s"] == pytest.approx([27.2e-6, 3e-6])


def test_json_is_strict_when_nothing_returns(tmp_path):
    # Far off the sphere, noiseless: an all-zero A-scan has no time of flight (NaN) and an
    # energy of −inf dB; strict JSON has neither, so both must come out as null.
    out = run(
        *("--pose", "40,40,20", "--specimen", "sphere", "--snr", "none", "--json"),
        *("--out", str(tmp_path)),
    )

    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")

    summary = json.loads(out.stdout, parse_constant=refuse)
    assert summary["tof_s"] is None and summary["energy_db"] is None
    assert summary["pseudo_energy"] == 0.0
