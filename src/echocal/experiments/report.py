"""One self-contained HTML page from calibration, scan, scenario and sweep result folders.

:func:`write_report` recognizes each folder by its files — a calibration folder by its
``result.json`` (``echocal calibrate --out``: the A-scan at the estimate, the path over
the map, convergence and provenance), a scan folder by its ``scan.nc`` (``echocal scan
--out``: the maps and the 3-D view), a scenario folder by its ``findings.json``
(:func:`echocal.experiments.scenarios.run_scenario`), a sweep folder by its
``sweep.json`` (read with :func:`echocal.experiments.execution.load_results`) — and
writes one HTML file
with every figure embedded as a base64 PNG: no external assets, so the page can
be mailed or archived as is.  Written atomically.

Example::

    write_report(["out/table-7", "out/sweep-quick"], "out/report.html")
"""

from __future__ import annotations

import html
import json
import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from echocal.errors import DataFileError, EchocalError
from echocal.experiments._output import FINDINGS_FILE
from echocal.experiments._report_html import CSS, fig_png, fmt, png, table
from echocal.experiments._report_position_scan import is_position_scan, position_scan_section
from echocal.experiments._report_results import (
    CALIBRATION_FILE,
    SCAN_FILE,
    calibration_section,
    is_calibration,
    scan_section,
)
from echocal.io import atomic_write_text

__all__ = ["folder_kind", "write_report"]

_SWEEP_FILE = "sweep.json"


def folder_kind(folder: str | Path) -> str:
    """``"scenario"``, ``"sweep"``, ``"calibration"``, ``"scan"`` or ``"position-scan"`` (a
    position scan's ``.nc`` file); DataFileError for a path that is none of them."""
    path = Path(folder)
    if path.is_file():
        if is_position_scan(path):
            return "position-scan"
        raise DataFileError(
            f"{str(path)!r} is a file but not a position scan's .nc file (`echocal import` "
            "and `echocal record-scan` write those); pass it or a results folder"
        )
    if not path.is_dir():
        raise DataFileError(f"results folder not found: {str(path)!r}")
    if (path / FINDINGS_FILE).is_file():
        return "scenario"
    if (path / _SWEEP_FILE).is_file():
        return "sweep"
    if is_calibration(path):
        return "calibration"
    if (path / SCAN_FILE).is_file():
        return "scan"
    raise DataFileError(
        f"{str(path)!r} holds no result echocal can report: pass a folder of `echocal "
        f"calibrate --out` ({CALIBRATION_FILE}), `echocal scan --out` ({SCAN_FILE}), "
        f"`echocal scenario run` ({FINDINGS_FILE}) or `echocal sweep run` ({_SWEEP_FILE}), "
        "or a position scan's .nc file (`echocal import` / `echocal record-scan`)"
    )


def _finding_html(f: dict[str, Any]) -> str:
    badge = (
        '<span class="agree">agrees</span>'
        if f.get("agrees")
        else '<span class="disagree">does not agree</span>'
    )
    group = f" <em>[{html.escape(f['group'])}]</em>" if f.get("group") else ""
    return (
        f'<div class="finding">{badge}{group} <b>{html.escape(f["claim"])}</b><br>'
        f'<span class="small">criterion: {html.escape(f["criterion"])}</span><br>'
        f"evidence: {html.escape(f['evidence'])}"
        + (f"<br>why: {html.escape(f['why'])}" if f.get("why") else "")
        + "</div>"
    )


_SCENARIO_COLUMNS = [
    "group",
    "label",
    "seeds",
    "final_error_deg",
    "n_measurements",
    "measurements_to_0.5deg",
    "measurements_to_0.1deg",
    "iterations_to_90pct",
    "measurements_to_90pct",
    "final_metric_rel",
    "oscillations",
]


