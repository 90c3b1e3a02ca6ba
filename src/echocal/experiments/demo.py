"""The main job: a short calibration study plus the thesis's Table 7 comparison, in one report.

:func:`run_demo` runs the short sweep ``echocal/data/sweeps/quick.toml`` (auto,
model-based, SPSA and quasi-Newton at 30 and 15 dB from random starts 2-4° off, several
seeds) on the thesis setup, reruns the Table 7 comparison (``table-7`` scenario: the six
thesis methods with the thesis presets, echocal's model-based and auto beyond the thesis,
and the thesis methods with automatic gains) and writes ``OUT/report.html``::

    OUT/sweep-quick/    the sweep folder (runs.parquet, history.parquet)
    OUT/table-7/        the scenario folder (findings.json, figures, tables)
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
ECHOCAL_FIRST = ("auto", "model-based")
"""echocal's own methods, listed before the thesis's in the summary."""


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
    """Run the quick sweep and Table 7 into ``out_dir`` and write ``out_dir/report.html``.

    quick : fewer seeds (for tests); progress : progress bars and a summary on stderr;
    overwrite : allow an ``out_dir`` that already holds files (else DataFileError).

    The summary leads with the calibration study (per method and SNR: runs within the
    tolerance, measurements they needed, and for a method that missed it, where its runs
    ended and why), then the thesis's Table 7 findings, each with its reason.
    """
    from echocal.experiments.execution import run_sweep

    t0 = time.perf_counter()
    out = Path(out_dir)
    check_out_dir(out, overwrite=overwrite)
    console = console or Console(stderr=True)
    sweep_dir = out / "sweep-quick"
    sweep = run_sweep(_sweep_spec(quick), sweep_dir, progress=progress, overwrite=overwrite)
    summary = sweep.summary()
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
    report = write_report(
        [sweep_dir, out / "table-7"],
        out / "report.html",
        title="echocal demo: a calibration study and the thesis's Table 7",
    )
    wall = time.perf_counter() - t0
    if progress:
        _print_study(console, sweep, summary)
        _print_findings(console, scenario)
        console.print(
            f"[bold]report:[/] {escape(str(report.resolve()))}  (open it in a browser; "
            f"results in {escape(str(out.resolve()))}, total {wall:.1f} s)",
            highlight=False,
            soft_wrap=True,
        )
    return DemoResult(
        report=report, scenario=scenario, sweep_dir=sweep_dir, sweep_summary=summary, wall_time=wall
    )


def _print_study(console: Console, sweep: Any, summary: Any) -> None:
    """The calibration study: echocal's methods first, each row's success and cost."""
    spec = sweep.spec
    tol = spec.tolerance
    budget = f"at most {spec.budget} measurements" if spec.budget else "no budget"
    console.print(
        f"[bold]What echocal finds[/]: {len(sweep.runs)} simulated calibrations on the "
        f"{escape(spec.setup)} setup ({escape(spec.description)}; {budget} per run). "
        f"A run succeeds when it ends within {tol:g}° of the true optimum.",
        highlight=False,
        soft_wrap=True,
    )
    order = {name: i for i, name in enumerate(ECHOCAL_FIRST)}
    rows = sorted(summary.itertuples(), key=lambda r: order.get(r.method, len(order)))
    for row in rows:
        n = int(row.runs)
        ok = round(row.success_rate * n)
        rate = percent(row.success_rate)
        line = f"  {row.label:12s} {row.snr_db:4.0f} dB  success {ok}/{n} ({rate})"
        if ok:
            line += (
                f"  to {tol:g}°: median {_count(row.median_measurements_to_tol)}"
                f", p90 {_count(row.p90_measurements_to_tol)} measurements"
            )
        if ok < n:
            line += f"; {_why_missed(row, spec.budget)}"
        console.print(escape(line), highlight=False, soft_wrap=True)


def _why_missed(row: Any, budget: int | None) -> str:
    """Where a configuration's runs ended when some missed the tolerance, and why (read
    from its numbers: the budget spent, or a settled estimate still outside)."""
    ended = f"runs ended a median {row.median_error_deg:.2g}° from the optimum"
    if budget and row.mean_measurements >= 0.95 * budget:
        return f"{ended}: the budget ran out first (a mean {row.mean_measurements:.0f} used)"
    return f"{ended}: they stopped (settled or iteration limit) before reaching it"


def _print_findings(console: Console, scenario: ScenarioResult) -> None:
    """The thesis's Table 7 claims, as findings on our runs, each with its reason."""
    console.print(
        f"[bold]The thesis's Table 7, rerun[/] ({scenario.wall_time:.1f} s): its claims "
        "tested on the same setup, each with what our runs show and why.",
        highlight=False,
        soft_wrap=True,
    )
    for f in scenario.findings:
        mark = "reproduced" if f.agrees else "not reproduced here"
        console.print(
            f"  {escape(f'[{f.group}]')} {escape(f.claim)}: [bold]{mark}[/]. {escape(f.evidence)}",
            highlight=False,
            soft_wrap=True,
        )
        if f.why:
            console.print(f"    [bold]why:[/] {escape(f.why)}", highlight=False, soft_wrap=True)


def _count(value: float) -> str:
    """A measurement count for the console ("never" when no run reached the tolerance,
    the report's word)."""
    return NEVER if value != value else f"{value:.0f}"  # NaN-safe without numpy
