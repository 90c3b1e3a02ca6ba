"""``echocal import``: a foreign scan file into a position-scan NetCDF file."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from echocal.cli._common import console

_LEN = "mm unless a unit is given"


def _quantity(field: str, text: str | None, kind: str, unit: str) -> float | None:
    from echocal.units import parse_quantity

    return None if text is None else parse_quantity(field, text, kind, unit)


def register(app: typer.Typer) -> None:
    """Add ``echocal import`` to ``app``."""

    @app.command("import")
    def import_command(
        source: Annotated[
            list[Path],
            typer.Argument(
                help="Scan file (.mat .csv .txt .npy .npz .h5 .hdf5 .nde), a folder "
                "or several files (one trace each)."
            ),
        ],
        out: Annotated[
            Path, typer.Option("--out", "-o", help="Position-scan file to write (.nc).")
        ],
        mapping: Annotated[
            Path | None, typer.Option(help="TOML mapping of what the file does not say.")
        ] = None,
        fs: Annotated[
            str | None, typer.Option("--fs", help="Sampling rate (Hz unless a unit).")
        ] = None,
        start_time: Annotated[
            str | None, typer.Option(help="Time of the first sample (µs unless a unit).")
        ] = None,
        x_start: Annotated[str | None, typer.Option(help=f"First x position ({_LEN}).")] = None,
        x_step: Annotated[str | None, typer.Option(help=f"Scan step along x ({_LEN}).")] = None,
        x_end: Annotated[
            str | None, typer.Option(help=f"Last x position, checked against the step ({_LEN}).")
        ] = None,
        y_start: Annotated[str | None, typer.Option(help=f"First y position ({_LEN}).")] = None,
        y_step: Annotated[str | None, typer.Option(help=f"Index step along y ({_LEN}).")] = None,
        y_end: Annotated[str | None, typer.Option(help=f"Last y position ({_LEN}).")] = None,
        sound_speed: Annotated[
            str | None, typer.Option(help="Coupling medium's speed (m/s unless a unit).")
        ] = None,
        probe_z: Annotated[str | None, typer.Option(help=f"Probe height ({_LEN}).")] = None,
        scale: Annotated[
            float | None, typer.Option(help="Amplitude per ADC code (CF scale_factor).")
        ] = None,
        dataset: Annotated[
            str | None, typer.Option(help="HDF5 dataset, MATLAB/npz variable or NDE group id.")
        ] = None,
        axes: Annotated[
            str | None, typer.Option(help="Meaning of the array's axes, e.g. y,x,time.")
        ] = None,
        layout: Annotated[
            str | None, typer.Option(help="CSV/NumPy matrix: columns (one trace each) or rows.")
        ] = None,
        time: Annotated[
            str | None, typer.Option("--time", help="Name (or number) of the time column/variable.")
        ] = None,
        overwrite: Annotated[bool, typer.Option(help="Replace an existing OUT.")] = False,
        as_json: Annotated[bool, typer.Option("--json", help="Print a JSON summary.")] = False,
    ) -> None:
        """Import a scan from MATLAB, CSV, NumPy, HDF5 or NDE files into echocal's
        position-scan NetCDF file; say what the file does not (rate, steps, speed)."""
        from echocal.cli._common import check_out_file, write_json
        from echocal.errors import DataFileError
        from echocal.positionscan import ScanFacts, import_scan, load_facts
        from echocal.provenance import start

        opened = start("import", {"source": [str(s) for s in source]})
        check_out_file(out, suffix=".nc", what="a NetCDF position-scan file")
        if out.exists() and not overwrite:
            raise DataFileError(f"{out} exists; choose another path or pass --overwrite")
        facts = load_facts(mapping) if mapping is not None else ScanFacts()
        facts = facts.merged(
            sampling_rate=_quantity("--fs", fs, "frequency", "Hz"),
            start_time=_quantity("--start-time", start_time, "time", "us"),
            x_start=_quantity("--x-start", x_start, "length", "mm"),
            x_step=_quantity("--x-step", x_step, "length", "mm"),
            x_end=_quantity("--x-end", x_end, "length", "mm"),
            y_start=_quantity("--y-start", y_start, "length", "mm"),
            y_step=_quantity("--y-step", y_step, "length", "mm"),
            y_end=_quantity("--y-end", y_end, "length", "mm"),
            sound_speed=_quantity("--sound-speed", sound_speed, "speed", "m/s"),
            probe_z=_quantity("--probe-z", probe_z, "length", "mm"),
            scale_factor=scale,
            dataset=dataset,
            axes=axes,
            layout=layout,
            time=time,
        )
        scan = import_scan(source[0] if len(source) == 1 else source, facts)
        scan.dataset.attrs["provenance"] = opened.finish_json()
        scan.save(out)
        summary: dict[str, Any] = {
            "out": str(out),
            "format": scan.dataset.attrs["source_format"],
            "shape": dict(scan.dataset["samples"].sizes),
            "sampling_rate_hz": scan.fs,
            "start_time_s": scan.start_time,
            "dtype": str(scan.raw.dtype),
        }
        if as_json:
            write_json(summary)
            return
        sizes = " × ".join(f"{n} {d}" for d, n in summary["shape"].items())
        console.print(
            f"{out}: {sizes} ({summary['format']}, {scan.fs / 1e6:g} MHz, {summary['dtype']})",
            soft_wrap=True,
            highlight=False,
        )
