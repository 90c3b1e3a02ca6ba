"""Running the ``echocal`` entry point in-process, as a user's shell would (shared by tests)."""

from __future__ import annotations

import sys

import pytest

import echocal.cli


def run_main(
    args: list[str], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> tuple[int, str, str]:
    """Run the ``echocal`` entry point; return (exit code, stdout, stderr)."""
    monkeypatch.setattr(sys, "argv", ["echocal", *args])
    with pytest.raises(SystemExit) as exit_info:
        echocal.cli.main()
    out, err = capsys.readouterr()
    code = exit_info.value.code
    return (0 if code is None else int(code)), out, err


def flat(text: str) -> str:
    """``text`` with every run of whitespace (console line wrapping) made one space."""
    return " ".join(text.split())
