"""The detection-range script: its covering arithmetic, and a quick run end to end."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))

from detection_range import HEX_COVER, ceiling, cover, radius  # noqa: E402


def test_covering_arithmetic():
    # a regular hexagon of covering radius r has area (3√3/2) r²: π R² / that = HEX_COVER R²/r²
    assert HEX_COVER == pytest.approx(np.pi / (1.5 * np.sqrt(3.0)))
    assert cover((0.0, 20.0), 2.0) == pytest.approx(HEX_COVER * 100.0)
    assert cover((5.0, 20.0), 2.0) == pytest.approx(HEX_COVER * 375.0 / 4.0)
    # a band search with 48 measurements reaches R: 1.209 (R² − 25) / 4 = 48
    reach = np.sqrt(48 * 4.0 / HEX_COVER + 25.0)
    assert ceiling(60, 12, 2.0, (5.0, 20.0)) == pytest.approx((reach - 5.0) / 15.0)
    assert ceiling(10, 12, 2.0, (5.0, 20.0)) == 0.0
    assert ceiling(10_000, 12, 2.0, (5.0, 20.0)) == 1.0


def test_radius_interpolates_the_90_percent_crossing():
    angles = np.array([0.0, 1.0, 2.0, 3.0])
    assert radius(angles, np.array([1.0, 1.0, 0.8, 0.0])) == pytest.approx(1.5)
    assert radius(angles, np.ones(4)) == 3.0
    assert radius(angles, np.zeros(4)) == 0.0


def test_quick_run_writes_the_table(tmp_path):
    out = tmp_path / "detection.md"
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "detection_range.py"),
            "--quick",
            "--snr",
            "30",
            "--out-md",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    text = out.read_text(encoding="utf-8")
    assert "matched-filter peak" in text and "| 30 |" in text
