"""Pieces that every source of ``echocal calibrate`` shares (simulated, replayed, a rig):
the parsed run options, output files, exit codes, the report and the final A-scan.

Both command modules (:mod:`echocal.cli.calibrate` and its measured-source half) import
from here; neither imports the other's internals.
"""

from __future__ import annotations

import inspect
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import typer
from rich.markup import escape

from echocal.cli._common import (
    console,
    output,
    parse_options,
    parse_pose,
    write_json,
)
from echocal.io import check_out_dir


def _check_source_options(
    replay: Path | None, replay_mode: str | None, instrument: str | None, timeout: float | None
) -> None:
    """Refuse ``--replay-mode`` without ``--replay`` and ``--timeout`` without ``--instrument``."""
    from echocal.errors import EchocalValueError

    if replay_mode is not None and replay is None:
        raise EchocalValueError("--replay-mode applies only with --replay FILE")
    if timeout is not None and instrument is None:
        raise EchocalValueError("--timeout applies only with --instrument HOST:PORT")


@dataclass(frozen=True)
class _Run:
    """The method and run options of one ``echocal calibrate``, parsed and checked."""

    method: str
    budget: int | None
    max_iter: int | None
    settle: tuple[float, int] | None
    preset: str | None
    search: dict[str, Any]
    extra: dict[str, Any]
    run_keywords: dict[str, Any]

    @classmethod
    def parse(
        cls,
        method: str,
        budget: int | None,
        max_iter: int | None,
        settle: str,
        preset: str | None,
        option: list[str] | None,
        search_radius: float | None,
        final_measure: bool = True,
    ) -> _Run:
        """Check --method, --option, --search-radius, --settle and --no-final-measure
        (before any measurement)."""
        from echocal.errors import EchocalValueError

        search = _search_options(method, search_radius)
        extra = parse_options(option, "--option")
        run_keywords = _check_options(method, extra, search)
        if not final_measure:
            if "final_check" in run_keywords:
                raise EchocalValueError(
                    "--no-final-measure and --option final_check=N both set the final "
                    "measurements at the estimate; give one"
                )
            run_keywords["final_check"] = 0
        return cls(
            method, budget, max_iter, _parse_settle(settle), preset, search, extra, run_keywords
        )

    def provenance(
        self,
        opened: Any,
        result: Any,
        *,
        setup: str | None,
        source: dict[str, Any],
        position: Any,
        seed: int | None,
        gate: Any = None,
    ) -> dict[str, Any] | None:
        """The provenance record of ``result`` (None without an ``opened`` record): the setup
        and its digest, the source, position [m], seed, the gate the metric was computed in
        (none: the whole recording), method with every option."""
        if opened is None:
            return None
        from echocal.setup_digest import setup_digest

        return opened.finish(
            setup=None if setup is None else setup_digest(setup),
            source=source,
            position_m=[float(v) for v in position],
            seed=seed,
            gate=None if gate is None else gate.describe(),
            method={
                "name": result.method,
                "options": result.options,
                "budget": self.budget,
                "max_iter": self.max_iter,
                "settle": self.settle,
                "preset": self.preset,
                "parameterization": result.parameterization,
                "x0": [float(v) for v in result.iterates[0]],
            },
        )

    def __call__(self, objective: Any, x0: tuple[float, float], rng: Any) -> Any:
        """Run the calibration; its warnings become one ``warning:`` line each on stderr."""
        from echocal.calibrate import calibrate

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = calibrate(
                objective,
                method=self.method,
                x0=x0,
                budget=self.budget,
                max_iter=self.max_iter,
                settle=self.settle,
                preset=self.preset,
                rng=rng,
                **self.run_keywords,
                **self.search,
                **{k: v for k, v in self.extra.items() if k not in self.run_keywords},
            )
        for warning in caught:
            console.print(f"[yellow]warning:[/] {escape(str(warning.message))}")
        return result


CALIBRATE_FILES = (
    "result.json",
    "summary.json",
    "convergence.png",
    "path.png",
    "partial_log.json",
    "ascan.nc",
    "ascan.png",
)
"""What ``echocal calibrate`` writes in --out."""


def prepare_out(out: Path) -> None:
    """Make --out ready for a result: create it and remove what an earlier calibration left
    there (the run began only after :func:`~echocal.io.refuse_existing_output` accepted
    --out: empty, or --overwrite given), so no stale plot stays beside the new result."""
    check_out_dir(out, overwrite=True, own_files=CALIBRATE_FILES)


EXIT_NO_ECHO = 1
"""Exit status of a calibration that found no echo (result files written all the same)."""
EXIT_NOT_CONVERGED = 3
"""Exit status of a calibration that returned an estimate without converging."""
EXIT_AT_LIMIT = 4
"""Exit status of a calibration whose estimate lies on the positioner's angle limits."""


