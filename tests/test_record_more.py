"""``echocal record`` refuses duplicate positions and absurd grids up front; a replay file
with duplicate positions is refused naming the file and the positions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cli_helpers import flat as _flat
from cli_helpers import run_main, tiny_setup_toml
from echocal.errors import DataFileError, EchocalValueError
from echocal.measurement import ReplaySource
from echocal.measurement.recording import (
    MAX_RECORDING_ASCANS,
    RecordingGrid,
    check_recording_size,
    save_recording,
)


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
