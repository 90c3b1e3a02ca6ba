"""The recorder: interruption, resume, refusal to mix recordings, atomic final file."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from fake_sources import GaussianEchoSource, InterruptingSource

from echocal.ascan import AScan
from echocal.errors import DataFileError, EchocalValueError, LimitError
from echocal.geometry import Pose
from echocal.measurement.base import BaseSource
from echocal.measurement.recording import RecordingGrid, partial_path, record
from echocal.measurement.replay import ReplaySource

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
