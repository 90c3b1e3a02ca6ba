"""The report's section of a position scan (``echocal import`` / ``echocal record-scan``):
what the file is and where it came from, a B-scan through the middle, a C-scan of the
peak over the whole recording and the middle trace's A-scan."""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any

import numpy as np

from echocal.experiments._report_html import facts, fig_png

__all__ = ["is_position_scan", "position_scan_section"]


def is_position_scan(path: Path) -> bool:
    """Whether ``path`` is a NetCDF file of echocal's ``position-scan`` kind."""
    if not (path.is_file() and path.suffix == ".nc"):
        return False
    from echocal.netcdf import open_netcdf

    try:
        with open_netcdf(path, what="position scan") as ds:
            return str(ds.attrs.get("echocal_format", "")).startswith("position-scan/")
    except (OSError, ValueError):
        return False


def position_scan_section(path: Path, anchor: str) -> tuple[str, str]:
    """HTML of the scan in ``path`` and its line in the report's contents."""
    from echocal.plots.position_scan import ascan_figure, bscan_figure, cscan_figure
    from echocal.positionscan import PositionScan
    from echocal.signal.gates import TimeGate

    scan = PositionScan.load(path)
    attrs = scan.dataset.attrs
    shape = f"{scan.y.size} × {scan.x.size}" if scan.is_raster else f"{scan.x.size}"
    kind = "raster" if scan.is_raster else "line"
    title = f"position scan ({kind} of {shape} traces)"
    rows: list[tuple[str, Any]] = [
        ("file", str(path)),
        ("source", f"{attrs.get('source_format', '?')}: {attrs.get('source_file', '?')}"),
        ("source SHA-256", attrs.get("source_sha256", "—")),
        ("x span [mm]", f"{scan.x[0] * 1e3:.4g} … {scan.x[-1] * 1e3:.4g}"),
        ("samples per trace", scan.times.size),
        ("sampling rate [MHz]", f"{scan.fs / 1e6:.6g}"),
        ("start time [µs]", f"{scan.start_time * 1e6:.6g}"),
        ("traces recorded", f"{int(np.count_nonzero(scan.valid))} of {scan.valid.size}"),
    ]
    if scan.is_raster:
        rows.insert(4, ("y span [mm]", f"{scan.y[0] * 1e3:.4g} … {scan.y[-1] * 1e3:.4g}"))
    if scan.sound_speed is not None:
        rows.append(("sound speed [m/s]", f"{scan.sound_speed:.6g}"))
    if attrs.get("user_facts"):
        rows.append(("supplied by the user", attrs["user_facts"]))
    whole = TimeGate(
        name="recording",
        width=float(scan.times[-1] - scan.times[0]) + 1.0 / scan.fs,
        start=float(scan.times[0]),
    )
    middle_x = float(scan.x[scan.x.size // 2])
    middle_y = float(scan.y[scan.y.size // 2]) if scan.is_raster else None
    parts = [
        f'<h2 id="{anchor}">{html.escape(title)}</h2>',
        facts(rows),
        "<h3>B-scan (middle line)</h3>",
        fig_png(bscan_figure(scan)),
        "<h3>C-scan: peak over the whole recording</h3>",
        fig_png(cscan_figure(scan, whole)),
        "<h3>A-scan (middle trace)</h3>",
        fig_png(ascan_figure(scan, middle_x, middle_y)),
    ]
    return "\n".join(parts), f"{title} — {path.name}"
