"""``echocal calibrate``: find the orientation of maximum echo on a simulated setup, a
recording (``--replay FILE``) or a rig speaking the TCP line protocol (``--instrument
HOST:PORT``).

The three sources go through the same :class:`~echocal.measurement.SourceObjective` and
:func:`~echocal.calibrate.calibrate` call; only a simulated setup knows its true optimum,
so a recording or a rig is reported without a truth or an error.
"""

from __future__ import annotations

import inspect
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.markup import escape

from echocal.cli._common import (
    console,
    output,
    parse_options,
    parse_pair,
    parse_pose,
    write_json,
)
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup


def register(app: typer.Typer) -> None:
    """Add ``echocal calibrate`` to ``app``."""

    @app.command("calibrate")
    def calibrate_command(
        setup: Annotated[
            str | None,
            typer.Option(
                help=SETUP_HELP + "  Default: thesis.  With --replay or --instrument only its "
                "pulse is used (the matched filter's template); a replay made by `echocal "
                "record` brings its own."
            ),
        ] = None,
        replay: Annotated[
            Path | None,
            typer.Option(
                "--replay",
                help="Calibrate on a recording (a replay file written by `echocal record`) "
                "instead of a simulation.",
            ),
        ] = None,
        replay_mode: Annotated[
            str | None,
            typer.Option(
                help="How the recording answers a pose: nearest (the default: the nearest "
                "grid pose), random-repeat or interpolate (see docs/sources.md)."
            ),
        ] = None,
        instrument: Annotated[
            str | None,
            typer.Option(
                "--instrument",
                metavar="HOST:PORT",
                help="Calibrate on a rig speaking echocal's TCP line protocol (e.g. `echocal "
                "instrument-server`); needs --position and --setup (for the pulse).",
            ),
        ] = None,
        timeout: Annotated[
            float | None,
            typer.Option(
                help="[s] With --instrument: how long one reply may take, a move included "
                "(default 2); a transport fault is retried 3 times."
            ),
        ] = None,
        method: Annotated[str, typer.Option(help="Calibration method (see `echocal methods`).")] = (
            "auto"
        ),
        x0: Annotated[
            str | None,
            typer.Option(
                "--x0",
                help="Initial guess A,B [deg] in the parameterization; default 0,0, on a "
                "replay the centre of the recorded grid.",
            ),
        ] = None,
        position: Annotated[
            str | None,
            typer.Option(
                help="X,Y,Z of the probe (mm unless a unit is given); default: the "
                "setup's reference position, or a recording's only position.  Only the "
                "position: the angles are what calibrate finds (start them with --x0)."
            ),
        ] = None,
        parameterization: Annotated[
            str | None,
            typer.Option(
                help="'tilt' (pole-free gimbal tilts) or 'azimuth-coelevation'; default tilt, "
                "on a replay azimuth-coelevation (the recorded grid's own angles)."
            ),
        ] = None,
        snr: Annotated[str | None, typer.Option(help=SNR_HELP)] = None,
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = None,
        budget: Annotated[int | None, typer.Option(help="Maximum number of measurements.")] = None,
        max_iter: Annotated[int | None, typer.Option(help="Maximum iterations.")] = None,
        settle: Annotated[
            str,
            typer.Option(
                help="TOL,PATIENCE: stop once the last PATIENCE recommendations lie within "
                "TOL degrees of their mean; 'none' runs to the budget or iteration limit."
            ),
        ] = "0.01,8",
        preset: Annotated[
            str | None, typer.Option(help="Method options preset, e.g. thesis-table-7.")
        ] = None,
        option: Annotated[
            list[str] | None,
            typer.Option(
                "--option",
                help="KEY=VALUE method option, repeatable (see `echocal methods NAME`), e.g. "
                "--option fine_radius=1 for auto at high SNR; true/false/yes/no and none "
                '(any case) are booleans and None, JSON values (1, 0.5, {"radius": 0.5}) '
                "are taken as such.  Also the run keywords xtol=DEG and final_check=N.  An "
                "unknown name or a value of the wrong type is an error.",
            ),
        ] = None,
        search_radius: Annotated[
            float | None,
            typer.Option(
                help="How far from x0 [deg] to search for a lost echo before giving up "
                "(status 4, 'acquisition failed'): auto and acquisition search to 20 by "
                "default; any other method gets this search in front of it."
            ),
        ] = None,
        seed: Annotated[
            int | None,
            typer.Option(
                help="Seed for the noise and randomized methods (and a random-repeat "
                "replay); default: the setup file's seed, else 0 (a replay or a rig: 0)."
            ),
        ] = None,
        out: Annotated[Path, typer.Option(help="Folder for result.json and the plots.")] = Path(
            "echocal-out/calibrate"
        ),
        plots: Annotated[bool, typer.Option(help="Save the convergence and path plots.")] = True,
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the result as one JSON object.")
        ] = False,
    ) -> None:
        """Calibrate the orientation at one position: on a simulated setup (and compare
        with its true optimum), on a recording (--replay FILE) or on a rig (--instrument
        HOST:PORT), where no truth is known.

        Exit status: 0 when the method returned an estimate; 1 when no echo was found
        (the acquisition search failed, or every measurement failed) — the result files
        are still written; 2 for bad input.
        """
        run = _Run.parse(method, budget, max_iter, settle, preset, option, search_radius)
        if replay is not None or instrument is not None:
            _check_measured_options(replay, instrument, snr, specimen)
            _calibrate_measured(
                run,
                replay=replay,
                replay_mode=replay_mode,
                instrument=instrument,
                timeout=timeout,
                setup=setup,
                position=position,
                parameterization=parameterization,
                x0=x0,
                seed=seed,
                out=out,
                plots=plots,
                json_output=json_output,
            )
            return
        for name, value in (("--replay-mode", replay_mode), ("--timeout", timeout)):
            if value is not None:
                from echocal.errors import EchocalValueError

                where = "--replay FILE" if name == "--replay-mode" else "--instrument HOST:PORT"
                raise EchocalValueError(f"{name} applies only with {where}")
        setup = "thesis" if setup is None else setup
        parameterization = "tilt" if parameterization is None else parameterization
        _calibrate_simulated(
            run,
            setup=setup,
            specimen=specimen,
            snr=snr,
            seed=seed,
            position=position,
            parameterization=parameterization,
            x0="0,0" if x0 is None else x0,
            out=out,
            plots=plots,
            json_output=json_output,
        )


