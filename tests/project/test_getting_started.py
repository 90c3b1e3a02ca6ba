"""The getting-started page's Python snippet and the command line agree: one set of defaults.

The snippet (docs/getting-started.md, run as written) and ``echocal calibrate`` on the same
setup, start and seed run the same calibration: the snippet settles (status 7, success)
within the command line's measurement count.  A misspelt option is an error in both,
naming the closest valid option.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cli_helpers import run_main
from echocal.errors import UnknownNameError

PAGE = Path(__file__).resolve().parents[2] / "docs" / "getting-started.md"


def _snippet() -> str:
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)
    assert len(blocks) == 1, "getting-started.md has one Python snippet"
    return blocks[0]


def test_getting_started_snippet_settles_within_the_cli_count(tmp_path, capsys, monkeypatch):
    names: dict = {}
    exec(compile(_snippet(), str(PAGE), "exec"), names)
    result = names["result"]
    capsys.readouterr()
    code, out, _ = run_main(
        [
            "calibrate",
            "--setup",
            "immersion-5mhz",
            "--x0",
            "0,0",
            "--seed",
            "0",
            "--json",
            "--no-plots",
            "--out",
            str(tmp_path / "cli"),
        ],
        capsys,
        monkeypatch,
    )
    cli = json.loads(out)
    assert code == 0 and cli["success"] and cli["status"] == 7
    assert result.success and result.status == 7, result.message
    assert result.n_measurements <= cli["n_measurements"]
    # the same defaults give the same run
    assert result.n_measurements == cli["n_measurements"]


def test_a_misspelt_option_is_an_error_in_python_and_on_the_command_line(
    tmp_path, capsys, monkeypatch
):
    names: dict = {}
    snippet = _snippet().replace("rng=0)", "rng=0, fine_raduis=1.0)")
    assert "fine_raduis" in snippet
    with pytest.raises(UnknownNameError, match=r"did you mean fine_radius\?"):
        exec(compile(snippet, str(PAGE), "exec"), names)
    code, _, err = run_main(
        [
            "calibrate",
            "--setup",
            "immersion-5mhz",
            "--option",
            "fine_raduis=1",
            "--out",
            str(tmp_path / "cli"),
        ],
        capsys,
        monkeypatch,
    )
    assert code == 2 and "did you mean fine_radius?" in " ".join(err.split())
