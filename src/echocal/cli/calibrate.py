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
from collections.abc import Callable
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
from echocal.cli._rig_option import RIG_HELP
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup
from echocal.io import check_out_dir, refuse_existing_output
from echocal.locking import hold_output_lock


def register(app: typer.Typer) -> None:
    """Add ``echocal calibrate`` to ``app``."""

    @app.command("calibrate")
    def calibrate_command(
        ctx: typer.Context,
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
        rig: Annotated[Path | None, typer.Option("--rig", help=RIG_HELP)] = None,
        timeout: Annotated[
            float | None,
            typer.Option(
                help="[s] With --instrument: how long one reply may take, a move included "
                "(default 2); a transport fault is retried 3 times."
            ),
        ] = None,
        token: Annotated[
            str | None,
            typer.Option(
                envvar="ECHOCAL_INSTRUMENT_TOKEN",
                help="With --instrument: the rig's shared secret (instrument-server --token), "
                "sent first on every connection; also read from $ECHOCAL_INSTRUMENT_TOKEN.",
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
        final_measure: Annotated[
            bool,
            typer.Option(
                help="End by moving to the estimate and measuring it (counted, within "
                "--budget; reported as final_value, and part of the evidence for success). "
                "--no-final-measure leaves the positioner at the last pose the method "
                "probed.  --option final_check=N measures it N times."
            ),
        ] = True,
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the result as one JSON object.")
        ] = False,
        overwrite: Annotated[
            bool,
            typer.Option(
                "--overwrite",
                help="Replace the result and plots in an --out that already holds files.",
            ),
        ] = False,
        from_file: Annotated[
            Path | None,
            typer.Option(
                "--from",
                help="Rerun the calibration recorded in a result.json (its provenance: the "
                "same setup, source, position, seed, method and options); the setup and a "
                "recording must be unchanged (their SHA-256 digests are checked).",
            ),
        ] = None,
    ) -> None:
        """Calibrate the orientation at one position: on a simulated setup (and compare
        with its true optimum), on a recording (--replay FILE) or on a rig (--instrument
        HOST:PORT), where no truth is known.

        Exit status: 0 when the run converged (its stopping rule fired with evidence:
        "success": true); 1 when no echo was found (the acquisition search failed, every
        measurement failed, or the estimate shows no echo); 2 for bad input or a rig that
        failed mid-run (what was measured before the fault is saved to partial_log.json
        in --out); 3 when the run ended on its budget or iteration limit, or its
        convergence was not supported by the measurements (an estimate is reported, not
        a converged one); 4 when the estimate lies on the positioner's angle limits.
        The result files are written in every case but 2.
        """
        if from_file is not None:  # the recorded parameters, then this call's output options
            from echocal.cli._rerun import rerun_parameters

            recorded = rerun_parameters(from_file, ctx)
            own: dict[str, Any] = {"out": out, "plots": plots, "json_output": json_output}
            return calibrate_command(ctx, **recorded, **own, token=token, overwrite=overwrite)
        from echocal.cli._rerun import recorded_parameters
        from echocal.provenance import start

        given = {k: v for k, v in locals().items() if k in ctx.params}  # the options only
        provenance = start("calibrate", recorded_parameters(given))
        run = _Run.parse(
            method, budget, max_iter, settle, preset, option, search_radius, final_measure
        )
        refuse_existing_output(out, overwrite=overwrite)
        hold_output_lock(out)  # one writer per --out, from the first measurement to the last file
        if replay is not None or instrument is not None or rig is not None:
            from echocal.cli._calibrate_measured import (
                _calibrate_measured,
                _check_measured_options,
            )

            _check_measured_options(replay, instrument, snr, specimen, rig)
            _calibrate_measured(
                run,
                replay=replay,
                replay_mode=replay_mode,
                instrument=instrument,
                timeout=timeout,
                token=token,
                setup=setup,
                position=position,
                parameterization=parameterization,
                x0=x0,
                seed=seed,
                out=out,
                plots=plots,
                json_output=json_output,
                rig=rig,
                provenance=provenance,
            )
            return
        _check_source_options(replay, replay_mode, instrument, timeout)
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
            provenance=provenance,
        )