@dataclass(frozen=True)
class _Run:
    """The method and run options of one ``echocal calibrate``, parsed and checked."""

    method: str
    budget: int | None
    max_iter: int | None
    settle: tuple[float, int] | None
    preset: str | None
    search: dict[str, Any]
    extra: dict[str, Any]
    run_keywords: dict[str, Any]

    @classmethod
    def parse(
        cls,
        method: str,
        budget: int | None,
        max_iter: int | None,
        settle: str,
        preset: str | None,
        option: list[str] | None,
        search_radius: float | None,
    ) -> _Run:
        """Check --method, --option, --search-radius and --settle (before any measurement)."""
        search = _search_options(method, search_radius)
        extra = parse_options(option, "--option")
        run_keywords = _check_options(method, extra, search)
        return cls(
            method, budget, max_iter, _parse_settle(settle), preset, search, extra, run_keywords
        )

    def __call__(self, objective: Any, x0: tuple[float, float], rng: Any) -> Any:
        """Run the calibration; its warnings become one ``warning:`` line each on stderr."""
        from echocal.calibrate import calibrate

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = calibrate(
                objective,
                method=self.method,
                x0=x0,
                budget=self.budget,
                max_iter=self.max_iter,
                settle=self.settle,
                preset=self.preset,
                rng=rng,
                **self.run_keywords,
                **self.search,
                **{k: v for k, v in self.extra.items() if k not in self.run_keywords},
            )
        for warning in caught:
            console.print(f"[yellow]warning:[/] {escape(str(warning.message))}")
        return result


def _calibrate_simulated(
    run: _Run,
    *,
    setup: str,
    specimen: str | None,
    snr: str | None,
    seed: int | None,
    position: str | None,
    parameterization: str,
    x0: str,
    out: Path,
    plots: bool,
    json_output: bool,
) -> None:
    """Calibrate on a simulated setup and judge the estimate against its true optimum."""
    from echocal.evaluation import evaluate_run
    from echocal.measurement.objective import SourceObjective

    virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
    where = _parse_position(position) if position else virtual.reference_position
    objective = SourceObjective(virtual, where, parameterization=parameterization)
    # the effective seed: --seed, else the setup file's, else 0
    result = run(objective, parse_pair(x0, "--x0"), virtual.rng)
    evaluation = evaluate_run(virtual, where, result)
    out.mkdir(parents=True, exist_ok=True)
    result.save_json(out / "result.json")
    figures = _save_plots(virtual, where, evaluation, out) if plots else {}
    found = result.success
    summary = {
        "setup": virtual.name,
        "seed": virtual.rng if isinstance(virtual.rng, int) else None,
        "source": {"kind": "setup", "name": virtual.name, "description": virtual.description},
        "position_m": [float(v) for v in where],
        "method": result.method,
        "parameterization": parameterization,
        "names": list(result.names),
        "success": found,
        "estimate_deg": [float(v) for v in result.x] if found else None,
        "truth_deg": [float(v) for v in evaluation.truth],
        "error_deg": evaluation.error if found else None,
        "n_measurements": result.n_measurements,
        "acquisition_measurements": result.acquisition_measurements,
        "n_iterations": result.n_iterations,
        "status": result.status,
        "message": result.message,
        "files": {"result": str(out / "result.json"), **figures},
    }
    if json_output:
        write_json(summary)
    elif found:
        _print_estimate(result, evaluation, virtual, out)
    else:
        _print_failure(result, out)
    if not found:
        raise typer.Exit(code=EXIT_NO_ECHO)


