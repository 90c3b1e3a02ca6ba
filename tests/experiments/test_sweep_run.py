"""Running sweeps: pure runs, incremental storage, kill-and-resume, refusal of a foreign folder,
the same results from local processes and from a real Dask cluster, summaries, CLI."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from echocal.cli import app
from echocal.errors import ConfigError, EchocalValueError
from echocal.evaluation import angular_error
from echocal.experiments import expand, load_results, load_sweep, run_case, run_sweep, summarize

TINY = {
    "name": "tiny",
    "setup": "thesis",
    "budget": 24,
    "max_iter": 30,
    "tolerance": 0.5,
    "seeds": 3,
    "snr_db": [30],
    "x0": {"offset": [1, 3]},
    "methods": [{"name": "model-based"}, {"name": "spsa", "preset": "thesis"}],
}
TIMING = ["wall_time"]


def _same(a: pd.DataFrame, b: pd.DataFrame, key: list[str]) -> None:
    """Bit-identical tables after sorting (wall times excluded: they measure the machine)."""
    a = a.drop(columns=[c for c in TIMING if c in a]).sort_values(key).reset_index(drop=True)
    b = b.drop(columns=[c for c in TIMING if c in b]).sort_values(key).reset_index(drop=True)
    pd.testing.assert_frame_equal(a, b, check_exact=True)


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The tiny sweep run in this process, uninterrupted."""
    out = tmp_path_factory.mktemp("reference")
    results = run_sweep(TINY, out, workers=1, progress=False)
    assert results.complete and results.n_new == 6
    return results.runs, results.history


def test_run_is_pure_and_consistent():
    case = next(c for c in expand(load_sweep(TINY)) if c.method == "model-based")
    row, history = run_case(case)
    again, history_again = run_case(case)
    assert {k: v for k, v in row.items() if k != "wall_time"} == {
        k: v for k, v in again.items() if k != "wall_time"
    }
    pd.testing.assert_frame_equal(history, history_again, check_exact=True)
    assert row["status"] >= 0, row["message"]
    assert len(history) == row["n_measurements"] <= TINY["budget"]
    assert list(history["index"]) == list(range(len(history)))
    truth = np.array([row["truth_tilt_x_deg"], row["truth_tilt_y_deg"]])
    # the random start lies 1..3 deg from the truth (tilts: deg of the parameterization)
    start = [row["x0_tilt_x_deg"], row["x0_tilt_y_deg"]]
    assert 1.0 <= np.hypot(start[0] - truth[0], start[1] - truth[1]) <= 3.0
    # the stored error is the beam angle between estimate and truth, recomputed here
    estimate = [row["estimate_tilt_x_deg"], row["estimate_tilt_y_deg"]]
    assert row["error_deg"] == pytest.approx(float(angular_error(estimate, truth, "tilt")))
    assert row["success"] == (row["error_deg"] <= TINY["tolerance"])
    if row["success"]:
        assert 0 <= row["measurements_to_tol"] <= row["n_measurements"]


def test_killed_sweep_resumes_to_the_same_rows(reference, tmp_path):
    stored = []

    def die_after_two(row):
        stored.append(row["case_id"])
        if len(stored) == 2:
            raise KeyboardInterrupt  # what Ctrl-C does mid-sweep

    with pytest.raises(KeyboardInterrupt):
        run_sweep(TINY, tmp_path, workers=1, progress=False, callback=die_after_two)
    partial = load_results(tmp_path)
    assert sorted(partial.runs["case_id"]) == sorted(stored) and not partial.complete
    resumed = run_sweep(TINY, tmp_path, workers=2, progress=False)
    assert resumed.n_new == 4 and resumed.complete
    assert not (tmp_path / "parts").exists()  # consolidated
    _same(resumed.runs, reference[0], ["case_id"])
    _same(resumed.history, reference[1], ["case_id", "index"])
    assert run_sweep(TINY, tmp_path, progress=False).n_new == 0  # nothing left to do


