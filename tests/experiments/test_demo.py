"""The main job: Table 7 + a short sweep → one report (quick mode end to end)."""

from __future__ import annotations

import io
import json

import pytest
from rich.console import Console
from typer.testing import CliRunner

from echocal.cli import app
from echocal.errors import DataFileError
from echocal.experiments.demo import run_demo


def test_demo_quick_end_to_end(tmp_path):
    out = tmp_path / "demo"
    printed = io.StringIO()
    console = Console(file=printed, width=120, color_system=None)
    result = run_demo(out, quick=True, progress=True, console=console)
    page = result.report.read_text()
    assert result.report == out / "report.html"
    assert "table-7: all methods compared" in page and "sweep quick-reduced" in page
    meta = json.loads((out / "table-7" / "findings.json").read_text())
    assert [f["group"] for f in meta["findings"]] == [
        "thesis presets (Table 7)",
        "echocal automatic gains",
    ]
    # every verdict that does not agree says why, in the file, the page and the console
    lines = printed.getvalue().splitlines()
    disagree = [f for f in meta["findings"] if not f["agrees"]]
    assert all(f["why"] for f in disagree)
    for f in disagree:
        assert f"why: {f['why']}" in page.replace("&#x27;", "'")
    for i, line in enumerate(lines):
        if "not reproduced here" in line:
            assert lines[i + 1].strip().startswith("why:"), lines[i : i + 2]
    # the summary leads with the calibration study, echocal's own methods first, and
    # only then the thesis's findings; no verdict is worded as a failure of echocal
    study = next(i for i, line in enumerate(lines) if line.startswith("What echocal finds"))
    thesis = next(i for i, line in enumerate(lines) if line.startswith("The thesis's Table 7"))
    assert study < thesis and "does not agree" not in printed.getvalue()
    rows = [line.split()[0] for line in lines[study + 1 : thesis] if " dB  success" in line]
    assert rows[:4] == ["auto", "auto", "model-based", "model-based"], rows
    # the sweep's lines use the report's words and percentages: "never", "40 %"; a row
    # that missed the tolerance says where its runs ended and why
    sweep_lines = [line for line in lines if " dB  success" in line]
    assert sweep_lines and not [
        line for line in sweep_lines if "—" in line or "%" in line.replace(" %", "")
    ]
    for line in sweep_lines:
        ok, n = line.split("success ")[1].split()[0].split("/")
        assert (ok != n) == ("from the optimum" in line), line
    # ... and the last thing printed is where the report is
    assert lines[-1].startswith(f"report: {(out / 'report.html').resolve()}")
    # the sweep summary covers every configuration of quick.toml: 4 methods x 2 SNRs
    assert len(result.sweep_summary) == 8
    # an existing demo folder is never overwritten silently (Python and CLI)
    with pytest.raises(DataFileError, match="already holds results"):
        run_demo(out, quick=True, progress=False)
    res = CliRunner().invoke(app, ["demo", "--quick", "--out", str(out)])
    assert isinstance(res.exception, DataFileError)
