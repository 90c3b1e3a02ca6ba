"""Report sections of single results: a calibration folder and a scan folder.

A calibration folder is what ``echocal calibrate --out DIR`` writes (``result.json`` with
its provenance, ``ascan.nc`` and the figures ``ascan.png``, ``path.png``,
``convergence.png``); a scan folder what ``echocal scan --out DIR`` writes (``scan.nc``
and the maps and 3-D view).  Each section returns (HTML, one line for the contents).
"""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any

from echocal.errors import DataFileError
from echocal.experiments._report_html import facts, fig_png, fmt, png

__all__ = ["CALIBRATION_FILE", "SCAN_FILE", "calibration_section", "scan_section"]

CALIBRATION_FILE = "result.json"
SCAN_FILE = "scan.nc"

_CALIBRATION_FIGURES = [
    (
        "A-scan at the estimate (gate: the pseudo-energy's window, at the detection threshold)",
        "ascan.png",
    ),
    ("path over the map", "path.png"),
    ("convergence", "convergence.png"),
]
_SCAN_FIGURES = [
    ("surface height", "height"),
    ("surface normals", "normals"),
    ("errors against the truth", "errors"),
    ("measurements per point", "measurements"),
    ("3-D view", "surface-3d"),
]


def is_calibration(folder: Path) -> bool:
    """Whether ``folder`` holds a calibration result (``result.json`` of calibrate)."""
    path = folder / CALIBRATION_FILE
    if not path.is_file():
        return False
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and "iterates" in data and "method" in data


