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