def _check_measured_options(
    replay: Path | None, instrument: str | None, snr: str | None, specimen: str | None
) -> None:
    """Refuse what a recording or a rig cannot honour (before any work)."""
    from echocal.errors import EchocalValueError

    if replay is not None and instrument is not None:
        raise EchocalValueError(
            "--replay and --instrument are mutually exclusive: calibrate on one source"
        )
    what = "a recording (--replay)" if replay is not None else "a rig (--instrument)"
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
) -> None:
    """Calibrate on a recording or a rig: the same objective and call, no truth known."""
    from echocal._validate import one_of
    from echocal.errors import EchocalValueError
    from echocal.geometry import PARAMETERIZATIONS

    if replay_mode is not None and replay is None:
        raise EchocalValueError("--replay-mode applies only with --replay FILE")
    if timeout is not None and instrument is None:
        raise EchocalValueError("--timeout applies only with --instrument HOST:PORT")
    default = "azimuth-coelevation" if replay is not None else "tilt"
    parameterization = one_of(
        "--parameterization",
        default if parameterization is None else parameterization,
        PARAMETERIZATIONS,
    )
    start = parse_pair(x0, "--x0") if x0 is not None else None
    seed = 0 if seed is None else seed
    common = {"parameterization": parameterization, "start": start, "seed": seed}
    if instrument is not None:
        done = _on_instrument(
            run, instrument, timeout, setup, position, out=out, plots=plots, **common
        )
    else:
        assert replay is not None
        done = _on_replay(run, replay, replay_mode, setup, position, out=out, plots=plots, **common)
    result, pulse = done.result, done.pulse
    found = result.success
    summary = {
        "setup": setup,
        "seed": seed,
        "source": done.source,
        "pulse": {
            "name": pulse.name,
            "center_frequency_hz": float(pulse.center_frequency),
            "from": done.pulse_from,
        },
        "position_m": [float(v) for v in done.where],
        "method": result.method,
        "parameterization": parameterization,
        "names": list(result.names),
        "success": found,
        "estimate_deg": [float(v) for v in result.x] if found else None,
        "truth_deg": None,  # only a simulation knows its optimum
        "error_deg": None,
        **done.extra,
        "n_measurements": result.n_measurements,
        "acquisition_measurements": result.acquisition_measurements,
        "n_iterations": result.n_iterations,
        "status": result.status,
        "message": result.message,
        "files": {"result": str(out / "result.json"), **done.figures},
    }
    if json_output:
        write_json(summary)
    elif found:
        _print_measured_estimate(done, out)
    else:
        _print_failure(result, out)
    if not found:
        raise typer.Exit(code=EXIT_NO_ECHO)


