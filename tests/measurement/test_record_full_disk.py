"""``record`` on a full disk stops with one line naming the file it could not write and
the cause, with what to do."""

from __future__ import annotations

import errno

from cli_helpers import flat, run_main, tiny_setup_toml


def test_a_full_disk_while_saving_a_chunk_names_the_file(tmp_path, capsys, monkeypatch):
    import echocal.measurement._partial_recording as partial

    def save(fh, rows):  # the disk fills up at the partial recording's first chunk
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(partial.np, "save", save)
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    out = tmp_path / "rec.nc"
    grid = ["--azimuth", "0", "--coelevation", "-2:2:3", "--position", "0,0,16"]
    code, _, err = run_main(
        ["record", "--setup", str(setup), *grid, "--out", str(out), "--no-progress"],
        capsys,
        monkeypatch,
    )
    text = flat(err)
    assert code == 2 and "Traceback" not in err and err.count("error:") == 1, err
    assert str(tmp_path / "rec.nc.partial" / "chunk-000000000.npy") in text
    assert "No space left on the device; free some space or write elsewhere" in text
    assert not out.exists()
