"""``echocal scan``: map a specimen's surface on an x–y raster (normals + distances).

A thin layer over :func:`echocal.scanning.scan_surface`: writes ``scan.nc`` and the
figures into ``--out``; resumable (an interrupted scan keeps its finished points in
``scan.nc.partial/`` and the same command continues).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from echocal.cli._gate_option import GATE_HELP, gate_for_setup, gate_for_source
from echocal.cli._rig_option import RIG_HELP
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP

GRID_HELP = (
    "X0:X1:DX,Y0:Y1:DY in mm unless a unit is given, e.g. -10:10:2,-10:10:2 or -1cm:1cm:2mm,0:0:1"
)


def parse_grid(text: str) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Parse ``"X0:X1:DX,Y0:Y1:DY"`` (lengths in mm unless a unit is given) into metres."""
    from echocal.errors import EchocalValueError
    from echocal.units import parse_length

    axes = [a.strip() for a in text.split(",")]
    usage = f"--grid takes {GRID_HELP}; got {text!r}"
    if len(axes) != 2 or any(len(a.split(":")) != 3 for a in axes):
        raise typer.BadParameter(usage)
    out = []
    for name, axis in zip("xy", axes, strict=True):
        try:
            first, last, step = (parse_length(f"--grid {name}", v.strip()) for v in axis.split(":"))
        except EchocalValueError as exc:
            raise typer.BadParameter(f"{exc}; {usage}") from None
        out.append((first, last, step))
    return out[0], out[1]


def _say(text: str) -> None:
    from echocal.cli._common import console

    console.print(text, soft_wrap=True, highlight=False)


def _seed_of(source) -> int:
    """The effective seed of a source from ``resolve_setup`` (its ``rng``; 0 if none)."""
    import numpy as np

    rng = getattr(source, "rng", None)
    return int(rng) if isinstance(rng, int | np.integer) and not isinstance(rng, bool) else 0


def _fmt(value: float | None, scale: float, unit: str, digits: int = 3) -> str:
    return "n/a" if value is None else f"{value * scale:.{digits}g} {unit}"