def test_process_killed_by_signal_resumes(reference, tmp_path):
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(_toml(TINY), encoding="utf-8")
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "echocal.cli", "sweep", "run", str(sweep), "--out", str(out)]
    proc = subprocess.Popen([*cmd, "--workers", "1", "--no-progress"], stderr=subprocess.PIPE)
    deadline = time.monotonic() + 600  # generous: a stuck sweep, not a loaded machine
    while len(list((out / "parts").glob("runs-*.parquet"))) < 2:
        assert proc.poll() is None, proc.stderr.read().decode()
        assert time.monotonic() < deadline, "the sweep stored fewer than two runs in 10 min"
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)  # no cleanup at all
    proc.wait()
    assert not (out / "runs.parquet").exists()
    done = len(load_results(out).runs)
    assert 2 <= done < 6
    resume = [sys.executable, "-X", "importtime", *cmd[1:], "--no-progress"]
    result = subprocess.run(resume, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert f"{done} already done" in result.stdout.replace("\n", " ")  # the result: stdout
    # its table needs no matplotlib (-X importtime lists every import on stderr)
    imported = {line.rsplit("|", 1)[-1].strip() for line in result.stderr.splitlines()}
    assert "numpy" in imported and "matplotlib" not in imported
    final = load_results(out)
    _same(final.runs, reference[0], ["case_id"])
    _same(final.history, reference[1], ["case_id", "index"])


def test_folder_of_another_sweep_is_refused(reference, tmp_path):
    run_sweep({**TINY, "seeds": 1}, tmp_path, workers=1, progress=False)
    before = {p: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()}
    with pytest.raises(ConfigError, match="holds another sweep.*--overwrite"):
        run_sweep({**TINY, "seeds": 2}, tmp_path, workers=1, progress=False)
    assert {p: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()} == before
    replaced = run_sweep({**TINY, "seeds": 2}, tmp_path, workers=1, progress=False, overwrite=True)
    assert replaced.n_new == 4 and len(replaced.runs) == 4
    assert json.loads((tmp_path / "sweep.json").read_text())["n_cases"] == 4
    other = tmp_path / "notes"
    other.mkdir()
    (other / "thesis.pdf").write_bytes(b"%PDF")
    with pytest.raises(ConfigError, match="not sweep results"):
        run_sweep(TINY, other, workers=1, progress=False, overwrite=True)
    assert (other / "thesis.pdf").read_bytes() == b"%PDF"


def test_dask_cluster_equals_local_run(reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    # separate scheduler and worker processes talking TCP on loopback
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        results = run_sweep(TINY, tmp_path, scheduler=cluster.scheduler_address, progress=False)
        with distributed.Client(cluster.scheduler_address) as client:
            worker_pids = set(client.run(os.getpid).values())
    assert len(worker_pids) == 2 and os.getpid() not in worker_pids
    assert results.complete
    _same(results.runs, reference[0], ["case_id"])
    _same(results.history, reference[1], ["case_id", "index"])


def test_summary_against_hand_computed_values():
    runs = pd.DataFrame(
        {
            "method": ["m"] * 4 + ["n"] * 2,
            "label": ["m"] * 4 + ["n"] * 2,
            "preset": [None] * 6,
            "params": ["{}"] * 6,
            "snr_db": [10.0] * 4 + [np.nan] * 2,
            "x0_kind": ["point"] * 6,
            "success": [True, True, True, False, False, False],
            "measurements_to_tol": pd.array([10, 20, 40, None, None, None], dtype="Int64"),
            "iterations_to_tol": pd.array([1, 2, 4, None, None, None], dtype="Int64"),
            "n_measurements": [50, 50, 50, 50, 30, 30],
            "status": [1, 1, 1, 1, 2, -1],
            "error_deg": [0.1, 0.2, 0.3, 5.0, 2.0, np.nan],
        }
    )
    table = summarize(runs)
    m, n = table.iloc[0], table.iloc[1]
    assert (m["runs"], m["success_rate"]) == (4, 0.75)
    assert m["median_measurements_to_tol"] == 20.0
    assert m["p90_measurements_to_tol"] == pytest.approx(36.0)  # 20 + 0.8 × (40 − 20)
    assert m["expected_measurements_to_success"] == pytest.approx(50 / 0.75)
    assert m["median_error_deg"] == pytest.approx(0.25)
    assert np.isnan(n["snr_db"]) and n["failed"] == 1 and n["success_rate"] == 0.0
    assert np.isnan(n["median_measurements_to_tol"])
    assert n["expected_measurements_to_success"] == np.inf


def test_cli_run_and_summary(reference, tmp_path):
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(_toml({**TINY, "seeds": 1}), encoding="utf-8")
    runner = CliRunner()
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["sweep", "run", str(sweep), "--out", str(out), "--workers", "1", "--json"]
    )
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["n_cases"] == data["n_new"] == 2
    assert {row["method"] for row in data["summary"]} == {"model-based", "spsa"}
    summary = runner.invoke(app, ["sweep", "summary", str(out)])
    assert summary.exit_code == 0 and "model-based" in summary.output
    refused = runner.invoke(app, ["sweep", "run", "quick", "--out", str(out)])
    assert isinstance(refused.exception, ConfigError)  # `echocal` shows it as one line, exit 2
    check = runner.invoke(app, ["sweep", "check", str(sweep), "--json"])
    assert json.loads(check.stdout)["n_cases"] == 2


def _toml(data: dict) -> str:
    """A minimal TOML writer for the flat test sweeps above."""
    lines = []
    tables = {k: v for k, v in data.items() if isinstance(v, dict)}
    for key, value in data.items():
        if key not in tables and key != "methods":
            lines.append(f"{key} = {json.dumps(value)}")
    for key, table in tables.items():
        lines.append(f"[{key}]")
        lines += [f"{k} = {json.dumps(v)}" for k, v in table.items()]
    for method in data["methods"]:
        lines.append("[[methods]]")
        lines += [f"{k} = {json.dumps(v)}" for k, v in method.items()]
    return "\n".join(lines) + "\n"


def test_a_failing_run_is_recorded_not_fatal(tmp_path, monkeypatch):
    # a run that raises while running (the configuration checks cannot foresee it, so a
    # failure is injected in the judging step) is stored with status -1, not fatal
    import echocal.evaluation

    def broken(*args, **kwargs):
        raise EchocalValueError("judging failed")

    monkeypatch.setattr(echocal.evaluation, "evaluate_run", broken)
    sweep = {**TINY, "seeds": 1, "methods": [{"name": "newton"}]}
    results = run_sweep(sweep, tmp_path, workers=1, progress=False)
    row = results.runs.iloc[0]
    assert row["status"] == -1 and row["message"] == "judging failed"
    assert not row["success"] and row["n_measurements"] == 0
    assert results.summary()["failed"].tolist() == [1]
    assert results.n_failed == 1
    assert results.most_common_failure() == ("judging failed", 1)
