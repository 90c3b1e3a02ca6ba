"""Two writers, one output (issue 15, "Two processes writing into one output folder"): every
writer holds an advisory lock on its output, and a second one is refused in one line
(exit 2) before it measures or writes anything.  The first writer's result is untouched.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_helpers import tiny_setup_toml
from echocal.errors import DataFileError
from echocal.locking import OutputLockedError, lock_file_path, output_lock

SWEEP = """
name = "pair"
setup = "thesis"
budget = 24
max_iter = 30
tolerance = 0.5
seeds = 3
snr_db = [30]
[x0]
offset = [1, 3]
[[methods]]
name = "model-based"
"""

COMMANDS = {
    "sweep run": (["sweep", "run", "pair.toml", "--out", "OUT", "--no-progress"], True),
    "scan": (
        ["scan", "--setup", "tiny.toml", "--grid", "0:0:1,0:0:1", "--z", "16", "--out", "OUT"],
        True,
    ),
    "record": (
        [
            "record",
            "--setup",
            "tiny.toml",
            "--azimuth",
            "0",
            "--coelevation",
            "0",
            "--out",
            "OUT.nc",
        ],
        False,
    ),
    "calibrate": (["calibrate", "--setup", "tiny.toml", "--out", "OUT", "--no-plots"], True),
    "simulate": (["simulate", "--setup", "tiny.toml", "--pose", "0,0,16", "--out", "OUT"], True),
}
"""Each writer's command line (OUT: its output) and whether OUT is a folder."""


def echocal(args: list[str], cwd: Path, **kwargs) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "echocal.cli", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    (tmp_path / "tiny.toml").write_text(tiny_setup_toml())
    (tmp_path / "pair.toml").write_text(SWEEP)
    return tmp_path


@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_second_writer_is_refused_in_one_line(command, folder):
    args, is_folder = COMMANDS[command]
    target = folder / ("OUT" if is_folder else "OUT.nc")
    with output_lock(target, folder=is_folder):  # another process is writing there
        process = echocal(args, folder)
        _, err = process.communicate(timeout=300)
    assert process.returncode == 2, err
    assert err.count("error:") == 1 and "Traceback" not in err
    assert "being written by another echocal process" in err and target.name in err
    if is_folder:  # nothing measured, nothing written (the lock's folder is removed again)
        assert not target.exists() or not any(target.iterdir())
    else:
        assert not target.exists() and not lock_file_path(target).exists()


@pytest.mark.slow
def test_two_sweeps_into_one_folder_at_once(folder):
    """The real race: the second `sweep run` is refused; the first completes untouched."""
    # long enough that the first is still running while the second process starts (a
    # calibration settles in a few measurements: 40 seeds once ended first on a busy CI)
    (folder / "long.toml").write_text(SWEEP.replace("seeds = 3", "seeds = 200"))
    args = ["sweep", "run", "long.toml", "--out", "out", "--no-progress", "--json"]
    first = echocal([*args, "--workers", "1"], folder)
    deadline = time.monotonic() + 600  # a stuck sweep, not a loaded machine
    while not (folder / "out" / "sweep.json").exists():
        assert first.poll() is None and time.monotonic() < deadline, first.communicate()
        time.sleep(0.02)
    second = echocal(args, folder)
    _, err = second.communicate(timeout=300)
    assert first.poll() is None  # the first was still writing when the second was refused
    out, first_err = first.communicate(timeout=300)
    assert second.returncode == 2 and "being written by another echocal process" in err, err
    assert first.returncode == 0, first_err
    summary = json.loads(out)
    assert summary["n_finished"] == 200 and summary["n_failed"] == 0
    assert not (folder / "out" / "parts").exists()  # consolidated, no stray part


def test_the_lock_is_reentrant_in_one_process_and_released_after(tmp_path):
    target = tmp_path / "grid.nc"
    with output_lock(target, folder=False), output_lock(target, folder=False):
        assert lock_file_path(target).exists()
    assert not lock_file_path(target).exists()  # removed on release
    with output_lock(tmp_path / "new-folder"):
        pass
    assert not (tmp_path / "new-folder").exists()  # created for the lock, left empty: gone


def test_lock_errors_are_data_file_errors():
    assert issubclass(OutputLockedError, DataFileError)
    assert issubclass(OutputLockedError, OSError)


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="needs setrlimit (POSIX)")
def test_a_scan_whose_final_write_fails_names_the_file_and_keeps_its_points(folder):
    """`ulimit -f`: the final NetCDF write is refused by the kernel. Before, HDF5 crashed
    (SIGSEGV, exit 139); now one error names the file, the points stay in the partial
    store, and the same command without the limit finishes the scan."""
    import resource

    args = ["scan", "--setup", "tiny.toml", "--grid", "-2:2:2,0:0:1", "--z", "16"]
    args += ["--no-figures", "--no-progress"]
    warm = echocal([*args, "--out", "warm"], folder)  # compiles and caches the kernels
    assert warm.wait(timeout=300) == 0, warm.communicate()

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (8192, resource.RLIM_INFINITY))

    limited = echocal([*args, "--out", "out"], folder, preexec_fn=small_files)
    _, err = limited.communicate(timeout=300)
    assert limited.returncode == 2, err  # not -11 (SIGSEGV) nor -25 (SIGXFSZ)
    assert err.count("error:") == 1 and "Traceback" not in err
    assert "cannot write out/scan.nc: File too large" in " ".join(err.split())
    assert (folder / "out" / "scan.nc.partial" / "points.jsonl").read_text().count("\n") == 3
    assert not list((folder / "out").glob(".scan.nc.*"))  # no half-written temporary
    again = echocal([*args, "--out", "out"], folder)
    _, err = again.communicate(timeout=300)
    assert again.returncode == 0, err
    assert (folder / "out" / "scan.nc").is_file()
