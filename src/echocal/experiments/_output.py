"""Writing a scenario's folder (private): tables, figures, findings.json, summary.md.

Every file is written atomically (:func:`echocal.io.atomic_path`), so a folder never
holds a half-written table.  ``findings.json`` is the marker by which
:mod:`echocal.experiments.report` recognizes a scenario folder.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from echocal.experiments._findings import Finding
from echocal.io import atomic_path, atomic_write_text, check_out_dir
from echocal.plots import save_figure
from echocal.plots._figure import release

__all__ = ["FINDINGS_FILE", "check_out_dir", "write_figure", "write_summary", "write_table"]

FINDINGS_FILE = "findings.json"
FORMAT_VERSION = 1


def write_table(frame: pd.DataFrame, out_dir: Path, stem: str) -> list[Path]:
    """``stem.csv`` and ``stem.parquet`` of ``frame``, atomically."""
    written = []
    for suffix in ("csv", "parquet"):
        target = out_dir / f"{stem}.{suffix}"
        with atomic_path(target) as tmp:
            if suffix == "csv":
                frame.to_csv(tmp, index=False)
            else:
                frame.to_parquet(tmp, index=False)
        written.append(target)
    return written


def write_figure(fig: Figure, out_dir: Path, stem: str) -> list[Path]:
    """``stem.png`` and ``stem.svg`` of ``fig`` (then released: a notebook does not show it)."""
    written = save_figure(fig, out_dir / f"{stem}.png", formats=("png", "svg"), dpi=110)
    release(fig)
    return written


def _jsonable(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    return value


def _markdown_table(frame: pd.DataFrame) -> str:
    def cell(v: Any) -> str:
        if isinstance(v, float):
            return "never" if v == math.inf else ("–" if math.isnan(v) else f"{v:.3g}")
        return str(v)

    header = "| " + " | ".join(frame.columns) + " |"
    rule = "|" + "---|" * len(frame.columns)
    body = ["| " + " | ".join(cell(v) for v in row) + " |" for row in frame.itertuples(index=False)]
    return "\n".join([header, rule, *body])


def write_summary(
    out_dir: Path,
    *,
    scenario: str,
    title: str,
    thesis: str,
    description: str,
    setup: str,
    quick: bool,
    seeds: Sequence[int],
    findings: Sequence[Finding],
    notes: Sequence[str],
    tables: Mapping[str, pd.DataFrame],
    figures: Mapping[str, Sequence[Path]],
    wall_time: float,
) -> list[Path]:
    """``findings.json`` (machine-readable) and ``summary.md`` (for people)."""
    files = {
        "tables": {name: [f"{name}.csv", f"{name}.parquet"] for name in tables},
        "figures": {k: [p.name for p in v] for k, v in figures.items()},
    }
    data = {
        "format": "echocal-scenario",
        "version": FORMAT_VERSION,
        "scenario": scenario,
        "title": title,
        "thesis": thesis,
        "description": description,
        "setup": setup,
        "quick": quick,
        "seeds": list(seeds),
        "findings": [f.to_dict() for f in findings],
        "notes": list(notes),
        "files": files,
        "wall_time_s": wall_time,
    }
    atomic_write_text(out_dir / FINDINGS_FILE, json.dumps(_jsonable(data), indent=1) + "\n")

    lines = [f"# {scenario}: {title}", "", f"*Thesis:* {thesis}", "", description, ""]
    lines += [f"*Setup:* {setup}", ""]
    lines += [
        f"*Seeds:* {len(seeds)} ({'quick' if quick else 'full'} mode); medians over seeds.",
        "",
    ]
    lines += ["## Findings", ""]
    for f in findings:
        mark = "AGREES" if f.agrees else "DOES NOT AGREE"
        where = f" [{f.group}]" if f.group else ""
        lines += [
            f"- **{mark}**{where} — {f.claim}",
            f"  - criterion: {f.criterion}",
            f"  - evidence: {f.evidence}",
        ]
        if f.why:
            lines.append(f"  - why: {f.why}")
    if notes:
        lines += ["", "## Notes", "", *[f"- {n}" for n in notes]]
    for name, frame in tables.items():
        lines += ["", f"## Table: {name}", "", _markdown_table(frame)]
    lines += ["", "## Figures", ""]
    for name, paths in figures.items():
        lines += [f"- {name}: " + ", ".join(p.name for p in paths)]
    atomic_write_text(out_dir / "summary.md", "\n".join(lines) + "\n")
    return [out_dir / FINDINGS_FILE, out_dir / "summary.md"]
