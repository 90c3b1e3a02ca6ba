"""Results go to stdout (pipe and grep them), messages about the work to stderr."""

from __future__ import annotations

import json
import subprocess
import sys


def _run(*args: str, flags: tuple[str, ...] = ()) -> subprocess.CompletedProcess[str]:
    """``python [flags] -m echocal.cli args`` in a process of its own."""
    return subprocess.run(
        [sys.executable, *flags, "-m", "echocal.cli", *args],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_listing_is_on_stdout():
    done = _run("methods")
    assert done.returncode == 0, done.stderr
    assert "spsa" in done.stdout and "model-based" in done.stdout
    assert done.stderr == ""


def test_a_calibration_summary_is_on_stdout_and_json_stays_pure(tmp_path):
    """The human summary and the JSON object on stdout; and ``--no-plots`` never imports
    matplotlib (``-X importtime`` lists every import on stderr): a quarter of the run's
    imports were spent drawing nothing."""
    args = ("calibrate", "--setup", "thesis", "--x0", "0,0", "--budget", "20", "--no-plots")
    human = _run(*args, "--out", str(tmp_path / "a"))
    assert human.returncode in (0, 3), human.stderr  # converged, or stopped by --budget
    assert "estimate" in human.stdout and "measurements" in human.stdout
    machine = _run(*args, "--out", str(tmp_path / "b"), "--json", flags=("-X", "importtime"))
    assert machine.returncode == human.returncode, machine.stderr
    assert json.loads(machine.stdout)["n_measurements"] <= 20  # one JSON object, nothing else
    imported = {line.rsplit("|", 1)[-1].strip() for line in machine.stderr.splitlines()}
    assert "numpy" in imported  # the listing is there
    assert not {name for name in imported if name.split(".")[0] == "matplotlib"}
