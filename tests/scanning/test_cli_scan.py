"""``echocal scan``: a tiny raster end to end — summary, NetCDF, figures, errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import typer
import xarray as xr
from typer.testing import CliRunner

import echocal.scanning.scan as scan_module
from cli_helpers import (
    SPHERE_UNDER_REFERENCE,
    TINY_PLATE,
    flat,
    run_main,
    tiny_setup_file,
)
from cli_helpers import flat as _flat
from echocal.cli import app
from echocal.cli.scan import parse_grid
from echocal.errors import LimitError
from echocal.geometry import Pose
from echocal.scanning import STATUS, ScanGrid, SurfaceScan, check_scan, scan_surface
from echocal.setups import load_setup

runner = CliRunner()


def test_parse_grid_reads_millimetres_unless_a_unit_is_given():
    (x0, x1, dx), (y0, y1, dy) = parse_grid("-2:2:1,0cm:1cm:5mm")
    assert (x0, x1, dx) == pytest.approx((-2e-3, 2e-3, 1e-3))
    assert (y0, y1, dy) == pytest.approx((0.0, 0.01, 0.005))
    with pytest.raises(typer.BadParameter, match="--grid"):
        parse_grid("0:1:1")


def test_scan_writes_netcdf_figures_and_a_json_summary(tmp_path):
    out = tmp_path / "run"
    result = runner.invoke(
        app,
        [
            "scan", "--setup", "scan-5mhz", "--specimen", "cylinder",
            "--grid", "-2:2:2,0:0:1", "--z", "25", "--seed", "3",
            "--cold", "--out", str(out), "--no-progress", "--json",
        ],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout.strip().splitlines()[-1])
    scan = report["scan"]
    assert scan["points"] == 3 and scan["found"] == 3
    # the targets on the cylinder at the setup's 30 dB
    assert scan["normal_error_deg"]["median"] <= 0.1
    assert scan["height_error_abs_m"]["median"] <= 0.05e-3
    assert report["cold"]["measurements_total"] > 0
    assert report["cold_over_warm_measurements"] == pytest.approx(
        report["cold"]["measurements_total"] / scan["measurements_total"]
    )
    saved = SurfaceScan.load(out / "scan.nc")
    assert saved.summary == scan
    assert saved.dataset["surface_z"].attrs["units"] == "m"
    for name in ("height", "normals", "errors", "measurements", "surface-3d"):
        assert (out / f"{name}.png").stat().st_size > 0
        assert (out / f"{name}.svg").exists()


def test_a_bad_grid_is_a_usage_error(tmp_path):
    result = runner.invoke(
        app, ["scan", "--setup", "scan-5mhz", "--grid", "1:2", "--out", str(tmp_path)]
    )
    assert result.exit_code == 2
    assert "--grid" in result.output


MM = 1e-3


BASE = ["scan", "--setup", "scan-5mhz", "--specimen", "sphere", "--no-figures", "--no-progress"]


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        (["--method", "nosuch"], "unknown method 'nosuch'"),
        (["--seed", "-1"], "--seed"),
        (["--snr", "abc"], "--snr must be a number"),
        # scan-5mhz's positioner: z in [5, 100] mm
        (["--z", "-5"], "z=-5 mm is outside the positioner's z limits [5, 100] mm"),
        # auto needs 7 measurements for its first iteration, plus 2 for the time of flight
        (["--budget-per-point", "3"], "budget_per_point >= 9"),
        (["--budget-per-point", "8"], "budget_per_point >= 9"),
        (["--method", "grid", "--budget-per-point", "22"], "budget_per_point >= 23"),
        (["--grid", "70:80:10,0:0:1"], "no grid point lies within the positioner's limits"),
    ],
)
def test_whole_run_mistakes_are_refused_before_any_output(
    tmp_path, capsys, monkeypatch, options, expected
):
    out = tmp_path / "out"
    args = [*BASE, "--grid", "0:0:1,0:0:1", "--out", str(out), *options]
    code, stdout, err = run_main(args, capsys, monkeypatch)
    assert code == 2
    assert expected in _flat(err) and "Traceback" not in err
    assert stdout == ""
    assert not out.exists()


def test_the_budget_minimum_is_the_methods_real_need():
    # at the stated minimum nothing is refused and no point fails for lack of budget to
    # even start: the calibration gets its one iteration and the time of flight its two
    setup = load_setup("scan-5mhz", seed=0)
    grid = ScanGrid.regular(x=(0.0, 0.0, MM), y=(0.0, 0.0, MM), z=25 * MM)
    check_scan(setup, grid, method="auto", budget_per_point=9)
    scan = scan_surface(setup, grid, budget_per_point=9, rng=0, progress=False)
    assert int(scan.dataset["status"].values[0, 0]) != STATUS["source-error"]
    assert 7 <= int(scan.dataset["n_measurements"].values[0, 0]) <= 9


def test_two_runs_without_seed_are_identical_and_use_the_setup_seed(tmp_path, capsys, monkeypatch):
    grid = ["--grid", "-3:3:3,0:0:1"]
    runs = {}
    for name, extra in (("a", []), ("b", []), ("seed0", ["--seed", "0"])):  # scan-5mhz: seed = 0
        code, stdout, err = run_main(
            [*BASE, *grid, "--out", str(tmp_path / name), "--json", *extra], capsys, monkeypatch
        )
        assert code == 0, err
        runs[name] = json.loads(stdout)["scan"]
    assert runs["a"] == runs["b"] == runs["seed0"]
    datasets = [SurfaceScan.load(tmp_path / n / "scan.nc").dataset for n in ("a", "b", "seed0")]
    for ds in datasets[1:]:
        for name in ("tilt_x", "tilt_y", "tof", "n_measurements"):
            np.testing.assert_array_equal(ds[name].values, datasets[0][name].values)
    assert datasets[0].attrs["seed"] == 0


def test_a_finished_scan_is_kept_refused_or_replaced(tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    first = [*BASE, "--grid", "0:0:1,0:0:1", "--out", str(out), "--seed", "1"]
    assert run_main(first, capsys, monkeypatch)[0] == 0
    stored = (out / "scan.nc").read_bytes()
    calls = []
    original = scan_module._measure_point

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(scan_module, "_measure_point", counting)
    # the same scan again: reported, not measured again
    code, _, err = run_main(first, capsys, monkeypatch)
    assert code == 0 and "already holds this scan" in _flat(err) and calls == []
    # another grid: refused, the stored scan untouched
    other = [*BASE, "--grid", "-3:3:3,0:0:1", "--out", str(out), "--seed", "1"]
    code, _, err = run_main(other, capsys, monkeypatch)
    assert code == 2 and "other settings (grid)" in _flat(err) and "--overwrite" in err
    assert (out / "scan.nc").read_bytes() == stored and calls == []
    # --overwrite replaces it
    code, _, err = run_main([*other, "--overwrite"], capsys, monkeypatch)
    assert code == 0, err
    assert SurfaceScan.load(out / "scan.nc").summary["points"] == 3


def test_refusing_to_resume_says_nothing_about_resuming(tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    original = scan_module._measure_point
    calls = []

    def interrupted(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(*args, **kwargs)

    monkeypatch.setattr(scan_module, "_measure_point", interrupted)
    args = [*BASE, "--grid", "-3:3:3,0:0:1", "--out", str(out)]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 130 and (out / "scan.nc.partial").is_dir()
    monkeypatch.setattr(scan_module, "_measure_point", original)
    code, _, err = run_main(
        [*BASE, "--grid", "-3:3:3,-3:0:3", "--out", str(out)], capsys, monkeypatch
    )
    assert code == 2
    assert "different unfinished scan (other grid)" in _flat(err)
    assert "resuming" not in err
    code, _, err = run_main(args, capsys, monkeypatch)  # the same scan resumes, and says so
    assert code == 0, err
    assert "resuming" in err and "1 point(s) already saved" in _flat(err)


def test_missing_points_keep_their_message(tmp_path):
    # x = 70 mm lies beyond the positioner (x in [-60, 60] mm): that point alone fails;
    # x = 0 is over the ball's top, where the calibration is short (at x = 50 mm, past the
    # ball, it searched its whole budget: 30 CPU-s of this test's 31)
    setup = load_setup("scan-5mhz", seed=0)
    grid = ScanGrid.regular(x=(0.0, 70 * MM, 70 * MM), y=(0.0, 0.0, MM), z=25 * MM)
    scan = scan_surface(setup, grid, rng=0, progress=False, out=tmp_path / "s.nc")
    with xr.open_dataset(tmp_path / "s.nc", engine="h5netcdf") as ds:
        status, message = ds["status"].values[0], ds["message"].values[0]
    assert status[1] == STATUS["source-error"]
    # the stored message is the positioner's own refusal of that position
    with pytest.raises(LimitError) as refusal:
        setup.limits.check(Pose(0.07, 0.0, 0.025, 0.0, 0.0))
    assert str(refusal.value) in str(message[1])
    assert status[0] == 0 and message[0] == ""  # the point over the top is found
    assert scan.summary["missing_messages"]["source-error"] == str(message[1])


def test_a_point_stopped_by_the_budget_is_unconverged_not_found():
    # the grid method's 21 x 21 nodes do not fit in 60 measurements: it stops on the
    # budget (calibrate status 2) having searched three rows; that is no estimate
    setup = load_setup("scan-5mhz", seed=0)
    grid = ScanGrid.regular(x=(0.0, 0.0, MM), y=(0.0, 0.0, MM), z=25 * MM)
    with pytest.warns(UserWarning, match="only part of it will be searched"):
        scan = scan_surface(setup, grid, method="grid", budget_per_point=60, rng=0, progress=False)
    ds = scan.dataset
    assert int(ds["status"].values[0, 0]) == STATUS["unconverged"]
    assert "measurement budget exhausted" in str(ds["message"].values[0, 0])
    assert np.isnan(ds["tilt_x"].values[0, 0])  # missing, not guessed
    assert scan.summary["missing_by_status"] == {"unconverged": 1}


def _scan(setup: Path, out: Path, z: str, *extra: str) -> list[str]:
    return [
        "scan", "--setup", str(setup), "--grid", "-1:1:1,-1:1:1", "--z", z, "--out", str(out),
        "--no-progress", *extra,
    ]  # fmt: skip


@pytest.mark.parametrize(
    ("specimen", "ref_z", "z", "expected"),
    [
        (TINY_PLATE, "16 mm", "40", "cannot contain any echo"),
        (SPHERE_UNDER_REFERENCE, "26 mm", "5", "inside sphere"),
    ],
)
def test_scan_refuses_a_run_where_every_point_fails(
    tmp_path, capsys, monkeypatch, specimen, ref_z, z, expected
):
    setup = tiny_setup_file(tmp_path, specimen, ref_z)
    out = tmp_path / "scan"
    code, _, err = run_main(_scan(setup, out, z), capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    assert expected in flat(err) and "every grid point would fail (9 of 9)" in flat(err)
    assert not out.exists()  # nothing written


def test_a_scan_that_finds_nothing_prints_no_numpy_warnings(tmp_path, capsys, monkeypatch):
    setup = tiny_setup_file(tmp_path)
    out = tmp_path / "scan"
    # 9 measurements per point: one auto iteration + 2 time-of-flight A-scans, never converged
    code, _, err = run_main(_scan(setup, out, "16", "--budget-per-point", "9"), capsys, monkeypatch)
    assert code == 0, err
    assert "0 found" in err  # the case of the defect: nothing found, summaries of nothing
    assert "Mean of empty slice" not in err and "invalid value" not in err
    assert "warning" not in err.lower()


def test_the_cli_checks_a_scan_once(tmp_path, capsys, monkeypatch):
    """``echocal scan`` refuses a bad scan before it creates --out, and hands its check's
    result to scan_surface, which does not check again (with --cold: once, not three
    times)."""
    import echocal.scanning as scanning

    calls = []

    def counting(*args, **kwargs):
        calls.append(1)
        return check_scan(*args, **kwargs)

    monkeypatch.setattr(scanning, "check_scan", counting)
    monkeypatch.setattr(scan_module, "check_scan", counting)
    out = tmp_path / "out"
    argv = [*BASE, "--grid", "0:0:1,0:0:1", "--out", str(out), "--seed", "1", "--cold"]
    assert run_main(argv, capsys, monkeypatch)[0] == 0
    assert (out / "scan.nc").exists() and len(calls) == 1
    # the API alone still checks
    calls.clear()
    setup = load_setup("scan-5mhz", seed=1)
    with pytest.raises(LimitError):
        scan_surface(setup, ScanGrid(x=(0.0,), y=(0.0,), z=1.0), progress=False)
    assert len(calls) == 1