def _on_instrument(
    run: _Run,
    instrument: str,
    timeout: float | None,
    setup: str | None,
    position: str | None,
    *,
    parameterization: str,
    start: tuple[float, float] | None,
    seed: int,
    out: Path,
    plots: bool,
) -> _Measured:
    """Check the rig's options, connect, calibrate, save: ``--instrument HOST:PORT``."""
    from echocal._validate import positive_float
    from echocal.errors import EchocalValueError
    from echocal.measurement.hardware import HardwareSource
    from echocal.measurement.objective import SourceObjective

    host, port = _parse_address(instrument)
    if position is None:
        raise EchocalValueError(
            "--position X,Y,Z is required with --instrument: the rig is calibrated at "
            "one position (mm unless a unit is given)"
        )
    where = _parse_position(position)
    if setup is None:
        raise EchocalValueError(
            "--instrument needs the transmitted pulse for the matched filter: pass "
            "--setup NAME|FILE whose [pulse] is the rig's (see `echocal setup list`)"
        )
    pulse = _setup_pulse(setup)
    wait = {} if timeout is None else {"timeout": positive_float("--timeout", timeout)}
    with HardwareSource.connect(host, port, **wait) as rig:
        _check_reachable(rig.limits, where)
        objective = SourceObjective(rig, where, pulse=pulse, parameterization=parameterization)
        result = run(objective, (0.0, 0.0) if start is None else start, seed)
        figures = _save_measured(result, out, None, plots)
        source = {"kind": "instrument", "address": f"{host}:{port}"}
        return _Measured(
            result=result,
            where=where,
            pulse=pulse,
            pulse_from=f"--setup {setup}",
            source={**source, "description": rig.description},
            extra={},
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
) -> _Measured:
    """Open the recording, check the options against it, calibrate, save: ``--replay FILE``."""
    from echocal._validate import one_of
    from echocal.measurement.objective import SourceObjective
    from echocal.measurement.replay import MODES, ReplaySource

    if replay_mode is not None:
        one_of("--replay-mode", replay_mode, MODES)
    mode = {} if replay_mode is None else {"mode": replay_mode}  # else the replay's default
    with ReplaySource.open(replay, rng=seed, **mode) as recording:
        index, where = _replay_position(recording, position)
        pulse, pulse_from = _replay_pulse(recording, setup)
        if start is None:
            start = _grid_centre(recording, parameterization)
        bounds = (
            _tilt_bounds_in_recording(recording, start)
            if parameterization == "tilt"
            else None  # the recorded grid's extent: every pose in it is recorded
        )
        objective = SourceObjective(
            recording, where, pulse=pulse, parameterization=parameterization, bounds=bounds
        )
        result = run(objective, start, seed)
        maps = _RecordingMap(recording, index, pulse, objective.metric, parameterization)
        best = None if maps.best is None else [float(v) for v in maps.best]
        source = {"kind": "replay", "file": str(replay), "mode": recording.mode}
        return _Measured(
            result=result,
            where=where,
            pulse=pulse,
            pulse_from=pulse_from,
            source={**source, "description": recording.description},
            extra={"recording_best_deg": best},
            figures=_save_measured(result, out, maps, plots),
        )


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


def _mm(point: Any) -> str:
    """A position [m] as ``"x, y, z"`` in mm."""
    return ", ".join(f"{1e3 * float(v):g}" for v in point)


def _check_reachable(limits: Any, where: Any) -> None:
    """LimitError if the rig cannot reach position ``where`` [m] (before any move)."""
    from echocal.errors import LimitError
    from echocal.geometry import Pose

    middle = (0.5 * sum(limits.azimuth), 0.5 * sum(limits.coelevation))
    problems = limits.violations(Pose(*(float(v) for v in where), *middle))
    if problems:
        raise LimitError(f"--position is outside the rig's limits: {'; '.join(problems)}")


def _config_pulse(config: Any, base_dir: Path, where: str) -> Any:
    """The pulse of a setup's ``[pulse]`` table, built as a setup builds it."""
    from echocal.setups import build_pulse

    return build_pulse(config, base_dir, where=where)


def _setup_pulse(setup: str) -> Any:
    """The pulse of ``--setup`` (a built-in or a TOML file); nothing else of it is used."""
    from echocal.setups import load_setup_config

    config, base_dir = load_setup_config(setup)
    return _config_pulse(config.pulse, base_dir, setup)


def _recorded_pulse(recording: Any) -> tuple[Any, str]:
    """The pulse of the setup a recording was made with (``echocal record`` stores its
    config in the file's ``source`` attribute) and where it came from; (None, why not)."""
    from echocal.errors import EchocalError
    from echocal.setups import PulseConfig

    stored = recording.source_info.get("setup")
    config = stored.get("config") if isinstance(stored, dict) else None
    table = config.get("pulse") if isinstance(config, dict) else None
    if not isinstance(table, dict):
        return None, (
            "the recording does not say which pulse was transmitted (only `echocal record` "
            "stores its setup in the file)"
        )
    name = stored.get("setup")
    # a setup file's relative paths (a sampled pulse's samples) are relative to its folder
    base = Path(name).parent if isinstance(name, str) and name.endswith(".toml") else Path.cwd()
    try:
        pulse = _config_pulse(PulseConfig.model_validate(table), base, "pulse")
    except (EchocalError, ValueError) as exc:
        return None, f"the recorded setup's pulse cannot be rebuilt ({exc})"
    return pulse, f"the recording's setup {name or config.get('name', '')}".rstrip()


def _same_pulse(a: Any, b: Any) -> bool:
    if type(a) is not type(b):
        return False
    pa, pb = a.parameters(), b.parameters()
    return pa.keys() == pb.keys() and all(np.array_equal(pa[k], pb[k]) for k in pa)


