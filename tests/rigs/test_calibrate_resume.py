"""``calibrate --rig`` resumes from the A-scans it saved: after a rig fault the same
command continues where the run stopped, measuring nothing twice, and returns the
uninterrupted run's result; a folder made with other settings, a damaged saved A-scan or
a run that asks for another pose than the saved one is refused in one line, before
anything is measured.

The rig is a lab's own python classes over the simulator in this process (the python
driver); its pulser fails at a chosen acquisition, as an unplugged scope would.
"""

from __future__ import annotations

import hashlib
import io
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cli_helpers import flat, run_main, simulated_lab, tiny_setup_toml
from echocal.setups import load_setup

ARGS = ["--position", "0,0,16", "--x0", "2,-1", "--method", "model-based", "--budget", "200"]
ARGS += ["--no-plots"]
BREAK_AT = 5  # the pulser fails at its 5th acquisition: 4 A-scans saved


class Lab:
    """The lab's module (a fresh simulator behind it each :meth:`restart`) and its rig file."""

    def __init__(self, folder: Path) -> None:
        self.setup = folder / "tiny.toml"
        self.setup.write_text(tiny_setup_toml(), encoding="utf-8")
        self.module, self.rig = simulated_lab(folder, f"lab_resume_{folder.name}", self.setup)
        self.restart()

    def restart(self) -> None:
        """A fresh simulator (the same seed: the same noise stream) and an empty log."""
        self.module.SOURCE = load_setup(self.setup)
        self.module.SERVED = []
        self.module.BREAK_AT = None

    @property
    def served(self) -> list[np.ndarray]:
        return self.module.SERVED


@pytest.fixture
def lab(tmp_path):
    made = Lab(tmp_path)
    yield made
    sys.path.remove(str(tmp_path))


def _run(lab: Lab, out: Path, capsys, monkeypatch, *extra: str) -> tuple[int, str, str]:
    args = ["calibrate", "--rig", str(lab.rig), *ARGS, *extra, "--out", str(out)]
    return run_main(args, capsys, monkeypatch)


def _interrupted(lab: Lab, out: Path, capsys, monkeypatch) -> None:
    """A run whose pulser fails at acquisition :data:`BREAK_AT`: 4 A-scans saved."""
    lab.module.BREAK_AT = BREAK_AT
    code, _, err = _run(lab, out, capsys, monkeypatch)
    assert code == 2 and "scope unplugged" in err, err
    assert "run the same command again to resume" in flat(err)
    assert len(lab.served) == BREAK_AT - 1
    lab.module.BREAK_AT = None


_REFERENCE: list[tuple[int, list[np.ndarray], dict[str, Any]]] = []
"""The uninterrupted run (exit code, A-scans served, result.json), computed once."""


def _reference(lab: Lab, tmp_path: Path, capsys, monkeypatch):
    """The uninterrupted run on a fresh simulator (the same seed and noise stream as every
    :meth:`Lab.restart`): its exit code, the A-scans it was served and its result."""
    if not _REFERENCE:
        code, _, err = _run(lab, tmp_path / "reference", capsys, monkeypatch)
        assert code in (0, 3), err
        result = json.loads((tmp_path / "reference" / "result.json").read_text())
        _REFERENCE.append((code, list(lab.served), result))
        lab.restart()
    return _REFERENCE[0]


@pytest.mark.parametrize("keep_log", [True, False], ids=["with-log", "killed-before-log"])
def test_after_a_rig_fault_the_same_command_resumes_to_the_uninterrupted_result(
    lab, keep_log, tmp_path, capsys, monkeypatch
):
    """The resumed run hands the 4 saved A-scans to the calibration, measures the rest on
    the rig, and ends with the uninterrupted run's result; the rig served each A-scan
    once.  Without partial_log.json (a process killed before writing it) the saved
    A-scans suffice."""
    code, reference, expected = _reference(lab, tmp_path, capsys, monkeypatch)
    out = tmp_path / "cal"
    _interrupted(lab, out, capsys, monkeypatch)
    if not keep_log:
        (out / "partial_log.json").unlink()
    again, _, err = _run(lab, out, capsys, monkeypatch)
    assert again == code, err
    assert f"resuming: {BREAK_AT - 1} measurements" in flat(err)
    assert len(lab.served) == len(reference)  # nothing measured twice
    for got, sent in zip(lab.served, reference, strict=True):
        np.testing.assert_array_equal(got, sent)
    result = json.loads((out / "result.json").read_text())
    for key in ("x", "n_measurements", "status", "values", "points", "message"):
        assert result[key] == expected[key], key
    assert result["provenance"]["resumed"] == {
        "measurements_from_log": BREAK_AT - 1,
        "measured_now": len(reference) - (BREAK_AT - 1),
    }
    assert "resumed" not in expected["provenance"]
    assert sorted(p.name for p in out.iterdir()) == ["ascan.nc", "result.json", "summary.json"]


