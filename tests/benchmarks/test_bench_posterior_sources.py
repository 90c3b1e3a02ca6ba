"""The posterior-on-sources benchmark's table from stored runs (no simulation)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import bench_posterior_sources


def _run(n_to: int | None, found_at: int | None, posterior: bool, cpu_s: float) -> dict:
    """A stored run whose error (3°) drops to 0.05° at measurement ``n_to`` (None: never)."""
    errors = np.full(101, 3.0)
    if n_to is not None:
        errors[n_to:] = 0.05
    return {
        "source": "rig",
        "start": "near",
        "snr": 20.0,
        "errors": errors.tolist(),
        "found_at": found_at,
        "posterior": posterior,
        "cpu_s": cpu_s,
    }


def test_the_table_counts_what_the_runs_say(tmp_path, capsys):
    # to 0.1° after 10, 20 and never: median 20, p90 and max ∞; echo found after 3, 5 and
    # never; two of three within 0.1° at the end (finals 0.05, 0.05, 3: p90 2.41° linear)
    runs = [_run(10, 3, True, 1.0), _run(20, 5, False, 2.0), _run(None, None, True, 3.0)]
    path = tmp_path / "runs.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in runs))
    assert bench_posterior_sources.main(["--summarize", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("| source | start | SNR | runs | posterior |")
    row = "| rig | near | 20 dB | 3 | 67% | 66.7% | 66.7% | 20/∞/∞ | 5/∞ | 0.050° / 2.410° | 2.0 |"
    assert lines[2:] == [row]
