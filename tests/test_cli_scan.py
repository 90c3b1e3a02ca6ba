"""``echocal scan``: a tiny raster end to end — summary, NetCDF, figures, errors."""

from __future__ import annotations

import json

import pytest
import typer
from typer.testing import CliRunner

from echocal.cli import app
from echocal.cli.scan import parse_grid
from echocal.scanning import SurfaceScan

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
