"""``echocal calibrate``: find the orientation of maximum echo on a simulated setup."""

from __future__ import annotations

import inspect
import warnings
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.markup import escape

from echocal.cli._common import console, parse_options, parse_pair, parse_pose, write_json
from echocal.cli._setup_option import SETUP_HELP, SNR_HELP, SPECIMEN_HELP, resolve_setup


def register(app: typer.Typer) -> None:
    """Add ``echocal calibrate`` to ``app``."""

    @app.command("calibrate")
    def calibrate_command(
        setup: Annotated[str, typer.Option(help=SETUP_HELP)] = "thesis",
        method: Annotated[str, typer.Option(help="Calibration method (see `echocal methods`).")] = (
            "auto"
        ),
        x0: Annotated[
            str, typer.Option("--x0", help="Initial guess A,B [deg] in the parameterization.")
        ] = "0,0",
        position: Annotated[
            str | None,
            typer.Option(
                help="X,Y,Z of the probe (mm unless a unit is given); default: the "
                "setup's reference position."
            ),
        ] = None,
        parameterization: Annotated[
            str, typer.Option(help="'tilt' (pole-free gimbal tilts) or 'azimuth-coelevation'.")
        ] = "tilt",
        snr: Annotated[str | None, typer.Option(help=SNR_HELP)] = None,
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = None,
        budget: Annotated[int | None, typer.Option(help="Maximum number of measurements.")] = None,
        max_iter: Annotated[int | None, typer.Option(help="Maximum iterations.")] = None,
        settle: Annotated[
            str,
            typer.Option(
                help="TOL,PATIENCE: stop once the last PATIENCE recommendations lie within "
                "TOL degrees of their mean; 'none' runs to the budget or iteration limit."
            ),
        ] = "0.01,8",
        preset: Annotated[
            str | None, typer.Option(help="Method options preset, e.g. thesis-table-7.")
        ] = None,
        option: Annotated[
            list[str] | None,
            typer.Option(
                "--option",
                help="KEY=VALUE method option, repeatable (see `echocal methods` and the "
                "method's docstring), e.g. --option fine_radius=1 for auto at high SNR.",
            ),
        ] = None,
        search_radius: Annotated[
            float | None,
            typer.Option(
                help="How far from x0 [deg] to search for a lost echo before giving up "
                "(status 4, 'acquisition failed'): auto and acquisition search to 20 by "
                "default; any other method gets this search in front of it."
            ),
        ] = None,
        seed: Annotated[int, typer.Option(help="Seed for noise and randomized methods.")] = 0,
        out: Annotated[Path, typer.Option(help="Folder for result.json and the plots.")] = Path(
            "echocal-out/calibrate"
        ),
        plots: Annotated[bool, typer.Option(help="Save the convergence and path plots.")] = True,
        json_output: Annotated[
            bool, typer.Option("--json", help="Print the result as one JSON object.")
        ] = False,
    ) -> None:
        """Calibrate the orientation at one position and compare with the true optimum."""
        from echocal.calibrate import calibrate
        from echocal.evaluation import evaluate_run
        from echocal.measurement.objective import SourceObjective

        virtual = resolve_setup(setup, specimen=specimen, snr=snr, seed=seed)
        where = parse_pose(position, "--position").position if position else None
        where = virtual.reference_position if where is None else where
        objective = SourceObjective(virtual, where, parameterization=parameterization)
        search = _search_options(method, search_radius)
        extra = parse_options(option, "--option")
        unsettable = sorted(set(extra) & set(_OBJECT_OPTIONS))
        if unsettable:
            raise typer.BadParameter(
                f"--option {', '.join(unsettable)}: takes a Python object, which the command "
                "line cannot give (the source objective supplies it); use the API"
            )
        driver = set(inspect.signature(calibrate).parameters) - {"options"}
        taken = sorted(set(extra) & {*driver, *search})
        if taken:
            raise typer.BadParameter(
                f"--option {', '.join(taken)}: set by its own command-line option "
                "(--budget, --max-iter, --settle, --preset, --seed, --search-radius)"
            )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = calibrate(
                objective,
                method=method,
                x0=parse_pair(x0, "--x0"),
                budget=budget,
                max_iter=max_iter,
                settle=_parse_settle(settle),
                preset=preset,
                rng=seed,
                **search,
                **extra,
            )
        for warning in caught:
            console.print(f"[yellow]warning:[/] {escape(str(warning.message))}")
        evaluation = evaluate_run(virtual, where, result)
        out.mkdir(parents=True, exist_ok=True)
        result.save_json(out / "result.json")
        figures = _save_plots(virtual, where, evaluation, out) if plots else {}
        summary = {
            "setup": virtual.name,
            "position_m": [float(v) for v in where],
            "method": result.method,
            "parameterization": parameterization,
            "names": list(result.names),
            "estimate_deg": [float(v) for v in result.x],
            "truth_deg": [float(v) for v in evaluation.truth],
            "error_deg": evaluation.error,
            "n_measurements": result.n_measurements,
            "acquisition_measurements": result.acquisition_measurements,
            "n_iterations": result.n_iterations,
            "status": result.status,
            "message": result.message,
            "files": {"result": str(out / "result.json"), **figures},
        }
        if json_output:
            write_json(summary)
            return
        names = result.names
        found = result.acquisition_measurements
        search = "" if found is None else f" (echo found after {found})"
        console.print(
            f"[bold]{escape(result.method)}[/] on {escape(virtual.description)}\n"
            f"  estimate  {names[0]} = {result.x[0]:8.3f}°, {names[1]} = {result.x[1]:8.3f}°\n"
            f"  truth     {names[0]} = {evaluation.truth[0]:8.3f}°, "
            f"{names[1]} = {evaluation.truth[1]:8.3f}°\n"
            f"  error     {evaluation.error:.4f}°   measurements {result.n_measurements}"
            f"{search}   iterations {result.n_iterations}\n"
            f"  stopped:  {escape(result.message)}\n"
            f"  saved to  {escape(str(out))}/"
        )