def found_echo(result: Any) -> bool:
    """Whether ``result`` has an estimate of anything (its status is not a no-echo one)."""
    from echocal.calibrate.result import NO_ECHO_STATUSES

    return result.status not in NO_ECHO_STATUSES


def exit_code(result: Any) -> int:
    """The exit status of ``echocal calibrate`` for ``result`` (see its ``--help``)."""
    if result.success:
        return 0
    if not found_echo(result):
        return EXIT_NO_ECHO
    return EXIT_AT_LIMIT if result.status == 8 else EXIT_NOT_CONVERGED


def calibration_summary(
    result: Any,
    out: Path,
    *,
    context: dict[str, Any],
    parameterization: str,
    truth_deg: list[float] | None = None,
    error_deg: float | None = None,
    figures: dict[str, str] | None = None,
) -> dict[str, Any]:
    """The ``--json`` summary of a calibration: ``context`` (what was calibrated: setup,
    seed, source, position, ...) first, then what every source reports alike — the
    estimate [deg] (None without an echo), the truth and error [deg] (a simulation's;
    None otherwise), the measurement counts, the searched passes, status, exit code and
    the files written under ``out`` (``result.json`` and ``figures``)."""
    found = found_echo(result)
    return {
        **context,
        "method": result.method,
        "parameterization": parameterization,
        "names": list(result.names),
        "success": result.success,
        "estimate_deg": [float(v) for v in result.x] if found else None,
        "truth_deg": truth_deg,
        "error_deg": error_deg if found else None,
        "n_measurements": result.n_measurements,
        "acquisition_measurements": result.acquisition_measurements,
        "search_passes_deg": result.search_passes,
        "search_snr_db": result.search_snr_db,
        "posterior_search": result.posterior_search,
        "final_value": result.final_value,
        "bench_time_s": result.bench_time,
        "bench_time_saved_s": result.bench_time_saved,
        "bench_uncertainty_deg": result.bench_uncertainty,
        "uncertainty_deg": result.uncertainty if found else None,
        "uncertainty_level": result.uncertainty_level,
        "false_alarms": result.false_alarms,
        "n_iterations": result.n_iterations,
        "status": result.status,
        "message": result.message,
        "exit_code": exit_code(result),
        "files": {"result": str(out / "result.json"), **(figures or {})},
    }


def _report(
    summary: dict[str, Any],
    result: Any,
    out: Path,
    json_output: bool,
    print_estimate: Callable[[], None],
) -> None:
    """Save ``summary`` as ``summary.json`` in ``out`` (what was calibrated, the estimate,
    and on a simulator the truth and the error: the report shows them), print it
    (``--json``), the estimate or the failure; exit with :func:`exit_code` (0 only for a
    converged run)."""
    write_json(summary, out / "summary.json")
    code = exit_code(result)
    if json_output:
        write_json(summary)
    elif code == EXIT_NO_ECHO:
        _print_failure(result, out)
    else:
        print_estimate()
        if code:
            console.print(
                f"[yellow]warning:[/] not converged (status {result.status}): "
                f"{escape(result.message)}; the estimate is the run's last recommendation"
            )
    if code:
        raise typer.Exit(code=code)


def _print_estimate(result: Any, evaluation: Any, virtual: Any, out: Path) -> None:
    names = result.names
    found = result.acquisition_measurements
    search = "" if found is None else f" (echo found after {found})"
    output.print(
        f"[bold]{escape(result.method)}[/] on {escape(virtual.description)}\n"
        f"  estimate  {names[0]} = {result.x[0]:8.3f}°, {names[1]} = {result.x[1]:8.3f}°"
        f"{_radius(result)}\n"
        f"  truth     {names[0]} = {evaluation.truth[0]:8.3f}°, "
        f"{names[1]} = {evaluation.truth[1]:8.3f}°\n"
        f"  error     {evaluation.error:.4f}°   measurements {result.n_measurements}"
        f"{search}   iterations {result.n_iterations}{_bench_line(result)}\n"
        f"  stopped:  {escape(result.message)}\n"
        f"  saved to  {escape(str(out))}/"
    )


def _radius(result: Any) -> str:
    """``   within 0.012° (90 %)``: the uncertainty the run reported, else ``""``."""
    radius = getattr(result, "uncertainty", None)
    if radius is None:
        return ""
    return f"   within {radius:.3g}° ({result.uncertainty_level:.0%})"


