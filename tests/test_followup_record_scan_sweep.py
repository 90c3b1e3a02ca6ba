"""Follow-up defects of ``record``/``report``/``scene``/``scan``/``sweep check``: runs that must
fail are refused up front (window, probe inside the part) without leaving files behind; a
stale partial recording yields to ``--overwrite``; output paths with a wrong suffix, a
directory or a file used as a folder are refused with the real cause."""

from __future__ import annotations

from pathlib import Path

import pytest
import xarray as xr

from cli_helpers import TINY_PLATE, flat, run_main, tiny_setup_toml
from echocal.measurement.recording import partial_path

# a sphere whose top is at z = 10 mm: the reference (26 mm) is 16 mm above it; z = 5 mm is inside
SPHERE = '[[specimen.shapes]]\nkind = "sphere"\ncenter = [0, 0, "-20 mm"]\nradius = "30 mm"'


def _setup(tmp_path: Path, specimen: str = TINY_PLATE, ref_z: str = "16 mm") -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml(specimen, ref_z, z_min="0 mm"), encoding="utf-8")
    return path


def _record(setup: Path, out: Path, position: str, *extra: str) -> list[str]:
    return [
        "record", "--setup", str(setup), "--out", str(out), "--azimuth", "-1:1:3",
        "--coelevation", "-1:1:3", "--position", position, "--no-progress", *extra,
    ]  # fmt: skip


