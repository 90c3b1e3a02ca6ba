"""The calibration benchmark's CMA-ES peer (optional: pycma) and its hold-out seeds
(``--seed-offset``)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from echocal.errors import BudgetExhaustedError

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))

import _peers  # noqa: E402  (a script directory, not a package)
import bench_calibration  # noqa: E402


class _Lobe:
    """A noiseless Gaussian echo of 1° peaking at ``peak`` [deg], with the budget's
    counting of a :class:`~echocal.measurement.SourceObjective` (all the peer sees)."""

    def __init__(self, peak: np.ndarray, budget: int) -> None:
        self.peak, self.budget, self.n_measurements = peak, budget, 0

    def __call__(self, points: np.ndarray) -> np.ndarray:
        if self.n_measurements + len(points) > self.budget:
            raise BudgetExhaustedError("budget spent")
        self.n_measurements += len(points)
        return np.exp(-0.5 * np.sum((points - self.peak) ** 2, axis=1))


def test_a_missing_peer_is_skipped_with_its_reason_not_a_crash():
    ok, skipped = _peers.available_peers(["cma-es"])
    assert (ok == ["cma-es"]) != ("cma-es" in skipped)
    if skipped:
        assert "cma" in skipped["cma-es"]  # the import that failed


def test_cma_es_climbs_a_lobe_and_reports_an_estimate_per_measurement():
    pytest.importorskip("cma")
    peak, x0, budget = np.array([1.5, -1.0]), np.array([0.0, 0.5]), 80
    lobe = _Lobe(peak, budget)
    tracker = _peers._Tracker(lobe)  # type: ignore[arg-type]
    box = _peers._box(x0, 4.0, np.array([[-30.0, 30.0], [-30.0, 30.0]]))
    with pytest.raises(_peers._Stop):
        _peers._peer_cma(tracker, x0, box, seed=3)
    history = tracker.history_override
    assert history is not None and len(history) == budget == lobe.n_measurements
    np.testing.assert_allclose(history[0], x0)  # no generation told yet: the start
    # 13 generations of 6 from 1.8° away on a noiseless lobe: the mean within 0.2° of the
    # peak (seeds 0-4 end 0.06-0.17° away; CMA-ES spends its first generations adapting σ)
    assert np.hypot(*(history[-1] - peak)) < 0.2


@pytest.mark.slow  # two seeded runs and the benchmark's imports: ~15 CPU-s
def test_seed_offset_runs_the_run_indices_after_it(tmp_path):
    out = tmp_path / "r.json"
    argv = ["--smoke", "--methods", "auto", "--runs", "1", "--seed-offset", "1"]
    assert bench_calibration.main([*argv, "--workers", "1", "--json", str(out)]) == 0
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["seed_offset"] == 1
    (run,) = data["raw"]
    assert run["run"] == 1  # the second run of a default benchmark, not its first
    again = bench_calibration.run_one(("thesis", "near", 30.0, 1, "auto"))
    assert run["errors"] == again["errors"]
    with pytest.raises(SystemExit):
        bench_calibration.main([*argv[:-1], "-1"])