def test_resuming_with_other_settings_is_refused_and_overwrite_starts_over(
    lab, tmp_path, capsys, monkeypatch
):
    out = tmp_path / "cal"
    _interrupted(lab, out, capsys, monkeypatch)
    saved = sorted((out / "partial_ascans").iterdir())
    code, _, err = _run(lab, out, capsys, monkeypatch, "--x0", "1,-1", "--seed", "3")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "cannot resume" in err and "another seed, x0_deg" in flat(err), err
    assert "x0_deg=[2.0, -1.0]" in flat(err) and "--overwrite" in err
    assert len(lab.served) == BREAK_AT - 1  # nothing measured
    assert sorted((out / "partial_ascans").iterdir()) == saved  # nothing touched
    code, _, err = _run(lab, out, capsys, monkeypatch, "--x0", "1,-1", "--overwrite")
    assert code in (0, 3), err
    assert "resuming" not in err
    result = json.loads((out / "result.json").read_text())
    assert "resumed" not in result["provenance"] and result["iterates"][0] == [1.0, -1.0]
    assert not (out / "partial_ascans").exists()


def test_a_damaged_saved_ascan_is_refused_before_anything_is_measured(
    lab, tmp_path, capsys, monkeypatch
):
    out = tmp_path / "cal"
    _interrupted(lab, out, capsys, monkeypatch)
    damaged = out / "partial_ascans" / "000002.npz"
    data = bytearray(damaged.read_bytes())
    data[-100] ^= 0x01  # one flipped bit
    damaged.write_bytes(bytes(data))
    code, _, err = _run(lab, out, capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert f"cannot resume: {damaged} is damaged" in flat(err) and "SHA-256" in err
    assert len(lab.served) == BREAK_AT - 1


def test_a_resumed_run_asking_for_another_pose_is_refused(lab, tmp_path, capsys, monkeypatch):
    """A saved A-scan measured for another pose than the one the resumed run asks for
    (here: its pose edited, checksum and all) is one error, not a silent divergence."""
    out = tmp_path / "cal"
    _interrupted(lab, out, capsys, monkeypatch)
    folder = out / "partial_ascans"
    with np.load(folder / "000002.npz") as npz:
        arrays: dict[str, Any] = {key: npz[key] for key in npz.files}
    arrays["requested"] = arrays["requested"] + [0, 0, 0, 0.5, 0]  # 0.5 deg of azimuth
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    (folder / "000002.npz").write_bytes(buffer.getvalue())
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["ascans"][2]["sha256"] = hashlib.sha256(buffer.getvalue()).hexdigest()
    (folder / "manifest.json").write_text(json.dumps(manifest))
    code, _, err = _run(lab, out, capsys, monkeypatch)
    assert code == 2 and err.count("error:") == 1 and "Traceback" not in err, err
    assert "cannot resume: measurement 3 asks for pose" in flat(err), err
    assert "diverged" in err and "saved one" in err
    assert len(lab.served) == BREAK_AT - 1  # the rig measured nothing
    assert len(list(folder.glob("*.npz"))) == BREAK_AT - 1


def test_a_run_off_the_rig_with_overwrite_leaves_nothing_to_resume(
    lab, tmp_path, capsys, monkeypatch
):
    """A simulated calibration written over a rig run's folder with --overwrite removes
    its saved A-scans: a later rig run starts afresh instead of resuming from them."""
    out = tmp_path / "cal"
    _interrupted(lab, out, capsys, monkeypatch)
    args = ["calibrate", "--setup", str(lab.setup), "--position", "0,0,16"]
    args += ["--x0", "2,-1", "--budget", "30", "--no-plots", "--out", str(out), "--overwrite"]
    code, _, err = run_main(args, capsys, monkeypatch)
    assert code in (0, 3), err
    assert not (out / "partial_ascans").exists()
    code, _, err = _run(lab, out, capsys, monkeypatch, "--overwrite")
    assert code in (0, 3), err
    assert "resuming" not in err
