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
