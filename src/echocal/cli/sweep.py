"""``echocal sweep``: run Monte-Carlo sweeps (locally or on Dask) and summarize them."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape

from echocal.cli._common import console, output, write_json
from echocal.cli._gate_option import GATE_HELP

_SWEEP_HELP = "Sweep TOML file, or a built-in sweep name (see `echocal sweep list`)."


def register(app: typer.Typer) -> None:
    """Add ``echocal sweep run|summary|check|list`` to ``app``."""
    sweep_app = typer.Typer(
        help="Monte-Carlo sweeps: methods × parameters × SNRs × starts × seeds.",
        no_args_is_help=True,
    )
    app.add_typer(sweep_app, name="sweep")

    @sweep_app.command("run")
    def run_command(
        sweep: Annotated[str, typer.Argument(help=_SWEEP_HELP)],
        out: Annotated[Path, typer.Option(help="Results folder (resumed if it holds this sweep).")],
        scheduler: Annotated[
            str | None,
            typer.Option(help="Dask scheduler address tcp://HOST:PORT; default: local processes."),
        ] = None,
        workers: Annotated[
            int | None, typer.Option(help="Local worker processes (default 2; 1 = in-process).")
        ] = None,
        overwrite: Annotated[
            bool, typer.Option(help="Delete the results of ANOTHER sweep found in --out.")
        ] = False,
        progress: Annotated[bool, typer.Option(help="Show a progress bar with ETA.")] = True,
        gate: Annotated[
            str | None,
            typer.Option(help=GATE_HELP + "  Replaces the sweep file's own gate."),
        ] = None,
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the summary as one JSON object.")
        ] = False,
    ) -> None:
        """Run every unfinished run of SWEEP into --out, then print its summary.

        The sweep and every run configuration are checked first (as `sweep check`
        does); nothing is written when they are refused.

        Exit codes: 0 every run completed; 1 some runs failed (their error is in
        runs.parquet's `message`; the most common one is printed); 2 the sweep, an
        option or --out was refused (nothing was run).
        """
        from echocal.experiments import run_sweep

        results = run_sweep(
            sweep,
            out,
            scheduler=scheduler,
            workers=workers,
            progress=progress and not json_output,
            overwrite=overwrite,
            gate=gate,
        )
        skipped = results.n_cases - results.n_new
        if json_output:
            write_json(_summary_json(results, skipped=skipped))
        else:
            resumed = f", {skipped} already done" if skipped else ""
            output.print(
                f"sweep [bold]{escape(results.spec.name)}[/]: {results.n_new} run(s) computed"
                f"{resumed}; results in {escape(str(out))}/ (runs.parquet, history.parquet)"
            )
            _print_table(results)
        if results.n_failed:
            message, count = results.most_common_failure() or ("?", 0)
            console.print(
                f"[bold red]{results.n_failed} of {len(results.runs)} run(s) failed[/]; "
                f"most common error ({count} run(s)): {escape(message)}",
                highlight=False,
                soft_wrap=True,
            )
            raise typer.Exit(1)

    @sweep_app.command("summary")
    def summary_command(
        out: Annotated[Path, typer.Argument(help="Results folder of a sweep.")],
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the summary as one JSON object.")
        ] = False,
    ) -> None:
        """Summarize a sweep's results: success rate and measurements to the tolerance."""
        from echocal.experiments import load_results

        results = load_results(out)
        if json_output:
            write_json(_summary_json(results))
            return
        _print_table(results)

    @sweep_app.command("check")
    def check_command(
        sweep: Annotated[str, typer.Argument(help=_SWEEP_HELP)],
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the resolved sweep as one JSON object.")
        ] = False,
    ) -> None:
        """Validate a sweep file and every run configuration, and count its runs.

        Nothing is measured: the setup is built at every SNR, the position and the
        starts are checked against the limits, and each method is set up with its
        options and the budget (what `calibrate` checks before its first measurement).
        Every problem is reported at once. Exit code 0: valid; 2: refused.
        """
        from echocal.experiments import expand, load_sweep, spec_hash

        spec = load_sweep(sweep)
        cases = expand(spec)
        if json_output:
            write_json(
                {
                    "n_cases": len(cases),
                    "hash": spec_hash(spec),
                    "spec": spec.model_dump(mode="json"),
                }
            )
            return
        console.print(
            f"sweep [bold]{escape(spec.name)}[/] is valid: {len(cases)} runs "
            f"({len(spec.methods)} method(s), {len(spec.snr_db or [])} SNR(s), "
            f"{len(spec.seed_list)} seed(s)); setup {escape(spec.setup)}"
        )

    @sweep_app.command("list")
    def list_command() -> None:
        """List the built-in sweeps."""
        from echocal.experiments import builtin_sweep_names, load_sweep

        for name in builtin_sweep_names():
            typer.echo(f"{name:16s} {load_sweep(name, check_runs=False).description}")


