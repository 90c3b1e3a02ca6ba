"""``echocal simulate``: one A-scan at one pose — time of flight, distance, pseudo-energy."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from echocal.cli._common import console, parse_pose, write_json
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup
from echocal.io import atomic_path, atomic_write_text
from echocal.units import parse_quantity


def register(app: typer.Typer) -> None:
    """Add ``echocal simulate`` to ``app``."""

    @app.command("simulate")
    def simulate(
        pose: Annotated[
            str,
            typer.Option(
                help="X,Y,Z[,AZIMUTH,COELEVATION]: lengths in mm unless a unit is given, "
                "angles in degrees."
            ),
        ],
        setup: Annotated[str, typer.Option(help=SETUP_HELP)] = "thesis",
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = None,
        snr: Annotated[str | None, typer.Option(help=SNR_HELP)] = None,
        seed: Annotated[int, typer.Option(help="Noise seed (reproducible A-scans).")] = 0,
        gate: Annotated[
            str | None,
            typer.Option(
                help="START,WIDTH of the gate (µs unless a unit is given): the time of "
                "flight is that of the strongest echo inside it; default: no gate (the "
                "plot shows the pseudo-energy window around the strongest echo)."
            ),
        ] = None,
        out: Annotated[Path, typer.Option(help="Folder for the A-scan file and plot.")] = Path(
            "echocal-out/simulate"
        ),
        fmt: Annotated[
            str, typer.Option("--format", help="A-scan file format: csv or nc (NetCDF).")
        ] = "csv",
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the result as one JSON object.")
        ] = False,
    ) -> None:
        """Simulate one A-scan; print time of flight, distance and pseudo-energy; save it."""
        from echocal.plots import plot_ascan, save_figure
        from echocal.signal import (
            distance,
            energy_db,
            peak_amplitude,
            pseudo_energy,
            time_of_flight,
        )

        if fmt not in ("csv", "nc"):
            raise typer.BadParameter(f"--format must be csv or nc; got {fmt!r}")
        virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
        target = parse_pose(pose)
        scan = virtual.measure(target)
        window, pulse = virtual.window, virtual.pulse
        user_gate = _parse_gate(gate, window) if gate else None
        # as on a flaw detector, a gate restricts the time of flight to the echo inside it
        tof = float(time_of_flight(scan.samples, window, pulse, gate=user_gate))
        chosen = user_gate or _default_gate(tof, pulse.duration, window)
        energy = float(pseudo_energy(scan.samples, window, pulse))
        summary: dict[str, Any] = {
            "setup": virtual.name,
            "pose": {
                "x_m": target.x,
                "y_m": target.y,
                "z_m": target.z,
                "azimuth_deg": target.azimuth,
                "coelevation_deg": target.coelevation,
            },
            "snr_db": virtual.receiver.snr_db,
            "tof_s": tof,
            "distance_m": float(distance(tof, virtual.sound_speed)),
            "pseudo_energy": energy,
            "energy_db": float(energy_db(scan.samples, window, pulse)),
            "peak_amplitude": float(peak_amplitude(scan.samples)),
            "gate_s": [chosen.start, chosen.width],
        }
        out.mkdir(parents=True, exist_ok=True)
        data_path = out / f"ascan.{fmt}"
        _save_ascan(data_path, scan, summary)
        fig = plot_ascan(
            scan.samples, window, pulse=pulse, gate=chosen, title=f"A-scan at {_label(target)}"
        )
        plots = save_figure(fig, out / "ascan.png")
        summary["files"] = {"ascan": str(data_path), "plot": [str(p) for p in plots]}
        if json_output:
            write_json(summary)
            return
        if np.isnan(tof):
            where = "gate" if user_gate else "recording window"
            console.print(f"[yellow]no echo in the {where}[/]")
        console.print(
            f"time of flight  {tof * 1e6:10.4f} µs\n"
            f"distance        {summary['distance_m'] * 1e3:10.4f} mm\n"
            f"pseudo-energy   {energy:10.4g}\n"
            f"saved           {data_path}, {plots[0]}"
        )


def _label(pose: Any) -> str:
    return (
        f"({pose.x * 1e3:.1f}, {pose.y * 1e3:.1f}, {pose.z * 1e3:.1f}) mm, "
        f"az {pose.azimuth:.1f}°, coel {pose.coelevation:.1f}°"
    )


def _parse_gate(text: str, window: Any) -> Any:
    from echocal.errors import EchocalValueError
    from echocal.signal import Gate

    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2:
        raise typer.BadParameter(f"--gate takes START,WIDTH (µs unless a unit); got {text!r}")
    start, width = (
        parse_quantity(f"--gate {n}", v, "time", "us")
        for n, v in zip(("start", "width"), parts, strict=True)
    )
    chosen = Gate(start=start, width=width)
    if not chosen.mask(window).any():
        raise EchocalValueError(
            f"--gate [{start * 1e6:g}, {chosen.end * 1e6:g}] µs holds no sample of the "
            f"recording window [{window.start * 1e6:g}, {window.end * 1e6:g}] µs"
        )
    return chosen


def _default_gate(tof: float, duration: float, window: Any) -> Any:
    from echocal.signal import Gate

    if np.isnan(tof):
        return Gate(start=window.start, width=window.duration)
    return Gate(start=tof - duration, width=2.0 * duration)


def _save_ascan(path: Path, scan: Any, summary: dict[str, Any]) -> None:
    """Write the A-scan as CSV (time_s, amplitude) or NetCDF with units, atomically."""
    if path.suffix == ".csv":
        lines = ["# " + json.dumps(summary), "time_s,amplitude"]
        lines += [f"{t:.9e},{x:.9e}" for t, x in zip(scan.times, scan.samples, strict=True)]
        atomic_write_text(path, "\n".join(lines) + "\n")
        return
    import xarray as xr

    ds = xr.Dataset(
        {"amplitude": ("time", scan.samples, {"units": "a.u.", "long_name": "A-scan"})},
        coords={"time": ("time", scan.times, {"units": "s"})},
        attrs={"fs_hz": scan.fs, "summary": json.dumps(summary), "echocal_format": "ascan/1"},
    )
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")