def _replay_pulse(recording: Any, setup: str | None) -> tuple[Any, str]:
    """The matched filter's template for a recording: ``--setup``'s pulse when given (with a
    warning if the recording was made with another), else the recorded setup's."""
    from echocal.errors import ConfigError

    recorded, origin = _recorded_pulse(recording)
    if setup is not None:
        pulse = _setup_pulse(setup)
        if recorded is not None and not _same_pulse(pulse, recorded):
            console.print(
                f"[yellow]warning:[/] the pulse of --setup {escape(setup)} ({pulse.name} "
                f"{pulse.center_frequency / 1e6:g} MHz) differs from the one {recording.path} "
                f"was recorded with ({recorded.name} {recorded.center_frequency / 1e6:g} MHz); "
                "the matched filter uses --setup's",
                highlight=False,
                soft_wrap=True,
            )
        return pulse, f"--setup {setup}"
    if recorded is None:
        raise ConfigError(
            f"{recording.path}: no pulse for the matched filter: {origin}; pass --setup "
            "NAME|FILE whose [pulse] is the transmitted one"
        )
    return recorded, origin


def _replay_position(recording: Any, position: str | None) -> tuple[int, Any]:
    """Index and [m] of the recorded position to calibrate at: ``--position`` (which must be
    a recorded one) or, when omitted, the recording's only position."""
    from echocal.errors import EchocalValueError, LimitError

    recorded = recording.positions
    listed = "; ".join(f"({_mm(p)})" for p in recorded[:8])
    if len(recorded) > 8:
        listed += f"; ... ({len(recorded)} in all)"
    if position is None:
        if len(recorded) > 1:
            raise EchocalValueError(
                f"{recording.path} holds {len(recorded)} positions, {listed} mm: choose one "
                "with --position X,Y,Z"
            )
        return 0, recorded[0]
    where = _parse_position(position)
    distance = np.linalg.norm(recorded - where, axis=1)
    index = int(np.argmin(distance))
    if distance[index] > recording.position_tolerance:
        raise LimitError(
            f"--position ({_mm(where)}) mm is not a position of {recording.path}: it holds "
            f"{listed} mm (tolerance {1e3 * recording.position_tolerance:g} mm)"
        )
    return index, recorded[index]


def _in_recording(recording: Any, azimuth: Any, coelevation: Any) -> Any:
    """Which orientations [deg] lie on a recording's grid (an azimuth also ±360°)."""
    az, coel = recording.azimuths, recording.coelevations
    inside = np.zeros(np.broadcast(azimuth, coelevation).shape, dtype=bool)
    for shift in (0.0, -360.0, 360.0):
        inside |= (az[0] <= azimuth + shift) & (azimuth + shift <= az[-1])
    return inside & (coel[0] <= coelevation) & (coelevation <= coel[-1])


def _tilt_extent(recording: Any) -> Any:
    """[deg] (2, 2): the tilt box around a recording's grid (its grid sampled densely)."""
    from echocal.geometry import convert_angles

    az, coel = recording.azimuths, recording.coelevations
    a, c = np.meshgrid(
        np.linspace(az[0], az[-1], 101), np.linspace(coel[0], coel[-1], 101), indexing="ij"
    )
    tx, ty = convert_angles(a, c, "azimuth-coelevation", "tilt")
    return np.array([[tx.min(), tx.max()], [ty.min(), ty.max()]])