def calibration_section(folder: Path, anchor: str) -> tuple[str, str]:
    """The page of one calibration: outcome, the A-scan at the estimate, the path over
    the map, convergence and provenance."""
    try:
        result: dict[str, Any] = json.loads((folder / CALIBRATION_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise DataFileError(f"cannot read {folder / CALIBRATION_FILE}: {exc}") from exc
    names = result.get("names") or ["a", "b"]
    x = result.get("x") or []
    estimate = ", ".join(f"{n} {float(v):.4f}°" for n, v in zip(names, x, strict=False))
    summary = _calibration_summary(folder)
    title = f"calibration ({result['method']})"
    outcome = (
        "converged" if result.get("success") else f"not converged (status {result.get('status')})"
    )
    rows: list[tuple[str, Any]] = [
        ("method", result["method"]),
        ("outcome", result.get("message") or outcome),
        *_setup_rows(summary),
        ("estimate", estimate or "–"),
        *_truth_rows(summary, names),
        ("parameterization", result.get("parameterization")),
        ("measurements", result.get("n_measurements")),
        ("of which acquisition", result.get("acquisition_measurements")),
        (
            "search beyond the first ring",
            _POSTERIOR
            if result.get("posterior_search")
            else _passes(result.get("search_passes"), result.get("search_snr_db")),
        ),
        ("iterations", result.get("n_iterations")),
        ("metric at the estimate", result.get("final_value")),
        ("wall time [s]", result.get("wall_time")),
    ]
    parts = [
        f'<h2 id="{anchor}">{html.escape(title)}</h2>',
        f'<p class="small">folder {html.escape(str(folder))}</p>',
        facts(rows),
    ]
    for label, name in _CALIBRATION_FIGURES:
        parts.append(f"<h3>{html.escape(label)}</h3>")
        path = folder / name
        parts.append(
            png(path)
            if path.is_file()
            else f"<p class='small'>no {name} (the run was made with --no-plots, "
            "or found no echo)</p>"
        )
    parts += [
        "<h3>provenance</h3>",
        _provenance(
            result.get("provenance"), rerun="echocal calibrate --from result.json --out NEW"
        ),
    ]
    line = f"{title} — {outcome}; estimate {estimate or 'none'}"
    return "\n".join(parts), line


def _calibration_summary(folder: Path) -> dict[str, Any]:
    """The ``summary.json`` that ``echocal calibrate`` writes beside ``result.json``
    (what was calibrated, truth and error); empty for a folder without one."""
    try:
        data = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _setup_rows(summary: dict[str, Any]) -> list[tuple[str, Any]]:
    """What was calibrated: the setup (or source), position [mm], seed."""
    source = summary.get("source") or {}
    what = source.get("description") or source.get("name") or source.get("kind")
    rows: list[tuple[str, Any]] = []
    if summary.get("setup") or what:
        name = summary.get("setup")
        both = name and what and what != name
        rows.append(("setup", f"{name}: {what}" if both else name or what))
    if summary.get("position_m") is not None:
        rows.append(("position [mm]", _text([1e3 * float(v) for v in summary["position_m"]])))
    return rows


def _truth_rows(summary: dict[str, Any], names: list[str]) -> list[tuple[str, Any]]:
    """The simulator's true optimum and the estimate's angular error [deg] (a simulated
    calibration only: a recording or a rig knows no truth)."""
    truth = summary.get("truth_deg")
    if not truth:
        return []
    pairs = zip(names, truth, strict=False)
    rows: list[tuple[str, Any]] = [
        ("true optimum", ", ".join(f"{n} {float(v):.4f}°" for n, v in pairs))
    ]
    error = summary.get("error_deg")
    rows.append(("error [°]", "– (no echo found)" if error is None else f"{float(error):.4f}"))
    return rows


def _text(value: Any) -> str:
    """A provenance value as a reader wants it: a list as ``a, b``, yes/no for a flag."""
    if isinstance(value, list | tuple):
        return ", ".join(_text(v) for v in value)
    if isinstance(value, float):
        return f"{value:g}"
    return fmt(value)


def _provenance(record: dict[str, Any] | None, *, rerun: str | None = None) -> str:
    """The provenance facts of a calibration or a scan; ``rerun``: how to rerun it."""
    if not record:
        return "<p class='small'>no provenance recorded (a run through the Python API)</p>"
    setup = record.get("setup") or {}
    source = record.get("source") or {}
    method = record.get("method") or {}
    versions = record.get("versions") or {}
    argv = list(record.get("argv") or [])
    if argv and argv[0] == "__main__.py":  # `python -m echocal` is the same command
        argv[0] = "echocal"
    rows: list[tuple[str, Any]] = [
        ("command line", " ".join(argv)),
        (
            "options given",
            ", ".join(
                f"{k} {_text(v)}"
                for k, v in (record.get("parameters") or {}).items()
                if v is not None
            ),
        ),
        ("working folder", record.get("cwd")),
        ("started / finished (UTC)", f"{record.get('started')} / {record.get('finished')}"),
        ("setup", f"{setup.get('name')} (sha256 {setup.get('sha256')})"),
        ("source", ", ".join(f"{k} {_text(v)}" for k, v in source.items() if v is not None)),
    ]
    if record.get("position_m") is not None:
        rows.append(("position [mm]", _text([1e3 * float(v) for v in record["position_m"]])))
    rows += [("seed", record.get("seed")), ("method", method.get("name"))]
    if "x0" in method:
        rows.append(("start x0 [°]", _text(method.get("x0"))))
    if "budget_per_point" in method:
        rows.append(("budget per point", method["budget_per_point"]))
    else:
        rows.append(("budget", method.get("budget") or "none (until it settles)"))
    rows.append(("versions", ", ".join(f"{k} {v}" for k, v in versions.items())))
    hint = f"<p class='small'>rerun it: <code>{html.escape(rerun)}</code></p>" if rerun else ""
    return facts(rows) + hint


def scan_section(folder: Path, anchor: str) -> tuple[str, str]:
    """The page of one surface scan: its summary, the maps and the 3-D view (the
    folder's figures; drawn from ``scan.nc`` when it has none)."""
    from echocal.scanning.dataset import SurfaceScan

    scan = SurfaceScan.load(folder / SCAN_FILE)
    s = scan.summary
    title = f"surface scan ({s.get('truth') or 'no truth'})"
    normal, height = s.get("normal_error_deg") or {}, s.get("height_error_abs_m") or {}
    rows: list[tuple[str, Any]] = [
        ("points", f"{s['points']} ({s['found']} found, {s['missing']} missing)"),
        (
            "measurements",
            f"{s['measurements_total']} ({s['measurements_per_point']:.1f} per point)",
        ),
    ]
    if normal:
        rows.append(("normal error [°]", _quantiles(normal, 1.0)))
    if height:
        rows.append(("|height error| [mm]", _quantiles(height, 1e3)))
    if s.get("missing_messages"):
        counts = s.get("missing_by_status") or {}
        rows.append(
            (
                "why points are missing",
                "; ".join(
                    f"{status} ({counts[status]} points): {message}"
                    if status in counts
                    else f"{status}: {message}"
                    for status, message in s["missing_messages"].items()
                ),
            )
        )
    parts = [
        f'<h2 id="{anchor}">{html.escape(title)}</h2>',
        f'<p class="small">folder {html.escape(str(folder))}</p>',
        facts(rows),
    ]
    drawn = _scan_figures(scan)
    for label, name in _SCAN_FIGURES:
        path = folder / f"{name}.png"
        if path.is_file():
            parts += [f"<h3>{html.escape(label)}</h3>", png(path)]
        elif name in drawn:
            parts += [f"<h3>{html.escape(label)}</h3>", fig_png(drawn[name]())]
    record = scan.dataset.attrs.get("provenance")
    if record:
        # the same command again resumes or reports a finished scan; --overwrite remeasures
        parts += ["<h3>provenance</h3>", _provenance(json.loads(record))]
    line = f"{title} — {s['found']} of {s['points']} points found"
    return "\n".join(parts), line


def _quantiles(q: dict[str, Any], scale: float) -> str:
    return ", ".join(f"{k} {float(v) * scale:.3g}" for k, v in q.items() if v is not None) or "–"


def _scan_figures(scan: Any) -> dict[str, Any]:
    """name → a function drawing that figure from the scan (no specimen known here)."""
    from echocal.plots import surface

    figures = {
        "height": lambda: surface.height_map_figure(scan),
        "normals": lambda: surface.normal_map_figure(scan),
        "measurements": lambda: surface.measurements_figure(scan),
        "surface-3d": lambda: surface.surface_3d_figure(scan),
    }
    if "normal_error" in scan.dataset:
        figures["errors"] = lambda: surface.error_maps_figure(scan)
    return figures


_POSTERIOR = "Bayesian: by the posterior over the optimum, every significance counted"
"""How the report names a posterior search (:mod:`echocal.calibrate.posterior_search`)."""


def _passes(spacings: list[float] | None, snr_db: float | None = None) -> str:
    """The acquisition's replanned pass spacings [deg] and the echo SNR [dB] they were
    sized for, or why there are none."""
    if not spacings:
        return "– (the planned search was kept)"
    passes = ", ".join(f"{float(v):.2f}°" for v in spacings)
    return passes if snr_db is None else f"{passes} (for an echo predicted at {snr_db:.1f} dB)"
