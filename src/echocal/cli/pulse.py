"""``echocal pulse NAME``: plot a pulse, its autocorrelation and spectral density."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from echocal.cli._common import console, write_json
from echocal.errors import EchocalError, EchocalValueError
from echocal.units import (
    format_frequency,
    parse_angle,
    parse_quantity,
    plausible_frequency,
    plausible_sampling_rate,
)

_OPTIONS_BY_PULSE = {
    "gabor": {"fc", "bandwidth", "alpha", "phase"},
    "gaussian": {"fc", "bandwidth", "alpha", "phase"},
    "sinc": {"fc", "bandwidth", "phase", "window", "lobes"},
    "ricker": {"fc"},
    "sampled": {"file"},
}


MAX_DRAWN_SAMPLES = 1_000_000
"""Most samples ``echocal pulse`` draws at ``--fs`` over the pulse's support."""


def _bandwidth(text: str, name: str, fc: float, lobes: int | None) -> float:
    """Gabor: fractional −6 dB bandwidth [%]; sinc: one-sided baseband B [Hz].

    ``60%`` or a bare number is a percentage of fc for gabor; a frequency (``3MHz``) is the
    full −6 dB width for gabor and B for sinc.  For sinc, ``60%`` means 2B = 0.6·fc, and a
    bare number is B in Hz — refused below 1 kHz with a hint (``--bandwidth 60``).
    """
    from echocal.signal.pulses import parse_bandwidth, plausible_bandwidth

    value = parse_bandwidth(name, text, fc, field="--bandwidth")
    try:
        float(text)
        bare = True  # no unit, no %
    except ValueError:
        bare = False
    return plausible_bandwidth(
        name, value, fc, field="--bandwidth", bare=bare, lobes=lobes if lobes else 4
    )


def register(app: typer.Typer) -> None:
    """Add the ``pulse`` command to ``app``."""

    @app.command("pulse")
    def pulse(
        name: str = typer.Argument(..., help="pulse name: gabor, gaussian, sinc, ricker, sampled"),
        out: Path = typer.Option(..., "--out", help="figure file (.png; an .svg is written too)"),
        fc: str | None = typer.Option(None, "--fc", help="centre frequency, e.g. 5MHz"),
        bandwidth: str | None = typer.Option(
            None, "--bandwidth", help="gabor: 60% (−6 dB, of fc) or 3MHz; sinc: B, e.g. 1.5MHz"
        ),
        alpha: float | None = typer.Option(None, "--alpha", help="gabor bandwidth factor [1/s²]"),
        phase: str | None = typer.Option(None, "--phase", help="carrier phase [deg]"),
        window: str | None = typer.Option(None, "--window", help="sinc window, e.g. hann"),
        lobes: int | None = typer.Option(None, "--lobes", help="sinc lobes on each side"),
        fs: str = typer.Option(
            "100MHz", "--fs", help="sampling frequency (samples drawn; rate of a 1-column file)"
        ),
        file: Path | None = typer.Option(None, "--file", help="CSV/NPY file for 'sampled'"),
        svg: bool = typer.Option(True, "--svg/--no-svg", help="also write an SVG"),
        as_json: bool = typer.Option(False, "--json", help="print one JSON object on stdout"),
    ) -> None:
        """Plot pulse, autocorrelation and spectral density side by side; print a summary."""
        try:
            summary = _run(name, out, fc, bandwidth, alpha, phase, window, lobes, fs, file, svg)
        except EchocalError as exc:
            console.print(f"[bold red]error:[/] {exc}", soft_wrap=True)
            raise typer.Exit(2) from None
        if as_json:
            write_json(summary)
        else:
            typer.echo(
                f"{summary['pulse']}: fc {summary['center_frequency_hz'] / 1e6:.4g} MHz, "
                f"−6 dB bandwidth {summary['bandwidth_6db_hz'] / 1e6:.4g} MHz, "
                f"−20 dB duration {summary['duration_20db_s'] * 1e6:.4g} µs, "
                f"support ±{summary['support_s'] * 1e6:.4g} µs, highest frequency "
                f"{summary['highest_frequency_hz'] / 1e6:.4g} MHz → {summary['figure']}"
            )