def test_record_refuses_a_probe_inside_the_part_and_then_records_the_fix(
    tmp_path, capsys, monkeypatch
):
    setup = _setup(tmp_path, SPHERE, "26 mm")
    out = tmp_path / "sp.nc"
    code, _, err = run_main(_record(setup, out, "0,0,5"), capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    assert "inside sphere" in flat(err) and "--position" in err
    assert not out.exists() and not partial_path(out).exists()  # nothing written
    code, _, err = run_main(_record(setup, out, "0,0,26", "--overwrite"), capsys, monkeypatch)
    assert code == 0, err
    assert out.is_file() and not partial_path(out).exists()


def test_record_refuses_a_window_that_cannot_hold_the_echo(tmp_path, capsys, monkeypatch):
    setup = _setup(tmp_path)
    out = tmp_path / "w.nc"
    code, _, err = run_main(_record(setup, out, "0,0,40"), capsys, monkeypatch)
    assert code == 2 and "cannot contain any echo" in flat(err)
    assert "(0, 0, 40) mm" in flat(err)
    assert not out.exists() and not partial_path(out).exists()


def test_record_keeps_a_grid_whose_steep_poses_alone_miss_the_window(tmp_path, capsys, monkeypatch):
    # thesis at z = 50 mm: the corner pose (-10, -40) deg alone has no echo in the window
    # (its rays return at ~80 us, the window ends at 71 us), but the simulator only fails a
    # batch where NO pose has an echo; the centre pose does, so the recording works and the
    # steep poses are noise A-scans.  Refusing it was a regression.
    out = tmp_path / "r2.nc"
    args = ["record", "--setup", "thesis", "--out", str(out), "--position", "0,0,50"]
    args += ["--azimuth=-10:10:3", "--coelevation=-40:40:5", "--no-progress"]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 0, err
    assert "recorded 15 A-scans" in flat(err)
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        assert ds["samples"].shape[:4] == (1, 3, 5, 1)
    assert not partial_path(out).exists()


def test_overwrite_discards_an_incompatible_partial_and_says_so(tmp_path, capsys, monkeypatch):
    setup = _setup(tmp_path)
    out = tmp_path / "p.nc"
    sidecar = partial_path(out)
    sidecar.mkdir()  # a partial recording of another grid, with nothing saved yet
    (sidecar / "manifest.json").write_text(
        '{"format": "replay-partial/1", "fingerprint": {"grid": "other"}, "chunks": []}'
    )
    code, _, err = run_main(_record(setup, out, "0,0,16"), capsys, monkeypatch)
    assert code == 2 and "--overwrite" in flat(err)  # the refusal names the way out
    code, _, err = run_main(_record(setup, out, "0,0,16", "--overwrite"), capsys, monkeypatch)
    assert code == 0, err
    assert "discarded the partial recording" in flat(err)
    assert out.is_file() and not sidecar.exists()


def test_a_stale_partial_is_refused_in_one_line_without_resuming_news(
    tmp_path, capsys, monkeypatch
):
    setup = _setup(tmp_path)
    out = tmp_path / "s.nc"
    sidecar = partial_path(out)
    sidecar.mkdir()  # another grid's partial recording with 5 A-scans saved
    (sidecar / "manifest.json").write_text(
        '{"format": "replay-partial/1", "fingerprint": {"grid": "other"},'
        ' "chunks": [{"file": "c0.npy", "count": 5}]}'
    )
    code, _, err = run_main(_record(setup, out, "0,0,16"), capsys, monkeypatch)
    assert code == 2
    assert "resuming" not in err and "saved" not in err  # it would not resume: no such news
    assert len(err.strip().splitlines()) == 1 and "--overwrite" in err
    assert sidecar.exists()  # kept until the user says --overwrite


@pytest.mark.parametrize(
    ("name", "expected"),
    [("x.txt", "ending in .nc"), ("x", "ending in .nc"), ("adir", "is a directory")],
)
def test_record_out_must_be_an_nc_file(tmp_path, capsys, monkeypatch, name, expected):
    setup = _setup(tmp_path)
    (tmp_path / "adir").mkdir()
    out = tmp_path / name
    for extra in ((), ("--overwrite",)):
        code, _, err = run_main(_record(setup, out, "0,0,16", *extra), capsys, monkeypatch)
        assert code == 2 and expected in flat(err) and "already exists" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir", "tiny.toml"]


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


SWEEP = {
    "name": "w",
    "setup": "thesis",
    "budget": 12,
    "max_iter": 3,
    "seeds": 1,
    "snr_db": [30],
    "methods": [{"name": "model-based"}],
}


def test_sweep_check_refuses_a_window_that_cannot_hold_the_echo():
    from echocal.errors import ConfigError
    from echocal.experiments import load_sweep

    # thesis: z limits [5, 100] mm, window [20, 71.2] us; the echo from 100 mm comes at 135 us
    with pytest.raises(ConfigError) as info:
        load_sweep({**SWEEP, "position": [0, 0, "100 mm"]})
    (problem,) = [line.strip() for line in str(info.value).splitlines()[1:]]
    assert problem.startswith("position:") and "cannot contain any echo" in problem
    assert load_sweep({**SWEEP, "position": [0, 0, "22 mm"]}).name == "w"  # a valid one passes


def _scan(setup: Path, out: Path, z: str, *extra: str) -> list[str]:
    return [
        "scan", "--setup", str(setup), "--grid", "-1:1:1,-1:1:1", "--z", z, "--out", str(out),
        "--no-progress", *extra,
    ]  # fmt: skip


@pytest.mark.parametrize(
    ("specimen", "ref_z", "z", "expected"),
    [
        (TINY_PLATE, "16 mm", "40", "cannot contain any echo"),
        (SPHERE, "26 mm", "5", "inside sphere"),
    ],
)
def test_scan_refuses_a_run_where_every_point_fails(
    tmp_path, capsys, monkeypatch, specimen, ref_z, z, expected
):
    setup = _setup(tmp_path, specimen, ref_z)
    out = tmp_path / "scan"
    code, _, err = run_main(_scan(setup, out, z), capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    assert expected in flat(err) and "every grid point would fail (9 of 9)" in flat(err)
    assert not out.exists()  # nothing written


def test_a_scan_that_finds_nothing_prints_no_numpy_warnings(tmp_path, capsys, monkeypatch):
    setup = _setup(tmp_path)
    out = tmp_path / "scan"
    # 9 measurements per point: one auto iteration + 2 time-of-flight A-scans, never converged
    code, _, err = run_main(_scan(setup, out, "16", "--budget-per-point", "9"), capsys, monkeypatch)
    assert code == 0, err
    assert "0 found" in err  # the case of the defect: nothing found, summaries of nothing
    assert "Mean of empty slice" not in err and "invalid value" not in err
    assert "warning" not in err.lower()
