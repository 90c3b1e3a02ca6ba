"""Smoke test of the calibration benchmark script: it runs ``--quick`` on one cell with 2
runs (the full ``--quick`` takes ~3 min), prints its headline and writes consistent JSON
and Markdown.  No thresholds on the numbers (2 runs say nothing
about success rates; the numbers are the benchmark's report)."""

from __future__ import annotations

import importlib
import json
import math
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "bench_calibration.py"


def _benchmark_module(name: str) -> ModuleType:
    """A module of the benchmarks folder (a script directory, not a package)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.pop(0)


@pytest.mark.slow  # 30 CPU-s: the slow tier
def test_bench_calibration_smoke_runs_and_reports(tmp_path):
    out_json, out_md, out_png = tmp_path / "c.json", tmp_path / "c.md", tmp_path / "c.png"
    proc = subprocess.run(
        [
            sys.executable,
            str(SCRIPT),
            "--quick",
            "--cases",
            "thesis",
            "--starts",
            "near",
            "--snr",
            "30",
            "--runs",
            "2",
            "--workers",
            "1",
            "--json",
            str(out_json),
            "--out-md",
            str(out_md),
            "--plot",
            str(out_png),
        ],
        capture_output=True,
        text=True,
        timeout=300,  # a loaded shared 2-core machine; the smoke run itself takes ~20 s
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "HEADLINE thesis: fewest measurements to 0.1 deg (median):" in proc.stdout
    assert "HEADLINE total time" in proc.stdout

    data = json.loads(out_json.read_text(encoding="utf-8"))
    assert data["mode"] == "quick" and data["runs_per_cell"] == 2
    # every peer is either run or reported as skipped (optional dependencies)
    ours = {"auto", "model-based", "newton", "quasi-newton", "spsa", "gradient"}
    assert ours <= set(data["methods"])
    for peer in _benchmark_module("_peers").PEERS:
        assert (peer in data["methods"]) + (peer in data["skipped_peers"]) == 1, peer
        if peer in data["skipped_peers"]:
            assert f"SKIPPED peer {peer}" in proc.stdout
    # every method that ran has the same number of runs (no per-method caps)
    assert {r["method"] for r in data["raw"]} == set(data["methods"])
    assert len(data["raw"]) == len(data["methods"]) * data["runs_per_cell"]
    budget = data["budget"]
    for run in data["raw"]:
        # the shared objective enforces the budget for every method, peers included
        assert run["n_measurements"] <= budget
        assert len(run["errors"]) == budget + 1
        assert all(math.isfinite(e) and 0.0 <= e < 180.0 for e in run["errors"])
    # the summary is derived from the raw runs: success at the budget = final error <= tol
    summary = data["cases"]["thesis"]
    for method, s in summary.items():
        finals = [r["errors"][-1] for r in data["raw"] if r["method"] == method]
        assert s["runs"] == len(finals)
        assert math.isclose(s["success_0.1"], sum(e <= 0.1 for e in finals) / len(finals))
    md = out_md.read_text(encoding="utf-8")
    assert md.startswith("# Calibration benchmark")
    # the page can be rerun: the exact command and the commit that made it
    commit = data["machine"]["echocal_git"]
    assert "`python benchmarks/bench_calibration.py --quick --cases thesis" in md
    assert commit is None or f"at echocal {commit} " in md
    assert "## thesis" in md and "| method |" in md
    assert "| thesis, start 1–3°, 30 dB | " in md  # the best of echocal and the best peer
    assert out_png.stat().st_size > 1000
    # the page again from the JSON alone, identical but for the figure's name
    again, again_png = tmp_path / "again.md", tmp_path / "again.png"
    render = [sys.executable, str(SCRIPT), "--render", str(out_json)]
    done = subprocess.run(
        [*render, "--out-md", str(again), "--plot", str(again_png)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert again.read_text(encoding="utf-8") == md.replace("(c.png)", "(again.png)")
    assert again_png.stat().st_size > 1000
    damaged = tmp_path / "damaged.json"
    damaged.write_text('{"mode": "quick"', encoding="utf-8")
    done = subprocess.run(
        [*render[:3], str(damaged), "--out-md", str(tmp_path / "x.md")],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert done.returncode == 2 and done.stdout.startswith(f"error: --render {damaged}")
    assert not (tmp_path / "x.md").exists()

    # one method run again on the JSON's cells and seeds: the others' runs kept as they were
    others = [r for r in data["raw"] if r["method"] != "auto"]
    update = [sys.executable, str(SCRIPT), "--update", str(out_json), "--workers", "1"]
    done = subprocess.run(
        [*update, "--methods", "auto"], capture_output=True, text=True, timeout=300, cwd=ROOT
    )
    assert done.returncode == 0, done.stdout + done.stderr[-3000:]
    updated = json.loads(out_json.read_text(encoding="utf-8"))
    assert [r for r in updated["raw"] if r["method"] != "auto"] == others
    reruns = [r for r in updated["raw"] if r["method"] == "auto"]
    assert len(reruns) == data["runs_per_cell"] and updated["methods"] == data["methods"]
    assert updated["updates"][0]["methods"] == ["auto"]
    assert updated["updates"][0]["echocal_git"] == commit
    done = subprocess.run(
        [*render, "--out-md", str(again)], capture_output=True, text=True, timeout=120, cwd=ROOT
    )
    assert "--update" in again.read_text(encoding="utf-8").split("## Method")[0]
    for wrong, message in (
        (["--methods", "simplex"], "not in"),  # a method the JSON never ran
        (["--methods", "auto", "--runs", "3"], "--update JSON takes --methods"),
    ):
        done = subprocess.run([*update, *wrong], capture_output=True, text=True, cwd=ROOT)
        assert done.returncode == 2 and message in done.stdout + done.stderr


@pytest.mark.slow  # 30 CPU-s: the slow tier
def test_the_back_wall_case_and_the_front_first_workflow():
    """The gated case is judged against the truth inside its gate: a flat, level plate's
    back wall is strongest at normal incidence (the independent truth; 1e-4° is the truth
    search's tolerance, 1e-5°, with margin).  The workflow (the whole recording until
    settled, then the gate, on one budget) on the cheap thesis setup with its front-wall
    gate: both stages' estimates, one per measurement, and every measurement counted."""
    import dataclasses

    bench_calibration = _benchmark_module("bench_calibration")
    from echocal.measurement import ReceiverSettings
    from echocal.signal.gates import resolve_gate

    case = bench_calibration._case("plate-back-wall")
    assert case.gate is not None and case.gate.name == "back-wall"
    assert np.hypot(*case.truth) < 1e-4 and case.optima.shape == (1, 2)

    thesis = bench_calibration._case("thesis")
    setup = dataclasses.replace(thesis.setup, receiver=ReceiverSettings(snr_db=30.0), rng=3)
    gate = resolve_gate("front-wall", pulse=setup.pulse)
    x0 = thesis.truth + np.array([1.5, -1.0])
    est, status, _, spent = bench_calibration._front_first(setup, thesis.position, gate, x0, 40)
    assert status.startswith("7/") and spent == 40 and est.shape == (41, 2)  # two stages
    np.testing.assert_array_equal(est[0], x0)
    assert np.hypot(*(est[-1] - thesis.truth)) < 0.2
    est, status, _, spent = bench_calibration._front_first(setup, thesis.position, gate, x0, 22)
    assert "/" not in status and spent == 22 and est.shape == (23, 2)  # no room for two
