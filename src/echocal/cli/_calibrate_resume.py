"""``echocal calibrate`` on a rig resumes after a signal or a fault (private).

While a calibration runs on a rig (``--rig FILE`` or ``--instrument HOST:PORT``), every
A-scan the rig delivers is saved at once in ``--out/partial_ascans/``: one ``.npz`` file
per measurement (its samples, sampling frequency, first-sample time, the pose asked for
and the pose reached), written atomically and listed with its SHA-256 in
``manifest.json``, beside the run's *fingerprint* (method and options, setup digest,
rig file digest or address, position, parameterization, x0, seed, gate).  A signal waits
for the measurement in progress and the saving of its A-scan
(:func:`echocal._signals.measuring`), so nothing the rig delivered is lost or measured
twice.

The same command again resumes: the calibration is deterministic given its seed and the
values it is told, so it starts over and :class:`ResumedRig` hands it the saved A-scans
for the first requested poses — each pose checked against the one saved — before it
measures anything on the rig.  The result equals an uninterrupted run's on the same
A-scans.  A run with other settings refuses the folder in one line.  The folder and its
manifest are an :class:`echocal.io.ChecksummedManifest`.
"""

from __future__ import annotations

import io
import json
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from echocal._signals import measuring, saving
from echocal.ascan import AScan
from echocal.errors import DataFileError
from echocal.geometry import Pose
from echocal.io import ChecksummedManifest, json_ready
from echocal.measurement.base import BaseSource

__all__ = [
    "JOURNAL",
    "POSE_TOLERANCE",
    "AScanJournal",
    "ResumeMismatch",
    "ResumedRig",
    "Tally",
    "discard_journal",
    "fingerprint",
    "resumable",
]

JOURNAL = "partial_ascans"
"""The folder, in ``--out``, of the A-scans a calibration on a rig has measured so far."""

FORMAT = "calibrate-partial/1"
"""``format`` of the journal's ``manifest.json``."""

POSE_TOLERANCE = 1e-9
"""[m] and [deg] how far a requested pose may lie from the saved one on resume: the resumed
run asks the very same numbers (same code, seed and values), so only float round-off."""


class ResumeMismatch(DataFileError):
    """The resumed run asked for another pose than the saved measurement's (it diverged)."""


def fingerprint(
    run: Any,
    *,
    setup: str | None,
    source: dict[str, Any],
    position: Any,
    parameterization: str,
    x0: tuple[float, float],
    seed: int,
    gate: Any,
) -> dict[str, Any]:
    """What makes a calibration on a rig the same run: ``run``'s method and options, the
    setup's digest, the ``source`` (a rig file's path and SHA-256, or an address),
    ``position`` [m], ``parameterization``, ``x0`` [deg], ``seed`` and ``gate`` — as
    plain JSON data."""
    from echocal.setup_digest import setup_digest

    record = {
        "method": run.method,
        "budget": run.budget,
        "max_iter": run.max_iter,
        "settle": run.settle,
        "preset": run.preset,
        "options": {**run.extra, **run.search, **run.run_keywords},
        "setup": None if setup is None else setup_digest(setup),
        "source": source,
        "position_m": [float(v) for v in position],
        "parameterization": parameterization,
        "x0_deg": [float(v) for v in x0],
        "seed": seed,
        "gate": None if gate is None else gate.describe(),
    }
    return json.loads(json.dumps(json_ready(record), sort_keys=True))


def resumable(out: Path) -> bool:
    """Whether ``out`` holds the saved measurements of a calibration on a rig (the same
    command resumes it, though the folder is not empty)."""
    return (out / JOURNAL / "manifest.json").is_file()


def discard_journal(out: Path) -> None:
    """Remove the saved measurements of a calibration on a rig from ``out`` (another run
    replaces that folder's contents with ``--overwrite``: a later rig run must not resume
    from them)."""
    shutil.rmtree(out / JOURNAL, ignore_errors=True)