def _bench_line(result: Any) -> str:
    """``   bench time 12.3 s`` when the source reported one (a simulated bench), with the
    time a motion-aware order saved when there is one, else ``""``."""
    spent = getattr(result, "bench_time", None)
    saved = getattr(result, "bench_time_saved", None)
    line = "" if spent is None else f"   bench time {spent:.3g} s"
    return line if saved is None else f"{line} (motion-aware order saved {saved:.3g} s)"


def _print_failure(result: Any, out: Path) -> None:
    output.print(
        f"[bold red]no echo found[/] ({escape(result.method)}, "
        f"{result.n_measurements} measurements{_bench_line(result)}): "
        f"{escape(result.message)}.\n"
        "  Nothing was calibrated.  Start nearer the echo (--x0), search farther "
        "(--search-radius) or check the setup (position, SNR).\n"
        f"  saved to  {escape(str(out))}/ (status {result.status})"
    )


_OWN_OPTION = {
    "budget": "--budget",
    "max_iter": "--max-iter",
    "settle": "--settle",
    "preset": "--preset",
    "rng": "--seed",
    "acquire": "--search-radius",
    "x0": "--x0",
    "method": "--method",
    "objective": "--setup and --position",
}
"""calibrate() keywords that have a command-line option of their own."""

_RUN_KEYWORDS = ("xtol", "final_check")
"""calibrate() keywords with no option of their own, accepted by --option."""

_API_ONLY = {
    "history": "is a warm start from earlier measurements (arrays of their points and "
    "values), which the command line cannot pass; use the Python API "
    "(calibrate(objective, 'model-based', history=(points, values)))",
    "detector": "is the source objective's echo detector, supplied automatically; to "
    "replace it with another Python callable use the Python API",
    "noise_model": "is the source objective's live noise estimate, supplied automatically; "
    "to replace it with another Python callable use the Python API",
    "lobe_template": "is the simulated probe's lobe, supplied automatically from the setup "
    "(none where the lobe peaks off normal incidence or has a side lobe below half its "
    "peak); to replace or turn it off (lobe_template=None) use the Python API",
    "normal_echo": "is the simulated probe's echo at normal incidence, supplied "
    "automatically from the setup (for the simulator measured with its own pulse); to "
    "replace or turn it off (normal_echo=None) use the Python API",
    "replan": "is the source objective's search plan for the echo it predicts against the "
    "measured noise, supplied automatically; to turn it off give --option fine_radius=3 "
    "(or set passes), to replace it use the Python API",
    "callback": "is a Python function called after each iteration; use the Python API",
    "bounds": "are the positioner's angle limits, taken from the setup",
}
"""Options the command line cannot give, and why."""


def _check_options(method: str, extra: dict[str, Any], search: dict[str, Any]) -> dict[str, Any]:
    """Refuse ``--option`` names the method does not take (naming the valid ones and the
    nearest), those set by their own option, and those only Python can give; return the
    run keywords (xtol, final_check) among them."""
    from echocal.calibrate import calibrate, get_method
    from echocal.calibrate._options import accepted_options, suggestion
    from echocal.errors import EchocalValueError, UnknownNameError

    accepted = accepted_options(get_method(method))  # an unknown method lists the valid ones
    driver = set(inspect.signature(calibrate).parameters) - {"options"}
    valid = sorted(accepted - set(_API_ONLY) - set(search))
    run: dict[str, Any] = {}
    for key, value in extra.items():
        if key in search:
            raise EchocalValueError(f"--option {key}: set by --search-radius; give it once")
        if key in _OWN_OPTION:
            raise EchocalValueError(
                f"--option {key}: set by its own option {_OWN_OPTION[key]}; use that instead"
            )
        if key in _API_ONLY:
            raise EchocalValueError(f"--option {key}: {key} {_API_ONLY[key]}")
        if key in _RUN_KEYWORDS:
            run[key] = value
        elif key in driver or key not in accepted:
            raise UnknownNameError(
                f"--option {key}: unknown option of method {method!r}"
                f"{suggestion(key, [*valid, *_RUN_KEYWORDS])}; valid: {', '.join(valid)} "
                f"(see `echocal methods {method}`), and the run keywords "
                f"{', '.join(_RUN_KEYWORDS)}"
            )
    return run


def _parse_position(text: str) -> Any:
    """``--position X,Y,Z`` [m] (mm unless a unit is given); refuses orientation angles."""
    from echocal.errors import EchocalValueError

    if len(text.split(",")) != 3:
        raise EchocalValueError(
            "--position takes X,Y,Z of the probe (lengths in mm unless a unit is given), "
            "without angles: the orientation is what calibrate finds (give its start with "
            f"--x0 A,B); got {text!r}"
        )
    return parse_pose(text, "--position").position


