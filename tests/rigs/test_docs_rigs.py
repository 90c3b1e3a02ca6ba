"""The Python examples of docs/rigs.md run as written (their own asserts are the checks)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[2] / "docs" / "rigs.md"
BLOCKS = re.findall(r"^```python\n(.*?)^```$", DOC.read_text(encoding="utf-8"), re.M | re.S)

pytest.importorskip("pyvisa_sim")
pytest.importorskip("bluesky")


def test_the_doc_has_runnable_examples() -> None:
    assert len(BLOCKS) == 3, f"expected the rig-file, Bluesky and suspender examples in {DOC}"


@pytest.mark.parametrize("code", BLOCKS, ids=["rig-file", "bluesky", "suspender"])
def test_example_runs(code: str) -> None:
    exec(compile(code, str(DOC), "exec"), {"__name__": "docs_rigs"})


def test_the_rig_file_example_is_valid(tmp_path: Path) -> None:
    """The doc's rig file validates, and with its commands table the scope preset builds."""
    from echocal.rigs import load_rig_config, scope_preset

    tomls = re.findall(r"^```toml\n(.*?)^```$", DOC.read_text(encoding="utf-8"), re.M | re.S)
    example = tmp_path / "my-rig.toml"
    example.write_text(tomls[0] + tomls[1], encoding="utf-8")  # + the commands table
    config, _ = load_rig_config(example)
    receiver = config.rig.receiver
    preset = scope_preset(receiver.preset, **receiver.commands)
    assert preset.datatype == "b" and preset.setup[1] == ":WAVeform:FORMat BYTE"
    assert config.rig.positioner.axes.z.limits == ("5 mm", "80 mm")
