"""Packaging: version metadata, ``python -m echocal``, py.typed and the licence."""

from __future__ import annotations

import importlib.metadata
import importlib.resources
import subprocess
import sys
from pathlib import Path

import echocal

ROOT = Path(__file__).resolve().parents[2]


def test_version_comes_from_the_installed_metadata():
    assert echocal.__version__ == importlib.metadata.version("echocal")
    assert echocal.__version__ != "0+unknown"


def test_python_dash_m_echocal_runs_the_cli_with_the_same_version():
    done = subprocess.run(
        [sys.executable, "-m", "echocal", "--version"],
        capture_output=True,
        text=True,
        timeout=600,  # a hang, not a loaded machine (< 2 s when idle)
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == echocal.__version__


def test_package_is_marked_typed_and_ships_the_marker():
    assert (importlib.resources.files("echocal") / "py.typed").is_file()
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert '"py.typed"' in pyproject  # package-data, so wheels carry it too


def test_license_is_mit_and_matches_the_metadata():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License") and "echocal developers" in text
    meta = importlib.metadata.metadata("echocal")
    assert meta.get("License-Expression") == "MIT"
