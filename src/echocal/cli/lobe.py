"""``echocal lobe``: the echo against tilt away from the optimum, beside the piston limits."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from echocal.cli._common import output, parse_position, write_json
from echocal.cli._gate_option import GATE_HELP, gate_for_setup
from echocal.cli._setup_option import SETUP_HELP, SPECIMEN_HELP, resolve_setup
from echocal.errors import EchocalValueError


def register(app: typer.Typer) -> None:
    """Add ``echocal lobe`` to ``app``."""

    @app.command("lobe")
    def lobe(
        setup: Annotated[str, typer.Option(help=SETUP_HELP)] = "immersion-5mhz-wave",
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = None,
        position: Annotated[
            str | None,
            typer.Option(
                help="X,Y,Z of the probe (mm unless a unit is given); default: the setup's "
                "reference position."
            ),
        ] = None,
        model: Annotated[
            str | None,
            typer.Option(help="Echo model: wave, lambertian or specular; default: the setup's."),
        ] = None,
        max_tilt: Annotated[
            float | None,
            typer.Option(help="Largest tilt [deg] either side; default: 3 far-field −6 dB widths."),
        ] = None,
        points: Annotated[int, typer.Option(help="Tilts computed (odd: one at the optimum).")] = 41,
        gate: Annotated[
            str | None,
            typer.Option(
                help=GATE_HELP + "  The envelope peak is then taken inside it, on the "
                "setup's own recording window."
            ),
        ] = None,
        out: Annotated[Path | None, typer.Option(help="Folder for lobe.json and lobe.png.")] = None,
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the result as one JSON object.")
        ] = False,
    ) -> None:
        """The noiseless echo (envelope peak) against tilt away from the optimum.

        Prints the −6 dB half-width; with --out, plots the lobe in dB beside the flat
        piston's analytic deep-near-field and far-field limits.
        """
        from echocal.echo import echo_model_names
        from echocal.lobe import echo_lobe

        virtual = resolve_setup(setup, specimen=specimen, snr="none", seed=0)
        if model is not None:
            if model not in echo_model_names():
                raise EchocalValueError(
                    f"--model: unknown echo model {model!r}; choose one of: "
                    f"{', '.join(echo_model_names())}"
                )
            virtual = dataclasses.replace(virtual, reflection=model)
        where = None if position is None else parse_position(position)
        chosen = gate_for_setup(gate, virtual)
        result = echo_lobe(virtual, where, max_tilt=max_tilt, n_points=points, gate=chosen)
        data = result.to_dict()
        if out is not None:
            from echocal.plots import save_figure
            from echocal.plots.lobe import plot_lobe

            out.mkdir(parents=True, exist_ok=True)
            write_json(data, out / "lobe.json")
            save_figure(plot_lobe(result), out / "lobe.png")
            data["files"] = [str(out / "lobe.json"), str(out / "lobe.png")]
        if json_output:
            write_json(data)
            return
        x, y, z = (1e3 * v for v in result.position)
        output.print(
            f"{result.setup} ({result.model} model) at ({x:g}, {y:g}, {z:g}) mm, "
            f"{1e3 * result.distance_m:.2f} mm from the surface, ka = {result.ka:.1f}"
        )
        width = result.minus6db_deg
        shown = "beyond the range" if not np.isfinite(width) else f"{width:.3f} deg"
        output.print(f"  -6 dB half-width: {shown}")
        output.print(f"  peak amplitude at the optimum: {result.peak_amplitude:.4g}")
        if chosen is not None:
            output.print(f"  inside gate {chosen.label()}")
        if out is not None:
            output.print(f"  wrote {out / 'lobe.json'} and {out / 'lobe.png'}")
