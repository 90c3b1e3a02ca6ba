"""The tails benchmark's summary: counts, percentiles and coverage from stored runs (no
simulation), and one real run of a near cell (slow tier)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import bench_tails


def _row(n_to: int | None, error: float, radius: float | None) -> dict:
    """A stored run whose error stays above 0.1° until measurement ``n_to`` (None: never)."""
    errors = np.full(81, 5.0)
    if n_to is not None:
        errors[n_to:] = error
    return {
        "start": "far",
        "snr": 30.0,
        "run": 0,
        "errors": errors.tolist(),
        "error": float(errors[-1]),
        "uncertainty": radius,
        "false_alarms": 1 if n_to is None else 0,
        "cpu_seconds": 1.0,
    }


def test_the_summary_counts_what_the_runs_say(tmp_path, capsys):
    # 100 runs: 97 reach 0.1° after k = 10..58 (k = 10 + i // 2), two after 70, one never;
    # errors 0.001 within radius 0.002 except 5 (0.003)
    runs = [_row(10 + i // 2, 0.003 if i < 5 else 0.001, 0.002) for i in range(97)]
    runs += [_row(70, 0.001, 0.002), _row(70, 0.001, None), _row(None, 5.0, None)]
    s = bench_tails.summarize(runs)
    assert s["runs"] == 100 and s["success"] == 0.99 and s["within_at"] == 0.97
    # percentiles "higher": the sorted counts' entries ceil(q (n - 1)), 0-based
    counts = sorted([10 + i // 2 for i in range(97)] + [70, 70, np.inf])
    assert (s["median"], s["p90"], s["p99"]) == (counts[50], counts[90], counts[99])
    assert (s["median"], s["p90"], s["p99"]) == (35, 55, np.inf)
    assert s["false_alarms"] == 1
    assert s["coverage"] == 0.93 and s["reported"] == 0.98  # 5 too far, 2 without a radius
    path = tmp_path / "runs.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in runs))
    assert bench_tails.main(["--summarize", str(path)]) == 0
    out = capsys.readouterr().out
    assert "| far | 30 dB | 100 | 99.0% | 97.0% | 35 / 55 / >80 | 1 | 93.0% | 98.0% |" in out


@pytest.mark.slow  # ~3 CPU-s with the wave model's kernels compiled
def test_one_run_of_a_near_cell(tmp_path):
    path = tmp_path / "t.jsonl"
    args = ["--runs", "1", "--snr", "30", "--starts", "near", "--jsonl", str(path)]
    assert bench_tails.main(args) == 0
    (row,) = [json.loads(line) for line in path.read_text().splitlines()]
    assert row["run"] == 0 and len(row["errors"]) == 81
    assert row["error"] < 0.1 and row["uncertainty"] is not None