def register(app: typer.Typer) -> None:
    """Add ``scan`` to ``app``."""

    @app.command("scan")
    def scan_command(
        setup: str | None = typer.Option(
            None,
            "--setup",
            help=SETUP_HELP + " Required unless --rig; with --rig it gives the pulse (the "
            "matched filter's template) and the sound speed (default: the rig file's setup).",
        ),
        rig: Path | None = typer.Option(None, "--rig", help=RIG_HELP),
        grid: str = typer.Option(..., "--grid", help=f"Raster: {GRID_HELP}."),
        out: Path = typer.Option(..., "--out", help="Output folder (scan.nc + figures)."),
        specimen: str | None = typer.Option(None, "--specimen", help=SPECIMEN_HELP),
        z: str = typer.Option("25", "--z", help="Probe stand-off height, mm unless a unit."),
        method: str = typer.Option("auto", "--method", help="Calibration method per point."),
        budget_per_point: int = typer.Option(
            80,
            "--budget-per-point",
            min=1,
            help="Measurement cap per point: at least one iteration of the method plus the "
            "2 time-of-flight A-scans (auto: 9, grid: 23).",
        ),
        cold: bool = typer.Option(
            False, "--cold", help="Also run a cold-start scan (no warm starts) to compare."
        ),
        snr: str | None = typer.Option(None, "--snr", help=SNR_HELP),
        gate: str | None = typer.Option(
            None,
            "--gate",
            help=GATE_HELP + "  Each point's orientation is calibrated inside it; the "
            "height is the strongest echo's time of flight.",
        ),
        seed: int | None = typer.Option(
            None,
            "--seed",
            min=0,
            help="Noise and calibration seed (default: the setup file's seed, else 0).",
        ),
        longitudinal_speed: float | None = typer.Option(
            None,
            "--longitudinal-speed",
            help="The part's longitudinal sound speed c_L [m/s]: also map the wall thickness "
            "c_L·(t_back − t_front)/2 at every point (back echo: in --gate when it is not the "
            "front wall, else the strongest after the front wall). Default: the setup's "
            "part material when the setup gives a plate thickness; otherwise no thickness map.",
        ),
        overwrite: bool = typer.Option(
            False, "--overwrite", help="Replace a finished scan in --out made with other settings."
        ),
        figures: bool = typer.Option(True, "--figures/--no-figures", help="Save figures."),
        progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar."),
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
        scheduler: str | None = typer.Option(
            None,
            "--scheduler",
            help="Dask scheduler address tcp://HOST:PORT: measure the points on its "
            "cluster (a simulated setup; the result equals a local scan's, bit for bit).",
        ),
    ) -> None:
        """Scan a specimen: surface normal and distance at every raster point.

        Ctrl-C keeps the finished points; the same command again resumes. A finished
        scan in --out with the same settings is reported, not measured again; one with
        other settings is refused unless --overwrite. Settings that would make every
        point fail (a height outside the positioner's limits, a budget below what the
        method needs) are refused before anything is written.
        """
        from contextlib import ExitStack

        from echocal.cli._rig_option import open_rig, refuse_simulation_options, rig_setup
        from echocal.cli._setup_option import resolve_setup
        from echocal.errors import EchocalValueError
        from echocal.provenance import start
        from echocal.scanning import ScanGrid, check_scan
        from echocal.setup_digest import setup_digest
        from echocal.units import parse_length

        opened = start(
            "scan", {"setup": setup, "grid": grid, "z": z, "method": method, "gate": gate}
        )
        gx, gy = parse_grid(grid)
        scan_grid = ScanGrid.regular(x=gx, y=gy, z=parse_length("--z", z))
        if scheduler is not None:
            from echocal.experiments.execution import _check_scheduler

            _check_scheduler(scheduler)
            if rig is not None:
                raise EchocalValueError(
                    "--scheduler: a rig is measured where it stands, not on a cluster; "
                    "drop --scheduler or --rig"
                )
        if rig is not None:
            refuse_simulation_options(specimen=specimen, snr=snr)
            setup = rig_setup(setup, rig, "--rig")
        elif setup is None:
            raise EchocalValueError(
                "--setup NAME|FILE is required (a simulated setup), or --rig FILE (a rig)"
            )
        base = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
        # one effective seed for the noise and the calibration: --seed, else the setup's
        effective = seed if seed is not None else _seed_of(base)
        chosen = (
            gate_for_source(gate, pulse=base.pulse, setup=base)
            if rig is not None
            else gate_for_setup(gate, base)
        )
        with ExitStack() as stack:
            if rig is not None:  # the setup gives only the pulse and the sound speed
                source: Any = stack.enter_context(open_rig(rig))
                extra: dict[str, Any] = {"pulse": base.pulse, "sound_speed": base.sound_speed}
                metadata = {"setup": setup, "seed": effective, "rig": source.description}
            else:
                source, extra = base, {}
                metadata = {"setup": setup, "specimen": base.specimen.name, "seed": effective}
            if scheduler is not None:
                from echocal.experiments.execution import _connect

                extra["client"] = stack.enter_context(_connect(scheduler))
                metadata["scheduler"] = scheduler

            metadata["provenance"] = opened.finish(  # finished when scan.nc is written
                setup=setup_digest(setup),
                source=(
                    {"kind": "rig", "file": str(rig), "identification": source.description}
                    if rig is not None
                    else {"kind": "simulator", "specimen": specimen, "snr_db": snr}
                ),
                seed=effective,
                gate=None if chosen is None else chosen.describe(),
                method={"name": method, "budget_per_point": budget_per_point, "z_m": scan_grid.z},
            )
            # refused before the output folder exists; scan_surface is told, not re-run
            prechecked = check_scan(
                source,
                scan_grid,
                method=method,
                budget_per_point=budget_per_point,
                pulse=extra.get("pulse"),
            )
            options = {
                "prechecked": prechecked,
                "method": method,
                "budget_per_point": budget_per_point,
                "rng": effective,
                "progress": progress,
                "metadata": metadata,
                "overwrite": overwrite,
                "gate": chosen,
                "longitudinal_speed": _thickness_speed(longitudinal_speed, base),
                **extra,
            }
            _scan(
                source,
                scan_grid,
                out,
                options,
                cold=cold,
                figures=figures,
                as_json=as_json,
            )


