"""The HTML report: one self-contained page with a section per results folder."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from echocal.cli import app
from echocal.errors import DataFileError
from echocal.experiments.demo import _sweep_spec
from echocal.experiments.execution import run_sweep
from echocal.experiments.report import folder_kind, write_report
from echocal.experiments.scenarios import run_scenario
from echocal.plots.sweep import success_ecdf_figure


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    root = tmp_path_factory.mktemp("report")
    run_scenario("scenario-1", root / "scenario-1", quick=True)
    run_scenario("table-6", root / "table-6", quick=True)
    run_sweep(_sweep_spec(quick=True), root / "sweep", progress=False, workers=1)
    return root


def test_report_is_one_self_contained_page(folders, tmp_path):
    dirs = [folders / "scenario-1", folders / "table-6", folders / "sweep"]
    assert [folder_kind(d) for d in dirs] == ["scenario", "scenario", "sweep"]
    out = write_report(dirs, tmp_path / "r.html")
    page = out.read_text()
    assert not re.search(r"""(src|href)=["']https?://""", page)  # no external assets
    assert "<link" not in page and "<script" not in page
    for title in ("scenario-1: A-scans", "table-6: quasi-Newton", "sweep quick-reduced"):
        assert title in page
    # scenario-1: 2 figures, table-6: 2 groups x 2 figures, sweep: 3 figures
    assert page.count("data:image/png;base64,") == 2 + 4 + 3
    assert "<th>success rate</th>" in page and "expected measurements to success" in page
    assert not re.search(r"<th>[^<]*_[^<]*</th>", page)  # human headers, no snake_case
    assert ">None<" not in page
    assert page.count('class="agree"') + page.count('class="disagree"') == 1 + 2


def test_non_result_folder_is_refused(tmp_path):
    (tmp_path / "junk").mkdir()
    with pytest.raises(DataFileError, match="holds no result echocal can report"):
        write_report([tmp_path / "junk"], tmp_path / "r.html")
    with pytest.raises(DataFileError, match="not found"):
        write_report([tmp_path / "missing"], tmp_path / "r.html")
    assert not (tmp_path / "r.html").exists()  # nothing written on error


def test_cli_report_refuses_to_overwrite(folders, tmp_path):
    runner = CliRunner()
    target = tmp_path / "r.html"
    ok = runner.invoke(app, ["report", str(folders / "scenario-1"), "--out", str(target)])
    assert ok.exit_code == 0 and target.is_file()
    again = runner.invoke(app, ["report", str(folders / "scenario-1"), "--out", str(target)])
    assert isinstance(again.exception, DataFileError)


def test_ecdf_ends_at_the_success_rate():
    runs = pd.DataFrame(
        {
            "label": ["a"] * 4,
            "snr_db": [30.0] * 4,
            "success": [True, True, False, True],
            "measurements_to_tol": pd.array([10, 30, None, 20], dtype="Int64"),
            "n_measurements": [50, 50, 50, 50],
        }
    )
    line = success_ecdf_figure(runs).axes[0].lines[0]
    x, y = line.get_data()
    # 3 of 4 runs succeed: the ECDF climbs 25 % at m = 10, 20, 30 and ends at 75 %
    np.testing.assert_allclose(y[-1], 75.0)
    np.testing.assert_allclose(np.asarray(y)[1:4], [25.0, 50.0, 75.0])
    np.testing.assert_allclose(np.asarray(x)[1:4], [10.0, 20.0, 30.0])


def test_sweep_figures_tell_configurations_apart_without_colour():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from echocal.plots.sweep import success_ecdf_figure, success_rate_figure

    rows = [
        {"label": f"m{k}", "snr_db": snr, "success": ok, "measurements_to_tol": 10.0 + k + i,
         "n_measurements": 40}
        for k in range(6)
        for snr in (30.0, 10.0)
        for i, ok in enumerate((True, True, False))
    ]  # fmt: skip
    runs = pd.DataFrame(rows)
    summary = pd.DataFrame(
        [{"label": f"m{k}", "snr_db": s, "success_rate": 2 / 3} for k in range(6) for s in (30, 10)]
    )
    for fig in (success_rate_figure(summary), success_ecdf_figure(runs)):
        ax = fig.axes[0]
        lines = [ln for ln in ax.get_lines() if ln.get_label().startswith("m")]
        keys = [(str(ln.get_linestyle()), ln.get_marker()) for ln in lines]
        assert len(set(keys)) == len(keys) == len(lines) > 0  # not by colour alone
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        renderer = canvas.get_renderer()
        legend = ax.get_legend().get_window_extent(renderer)
        assert not legend.overlaps(ax.get_window_extent(renderer))  # beside the curves
