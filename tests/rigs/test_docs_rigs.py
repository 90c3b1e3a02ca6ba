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
    assert len(BLOCKS) == 2, f"expected the rig-file and the Bluesky examples in {DOC}"


@pytest.mark.parametrize("code", BLOCKS, ids=["rig-file", "bluesky"])
def test_example_runs(code: str) -> None:
    exec(compile(code, str(DOC), "exec"), {"__name__": "docs_rigs"})
