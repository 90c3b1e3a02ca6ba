"""``echocal record``: measure a grid of orientations with a virtual setup into a replay file.

Resumable: an interrupted recording (Ctrl-C, an error) keeps every saved
measurement in ``<out>.partial/``; running the same command again continues
where it stopped (see :func:`echocal.measurement.record`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from echocal.cli._common import check_out_file
from echocal.cli._gate_option import GATE_HELP, gate_for_setup, gate_for_source
from echocal.cli._rig_option import RIG_HELP
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP

GRID_HELP = "FIRST:LAST:COUNT in degrees, e.g. -10:10:21 (or with units: -0.2rad:0.2rad:5)"


def parse_axis(text: str, option: str) -> tuple[float, float, int]:
    """Parse ``"FIRST:LAST:COUNT"`` (angles in degrees unless a unit is given) or one angle.

    ``"5"`` is the single value 5 deg (``5:5:1``).  Malformed text raises
    :class:`typer.BadParameter` naming ``option``.
    """
    from echocal.errors import EchocalValueError
    from echocal.units import parse_angle

    parts = [p.strip() for p in text.split(":")]
    usage = f"{option} takes {GRID_HELP}; got {text!r}"
    if len(parts) not in (1, 3):
        raise typer.BadParameter(usage)
    try:
        first = parse_angle(f"{option} first", parts[0])
        last = first if len(parts) == 1 else parse_angle(f"{option} last", parts[1])
    except EchocalValueError as exc:
        raise typer.BadParameter(f"{exc}; {usage}") from None
    count = 1 if len(parts) == 1 else _count(parts[2], usage)
    if count == 1 and first != last:
        raise typer.BadParameter(f"{option}: COUNT 1 needs FIRST == LAST; got {text!r}")
    if count > 1 and not last > first:
        raise typer.BadParameter(f"{option}: LAST must be greater than FIRST; got {text!r}")
    return first, last, count


def _count(text: str, usage: str) -> int:
    try:
        count = int(text)
    except ValueError:
        raise typer.BadParameter(usage) from None
    if count < 1:
        raise typer.BadParameter(f"COUNT must be >= 1; {usage}")
    return count


def parse_position(text: str) -> tuple[float, float, float]:
    """Parse ``"X,Y,Z"`` [mm unless a unit is given] into metres."""
    from echocal.cli._common import parse_pose

    if len(text.split(",")) != 3:
        raise typer.BadParameter(
            f"--position takes X,Y,Z (mm unless a unit is given, e.g. 0,0,22 or "
            f"10mm,0,2.2cm); got {text!r}"
        )
    pose = parse_pose(text, "--position")
    return pose.x, pose.y, pose.z


def _say(text: str) -> None:
    """One message line on stderr, not wrapped at the console width."""
    from echocal.cli._common import console

    console.print(text, soft_wrap=True, highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``record`` to ``app``."""

    @app.command("record")
    def record_command(
        setup: str | None = typer.Option(
            None,
            "--setup",
            help=SETUP_HELP + " Required unless --rig; with --rig optional: its pulse is "
            "stored for the replay's matched filter (default: the rig file's setup).",
        ),
        rig: Path | None = typer.Option(None, "--rig", help=RIG_HELP),
        out: Path = typer.Option(..., "--out", help="Replay file to write (.nc)."),
        azimuth: str = typer.Option(..., "--azimuth", help=f"Azimuth grid: {GRID_HELP}"),
        coelevation: str = typer.Option(
            ..., "--coelevation", help=f"Co-elevation grid: {GRID_HELP}"
        ),
        position: list[str] | None = typer.Option(
            None,
            "--position",
            help="X,Y,Z of a recording position, mm unless a unit is given; repeat the "
            "option for several positions. Default: the setup's reference position.",
        ),
        repeats: int = typer.Option(1, "--repeats", min=1, help="A-scans per grid pose."),
        seed: int | None = typer.Option(
            None, "--seed", help="Seed of the receiver noise (default: the setup's)."
        ),
        snr: str | None = typer.Option(None, "--snr", help=SNR_HELP),
        gate: str | None = typer.Option(
            None,
            "--gate",
            help=GATE_HELP + "  The A-scans are recorded whole; the gate is stored with "
            "them and the summary gives each position's best grid pose inside it.",
        ),
        batch_size: int = typer.Option(
            16,
            "--batch-size",
            min=1,
            help="Poses simulated at once (an interruption loses "
            "at most one batch, measured again on resume).",
        ),
        overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing file."),
        progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar."),
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """Record A-scans on an (azimuth, co-elevation) grid into a replay file; resumable.

        Ctrl-C keeps what was measured; the same command again resumes.
        """
        from echocal.cli._rig_option import open_rig, refuse_simulation_options
        from echocal.cli._setup_option import resolve_setup
        from echocal.errors import DataFileError, EchocalValueError
        from echocal.locking import hold_output_lock
        from echocal.measurement.recording import (
            RecordingGrid,
            check_recording_size,
            partial_path,
        )
        from echocal.provenance import start
        from echocal.rigs import load_rig_config
        from echocal.setups import load_setup_config

        opened = start(
            "record",
            {"setup": setup, "azimuth": azimuth, "coelevation": coelevation, "gate": gate},
        )
        check_out_file(out, suffix=".nc", what="a NetCDF replay file")
        az = parse_axis(azimuth, "--azimuth")
        coel = parse_axis(coelevation, "--coelevation")
        positions = [parse_position(p) for p in position or []]
        if rig is not None:
            refuse_simulation_options(snr=snr, seed=seed)
            if setup is None:
                setup = load_rig_config(rig)[0].rig.setup
        elif setup is None:
            raise EchocalValueError(
                "--setup NAME|FILE is required (a simulated setup), or --rig FILE (a rig)"
            )
        config = None if setup is None else load_setup_config(setup)[0]
        if config is not None:
            seed = config.seed if seed is None else seed
        if not positions and config is None:
            raise EchocalValueError(
                "--position X,Y,Z is required with --rig when no setup gives a reference "
                "position (mm unless a unit is given; repeat it for several positions)"
            )
        if not positions:
            assert config is not None
            x, y, z = (float(v) for v in config.positioner.reference_position)
            positions = [(x, y, z)]
        grid = RecordingGrid.regular(azimuth=az, coelevation=coel, positions=positions)
        n_samples = None if rig is not None or config is None else config.window.n_samples
        total = check_recording_size(grid, repeats, n_samples)
        # the gate is refused before any folder is made or anything measured
        simulated: Any = None
        if rig is not None:
            chosen = gate_for_source(gate, pulse=_setup_pulse(setup), setup=setup)
        else:
            assert setup is not None  # refused above
            simulated = resolve_setup(setup, snr=snr, seed=seed)
            chosen = gate_for_setup(gate, simulated)
        hold_output_lock(out, folder=False)  # one recording per file, from here to the end
        sidecar = partial_path(out)
        if out.exists() and not sidecar.exists() and not overwrite:
            raise DataFileError(f"{out} already exists; pass --overwrite to record it again")
        source: Any = simulated if rig is None else open_rig(rig)
        with source:
            _record(
                source,
                grid,
                out,
                total,
                setup,
                seed,
                snr,
                config,
                rig,
                repeats=repeats,
                overwrite=overwrite,
                progress=progress,
                batch_size=batch_size,
                as_json=as_json,
                opened=opened,
                gate=chosen,
            )


def _setup_pulse(setup: str | None) -> Any:
    """The pulse of ``setup`` (a gate's size needs it), or a refusal naming the fix."""
    from echocal.errors import EchocalValueError
    from echocal.setups import load_setup

    if setup is None:
        raise EchocalValueError("--gate needs the pulse: give --setup (the rig's setup)")
    return load_setup(setup).pulse


def _record(
    source,
    grid,
    out: Path,
    total: int,
    setup,
    seed,
    snr,
    config,
    rig,
    *,
    repeats: int,
    overwrite: bool,
    progress: bool,
    batch_size: int,
    as_json: bool,
    opened: Any = None,
    gate: Any = None,
) -> None:
    """Record ``grid`` with ``source`` (a simulated setup or a rig) into ``out``: resume,
    interruption and report (with ``gate``, each position's best grid pose inside it)."""
    from echocal.cli._common import write_json
    from echocal.errors import DataFileError, EchocalError
    from echocal.measurement.recording import (
        discard_partial,
        partial_matches,
        partial_path,
        record,
        saved_count,
    )

    sidecar = partial_path(out)
    stale = partial_matches(out, source, grid, repeats) is False
    if stale and overwrite:
        discard_partial(out)
        _say(
            f"--overwrite: discarded the partial recording {sidecar} (made with another "
            "grid, repeat count or setup); recording from the start"
        )
    elif stale:  # before any "resuming" news: it would not resume
        raise DataFileError(
            f"cannot resume: {sidecar} was recorded with another grid, repeat count or "
            "setup; pass --overwrite to discard it and record from the start, or record "
            "to another --out"
        )
    done = saved_count(out) if sidecar.exists() else 0
    # resumed, record() continues a simulator's noise stream after the saved A-scans: the
    # file equals an uninterrupted recording's
    if done:
        _say(f"resuming {out}: {done} of {total} measurements already saved in {sidecar}")
    try:
        path = record(
            source,
            grid,
            out,
            repeats=repeats,
            progress=progress,
            batch_size=batch_size,
            setup=_provenance(setup, seed, snr, config, rig),
            overwrite=overwrite,
            provenance=(
                None
                if opened is None
                else _origin(opened, source, grid, repeats, setup, seed, snr, rig, gate)
            ),
        )
    except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM, SIGHUP
        from echocal._signals import exit_code, how

        _say(
            f"[yellow]{how(exc)}:[/] {saved_count(out)} of {total} measurements are saved "
            f"in {sidecar}; run the same command again to resume"
        )
        raise typer.Exit(exit_code(exc)) from None
    except EchocalError:
        if sidecar.exists() and saved_count(out):
            _say(
                f"{saved_count(out)} of {total} measurements are saved in {sidecar}; "
                "fix the problem and run the same command again to resume"
            )
        raise
    n_p, n_a, n_c = grid.shape
    n_time = _n_time(path)
    best = None if gate is None else _best_in_gate(path, gate, setup)
    if as_json:
        write_json(
            {
                "path": str(path),
                "n_ascans": total,
                "shape": {
                    "position": n_p,
                    "azimuth": n_a,
                    "coelevation": n_c,
                    "repeat": repeats,
                    "time": n_time,
                },
                "resumed_after": done,
                "source": source.description,
                **({} if gate is None else {"gate": gate.describe(), "best_in_gate": best}),
            }
        )
    _say(
        f"recorded {total} A-scans ({n_p} position(s) x {n_a} azimuths x {n_c} "
        f"co-elevations x {repeats} repeat(s)) of {source.description} to {path}"
        + (f" (resumed after {done})" if done else "")
    )
    for i, b in enumerate(best or []):
        _say(
            f"position {i}: best grid pose in gate {gate.name}: azimuth "
            f"{b['azimuth_deg']:g}°, co-elevation {b['coelevation_deg']:g}° "
            f"(pseudo-energy {b['value']:.4g})"
            if b["azimuth_deg"] is not None
            else f"position {i}: no finite value in gate {gate.name}"
        )


def _best_in_gate(path: Path, gate: Any, setup: str | None) -> list[dict[str, Any]]:
    """Each recorded position's best grid pose and its repeat-averaged pseudo-energy inside
    ``gate`` (read back from the replay file: what a calibration on it would see)."""
    from echocal.cli._measured_pulse import _replay_pulse
    from echocal.cli._replay_grid import RecordingMap
    from echocal.measurement.replay import ReplaySource

    out = []
    with ReplaySource.open(path) as recording:
        pulse, _ = _replay_pulse(recording, setup)
        for index in range(len(recording.positions)):
            maps = RecordingMap(
                recording, index, pulse, "pseudo-energy", "azimuth-coelevation", gate
            )
            found = maps.best is not None
            out.append(
                {
                    "azimuth_deg": float(maps.best[0]) if found else None,
                    "coelevation_deg": float(maps.best[1]) if found else None,
                    "value": maps.peak if found else None,
                }
            )
    return out


def _origin(opened, source, grid, repeats: int, setup, seed, snr, rig, gate=None) -> dict:
    """The recording's provenance record (:mod:`echocal.provenance`), end time set when the
    file is written."""
    from echocal.setup_digest import setup_digest

    origin = (
        {"kind": "rig", "file": str(Path(rig).resolve()), "identification": source.description}
        if rig is not None
        else {"kind": "simulator", "snr_db": snr}
    )
    return opened.finish(
        setup=None if setup is None else setup_digest(setup),
        source=origin,
        seed=seed,
        gate=None if gate is None else gate.describe(),
        method={"name": "record", "grid": grid.to_dict(), "repeats": repeats},
    )


def _n_time(path: Path) -> int:
    """Samples per A-scan of the recording at ``path`` (a rig says only when it measures)."""
    import xarray as xr

    with xr.open_dataset(path, engine="h5netcdf") as data:
        return int(data.sizes["time"])


def _provenance(setup, seed, snr, config, rig) -> dict:
    """What the replay file stores of the source: the setup (its pulse is the matched
    filter's template for a replay) and, on a rig, the rig file."""
    info = {
        # a file as an absolute path: a replay elsewhere still finds a sampled
        # pulse's file relative to it
        "setup": str(Path(setup).resolve()) if setup and Path(setup).is_file() else setup,
        "seed": seed,
        "snr": snr,
        "config": None if config is None else config.model_dump(),
    }
    if rig is not None:
        from echocal.rigs import load_rig_config

        info["rig"] = {
            "file": str(Path(rig).resolve()),
            "config": load_rig_config(rig)[0].model_dump(by_alias=True),
        }
    return info
