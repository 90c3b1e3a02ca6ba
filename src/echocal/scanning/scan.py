"""``scan_surface``: map a specimen's surface — normal and distance at every raster point.

At each probe position of a :class:`~echocal.scanning.ScanGrid`, in serpentine order
from the centre out (:meth:`~echocal.scanning.ScanGrid.order`):

1. **Orientation.**  Calibrate the orientation of maximum echo (the surface normal)
   with :func:`echocal.calibrate.calibrate`, warm-started from the finished
   neighbours: a least-squares plane through the estimates of the found points
   within 1.5 raster steps, evaluated at this position (the previous point alone
   at the start of a scan, nothing — a cold start at ``x0`` — when no neighbour was
   found).  A run stops when its recommendation has stayed within ``tol`` [deg] for
   ``patience`` iterations, or at ``budget_per_point``.
2. **Distance.**  Measure ``tof_repeats`` A-scans at the estimate (counted) and take
   the matched-filter peak (:func:`echocal.signal.time_of_flight`) of each; their mean
   τ gives the distance along the beam d = c₀τ/2 and the surface point
   p + d · (−n).
3. **Missing, not guessed.**  A point is *missing* (NaN, and never a warm start for
   its neighbours) when the calibration found no echo (acquisition failed, every
   value NaN), when it stopped on the budget or the iteration limit before the
   method's own convergence (``unconverged``: see :data:`CONVERGED_STATUSES`; no
   time of flight is measured then), when the estimate sits on the positioner's
   angle limits (the true optimum is out of reach), when the echo at the estimate
   is not clearly above
   noise (matched-envelope peak < ``min_snr`` × its median over the window, a
   robust noise level every source provides), when the time of flight is NaN, or
   when the source raised an echocal error at that point.
4. **Second look.**  After the pass, suspicious points — missing after a cold start,
   an echo below ``relative_snr`` × the scan's 90th-percentile echo (a side lobe), or more
   than ``outlier`` degrees off the plane through their neighbours — are measured
   once more, warm from their trusted neighbours; the attempt with the stronger echo
   is kept, the measurements of both are counted, and a point still far weaker than
   the strong echoes is missing.

The result (:class:`SurfaceScan`) is an xarray Dataset on dims (y, x); see
:func:`surface_dataset` for its variables.  With ``out`` the scan is resumable (see
:mod:`echocal.scanning.store`) and the NetCDF file is written atomically at the end.
"""

from __future__ import annotations

import json
import os
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._progress import ProgressBar
from echocal._rng import RngLike, as_generator
from echocal._validate import (
    finite_array,
    nonnegative_float,
    positive_float,
    positive_int,
)
from echocal.angle_columns import angle_columns, record_angles
from echocal.calibrate import calibrate
from echocal.calibrate.result import NO_ECHO_STATUSES, SUCCESS_STATUSES
from echocal.constants import SOUND_SPEED_WATER
from echocal.errors import DataFileError, EchocalError
from echocal.measurement.base import MeasurementSource
from echocal.measurement.objective import SourceObjective
from echocal.provenance import stamped
from echocal.scanning.checks import check_scan
from echocal.scanning.dataset import STATUS, SurfaceScan, surface_dataset
from echocal.scanning.defaults import point_options
from echocal.scanning.grid import ScanGrid
from echocal.scanning.neighbours import attempt_score, demote_weak, predict, suspicious_points
from echocal.scanning.store import (
    PointStore,
    partial_path,
    setting_differences,
    settings_digest,
)
from echocal.signal import Pulse, RecordingWindow, matched_envelope, time_of_flight
from echocal.signal.gates import TimeGate
from echocal.signal.thickness import wall_thickness
from echocal.specimen import Specimen

__all__ = ["CONVERGED_STATUSES", "echo_snr", "scan_surface"]

_NOISE_STREAM = 7
"""Entropy word that separates a point's noise stream from its calibration's."""

CONVERGED_STATUSES = SUCCESS_STATUSES
"""Calibration statuses (:data:`echocal.calibrate.STATUS_MESSAGES`) after which a point's
orientation is trusted: a calibration's ``success`` — the method's own convergence (a
short step, a complete search, a settled recommendation) with its evidence.  A run
stopped by the budget or the iteration limit is ``unconverged``: its estimate is
wherever the method happened to be."""

FloatArray = NDArray[np.float64]


