"""A partial recording's chunks carry the SHA-256 of their file: a chunk changed after it
was written (a flipped byte, a chunk overwritten with NaN of the right shape) is refused
in one line naming it, on resume, before anything more is measured and before it can reach
the final file; a source delivering a non-finite A-scan stops the recording, keeping the
earlier measurements."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import tiny_setup_toml
from echocal.errors import DataFileError, EchocalValueError
from echocal.measurement.recording import RecordingGrid, partial_path, record, saved_count
from echocal.setups import load_setup

GRID = RecordingGrid(
    azimuth=(0.0,), coelevation=(-2.0, -1.0, 0.0, 1.0, 2.0, 3.0), positions=((0.0, 0.0, 0.016),)
)


class _StopAfter:
    """The simulator, interrupted (KeyboardInterrupt) at its ``n``-th measurement; or
    delivering NaN there (``nan=True``)."""

    def __init__(self, source, n: int, *, nan: bool = False) -> None:
        self._source, self._n, self._nan, self._count = source, n, nan, 0

    def __getattr__(self, name):
        return getattr(self._source, name)

    def measure(self, pose):
        self._count += 1
        scan = self._source.measure(pose)
        if self._count == self._n:
            if not self._nan:
                raise KeyboardInterrupt
            samples = np.array(scan.samples)
            samples[3] = np.nan
            return type(scan)(samples=samples, fs=scan.fs, start_time=scan.start_time, pose=pose)
        return scan


@pytest.fixture
def setup(tmp_path: Path):
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_setup_toml(), encoding="utf-8")
    return path


def _interrupted(setup: Path, out: Path) -> Path:
    """A partial recording of 4 A-scans in chunks of 2; returns its first chunk."""
    source = _StopAfter(load_setup(setup), 5)
    with pytest.raises(KeyboardInterrupt):
        record(source, GRID, out, progress=False, chunk_size=2)
    assert saved_count(out) == 4
    manifest = json.loads((partial_path(out) / "manifest.json").read_text())
    assert all(len(c["sha256"]) == 64 for c in manifest["chunks"])
    return partial_path(out) / manifest["chunks"][0]["file"]


def test_an_intact_partial_recording_resumes(setup, tmp_path):
    out = tmp_path / "rec.nc"
    _interrupted(setup, out)
    record(load_setup(setup), GRID, out, progress=False, chunk_size=2)
    assert out.exists() and not partial_path(out).exists()


def test_a_flipped_byte_in_a_chunk_is_refused(setup, tmp_path):
    out = tmp_path / "rec.nc"
    chunk = _interrupted(setup, out)
    data = bytearray(chunk.read_bytes())
    data[-5] ^= 0x01  # one bit of the last sample's mantissa: still a valid .npy
    chunk.write_bytes(bytes(data))
    with pytest.raises(DataFileError, match="SHA-256") as refused:
        record(load_setup(setup), GRID, out, progress=False, chunk_size=2)
    message = str(refused.value)
    assert (
        chunk.name in message and "\n" not in message and f"delete {partial_path(out)}" in message
    )
    assert not out.exists()


@pytest.mark.parametrize("keep_digest", [True, False], ids=["digest", "no-digest"])
def test_a_chunk_of_nan_is_refused(setup, tmp_path, keep_digest):
    """Overwritten with NaN of the right shape: the digest catches it; a manifest without
    digests (or one edited to match) is still refused, for the non-finite samples."""
    out = tmp_path / "rec.nc"
    chunk = _interrupted(setup, out)
    shape = np.load(chunk).shape
    np.save(chunk, np.full(shape, np.nan))
    if not keep_digest:
        manifest_path = partial_path(out) / "manifest.json"
        manifest = json.loads(manifest_path.read_text())
        for entry in manifest["chunks"]:
            entry.pop("sha256")
        manifest_path.write_text(json.dumps(manifest))
    expected = "SHA-256" if keep_digest else "not finite"
    with pytest.raises(DataFileError, match=expected) as refused:
        record(load_setup(setup), GRID, out, progress=False, chunk_size=2)
    assert chunk.name in str(refused.value)
    assert not out.exists()


def test_a_non_finite_ascan_stops_the_recording_and_keeps_the_earlier_ones(setup, tmp_path):
    out = tmp_path / "rec.nc"
    source = _StopAfter(load_setup(setup), 4, nan=True)
    with pytest.raises(EchocalValueError, match="measurement 3: .* not finite"):
        record(source, GRID, out, progress=False, chunk_size=2)
    assert saved_count(out) == 3 and not out.exists()
