"""Record a replay file from any measurement source, resumably.

:func:`record` measures every pose of a :class:`RecordingGrid` ``repeats``
times and writes the replay file read by
:class:`~echocal.measurement.replay.ReplaySource`.

Interruption-safe: measurements go first to a sidecar directory
``<path>.partial/`` — chunk files ``chunk-<start>.npy`` of shape
``(count, n_samples)`` plus ``manifest.json`` listing the finished chunks, each
written atomically.  On an interruption (Ctrl-C, a source error) the
measurements already taken are flushed there before the exception propagates.
Running the same :func:`record` call again resumes after the last saved
measurement, never measuring a saved one again; it refuses to resume (clear
:class:`~echocal.errors.DataFileError`) if the partial recording was made with
another grid, repeat count or source description.  Only when everything is
measured is the final file written — atomically, so it is never half-written —
and the sidecar removed.

Measurement order: positions, then azimuths, then co-elevations, then repeats
(C order of ``(position, azimuth, coelevation, repeat)``).
"""

from __future__ import annotations

import json
import os
import shutil
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._signals import measuring, saving
from echocal._validate import finite_array, positive_int
from echocal.errors import DataFileError, EchocalError, EchocalValueError, LimitError
from echocal.geometry import Pose
from echocal.io import json_ready
from echocal.locking import output_lock
from echocal.measurement._partial_recording import PARTIAL_FORMAT, _Partial
from echocal.measurement.base import MeasurementSource
from echocal.measurement.replay import DIMS, FORMAT, VARIABLES
from echocal.provenance import stamped

__all__ = [
    "MAX_RECORDING_ASCANS",
    "MAX_RECORDING_BYTES",
    "MIN_POSITION_DISTANCE",
    "PARTIAL_FORMAT",
    "RecordingGrid",
    "check_recording_size",
    "discard_partial",
    "partial_matches",
    "partial_path",
    "record",
    "recording_dataset",
    "save_recording",
    "saved_count",
    "simulation_errors",
]


MAX_RECORDING_ASCANS = 1_000_000
"""The most A-scans one recording may hold (poses × repeats): a million A-scans are days
on an instrument, and a larger count is almost always a mistyped COUNT."""

MAX_RECORDING_BYTES = 8 * 2**30
"""[bytes] the largest recording (A-scans × samples × 8 bytes): the final file is
assembled in memory before it is written, so it must fit in RAM."""

MIN_POSITION_DISTANCE = 1e-6
"""[m] recording positions closer than this are the same position (a replay could not
tell them apart; 1 µm is also a replay's position tolerance with one position)."""


def _axis(name: str, values: ArrayLike) -> tuple[float, ...]:
    arr = finite_array(name, np.atleast_1d(values))
    if arr.ndim != 1 or arr.size == 0:
        raise EchocalValueError(f"{name} must be a non-empty 1-D list of values; got {arr.shape}")
    if np.any(np.diff(arr) <= 0):
        raise EchocalValueError(f"{name} must be strictly increasing; got {arr.tolist()}")
    return tuple(float(v) for v in arr)