def _tilt_bounds_in_recording(recording: Any, start: tuple[float, float]) -> Any:
    """[deg] (2, 2): the largest tilt box around ``start`` whose every orientation the
    recording holds.

    The grid is in (azimuth, co-elevation): in tilts it is a curved region.  On a 161 × 161
    lattice over that region, less one lattice step all round (its curved edges bulge
    between lattice points), the box of largest area that contains ``start`` is found; it
    is shrunk further, a step at a time, should any of 400 points along each of its edges
    lie off the grid.
    """
    from scipy.ndimage import binary_erosion

    from echocal.errors import LimitError
    from echocal.geometry import convert_angles

    def inside(tx: Any, ty: Any) -> Any:
        return _in_recording(recording, *convert_angles(tx, ty, "tilt", "azimuth-coelevation"))

    extent = _tilt_extent(recording)
    ga, gb = (np.linspace(lo, hi, 161) for lo, hi in extent)
    ok = binary_erosion(inside(ga[:, None], gb[None, :]), np.ones((3, 3)), border_value=0)
    # the lattice cell holding start: rows i0..i1 (tilt_x), columns j0..j1 (tilt_y)
    i0 = int(np.clip(np.searchsorted(ga, start[0]) - 1, 0, ga.size - 2))
    j0 = int(np.clip(np.searchsorted(gb, start[1]) - 1, 0, gb.size - 2))
    i1, j1 = i0 + 1, j0 + 1
    covered = (
        f"it covers azimuth [{recording.azimuths[0]:g}, {recording.azimuths[-1]:g}] and "
        f"co-elevation [{recording.coelevations[0]:g}, {recording.coelevations[-1]:g}] deg, "
        f"tilt_x [{extent[0, 0]:.3g}, {extent[0, 1]:.3g}], tilt_y [{extent[1, 0]:.3g}, "
        f"{extent[1, 1]:.3g}] deg"
    )
    if not bool(inside(*start)):
        raise LimitError(
            f"--x0 (tilt_x={start[0]:g}, tilt_y={start[1]:g}) deg is not an orientation of "
            f"{recording.path}: {covered}"
        )
    if not ok[i0 : i1 + 1, j0 : j1 + 1].all():
        raise LimitError(
            f"--x0 (tilt_x={start[0]:g}, tilt_y={start[1]:g}) deg lies at the edge of "
            f"{recording.path}: start farther inside ({covered})"
        )
    box, area = (i0, i1, j0, j1), 0
    rows = ok[i1].copy()
    for lo in range(i0, -1, -1):  # tilt_x rows lo..hi around the cell; a tilt_y run through it
        rows &= ok[lo]
        if not rows[j0 : j1 + 1].all():
            break
        cols = rows.copy()
        for hi in range(i1, ok.shape[0]):
            cols &= ok[hi]
            if not cols[j0 : j1 + 1].all():
                break
            gaps = np.flatnonzero(~cols)
            k = int(np.searchsorted(gaps, j0))
            left = int(gaps[k - 1]) + 1 if k > 0 else 0
            right = int(gaps[k]) - 1 if k < gaps.size else ok.shape[1] - 1
            if (hi - lo) * (right - left) > area:
                box, area = (lo, hi, left, right), (hi - lo) * (right - left)
    edge = np.linspace(0.0, 1.0, 400)
    for shrink in range(5):
        lo_a, hi_a, lo_b, hi_b = box[0] + shrink, box[1] - shrink, box[2] + shrink, box[3] - shrink
        if lo_a >= hi_a or lo_b >= hi_b:
            break
        bounds = np.array([[ga[lo_a], ga[hi_a]], [gb[lo_b], gb[hi_b]]])
        (a0, a1), (b0, b1) = bounds
        ring_a = np.concatenate([a0 + edge * (a1 - a0)] * 2 + [np.full(400, a0), np.full(400, a1)])
        ring_b = np.concatenate([np.full(400, b0), np.full(400, b1)] + [b0 + edge * (b1 - b0)] * 2)
        if inside(ring_a, ring_b).all():
            if not (a0 <= start[0] <= a1 and b0 <= start[1] <= b1):
                raise LimitError(
                    f"--x0 (tilt_x={start[0]:g}, tilt_y={start[1]:g}) deg lies at the edge of "
                    f"{recording.path}: start farther inside ({covered})"
                )
            return bounds
    raise LimitError(
        f"{recording.path} is too narrow around --x0 for a calibration in tilts: {covered}; "
        "calibrate in its own angles (--parameterization azimuth-coelevation)"
    )


def _grid_centre(recording: Any, parameterization: str) -> tuple[float, float]:
    """[deg] the centre of a recording's grid in ``parameterization`` (the default x0)."""
    from echocal.geometry import convert_angles

    az, coel = recording.azimuths, recording.coelevations
    centre = convert_angles(
        0.5 * (az[0] + az[-1]),
        0.5 * (coel[0] + coel[-1]),
        "azimuth-coelevation",
        parameterization,
    )
    return float(centre[0]), float(centre[1])


