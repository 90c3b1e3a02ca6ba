"""echocal.io.ChecksummedManifest: files listed with their SHA-256 beside a run's
fingerprint; a file changed after it was written, or a manifest that cannot be read, is
refused in one line naming it.  The digests are checked against hashlib's, computed here."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from echocal.errors import DataFileError
from echocal.io import ChecksummedManifest

LABEL, FIX = "cannot resume: ", "delete the folder to start over"


def _new(folder: Path, stamp: dict | None = None) -> ChecksummedManifest:
    stamp = {"seed": 1, "x0": [2.0, -1.0]} if stamp is None else stamp
    return ChecksummedManifest.new(folder, "test/1", stamp, "files", label=LABEL, fix=FIX)


def _read(folder: Path) -> ChecksummedManifest | None:
    return ChecksummedManifest.read(folder, "files", label=LABEL, fix=FIX)


def _one_line(error: pytest.ExceptionInfo[DataFileError]) -> str:
    message = str(error.value)
    assert "\n" not in message and message.startswith(LABEL) and message.endswith(FIX)
    return message


def test_files_are_listed_with_their_sha256_and_read_back(tmp_path):
    folder = tmp_path / "journal"
    assert _read(folder) is None  # nothing saved yet
    manifest = _new(folder)
    blobs = [b"first", bytes(range(256)) * 5000]  # the second spans more than one 1 MiB block
    for i, blob in enumerate(blobs):
        manifest.add(f"{i}.bin", lambda tmp, blob=blob: tmp.write_bytes(blob), index=i)
    on_disk = json.loads((folder / "manifest.json").read_text())
    assert on_disk["format"] == "test/1" and on_disk["fingerprint"]["seed"] == 1
    assert on_disk["files"] == [
        {"file": f"{i}.bin", "index": i, "sha256": hashlib.sha256(b).hexdigest()}
        for i, b in enumerate(blobs)
    ]
    again = _read(folder)
    assert again is not None and again.entries == on_disk["files"]
    assert [again.verify(e).read_bytes() for e in again.entries] == blobs
    assert sorted(p.name for p in folder.iterdir()) == ["0.bin", "1.bin", "manifest.json"]


def test_a_changed_file_is_refused_in_one_line(tmp_path):
    manifest = _new(tmp_path)
    entry = manifest.add("a.bin", lambda tmp: tmp.write_bytes(b"\x00" * 64))
    (tmp_path / "a.bin").write_bytes(b"\x00" * 63 + b"\x01")  # one flipped bit
    with pytest.raises(DataFileError) as refused:
        manifest.verify(entry)
    message = _one_line(refused)
    assert f"{tmp_path / 'a.bin'} is damaged" in message and "SHA-256" in message
    assert hashlib.sha256(b"\x00" * 63 + b"\x01").hexdigest()[:12] in message
    (tmp_path / "a.bin").unlink()
    with pytest.raises(DataFileError, match="is unreadable") as missing:
        manifest.verify(entry)
    _one_line(missing)


def test_an_entry_without_a_digest_is_refused_unless_it_may_lack_one(tmp_path):
    manifest = _new(tmp_path)
    manifest.add("a.bin", lambda tmp: tmp.write_bytes(b"abc"))
    old_entry = {"file": "a.bin"}  # an older manifest's entry: no digest
    assert manifest.verify(old_entry, digest_optional=True) == tmp_path / "a.bin"
    with pytest.raises(DataFileError, match="is damaged"):
        manifest.verify(old_entry)


@pytest.mark.parametrize(
    "text",
    ["{not json", '{"format": "test/1", "files": []}', '{"fingerprint": {}, "files": {}}'],
    ids=["not-json", "no-fingerprint", "files-not-a-list"],
)
def test_an_unreadable_manifest_is_refused_in_one_line(tmp_path, text):
    (tmp_path / "manifest.json").write_text(text)
    with pytest.raises(DataFileError, match="manifest.json is unreadable") as refused:
        _read(tmp_path)
    _one_line(refused)


def test_the_keys_that_differ_from_the_recorded_fingerprint(tmp_path):
    _new(tmp_path, {"seed": 1, "x0": [2.0, -1.0], "gate": "front"}).save()
    found = _read(tmp_path)
    assert found is not None
    assert found.differing({"seed": 1, "x0": [2.0, -1.0], "gate": "front"}) == []
    assert found.differing({"seed": 1, "x0": [2.0, -1.0], "gate": "front", "new": None}) == []
    assert found.differing({"seed": 3, "x0": [2.0, -1.0], "budget": 9}) == [
        "budget",
        "gate",
        "seed",
    ]
    assert found.recorded(["budget", "gate", "x0"]) == 'budget=null; gate="front"; x0=[2.0, -1.0]'
    assert found.recorded(["x0"], limit=6) == "x0=[2.0,…"  # a long value is cut


def test_a_failed_write_lists_nothing_and_leaves_no_file(tmp_path):
    manifest = _new(tmp_path)
    manifest.add("a.bin", lambda tmp: tmp.write_bytes(b"a"))
    before = (tmp_path / "manifest.json").read_text()

    def full_disk(tmp: Path) -> None:
        tmp.write_bytes(b"half")
        raise OSError(28, "No space left on device")

    with pytest.raises(DataFileError, match="b.bin: No space left"):
        manifest.add("b.bin", full_disk)
    assert (tmp_path / "manifest.json").read_text() == before
    assert len(manifest.entries) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin", "manifest.json"]
