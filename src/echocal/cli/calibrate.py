"""``echocal calibrate``: find the orientation of maximum echo on a simulated setup, a
recording (``--replay FILE``) or a rig speaking the TCP line protocol (``--instrument
HOST:PORT``).

The three sources go through the same :class:`~echocal.measurement.SourceObjective` and
:func:`~echocal.calibrate.calibrate` call; only a simulated setup knows its true optimum,
so a recording or a rig is reported without a truth or an error.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from echocal.cli._calibrate_common import (
    _check_source_options,
    _parse_position,
    _print_estimate,
    _report,
    _Run,
    calibration_summary,
    prepare_out,
    save_final_ascan,
    save_pngs,
)
from echocal.cli._common import (
    parse_pair,
)
from echocal.cli._gate_option import GATE_HELP, gate_for_setup
from echocal.cli._rig_option import RIG_HELP
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup
from echocal.constants import DEFAULT_SETTLE
from echocal.constants import MAP_POINTS as DEFAULT_MAP_POINTS
from echocal.constants import MAP_SECONDS as DEFAULT_MAP_SECONDS
from echocal.io import refuse_existing_output
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
        gate: Annotated[str | None, typer.Option(help=GATE_HELP)] = None,
        budget: Annotated[int | None, typer.Option(help="Maximum number of measurements.")] = None,
        max_iter: Annotated[int | None, typer.Option(help="Maximum iterations.")] = None,
        settle: Annotated[
            str,
            typer.Option(
                help="TOL,PATIENCE: stop once the last PATIENCE recommendations lie within "
                "TOL degrees of their mean; 'none' runs to the budget or iteration limit."
            ),
        ] = f"{DEFAULT_SETTLE[0]:g},{DEFAULT_SETTLE[1]}",
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
        motion_aware: Annotated[
            bool,
            typer.Option(
                "--motion-aware",
                help="Measure each batch of points along a short path of the positioner "
                "instead of in the order asked; on a simulated bench ([bench] in the setup) "
                "the bench time saved against the plain order is reported.  Simulator only.",
            ),
        ] = False,
        map_points: Annotated[
            int | None,
            typer.Option(
                "--map-points",
                min=0,
                metavar="N",
                help="The most noiseless A-scans the path plot's cost map may simulate.  "
                "Near the optimum the map comes from the setup's lobe profile (computed "
                "once, cached on disk) and costs none; by default nothing is simulated "
                f"beyond its reach (left blank), or {DEFAULT_MAP_POINTS} points where no "
                "profile describes the metric (a gate, a two-humped lobe); 0 draws only "
                f"what the profile gives.  The map also stops after {DEFAULT_MAP_SECONDS:g} "
                "s (the rest blank, with a note).",
            ),
        ] = None,
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
                help="Replace the result and plots in an --out that already holds files; on a "
                "rig, also discard measurements saved there by a run with other settings "
                "(the same settings resume it).",
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
        current_setup: Annotated[
            bool,
            typer.Option(
                "--current-setup",
                help="With --from: rerun on the setup file as it is now, though it changed "
                "since the run (the new result's provenance records the rerun, with both "
                "digests, under 'rerun').",
            ),
        ] = False,
    ) -> None:
        """Calibrate the orientation at one position: on a simulated setup (and compare
        with its true optimum), on a recording (--replay FILE) or on a rig (--instrument
        HOST:PORT), where no truth is known.

        Exit status: 0 when the run converged (its stopping rule fired with evidence:
        "success": true); 1 when no echo was found (the acquisition search failed, every
        measurement failed, or the estimate shows no echo); 2 for bad input or a rig that
        failed mid-run (what was measured before the fault is saved to partial_log.json
        and partial_ascans/ in --out, and the same command resumes); 3 when the run
        ended on its budget or iteration limit, or its convergence was not supported by
        the measurements (an estimate is reported, not a converged one); 4 when the
        estimate lies on the positioner's angle limits.
        The result files are written in every case but 2.
        """
        if from_file is not None:  # the recorded parameters, then this call's output options
            from echocal.cli._rerun import rerun_parameters

            recorded = rerun_parameters(from_file, ctx, current_setup=current_setup)
            own: dict[str, Any] = {
                "out": out, "plots": plots, "map_points": map_points, "json_output": json_output
            }  # fmt: skip
            return calibrate_command(ctx, **recorded, **own, token=token, overwrite=overwrite)
        from echocal.cli._rerun import RERUN_KEY, recorded_parameters
        from echocal.provenance import start

        if current_setup:
            raise typer.BadParameter("only with --from", param_hint="--current-setup")
        given = {k: v for k, v in locals().items() if k in ctx.params}  # the options only
        provenance = start("calibrate", recorded_parameters(given))
        provenance.rerun = ctx.meta.get(RERUN_KEY)
        run = _Run.parse(
            method, budget, max_iter, settle, preset, option, search_radius, final_measure
        )
        from echocal.cli._calibrate_resume import discard_journal, resumable

        on_rig = instrument is not None or rig is not None
        if not (on_rig and resumable(out)):  # a rig's run cut short resumes in its --out
            refuse_existing_output(out, overwrite=overwrite)  # locked once the inputs pass
            if resumable(out):  # --overwrite by a run off the rig: nothing to resume later
                discard_journal(out)
        if replay is not None or on_rig:
            if motion_aware:
                raise typer.BadParameter(
                    "orders the simulator's moves only; drop it with --replay, "
                    "--instrument or --rig",
                    param_hint="--motion-aware",
                )
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
                gate=gate,
                overwrite=overwrite,
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
            gate=gate,
            motion_aware=motion_aware,
            map_points=map_points,
        )


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
    gate: str | None = None,
    motion_aware: bool = False,
    map_points: int | None = None,
) -> None:
    """Calibrate on a simulated setup and judge the estimate against its true optimum."""
    from echocal.evaluation import evaluate_run
    from echocal.measurement.objective import SourceObjective

    virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
    where = _parse_position(position) if position else virtual.reference_position
    chosen = gate_for_setup(gate, virtual)  # refused here, before any measurement
    hold_output_lock(out)  # one writer per --out (made here), from the first measurement on
    objective = SourceObjective(
        virtual, where, parameterization=parameterization, gate=chosen, motion_aware=motion_aware
    )
    # the effective seed: --seed, else the setup file's, else 0
    result = run(objective, parse_pair(x0, "--x0"), virtual.rng)
    evaluation = evaluate_run(virtual, where, result, gate=chosen)
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
            gate=chosen,
        ),
    )
    figures = (
        _save_plots(virtual, where, evaluation, out, chosen, map_points, not json_output)
        if plots
        else {}
    )
    figures.update(save_final_ascan(objective, result, out, plots))
    summary = calibration_summary(
        result,
        out,
        context={
            "setup": virtual.name,
            "seed": virtual.rng if isinstance(virtual.rng, int) else None,
            "source": {
                "kind": "setup",
                "name": virtual.name,
                "description": virtual.description,
            },
            "position_m": [float(v) for v in np.asarray(where, dtype=np.float64)],
            "gate": None if chosen is None else chosen.describe(),
        },
        parameterization=parameterization,
        truth_deg=[float(v) for v in evaluation.truth],
        error_deg=evaluation.error,
        figures=figures,
    )
    _report(
        summary, result, out, json_output, lambda: _print_estimate(result, evaluation, virtual, out)
    )


def _save_plots(
    virtual, where, evaluation, out: Path, gate=None, map_points=None, talk=True
) -> dict[str, str]:
    """The convergence and path figures (the path over a cost map of at most
    ``map_points`` simulated A-scans: :func:`~echocal.plots.path_map.path_cost_map`, with
    a progress bar on a terminal when ``talk``)."""
    import sys

    from echocal.plots.calibration import convergence_figure, path_figure
    from echocal.plots.path_map import path_cost_map

    result = evaluation.result
    label = result.method
    conv = convergence_figure(
        {label: result},
        {label: evaluation.iterate_values / evaluation.optimum_value},
        optimum_value=1.0,
        title=f"{label}: pseudo-energy of the estimate"
        + ("" if gate is None else f" in the {gate.name} gate"),
    )
    points = np.vstack([result.iterates, result.points, evaluation.truth[None, :]])
    span = max(3.0, 1.3 * float(np.max(np.abs(points - evaluation.truth))))
    drawn = path_cost_map(
        virtual,
        where,
        evaluation.truth,
        span,
        parameterization=result.parameterization,
        gate=gate,
        max_points=map_points,
        progress=talk and sys.stderr.isatty(),
    )
    if drawn.stopped and talk:
        typer.echo(
            f"path map: stopped after {drawn.seconds:.0f} s at {drawn.simulated} of "
            f"{drawn.planned} A-scans (the rest is blank; --map-points N sizes the map)",
            err=True,
        )
    empty = not np.any(np.isfinite(drawn.cost_map.values))
    path = path_figure(
        None if empty else drawn.cost_map,
        {label: result},
        x0=result.iterates[0],
        truth=evaluation.truth,
        title=f"{label}: path over the cost map (every measured pose in grey)",
        show_measurements=True,
    )
    if drawn.from_lobe and not drawn.planned and np.any(np.isnan(drawn.cost_map.values)):
        path.axes[0].text(
            0.02, 0.02,
            f"map: the lobe profile, within {drawn.reach:.3g}° of the optimum;\n"
            "beyond, blank (--map-points N simulates N A-scans there)",
            transform=path.axes[0].transAxes, fontsize=7, color="0.2", va="bottom",
            bbox={"fc": "w", "alpha": 0.7, "lw": 0},
        )  # fmt: skip
    return save_pngs({"convergence": conv, "path": path}, out)
