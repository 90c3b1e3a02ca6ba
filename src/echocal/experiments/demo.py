"""The main job: the thesis's Table 7 comparison plus a short sweep, in one report.

:func:`run_demo` builds the thesis setup, reruns the Table 7 comparison
(``table-7`` scenario: the six thesis methods with the thesis presets, echocal's
model-based and auto beyond the thesis, and the thesis methods with automatic
gains), runs the short sweep ``echocal/data/sweeps/quick.toml`` (SPSA, quasi-Newton,
model-based and auto at 30 and 15 dB from random starts 2-4° off, several seeds) and writes
``OUT/report.html``::

    OUT/table-7/        the scenario folder (findings.json, figures, tables)
    OUT/sweep-quick/    the sweep folder (runs.parquet, history.parquet)
    OUT/report.html     one self-contained page

About a minute on a 2-core machine; ``quick=True`` (tests) runs fewer seeds.
"""

from __future__ import annotations

import importlib.resources
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from echocal.experiments._output import check_out_dir
from echocal.experiments._report_html import NEVER, percent
from echocal.experiments.report import write_report
from echocal.experiments.scenarios import ScenarioResult, run_scenario

__all__ = ["DemoResult", "run_demo"]

QUICK_SWEEP_SEEDS = 2


@dataclass(frozen=True)
class DemoResult:
    """What the demo wrote: the report, the scenario result, the sweep summary, timing [s]."""

    report: Path
    scenario: ScenarioResult
    sweep_dir: Path
    sweep_summary: Any
    wall_time: float


def _sweep_spec(quick: bool) -> dict[str, Any]:
    """The packaged quick sweep as a dict (fewer seeds in quick mode)."""
    resource = importlib.resources.files("echocal") / "data" / "sweeps" / "quick.toml"
    spec = tomllib.loads(resource.read_text(encoding="utf-8"))
    if quick:
        spec["seeds"] = QUICK_SWEEP_SEEDS
        spec["name"] = f"{spec.get('name', 'quick')}-reduced"
    return spec


def run_demo(
    out_dir: str | Path,
    *,
    quick: bool = False,
    progress: bool = True,
    overwrite: bool = False,
    console: Console | None = None,
) -> DemoResult:
    """Run Table 7 and the quick sweep into ``out_dir`` and write ``out_dir/report.html``.

    quick : fewer seeds (for tests); progress : progress bars and a summary on stderr;
    overwrite : allow an ``out_dir`` that already holds files (else DataFileError).
    """
    from echocal.experiments.execution import run_sweep

    t0 = time.perf_counter()
    out = Path(out_dir)
    check_out_dir(out, overwrite=overwrite)
    console = console or Console(stderr=True)
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        console=console,
        disable=not progress,
        transient=False,
    ) as bar:
        task = bar.add_task("table-7: thesis methods compared", total=None)

        def advance(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        scenario = run_scenario(
            "table-7", out / "table-7", quick=quick, overwrite=overwrite, progress=advance
        )
    sweep_dir = out / "sweep-quick"
    sweep = run_sweep(_sweep_spec(quick), sweep_dir, progress=progress, overwrite=overwrite)
    summary = sweep.summary()
    report = write_report(
        [out / "table-7", sweep_dir],
        out / "report.html",
        title="echocal demo: thesis Table 7 and a short sweep",
    )
    wall = time.perf_counter() - t0
    if progress:
        console.print(f"[bold]table-7[/] ({scenario.wall_time:.1f} s):")
        for f in scenario.findings:
            mark = "[green]agrees[/]" if f.agrees else "[red]does not agree[/]"
            console.print(
                f"  {mark} {escape(f'[{f.group}]')} {escape(f.claim)}: {escape(f.evidence)}",
                highlight=False,
                soft_wrap=True,
            )
            if f.why:
                console.print(f"    [bold]why:[/] {escape(f.why)}", highlight=False, soft_wrap=True)
        console.print(f"[bold]sweep[/] {sweep.spec.name}: {len(sweep.runs)} runs")
        for row in summary.itertuples():
            console.print(
                f"  {row.label:12s} {row.snr_db:4.0f} dB  success {percent(row.success_rate):>5s}"
                f"  to {sweep.spec.tolerance:g}°: median {_count(row.median_measurements_to_tol)}"
                f", p90 {_count(row.p90_measurements_to_tol)} measurements",
                highlight=False,
            )
        console.print(
            f"[bold]report:[/] {escape(str(report.resolve()))}  (open it in a browser; "
            f"results in {escape(str(out.resolve()))}, total {wall:.1f} s)",
            highlight=False,
            soft_wrap=True,
        )
    return DemoResult(
        report=report, scenario=scenario, sweep_dir=sweep_dir, sweep_summary=summary, wall_time=wall
    )


def _count(value: float) -> str:
    """A measurement count for the console ("never" when no run reached the tolerance,
    the report's word)."""
    return NEVER if value != value else f"{value:.0f}"  # NaN-safe without numpy
