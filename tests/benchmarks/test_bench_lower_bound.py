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


def test_the_best_lattice_covers_a_disc_of_radius_2_with_7_sure_discs_of_radius_1(bench):
    """Hand-checked: 7 discs of radius 1 cover a disc of radius 2 (the centre and six at
    √3, a hexagonal lattice) and 6 cannot (the classical covering result), so a measurement
    that detects surely within 1° and never beyond needs 7 lattice points to detect 99 % of
    optima within 2°; within 1°, one."""
    angles = np.arange(0.0, 3.0 + 5e-4, 1e-3)
    sure = (angles <= 1.0).astype(float)
    n, spacing = bench.lattice_search((0.0, 2.0), angles, sure, samples=4000)
    assert n == 7 and math.sqrt(3.0) * 0.95 <= spacing <= 2.0
    assert bench.lattice_search((0.0, 1.0), angles, sure, samples=4000)[0] == 1


@pytest.mark.parametrize("width", [0.7, 1.0, 1.5])
def test_no_lattice_beats_the_union_bound(bench, width):
    """The union bound holds for every placement, so the best lattice spends at least as
    many measurements (soft Gaussian detection curves of three widths [deg], cut at 4 widths,
    where p < 4·10⁻⁴: the search reaches no farther, and each side counts the same curve)."""
    angles = np.arange(0.0, 4.0 * width + 1e-3, 0.01)
    prob = np.exp(-0.5 * (angles / width) ** 2)
    band = (1.0, 4.0)
    n, _ = bench.lattice_search(band, angles, prob, samples=4000)
    assert bench.detection_bound(band, bench.seen_area(angles, prob)) <= n < math.inf


def test_lower_bound_smoke_runs_and_reports(tmp_path):
    out_md = tmp_path / "lb.md"
    proc = subprocess.run(
        [
            *(sys.executable, str(SCRIPT), "--smoke", "--workers", "1", "--budget", "60"),
            *("--out-md", str(out_md)),
        ],
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
    assert "--budget 60`" in text  # the run line reruns it with the budget it had


def test_a_budget_below_the_reading_point_is_refused(bench, capsys):
    with pytest.raises(SystemExit):
        bench.main(["--budget", "50"])
    assert "--budget must be at least 60" in capsys.readouterr().err
