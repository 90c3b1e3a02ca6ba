"""echocal.io: atomic file output."""

from __future__ import annotations

import os

from echocal.io import atomic_write_text


def test_atomic_files_follow_the_umask(tmp_path):
    umask = os.umask(0o022)
    try:
        atomic_write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(umask)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644


def test_atomic_path_leaves_the_process_umask_alone(tmp_path, monkeypatch):
    # Reading the umask by setting it (os.umask(0)) races other threads' file creation;
    # atomic_path must never call os.umask at all.
    def forbidden(_mask):
        raise AssertionError("atomic_path changed the process umask")

    monkeypatch.setattr(os, "umask", forbidden)
    atomic_write_text(tmp_path / "b.txt", "y")
    assert (tmp_path / "b.txt").read_text() == "y"
    assert [p.name for p in tmp_path.iterdir()] == ["b.txt"]  # no temporary file left


def test_json_ready_is_strict_json():
    import json
    from pathlib import Path

    import numpy as np

    from echocal.io import json_ready

    data = {"a": np.float64("nan"), "b": [1.0, float("inf"), (np.int64(2), Path("x"))]}
    data["c"] = np.array([0.5, -np.inf])
    text = json.dumps(json_ready(data), allow_nan=False)  # raises on any NaN/inf left
    assert json.loads(text) == {"a": None, "b": [1.0, None, [2, "x"]], "c": [0.5, None]}


def test_unwritable_targets_are_data_file_errors_naming_the_path(tmp_path):
    import pytest

    from echocal.errors import DataFileError

    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(DataFileError, match=r"cannot write .*file/out\.txt"):
        atomic_write_text(blocker / "out.txt", "y")  # parent is a file, not a directory
    (tmp_path / "dir").mkdir()
    with pytest.raises(DataFileError, match="is a directory"):
        atomic_write_text(tmp_path / "dir", "y")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir", "file"]  # nothing left behind


def test_cli_turns_os_errors_into_one_line_and_exit_2(tmp_path, capsys, monkeypatch):
    import sys

    import pytest
    import typer

    from echocal.cli._common import run_cli

    app = typer.Typer()

    @app.command()
    def read() -> None:
        (tmp_path / "missing" / "x.txt").read_text()  # the OSError is the point

    monkeypatch.setattr(sys, "argv", ["echocal"])  # a one-command app runs it directly
    with pytest.raises(SystemExit) as exit_info:
        run_cli(app)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "cannot access" in err and "missing" in err and "Traceback" not in err


def test_version_flag_and_info_print_real_versions():
    from importlib.metadata import version

    from typer.testing import CliRunner

    import echocal
    from echocal.cli import app

    result = CliRunner().invoke(app, ["--version"])
    assert result.exit_code == 0 and result.output.strip() == echocal.__version__
    info = CliRunner().invoke(app, ["info"])
    assert info.exit_code == 0 and f"numpy      {version('numpy')}" in info.output


def test_usage_errors_are_one_line_with_exit_2(capsys, monkeypatch):
    import sys

    import pytest

    from echocal.cli import app
    from echocal.cli._common import run_cli

    monkeypatch.setattr(sys, "argv", ["echocal", "simulate", "--pos", "1"])
    with pytest.raises(SystemExit) as exit_info:
        run_cli(app)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "No such option: --pos" in err
    assert "echocal simulate --help" in err  # where to look


def test_warnings_in_a_command_are_one_line(capsys, monkeypatch):
    import sys
    import warnings

    import pytest
    import typer

    from echocal.cli._common import run_cli

    app = typer.Typer()

    @app.command()
    def doubtful() -> None:
        warnings.warn("specimen.mesh_scale is ignored", UserWarning, stacklevel=1)

    monkeypatch.setattr(sys, "argv", ["echocal"])
    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)  # restored afterwards
    with pytest.raises(SystemExit) as exit_info:
        run_cli(app)
    assert exit_info.value.code == 0
    assert capsys.readouterr().err.strip() == "warning: specimen.mesh_scale is ignored"


def test_a_file_in_the_way_of_the_output_folder_is_named(tmp_path):
    import pytest

    from echocal.errors import DataFileError

    (tmp_path / "notes").write_text("x")
    with pytest.raises(DataFileError, match=r"notes is not a directory"):
        atomic_write_text(tmp_path / "notes" / "deeper" / "out.txt", "y")