class AScanJournal:
    """The A-scans of one calibration on a rig, one file each, in ``folder``.

    ``saved`` lists the measurements found when it was opened (resumed), in order, as
    ``(requested pose (5,) [m, deg], AScan)``; :meth:`keep` adds each new one.  The
    folder is made with the first measurement.  Each :meth:`keep` rewrites the whole
    manifest (atomically): O(n) per A-scan, fine for a calibration's few hundred.
    """

    def __init__(self, folder: Path, stamp: dict[str, Any]) -> None:
        self.folder = folder
        self.fingerprint = stamp
        fix = f"delete {folder} (and partial_log.json beside it) to start over"
        self.files = ChecksummedManifest.new(
            folder, FORMAT, stamp, "ascans", label="cannot resume: ", fix=fix
        )
        self.saved: list[tuple[np.ndarray, AScan]] = []

    @classmethod
    def open(cls, folder: Path, stamp: dict[str, Any], *, overwrite: bool) -> AScanJournal:
        """The journal in ``folder`` for the run whose :func:`fingerprint` is ``stamp``:
        the saved A-scans read back and checked when the folder was made by the same run;
        with another fingerprint a :class:`~echocal.errors.DataFileError` naming what
        differs, unless ``overwrite`` (then it is discarded and the run starts from the
        beginning)."""
        journal = cls(folder, stamp)
        found = ChecksummedManifest.read(
            folder, "ascans", label=journal.files.label, fix=journal.files.fix
        )
        if found is None:
            return journal
        differ = found.differing(stamp)
        if differ and overwrite:
            journal.discard()
            return journal
        if differ:
            raise DataFileError(
                f"cannot resume: {folder} holds the measurements of a calibration with "
                f"another {', '.join(differ)} (recorded {found.recorded(differ)}); run it with "
                "those settings to resume it, pass --overwrite to discard it, or choose another "
                "--out"
            )
        journal.files = found
        journal.saved = [journal._load(i, entry) for i, entry in enumerate(found.entries)]
        return journal

    @property
    def n_saved(self) -> int:
        """Measurements saved so far."""
        return len(self.files.data["ascans"])

    def _load(self, index: int, entry: dict[str, Any]) -> tuple[np.ndarray, AScan]:
        """Measurement ``index``, checked against its SHA-256."""
        path = self.files.verify(entry)
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise self.files.unreadable(path, exc.strerror or exc) from None
        with np.load(io.BytesIO(data), allow_pickle=False) as npz:
            reached = np.asarray(npz["reached"], dtype=np.float64)
            scan = AScan(
                samples=npz["samples"],
                fs=float(npz["fs"]),
                start_time=float(npz["start_time"]),
                pose=Pose.from_array(reached) if np.all(np.isfinite(reached)) else None,
                metadata={**json.loads(str(npz["metadata"])), "from_partial_log": index},
            )
            return np.asarray(npz["requested"], dtype=np.float64), scan

    def keep(self, index: int, requested: Pose, scan: AScan) -> None:
        """Save measurement ``index`` (``scan``, measured for ``requested``) unless it is
        saved already (a resumed run's first ones); a signal waits until it is written."""
        if index < self.n_saved:
            return
        reached = np.full(5, np.nan) if scan.pose is None else scan.pose.as_array()
        buffer = io.BytesIO()
        np.savez(
            buffer,
            samples=scan.samples,
            fs=np.float64(scan.fs),
            start_time=np.float64(scan.start_time),
            requested=requested.as_array(),
            reached=reached,
            metadata=np.array(json.dumps(json_ready(dict(scan.metadata)), default=repr)),
        )
        data = buffer.getvalue()
        with saving():
            self.files.add(f"{index:06d}.npz", lambda tmp: tmp.write_bytes(data))

    def discard(self) -> None:
        """Remove the folder (the run finished, or --overwrite started it again)."""
        with saving():
            shutil.rmtree(self.folder, ignore_errors=True)


class ResumedRig(BaseSource):
    """A rig that first hands back ``saved`` A-scans (from an :class:`AScanJournal`), in
    order, each for the pose it was measured for, then measures on ``rig``.

    A requested pose farther than :data:`POSE_TOLERANCE` from the saved one raises
    :class:`ResumeMismatch` (the run diverged from the interrupted one)."""

    def __init__(self, rig: Any, saved: list[tuple[np.ndarray, AScan]], where: Path) -> None:
        self.rig = rig
        self.limits = rig.limits
        self.description = rig.description
        self.saved = saved
        self.where = where
        self.n_measurements = 0
        """Measurements handed out so far (from the journal, then from the rig)."""

    @property
    def n_replayed(self) -> int:
        """Measurements handed back from the journal so far."""
        return min(self.n_measurements, len(self.saved))

    def measure(self, pose: Pose) -> AScan:
        """The saved A-scan of the next measurement, while there is one; else the rig's."""
        index = self.n_measurements
        if index >= len(self.saved):
            scan = self.rig.measure(pose)
            self.n_measurements += 1
            return scan
        requested, scan = self.saved[index]
        asked = pose.as_array()
        if not np.allclose(asked, requested, rtol=0.0, atol=POSE_TOLERANCE):
            raise ResumeMismatch(
                f"cannot resume: measurement {index + 1} asks for pose {_pose(asked)}, the "
                f"saved one in {self.where} was measured at {_pose(requested)} (the run "
                "diverged from the interrupted one: another echocal version?); pass "
                "--overwrite to discard the saved measurements, or choose another --out"
            )
        self.n_measurements += 1
        return scan


def _pose(values: np.ndarray) -> str:
    x, y, z, azimuth, coelevation = (float(v) for v in values)
    return (
        f"(x={x * 1e3:.4f} mm, y={y * 1e3:.4f} mm, z={z * 1e3:.4f} mm, "
        f"azimuth={azimuth:.6f} deg, co-elevation={coelevation:.6f} deg)"
    )


class Tally(BaseSource):
    """A rig whose every A-scan is saved to ``journal`` as it arrives, and kept with its
    pose and arrival time until the objective logs it: an objective logs a batch of poses
    only once all of it is measured, so the A-scans of a batch cut short by a fault would
    be lost.  A signal waits for the measurement in progress and its saving."""

    def __init__(self, rig: Any, journal: AScanJournal) -> None:
        self.rig = rig
        self.journal = journal
        self.limits = rig.limits
        self.description = rig.description
        self.logged: Callable[[], int] = lambda: 0  # measurements the objective has logged
        self.n_measurements = 0
        """A-scans delivered so far."""
        self._unlogged: list[tuple[float, Any, Any]] = []  # (time [s], pose, A-scan)

    def measure(self, pose: Pose) -> AScan:
        """Measure ``pose`` on the rig; save the A-scan; keep it until the objective logs it."""
        with measuring():
            scan = self.rig.measure(pose)
            self.journal.keep(self.n_measurements, pose, scan)
            self.n_measurements += 1
            keep = self.n_measurements - 1 - self.logged()  # earlier A-scans still unlogged
            self._unlogged = self._unlogged[len(self._unlogged) - keep :] if keep > 0 else []
            self._unlogged.append((time.time(), pose, scan))
        return scan

    def unlogged(self, n_logged: int) -> list[tuple[float, Any, Any]]:
        """The A-scans delivered after the first ``n_logged`` ones, in order."""
        n = self.n_measurements - n_logged
        return self._unlogged[len(self._unlogged) - n :] if n > 0 else []