def _check_source_options(
    replay: Path | None, replay_mode: str | None, instrument: str | None, timeout: float | None
) -> None:
    """Refuse ``--replay-mode`` without ``--replay`` and ``--timeout`` without ``--instrument``."""
    from echocal.errors import EchocalValueError

    if replay_mode is not None and replay is None:
        raise EchocalValueError("--replay-mode applies only with --replay FILE")
    if timeout is not None and instrument is None:
        raise EchocalValueError("--timeout applies only with --instrument HOST:PORT")


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
        final_measure: bool = True,
    ) -> _Run:
        """Check --method, --option, --search-radius, --settle and --no-final-measure
        (before any measurement)."""
        from echocal.errors import EchocalValueError

        search = _search_options(method, search_radius)
        extra = parse_options(option, "--option")
        run_keywords = _check_options(method, extra, search)
        if not final_measure:
            if "final_check" in run_keywords:
                raise EchocalValueError(
                    "--no-final-measure and --option final_check=N both set the final "
                    "measurements at the estimate; give one"
                )
            run_keywords["final_check"] = 0
        return cls(
            method, budget, max_iter, _parse_settle(settle), preset, search, extra, run_keywords
        )

    def provenance(
        self,
        opened: Any,
        result: Any,
        *,
        setup: str | None,
        source: dict[str, Any],
        position: Any,
        seed: int | None,
    ) -> dict[str, Any] | None:
        """The provenance record of ``result`` (None without an ``opened`` record): the setup
        and its digest, the source, position [m], seed, method with every option."""
        if opened is None:
            return None
        from echocal.provenance import setup_digest

        return opened.finish(
            setup=None if setup is None else setup_digest(setup),
            source=source,
            position_m=[float(v) for v in position],
            seed=seed,
            method={
                "name": result.method,
                "options": result.options,
                "budget": self.budget,
                "max_iter": self.max_iter,
                "settle": self.settle,
                "preset": self.preset,
                "parameterization": result.parameterization,
                "x0": [float(v) for v in result.iterates[0]],
            },
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
    provenance: Any = None,
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
    prepare_out(out)
    result.save_json(
        out / "result.json",
        provenance=run.provenance(
            provenance,
            result,
            setup=setup,
            source={"kind": "simulator", "specimen": specimen, "snr_db": snr},
            position=where,
            seed=virtual.rng if isinstance(virtual.rng, int) else None,
        ),
    )
    figures = _save_plots(virtual, where, evaluation, out) if plots else {}
    figures.update(save_final_ascan(objective, result, out, plots))
    found = found_echo(result)
    summary = {
        "setup": virtual.name,
        "seed": virtual.rng if isinstance(virtual.rng, int) else None,
        "source": {"kind": "setup", "name": virtual.name, "description": virtual.description},
        "position_m": [float(v) for v in np.asarray(where, dtype=np.float64)],
        "method": result.method,
        "parameterization": parameterization,
        "names": list(result.names),
        "success": result.success,
        "estimate_deg": [float(v) for v in result.x] if found else None,
        "truth_deg": [float(v) for v in evaluation.truth],
        "error_deg": evaluation.error if found else None,
        "n_measurements": result.n_measurements,
        "acquisition_measurements": result.acquisition_measurements,
        "final_value": result.final_value,
        "n_iterations": result.n_iterations,
        "status": result.status,
        "message": result.message,
        "exit_code": exit_code(result),
        "files": {"result": str(out / "result.json"), **figures},
    }
    _report(
        summary, result, out, json_output, lambda: _print_estimate(result, evaluation, virtual, out)
    )


CALIBRATE_FILES = (
    "result.json",
    "convergence.png",
    "path.png",
    "partial_log.json",
    "ascan.nc",
    "ascan.png",
)
"""What ``echocal calibrate`` writes in --out."""


def prepare_out(out: Path) -> None:
    """Make --out ready for a result: create it and remove what an earlier calibration left
    there (the run began only after :func:`~echocal.io.refuse_existing_output` accepted
    --out: empty, or --overwrite given), so no stale plot stays beside the new result."""
    check_out_dir(out, overwrite=True, own_files=CALIBRATE_FILES)


EXIT_NO_ECHO = 1
"""Exit status of a calibration that found no echo (result files written all the same)."""
EXIT_NOT_CONVERGED = 3
"""Exit status of a calibration that returned an estimate without converging."""
EXIT_AT_LIMIT = 4
"""Exit status of a calibration whose estimate lies on the positioner's angle limits."""


def found_echo(result: Any) -> bool:
    """Whether ``result`` has an estimate of anything (its status is not a no-echo one)."""
    from echocal.calibrate.result import NO_ECHO_STATUSES

    return result.status not in NO_ECHO_STATUSES


def exit_code(result: Any) -> int:
    """The exit status of ``echocal calibrate`` for ``result`` (see its ``--help``)."""
    if result.success:
        return 0
    if not found_echo(result):
        return EXIT_NO_ECHO
    return EXIT_AT_LIMIT if result.status == 8 else EXIT_NOT_CONVERGED


def _report(
    summary: dict[str, Any],
    result: Any,
    out: Path,
    json_output: bool,
    print_estimate: Callable[[], None],
) -> None:
    """Print ``summary`` (``--json``), the estimate or the failure; exit with
    :func:`exit_code` (0 only for a converged run)."""
    code = exit_code(result)
    if json_output:
        write_json(summary)
    elif code == EXIT_NO_ECHO:
        _print_failure(result, out)
    else:
        print_estimate()
        if code:
            console.print(
                f"[yellow]warning:[/] not converged (status {result.status}): "
                f"{escape(result.message)}; the estimate is the run's last recommendation"
            )
    if code:
        raise typer.Exit(code=code)


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
    from echocal._validate import capped_float
    from echocal.calibrate import Acquisition, get_method
    from echocal.calibrate.acquisition import _CAP_WHY, MAX_SEARCH_RADIUS
    from echocal.calibrate.auto import AUTO_SEARCH

    radius = capped_float("--search-radius", radius, MAX_SEARCH_RADIUS, _CAP_WHY)
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
    return save_pngs({"convergence": conv, "path": path}, out)


def save_final_ascan(objective: Any, result: Any, out: Path, plots: bool) -> dict[str, str]:
    """Save the A-scan measured at the estimate: ``out/ascan.nc`` (echocal's NetCDF schema,
    see docs/netcdf-schema.md) and, with ``plots``, ``out/ascan.png``.

    It is the driver's final measurement at the estimate (``final_check``, counted in the
    result's measurements) when the run made one; otherwise (``--option final_check=0``,
    or no budget left for it) the estimate is measured once more here, through the
    objective's source (a rig moves there), not counted: the file's summary says which.
    Nothing is measured or written when no echo was found.  Returns name -> path.
    """
    if not found_echo(result):
        return {}
    from echocal.ascan import save_ascan
    from echocal.measurement.objective import ascan_metric
    from echocal.plots import plot_ascan
    from echocal.signal.window import RecordingWindow

    scan = objective.last_scan if result.final_value is not None else None
    counted = scan is not None
    if scan is None:
        scan = objective.source.measure(objective.pose(*result.x))
    value = ascan_metric(scan, objective.metric, objective.pulse, objective.window_length)
    summary = {
        "estimate_deg": [float(v) for v in result.x],
        "names": list(result.names),
        "parameterization": result.parameterization,
        "metric": objective.metric,
        "value": float(value),
        "counted": counted,
        "note": "the run's final measurement at the estimate (in n_measurements)"
        if counted
        else "measured once at the estimate after the run; not in n_measurements",
    }
    files = {
        "ascan": str(
            save_ascan(
                scan,
                out / "ascan.nc",
                summary=summary,
                title="echocal A-scan measured at the calibration's estimate",
            )
        )
    }
    if plots:
        window = RecordingWindow(fs=scan.fs, start=scan.start_time, n_samples=scan.n_samples)
        a, b = result.x
        fig = plot_ascan(
            scan.samples,
            window,
            pulse=objective.pulse,
            title=f"A-scan at the estimate ({result.names[0]} {a:.3f}°, "
            f"{result.names[1]} {b:.3f}°)",
        )
        files["ascan_plot"] = save_pngs({"ascan": fig}, out)["ascan"]
    return files


def save_pngs(figures: dict[str, Any], out: Path) -> dict[str, str]:
    """Write each figure as ``out/<name>.png`` (atomically); return name -> path."""
    from echocal.plots import save_figure

    return {
        name: str(save_figure(fig, out / f"{name}.png", formats=("png",), dpi=110)[0])
        for name, fig in figures.items()
    }
