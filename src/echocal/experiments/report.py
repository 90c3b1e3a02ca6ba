"""One self-contained HTML page from scenario and sweep result folders.

:func:`write_report` recognizes each folder by its files — a scenario folder by its
``findings.json`` (:func:`echocal.experiments.scenarios.run_scenario`), a sweep
folder by its ``sweep.json`` (read with
:func:`echocal.experiments.execution.load_results`) — and writes one HTML file
with every figure embedded as a base64 PNG: no external assets, so the page can
be mailed or archived as is.  Written atomically.

Example::

    write_report(["out/table-7", "out/sweep-quick"], "out/report.html")
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from echocal.errors import DataFileError, EchocalError
from echocal.experiments._output import FINDINGS_FILE
from echocal.io import atomic_write_text

__all__ = ["folder_kind", "write_report"]

_SWEEP_FILE = "sweep.json"

_CSS = """
body{font-family:system-ui,sans-serif;max-width:1150px;margin:2em auto;padding:0 1em;color:#222}
h1{border-bottom:2px solid #446}h2{border-bottom:1px solid #aab;margin-top:2.2em}
table{border-collapse:collapse;font-size:12px;margin:0.6em 0}
td,th{border:1px solid #ccd;padding:3px 6px;text-align:right}th{background:#eef}
td:first-child,td:nth-child(2){text-align:left}
.agree{color:#fff;background:#2a7;padding:1px 6px;border-radius:3px;font-weight:bold}
.disagree{color:#fff;background:#c43;padding:1px 6px;border-radius:3px;font-weight:bold}
.finding{margin:0.7em 0;padding:0.4em 0.8em;border-left:4px solid #aab;background:#f7f7fb}
.small{font-size:12px;color:#555}img{max-width:100%;margin:0.5em 0;border:1px solid #eee}
"""


def folder_kind(folder: str | Path) -> str:
    """``"scenario"`` or ``"sweep"``; DataFileError for a folder that is neither."""
    path = Path(folder)
    if not path.is_dir():
        raise DataFileError(f"results folder not found: {str(path)!r}")
    if (path / FINDINGS_FILE).is_file():
        return "scenario"
    if (path / _SWEEP_FILE).is_file():
        return "sweep"
    raise DataFileError(
        f"{str(path)!r} is neither a scenario result (no {FINDINGS_FILE}; see `echocal "
        f"scenario run`) nor a sweep result (no {_SWEEP_FILE}; see `echocal sweep run`)"
    )


def _png(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


def _fig_png(fig: Figure) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, bbox_inches="tight")
    data = base64.b64encode(buffer.getvalue()).decode("ascii")
    return f'<img alt="figure" src="data:image/png;base64,{data}">'


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        if math.isnan(value):
            return "–"
        if math.isinf(value):
            return "never" if value > 0 else "-inf"
        return f"{value:.3g}"
    return str(value)


def _table(frame: pd.DataFrame) -> str:
    return frame.to_html(index=False, na_rep="–", formatters=dict.fromkeys(frame.columns, _fmt))


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
        parts += [f"<h3>{html.escape(name)}</h3>", _table(frame[shown] if shown else frame)]
    for label, files in meta["files"]["figures"].items():
        png = [folder / f for f in files if f.endswith(".png")]
        parts += [f"<h3>{html.escape(label)}</h3>"] + [_png(p) for p in png if p.is_file()]
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
        _table(summary[shown]),
        "<h3>success rate vs SNR</h3>",
        _fig_png(success_rate_figure(summary)),
        "<h3>measurements to tolerance</h3>",
        _fig_png(measurements_figure(runs)),
        "<h3>success vs measurements</h3>",
        _fig_png(success_ecdf_figure(runs)),
    ]
    best = summary.sort_values("expected_measurements_to_success").iloc[0]
    return "\n".join(parts), (
        f"{title} — {done}; cheapest expected measurements to success: {best['label']} "
        f"at {_fmt(best['snr_db'])} dB ({_fmt(float(best['expected_measurements_to_success']))})"
    )


def write_report(
    results_dirs: Sequence[str | Path], out_html: str | Path, *, title: str = "echocal report"
) -> Path:
    """Write one self-contained HTML page for scenario and sweep result folders.

    results_dirs : folders written by ``run_scenario`` or ``run_sweep`` (each recognized
    by its files; DataFileError for any other folder, before anything is written).
    out_html : the page to write (atomically).  Returns its path.
    """
    folders = [Path(d) for d in results_dirs]
    if not folders:
        raise DataFileError("no results folders given; pass scenario or sweep result folders")
    kinds = [folder_kind(f) for f in folders]
    sections, toc = [], []
    for k, (folder, kind) in enumerate(zip(folders, kinds, strict=True)):
        anchor = f"s{k}"
        try:
            body, line = (_scenario_section if kind == "scenario" else _sweep_section)(
                folder, anchor
            )
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
        f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"
        f"<h1>{html.escape(title)}</h1><p class='small'>generated {stamp} by echocal</p>"
        f"<ul>{''.join(toc)}</ul>" + "\n".join(sections) + "</body></html>\n"
    )
    out = Path(out_html)
    atomic_write_text(out, page)
    return out
