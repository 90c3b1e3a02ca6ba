"""``echocal record-scan`` (a position scan on the simulator), ``echocal surface`` (a
time-of-flight surface fit of a position scan), ``echocal layers`` (layer thickness) and
``echocal probe`` (the probe from its echo)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from echocal.cli._common import console
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP

AXIS_HELP = "FIRST:LAST:COUNT in mm (or with units, e.g. -5mm:5mm:11), or one position"


def parse_positions(text: str, option: str) -> Any:
    """``"FIRST:LAST:COUNT"`` or ``"X"`` (mm unless a unit is given) → positions [m]."""
    import numpy as np

    from echocal.errors import EchocalValueError
    from echocal.units import parse_quantity

    parts = [p.strip() for p in text.split(":")]
    usage = f"{option} takes {AXIS_HELP}; got {text!r}"
    if len(parts) not in (1, 3):
        raise EchocalValueError(usage)
    first = parse_quantity(f"{option} first", parts[0], "length", "mm")
    if len(parts) == 1:
        return np.array([first])
    last = parse_quantity(f"{option} last", parts[1], "length", "mm")
    try:
        count = int(parts[2])
    except ValueError:
        raise EchocalValueError(usage) from None
    if count < 2 or not last > first:
        raise EchocalValueError(f"{option}: COUNT must be >= 2 and LAST > FIRST; {usage}")
    return np.linspace(first, last, count)


def register(app: typer.Typer) -> None:
    """Add ``echocal record-scan``, ``surface`` and ``layers`` to ``app``."""
    register_layers(app)
    register_probe(app)

    @app.command("record-scan")
    def record_scan_command(
        setup: Annotated[str, typer.Option("--setup", help=SETUP_HELP)],
        x: Annotated[str, typer.Option("--x", help=f"x positions: {AXIS_HELP}.")],
        out: Annotated[Path, typer.Option("--out", "-o", help="Position-scan file (.nc).")],
        y: Annotated[
            str | None, typer.Option("--y", help=f"y positions (a raster): {AXIS_HELP}.")
        ] = None,
        z: Annotated[
            str | None, typer.Option("--z", help="Probe height (mm; default: the setup's).")
        ] = None,
        tilt_x: Annotated[float, typer.Option(help="Fixed gimbal tilt about x [deg].")] = 0.0,
        tilt_y: Annotated[float, typer.Option(help="Fixed gimbal tilt about y [deg].")] = 0.0,
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = None,
        snr: Annotated[str | None, typer.Option("--snr", help=SNR_HELP)] = None,
        seed: Annotated[int | None, typer.Option(help="Seed of the receiver noise.")] = None,
        overwrite: Annotated[bool, typer.Option(help="Replace an existing OUT.")] = False,
    ) -> None:
        """Record a line or raster position scan at a fixed orientation on the simulator
        (the file kind `echocal import` writes, with the setup's zero offset)."""
        from echocal.cli._common import check_out_file
        from echocal.cli._setup_option import resolve_setup
        from echocal.errors import DataFileError
        from echocal.positionscan import simulate_position_scan
        from echocal.provenance import start
        from echocal.units import parse_quantity

        opened = start("record-scan", {"setup": setup, "x": x, "y": y, "z": z, "seed": seed})
        check_out_file(out, suffix=".nc", what="a NetCDF position-scan file")
        if out.exists() and not overwrite:
            raise DataFileError(f"{out} exists; choose another path or pass --overwrite")
        xs = parse_positions(x, "--x")
        ys = None if y is None else parse_positions(y, "--y")
        height = None if z is None else parse_quantity("--z", z, "length", "mm")
        virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
        scan = simulate_position_scan(virtual, x=xs, y=ys, z=height, tilt_x=tilt_x, tilt_y=tilt_y)
        scan.dataset.attrs["provenance"] = opened.finish_json(
            setup={"name": virtual.name}, source={"kind": "simulator"}, seed=virtual.rng
        )
        scan.save(out)
        sizes = " × ".join(f"{n} {d}" for d, n in scan.dataset["samples"].sizes.items())
        console.print(f"{out}: {sizes} ({virtual.description})", soft_wrap=True, highlight=False)

    @app.command("surface")
    def surface_command(
        file: Annotated[Path, typer.Argument(help="Position-scan file (.nc).")],
        shape: Annotated[str, typer.Option(help="plane, sphere or cylinder.")] = "plane",
        gate: Annotated[
            str | None,
            typer.Option(help="Gate of the front-wall echo: front-wall (default) or START,WIDTH."),
        ] = None,
        sound_speed: Annotated[
            str | None, typer.Option(help="Medium's speed (m/s; default: the file's).")
        ] = None,
        zero_offset: Annotated[
            str | None,
            typer.Option(help="Zero offset from a calibration block (µs; default: the file's)."),
        ] = None,
        probe_z: Annotated[
            str | None, typer.Option(help="Probe height (mm; default: the file's, else 0).")
        ] = None,
        out: Annotated[
            Path | None, typer.Option("--out", "-o", help="Residual and TOF maps (.nc).")
        ] = None,
        figure: Annotated[
            Path | None, typer.Option(help="Residual map figure (.png, .svg, .pdf).")
        ] = None,
        as_json: Annotated[bool, typer.Option("--json", help="Print the fit as JSON.")] = False,
    ) -> None:
        """Fit a plane, sphere or cylinder to a scan's front-wall times of flight: tilt,
        distance, radius, the residual map and 1-σ uncertainties."""
        from echocal.cli._common import write_json
        from echocal.cli.positionscan import scan_gate
        from echocal.errors import EchocalValueError
        from echocal.netcdf import write_netcdf
        from echocal.positionscan import PositionScan, fit_surface
        from echocal.provenance import start
        from echocal.units import parse_quantity

        opened = start("surface", {"file": str(file), "shape": shape})
        fmt = None if figure is None else figure.suffix.lower().lstrip(".")
        if fmt is not None and fmt not in ("png", "svg", "pdf"):
            raise EchocalValueError(f"--figure {figure}: give a .png, .svg or .pdf file")
        scan = PositionScan.load(file)
        fit = fit_surface(
            scan,
            shape,
            gate=None if gate is None else scan_gate(gate, scan),
            sound_speed=None
            if sound_speed is None
            else parse_quantity("--sound-speed", sound_speed, "speed", "m/s"),
            zero_offset=None
            if zero_offset is None
            else parse_quantity("--zero-offset", zero_offset, "time", "us"),
            probe_z=None
            if probe_z is None
            else parse_quantity("--probe-z", probe_z, "length", "mm"),
        )
        if out is not None:
            ds = fit.dataset(scan)
            ds.attrs["provenance"] = opened.finish_json()
            write_netcdf(
                ds,
                out,
                fmt="tof-surface/1",
                title=f"echocal time-of-flight {shape} fit of a position scan",
                source=str(file),
            )
        if figure is not None:
            from echocal.plots import save_figure
            from echocal.plots.position_scan import residual_map_figure

            assert fmt is not None
            save_figure(residual_map_figure(scan, fit), figure, formats=(fmt,))
        if as_json:
            write_json(fit.summary())
            return
        _print_fit(fit)


def _print_fit(fit: Any) -> None:
    """The estimates ± 1 σ, one per line, in mm, µm and degrees."""
    lines = [
        f"{fit.shape} fit of {fit.summary()['inliers']} traces "
        f"({fit.summary()['outliers']} outliers), rms {fit.rms * 1e6:.2f} µm"
    ]
    for key, value in fit.parameters.items():
        sigma = fit.sigma.get(key, float("nan"))
        if key.startswith(("tilt", "azimuth", "coelevation", "axis_azimuth", "axis_elevation")):
            lines.append(f"  {key:<15} {value:+.4f} ± {sigma:.4f} deg")
        else:
            lines.append(f"  {key:<15} {value * 1e3:+.4f} ± {sigma * 1e3:.4f} mm")
    if fit.misfit:
        lines.append(
            f"warning: the residuals (rms {fit.rms * 1e6:.2f} µm) are smooth and exceed the "
            f"noise ({fit.noise * 1e6:.2f} µm): the {fit.shape} model does not describe these "
            "echoes and the ± are too small (a probe too wide for the curvature? see "
            "docs/position-scans.md)"
        )
    console.print("\n".join(lines), soft_wrap=True, highlight=False)


def register_layers(app: typer.Typer) -> None:
    """Add ``echocal layers`` to ``app``."""

    @app.command("layers")
    def layers_command(
        file: Annotated[Path, typer.Argument(help="Position-scan file (.nc).")],
        speed: Annotated[
            list[str], typer.Option(help="Speed of each layer, front to back (m/s unless a unit).")
        ],
        gate: Annotated[
            list[str] | None,
            typer.Option(
                help="Gate of each interface, front wall first (front-wall or START,WIDTH µs);"
                " default: the front-wall gate, and for one layer the strongest later echo."
            ),
        ] = None,
        out: Annotated[
            Path | None, typer.Option("--out", "-o", help="Thickness maps (.nc).")
        ] = None,
        as_json: Annotated[
            bool, typer.Option("--json", help="Print the statistics as JSON.")
        ] = False,
    ) -> None:
        """Thickness of each layer under each trace from the interface echoes, as a map
        with its statistics."""
        from echocal.cli._common import write_json
        from echocal.cli.positionscan import scan_gate
        from echocal.netcdf import write_netcdf
        from echocal.positionscan import PositionScan
        from echocal.positionscan.layers import layer_thickness
        from echocal.provenance import start
        from echocal.units import parse_quantity

        opened = start("layers", {"file": str(file), "speed": speed, "gate": gate})
        speeds = [parse_quantity("--speed", s, "speed", "m/s") for s in speed]
        scan = PositionScan.load(file)
        gates = None if not gate else [scan_gate(g, scan) for g in gate]
        result = layer_thickness(scan, speeds, gates=gates)
        if out is not None:
            ds = result.dataset(scan)
            ds.attrs["provenance"] = opened.finish_json()
            write_netcdf(
                ds, out, fmt="layers/1", title="echocal layer thickness map", source=str(file)
            )
        stats = result.statistics()
        if as_json:
            write_json({"layers": stats})
            return
        for s in stats:
            if s["traces"]:
                console.print(
                    f"layer {s['layer']} (c = {s['speed_m_s']:g} m/s): {s['traces']} traces, "
                    f"mean {s['mean'] * 1e3:.4f} mm, std {s['std'] * 1e3:.4f} mm, "
                    f"min {s['min'] * 1e3:.4f}, max {s['max'] * 1e3:.4f} mm",
                    soft_wrap=True,
                    highlight=False,
                )
            else:
                console.print(f"layer {s['layer']}: no trace holds both echoes")


def register_probe(app: typer.Typer) -> None:
    """Add ``echocal probe`` to ``app``."""

    @app.command("probe")
    def probe_command(
        file: Annotated[Path, typer.Argument(help="Position-scan file (.nc).")],
        pulse: Annotated[
            Path | None,
            typer.Option(help="Write the echo as a sampled pulse (.csv) for a setup file."),
        ] = None,
        gate: Annotated[
            str | None, typer.Option(help="Gate of the echo: front-wall (default) or START,WIDTH.")
        ] = None,
        as_json: Annotated[
            bool, typer.Option("--json", help="Print the estimate as JSON.")
        ] = False,
    ) -> None:
        """The probe from its front-wall echo: centre frequency, -6 dB bandwidth, noise
        level and whiteness; optionally its sampled pulse for a setup file."""
        from echocal.cli._common import check_out_file, write_json
        from echocal.cli.positionscan import scan_gate
        from echocal.positionscan import PositionScan
        from echocal.positionscan.probe import probe_from_echo

        if pulse is not None:
            check_out_file(pulse, suffix=".csv", option="--pulse", what="a CSV pulse file")
        scan = PositionScan.load(file)
        est = probe_from_echo(scan, gate=None if gate is None else scan_gate(gate, scan))
        if pulse is not None:
            est.write_pulse(pulse)
        summary = est.summary()
        if as_json:
            write_json(summary)
            return
        lo, hi = est.band
        snr = summary["snr_db"]
        console.print(
            f"centre frequency {est.center_frequency / 1e6:.3f} MHz, -6 dB band "
            f"{lo / 1e6:.3f}-{hi / 1e6:.3f} MHz ({est.bandwidth_percent:.1f} %)\n"
            f"noise sigma {est.noise_sigma:.4g} (echo peak/noise {snr:.1f} dB), spectral "
            f"flatness {est.spectral_flatness:.2f}, Ljung-Box p = {est.whiteness_p_value:.2g}: "
            f"{'white' if est.white else 'NOT white (coloured noise)'}"
            + (
                f'\npulse written to {pulse} ([pulse] name = "sampled", file = ...)'
                if pulse
                else ""
            ),
            soft_wrap=True,
            highlight=False,
            markup=False,
        )