class _RecordingMap:
    """A recording's own metric at one position, repeat-averaged (no measurement counted):
    its best grid pose, its value at given orientations, and the path plot's map."""

    def __init__(
        self, recording: Any, index: int, pulse: Any, metric: str, parameterization: str
    ) -> None:
        from functools import partial

        from echocal.geometry import convert_angles
        from echocal.measurement.objective import ascan_metric

        self.recording, self.parameterization = recording, parameterization
        self.position = recording.positions[index]
        self.metric = partial(ascan_metric, metric=metric, pulse=pulse)  # one object: cached
        self.values = recording.metric_grid(self.metric, index)  # (n_azimuth, n_coelevation)
        finite = np.isfinite(self.values)
        self.peak = float(np.max(self.values[finite])) if finite.any() else float("nan")
        self.best: Any = None
        if finite.any():
            a, c = np.unravel_index(np.argmax(np.where(finite, self.values, -np.inf)), finite.shape)
            best = convert_angles(
                recording.azimuths[a],
                recording.coelevations[c],
                "azimuth-coelevation",
                parameterization,
            )
            self.best = np.array(best, dtype=float)

    def at(self, points: Any) -> Any:
        """The recording's metric interpolated at orientations ``points`` [deg], shape (k, 2);
        NaN off the grid."""
        from echocal.errors import LimitError
        from echocal.geometry import pose_from_angles

        out = np.full(len(points), np.nan)
        for k, (a, b) in enumerate(points):
            pose = pose_from_angles(self.position, a, b, self.parameterization)
            try:
                out[k] = self.recording.interpolated_metric(pose, self.metric)
            except LimitError:
                continue
        return out

    def cost_map(self) -> Any:
        """The path plot's background: the grid itself in (azimuth, co-elevation), or the
        grid interpolated onto a 81 × 81 tilt lattice over its extent (NaN off the grid);
        None for a grid with a single azimuth or co-elevation."""
        from echocal.calibrate.objective import PARAMETERIZATIONS
        from echocal.evaluation import CostMap

        names = PARAMETERIZATIONS[self.parameterization]
        az, coel = self.recording.azimuths, self.recording.coelevations
        if az.size < 2 or coel.size < 2:
            return None
        if self.parameterization == "azimuth-coelevation":
            return CostMap(a=az, b=coel, values=self.values, names=names)
        (a0, a1), (b0, b1) = _tilt_extent(self.recording)
        a, b = np.linspace(a0, a1, 81), np.linspace(b0, b1, 81)
        grid = np.stack(np.meshgrid(a, b, indexing="ij"), axis=-1).reshape(-1, 2)
        return CostMap(a=a, b=b, values=self.at(grid).reshape(81, 81), names=names)


def _save_measured(
    result: Any, out: Path, maps: _RecordingMap | None, plots: bool
) -> dict[str, str]:
    """Write result.json and (with ``plots``) the convergence and path plots of a run on a
    recording (``maps``) or a rig (None: no map)."""
    out.mkdir(parents=True, exist_ok=True)
    result.save_json(out / "result.json")
    if not plots:
        return {}
    from echocal.plots import save_figure
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
            db_floor=-40.0,
            show_measurements=True,
        )
    return {
        name: str(save_figure(fig, out / f"{name}.png", formats=("png",), dpi=110)[0])
        for name, fig in (("convergence", conv), ("path", path))
    }


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


EXIT_NO_ECHO = 1
"""Exit status of a calibration that found no echo (result files written all the same)."""


def _print_estimate(result: Any, evaluation: Any, virtual: Any, out: Path) -> None:
    names = result.names
    found = result.acquisition_measurements
    search = "" if found is None else f" (echo found after {found})"
    output.print(
        f"[bold]{escape(result.method)}[/] on {escape(virtual.description)}\n"
        f"  estimate  {names[0]} = {result.x[0]:8.3f}°, {names[1]} = {result.x[1]:8.3f}°\n"
        f"  truth     {names[0]} = {evaluation.truth[0]:8.3f}°, "
        f"{names[1]} = {evaluation.truth[1]:8.3f}°\n"
        f"  error     {evaluation.error:.4f}°   measurements {result.n_measurements}"
        f"{search}   iterations {result.n_iterations}\n"
        f"  stopped:  {escape(result.message)}\n"
        f"  saved to  {escape(str(out))}/"
    )


def _print_failure(result: Any, out: Path) -> None:
    output.print(
        f"[bold red]no echo found[/] ({escape(result.method)}, "
        f"{result.n_measurements} measurements): {escape(result.message)}.\n"
        "  Nothing was calibrated.  Start nearer the echo (--x0), search farther "
        "(--search-radius) or check the setup (position, SNR).\n"
        f"  saved to  {escape(str(out))}/ (status {result.status})"
    )


_OWN_OPTION = {
    "budget": "--budget",
    "max_iter": "--max-iter",
    "settle": "--settle",
    "preset": "--preset",
    "rng": "--seed",
    "acquire": "--search-radius",
    "x0": "--x0",
    "method": "--method",
    "objective": "--setup and --position",
}
"""calibrate() keywords that have a command-line option of their own."""

_RUN_KEYWORDS = ("xtol", "final_check")
"""calibrate() keywords with no option of their own, accepted by --option."""

_API_ONLY = {
    "history": "is a warm start from earlier measurements (arrays of their points and "
    "values), which the command line cannot pass; use the Python API "
    "(calibrate(objective, 'model-based', history=(points, values)))",
    "detector": "is the source objective's echo detector, supplied automatically; to "
    "replace it with another Python callable use the Python API",
    "noise_model": "is the source objective's live noise estimate, supplied automatically; "
    "to replace it with another Python callable use the Python API",
    "callback": "is a Python function called after each iteration; use the Python API",
    "bounds": "are the positioner's angle limits, taken from the setup",
}
"""Options the command line cannot give, and why."""


