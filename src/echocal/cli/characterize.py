"""``echocal characterize``: a probe's beam axis, squint, centre frequency and bandwidth."""

from __future__ import annotations

from contextlib import ExitStack
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import numpy as np
import typer

from echocal.cli._common import output, parse_position, write_json
from echocal.cli._rig_option import RIG_HELP
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup
from echocal.errors import EchocalValueError
from echocal.units import parse_quantity

if TYPE_CHECKING:
    from echocal.measurement.base import MeasurementSource
    from echocal.measurement.virtual import VirtualSetup


_OWN_FILES = ("characterize.json", "characterize.png", "characterize.svg")
"""What ``--out`` holds after a run (removed first with --overwrite)."""


def _tilts(text: str) -> np.ndarray:
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 2 or not np.all(np.isfinite(values)):
        raise EchocalValueError(f"--reflector-tilts must be TX,TY in degrees; got {text!r}")
    return np.array(values)


def _lengths(option: str, text: str | None) -> np.ndarray:
    """Comma-separated lengths (mm unless a unit is given) [m]; none when not given."""
    if text is None:
        return np.zeros(0)
    parts = [p.strip() for p in text.split(",") if p.strip()]
    if not parts:
        raise EchocalValueError(f"{option} must be one or more lengths, e.g. 40,50,60 (mm)")
    return np.array([parse_quantity(option, p, "length", "mm") for p in parts])


def _default_target(virtual: VirtualSetup) -> np.ndarray:
    """The top of the point setup's first flaw (a pore's top, a hole's axis)."""
    interior = virtual.interior
    if interior is None or not interior.flaws:
        raise EchocalValueError(
            "--target: the point setup has no flaw to scan; give X,Y,Z of the point target"
        )
    flaw = interior.flaws[0]
    top = 0.5 * flaw.diameter if flaw.kind == "pore" else 0.0
    return np.asarray(flaw.position, float) + np.array([0.0, 0.0, top])


def _surface_normal_tilts(virtual: VirtualSetup, where: np.ndarray) -> np.ndarray:
    """Gimbal tilts [deg] of the specimen's surface normal where the beam meets it at
    normal incidence from ``where`` [m] (the exact normal of the surface hit)."""
    from echocal.geometry import normal_to_tilt, tilt_normal
    from echocal.raytrace import cast

    best = virtual.normal_incidence_directions(where)[0]
    direction = -tilt_normal(*best)[None, :]
    hits = cast(virtual.specimen, where[None, :], direction)
    normal = np.asarray(hits.normal[0], float)
    normal = normal if normal @ direction[0] < 0 else -normal
    return np.array([float(v) for v in normal_to_tilt(normal)])


