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
    assert bench.area_bound((5.0, 20.0), math.pi * 16.0) == 24
    # a disc is covered by one measurement that sees all of it
    assert bench.area_bound((0.0, 1.0), math.pi * 4.0) == 1


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


@pytest.mark.parametrize(
    "width", [pytest.param(0.7, marks=pytest.mark.slow), 1.0, 1.5]
)  # 0.7: 15 CPU-s
def test_no_lattice_beats_the_union_bound(bench, width):
    """The union bound holds for every placement, so the best lattice spends at least as
    many measurements (soft Gaussian detection curves of three widths [deg], cut at 4 widths,
    where p < 4·10⁻⁴: the search reaches no farther, and each side counts the same curve)."""
    angles = np.arange(0.0, 4.0 * width + 1e-3, 0.01)
    prob = np.exp(-0.5 * (angles / width) ** 2)
    band = (1.0, 4.0)
    n, _ = bench.lattice_search(band, angles, prob, samples=4000)
    assert bench.area_bound(band, bench.seen_area(angles, prob)) <= n < math.inf


@pytest.mark.slow  # 14 CPU-s: the slow tier
def test_lower_bound_smoke_runs_and_reports(tmp_path, bench):
    out_md = tmp_path / "lb.md"
    kept = f"{bench.KEEP_MARKER}\n\n**Reading** by hand.\n"
    out_md.write_text("# an older run's page\n\n| old table |\n\n" + kept)
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
    # the any-search bound, its derivation's summary, and auto over it
    assert "any search needs at least" in proc.stdout
    assert "bound for any search (information / change of measure)" in text
    assert "The any-search bound (:func:`information_bound.search_bound`)" in text
    assert text.endswith(kept) and "old table" not in text  # the hand-written part is kept


def test_a_page_without_the_marker_keeps_nothing(tmp_path, bench):
    page = tmp_path / "lb.md"
    assert bench._kept_sections(page) == ""  # no page yet
    page.write_text("# generated only\n")
    assert bench._kept_sections(page) == ""


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--budget", "50"], "--budget must be at least 60"),
        (["--snr", "30,20", "--budget", "80,400,1200"], "3 budgets for 2 SNRs"),
        (["--budget", "eighty"], "--budget must be whole numbers"),
    ],
)
def test_a_budget_that_cannot_serve_is_refused(bench, capsys, options, message):
    with pytest.raises(SystemExit):
        bench.main(options)
    assert message in capsys.readouterr().err


def _sure(r: float, step: float = 1e-3, out_to: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """A detection curve [deg] that detects surely up to r and never beyond."""
    angles = np.arange(0.0, out_to + step / 2, step)
    return angles, (angles <= r).astype(float)


def test_the_ring_kernel_is_the_arc_a_sure_disc_covers(bench):
    """Hand-checked: a sure disc of radius r centred on the circle of radius ρ covers the
    arc 2·2·asin(r / 2ρ) of it, so P̄(ρ, ρ) = (2/π)·asin(r / 2ρ); a measurement at the start
    (s = 0) sees an optimum at ρ < r surely and one at ρ > r never."""
    angles, sure = _sure(1.0)
    kernel = bench.ring_kernel(np.array([10.0, 0.5, 1.5]), np.array([10.0, 0.0]), angles, sure)
    assert kernel[0, 0] == pytest.approx(2.0 / math.pi * math.asin(1.0 / 20.0), rel=2e-3)
    assert kernel[1, 1] == 1.0 and kernel[2, 1] == 0.0


def test_the_covering_programme_on_hand_checked_cases(bench):
    """A disc of radius 1 inside a sure disc of radius 2: one measurement at the start, and no
    fraction of one less (every optimum near the start needs Σ w ≥ y), so 0.99.  A curve that
    detects with 0.25 anywhere within 3°: 0.99 / 0.25 = 3.96 on a band within 1°.  A thin
    band at 10° and a sure 1° disc: the circle needs 0.99 · π / (2 asin(1/20)) = 31.09 (its
    circumference over the arc each disc covers) — the cells' maxima may only lower it."""
    angles, sure = _sure(2.0, out_to=4.0)
    assert bench.covering_bound((0.0, 1.0), angles, sure, cell=0.05) == pytest.approx(0.99)
    quarter = 0.25 * (angles <= 3.0)
    assert bench.covering_bound((0.0, 1.0), angles, quarter, cell=0.05) == pytest.approx(3.96)
    angles, sure = _sure(1.0)
    ring = bench.covering_bound((10.0, 10.02), angles, sure, cell=0.01)
    assert 0.98 * 31.09 <= ring <= 31.09 + 1e-6


def test_no_lattice_beats_the_covering_programme(bench):
    """The programme bounds every fixed sequence, so the best lattice (which samples the same
    start distribution) spends at least its rounded-up value (5.9 ≤ 15 here, a soft curve of
    width 1.5°; 20.3 ≤ 56 at 0.7°, a 30 s lattice search left out: the union bound Σp is
    loose where soft curves overlap); and on this band, narrow against the curve, the edges
    waste more than the start distribution's weight on the inner edge saves, so the
    programme is above the area bound (3.3)."""
    width = 1.5
    angles = np.arange(0.0, 4.0 * width + 1e-3, 0.01)
    prob = np.exp(-0.5 * (angles / width) ** 2)
    band = (1.0, 4.0)
    programme = bench.covering_bound(band, angles, prob)
    n, _ = bench.lattice_search(band, angles, prob, samples=4000)
    assert math.ceil(programme) <= n < math.inf
    assert programme > 0.99 * math.pi * (4.0**2 - 1.0**2) / bench.seen_area(angles, prob)