def echo_snr(samples: ArrayLike, window: RecordingWindow, pulse: Pulse) -> FloatArray:
    """Peak of the matched-filter envelope over its median across the window, shape (...,).

    The median envelope is a robust noise level (an echo occupies a few percent of the
    window); pure noise gives ≈ 3–4 (a Rayleigh maximum over ~10³ samples), a clear
    echo tens to thousands; a noiseless echo +inf; an all-zero A-scan NaN.
    """
    env = matched_envelope(np.asarray(samples, dtype=np.float64), pulse, window.fs)
    peak = env.max(axis=-1)
    median = np.median(env, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(peak > 0, peak / median, np.nan)
    return ratio


def _settings(source: MeasurementSource, grid: ScanGrid, options: dict[str, Any]) -> dict[str, Any]:
    return {"grid": grid.to_dict(), "source": source.description, **options}


def _stored_settings(path: Path) -> dict[str, Any] | None:
    """The settings of the finished scan in ``path`` (None if it does not record them)."""
    attrs = SurfaceScan.load(path).dataset.attrs
    try:
        return json.loads(attrs["settings"])
    except (KeyError, TypeError, ValueError):
        return None


@dataclass
class _Context:
    """Everything one point's measurement needs (private)."""

    source: MeasurementSource
    method: str
    parameterization: str
    budget: int
    tof_repeats: int
    tol: float
    patience: int
    min_snr: float
    relative_snr: float
    outlier: float
    x0: FloatArray
    pulse: Pulse | None
    sound_speed: float
    options: dict[str, Any] = field(default_factory=dict)
    min_attempt: int = 1
    gate: TimeGate | None = None
    """The fewest measurements an attempt at a point needs (one iteration + time of flight)."""
    longitudinal_speed: float | None = None
    """[m/s] the part's c_L: each found point also gets its wall thickness."""


def _measure_point(
    ctx: _Context,
    position: FloatArray,
    start: FloatArray,
    seed: list[int],
    budget: int | None = None,
) -> dict[str, Any]:
    """Calibrate, then time of flight, at one probe position; a JSON-ready record.

    seed : the attempt's own entropy: the calibration's generator and, when the source
        can (:meth:`~echocal.measurement.BaseSource.reseed`), its noise start from it, so
        the point's numbers do not depend on what was measured before it (a resumed scan
        equals an uninterrupted one).
    budget : measurements this attempt may use, time of flight included (default
        ``ctx.budget``).
    """
    budget = ctx.budget if budget is None else budget
    rng = np.random.default_rng(seed)
    reseed = getattr(ctx.source, "reseed", None)
    if callable(reseed):
        reseed(np.random.default_rng([*seed, _NOISE_STREAM]))
    angles = angle_columns(ctx.parameterization)
    record: dict[str, Any] = {
        "status": STATUS["found"],
        angles[0]: np.nan,
        angles[1]: np.nan,
        "tof": np.nan,
        "snr": np.nan,
        "n_measurements": 0,
        "n_calibration": 0,
        "start": [float(v) for v in start],
        "message": "",
    }
    t0 = time.perf_counter()
    objective = SourceObjective(
        ctx.source, position, parameterization=ctx.parameterization, pulse=ctx.pulse, gate=ctx.gate
    )
    try:
        x0 = np.clip(start, objective.bounds[:, 0], objective.bounds[:, 1])
        with warnings.catch_warnings():  # the point's status says so ("at-limit")
            warnings.filterwarnings("ignore", "the estimate .* angle limits", UserWarning)
            result = calibrate(
                objective,
                ctx.method,
                x0=x0,
                budget=budget - ctx.tof_repeats,
                rng=rng,
                settle=(ctx.tol, ctx.patience),
                final_check=0,  # the time-of-flight A-scans below measure the estimate
                **point_options(ctx.method, ctx.options),
            )
    except EchocalError as exc:
        record.update(status=STATUS["source-error"], message=str(exc))
        record["n_measurements"] = record["n_calibration"] = objective.n_measurements
        record["wall_time"] = time.perf_counter() - t0
        return record
    record["n_calibration"] = result.n_measurements
    record["n_measurements"] = result.n_measurements
    record[angles[0]], record[angles[1]] = (float(v) for v in result.x)
    if result.status in NO_ECHO_STATUSES:
        record.update(status=STATUS["no-echo"], message=result.message)
    elif result.status == 8:
        record.update(status=STATUS["at-limit"], message="estimate on the angle limits")
    elif result.status not in CONVERGED_STATUSES:
        record.update(
            status=STATUS["unconverged"],
            message=f"{result.message} after {result.n_measurements} measurements, before "
            f"the method converged: no clear echo here, or budget_per_point ({ctx.budget}) "
            "too small",
        )
    else:
        pose = objective.pose(*result.x)
        try:
            scans = ctx.source.measure_many([pose] * ctx.tof_repeats)
        except EchocalError as exc:
            record.update(status=STATUS["source-error"], message=str(exc))
            scans = []
        record["n_measurements"] += len(scans)
        if scans:
            samples = np.stack([s.samples for s in scans])
            window = RecordingWindow(
                fs=scans[0].fs, start=scans[0].start_time, n_samples=scans[0].n_samples
            )
            pulse = objective.pulse
            snr = echo_snr(samples, window, pulse) if np.all(np.isfinite(samples)) else [np.nan]
            tof = (
                time_of_flight(samples, window, pulse) if np.all(np.isfinite(samples)) else [np.nan]
            )
            record["snr"] = float(np.mean(snr))
            record["tof"] = float(np.mean(tof))
            if ctx.longitudinal_speed is not None and np.all(np.isfinite(samples)):
                back = ctx.gate if ctx.gate is not None and ctx.gate.name != "front-wall" else None
                thickness = wall_thickness(samples, window, pulse, ctx.longitudinal_speed, back)
                record["thickness"] = float(np.mean(thickness))
            if not np.isfinite(record["tof"]):
                record.update(status=STATUS["no-tof"], message="time of flight is NaN")
            elif not record["snr"] >= ctx.min_snr:
                record.update(
                    status=STATUS["weak-echo"],
                    message=f"echo {record['snr']:.3g} x the noise median < {ctx.min_snr:g}",
                )
    record["wall_time"] = time.perf_counter() - t0
    return record


def scan_surface(
    source: MeasurementSource,
    grid: ScanGrid,
    *,
    method: str = "auto",
    parameterization: str = "tilt",
    budget_per_point: int = 80,
    warm_start: bool = True,
    rng: RngLike = None,
    progress: bool = True,
    out: str | os.PathLike[str] | None = None,
    truth: Specimen | None = None,
    x0: ArrayLike = (0.0, 0.0),
    tof_repeats: int = 2,
    tol: float = 0.01,
    patience: int = 8,
    min_snr: float = 6.0,
    relative_snr: float = 0.25,
    outlier: float = 0.3,
    pulse: Pulse | None = None,
    sound_speed: float | None = None,
    method_options: Mapping[str, Any] | None = None,
    metadata: Mapping[str, Any] | None = None,
    on_point: Callable[[int, int], None] | None = None,
    start: str = "centre",
    overwrite: bool = False,
    log: Callable[[str], None] | None = None,
    gate: TimeGate | None = None,
    longitudinal_speed: float | None = None,
    prechecked: int | None = None,
    client: Any = None,
) -> SurfaceScan:
    """Scan ``grid`` with ``source``: surface normal and distance at every point.

    Parameters
    ----------
    source : any measurement source (simulator, replay, hardware).
    grid : probe positions [m].
    method : calibration method (:func:`echocal.calibrate.method_names`).
    parameterization : ``"tilt"`` (default: no pole at normal incidence) or
        ``"azimuth-coelevation"``.
    budget_per_point : [measurements] cap per point, time-of-flight repeats and the
        second look included.
    warm_start : start each point from its finished neighbours (else from ``x0``).
    rng : seed or Generator; each point draws its own seed from it in scan order, for its
        calibration and (on a source that can, e.g. the simulator) its noise: a resumed
        scan measures the same numbers as an uninterrupted one.
    progress : show a progress bar with ETA on stderr.
    out : NetCDF file to write (atomically); the scan is then resumable from
        ``<out>.partial/`` and refuses to resume a different scan.
    truth : the specimen to judge against; default ``source.specimen`` if the source has
        one (the simulator).  Adds ``normal_error`` and ``height_error``.
    x0 : [deg] (2,) cold-start orientation.
    tof_repeats : A-scans averaged for the time of flight (counted).
    tol, patience : [deg], [iterations] the per-point stopping rule.
    min_snr : the echo must exceed this many times the median matched envelope.
    relative_snr : ... and this fraction of the 90th-percentile echo of the found points (a
        weaker one is a side lobe or a partial footprint).
    outlier : [deg] a found point this far from the plane through its neighbours'
        estimates is measured again from them; the stronger echo is kept.
    pulse : matched-filter template (default: the source's own).
    sound_speed : [m/s] c₀ (default: the source's, else water).
    method_options : extra options of the calibration method.
    metadata : extra JSON-ready attributes to store (e.g. the setup name and seed); a
        ``provenance`` record (:mod:`echocal.provenance`) is stored as JSON, finished when
        the file is written.
    start : ``"centre"`` (default) or ``"corner"``: where the serpentine order begins
        (:meth:`ScanGrid.order`).
    on_point : called with (points done, total) after each point (e.g. to interrupt
        a scan in tests or drive another progress display).
    overwrite : replace a finished scan in ``out`` made with other settings (without
        it that is refused); a finished scan with the same settings is returned as
        stored (nothing measured) unless ``overwrite``.
    log : called with one line of news (resuming, already finished).
    gate : calibrate each point's orientation on the metric inside this gate
        (:mod:`echocal.signal.gates`, e.g. the back wall); the time of flight, and so the
        height, stays the strongest echo's (the front wall on a plate).
    longitudinal_speed : [m/s] the part's longitudinal speed c_L: each found point also
        gets its wall thickness c_L·(t_back − t_front)/2 from its time-of-flight A-scans
        (:func:`echocal.signal.thickness.wall_thickness`; the back echo inside ``gate``
        when that is not the front-wall gate, else the strongest after the front wall),
        and the scan a ``thickness`` map (with ``thickness_error`` against the source's
        own ``thickness`` when it has one, e.g. a simulated plate).

    prechecked : what :func:`check_scan` returned for this source, grid and these same
        settings, when the caller has already run it (the CLI does, before it creates the
        output folder); None: the check runs here.
    client : a :class:`distributed.Client`: the points are measured on its Dask cluster
        (the source travels to the workers: a simulator or a replay, not a rig).  A point
        starts once every earlier point (in scan order) within the warm-start radius is
        finished, and its warm start is computed from them here, exactly as a local scan
        does; each point's noise and calibration come from its own seed.  So the result
        equals a local scan's bit for bit; a cold scan (``warm_start=False``) runs all
        its points at once, a warm scan's serpentine chain runs mostly one after another.

    Notes
    -----
    Whole-run mistakes (:func:`check_scan`) are refused before anything is written.
    """
    min_attempt = prechecked
    if min_attempt is None:
        min_attempt = check_scan(
            source,
            grid,
            method=method,
            parameterization=parameterization,
            budget_per_point=budget_per_point,
            tof_repeats=tof_repeats,
            x0=x0,
            pulse=pulse,
            method_options=method_options,
        )
    min_attempt = positive_int("prechecked", min_attempt)
    budget = int(budget_per_point)
    tof_repeats = int(tof_repeats)
    x0 = finite_array("x0", x0)
    c0 = sound_speed if sound_speed is not None else getattr(source, "sound_speed", None)
    ctx = _Context(
        source=source,
        method=method,
        parameterization=parameterization,
        budget=budget,
        tof_repeats=tof_repeats,
        tol=nonnegative_float("tol", tol),
        patience=positive_int("patience", patience),
        min_snr=positive_float("min_snr", min_snr),
        relative_snr=nonnegative_float("relative_snr", relative_snr),
        outlier=positive_float("outlier", outlier),
        x0=x0,
        pulse=pulse,
        sound_speed=positive_float("sound_speed", SOUND_SPEED_WATER if c0 is None else c0),
        options=dict(method_options or {}),
        min_attempt=min_attempt,
        gate=gate,
        longitudinal_speed=(
            None
            if longitudinal_speed is None
            else positive_float("longitudinal_speed", longitudinal_speed)
        ),
    )
    gen = as_generator(rng)
    order = grid.order(start)
    seeds = gen.integers(0, 2**63 - 1, size=len(order))
    settings = _settings(
        source,
        grid,
        {
            "method": method,
            "parameterization": parameterization,
            "budget_per_point": budget,
            "start": start,
            "warm_start": bool(warm_start),
            "x0": ctx.x0.tolist(),
            "tof_repeats": tof_repeats,
            "tol": ctx.tol,
            "patience": ctx.patience,
            "min_snr": ctx.min_snr,
            "relative_snr": ctx.relative_snr,
            "outlier": ctx.outlier,
            "sound_speed": ctx.sound_speed,
            "method_options": ctx.options,
            # an integer seed defines the scan: resuming with another one is refused
            "seed": int(rng) if isinstance(rng, int | np.integer) else None,
            **({} if gate is None else {"gate": gate.describe()}),
            **(
                {}
                if ctx.longitudinal_speed is None
                else {"longitudinal_speed": ctx.longitudinal_speed}
            ),
        },
    )
    store = None
    records: dict[tuple[int, int], dict[str, Any]] = {}
    if out is not None:
        out = Path(out)
        if out.is_dir():
            raise DataFileError(f"{out} is a folder; give the scan file's path (.nc)")
        if out.exists() and not partial_path(out).exists() and not overwrite:
            stored = _stored_settings(out)
            differ = setting_differences(stored, settings)
            if not differ:
                if log is not None:
                    log(f"{out} already holds this scan (finished): nothing to measure")
                return SurfaceScan.load(out)
            raise DataFileError(
                f"{out} holds a finished scan with other settings ({', '.join(differ)}); "
                "pass --overwrite (overwrite=True) to replace it, or choose another output"
            )
        store = PointStore(out, settings)
        for rec in store.open():
            records[(int(rec["iy"]), int(rec["ix"]))] = rec
        if records and log is not None:
            log(f"resuming {out}: {len(records)} point(s) already saved in {store.directory}")
    resumed = len(records)

    xy = grid.positions()[..., :2]
    positions = grid.positions()
    found: dict[tuple[int, int], FloatArray] = {
        k: record_angles(r, parameterization) for k, r in records.items() if r["status"] == 0
    }
    radius = 2.5 * grid.spacing
    t_start = time.perf_counter()
    runner = _Runner(ctx, client)
    ahead = _Ahead(runner, order, xy, radius, warm_start, records)
    with ProgressBar("scan", total=len(order), completed=resumed, enabled=progress) as bar:
        for i, key in enumerate(order):
            if key in records:
                continue

            def start_point(j: int) -> tuple[Any, bool]:
                """Start point ``j`` (its earlier neighbours are finished): its task and
                whether it is warm-started."""
                k = order[j]
                guess = None
                if warm_start:
                    guess = predict(found, xy[k], {n: xy[n] for n in found}, radius)
                start = ctx.x0 if guess is None else guess
                return runner.submit(positions[k], start, [int(seeds[j])]), guess is not None

            ahead.start_ready(i, start_point)
            task, warm = ahead.take(i)
            rec = runner.result(task)
            rec.update(iy=key[0], ix=key[1], order=i, warm=bool(warm_start and warm))
            records[key] = rec
            if rec["status"] == 0:
                found[key] = record_angles(rec, ctx.parameterization)
            if store is not None:
                store.append(rec)
            bar.advance()
            if on_point is not None:
                on_point(len(records), len(order))
        # second look at suspicious points, warm from their trusted neighbours
        retry, snr_ref = suspicious_points(
            records, found, xy, radius, relative_snr=ctx.relative_snr, outlier=ctx.outlier
        )
        if not warm_start:  # a cold scan takes no advice from its neighbours
            retry = set()
        # a point already retried (before an interruption) keeps its final record and
        # stays a trusted neighbour
        pending = {k for k in retry if not records[k].get("retried")}
        for key in pending:
            found.pop(key, None)
        index = {key: i for i, key in enumerate(order)}
        while pending:
            # the point with the most trusted neighbours first: the best warm start
            support = {
                k: sum(np.hypot(*(xy[j] - xy[k])) <= radius for j in found if j != k)
                for k in pending
            }
            key = max(sorted(pending), key=lambda k: support[k])
            if support[key] == 0:
                break
            pending.discard(key)
            i, old = index[key], records[key]
            left = ctx.budget - int(old["n_measurements"])  # budget_per_point is a cap
            if left < ctx.min_attempt:
                continue
            others = {k: v for k, v in found.items() if k != key}
            guess = predict(others, xy[key], {k: xy[k] for k in others}, radius)
            new = runner.result(
                runner.submit(
                    positions[key],
                    ctx.x0 if guess is None else guess,  # None only without neighbours
                    [int(seeds[i]), 1],
                    left,
                )
            )
            new["warm"] = True
            best = new if attempt_score(new) >= attempt_score(old) else old
            rec = {**best, "iy": key[0], "ix": key[1], "order": i, "retried": True}
            rec["n_measurements"] = int(old["n_measurements"]) + int(new["n_measurements"])
            rec = demote_weak(rec, ctx.relative_snr, snr_ref)
            records[key] = rec
            if rec["status"] == 0:
                found[key] = record_angles(rec, ctx.parameterization)
            if store is not None:
                store.append(rec)
        for key in records:  # a found echo far below the strong ones is not trusted
            records[key] = demote_weak(records[key], ctx.relative_snr, snr_ref)
    runner.close()
    wall = time.perf_counter() - t_start
    if truth is None:
        truth = getattr(source, "specimen", None)
    attrs = {
        **{k: v for k, v in settings.items() if k not in ("grid",)},
        **stamped(metadata),  # a provenance record gets its end time now
        "resumed_points": resumed,
        "wall_time": wall,
        "settings": json.dumps(settings, sort_keys=True, default=str),
        "settings_digest": settings_digest(settings),
    }
    result = surface_dataset(
        grid,
        records,
        parameterization=parameterization,
        sound_speed=ctx.sound_speed,
        truth=truth,
        attrs=attrs,
        thickness=ctx.longitudinal_speed is not None,
        true_thickness=getattr(source, "thickness", None),
    )
    if out is not None and store is not None:
        result.save(out)
        store.remove()
    return result


class _Runner:
    """Measures points (:func:`_measure_point`) here, or on a Dask cluster (private)."""

    def __init__(self, ctx: _Context, client: Any) -> None:
        self.ctx = ctx
        self.client = client
        self._ctx_future = None
        if client is not None:  # sent to every worker once, not with each point
            self._ctx_future = client.scatter(ctx, broadcast=True, hash=False)

    def submit(self, position: FloatArray, start: FloatArray, seed: list[int], *rest: Any) -> Any:
        """A point's task: its record (here) or a future of it (on the cluster)."""
        if self.client is None:
            return _measure_point(self.ctx, position, start, seed, *rest)
        return self.client.submit(
            _measure_point, self._ctx_future, position, start, seed, *rest, pure=False
        )

    def result(self, task: Any) -> dict[str, Any]:
        """The record of a task :meth:`submit` returned."""
        if self.client is None:
            return task
        record = task.result()
        task.release()
        return record

    def close(self) -> None:
        """Forget the context on the cluster."""
        if self._ctx_future is not None:
            self._ctx_future.release()
            self._ctx_future = None


class _Ahead:
    """Which points of the first pass may start before the one being collected (private).

    Point ``j`` depends on the earlier points (in scan order) within the warm-start
    ``radius`` (none on a cold scan): once all of them are collected, its warm start is
    the one a local scan computes, and it may run.  Locally nothing runs ahead (each
    point is measured when it is collected); on a cluster every ready point is started.
    """

    def __init__(
        self,
        runner: _Runner,
        order: list[tuple[int, int]],
        xy: FloatArray,
        radius: float,
        warm_start: bool,
        records: Mapping[tuple[int, int], Any],
    ) -> None:
        self.runner = runner
        self.order = order
        self.todo = [j for j, key in enumerate(order) if key not in records]
        points = np.array([xy[key] for key in order]).reshape(len(order), 2)
        self.last_dependency = np.full(len(order), -1)
        if warm_start:
            for j in range(len(order)):
                near = np.hypot(*(points[:j] - points[j]).T) <= radius
                earlier = np.flatnonzero(near)
                self.last_dependency[j] = earlier[-1] if earlier.size else -1
        self.started: dict[int, tuple[Any, bool]] = {}
        self._next = 0  # index into todo of the first point not started

    def start_ready(self, i: int, start_point: Callable[[int], tuple[Any, bool]]) -> None:
        """Start point ``i`` and, on a cluster, every later point whose dependencies
        are all before ``i`` (collected)."""
        while self._next < len(self.todo):
            j = self.todo[self._next]
            if j != i and (self.runner.client is None or self.last_dependency[j] >= i):
                break
            if j not in self.started:
                self.started[j] = start_point(j)
            self._next += 1

    def take(self, i: int) -> tuple[Any, bool]:
        """The started task of point ``i``."""
        return self.started.pop(i)