def _run(
    name: str,
    out: Path,
    fc: str | None,
    bandwidth: str | None,
    alpha: float | None,
    phase: str | None,
    window: str | None,
    lobes: int | None,
    fs_text: str,
    file: Path | None,
    svg: bool,
) -> dict[str, Any]:
    from echocal._validate import lookup
    from echocal.plots import figure_formats, save_figure
    from echocal.plots.pulses import plot_pulse
    from echocal.signal import make_pulse, pulse_names

    allowed = lookup("pulse", name, {n: _OPTIONS_BY_PULSE.get(n, set()) for n in pulse_names()})
    given = {
        "fc": fc,
        "bandwidth": bandwidth,
        "alpha": alpha,
        "phase": phase,
        "window": window,
        "lobes": lobes,
        "file": file,
    }
    for key, value in given.items():
        if value is not None and key not in allowed:
            raise EchocalValueError(
                f"--{key} does not apply to the {name} pulse; it takes "
                + (", ".join(f"--{k}" for k in sorted(allowed)) or "no options")
            )
    formats = figure_formats(out, ("svg",) if svg else ())  # before any work
    fs = parse_quantity("--fs", fs_text, "frequency", "Hz")
    plausible_sampling_rate("--fs", fs)
    params: dict[str, Any] = {}
    if fc is not None:
        params["center_frequency"] = plausible_frequency(
            "--fc", parse_quantity("--fc", fc, "frequency", "Hz")
        )
    if bandwidth is not None:
        from echocal.constants import DEFAULT_CENTER_FREQUENCY

        params["bandwidth"] = _bandwidth(
            bandwidth, name, params.get("center_frequency", DEFAULT_CENTER_FREQUENCY), lobes
        )
    if alpha is not None:
        params["alpha"] = alpha
    if phase is not None:
        params["phase"] = parse_angle("--phase", phase)
    if window is not None:
        params["window"] = window
    if lobes is not None:
        params["lobes"] = lobes
    if name == "sampled":
        if file is None:
            raise EchocalValueError("the sampled pulse needs --file (CSV or NPY)")
        params["file"] = file
        try:  # a (time, amplitude) file brings its own rate: --fs must not override it
            pulse = make_pulse(name, **params)
        except EchocalValueError as exc:
            if not str(exc).startswith("fs is required"):
                raise
            pulse = make_pulse(name, **params, fs=fs)  # amplitudes only: sampled at --fs
    else:
        pulse = make_pulse(name, **params)
    aliased = fs < 2.0 * pulse.highest_frequency
    if aliased:
        console.print(
            f"[yellow]warning:[/] --fs {fs / 1e6:g} MHz is below twice the pulse's highest "
            f"frequency ({pulse.highest_frequency / 1e6:.4g} MHz): sampling would alias",
            soft_wrap=True,
        )
    drawn = 2.0 * pulse.support * fs
    if drawn > MAX_DRAWN_SAMPLES:
        raise EchocalValueError(
            f"--fs {format_frequency(fs)} over the {name} pulse's support "
            f"(±{pulse.support:.3g} s) would draw {drawn:.3g} samples; at most "
            f"{MAX_DRAWN_SAMPLES} — check the pulse's options (--fc, --bandwidth, --alpha; "
            "numbers without a unit are Hz) and --fs"
        )
    fig = plot_pulse(pulse, fs=fs)
    written = save_figure(fig, out, formats=formats)
    summary = pulse.summary()
    summary.update(
        fs_hz=fs, aliased=aliased, figure=str(written[0]), files=[str(p) for p in written]
    )
    return summary
