"""A TOML boolean in any number field of a sweep file is refused naming the field, never
read as 1 or 0 (``seeds = true`` was one seed, ``budget = true`` a budget of 1)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cli_helpers import flat, run_main

METHOD = '[[methods]]\nname = "model-based"\n'


@pytest.mark.parametrize(
    ("line", "field"),
    [
        ("seeds = true", "seeds"),
        ("seeds = [0, true]", "seeds"),
        ("budget = true", "budget"),
        ("max_iter = true", "max_iter"),
        ("xtol = false", "xtol"),
        ("tolerance = true", "tolerance"),
        ("seed = true", "seed"),
        ("settle = [0.01, true]", "settle.1"),
        ("snr_db = true", "snr_db.0"),
        ("position = [true, 0, 0.02]", "position.0"),
    ],
)
def test_a_boolean_in_a_sweep_field_is_refused(line, field, tmp_path: Path, capsys, monkeypatch):
    path = tmp_path / "sweep.toml"
    path.write_text(f'setup = "thesis"\n{line}\n{METHOD}', encoding="utf-8")
    code, _, err = run_main(["sweep", "check", str(path)], capsys, monkeypatch)
    text = flat(err)
    assert code == 2 and "Traceback" not in err, err
    assert f"{field}:" in text and "boolean" in text, text