def _thickness_speed(given: float | None, setup: Any) -> float | None:
    """[m/s] c_L for the thickness map: ``--longitudinal-speed``, else the setup part's
    when it has a thickness (a plate), else None (no map).  Refuses a value ≤ 0 or NaN."""
    if given is not None:
        from echocal._validate import positive_float

        return positive_float("--longitudinal-speed", given)
    if getattr(setup, "thickness", None) is None:
        return None
    return getattr(getattr(setup, "material", None), "longitudinal_speed", None)


def _scan(
    base: Any,
    scan_grid: Any,
    out: Path,
    options: dict[str, Any],
    *,
    cold: bool,
    figures: bool,
    as_json: bool,
) -> None:
    """Scan with ``base`` (a simulated setup or a rig) and ``options`` for
    :func:`~echocal.scanning.scan_surface`: warm (and cold) runs, resume (each point's
    noise restarts from its own seed, so a resumed run equals an uninterrupted one),
    figures and the report."""
    from echocal.cli._common import write_json
    from echocal.errors import DataFileError
    from echocal.locking import hold_output_lock
    from echocal.scanning import partial_path, scan_surface

    if out.exists() and not out.is_dir():
        raise DataFileError(f"--out {out}: exists and is not a folder")
    hold_output_lock(out)  # one scan at a time in --out (creates the folder)
    runs = {"warm": True, "cold": False} if cold else {"warm": True}
    results = {}
    for label, warm in runs.items():
        path = out / ("scan.nc" if warm else "scan-cold.nc")
        sidecar = partial_path(path)
        try:
            results[label] = scan_surface(
                base, scan_grid, warm_start=warm, out=path, log=_say, **options
            )
        except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM, SIGHUP
            from echocal._signals import exit_code, how

            _say(
                f"[yellow]{how(exc)}:[/] finished points are saved in {sidecar}; "
                "run the same command again to resume"
            )
            raise typer.Exit(exit_code(exc)) from None
        if figures and warm:
            from echocal.plots.surface import save_surface_figures

            specimen = getattr(base, "specimen", None)  # a rig has none to draw
            save_surface_figures(results[label], out, specimen=specimen)
    summary = results["warm"].summary
    report = {
        "out": str(out),
        "scan": summary,
        "wall_time": results["warm"].dataset.attrs["wall_time"],
    }
    if cold:
        cs = results["cold"].summary
        report["cold"] = cs
        report["cold_over_warm_measurements"] = (
            cs["measurements_total"] / summary["measurements_total"]
            if summary["measurements_total"]
            else None
        )
    if as_json:
        write_json(report)
    ne, he = summary.get("normal_error_deg"), summary.get("height_error_abs_m")
    lines = [
        f"scanned {summary['points']} points: {summary['found']} found, "
        f"{summary['missing']} missing {summary['missing_by_status'] or ''}".rstrip(),
        *(f"  {name}: {message}" for name, message in summary.get("missing_messages", {}).items()),
        f"measurements: {summary['measurements_total']} total, "
        f"{summary['measurements_per_point']:.1f} per point "
        f"(median {summary['measurements_per_point_median']:g})",
    ]
    if ne is not None and he is not None:
        lines.append(
            f"normal error: median {_fmt(ne['median'], 1, 'deg')}, "
            f"p90 {_fmt(ne['p90'], 1, 'deg')}; |height error|: median "
            f"{_fmt(he['median'], 1e3, 'mm')}, p90 {_fmt(he['p90'], 1e3, 'mm')}"
        )
    wall, wall_error = summary.get("thickness_m"), summary.get("thickness_error_abs_m")
    if wall is not None:
        lines.append(
            f"wall thickness: median {_fmt(wall['median'], 1e3, 'mm')}"
            + (
                ""
                if wall_error is None
                else f"; |thickness error|: median {_fmt(wall_error['median'], 1e3, 'mm', 2)}"
                f", max {_fmt(wall_error['max'], 1e3, 'mm', 2)}"
            )
        )
    if cold:
        lines.append(
            f"cold starts: {report['cold']['measurements_total']} measurements, "
            f"{report['cold']['found']} found; warm starts save a factor "
            f"{report['cold_over_warm_measurements']:.2f}"
        )
    lines.append(f"results: {out / 'scan.nc'}" + (" and figures" if figures else ""))
    for line in lines:
        _say(line)
