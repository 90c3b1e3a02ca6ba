"""``echocal characterize``: a probe's beam axis, squint, centre frequency and bandwidth."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from echocal.cli._common import output, write_json
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup
from echocal.errors import EchocalValueError
from echocal.units import parse_quantity


def _position(text: str) -> np.ndarray:
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 3:
        raise EchocalValueError(
            f"--position must be X,Y,Z (mm unless a unit is given); got {text!r}"
        )
    return np.array([parse_quantity("--position", p, "length", "mm") for p in parts])


def _tilts(text: str) -> np.ndarray:
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 2 or not np.all(np.isfinite(values)):
        raise EchocalValueError(f"--reflector-tilts must be TX,TY in degrees; got {text!r}")
    return np.array(values)


def register(app: typer.Typer) -> None:
    """Add ``echocal characterize`` to ``app``."""

    @app.command("characterize")
    def characterize(
        setup: Annotated[str, typer.Option(help=SETUP_HELP)] = "immersion-5mhz-ray",
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = "flat-plate",
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
        out: Annotated[
            Path | None, typer.Option(help="Folder for characterize.json and characterize.png.")
        ] = None,
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the result as one JSON object.")
        ] = False,
    ) -> None:
        """Measure the probe's beam axis and squint over a flat reflector, then the centre
        frequency and −6 dB bandwidth of the echo at that axis (EN 12668-2 style)."""
        from echocal.characterize import characterize_probe

        virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
        where = (
            np.asarray(virtual.reference_position, float)
            if position is None
            else _position(position)
        )
        if reflector_tilts is None:
            normals = virtual.normal_incidence_directions(where)
            if len(normals) == 0:
                raise EchocalValueError(
                    "--reflector-tilts: no surface below the probe; give TX,TY or --position"
                )
            reflector = np.asarray(normals[0], float)
        else:
            reflector = _tilts(reflector_tilts)
        result = characterize_probe(
            virtual,
            where,
            reflector_tilts_deg=reflector,
            span_deg=span,
            coarse_points=coarse_points,
            fine_points=fine_points,
            repeats=repeats,
            n_ascans=averages,
        )
        data = result.to_dict()
        if out is not None:
            from echocal.plots import save_figure
            from echocal.plots.characterize import plot_characterization

            out.mkdir(parents=True, exist_ok=True)
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
        if out is not None:
            output.print(f"  wrote {', '.join(data['files'])}")  # type: ignore[arg-type]
