"""``echocal rig``: try a rig file's wiring (``rig check``) and list the driver presets."""

from __future__ import annotations

from pathlib import Path

import typer


def _say(text: str) -> None:
    from echocal.cli._common import output

    output.print(text, soft_wrap=True, highlight=False, markup=False)


def register(app: typer.Typer) -> None:
    """Add the ``rig`` command group to ``app``."""
    rig_app = typer.Typer(
        help="Rigs: a positioner and a receiver described in a rig file (docs/rigs.md).",
        no_args_is_help=True,
    )
    app.add_typer(rig_app, name="rig")

    @rig_app.command("check")
    def check(
        file: Path = typer.Argument(..., help="The rig file ([rig] TOML)."),
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """Validate the rig file, connect, print each instrument's identification and the
        axis limits, and take one A-scan where the positioner stands (nothing moves).

        A rig file with a problem (a missing axis, an unknown preset) is refused before
        anything is connected.
        """
        from echocal.cli._common import write_json
        from echocal.rigs import check_rig

        report = check_rig(file)
        if as_json:
            write_json(report.as_dict())
            return
        limits = report.limits
        scan = report.ascan
        pose = report.pose
        _say(f"rig {report.name} ({file})")
        _say(f"  positioner  {report.positioner}")
        _say(f"  receiver    {report.receiver}")
        _say("  axis limits")
        for axis in ("x", "y", "z"):
            low, high = getattr(limits, axis)
            _say(f"    {axis:<12}[{low * 1e3:g}, {high * 1e3:g}] mm")
        for axis in ("azimuth", "coelevation"):
            low, high = getattr(limits, axis)
            _say(f"    {axis:<12}[{low:g}, {high:g}] deg")
        _say(
            f"  position    x={pose.x * 1e3:g} mm, y={pose.y * 1e3:g} mm, z={pose.z * 1e3:g} mm, "
            f"azimuth={pose.azimuth:g} deg, co-elevation={pose.coelevation:g} deg"
        )
        peak = float(abs(scan.samples).max())
        _say(
            f"  one A-scan  {scan.n_samples} samples at {scan.fs / 1e6:g} MHz from "
            f"{scan.start_time * 1e6:g} us, peak |amplitude| {peak:.4g}"
            + ("" if scan.is_finite else " (holds NaN or inf samples!)")
        )
        _say("ok: the rig answers; calibrate with `echocal calibrate --rig FILE --position X,Y,Z`")

    @rig_app.command("presets")
    def presets(
        as_json: bool = typer.Option(False, "--json", help="Print one JSON object on stdout."),
    ) -> None:
        """The VISA presets: oscilloscope (receiver) and motion-controller (positioner)
        command families a rig file may name with ``preset = ...``."""
        from echocal.cli._common import write_json
        from echocal.rigs import MOTION_PRESETS, SCOPE_PRESETS

        table = {
            "receiver": {name: p.family for name, p in SCOPE_PRESETS.items()},
            "positioner": {name: p.family for name, p in MOTION_PRESETS.items()},
        }
        if as_json:
            write_json(table)
            return
        for role, entries in table.items():
            _say(f'{role} (driver = "visa"):')
            for name, family in entries.items():
                _say(f"  {name:<12}{family}")
