"""``echocal calibrate`` on a recording (``--replay FILE``) or a rig (``--instrument
HOST:PORT``): the options checked against the source, the pulse found, the recording's
grid turned into bounds and a map, the run saved and printed without a truth.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rich.markup import escape

from echocal.cli._calibrate_common import (
    _check_source_options,
    _parse_position,
    _report,
    _Run,
    calibration_summary,
    prepare_out,
    save_final_ascan,
    save_pngs,
)
from echocal.cli._calibrate_resume import JOURNAL, Tally
from echocal.cli._common import console, output, parse_pair
from echocal.cli._gate_option import gate_for_source
from echocal.cli._measured_pulse import _replay_pulse, _setup_pulse
from echocal.cli._replay_grid import (
    RecordingMap,
    grid_centre,
    replay_position,
    tilt_bounds_in_recording,
)
from echocal.locking import hold_output_lock


def _check_measured_options(
    replay: Path | None,
    instrument: str | None,
    snr: str | None,
    specimen: str | None,
    rig: Path | None = None,
) -> None:
    """Refuse what a recording or a rig cannot honour (before any work)."""
    from echocal.errors import EchocalValueError

    given = [
        name
        for name, v in (("--replay", replay), ("--instrument", instrument), ("--rig", rig))
        if v is not None
    ]
    if len(given) > 1:
        raise EchocalValueError(
            f"{' and '.join(given)} are mutually exclusive: calibrate on one source"
        )
    what = (
        "a recording (--replay)"
        if replay is not None
        else "a rig (--rig)"
        if rig is not None
        else "a rig (--instrument)"
    )
    if snr is not None:
        raise EchocalValueError(
            f"--snr applies to a simulated setup only: {what} has its own noise; drop --snr"
        )
    if specimen is not None:
        raise EchocalValueError(
            f"--specimen applies to a simulated setup only: {what} measures its own "
            "specimen; drop --specimen"
        )


@dataclass(frozen=True)
class _Measured:
    """A run on a recording or a rig, with what its report needs (no truth)."""

    result: Any
    where: Any  # [m] shape (3,)
    pulse: Any
    pulse_from: str  # where the matched filter's pulse came from
    source: dict[str, Any]  # the summary's "source" object
    extra: dict[str, Any]  # further summary fields (a replay's recording_best_deg)
    figures: dict[str, str]


def _calibrate_measured(
    run: _Run,
    *,
    replay: Path | None,
    replay_mode: str | None,
    instrument: str | None,
    timeout: float | None,
    setup: str | None,
    position: str | None,
    parameterization: str | None,
    x0: str | None,
    seed: int | None,
    out: Path,
    plots: bool,
    json_output: bool,
    rig: Path | None = None,
    token: str | None = None,
    provenance: Any = None,
    gate: str | None = None,
    overwrite: bool = False,
) -> None:
    """Calibrate on a recording or a rig: the same objective and call, no truth known
    (on a rig, a run cut short resumes; ``overwrite`` discards one made with other
    settings)."""
    from echocal._validate import one_of
    from echocal.geometry import PARAMETERIZATIONS

    _check_source_options(replay, replay_mode, instrument, timeout)
    default = "azimuth-coelevation" if replay is not None else "tilt"
    parameterization = one_of(
        "--parameterization",
        default if parameterization is None else parameterization,
        PARAMETERIZATIONS,
    )
    start = parse_pair(x0, "--x0") if x0 is not None else None
    seed = 0 if seed is None else seed
    common: dict[str, Any] = {
        "parameterization": parameterization,
        "start": start,
        "seed": seed,
        "gate": gate,
    }
    if instrument is not None or rig is not None:
        done = _on_instrument(
            run,
            instrument,
            timeout,
            setup,
            position,
            rig=rig,
            out=out,
            plots=plots,
            token=token,
            provenance=provenance,
            overwrite=overwrite,
            **common,
        )
    else:
        assert replay is not None
        done = _on_replay(
            run,
            replay,
            replay_mode,
            setup,
            position,
            out=out,
            plots=plots,
            provenance=provenance,
            **common,
        )
    result, pulse = done.result, done.pulse
    summary = calibration_summary(
        result,
        out,
        context={
            "setup": setup,
            "seed": seed,
            "source": done.source,
            "pulse": {
                "name": pulse.name,
                "center_frequency_hz": float(pulse.center_frequency),
                "from": done.pulse_from,
            },
            "position_m": [float(v) for v in done.where],
            **done.extra,
        },
        parameterization=parameterization,
        figures=done.figures,
    )
    _report(summary, result, out, json_output, lambda: _print_measured_estimate(done, out))


def _on_instrument(
    run: _Run,
    instrument: str | None,
    timeout: float | None,
    setup: str | None,
    position: str | None,
    *,
    parameterization: str,
    start: tuple[float, float] | None,
    seed: int,
    out: Path,
    plots: bool,
    rig: Path | None = None,
    token: str | None = None,
    provenance: Any = None,
    gate: str | None = None,
    overwrite: bool = False,
) -> _Measured:
    """Check the rig's options, connect, calibrate, save: ``--instrument HOST:PORT`` or
    ``--rig FILE``.  Every A-scan is saved in ``out/partial_ascans/`` as it arrives; a
    run cut short resumes from there when the same command is run again
    (:mod:`echocal.cli._calibrate_resume`)."""
    from echocal.cli._calibrate_resume import (
        AScanJournal,
        ResumedRig,
        ResumeMismatch,
        fingerprint,
    )
    from echocal.cli._rig_option import open_rig, require_position, rig_setup
    from echocal.errors import EchocalError
    from echocal.measurement.hardware import HardwareSource
    from echocal.measurement.objective import SourceObjective
    from echocal.provenance import file_digest
    from echocal.setups import load_setup

    option = "--rig" if rig is not None else "--instrument"
    host, port = _parse_address(instrument) if instrument is not None else ("", 0)
    where = _parse_position(require_position(position, option))
    setup = rig_setup(setup, rig, option)
    pulse = _setup_pulse(setup)
    chosen = gate_for_source(gate, pulse=pulse, setup=setup)
    wait: dict[str, Any] = {}
    if timeout is not None:
        wait["timeout"] = _check_timeout(timeout)
    x0 = (0.0, 0.0) if start is None else start
    where_from = {"file": str(rig)} if rig is not None else {"address": f"{host}:{port}"}
    which = (
        {"file": str(Path(rig).resolve()), "sha256": file_digest(rig)}
        if rig is not None
        else where_from
    )
    stamp = fingerprint(
        run,
        setup=setup,
        source=which,
        position=where,
        parameterization=parameterization,
        x0=x0,
        seed=seed,
        gate=chosen,
    )
    hold_output_lock(out)  # one writer per --out (made here, the options checked)
    journal = AScanJournal.open(out / JOURNAL, stamp, overwrite=overwrite)
    if journal.saved:
        console.print(
            f"resuming: {journal.n_saved} measurements saved in {escape(str(journal.folder))} "
            "are handed to the calibration again (not measured again)",
            highlight=False,
            soft_wrap=True,
        )
    connect = (
        (lambda: open_rig(rig))
        if rig is not None
        else (lambda: HardwareSource.connect(host, port, token=token, **wait))
    )
    with connect() as hardware:
        _check_reachable(hardware.limits, where)
        resumed = ResumedRig(hardware, journal.saved, journal.folder)
        tally = Tally(resumed, journal)
        objective = SourceObjective(
            tally,
            where,
            pulse=pulse,
            parameterization=parameterization,
            gate=chosen,
            twin=load_setup(setup),  # the lobe's shape for the posterior search
        )
        tally.logged = lambda: objective.n_measurements
        source = {
            "kind": "rig" if rig is not None else "instrument",
            **where_from,
            "description": hardware.description,
        }
        try:
            result = run(objective, x0, seed)
        except ResumeMismatch:
            raise  # nothing new measured: the saved measurements stay as they are
        except (EchocalError, KeyboardInterrupt) as exc:  # the rig failed, or Ctrl-C
            context = {
                "method": run.method,
                "setup": setup,
                "seed": seed,
                "source": source,
                "pulse": {"name": pulse.name, "center_frequency_hz": pulse.center_frequency},
                "x0_deg": list(x0),
                "fingerprint": stamp,
                "ascans": JOURNAL,
                "resumed_from": resumed.n_replayed,
            }
            note = _save_interrupted(exc, objective, tally, out, context)
            if note is None:  # nothing measured: nothing to save
                raise
            if isinstance(exc, KeyboardInterrupt):  # then exit 130, as any Ctrl-C
                console.print(
                    f"[yellow]interrupted:[/] {escape(note)}", highlight=False, soft_wrap=True
                )
                raise
            raise _with_note(exc, note) from exc
        from_log = resumed.n_replayed
        record = run.provenance(
            provenance,
            result,
            setup=setup,
            source={**source, "identification": hardware.description},
            position=where,
            seed=seed,
            gate=chosen,
        )
        resumption = (
            {"measurements_from_log": from_log, "measured_now": tally.n_measurements - from_log}
            if journal.saved
            else None
        )
        if record is not None and resumption is not None:
            record["resumed"] = resumption
        figures = _save_measured(result, out, None, plots, objective, record)
        journal.discard()  # the result is written: nothing left to resume
        extra: dict[str, Any] = {"gate": None if chosen is None else chosen.describe()}
        if resumption is not None:
            extra["resumed"] = resumption
        return _Measured(
            result=result,
            where=where,
            pulse=pulse,
            pulse_from=f"--setup {setup}",
            source=source,
            extra=extra,
            figures=figures,
        )


def _on_replay(
    run: _Run,
    replay: Path,
    replay_mode: str | None,
    setup: str | None,
    position: str | None,
    *,
    parameterization: str,
    start: tuple[float, float] | None,
    seed: int,
    out: Path,
    plots: bool,
    provenance: Any = None,
    gate: str | None = None,
) -> _Measured:
    """Open the recording, check the options against it, calibrate, save: ``--replay FILE``."""
    from echocal._validate import one_of
    from echocal.measurement.objective import SourceObjective
    from echocal.measurement.replay import MODES, ReplaySource
    from echocal.signal.window import RecordingWindow

    if replay_mode is not None:
        one_of("--replay-mode", replay_mode, MODES)
    mode: dict[str, Any] = {} if replay_mode is None else {"mode": replay_mode}  # else default
    with ReplaySource.open(replay, rng=seed, **mode) as recording:
        index, where = replay_position(recording, position)
        pulse, pulse_from = _replay_pulse(recording, setup)
        window = RecordingWindow(
            fs=recording.fs, start=recording.start_time, n_samples=recording.n_samples
        )
        chosen = gate_for_source(gate, pulse=pulse, setup=setup, window=window)
        hold_output_lock(out)  # one writer per --out (made here, the options checked)
        if start is None:
            start = grid_centre(recording, parameterization)
        bounds = (
            tilt_bounds_in_recording(recording, start)
            if parameterization == "tilt"
            else None  # the recorded grid's extent: every pose in it is recorded
        )
        objective = SourceObjective(
            recording,
            where,
            pulse=pulse,
            parameterization=parameterization,
            bounds=bounds,
            gate=chosen,
            twin=recording.recorded_setup(),  # the lobe's shape for the posterior search
        )
        result = run(objective, start, seed)
        maps = RecordingMap(recording, index, pulse, objective.metric, parameterization, chosen)
        from echocal.provenance import file_digest

        record = run.provenance(
            provenance,
            result,
            setup=setup,
            source={
                "kind": "replay",
                "file": str(Path(replay).resolve()),
                "sha256": file_digest(replay),
                "mode": recording.mode,
                "description": recording.description,
            },
            position=where,
            seed=seed,
            gate=chosen,
        )
        best = None if maps.best is None else [float(v) for v in maps.best]
        return _Measured(
            result=result,
            where=where,
            pulse=pulse,
            pulse_from=pulse_from,
            source={
                "kind": "replay",
                "file": str(replay),
                "mode": recording.mode,
                "description": recording.description,
            },
            extra={
                "recording_best_deg": best,
                "gate": None if chosen is None else chosen.describe(),
            },
            figures=_save_measured(result, out, maps, plots, objective, record),
        )


PARTIAL_LOG = "partial_log.json"
"""What a run on a rig measured before the rig failed (or Ctrl-C), in ``--out``."""


def _save_interrupted(
    exc: BaseException, objective: Any, tally: Tally, out: Path, context: dict[str, Any]
) -> str | None:
    """Write ``out/partial_log.json`` — every measurement made so far, in order, with its
    point, pose, value and time — and return the sentence that says so; None (nothing
    written) when nothing was measured.  The objective's log is followed by the A-scans of
    the batch the fault cut short (``unfinished_batch`` of them; the method never saw
    their values, computed here with the objective's metric).  If the file cannot be
    written the sentence says so instead (the run's own error stays the one reported)."""
    from echocal._signals import how
    from echocal.geometry import convert_angles
    from echocal.io import atomic_write_text, json_ready
    from echocal.measurement.objective import ascan_metric

    log = objective.log
    tail = tally.unlogged(len(log.values))
    n = len(log.values) + len(tail)
    if n == 0:
        return None
    names, parameterization = objective.names, objective.parameterization
    poses = [objective.pose(a, b) for a, b in log.points] + [pose for _, pose, _ in tail]
    tail_points = [
        convert_angles(pose.azimuth, pose.coelevation, "azimuth-coelevation", parameterization)
        for _, pose, _ in tail
    ]
    points = np.concatenate([log.points, np.reshape(tail_points, (-1, 2))])
    values = np.concatenate(
        [
            log.values,
            [
                ascan_metric(scan, objective.metric, objective.pulse, objective.window_length)
                for _, _, scan in tail
            ],
        ]
    )
    times = np.concatenate([log.times, [t for t, _, _ in tail]])
    finite = np.isfinite(values)
    best = None
    if np.any(finite):
        i = int(np.flatnonzero(finite)[np.argmax(values[finite])])
        best = {"index": i, "point_deg": points[i], "value": values[i]}
    record = {
        "status": "interrupted",
        "error": how(exc) if isinstance(exc, KeyboardInterrupt) else str(exc),
        **context,
        "position_m": objective.position,
        "metric": objective.metric,
        "parameterization": parameterization,
        "names": list(names),
        "n_measurements": n,
        "unfinished_batch": len(tail),
        "points": points,
        "values": values,
        "times": times,
        "pose_columns": ["x_m", "y_m", "z_m", "azimuth_deg", "coelevation_deg"],
        "poses": np.array([pose.as_array() for pose in poses]),
        "best": best,
    }
    path = out / PARTIAL_LOG
    try:
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, json.dumps(json_ready(record), indent=1))
    except OSError as err:  # DataFileError is one too
        return f"the {n} measurements made before could not be saved to {path}: {err}"
    where = ""
    if best is not None:
        a, b = (float(v) for v in best["point_deg"])
        where = (
            f"; the largest value was at {names[0]}={a:.3f}, {names[1]}={b:.3f} deg "
            f"(a new run could start there instead: --x0 {a:.3f},{b:.3f})"
        )
    return (
        f"the run stopped after {n} measurements; they are saved, with their poses, values "
        f"and times, to {path}, and their A-scans in {out / JOURNAL}: run the same command "
        f"again to resume (nothing is measured twice){where}"
    )


def _with_note(exc: BaseException, note: str) -> Exception:
    """``exc``'s error with ``note`` appended, of the same public class (one error line)."""
    from echocal.errors import EchocalError, InstrumentError, LimitError

    kind = next((k for k in (InstrumentError, LimitError) if isinstance(exc, k)), EchocalError)
    return kind(f"{exc}; {note}")


def _check_timeout(timeout: float) -> float:
    """``--timeout`` [s], > 0 and at most :data:`~echocal.measurement.hardware.MAX_TIMEOUT`."""
    from echocal._validate import capped_float
    from echocal.measurement.hardware import _TIMEOUT_WHY, MAX_TIMEOUT

    return capped_float("--timeout", timeout, MAX_TIMEOUT, _TIMEOUT_WHY)


def _parse_address(text: str) -> tuple[str, int]:
    """``--instrument HOST:PORT`` → (host, port); an IPv6 host may be bracketed."""
    from echocal.errors import EchocalValueError

    host, sep, port = text.strip().rpartition(":")
    host = host.strip().removeprefix("[").removesuffix("]")
    if not sep or not host or not port.strip().isdigit() or not 1 <= int(port) <= 65535:
        raise EchocalValueError(
            "--instrument takes HOST:PORT of a rig speaking echocal's line protocol, the "
            f"port 1-65535 (e.g. 127.0.0.1:5025); got {text!r}"
        )
    return host, int(port)


def _check_reachable(limits: Any, where: Any) -> None:
    """LimitError if the rig cannot reach position ``where`` [m] (before any move)."""
    from echocal.errors import LimitError
    from echocal.geometry import Pose

    middle = (0.5 * sum(limits.azimuth), 0.5 * sum(limits.coelevation))
    x, y, z = (float(v) for v in where)
    problems = limits.violations(Pose(x, y, z, *middle))
    if problems:
        raise LimitError(f"--position is outside the rig's limits: {'; '.join(problems)}")


def _save_measured(
    result: Any,
    out: Path,
    maps: RecordingMap | None,
    plots: bool,
    objective: Any,
    provenance: dict[str, Any] | None = None,
) -> dict[str, str]:
    """Write result.json (with its ``provenance``), the A-scan at the estimate
    (:func:`save_final_ascan`) and (with ``plots``) the convergence and path plots of a run
    on a recording (``maps``) or a rig (None: no map)."""
    prepare_out(out)
    result.save_json(out / "result.json", provenance=provenance)
    final = save_final_ascan(objective, result, out, plots)
    if not plots:
        return final
    from echocal.plots.calibration import measured_convergence_figure, path_figure

    label = result.method
    if maps is None:
        conv = measured_convergence_figure(
            result, title=f"{label} on a rig: the pseudo-energy measured (no truth known)"
        )
        path = path_figure(
            None,
            {label: result},
            x0=result.iterates[0],
            title=f"{label}: path over the measured poses (a rig has no map)",
            show_measurements=True,
        )
    else:
        peak = maps.peak if maps.peak > 0 else None
        conv = measured_convergence_figure(
            result,
            scale=peak,
            scale_label="the recording's maximum",
            iterate_values=maps.at(result.iterates),
            iterate_label="the recording's metric at the estimate",
            title=f"{label} on a recording: the pseudo-energy measured (no truth known)",
        )
        path = path_figure(
            maps.cost_map(),
            {label: result},
            x0=result.iterates[0],
            truth=maps.best,
            truth_label="the recording's best grid pose",
            title=f"{label}: path over the recording's metric map (measured poses in grey)",
            show_measurements=True,
        )
    return {**final, **save_pngs({"convergence": conv, "path": path}, out)}


def _print_measured_estimate(done: _Measured, out: Path) -> None:
    """The human report of a run on a recording or a rig: no truth, so no error."""
    result, pulse, extra = done.result, done.pulse, done.extra
    names = result.names
    found = result.acquisition_measurements
    search = "" if found is None else f" (echo found after {found})"
    best = extra.get("recording_best_deg")
    if "recording_best_deg" not in extra:
        reference = "  truth     unknown: a rig does not know its optimum (no error computed)"
    elif best is None:
        reference = "  truth     unknown, and the recording has no finite A-scan to compare with"
    else:
        reference = (
            f"  recording's best grid pose {names[0]} = {best[0]:.3f}°, {names[1]} = "
            f"{best[1]:.3f}° (no truth is known for a recording)"
        )
    resumed = extra.get("resumed")
    if resumed is not None:
        reference += (
            f"\n  resumed   {resumed['measurements_from_log']} measurements from the "
            f"interrupted run, {resumed['measured_now']} measured now"
        )
    output.print(
        f"[bold]{escape(result.method)}[/] on {escape(done.source['description'])}\n"
        f"  estimate  {names[0]} = {result.x[0]:8.3f}°, {names[1]} = {result.x[1]:8.3f}°\n"
        f"{escape(reference)}\n"
        f"  measurements {result.n_measurements}{search}   iterations {result.n_iterations}\n"
        f"  pulse     {escape(pulse.name)} {pulse.center_frequency / 1e6:g} MHz, from "
        f"{escape(done.pulse_from)}\n"
        f"  stopped:  {escape(result.message)}\n"
        f"  saved to  {escape(str(out))}/"
    )