def register(app: typer.Typer) -> None:
    """Add ``echocal characterize`` to ``app``."""

    @app.command("characterize")
    def characterize(
        setup: Annotated[str, typer.Option(help=SETUP_HELP)] = "immersion-5mhz-ray",
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = None,
        snr: Annotated[str | None, typer.Option(help=SNR_HELP)] = None,
        seed: Annotated[int | None, typer.Option(help="Noise seed.")] = None,
        position: Annotated[
            str | None,
            typer.Option(
                help="X,Y,Z of the probe (mm unless a unit is given); default: "
                "the setup's reference position."
            ),
        ] = None,
        reflector_tilts: Annotated[
            str | None,
            typer.Option(
                help="TX,TY [deg]: the flat reflector's normal as gimbal tilts (the "
                "mechanical axis); default: the specimen's normal below the probe."
            ),
        ] = None,
        span: Annotated[float, typer.Option(help="Coarse grid's half-width [deg].")] = 3.0,
        coarse_points: Annotated[int, typer.Option(help="Coarse grid points per side.")] = 13,
        fine_points: Annotated[int, typer.Option(help="Fine grid points per side.")] = 11,
        repeats: Annotated[int, typer.Option(help="A-scans averaged per tilt.")] = 1,
        averages: Annotated[int, typer.Option(help="A-scans averaged for the spectrum.")] = 16,
        rig: Annotated[Path | None, typer.Option(help=RIG_HELP)] = None,
        point_setup: Annotated[
            str | None,
            typer.Option(
                help="Setup (same probe) with a point target (a ball; a pore in a part of "
                "water's impedance) for the beam widths and the focal distance."
            ),
        ] = None,
        target: Annotated[
            str | None,
            typer.Option(
                help="X,Y,Z of the point target (mm unless a unit is given); default: the "
                "top of the point setup's first flaw."
            ),
        ] = None,
        distances: Annotated[
            str | None,
            typer.Option(help="Distances probe to target for the beam widths, e.g. 40,50,60 (mm)."),
        ] = None,
        half_span: Annotated[
            str, typer.Option(help="Each lateral line's half-length (mm unless a unit is given).")
        ] = "10",
        line_points: Annotated[int, typer.Option(help="Points per lateral line.")] = 41,
        focus_distances: Annotated[
            str | None,
            typer.Option(help="Distances of the on-axis scan for the focal distance (mm)."),
        ] = None,
        out: Annotated[
            Path | None, typer.Option(help="Folder for characterize.json and characterize.png.")
        ] = None,
        overwrite: Annotated[
            bool, typer.Option("--overwrite", help="Replace the files of a run in --out.")
        ] = False,
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the result as one JSON object.")
        ] = False,
    ) -> None:
        """Measure the probe's beam axis and squint over a flat reflector, then the centre
        frequency and −6 dB bandwidth of the echo at that axis; with --point-setup, the −6
        dB beam widths at --distances and the focal distance over a point target (EN
        12668-2 style).  With --rig, on a rig: --position is required, the reflector is
        level unless --reflector-tilts says otherwise, and the point target (--target) is
        on the same rig."""
        from echocal.characterize import AxisScan, characterize_probe
        from echocal.io import check_out_dir, refuse_existing_output

        if out is not None:  # refused before anything is measured
            refuse_existing_output(out, overwrite=overwrite)
        span_m = parse_quantity("--half-span", half_span, "length", "mm")
        dist = np.zeros(0) if distances is None else _lengths("--distances", distances)
        focal = (
            np.zeros(0)
            if focus_distances is None
            else _lengths("--focus-distances", focus_distances)
        )
        target_at = None if target is None else parse_position(target, "--target")
        with ExitStack() as stack:
            if rig is not None:
                from echocal.cli._rig_option import (
                    open_rig,
                    refuse_simulation_options,
                    require_position,
                )

                refuse_simulation_options(
                    specimen=specimen, snr=snr, seed=seed, point_setup=point_setup
                )
                where = parse_position(require_position(position, "--rig"))
                reflector = np.zeros(2) if reflector_tilts is None else _tilts(reflector_tilts)
                if target_at is None and (dist.size or focal.size):
                    raise EchocalValueError(
                        "--target X,Y,Z of the point target is required with --rig for "
                        "--distances and --focus-distances"
                    )
                source: MeasurementSource = stack.enter_context(open_rig(rig))
                points: MeasurementSource | None = source
            else:
                virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
                source, points = virtual, None
                where = (
                    np.asarray(virtual.reference_position, float)
                    if position is None
                    else parse_position(position)
                )
                reflector = (
                    _surface_normal_tilts(virtual, where)
                    if reflector_tilts is None
                    else _tilts(reflector_tilts)
                )
                if point_setup is None and (dist.size or focal.size or target is not None):
                    raise EchocalValueError(
                        "--point-setup: the beam widths and the focal distance need a setup "
                        "with a point target (or --rig)"
                    )
                if point_setup is not None:
                    points = resolve_setup(point_setup, snr=snr, seed=seed)
                    if target_at is None:
                        target_at = _default_target(points)
                    if dist.size == 0 and focal.size == 0:
                        raise EchocalValueError(
                            "--distances: give the distances of the beam widths (or "
                            "--focus-distances)"
                        )
            result = characterize_probe(
                source,
                where,
                axis_scan=AxisScan(
                    reflector_tilts_deg=reflector,
                    span_deg=span,
                    coarse_points=coarse_points,
                    fine_points=fine_points,
                ),
                repeats=repeats,
                n_ascans=averages,
                point_source=points,
                target=target_at,
                distances=dist,
                half_span=span_m,
                line_points=line_points,
                focus_distances=focal,
            )
        data = result.to_dict()
        if out is not None:
            from echocal.plots import save_figure
            from echocal.plots.characterize import plot_characterization

            check_out_dir(out, overwrite=overwrite, own_files=_OWN_FILES)
            write_json(data, out / "characterize.json")
            files = save_figure(plot_characterization(result), out / "characterize.png")
            data["files"] = [str(out / "characterize.json"), *map(str, files)]
        if json_output:
            write_json(data)
            return
        axis, spec = result.axis, result.spectrum
        output.print(f"{result.source}: {result.measurements} A-scans")
        (tx, ty), (etx, ety) = axis.tilts_deg, axis.tilts_sigma_deg
        (sx, sy), (esx, esy) = axis.squint_deg, axis.squint_sigma_deg
        rx, ry = axis.reflector_tilts_deg
        output.print(f"  beam axis at tilts ({tx:.4f} ± {etx:.4f}, {ty:.4f} ± {ety:.4f}) deg")
        output.print(
            f"  squint ({sx:.4f} ± {esx:.4f}, {sy:.4f} ± {esy:.4f}) deg against the "
            f"reflector normal ({rx:g}, {ry:g})"
        )
        output.print(
            f"  centre frequency {spec.center_hz / 1e6:.4f} ± {spec.center_sigma_hz / 1e6:.4f}"
            f" MHz (peak {spec.peak_hz / 1e6:.4f} MHz)"
        )
        output.print(
            f"  -6 dB bandwidth {spec.bandwidth_hz / 1e6:.4f} ± "
            f"{spec.bandwidth_sigma_hz / 1e6:.4f} MHz ({100 * spec.relative_bandwidth:.1f} %), "
            f"{spec.lower_hz / 1e6:.4f} to {spec.upper_hz / 1e6:.4f} MHz"
        )
        if result.profile is not None:
            profile = result.profile
            for d, widths, sigmas in zip(
                profile.distances, profile.width, profile.width_sigma, strict=True
            ):
                shown = ", ".join(
                    f"{name}' {1e3 * w:.3f} ± {1e3 * e:.3f} mm"
                    for name, w, e in zip(profile.axes, widths, sigmas, strict=True)
                )
                output.print(f"  -6 dB beam width at {1e3 * d:g} mm: {shown}")
        if result.focus is not None:
            f, e = result.focus.focal_distance, result.focus.focal_sigma
            shown = "no maximum inside the scan" if not np.isfinite(f) else f"{1e3 * f:.2f} mm"
            if np.isfinite(e):
                shown += f" ± {1e3 * e:.2f} mm"
            output.print(f"  focal distance: {shown}")
        if out is not None:
            output.print(f"  wrote {', '.join(data['files'])}")  # type: ignore[arg-type]