def _jsonable(value: Any) -> Any:
    import pandas as pd

    if value is None or value is pd.NA:
        return None
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _summary_json(results, *, skipped: int | None = None) -> dict[str, Any]:
    table = results.summary()
    rows = [{k: _jsonable(v) for k, v in row.items()} for row in table.to_dict("records")]
    data: dict[str, Any] = {
        "sweep": results.spec.name,
        "out_dir": str(results.out_dir),
        "hash": results.hash,
        "n_cases": results.n_cases,
        "n_finished": len(results.runs),
        "n_failed": results.n_failed,
        "most_common_failure": _failure_json(results),
        "tolerance_deg": results.spec.tolerance,
        "files": {"runs": str(results.runs_path), "history": str(results.history_path)},
        "summary": rows,
    }
    if skipped is not None:
        data["n_new"], data["n_skipped"] = results.n_new, skipped
    return data


def _failure_json(results) -> dict[str, Any] | None:
    common = results.most_common_failure()
    return None if common is None else {"message": common[0], "runs": common[1]}


def _fmt(value: Any, spec: str = ".3g", *, missing: str = "—") -> str:
    """A table cell; ``missing`` for no value (a milestone no run reached: "never", the
    report's word) and "never" for an infinite expected cost too."""
    from echocal.experiments._report_html import NEVER

    if value is None or (isinstance(value, float) and math.isnan(value)):
        return missing
    if isinstance(value, float) and math.isinf(value):
        return NEVER
    return format(value, spec)


def _print_table(results) -> None:
    from rich.table import Table

    from echocal.experiments._report_html import NEVER, percent

    table = results.summary()
    done = len(results.runs)
    state = "" if done == results.n_cases else f" — INCOMPLETE: {done}/{results.n_cases} runs"
    view = Table(
        title=f"sweep {escape(results.spec.name)}: tolerance {results.spec.tolerance:g}°{state}",
        title_justify="left",
        caption="ok: success rate; to tol / p90: median and 90th percentile of measurements "
        "to the tolerance (successful runs); E(meas): mean measurements / success rate; "
        "err°: median final error [deg]",
        caption_justify="left",
    )
    show_options = bool((table["params"] != "{}").any())
    show_x0 = table["x0_kind"].nunique() > 1 or len(results.spec.x0.points) > 1
    names = ["method", "options", "SNR", "x0", "runs", "ok", "to tol", "p90", "E(meas)", "err°"]
    for name in names:
        if (name == "options" and not show_options) or (name == "x0" and not show_x0):
            continue
        left = name in ("method", "options", "x0")
        view.add_column(name, justify="left" if left else "right", no_wrap=name == "method")
    for row in table.itertuples(index=False):
        method = row.label + (f"@{row.preset}" if isinstance(row.preset, str) else "")
        failed = f" ({row.failed} failed)" if row.failed else ""
        cells = [escape(method)]
        if show_options:
            cells.append("" if row.params == "{}" else escape(row.params))
        cells.append("none" if math.isnan(row.snr_db) else f"{row.snr_db:g}")
        if show_x0:
            cells.append(row.x0_kind)
        cells += [
            f"{row.runs}{failed}",
            percent(row.success_rate),  # as the report and the figures' axes write it
            _fmt(row.median_measurements_to_tol, ".1f", missing=NEVER),
            _fmt(row.p90_measurements_to_tol, ".1f", missing=NEVER),
            _fmt(row.expected_measurements_to_success, ".1f", missing=NEVER),
            _fmt(row.median_error_deg, ".2g"),
        ]
        view.add_row(*cells)
    output.print(view)