def _search_options(method: str, radius: float | None) -> dict[str, Any]:
    """calibrate() keywords for ``--search-radius``: the method's own ``max_radius`` if it
    searches, else an acquisition phase in front of it."""
    if radius is None:
        return {}
    from echocal._validate import capped_float
    from echocal.calibrate import Acquisition, get_method
    from echocal.calibrate.acquisition import _CAP_WHY, MAX_SEARCH_RADIUS
    from echocal.calibrate.auto import AUTO_SEARCH

    radius = capped_float("--search-radius", radius, MAX_SEARCH_RADIUS, _CAP_WHY)
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


def save_final_ascan(objective: Any, result: Any, out: Path, plots: bool) -> dict[str, str]:
    """Save the A-scan measured at the estimate: ``out/ascan.nc`` (echocal's NetCDF schema,
    see docs/netcdf-schema.md) and, with ``plots``, ``out/ascan.png``.

    It is the driver's final measurement at the estimate (``final_check``, counted in the
    result's measurements) when the run made one; otherwise (``--option final_check=0``,
    or no budget left for it) the estimate is measured once more here, through the
    objective's source (a rig moves there), not counted: the file's summary says which.
    Nothing is measured or written when no echo was found.  Returns name -> path.
    """
    if not found_echo(result):
        return {}
    from echocal.ascan import save_ascan
    from echocal.measurement.objective import ascan_metric
    from echocal.signal.window import RecordingWindow

    scan = objective.last_scan if result.final_value is not None else None
    counted = scan is not None
    if scan is None:
        scan = objective.source.measure(objective.pose(*result.x))
    gate = getattr(objective, "gate", None)
    value = ascan_metric(
        scan, objective.metric, objective.pulse, objective.window_length, gate=gate
    )
    summary = {
        "estimate_deg": [float(v) for v in result.x],
        "names": list(result.names),
        "parameterization": result.parameterization,
        "metric": objective.metric,
        "gate": None if gate is None else gate.describe(),
        "value": float(value),
        "counted": counted,
        "note": "the run's final measurement at the estimate (in n_measurements)"
        if counted
        else "measured once at the estimate after the run; not in n_measurements",
    }
    files = {
        "ascan": str(
            save_ascan(
                scan,
                out / "ascan.nc",
                summary=summary,
                title="echocal A-scan measured at the calibration's estimate",
            )
        )
    }
    if plots:  # matplotlib is imported only to draw (--no-plots: not at all)
        from echocal.plots import plot_ascan

        window = RecordingWindow(fs=scan.fs, start=scan.start_time, n_samples=scan.n_samples)
        a, b = result.x
        fig = plot_ascan(
            scan.samples,
            window,
            pulse=objective.pulse,
            gates=() if gate is None else (gate,),
            gate=_energy_gate(
                scan.samples, window, objective, None if gate is None else gate.apply
            ),
            gate_label="pseudo-energy window",
            title=f"A-scan at the estimate ({result.names[0]} {a:.3f}°, "
            f"{result.names[1]} {b:.3f}°)",
        )
        files["ascan_plot"] = save_pngs({"ascan": fig}, out)["ascan"]
    return files


def _energy_gate(samples: Any, window: Any, objective: Any, gated: Any = None) -> Any:
    """The pseudo-energy's window (the gate its metric sums over: centred on the matched
    filter's peak — inside the measurement gate, ``gated(samples, window)``, when there is
    one — ``window_length`` or 2 pulse durations wide), its bar drawn at the detector's
    threshold (:data:`~echocal.constants.ECHO_THRESHOLD` σ) over the noise σ."""
    from echocal.constants import ECHO_THRESHOLD
    from echocal.signal.detection import shared_detector
    from echocal.signal.noise import scan_noise_sigma
    from echocal.signal.processing import Gate, time_of_flight

    pulse = objective.pulse
    width = objective.window_length or 2.0 * pulse.duration
    inside = samples if gated is None else gated(samples, window)
    tof = float(time_of_flight(inside, window, pulse))
    sigma, _ = scan_noise_sigma(samples)
    level = 0.0
    if sigma:
        detector = shared_detector(pulse, float(window.fs), int(window.n_samples))
        level = detector.threshold_amplitude(sigma, ECHO_THRESHOLD)
    return Gate(start=tof - width / 2, width=width, threshold=level, absolute=True)


def save_pngs(figures: dict[str, Any], out: Path) -> dict[str, str]:
    """Write each figure as ``out/<name>.png`` (atomically); return name -> path."""
    from echocal.plots import save_figure

    return {
        name: str(save_figure(fig, out / f"{name}.png", formats=("png",), dpi=110)[0])
        for name, fig in figures.items()
    }
