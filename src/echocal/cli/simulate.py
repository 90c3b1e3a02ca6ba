"""``echocal simulate``: one A-scan at one pose — time of flight, distance, pseudo-energy."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from echocal.cli._common import output, parse_pose, write_json
from echocal.cli._gate_option import GATE_HELP, gate_for_setup
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup
from echocal.constants import ECHO_THRESHOLD
from echocal.io import (
    atomic_write_text,
    check_out_dir,
    json_ready,
    refuse_existing_output,
)
from echocal.locking import hold_output_lock

SIMULATE_FILES = ("ascan.csv", "ascan.nc", "ascan.png", "ascan.svg")
"""What ``echocal simulate`` writes in --out (removed first with --overwrite)."""


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
        seed: Annotated[
            int | None,
            typer.Option(
                help="Noise seed (reproducible A-scans); default: the setup file's seed, else 0."
            ),
        ] = None,
        gate: Annotated[
            str | None,
            typer.Option(
                help=GATE_HELP + "  Here the echo is also looked for, and its time of "
                "flight taken, inside the gate.  A gate that never sees an echo (in the "
                "noiseless A-scan at the setup's reference pose) is refused before anything "
                "is simulated."
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
        overwrite: Annotated[
            bool,
            typer.Option(
                "--overwrite", help="Replace the A-scan files in an --out that already holds files."
            ),
        ] = False,
    ) -> None:
        """Simulate one A-scan; print time of flight, distance and pseudo-energy; save it.

        With receiver noise, the echo counts as present only when its matched-filter peak
        is significant (g > 4.5, see echocal.signal.detection.EchoDetector); otherwise
        "no echo detected" is printed with g, and the time of flight and distance are
        null in the JSON output ("detected": false).

        The distance is the water path, probe to front surface (c0 times the front-wall
        echo's time of flight over 2); with a --gate on a deeper echo (back wall, flaw) its
        depth in the part, c_L (tau - tau_front)/2, is printed too (JSON depth_m).  See
        docs/gates.md.
        """
        from echocal.plots import plot_ascan, save_figure
        from echocal.signal import distance
        from echocal.signal.gates import gated_metric

        if fmt not in ("csv", "nc"):
            raise typer.BadParameter(f"--format must be csv or nc; got {fmt!r}")
        refuse_existing_output(out, overwrite=overwrite)
        virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
        target = parse_pose(pose)
        user_gate = gate_for_setup(gate, virtual)  # refused here, as calibrate/scan/... do
        scan = virtual.measure(target)
        window, pulse = virtual.window, virtual.pulse
        # as on a flaw detector, a gate restricts the time of flight to the echo inside it
        peak_tof = _gated_tof(scan.samples, window, pulse, user_gate)
        significance = _significance(scan.samples, virtual, user_gate)
        detected = bool(np.isfinite(peak_tof)) and (
            significance is None or significance > ECHO_THRESHOLD
        )
        tof = peak_tof if detected else float("nan")
        surface_tof = _surface_tof(scan.samples, virtual, user_gate, tof)
        energy = float(gated_metric("pseudo-energy", scan.samples, window, pulse, user_gate))
        summary: dict[str, Any] = {
            "setup": virtual.name,
            "seed": virtual.rng if isinstance(virtual.rng, int) else None,
            "pose": {
                "x_m": target.x,
                "y_m": target.y,
                "z_m": target.z,
                "azimuth_deg": target.azimuth,
                "coelevation_deg": target.coelevation,
            },
            "snr_db": virtual.receiver.snr_db,
            "detected": detected,
            "significance": significance,
            "detection_threshold": None if significance is None else ECHO_THRESHOLD,
            "tof_s": tof,
            "distance_m": float(distance(surface_tof, virtual.sound_speed)),
            "pseudo_energy": energy,
            "energy_db": float(gated_metric("energy-db", scan.samples, window, pulse, user_gate)),
            "peak_amplitude": float(
                gated_metric("peak-amplitude", scan.samples, window, pulse, user_gate)
            ),
        }
        depth = _depth(virtual, tof, surface_tof)
        if depth is not None:
            summary["depth_m"] = depth
        summary["echoes"] = _echoes(virtual, target)
        if user_gate is not None:
            start = float(user_gate.starts(scan.samples, window))
            summary["gate_s"] = [start, user_gate.width]  # where it was on this A-scan
            summary["gate"] = user_gate.describe()
        energy_window = _energy_window(scan.samples, window, pulse, user_gate)
        if energy_window is not None:
            summary["energy_window_s"] = list(energy_window)
        hold_output_lock(out)  # one writer per --out
        check_out_dir(out, overwrite=overwrite, own_files=SIMULATE_FILES)
        data_path = out / f"ascan.{fmt}"
        _save_ascan(data_path, scan, summary)
        fig = plot_ascan(
            scan.samples,
            window,
            pulse=pulse,
            echo=bool(detected),  # pure noise: its threshold, but no time-of-flight line
            gates=() if user_gate is None else (user_gate,),
            title=f"A-scan at {_label(target)}",
            noise_sigma=float(virtual.noise_sigma),
            expected_amplitude=float(np.max(np.abs(virtual.reference_samples))),
        )
        if energy_window is not None:
            label = "pseudo-energy window" + ("" if detected else " (noise: no echo)")
            _shade(fig, energy_window, label)
        plots = save_figure(fig, out / "ascan.png")
        summary["files"] = {"ascan": str(data_path), "plot": [str(p) for p in plots]}
        if json_output:
            write_json(summary)
            return
        where = "gate" if user_gate else "recording window"
        if significance is not None and not detected:
            output.print(
                f"[yellow]no echo detected in the {where}[/] (significance g = "
                f"{significance:.2f}, an echo needs g > {ECHO_THRESHOLD:g})"
            )
        elif np.isnan(tof):
            output.print(f"[yellow]no echo in the {where}[/]")
        if len(summary["echoes"]) > 1:
            output.print("echoes (noiseless)")
            for echo in summary["echoes"]:
                output.print(
                    f"  {echo['label']:<16} {_show(echo['tof_s'] * 1e6, 'µs')}   "
                    f"amplitude {echo['amplitude']:.4g}"
                )
        seen = "" if significance is None else f"   (significance g = {significance:.1f})"
        water = "   (water path, from the front-wall echo)" if depth is not None else ""
        inside = (
            "" if depth is None else f"depth           {_show(depth * 1e3, 'mm')}   (in the part)\n"
        )
        output.print(
            f"time of flight  {_show(tof * 1e6, 'µs')}{seen if detected else ''}\n"
            f"distance        {_show(summary['distance_m'] * 1e3, 'mm')}{water}\n"
            f"{inside}"
            f"pseudo-energy   {energy:10.4g}\n"
            f"saved           {data_path}, {plots[0]}"
        )


def _echoes(virtual: Any, pose: Any) -> list[dict[str, Any]]:
    """Every labelled echo at ``pose`` (noiseless): label, tof_s and amplitude."""
    from echocal.wave.interior import echo_list

    if not hasattr(virtual, "labelled_echoes"):  # a replayed or rig source has no labels
        return []
    echoes = echo_list(virtual.labelled_echoes(pose), virtual.window)
    train = getattr(virtual, "interior_echoes", None)
    paths = train.describe() if train is not None else {}  # a layered plate's paths
    return [
        {"label": e.label, "tof_s": e.tof_s, "amplitude": e.amplitude}
        | ({"path": paths[e.label]} if e.label in paths else {})
        for e in echoes
    ]


def _show(value: float, unit: str) -> str:
    return "         —" if np.isnan(value) else f"{value:10.4f} {unit}"


def _significance(samples: np.ndarray, virtual: Any, gate: Any) -> float | None:
    """Matched-filter peak significance g of the A-scan (inside ``gate`` if given) against
    the receiver's noise σ; None for a noiseless receiver (any echo is then certain).

    With a gate the detector's false-alarm law is still that of the whole window, which
    overstates the chance that noise alone made the peak: g is then conservative.
    """
    from echocal.signal.detection import shared_detector
    from echocal.signal.processing import matched_envelope

    sigma = float(virtual.noise_sigma)
    if sigma <= 0.0:
        return None
    window = virtual.window
    detector = shared_detector(virtual.pulse, window.fs, window.n_samples)
    env = matched_envelope(samples, virtual.pulse, window.fs)
    if gate is not None:
        env = np.where(gate.masks(samples, window), env, 0.0)
    return float(detector.significance_of_peak(float(np.max(env)), sigma))


def _energy_window(
    samples: np.ndarray, window: Any, pulse: Any, gate: Any
) -> tuple[float, float] | None:
    """[s] (start, width) of the samples the pseudo-energy summed: two pulse durations
    centred on the strongest matched-filter peak of the trace (of the gated trace with a
    ``gate``, then clipped to the gate where it is on this A-scan, as its samples outside
    are zero); None for an all-zero (gated) trace."""
    from echocal.signal import time_of_flight

    trace = samples if gate is None else gate.apply(samples, window)
    peak = float(time_of_flight(trace, window, pulse))
    if np.isnan(peak):
        return None
    lo, hi = peak - pulse.duration, peak + pulse.duration
    if gate is not None:
        start, end = (float(v) for v in gate.spans(samples, window))
        lo, hi = max(lo, start), min(hi, end)
    return (lo, hi - lo) if hi > lo else None


def _surface_tof(samples: np.ndarray, virtual: Any, gate: Any, tof: float) -> float:
    """[s] the time of flight ``distance_m`` converts with the water's speed c₀: the
    front-wall echo's (the probe-to-surface water path) when the echo in ``gate`` lies more
    than a pulse duration after it (a back wall, a flaw), else ``tof`` itself."""
    from echocal.signal.gates import named_gate

    if gate is None or np.isnan(tof):
        return tof
    pulse = virtual.pulse
    front_wall = named_gate(
        "front-wall",
        pulse=pulse,
        thickness=getattr(virtual, "thickness", None),
        material=getattr(virtual, "material", None),
    )
    front = _gated_tof(samples, virtual.window, pulse, front_wall)
    return front if front < tof - pulse.duration else tof


def _depth(virtual: Any, tof: float, surface_tof: float) -> float | None:
    """[m] depth of the gated echo below the front surface, c_L·(τ − τ_front)/2 (a flaw
    detector's IF-gate sound path; through a layered plate layer by layer, each at its
    c_L), when it lies deeper than the front wall in a plate with an interior; else None."""
    speed = getattr(getattr(virtual, "material", None), "longitudinal_speed", None)
    if getattr(virtual, "thickness", None) is None or speed is None or surface_tof == tof:
        return None
    from echocal.signal.gates import plate_layers

    half_time, depth = (tof - surface_tof) / 2.0, 0.0
    for h, c in plate_layers(virtual):  # a layered plate: through each layer at its speed
        speed = c
        if half_time <= h / c:
            break
        half_time, depth = half_time - h / c, depth + h
    return depth + float(speed) * half_time


def _shade(fig: Any, span: tuple[float, float], label: str) -> None:
    """Shade ``span`` [s] (start, width) on the A-scan figure, with a legend entry."""
    ax = fig.axes[0]
    start, width = span
    from echocal.plots.ascan import _legend

    ax.axvspan(start * 1e6, (start + width) * 1e6, color="C2", alpha=0.15, label=label)
    _legend(ax)


def _label(pose: Any) -> str:
    return (
        f"({pose.x * 1e3:.1f}, {pose.y * 1e3:.1f}, {pose.z * 1e3:.1f}) mm, "
        f"az {pose.azimuth:.1f}°, coel {pose.coelevation:.1f}°"
    )


def _gated_tof(samples: np.ndarray, window: Any, pulse: Any, gate: Any) -> float:
    """[s] time of flight of the strongest echo, inside ``gate`` (where it is on this
    A-scan) if given: the matched-envelope peak of the whole trace, masked."""
    from echocal.signal import Gate, time_of_flight

    if gate is None:
        return float(time_of_flight(samples, window, pulse))
    start = float(gate.starts(samples, window))
    if not np.isfinite(start):
        return float("nan")
    return float(time_of_flight(samples, window, pulse, gate=Gate(start=start, width=gate.width)))


def _save_ascan(path: Path, scan: Any, summary: dict[str, Any]) -> None:
    """Write the A-scan as CSV (time_s, amplitude) or NetCDF (echocal's schema), atomically."""
    if path.suffix == ".csv":
        lines = ["# " + json.dumps(json_ready(summary), allow_nan=False), "time_s,amplitude"]
        lines += [f"{t:.9e},{x:.9e}" for t, x in zip(scan.times, scan.samples, strict=True)]
        atomic_write_text(path, "\n".join(lines) + "\n")
        return
    from echocal.ascan import save_ascan

    save_ascan(scan, path, summary=summary, title="echocal simulated A-scan")
