"""The recorder: interruption, resume, refusal to mix recordings, atomic final file."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from fake_sources import GaussianEchoSource, InterruptingSource

from cli_helpers import (
    SPHERE_UNDER_REFERENCE,
    flat,
    run_main,
    tiny_setup_file,
    tiny_setup_toml,
)
from cli_helpers import flat as _flat
from echocal.ascan import AScan
from echocal.errors import DataFileError, EchocalValueError, LimitError
from echocal.geometry import Pose
from echocal.measurement import ReplaySource
from echocal.measurement.base import BaseSource
from echocal.measurement.recording import (
    MAX_RECORDING_ASCANS,
    RecordingGrid,
    check_recording_size,
    partial_path,
    record,
    save_recording,
)

GRID = RecordingGrid.regular(
    azimuth=(0.0, 30.0, 4), coelevation=(-5.0, 5.0, 3), positions=[(0, 0, 0.02), (0.003, 0, 0.02)]
)
REPEATS = 2
TOTAL = 2 * 4 * 3 * REPEATS  # 48 measurements


def _samples(path: Path) -> np.ndarray:
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        return ds["samples"].values


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> np.ndarray:
    path = tmp_path_factory.mktemp("ref") / "ref.nc"
    return _samples(record(GaussianEchoSource(), GRID, path, repeats=REPEATS, progress=False))


@pytest.mark.parametrize("stops", [(0,), (17,), (5, 11, 30), (47,)])
def test_interrupted_recording_resumes_to_the_same_file(
    tmp_path: Path, reference: np.ndarray, stops: tuple[int, ...]
) -> None:
    inner = GaussianEchoSource()  # deterministic: the file must equal the uninterrupted one
    path = tmp_path / "scan.nc"
    for stop in stops:
        already = len(inner.measured)
        with pytest.raises(KeyboardInterrupt):
            record(
                InterruptingSource(inner, stop - already),
                GRID,
                path,
                repeats=REPEATS,
                progress=False,
                chunk_size=4,  # several chunks, and a partly filled buffer at each stop
            )
        assert not path.exists()  # never a half-written final file
        assert partial_path(path).is_dir()
    final = record(inner, GRID, path, repeats=REPEATS, progress=False, chunk_size=4)
    assert final == path
    assert not partial_path(path).exists()
    np.testing.assert_array_equal(_samples(path), reference)
    # every grid pose measured exactly REPEATS times over all runs: nothing measured twice
    assert len(inner.measured) == TOTAL
    assert Counter(inner.measured) == {p: REPEATS for p in GRID.poses()}


def test_batches_use_measure_many_and_give_the_same_file(
    tmp_path: Path, reference: np.ndarray
) -> None:
    path = record(
        GaussianEchoSource(), GRID, tmp_path / "b.nc", repeats=REPEATS, progress=True, batch_size=5
    )
    np.testing.assert_array_equal(_samples(path), reference)


def test_resume_refuses_another_grid_or_source(tmp_path: Path) -> None:
    path = tmp_path / "scan.nc"
    with pytest.raises(KeyboardInterrupt):
        record(InterruptingSource(GaussianEchoSource(), 7), GRID, path, progress=False)
    other_grid = RecordingGrid.regular(
        azimuth=(0.0, 30.0, 7), coelevation=(-5.0, 5.0, 3), positions=[(0, 0, 0.02)]
    )
    with pytest.raises(DataFileError, match=r"cannot resume.*different grid"):
        record(GaussianEchoSource(), other_grid, path, progress=False)
    with pytest.raises(DataFileError, match=r"different repeats"):
        record(GaussianEchoSource(), GRID, path, repeats=3, progress=False)
    with pytest.raises(DataFileError, match=r"different source"):
        record(GaussianEchoSource(width=9.0), GRID, path, progress=False)
    # the partial recording is untouched by the refusals and still resumes
    fake = GaussianEchoSource()
    record(fake, GRID, path, progress=False)
    assert len(fake.measured) == 24 - 7


def test_existing_final_file_needs_overwrite(tmp_path: Path) -> None:
    path = record(GaussianEchoSource(), GRID, tmp_path / "a.nc", progress=False)
    with pytest.raises(DataFileError, match="already exists.*overwrite"):
        record(GaussianEchoSource(), GRID, path, progress=False)
    record(GaussianEchoSource(), GRID, path, progress=False, overwrite=True)


def test_unwritable_targets_are_named_data_file_errors(tmp_path: Path) -> None:
    (tmp_path / "folder.nc").mkdir()
    with pytest.raises(DataFileError, match="folder.nc is a directory"):
        record(GaussianEchoSource(), GRID, tmp_path / "folder.nc", progress=False, overwrite=True)
    # the sidecar's parent is a regular file: mkdir fails (as on a read-only disk)
    (tmp_path / "plain").write_text("")
    with pytest.raises(DataFileError, match="plain is not a directory"):
        record(GaussianEchoSource(), GRID, tmp_path / "plain" / "a.nc", progress=False)


def test_grid_outside_the_source_limits_measures_nothing(tmp_path: Path) -> None:
    fake = GaussianEchoSource()
    wide = RecordingGrid.regular(
        azimuth=(0.0, 30.0, 2), coelevation=(0.0, 40.0, 3), positions=[(0, 0, 0.02)]
    )
    with pytest.raises(LimitError, match=r"2 grid pose\(s\).*coelevation ?= ?40"):
        record(fake, wide, tmp_path / "w.nc", progress=False)
    assert fake.measured == []
    assert not partial_path(tmp_path / "w.nc").exists()


class ChangingFormat(BaseSource):
    """Switches sampling frequency after 5 A-scans (a misconfigured receiver)."""

    description = "changing format"

    def __init__(self) -> None:
        self.n = 0

    def measure(self, pose: Pose) -> AScan:
        self.n += 1
        return AScan(np.zeros(8), fs=1e6 if self.n <= 5 else 2e6)


def test_inconsistent_sampling_is_refused_and_earlier_data_kept(tmp_path: Path) -> None:
    path = tmp_path / "c.nc"
    with pytest.raises(EchocalValueError, match="measurement 5 .*one sampling format"):
        record(ChangingFormat(), GRID, path, progress=False)
    assert (partial_path(path) / "chunk-000000000.npy").exists()
    assert np.load(partial_path(path) / "chunk-000000000.npy").shape == (5, 8)


def test_recording_replays(tmp_path: Path) -> None:
    fake = GaussianEchoSource()
    path = record(fake, GRID, tmp_path / "r.nc", progress=False)
    with ReplaySource.open(path) as replay:
        pose = Pose(0.003, 0.0, 0.02, 20.0, 5.0)
        np.testing.assert_array_equal(replay.measure(pose).samples, fake.clean_samples(pose))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"azimuth": (0.0, 10.0, 5.0)}, "strictly increasing"),
        ({"azimuth": (0.0, float("nan"))}, "finite"),
        ({"positions": ()}, "at least one"),
        ({"positions": ((0.0, 0.0),)}, "trailing shape"),
    ],
)
def test_grid_validation(kwargs: dict, message: str) -> None:
    base = {"azimuth": (0.0, 10.0), "coelevation": (0.0,), "positions": ((0.0, 0.0, 0.02),)}
    with pytest.raises(EchocalValueError, match=message):
        RecordingGrid(**{**base, **kwargs})


def test_repeats_must_be_positive(tmp_path: Path) -> None:
    with pytest.raises(EchocalValueError, match="repeats"):
        record(GaussianEchoSource(), GRID, tmp_path / "x.nc", repeats=0, progress=False)


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml(), encoding="utf-8")
    return path


def test_duplicate_positions_are_refused_at_record_time(tiny, tmp_path, capsys, monkeypatch):
    out = tmp_path / "r.nc"
    args = ["record", "--setup", str(tiny), "--out", str(out), "--azimuth", "0"]
    args += ["--coelevation", "0", "--position", "0,0,16", "--position", "0mm,0,1.6cm"]
    code, _, err = run_main([*args, "--no-progress"], capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    assert "#0 and #1 are the same position (0, 0, 16) mm" in _flat(err)
    assert "--position" in err
    assert not out.exists() and not Path(f"{out}.partial").exists()
    with pytest.raises(EchocalValueError, match="same position"):
        # 0.1 µm apart: a replay could not tell them apart either
        RecordingGrid(
            azimuth=[0.0], coelevation=[0.0], positions=[(0, 0, 0.016), (0, 0, 0.0160001)]
        )


def test_duplicates_among_thousands_of_positions_are_found_and_named():
    # 3,000 distinct positions on a 1 mm lattice (a P x P distance array would be 216 MB;
    # the tree search is O(P log P)): accepted, in order
    grid_xyz = np.stack(np.meshgrid(*(np.arange(15) * 1e-3,) * 2, np.arange(14) * 1e-3), -1)
    many = grid_xyz.reshape(-1, 3)[:3000] + np.array([0.0, 0.0, 0.02])
    grid = RecordingGrid(azimuth=[0.0], coelevation=[0.0], positions=many)
    np.testing.assert_array_equal(np.array(grid.positions), many)
    # 0.5 um from #1234 (below the 1 um limit) appended as #3000, plus an exact copy of
    # #17 as #3001: the first pair in (i, j) order, (17, 3001), is named
    near = many[1234] + [5e-7, 0.0, 0.0]
    bad = np.vstack([many, near, many[17]])
    where = ", ".join(f"{1e3 * c:g}" for c in many[17])
    with pytest.raises(
        EchocalValueError, match=rf"#17 and #3001 are the same position \({where}\)"
    ):
        RecordingGrid(azimuth=[0.0], coelevation=[0.0], positions=bad)
    # 1.5 um apart (above the 1 um limit, clear of rounding) is allowed
    apart = np.vstack([many[:2], many[0] + [1.5e-6, 0.0, 0.0]])
    assert len(RecordingGrid(azimuth=[0.0], coelevation=[0.0], positions=apart).positions) == 3


def test_replay_with_duplicate_positions_names_the_file_and_them(
    tiny, tmp_path, capsys, monkeypatch
):
    good = tmp_path / "good.nc"
    args = ["record", "--setup", str(tiny), "--out", str(good), "--azimuth", "0"]
    args += ["--coelevation", "0", "--position", "0,0,16", "--position", "1,0,16"]
    assert run_main([*args, "--no-progress", "--snr", "none"], capsys, monkeypatch)[0] == 0
    # a file made elsewhere (or by an older echocal) with both positions the same
    bad = tmp_path / "dup.nc"
    with xr.open_dataset(good, engine="h5netcdf") as ds:
        data = ds.load()
    data = data.assign_coords(position_x=("position", [0.0, 0.0], data["position_x"].attrs))
    save_recording(data, bad)
    with pytest.raises(DataFileError) as info:
        ReplaySource.open(bad)
    message = str(info.value)
    assert str(bad) in message and "#0 and #1" in message and "(0, 0, 0.016) m" in message
    # with an explicit tolerance the file opens, and the first of the two answers
    with ReplaySource.open(bad, position_tolerance=1e-6) as replay:
        assert replay.position_tolerance == 1e-6


def test_an_absurd_grid_is_refused_at_once(tiny, tmp_path, capsys, monkeypatch):
    out = tmp_path / "huge.nc"
    args = ["record", "--setup", str(tiny), "--out", str(out)]
    args += ["--azimuth", "-10:10:100000", "--coelevation", "0:10:100000", "--no-progress"]

    def no_poses(self):  # building 10^10 Pose objects is what hung
        raise AssertionError("the poses of a refused grid must not be built")

    monkeypatch.setattr(RecordingGrid, "poses", no_poses)
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    text = _flat(err)
    assert "10,000,000,000 A-scans" in text and f"cap is {MAX_RECORDING_ASCANS:,}" in text
    assert not out.exists() and not Path(f"{out}.partial").exists()


def test_recording_size_caps_count_and_bytes():
    grid = RecordingGrid.regular(
        azimuth=(-10.0, 10.0, 500), coelevation=(0.0, 10.0, 1000), positions=[(0, 0, 0.02)]
    )
    # 500 000 A-scans (under the count cap) of 4096 samples: 500000 * 4096 * 8 B = 15.3 GiB
    with pytest.raises(EchocalValueError, match=r"15\.3 GiB .*cap is 8 GiB"):
        check_recording_size(grid, 1, 4096)
    assert check_recording_size(grid, 1, 256) == 500_000  # 0.95 GiB: allowed
    assert check_recording_size(grid, 2, None) == 1_000_000  # the count cap itself is allowed
    with pytest.raises(EchocalValueError, match="1,500,000 A-scans"):
        check_recording_size(grid, 3, None)
    assert np.prod(grid.shape) == grid.size == 500_000


def _record(setup: Path, out: Path, position: str, *extra: str) -> list[str]:
    return [
        "record", "--setup", str(setup), "--out", str(out), "--azimuth", "-1:1:3",
        "--coelevation", "-1:1:3", "--position", position, "--no-progress", *extra,
    ]  # fmt: skip


def test_record_refuses_a_probe_inside_the_part_and_then_records_the_fix(
    tmp_path, capsys, monkeypatch
):
    setup = tiny_setup_file(tmp_path, SPHERE_UNDER_REFERENCE, "26 mm")
    out = tmp_path / "sp.nc"
    code, _, err = run_main(_record(setup, out, "0,0,5"), capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    assert "inside sphere" in flat(err) and "--position" in err
    assert not out.exists() and not partial_path(out).exists()  # nothing written
    code, _, err = run_main(_record(setup, out, "0,0,26", "--overwrite"), capsys, monkeypatch)
    assert code == 0, err
    assert out.is_file() and not partial_path(out).exists()


def test_record_refuses_a_window_that_cannot_hold_the_echo(tmp_path, capsys, monkeypatch):
    setup = tiny_setup_file(tmp_path)
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
    setup = tiny_setup_file(tmp_path)
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
    setup = tiny_setup_file(tmp_path)
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
    setup = tiny_setup_file(tmp_path)
    (tmp_path / "adir").mkdir()
    out = tmp_path / name
    for extra in ((), ("--overwrite",)):
        code, _, err = run_main(_record(setup, out, "0,0,16", *extra), capsys, monkeypatch)
        assert code == 2 and expected in flat(err) and "already exists" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir", "tiny.toml"]