def _scenario_section(folder: Path, anchor: str) -> tuple[str, str]:
    try:
        meta = json.loads((folder / FINDINGS_FILE).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise DataFileError(f"cannot read {folder / FINDINGS_FILE}: {exc}") from exc
    if meta.get("format") != "echocal-scenario":
        raise DataFileError(f"{folder / FINDINGS_FILE} is not an echocal scenario result")
    title = f"{meta['scenario']}: {meta['title']}"
    parts = [
        f'<h2 id="{anchor}">{html.escape(title)}</h2>',
        f'<p class="small">thesis {html.escape(meta["thesis"])} · {html.escape(meta["setup"])}'
        f" · {len(meta['seeds'])} seed(s){' (quick mode)' if meta.get('quick') else ''} · "
        f"folder {html.escape(str(folder))}</p>",
        f"<p>{html.escape(meta['description'])}</p>",
        *[_finding_html(f) for f in meta["findings"]],
    ]
    if meta.get("notes"):
        parts.append(
            "<ul class='small'>"
            + "".join(f"<li>{html.escape(n)}</li>" for n in meta["notes"])
            + "</ul>"
        )
    for name in meta["files"]["tables"]:
        path = folder / f"{name}.parquet"
        if name in ("runs", "ascan_samples") or not path.is_file():
            continue
        frame = pd.read_parquet(path)
        shown = [c for c in _SCENARIO_COLUMNS if c in frame] if name == "summary" else None
        parts += [f"<h3>{html.escape(name)}</h3>", table(frame[shown] if shown else frame)]
    for label, files in meta["files"]["figures"].items():
        pngs = [folder / f for f in files if f.endswith(".png")]
        parts += [f"<h3>{html.escape(label)}</h3>"] + [png(p) for p in pngs if p.is_file()]
    agree = sum(bool(f["agrees"]) for f in meta["findings"])
    return "\n".join(parts), f"{title} — {agree}/{len(meta['findings'])} findings agree"


_SWEEP_COLUMNS = [
    "label",
    "preset",
    "snr_db",
    "x0_kind",
    "runs",
    "failed",
    "success_rate",
    "median_measurements_to_tol",
    "p90_measurements_to_tol",
    "expected_measurements_to_success",
    "median_error_deg",
]


def _sweep_section(folder: Path, anchor: str) -> tuple[str, str]:
    from echocal.experiments.execution import load_results
    from echocal.plots.sweep import measurements_figure, success_ecdf_figure, success_rate_figure

    results = load_results(folder)
    runs = results.runs
    summary = results.summary()
    spec = results.spec
    title = f"sweep {spec.name}"
    done = f"{len(runs)} of {results.n_cases} runs"
    parts = [
        f'<h2 id="{anchor}">{html.escape(title)}</h2>',
        f'<p class="small">{html.escape(getattr(spec, "description", "") or "")} · {done}'
        f"{'' if results.complete else ' (incomplete)'} · folder {html.escape(str(folder))}</p>",
    ]
    if runs.empty:
        parts.append("<p>No finished runs yet.</p>")
        return "\n".join(parts), f"{title} — no runs"
    shown = [c for c in _SWEEP_COLUMNS if c in summary]
    tolerance = float(runs["tolerance"].iloc[0]) if "tolerance" in runs else math.nan
    parts += [
        f"<h3>summary (tolerance {tolerance:g}°)</h3>",
        table(summary[shown]),
        "<h3>success rate vs SNR</h3>",
        fig_png(success_rate_figure(summary)),
        "<h3>measurements to tolerance</h3>",
        fig_png(measurements_figure(runs)),
        "<h3>success vs measurements</h3>",
        fig_png(success_ecdf_figure(runs)),
    ]
    best = summary.sort_values("expected_measurements_to_success").iloc[0]
    return "\n".join(parts), (
        f"{title} — {done}; cheapest expected measurements to success: {best['label']} "
        f"at {fmt(best['snr_db'])} dB ({fmt(float(best['expected_measurements_to_success']))})"
    )


_SECTIONS = {
    "scenario": _scenario_section,
    "sweep": _sweep_section,
    "calibration": calibration_section,
    "scan": scan_section,
    "position-scan": position_scan_section,
}


def write_report(
    results_dirs: Sequence[str | Path], out_html: str | Path, *, title: str = "echocal report"
) -> Path:
    """Write one self-contained HTML page for result folders.

    results_dirs : folders written by ``echocal calibrate --out``, ``echocal scan --out``,
    ``run_scenario`` or ``run_sweep``, or position-scan files (``echocal import``,
    ``echocal record-scan``), each recognized by its files, one section each
    (DataFileError for any other path, before anything is written).
    out_html : the page to write (atomically).  Returns its path.
    """
    folders = [Path(d) for d in results_dirs]
    if not folders:
        raise DataFileError(
            "no results folders given; pass calibration, scan, scenario or sweep folders"
        )
    kinds = [folder_kind(f) for f in folders]
    sections, toc = [], []
    for k, (folder, kind) in enumerate(zip(folders, kinds, strict=True)):
        anchor = f"s{k}"
        try:
            body, line = _SECTIONS[kind](folder, anchor)
        except (KeyError, ValueError, OSError) as exc:
            if isinstance(exc, EchocalError):
                raise
            raise DataFileError(
                f"cannot read the {kind} results in {str(folder)!r}: {exc}"
            ) from exc
        sections.append(body)
        toc.append(f'<li><a href="#{anchor}">{html.escape(line)}</a></li>')
    stamp = time.strftime("%Y-%m-%d %H:%M")
    page = (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body>"
        f"<h1>{html.escape(title)}</h1><p class='small'>generated {stamp} by echocal</p>"
        f"<ul>{''.join(toc)}</ul>" + "\n".join(sections) + "</body></html>\n"
    )
    out = Path(out_html)
    atomic_write_text(out, page)
    return out