@dataclass(frozen=True, slots=True)
class RecordingGrid:
    """The poses of a recording: every (azimuth, co-elevation) pair at every position.

    Attributes
    ----------
    azimuth : [deg], strictly increasing, shape ``(n_azimuth,)``.
    coelevation : [deg], strictly increasing, shape ``(n_coelevation,)``.
    positions : [m], shape ``(n_positions, 3)``.
    """

    azimuth: tuple[float, ...]
    coelevation: tuple[float, ...]
    positions: tuple[tuple[float, float, float], ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "azimuth", _axis("grid.azimuth", self.azimuth))
        object.__setattr__(self, "coelevation", _axis("grid.coelevation", self.coelevation))
        if len(self.positions) == 0:
            raise EchocalValueError("grid.positions must hold at least one (x, y, z) [m]")
        pos = finite_array("grid.positions", self.positions, shape_tail=(3,)).reshape(-1, 3)
        if len(pos) > 1:
            from scipy.spatial import cKDTree

            # pairs within the distance, O(P log P) memory-light (a P x P array would not fit)
            pairs = cKDTree(pos).query_pairs(MIN_POSITION_DISTANCE, output_type="ndarray")
            if len(pairs):
                pairs = np.sort(pairs, axis=1)
                gap = np.linalg.norm(pos[pairs[:, 0]] - pos[pairs[:, 1]], axis=-1)
                pairs = pairs[gap < MIN_POSITION_DISTANCE]  # query_pairs includes the bound
            if len(pairs):
                a, b = (int(v) for v in pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))[0]])
                where = ", ".join(f"{1e3 * c:g}" for c in pos[a])
                raise EchocalValueError(
                    f"grid.positions #{a} and #{b} are the same position ({where}) mm "
                    f"(closer than {MIN_POSITION_DISTANCE * 1e3:g} mm); give each recording "
                    "position once (--position)"
                )
        object.__setattr__(self, "positions", tuple(tuple(float(c) for c in p) for p in pos))

    @property
    def size(self) -> int:
        """Number of poses (positions × azimuths × co-elevations)."""
        n_p, n_a, n_c = self.shape
        return n_p * n_a * n_c

    @classmethod
    def regular(
        cls,
        *,
        azimuth: tuple[float, float, int],
        coelevation: tuple[float, float, int],
        positions: Sequence[Sequence[float]],
    ) -> RecordingGrid:
        """Evenly spaced angles: ``azimuth=(first, last, count)`` [deg], likewise co-elevation."""
        axes = []
        for name, (first, last, count) in (("azimuth", azimuth), ("coelevation", coelevation)):
            n = positive_int(f"grid.{name} count", count)
            axes.append(np.linspace(float(first), float(last), n))
        return cls(azimuth=axes[0], coelevation=axes[1], positions=positions)  # type: ignore[arg-type]

    @property
    def shape(self) -> tuple[int, int, int]:
        """(n_positions, n_azimuth, n_coelevation)."""
        return len(self.positions), len(self.azimuth), len(self.coelevation)

    def pose(self, p: int, a: int, c: int) -> Pose:
        """The pose at position index ``p``, azimuth index ``a``, co-elevation index ``c``."""
        return Pose(*self.positions[p], self.azimuth[a], self.coelevation[c])

    def poses(self) -> list[Pose]:
        """All poses in recording order (position, azimuth, co-elevation)."""
        n_p, n_a, n_c = self.shape
        return [self.pose(p, a, c) for p in range(n_p) for a in range(n_a) for c in range(n_c)]

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready)."""
        return {
            "azimuth": list(self.azimuth),
            "coelevation": list(self.coelevation),
            "positions": [list(p) for p in self.positions],
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RecordingGrid:
        """Inverse of :meth:`to_dict`."""
        return cls(
            azimuth=data["azimuth"], coelevation=data["coelevation"], positions=data["positions"]
        )


def check_recording_size(grid: RecordingGrid, repeats: int, n_samples: int | None) -> int:
    """Refuse a recording too large to make; return its number of A-scans.

    ``n_samples`` : samples per A-scan (None if the source does not say: then only the
    count is checked).  Raises :class:`~echocal.errors.EchocalValueError` stating the
    computed count or size and the cap (:data:`MAX_RECORDING_ASCANS`,
    :data:`MAX_RECORDING_BYTES`) before anything is measured or written.
    """
    repeats = positive_int("repeats", repeats)
    n_p, n_a, n_c = grid.shape
    count = grid.size * repeats
    shape = f"{n_p} position(s) x {n_a} azimuths x {n_c} co-elevations x {repeats} repeat(s)"
    if count > MAX_RECORDING_ASCANS:
        raise EchocalValueError(
            f"the recording would hold {count:,} A-scans ({shape}); the cap is "
            f"{MAX_RECORDING_ASCANS:,}: use fewer grid points (COUNT) or repeats"
        )
    if n_samples is not None:
        size = count * int(n_samples) * 8
        if size > MAX_RECORDING_BYTES:
            raise EchocalValueError(
                f"the recording would be {size / 2**30:.1f} GiB ({count:,} A-scans of "
                f"{int(n_samples)} samples, {shape}); the cap is "
                f"{MAX_RECORDING_BYTES / 2**30:g} GiB (the file is assembled in memory): use "
                "fewer grid points (COUNT), repeats or samples"
            )
    return count


def simulation_errors(source: MeasurementSource, poses: Sequence[Pose]) -> list[str | None]:
    """What a noiseless simulation of each pose alone would refuse, before anything is measured.

    For a simulator (a source with ``ideal_samples``, e.g.
    :class:`~echocal.measurement.VirtualSetup`): the message of the echocal error that
    simulating the pose alone raises — the probe inside the specimen, a recording window
    that cannot contain the echo — or None where the pose simulates.  All None for any
    other source (a replay, a rig), which cannot be asked without measuring.
    """
    return [None if e is None else str(e) for e in _simulation_exceptions(source, poses)]


def _simulation_exceptions(
    source: MeasurementSource, poses: Sequence[Pose]
) -> list[EchocalError | None]:
    """:func:`simulation_errors` as the raised exceptions (None where the pose simulates)."""
    from echocal.geometry import poses_to_arrays

    ideal = getattr(source, "ideal_samples", None)
    if ideal is None or not poses:
        return [None] * len(poses)
    positions, frames = poses_to_arrays(list(poses))
    out: list[EchocalError | None] = []
    for k in range(len(poses)):
        try:
            ideal(positions[k : k + 1], frames[k : k + 1])
        except EchocalError as exc:
            out.append(exc)
        else:
            out.append(None)
    return out


# the simulator's window error (echocal.signal.window.check_echoes): raised only when NO pose
# of a simulated batch has an echo in the window, so one silent pose among others is not fatal
_WINDOW_ERROR = "cannot contain any echo"


def _check_measurable(source: MeasurementSource, grid: RecordingGrid) -> None:
    """Refuse a grid whose recording must fail (see :func:`simulation_errors`).

    Checked per position at the grid's centre and corner orientations (the extremes of the
    beam's tilt), before the partial recording is created.  An error that fails every
    orientation of a position (the probe inside the specimen) is refused at the first
    pose that raises it.  The window error is raised by the simulator only when no pose of
    a simulated batch has an echo in the window; a steep pose measured together with
    others is just a noise A-scan.  So a position is refused for it only when every
    checked orientation of that position raises it: the recording would then fail.
    """
    n_p, n_a, n_c = grid.shape
    corners = {(0, 0), (0, n_c - 1), (n_a - 1, 0), (n_a - 1, n_c - 1)}
    orientations = sorted({(n_a // 2, n_c // 2)} | corners)
    for p in range(n_p):
        poses = [grid.pose(p, a, c) for a, c in orientations]
        errors = _simulation_exceptions(source, poses)
        failing = [
            (pose, error)
            for pose, error in zip(poses, errors, strict=True)
            if error is not None
            and (_WINDOW_ERROR not in str(error) or all(e is not None for e in errors))
        ]
        if failing:
            pose, error = failing[0]
            x, y, z = (1e3 * v for v in pose.position)
            raise EchocalValueError(
                f"the recording would fail at position ({x:g}, {y:g}, {z:g}) mm, azimuth "
                f"{pose.azimuth:g} deg, co-elevation {pose.coelevation:g} deg: {error}"
                " (--position, or the setup)"
            )


def _fingerprint(source: MeasurementSource, grid: RecordingGrid, repeats: int) -> dict[str, Any]:
    return {
        "grid": grid.to_dict(),
        "repeats": repeats,
        "source": source.description,
        "format": FORMAT,
    }


def partial_matches(
    path: str | os.PathLike[str], source: MeasurementSource, grid: RecordingGrid, repeats: int
) -> bool | None:
    """Whether the partial recording of ``path`` was made with this grid, repeats and source.

    None when there is no partial recording; False also when it is unreadable.
    """
    manifest = partial_path(path) / "manifest.json"
    if not partial_path(path).exists():
        return None
    try:
        old = json.loads(manifest.read_text(encoding="utf-8"))["fingerprint"]
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return bool(old == json.loads(json.dumps(_fingerprint(source, grid, repeats))))


def discard_partial(path: str | os.PathLike[str]) -> None:
    """Delete the partial recording of ``path`` (if any)."""
    shutil.rmtree(partial_path(path), ignore_errors=True)


def partial_path(path: str | os.PathLike[str]) -> Path:
    """The sidecar directory of an unfinished recording of ``path``."""
    target = Path(path)
    return target.with_name(target.name + ".partial")


def saved_count(path: str | os.PathLike[str]) -> int:
    """Measurements already saved in the unfinished recording of ``path`` (0 if none).

    What a resumed :func:`record` call will skip.  An unreadable partial recording
    counts as 0 here; :func:`record` itself reports it.
    """
    manifest = partial_path(path) / "manifest.json"
    try:
        chunks = json.loads(manifest.read_text(encoding="utf-8"))["chunks"]
        return sum(int(c["count"]) for c in chunks)
    except (OSError, ValueError, KeyError, TypeError):
        return 0


def recording_dataset(
    samples: NDArray[np.float64],
    grid: RecordingGrid,
    *,
    fs: float,
    start_time: float,
    source_info: Mapping[str, Any],
) -> Any:
    """Build the replay ``xarray.Dataset`` (schema ``replay/2``, see docs/netcdf-schema.md);
    write it with :func:`save_recording`.

    Parameters
    ----------
    samples : numpy.ndarray
        Shape ``(n_positions, n_azimuth, n_coelevation, n_repeats, n_samples)``.
    grid : RecordingGrid
        The poses recorded.
    fs : float
        [Hz] sampling rate.
    start_time : float
        [s] time of the first sample.
    source_info : Mapping
        JSON-ready description of the source (attribute ``source_info``).
    """
    import xarray as xr

    positions = np.asarray(grid.positions)
    n_samples = samples.shape[-1]
    values = {
        "azimuth": ("azimuth", np.asarray(grid.azimuth)),
        "coelevation": ("coelevation", np.asarray(grid.coelevation)),
        "repeat": ("repeat", np.arange(samples.shape[3])),
        "time": ("time", start_time + np.arange(n_samples) / fs),
        **{f"position_{c}": ("position", positions[:, i]) for i, c in enumerate("xyz")},
    }
    coords = {name: (*pair, _attrs(name)) for name, pair in values.items()}
    description = str(source_info.get("description", "unknown source"))
    return xr.Dataset(
        {"samples": (DIMS, samples, _attrs("samples"))},
        coords=coords,
        attrs={
            "echocal_format": FORMAT,
            "source": description,
            "sampling_rate_hz": float(fs),
            "start_time_s": float(start_time),
            "source_info": json.dumps(json_ready(dict(source_info))),
            "grid": json.dumps(grid.to_dict()),
            "comment": "samples dims (position, azimuth, coelevation, repeat, time)",
        },
    )


def _attrs(name: str) -> dict[str, str]:
    units, long_name = VARIABLES[name]
    return {"units": units, "long_name": long_name}


def save_recording(dataset: Any, path: str | os.PathLike[str]) -> Path:
    """Write a replay Dataset (from :func:`recording_dataset`) atomically, compressed and
    checksummed (:func:`echocal.netcdf.write_netcdf`)."""
    from echocal.netcdf import write_netcdf

    return write_netcdf(
        dataset,
        path,
        fmt=FORMAT,
        title="echocal replay recording: A-scans on a grid of probe orientations",
        source=dataset.attrs.get("source", "unknown source"),
    )


def record(
    source: MeasurementSource,
    grid: RecordingGrid,
    path: str | os.PathLike[str],
    *,
    repeats: int = 1,
    progress: bool = True,
    batch_size: int = 1,
    chunk_size: int = 256,
    setup: Mapping[str, Any] | None = None,
    overwrite: bool = False,
    provenance: Mapping[str, Any] | None = None,
) -> Path:
    """Measure ``grid`` with ``source`` and write a replay file to ``path``; resumable.

    Parameters
    ----------
    source : any measurement source (simulator, rig, even another replay).
    grid : the poses to record; all must lie within ``source.limits``.
    path : the final NetCDF file (``.nc``).
    repeats : A-scans per grid pose (>= 1), taken one after the other.
    progress : show a rich progress bar on stderr.
    batch_size : poses handed to ``source.measure_many`` at once (>= 1).  With 1 every
        finished measurement survives an interruption; with more, an interruption inside
        a batch loses (and later re-measures) that batch.  Only a simulator (a source
        with ``ideal_samples``) is batched: any other source (a rig measures one pose
        after another) is measured one pose at a time, so every A-scan it delivered
        survives an interruption.
    chunk_size : measurements per chunk file in the sidecar directory.
    setup : JSON-ready description of the setup, stored with the source description.
    provenance : a provenance record (:mod:`echocal.provenance`), stored as the file's
        ``provenance`` attribute (JSON), its end time set when the file is written.
    overwrite : replace an existing final file (otherwise that is an error) and discard a
        partial recording made with another grid/repeats/source.  A compatible partial
        recording is resumed.

    Notes
    -----
    A simulator's grid is checked first (:func:`simulation_errors` at the centre and
    corner orientations of every position): a probe inside the specimen, or a window
    that cannot contain the echo at any checked orientation of a position, is refused
    before the partial recording is created.
    A run that fails (an error, not an interruption) before saving anything leaves no
    partial recording behind.

    Returns
    -------
    The path of the final file.

    Raises
    ------
    DataFileError : the final file exists (without ``overwrite``) or a partial recording
        there was made with a different grid/repeats/source (with ``overwrite`` such a
        partial recording is discarded and the recording starts over).
    OutputLockedError : another process is recording to ``path`` (see
        :func:`~echocal.locking.output_lock`).
    LimitError : a grid pose lies outside ``source.limits`` (nothing is measured).
    EchocalValueError : the recording is too large (:func:`check_recording_size`).
    """
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    target = Path(path)
    repeats = positive_int("repeats", repeats)
    batch_size = positive_int("batch_size", batch_size)
    if not hasattr(source, "ideal_samples"):  # no vectorized batch to gain: keep each A-scan
        batch_size = 1
    chunk_size = positive_int("chunk_size", chunk_size)
    sidecar = partial_path(target)
    if target.is_dir():
        raise DataFileError(f"{target} is a directory; give the replay file's path (.nc)")
    if target.exists() and not sidecar.exists() and not overwrite:
        raise DataFileError(f"{target} already exists; pass overwrite=True to record it again")
    window = getattr(source, "window", None)
    check_recording_size(grid, repeats, getattr(window, "n_samples", None))
    poses = grid.poses()
    bad = [(i, v) for i, p in enumerate(poses) if (v := source.limits.violations(p))]
    if bad:
        i, v = bad[0]
        raise LimitError(
            f"{len(bad)} grid pose(s) lie outside the source's limits, e.g. #{i}: {'; '.join(v)}"
        )
    with output_lock(target, folder=False):  # one writer per file
        fingerprint = _fingerprint(source, grid, repeats)
        if overwrite and partial_matches(target, source, grid, repeats) is False:
            discard_partial(target)  # --overwrite: start over instead of refusing to resume
        if not sidecar.exists():
            _check_measurable(source, grid)
        partial = _Partial(sidecar, fingerprint)
        total = len(poses) * repeats
        done = partial.n_done
        if done and hasattr(source, "skip_noise"):  # a simulator: continue its noise stream,
            source.skip_noise(done)  # so a resumed recording equals an uninterrupted one

        rows: list[NDArray[np.float64]] = []
        row_start = done
        columns = (
            TextColumn(f"recording {target.name}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeRemainingColumn(),
        )
        with Progress(*columns, console=Console(stderr=True), disable=not progress) as bar:
            task = bar.add_task("record", total=total, completed=done)
            try:
                index = done
                while index < total:
                    batch = list(range(index, min(index + batch_size, total)))
                    batch_poses = [poses[i // repeats] for i in batch]
                    if len(batch) == 1:  # one A-scan (a rig): a signal waits for it
                        with measuring():
                            ascans = [source.measure(batch_poses[0])]
                            partial.check_format(ascans[0], batch[0])
                            rows.append(ascans[0].samples)
                    else:
                        ascans = list(source.measure_many(batch_poses))
                        for i, ascan in zip(batch, ascans, strict=True):
                            partial.check_format(ascan, i)
                            rows.append(ascan.samples)
                    index = batch[-1] + 1
                    bar.update(task, completed=index)
                    if len(rows) >= chunk_size:
                        with saving():  # a signal waits until the chunk is whole
                            partial.write_chunk(row_start, rows)
                        row_start, rows = index, []
            finally:
                if rows:  # keep what was measured, also on KeyboardInterrupt or a source error
                    with saving():
                        partial.write_chunk(row_start, rows)
                elif partial.n_done == 0 and isinstance(sys.exc_info()[1], Exception):
                    # failed (not interrupted) before saving anything: nothing to resume
                    shutil.rmtree(sidecar, ignore_errors=True)

        data = partial.load(total)
        n_p, n_a, n_c = grid.shape
        fmt = partial.manifest["ascan"]
        dataset = recording_dataset(
            data.reshape(n_p, n_a, n_c, repeats, -1),
            grid,
            fs=fmt["fs"],
            start_time=fmt["start_time"],
            source_info={
                "description": source.description,
                "limits": source.limits.as_dict(),
                "setup": dict(setup) if setup is not None else None,
                "repeats": repeats,
            },
        )
        if provenance is not None:
            dataset.attrs["provenance"] = stamped({"provenance": dict(provenance)})["provenance"]
        save_recording(dataset, target)
        shutil.rmtree(sidecar)
        return target
