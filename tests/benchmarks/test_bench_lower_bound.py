"""The lower-bound benchmark: its bound against closed forms, and a ``--smoke`` run end to
end (no thresholds on auto's numbers: 2 runs say nothing about a 99th percentile)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "bench_lower_bound.py"


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import bench_lower_bound
    finally:
        sys.path.pop(0)
    return bench_lower_bound


def test_a_sure_disc_of_radius_r_sees_pi_r_squared(bench):
    # p = 1 up to r, 0 beyond: K = π r² (the trapezoid's error is O(step·r) at the edge)
    r, step = 2.0, 1e-3
    angles = np.arange(0.0, 5.0 + step / 2, step)
    k = bench.seen_area(angles, (angles <= r).astype(float))
    assert k == pytest.approx(math.pi * r**2, rel=2e-3)


def test_the_bound_is_the_annulus_over_the_seen_area(bench):
    # 5–20° with K = π·4² (a sure 4° disc): 0.99 · (400 − 25)/16 = 23.2 → 24 measurements
    assert bench.detection_bound((5.0, 20.0), math.pi * 16.0) == 24
    # a disc is covered by one measurement that sees all of it
    assert bench.detection_bound((0.0, 1.0), math.pi * 4.0) == 1


def test_lower_bound_smoke_runs_and_reports(tmp_path):
    out_md = tmp_path / "lb.md"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--smoke", "--workers", "1", "--out-md", str(out_md)],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "HEADLINE immersion-5mhz far 30 dB: bound" in proc.stdout
    text = out_md.read_text()
    assert text.startswith("# Lower bound on measurements vs `auto`")
    assert "N ≥ 0.99 · A / K" in text and "| 30 |" in text
