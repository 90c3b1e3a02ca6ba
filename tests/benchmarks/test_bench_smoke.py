"""Smoke test of the simulator benchmark script: it runs ``--quick`` (~10 s), prints its
headline and writes consistent JSON and Markdown.  No timing thresholds (speed is the
benchmark's report)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "bench_ascan.py"

HEADLINES = (
    "HEADLINE one A-scan, fast path:",
    "HEADLINE one A-scan, direct:",
    "HEADLINE fast vs direct:",
    "HEADLINE batch of 1 poses:",
    "HEADLINE batch of 10 poses:",
    "HEADLINE cost map",
    "HEADLINE ray-mesh casting, echocal (numpy):",
)


def _positive(x: float) -> bool:
    return math.isfinite(x) and x > 0


@pytest.mark.slow  # 14 CPU-s: the slow tier
def test_bench_ascan_smoke_runs_and_reports(tmp_path):
    out_json = tmp_path / "ascan.json"
    out_md = tmp_path / "ascan.md"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--json", str(out_json), "--out-md", str(out_md)],
        capture_output=True,
        text=True,
        timeout=300,  # a loaded 2-core machine; the --quick run itself takes ~10 s
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    for line in HEADLINES:
        assert line in proc.stdout, f"missing {line!r} in:\n{proc.stdout}"

    data = json.loads(out_json.read_text(encoding="utf-8"))
    assert data["mode"] == "quick"
    assert data["machine"]["cores"] >= 1
    head = data["headline"]
    assert _positive(head["fast"]["median"]) and _positive(head["direct"]["median"])
    # the ratio is the quotient of the two medians it reports
    assert math.isclose(
        head["ratio_direct_over_fast"],
        head["direct"]["median"] / head["fast"]["median"],
        rel_tol=1e-12,
    )
    for n, row in data["batches"].items():
        assert math.isclose(row["per_ascan"], row["median"] / int(n), rel_tol=1e-12)
    side = data["cost_map"]["side"]
    assert math.isclose(
        data["cost_map"]["per_pose"], data["cost_map"]["median"] / side**2, rel_tol=1e-12
    )
    # every caster that ran agrees with echocal's numpy engine on (almost) every ray
    for name, row in data["mesh"]["throughput"].items():
        assert row["agree"] >= 0.99, name

    md = out_md.read_text(encoding="utf-8")
    assert md.startswith("# Simulator benchmark")
    assert "| fast path, 1 pose |" in md
    assert "Fast vs direct:" in md
