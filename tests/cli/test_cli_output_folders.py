"""One rule for every command writing an output folder (issue 15, item 10): a folder that
already holds files is refused in one line (exit 2) unless --overwrite, and --overwrite
leaves no stale file of the command's own beside the new result."""

from __future__ import annotations

import json

import pytest

from cli_helpers import flat, run_main
from echocal.errors import DataFileError
from echocal.io import check_out_dir, refuse_existing_output

CALIBRATE = ["calibrate", "--method", "gradient", "--max-iter", "1", "--x0", "1,1", "--json"]
SIMULATE = ["simulate", "--pose", "0,0,20", "--json"]


@pytest.mark.parametrize("command", [CALIBRATE, SIMULATE], ids=["calibrate", "simulate"])
def test_a_folder_with_results_is_refused_without_overwrite(command, tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("an earlier run's file")
    code, stdout, err = run_main([*command, "--out", str(out)], capsys, monkeypatch)
    assert code == 2 and stdout == "", err
    assert "Traceback" not in err and err.count("error:") == 1
    assert "already holds results" in flat(err) and "--overwrite" in err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]  # nothing measured, written


def test_calibrate_overwrite_removes_its_own_stale_plots(tmp_path, capsys, monkeypatch):
    out = tmp_path / "cal"
    code, _, err = run_main([*CALIBRATE, "--out", str(out)], capsys, monkeypatch)
    assert code in (0, 3), err
    assert {"result.json", "convergence.png", "path.png"} <= {p.name for p in out.iterdir()}
    (out / "notes.txt").write_text("the user's own file")
    code, stdout, err = run_main(
        [*CALIBRATE, "--out", str(out), "--no-plots", "--overwrite"], capsys, monkeypatch
    )
    assert code in (0, 3), err
    # the plots of the first run would describe another run: gone; the user's file kept
    # data, not plots, is kept with --no-plots: the A-scan at the estimate (ascan.nc)
    assert sorted(p.name for p in out.iterdir()) == [
        "ascan.nc",
        "notes.txt",
        "result.json",
        "summary.json",
    ]
    assert json.loads(stdout)["files"] == {
        "result": str(out / "result.json"),
        "ascan": str(out / "ascan.nc"),
    }


def test_simulate_overwrite_leaves_no_stale_ascan_of_another_format(tmp_path, capsys, monkeypatch):
    out = tmp_path / "sim"
    assert run_main([*SIMULATE, "--out", str(out)], capsys, monkeypatch)[0] == 0
    assert (out / "ascan.csv").exists()
    code, _, err = run_main(
        [*SIMULATE, "--out", str(out), "--format", "nc", "--overwrite"], capsys, monkeypatch
    )
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["ascan.nc", "ascan.png", "ascan.svg"]


def test_an_empty_folder_is_accepted_and_a_file_refused(tmp_path):
    (tmp_path / "empty").mkdir()
    assert refuse_existing_output(tmp_path / "empty", overwrite=False) == tmp_path / "empty"
    (tmp_path / "file").write_text("x")
    with pytest.raises(DataFileError, match="is not a folder"):
        check_out_dir(tmp_path / "file", overwrite=True)


@pytest.mark.parametrize(
    ("name", "expected"), [("r.txt", "ending in .html"), ("adir", "is a directory")]
)
def test_report_out_must_be_an_html_file(tmp_path, capsys, monkeypatch, name, expected):
    (tmp_path / "adir").mkdir()
    out = tmp_path / name
    code, _, err = run_main(["report", str(tmp_path), "--out", str(out)], capsys, monkeypatch)
    assert code == 2 and expected in flat(err) and "pass --overwrite" not in err
    assert not (tmp_path / "r.txt").exists()


def test_scene_under_a_file_says_not_a_directory(tmp_path, capsys, monkeypatch):
    blocker = tmp_path / "afile"
    blocker.write_text("x")
    out = blocker / "x.png"
    args = ["scene", "--pose", "0,0,20", "--out", str(out)]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 2 and "is not a directory" in flat(err) and "File exists" not in err
