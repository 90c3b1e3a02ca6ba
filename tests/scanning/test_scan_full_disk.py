"""A scan whose point store cannot be written (a full disk) stops with one line naming
the file and the cause, not ``cannot access: No space left on device``."""

from __future__ import annotations

import errno
import json
from types import SimpleNamespace

from cli_helpers import flat, run_main, tiny_setup_toml


def test_a_full_disk_while_saving_a_point_names_the_file(tmp_path, capsys, monkeypatch):
    import echocal.scanning.store as store

    def dumps(obj, **kwargs):
        if kwargs.get("allow_nan"):  # a point's line (the manifest is written before)
            raise OSError(errno.ENOSPC, "No space left on device")
        return json.dumps(obj, **kwargs)

    monkeypatch.setattr(store, "json", SimpleNamespace(dumps=dumps, loads=json.loads))
    setup = tmp_path / "tiny.toml"
    setup.write_text(tiny_setup_toml(), encoding="utf-8")
    out = tmp_path / "scan"
    args = ["scan", "--setup", str(setup), "--grid", "0:0:1,0:0:1", "--z", "16"]
    code, _, err = run_main(
        [*args, "--out", str(out), "--no-figures", "--no-progress"],
        capsys,
        monkeypatch,
    )
    text = flat(err)
    assert code == 2 and "Traceback" not in err and err.count("error:") == 1
    assert str(out / "scan.nc.partial" / "points.jsonl") in text
    assert "No space left on the device; free some space or write elsewhere" in text
