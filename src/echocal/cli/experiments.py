"""``echocal scenario list|run``, ``echocal report`` and ``echocal demo``: thesis experiments.

Thin layer over :mod:`echocal.experiments.scenarios`, :mod:`echocal.experiments.report`
and :mod:`echocal.experiments.demo`.  Existing result folders are refused unless
``--overwrite``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from echocal.cli._common import console, write_json


def register(app: typer.Typer) -> None:
    """Add ``scenario``, ``report`` and ``demo`` to ``app``."""
    group = typer.Typer(
        help="Thesis scenarios (§12): A-scan comparisons and Tables 1–7, with findings.",
        no_args_is_help=True,
    )
    app.add_typer(group, name="scenario")

    @group.command("list")
    def list_command(
        json_output: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    ) -> None:
        """List the thesis scenarios."""
        from echocal.experiments.scenarios import get_scenario, scenario_names

        items = [get_scenario(n) for n in scenario_names()]
        if json_output:
            write_json(
                {
                    "scenarios": [
                        {"name": s.name, "title": s.title, "thesis": s.thesis} for s in items
                    ]
                }
            )
            return
        for s in items:
            typer.echo(f"{s.name:12s} {s.title}  ({s.thesis})")

    @group.command("run")
    def run_command(
        name: Annotated[str, typer.Argument(help="Scenario name (see `scenario list`) or 'all'.")],
        out: Annotated[
            Path, typer.Option(help="Parent folder; each scenario writes OUT/NAME.")
        ] = Path("echocal-out/scenarios"),
        quick: Annotated[bool, typer.Option(help="Fewer seeds, coarser cost maps.")] = False,
        seed: Annotated[int, typer.Option(help="First seed (noise and methods).")] = 0,
        overwrite: Annotated[
            bool, typer.Option(help="Replace the results in an existing folder.")
        ] = False,
        json_output: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    ) -> None:
        """Run a thesis scenario (or all) and check the thesis's findings."""
        from echocal.experiments.scenarios import get_scenario, run_scenario, scenario_names

        names = scenario_names() if name == "all" else [get_scenario(name).name]
        from echocal.experiments._output import check_out_dir

        for n in names:  # refuse before running anything
            if (out / n).is_dir() and any((out / n).iterdir()) and not overwrite:
                check_out_dir(out / n, overwrite=False)
        report = []
        for n in names:
            with console.status(f"running {n} ..."):
                result = run_scenario(n, out / n, quick=quick, seed=seed, overwrite=overwrite)
            report.append(
                {
                    "scenario": n,
                    "out_dir": str(result.out_dir),
                    "wall_time_s": result.wall_time,
                    "findings": [f.to_dict() for f in result.findings],
                }
            )
            if not json_output:
                console.print(f"[bold]{n}[/] → {result.out_dir} ({result.wall_time:.1f} s)")
                for f in result.findings:
                    mark = "[green]agrees[/]" if f.agrees else "[red]does not agree[/]"
                    group_text = f" [{f.group}]" if f.group else ""
                    why = f"\n    why: {escape(f.why)}" if f.why else ""
                    console.print(
                        f"  {mark}{escape(group_text)} {escape(f.claim)}\n    {escape(f.evidence)}"
                        + why,
                        highlight=False,
                    )
        if json_output:
            write_json({"scenarios": report})

    @app.command("report")
    def report_command(
        results: Annotated[
            list[Path],
            typer.Argument(
                help="Result folders (of calibrate --out, scan --out, scenario run or sweep "
                "run) or position-scan files (of import or record-scan)."
            ),
        ],
        out: Annotated[Path, typer.Option(help="The HTML page to write.")] = Path("report.html"),
        overwrite: Annotated[bool, typer.Option(help="Replace an existing page.")] = False,
    ) -> None:
        """Write one self-contained HTML report of calibration, scan, scenario and sweep results."""
        from echocal.cli._common import check_out_file
        from echocal.errors import DataFileError
        from echocal.experiments.report import write_report

        check_out_file(out, suffix=".html", what="an HTML page")
        if out.exists() and not overwrite:
            raise DataFileError(f"{str(out)!r} exists; choose another --out or pass --overwrite")
        path = write_report(results, out)
        console.print(f"report written to {path}")

    @app.command("demo")
    def demo_command(
        out: Annotated[Path, typer.Option(help="Folder for the results and report.html.")] = Path(
            "echocal-out/demo"
        ),
        quick: Annotated[bool, typer.Option(help="Fewer seeds (a smoke test).")] = False,
        overwrite: Annotated[
            bool, typer.Option(help="Replace the results in an existing folder.")
        ] = False,
    ) -> None:
        """The main job: thesis Table 7 + a short sweep → OUT/report.html (about a minute)."""
        from echocal.experiments.demo import run_demo

        run_demo(out, quick=quick, progress=True, overwrite=overwrite, console=console)
