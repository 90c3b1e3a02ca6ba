"""A recording holding an infinite sample, or one of 1e300 (whose square overflows in
every metric), is refused in one line naming the file and where the value sits, instead
of calibrating on it silently; NaN (a missing A-scan) stays allowed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cli_helpers import flat, run_main, tiny_setup_toml
from echocal.errors import DataFileError
from echocal.geometry import Pose
from echocal.measurement import ReplaySource
from echocal.measurement.recording import RecordingGrid, record, save_recording
from echocal.setups import load_setup

GRID = RecordingGrid(
    azimuth=(0.0, 90.0), coelevation=(-2.0, 0.0, 2.0), positions=((0.0, 0.0, 0.016),)
)


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("replay-magnitudes")
    setup = folder / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    path = folder / "rec.nc"
    record(load_setup(setup), GRID, path, progress=False)
    return setup, path


def _with(path: Path, value: float, out: Path) -> Path:
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        edited = ds.load()
    samples = edited["samples"].values.copy()
    samples[0, 1, 2, 0, 40] = value
    edited["samples"].values = samples
    save_recording(edited, out)
    return out


@pytest.mark.parametrize("value", [1e300, -1e300, np.inf, -np.inf], ids=str)
def test_an_absurd_sample_is_refused_naming_where_it_is(recording, value, tmp_path):
    _, path = recording
    edited = _with(path, value, tmp_path / "edited.nc")
    source = ReplaySource.open(edited)
    with pytest.raises(DataFileError) as refused:
        source.measure(Pose(0.0, 0.0, 0.016, 0.0, 0.0))
    message = str(refused.value)
    assert str(edited) in message and "\n" not in message
    assert "azimuth index 1, coelevation index 2, repeat 0, sample 40" in message


def test_nan_marks_a_missing_ascan_and_stays_allowed(recording, tmp_path):
    _, path = recording
    edited = _with(path, np.nan, tmp_path / "nan.nc")
    scan = ReplaySource.open(edited).measure(Pose(0.0, 0.0, 0.016, 0.0, 0.0))
    assert np.all(np.isfinite(scan.samples))  # another A-scan: the NaN is elsewhere


def test_calibrate_on_such_a_recording_is_one_line(recording, tmp_path, capsys, monkeypatch):
    setup, path = recording
    edited = _with(path, 1e300, tmp_path / "big.nc")
    args = ["calibrate", "--replay", str(edited), "--setup", str(setup)]
    code, _, err = run_main(
        [*args, "--position", "0,0,16", "--no-plots", "--out", str(tmp_path / "cal")],
        capsys,
        monkeypatch,
    )
    assert code == 2 and "Traceback" not in err
    assert str(edited) in flat(err) and "beyond ±1e+30" in flat(err)