def _check_options(method: str, extra: dict[str, Any], search: dict[str, Any]) -> dict[str, Any]:
    """Refuse ``--option`` names the method does not take (naming the valid ones and the
    nearest), those set by their own option, and those only Python can give; return the
    run keywords (xtol, final_check) among them."""
    from echocal.calibrate import calibrate, get_method
    from echocal.calibrate._options import accepted_options, suggestion
    from echocal.errors import EchocalValueError, UnknownNameError

    accepted = accepted_options(get_method(method))  # an unknown method lists the valid ones
    driver = set(inspect.signature(calibrate).parameters) - {"options"}
    valid = sorted(accepted - set(_API_ONLY) - set(search))
    run: dict[str, Any] = {}
    for key, value in extra.items():
        if key in search:
            raise EchocalValueError(f"--option {key}: set by --search-radius; give it once")
        if key in _OWN_OPTION:
            raise EchocalValueError(
                f"--option {key}: set by its own option {_OWN_OPTION[key]}; use that instead"
            )
        if key in _API_ONLY:
            raise EchocalValueError(f"--option {key}: {key} {_API_ONLY[key]}")
        if key in _RUN_KEYWORDS:
            run[key] = value
        elif key in driver or key not in accepted:
            raise UnknownNameError(
                f"--option {key}: unknown option of method {method!r}"
                f"{suggestion(key, [*valid, *_RUN_KEYWORDS])}; valid: {', '.join(valid)} "
                f"(see `echocal methods {method}`), and the run keywords "
                f"{', '.join(_RUN_KEYWORDS)}"
            )
    return run


def _parse_position(text: str) -> Any:
    """``--position X,Y,Z`` [m] (mm unless a unit is given); refuses orientation angles."""
    from echocal.errors import EchocalValueError

    if len(text.split(",")) != 3:
        raise EchocalValueError(
            "--position takes X,Y,Z of the probe (lengths in mm unless a unit is given), "
            "without angles: the orientation is what calibrate finds (give its start with "
            f"--x0 A,B); got {text!r}"
        )
    return parse_pose(text, "--position").position


def _search_options(method: str, radius: float | None) -> dict[str, Any]:
    """calibrate() keywords for ``--search-radius``: the method's own ``max_radius`` if it
    searches, else an acquisition phase in front of it."""
    if radius is None:
        return {}
    from echocal._validate import positive_float
    from echocal.calibrate import Acquisition, get_method
    from echocal.calibrate.auto import AUTO_SEARCH

    radius = positive_float("--search-radius", radius)
    if issubclass(get_method(method), Acquisition):
        return {"max_radius": radius}
    return {"acquire": {"max_radius": radius, **AUTO_SEARCH}}  # auto's search geometry


def _parse_settle(text: str) -> tuple[float, int] | None:
    if text.strip().lower() == "none":
        return None
    parts = [p.strip() for p in text.split(",")]
    try:
        tol, patience = float(parts[0]), int(parts[1])
    except (IndexError, ValueError):
        raise typer.BadParameter(
            f"--settle takes TOL,PATIENCE (degrees, iterations) or 'none'; got {text!r}"
        ) from None
    if len(parts) != 2:
        raise typer.BadParameter(f"--settle takes exactly TOL,PATIENCE; got {text!r}")
    return tol, patience


def _save_plots(virtual, where, evaluation, out: Path) -> dict[str, str]:
    from echocal.evaluation import cost_map
    from echocal.plots import save_figure
    from echocal.plots.calibration import convergence_figure, path_figure

    result = evaluation.result
    label = result.method
    conv = convergence_figure(
        {label: result},
        {label: evaluation.iterate_values / evaluation.optimum_value},
        optimum_value=1.0,
        title=f"{label}: pseudo-energy of the estimate",
    )
    points = np.vstack([result.iterates, result.points, evaluation.truth[None, :]])
    span = max(3.0, 1.3 * float(np.max(np.abs(points - evaluation.truth))))
    centre = evaluation.truth
    cmap = cost_map(
        virtual,
        where,
        parameterization=result.parameterization,
        a_range=(centre[0] - span, centre[0] + span),
        b_range=(centre[1] - span, centre[1] + span),
        n=61,
    )
    path = path_figure(
        cmap,
        {label: result},
        x0=result.iterates[0],
        truth=evaluation.truth,
        title=f"{label}: path over the cost map (every measured pose in grey)",
        db_floor=-40.0,
        show_measurements=True,
    )
    return {
        name: str(save_figure(fig, out / f"{name}.png", formats=("png",), dpi=110)[0])
        for name, fig in (("convergence", conv), ("path", path))
    }
