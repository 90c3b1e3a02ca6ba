"""HTML pieces of the report: the page's style, embedded figures and readable tables.

Tables fit the page (cells wrap at spaces, an overlong word where it must; a horizontal scroll
container for a table with many columns), carry human headers instead of column names, write "never"
for a milestone a run did not reach (never Python's ``None``), and show fractions as
percentages, formatted as the figures' percent axes are.
"""

from __future__ import annotations

import base64
import html
import io
import math
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

if TYPE_CHECKING:  # matplotlib is imported only to draw: `sweep run`'s table needs none
    from matplotlib.figure import Figure

__all__ = ["CSS", "NEVER", "facts", "fig_png", "fmt", "header", "percent", "png", "table"]

CSS = """
body{font-family:system-ui,sans-serif;max-width:1150px;margin:2em auto;padding:0 1em;color:#222}
h1{border-bottom:2px solid #446}h2{border-bottom:1px solid #aab;margin-top:2.2em}
.table-wrap{max-width:100%;overflow-x:auto;margin:0.6em 0}
table{border-collapse:collapse;font-size:12px;width:100%}
td,th{border:1px solid #ccd;padding:3px 6px;text-align:right;vertical-align:top}
td{overflow-wrap:break-word}th{background:#eef;font-weight:600;overflow-wrap:normal}
table.facts{table-layout:fixed}
td:first-child,td:nth-child(2){text-align:left}
table.facts td{text-align:left}table.facts td:first-child{width:14em;font-weight:600}
.agree{color:#fff;background:#2a7;padding:1px 6px;border-radius:3px;font-weight:bold}
.disagree{color:#fff;background:#c43;padding:1px 6px;border-radius:3px;font-weight:bold}
.finding{margin:0.7em 0;padding:0.4em 0.8em;border-left:4px solid #aab;background:#f7f7fb}
.small{font-size:12px;color:#555}img{max-width:100%;margin:0.5em 0;border:1px solid #eee}
"""

NEVER = "never"
"""The one word for a milestone a run did not reach."""

_HEADERS = {
    "label": "configuration",
    "x0_kind": "start",
    "snr_db": "SNR [dB]",
    "n_measurements": "measurements",
    "n_iterations": "iterations",
    "final_error_deg": "final error [°]",
    "initial_error_deg": "initial error [°]",
    "median_error_deg": "median error [°]",
    "measurements_to_0.5deg": "measurements to 0.5°",
    "measurements_to_0.1deg": "measurements to 0.1°",
    "iterations_to_90pct": "iterations to 90 % of the optimum",
    "measurements_to_90pct": "measurements to 90 % of the optimum",
    "final_metric_rel": "final metric / optimum",
    "success_rate": "success rate",
    "median_measurements_to_tol": "median measurements to tolerance",
    "p90_measurements_to_tol": "90th percentile measurements to tolerance",
    "expected_measurements_to_success": "expected measurements to success",
    "rebound_deg": "largest rebound [°]",
}
_UNITS = {"deg": "[°]", "db": "[dB]", "mm": "[mm]", "m": "[m]", "s": "[s]", "hz": "[Hz]"}
_PERCENT = re.compile(r"(_rate|_fraction)$")
"""Fractions the figures draw in percent (success rates); a ratio such as
``final_metric_rel`` stays a ratio, as on the convergence figures' axes."""
_MILESTONE = re.compile(r"_to_")
_MISSING_WORD = {"preset": "default", "group": ""}
"""What a missing value means in these columns (a sweep row without a preset ran the
method's defaults)."""


def header(column: str) -> str:
    """A human header for a table column: the known ones spelled out, others with their
    underscores as spaces and a trailing unit (``_deg``, ``_db``, …) in brackets."""
    if column in _HEADERS:
        return _HEADERS[column]
    words = str(column).split("_")
    unit = _UNITS.get(words[-1].lower()) if len(words) > 1 else None
    text = " ".join(words[:-1] if unit else words).replace("pct", "%")
    return f"{text} {unit}" if unit else text


def _missing(value: Any) -> bool:
    if value is None or value is pd.NA or value is pd.NaT:
        return True
    return isinstance(value, float) and math.isnan(value)


def percent(fraction: float) -> str:
    """A fraction as the figures' percent axes read it: ``0.6`` → ``60 %``."""
    return f"{100.0 * fraction:.3g} %"


def fmt(value: Any, column: str = "") -> str:
    """One table cell: "never" for a milestone not reached (missing or +inf in a
    ``*_to_*`` column, or +inf anywhere), "–" for another missing value, fractions
    (``*_rate``, ``*_fraction``) as percentages, floats to 3 significant digits."""
    milestone = bool(_MILESTONE.search(column))
    if _missing(value):
        return NEVER if milestone else _MISSING_WORD.get(column, "–")
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if math.isinf(value):
            return NEVER if value > 0 else "−∞"
        if _PERCENT.search(column):
            return percent(value)
        return f"{value:.3g}"
    return str(value)


def table(frame: pd.DataFrame) -> str:
    """``frame`` as an HTML table that fits the page (see the module docstring)."""
    cells = frame.astype(object).where(frame.notna(), None)
    head = "".join(f"<th>{html.escape(header(str(c)))}</th>" for c in frame.columns)
    rows = "".join(
        "<tr>"
        + "".join(
            f"<td>{html.escape(fmt(_plain(v), str(c)))}</td>"
            for c, v in zip(frame.columns, row, strict=True)
        )
        + "</tr>"
        for row in cells.itertuples(index=False, name=None)
    )
    wide = len(frame.columns) > 12  # past a dozen columns: scroll rather than squeeze
    style = ' style="width:auto"' if wide else ""
    return (
        f'<div class="table-wrap"><table{style}><thead><tr>{head}</tr></thead>'
        f"<tbody>{rows}</tbody></table></div>"
    )


def facts(rows: list[tuple[str, Any]]) -> str:
    """A two-column table of named facts (already formatted or plain values)."""
    body = "".join(
        f"<tr><td>{html.escape(name)}</td><td>{html.escape(fmt(_plain(value)))}</td></tr>"
        for name, value in rows
    )
    return f'<div class="table-wrap"><table class="facts"><tbody>{body}</tbody></table></div>'


def _plain(value: Any) -> Any:
    """numpy scalars as Python numbers (floats formatted, ints as they are)."""
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        try:
            return value.item()
        except (ValueError, AttributeError):
            return value
    return value


def png(path: Path) -> str:
    """An ``<img>`` with the PNG file embedded (base64)."""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


def fig_png(fig: Figure) -> str:
    """An ``<img>`` with the figure embedded as PNG (base64)."""
    from echocal.plots._figure import release

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, bbox_inches="tight")
    release(fig)
    data = base64.b64encode(buffer.getvalue()).decode("ascii")
    return f'<img alt="figure" src="data:image/png;base64,{data}">'