_OBJECT_OPTIONS = ("detector", "noise_model", "history", "bounds", "rng")
"""Method options that take Python objects, not values."""


def _search_options(method: str, radius: float | None) -> dict[str, Any]:
    """calibrate() keywords for ``--search-radius``: the method's own ``max_radius`` if it
    searches, else an acquisition phase in front of it."""
    if radius is None:
        return {}
    from echocal._validate import positive_float
    from echocal.calibrate import Acquisition, get_method
    from echocal.calibrate.auto import AUTO_SEARCH

    radius = positive_float("--search-radius", radius)
    if issubclass(get_method(method), Acquisition):
        return {"max_radius": radius}
    return {"acquire": {"max_radius": radius, **AUTO_SEARCH}}  # auto's search geometry


def _parse_settle(text: str) -> tuple[float, int] | None:
    if text.strip().lower() == "none":
        return None
    parts = [p.strip() for p in text.split(",")]
    try:
        tol, patience = float(parts[0]), int(parts[1])
    except (IndexError, ValueError):
        raise typer.BadParameter(
            f"--settle takes TOL,PATIENCE (degrees, iterations) or 'none'; got {text!r}"
        ) from None
    if len(parts) != 2:
        raise typer.BadParameter(f"--settle takes exactly TOL,PATIENCE; got {text!r}")
    return tol, patience


def _save_plots(virtual, where, evaluation, out: Path) -> dict[str, str]:
    from echocal.evaluation import cost_map
    from echocal.plots import save_figure
    from echocal.plots.calibration import convergence_figure, path_figure

    result = evaluation.result
    label = result.method
    conv = convergence_figure(
        {label: result},
        {label: evaluation.iterate_values / evaluation.optimum_value},
        optimum_value=1.0,
        title=f"{label}: pseudo-energy of the estimate",
    )
    points = np.vstack([result.iterates, evaluation.truth[None, :]])
    span = max(3.0, 1.3 * float(np.max(np.abs(points - evaluation.truth))))
    centre = evaluation.truth
    cmap = cost_map(
        virtual,
        where,
        parameterization=result.parameterization,
        a_range=(centre[0] - span, centre[0] + span),
        b_range=(centre[1] - span, centre[1] + span),
        n=41,
    )
    path = path_figure(
        cmap,
        {label: result},
        x0=result.iterates[0],
        truth=evaluation.truth,
        title=f"{label}: path over the cost map",
    )
    return {
        name: str(save_figure(fig, out / f"{name}.png", formats=("png",), dpi=110)[0])
        for name, fig in (("convergence", conv), ("path", path))
    }
