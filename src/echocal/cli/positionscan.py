"""Position scans on the command line: ``echocal import`` (a foreign scan file into a
position-scan NetCDF file), ``echocal view`` (B-, C- and A-scans)."""

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
    """Add ``echocal import``, ``view``, ``surface`` and ``record-scan`` to ``app``."""
    _register_import(app)
    register_view(app)


def _register_import(app: typer.Typer) -> None:

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


def _parse_xy(text: str) -> tuple[float, float | None]:
    """``"X,Y"`` or ``"X"`` (mm unless a unit is given) into metres."""
    from echocal.errors import EchocalValueError

    parts = [p.strip() for p in text.split(",")]
    if len(parts) not in (1, 2) or not all(parts):
        raise EchocalValueError(f"--ascan takes X,Y (mm unless a unit is given); got {text!r}")
    x = _quantity("--ascan x", parts[0], "length", "mm")
    y = _quantity("--ascan y", parts[1], "length", "mm") if len(parts) == 2 else None
    assert x is not None
    return x, y


def scan_gate(text: str, scan: Any, *, field: str = "--gate") -> Any:
    """The gate ``text`` names on a position scan: ``front-wall`` (sized by the scan's own
    echo) or ``START,WIDTH`` (µs unless a unit is given)."""
    from echocal.positionscan.tof import echo_template
    from echocal.signal.gates import check_gate, resolve_gate

    gate = resolve_gate(text, pulse=echo_template(scan.samples, scan.fs), field=field)
    check_gate(gate, scan.window, field=field)
    return gate


def register_view(app: typer.Typer) -> None:
    """Add ``echocal view`` to ``app``."""

    @app.command("view")
    def view_command(
        file: Annotated[Path, typer.Argument(help="Position-scan file (.nc).")],
        out: Annotated[
            Path, typer.Option("--out", "-o", help="Figure to write (.png, .svg, .pdf).")
        ],
        bscan: Annotated[bool, typer.Option("--bscan", help="B-scan (the default view).")] = False,
        cscan: Annotated[
            str | None,
            typer.Option(help="C-scan inside this gate: front-wall or START,WIDTH (µs)."),
        ] = None,
        ascan: Annotated[
            str | None, typer.Option(help="A-scan nearest X,Y (mm unless a unit is given).")
        ] = None,
        value: Annotated[str, typer.Option(help="C-scan value: amplitude or tof.")] = "amplitude",
        line: Annotated[
            str | None,
            typer.Option(help="B-scan: the row at this y (mm), or column with --along y."),
        ] = None,
        along: Annotated[str, typer.Option(help="B-scan along x (a row) or y (a column).")] = "x",
        depth: Annotated[
            bool, typer.Option(help="B-scan: water path c₀t/2 instead of time.")
        ] = False,
        gate: Annotated[
            list[str] | None, typer.Option(help="A-scan: a gate to draw (repeatable).")
        ] = None,
        dynamic_range: Annotated[
            float, typer.Option(help="Colour span below the peak [dB].")
        ] = 40.0,
    ) -> None:
        """Show a position scan: B-scan, C-scan (gated amplitude or time of flight) or A-scan."""
        from echocal.errors import EchocalValueError
        from echocal.plots import save_figure
        from echocal.plots.position_scan import ascan_figure, bscan_figure, cscan_figure
        from echocal.positionscan import PositionScan

        chosen = sum([bscan, cscan is not None, ascan is not None])
        if chosen > 1:
            raise EchocalValueError("choose one view: --bscan, --cscan GATE or --ascan X,Y")
        fmt = out.suffix.lower().lstrip(".")
        if fmt not in ("png", "svg", "pdf"):
            raise EchocalValueError(f"--out {out}: give a .png, .svg or .pdf file")
        scan = PositionScan.load(file)
        if cscan is not None:
            if value not in ("amplitude", "tof"):
                raise EchocalValueError(f"--value must be amplitude or tof; got {value!r}")
            fig = cscan_figure(
                scan,
                scan_gate(cscan, scan, field="--cscan"),
                value=value,
                dynamic_range_db=dynamic_range,
            )
        elif ascan is not None:
            x, y = _parse_xy(ascan)
            gates = tuple(scan_gate(g, scan) for g in gate or [])
            fig = ascan_figure(scan, x, y, gates=gates)
        else:
            if along not in ("x", "y"):
                raise EchocalValueError(f"--along must be x or y; got {along!r}")
            if depth and scan.sound_speed is None:
                raise EchocalValueError(
                    "--depth needs the medium's sound speed; import the scan with --sound-speed"
                )
            where = _quantity("--line", line, "length", "mm")
            fig = bscan_figure(
                scan, y=where, along=along, depth=depth, dynamic_range_db=dynamic_range
            )
        written = save_figure(fig, out, formats=(fmt,))
        console.print(f"wrote {', '.join(str(p) for p in written)}", soft_wrap=True)
