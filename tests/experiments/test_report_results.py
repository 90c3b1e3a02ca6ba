"""`echocal report` on the folders of `echocal calibrate --out` and `echocal scan --out`."""

from __future__ import annotations

import base64
import json
import re

import pandas as pd
import pytest
from typer.testing import CliRunner

from echocal.cli import app
from echocal.experiments._report_html import fmt, header, table
from echocal.experiments.report import folder_kind

runner = CliRunner()


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    root = tmp_path_factory.mktemp("results")
    calibrate = [
        "calibrate", "--setup", "immersion-5mhz", "--x0", "0.5,-0.3", "--seed", "2",
        "--out", str(root / "cal"),
    ]  # fmt: skip
    done = runner.invoke(app, calibrate)
    assert done.exit_code == 0, done.output
    scan = [
        "scan", "--setup", "scan-5mhz", "--specimen", "sphere", "--grid", "-3:3:3,0:3:3",
        "--seed", "1", "--out", str(root / "scan"), "--no-progress",
    ]  # fmt: skip
    done = runner.invoke(app, scan)
    assert done.exit_code == 0, done.output
    return root


def _images(section: str) -> list[bytes]:
    return [base64.b64decode(m) for m in re.findall(r"base64,([A-Za-z0-9+/=]+)", section)]


def test_cli_report_renders_a_calibration_and_a_scan_folder(folders, tmp_path):
    cal, scan = folders / "cal", folders / "scan"
    assert [folder_kind(cal), folder_kind(scan)] == ["calibration", "scan"]
    out = tmp_path / "r.html"
    done = runner.invoke(app, ["report", str(cal), str(scan), "--out", str(out)])
    assert done.exit_code == 0, done.output
    page = out.read_text(encoding="utf-8")
    assert not re.search(r"""(src|href)=["']https?://""", page) and "<script" not in page
    cal_part, scan_part = page.split('<h2 id="s1">')
    # the calibration: its three figures embedded byte for byte, and its provenance
    images = _images(cal_part)
    for name in ("ascan.png", "path.png", "convergence.png"):
        assert (cal / name).read_bytes() in images
    assert "setup immersion-5mhz, replay" not in cal_part  # options not given are left out
    assert "setup immersion-5mhz, method auto, x0 0.5,-0.3," in cal_part
    assert "immersion-5mhz (sha256 " in cal_part and "provenance" in cal_part
    assert "search beyond the first ring" in cal_part  # found near x0: none
    # what was calibrated, the simulator's truth and the error, as the command printed them
    summary = json.loads((cal / "summary.json").read_text(encoding="utf-8"))
    assert "setup</td><td>immersion-5mhz: " in cal_part
    pairs = zip(summary["names"], summary["truth_deg"], strict=True)
    truth = ", ".join(f"{n} {v:.4f}°" for n, v in pairs)
    assert f"true optimum</td><td>{truth}<" in cal_part
    assert f"error [°]</td><td>{summary['error_deg']:.4f}<" in cal_part
    # the scan: its maps and its 3-D view
    images = _images(scan_part)
    for name in ("height", "normals", "errors", "measurements", "surface-3d"):
        assert (scan / f"{name}.png").read_bytes() in images
    assert "6 of 6 points found" in page
    text = re.sub(r"base64,[A-Za-z0-9+/=]+", "", page)
    assert "None" not in text and not re.search(r"\bnan\b", text, re.IGNORECASE)
    # provenance on both pages, read as text: no Python literals (True, [0.0, 0.05])
    assert "provenance" in scan_part and "scan-5mhz (sha256 " in scan_part
    assert "budget per point</td><td>80" in scan_part
    cells = re.findall(r"<td>(.*?)</td>", text)
    assert not [c for c in cells if re.search(r"\bTrue\b|\bFalse\b|\[-?\d", c)], cells
    assert "position [mm]</td><td>0, 0, 50<" in cal_part


def test_a_scan_folder_without_figures_is_drawn_from_its_netcdf(folders, tmp_path):
    import shutil

    bare = tmp_path / "bare"
    bare.mkdir()
    shutil.copy(folders / "scan" / "scan.nc", bare / "scan.nc")
    out = tmp_path / "r.html"
    assert runner.invoke(app, ["report", str(bare), "--out", str(out)]).exit_code == 0
    page = out.read_text(encoding="utf-8")
    assert page.count("data:image/png;base64,") == 5  # height, normals, errors, counts, 3-D
    assert not list(bare.glob("*.png"))  # the report draws; it writes nothing beside


def test_tables_have_human_headers_one_never_and_percentages():
    frame = pd.DataFrame(
        {
            "label": ["a", "b"],
            "preset": [None, "thesis"],
            "success_rate": [0.6, 1.0],
            "measurements_to_0.1deg": pd.array([12, None], dtype="Int64"),
            "expected_measurements_to_success": [20.5, float("inf")],
            "median_error_deg": [0.04, float("nan")],
        }
    )
    html = table(frame)
    heads = re.findall(r"<th>(.*?)</th>", html)
    assert heads == [
        "configuration", "preset", "success rate", "measurements to 0.1°",
        "expected measurements to success", "median error [°]",
    ]  # fmt: skip
    cells = re.findall(r"<td>(.*?)</td>", html)
    assert cells == ["a", "default", "60 %", "12", "20.5", "0.04",
                     "b", "thesis", "100 %", "never", "never", "–"]  # fmt: skip
    assert 'class="table-wrap"' in html  # a scroll container: never off the page
    assert header("normal_error_deg") == "normal error [°]" and header("snr_db") == "SNR [dB]"
    assert fmt(None, "iterations_to_90pct") == "never" and fmt(float("inf")) == "never"


def test_the_searched_passes_say_what_echo_they_were_sized_for():
    from echocal.experiments._report_results import _passes

    assert _passes([1.333], 10.04) == "1.33° (for an echo predicted at 10.0 dB)"
    assert _passes([8.614, 4.17]) == "8.61°, 4.17°"  # a result written before ŝ was kept
    assert _passes(None, None).startswith("– (the planned search was kept)")
