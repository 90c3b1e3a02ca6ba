"""The thesis's test scenarios (§12), each by name, reproduced and checked, and
echocal's own beyond them (``wall-echoes``: :mod:`echocal.experiments.wall_scenario`).

``scenario-1`` and ``scenario-2`` compare A-scans at two points over the thesis
block (Figs. 7–10).  ``table-1`` … ``table-7`` rerun the calibration studies of
Tables 1–7 on the thesis setup at (10, 0, 22) mm in the thesis's own
parameterization (azimuth, co-elevation), from x0 = (0, 0) for 30 iterations at
30 dB SNR unless the table varies it, with the thesis presets
(:mod:`echocal.calibrate.presets`), over several seeds.

Each scenario writes into its folder::

    findings.json   the thesis's qualitative finding(s), our criterion, agree/disagree, evidence
    summary.md      the same for people, with the tables
    runs.csv/.parquet       one row per run (tables)       | ascans.csv/.parquet (scenarios 1–2)
    summary.csv/.parquet    medians over seeds per configuration
    convergence_*.png/.svg  metric of the estimate vs iteration and vs measurements
    paths_*.png/.svg        paths over the cost-map heat map, x0 and truth marked
    (scenarios 1–2: ascans.png/.svg, scene.png/.svg)

Example::

    from echocal.experiments.scenarios import run_scenario, scenario_names
    result = run_scenario("table-2", "out/table-2", quick=True)
    for finding in result.findings:
        print(finding.agrees, finding.evidence)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from echocal.errors import EchocalValueError
from echocal.experiments import thesis_studies as studies
from echocal.experiments._ascan import ascan_overlay_figure, ascan_study
from echocal.experiments._findings import Finding
from echocal.experiments._output import check_out_dir, write_figure, write_table
from echocal.experiments._runs import (
    Bench,
    RunRecord,
    representative,
    runs_frame,
    summarize_configs,
)
from echocal.experiments._scenario_base import (
    Progress,
    Scenario,
    ScenarioResult,
    _finish,
    _register,
    get_scenario,
    scenario_names,
)
from echocal.experiments.thesis_studies import (
    FULL_SEEDS,
    PARAMETERIZATION,
    QUICK_SEEDS,
    RESCALED_MU,
    TABLE1_STEP_SIZES,
)
from echocal.experiments.wall_scenario import WALL_SCENARIO
from echocal.plots.calibration import convergence_figure, path_figure
from echocal.specimen.builtins import THESIS_MEASUREMENT_POINTS

__all__ = [
    "RESCALED_MU",
    "TABLE1_STEP_SIZES",
    "Scenario",
    "ScenarioResult",
    "get_scenario",
    "run_scenario",
    "scenario_names",
]


def run_scenario(
    name: str,
    out_dir: str | Path,
    *,
    quick: bool = False,
    seed: int = 0,
    overwrite: bool = False,
    progress: Progress | None = None,
) -> ScenarioResult:
    """Run scenario ``name`` and write its files into ``out_dir``.

    quick : fewer seeds and a coarser cost map (for tests); seed : first seed
    (runs use ``seed, seed + 1, …`` for the receiver noise and the method);
    overwrite : allow a folder that already holds files (otherwise DataFileError);
    progress : ``progress(done, total)`` after each run.
    """
    scenario = get_scenario(name)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise EchocalValueError(f"seed must be an integer >= 0; got {seed!r}")
    out = Path(out_dir)
    check_out_dir(out, overwrite=overwrite)
    return scenario.run(scenario, out, quick=quick, seed=seed, progress=progress)


# ------------------------------------------------------------------ A-scan scenarios
def _run_ascans(
    scenario: Scenario,
    out: Path,
    *,
    quick: bool,
    seed: int,
    progress: Progress | None,
    points: Sequence[int],
) -> ScenarioResult:
    from echocal.plots.scene import scene_figure
    from echocal.setups import load_setup

    t0 = time.perf_counter()
    setup = load_setup("thesis", seed=seed)
    where = THESIS_MEASUREMENT_POINTS[list(points)]
    table, samples, poses, finding = ascan_study(setup, where, seed=seed)
    labels = [f"({p[0] * 1e3:g}, {p[1] * 1e3:g}, {p[2] * 1e3:g}) mm" for p in where]
    if progress:
        progress(1, 3)
    overlay = ascan_overlay_figure(
        setup.window.times,
        samples,
        labels,
        (table["expected_tof_us"] * 1e-6).tolist(),
        title=f"{scenario.name}: A-scans at the optimal orientation of each point (SNR "
        f"{setup.receiver.snr_db:g} dB)",
        pulse=setup.pulse,
    )
    figures = {"A-scans (Figs. 8/10)": write_figure(overlay, out, "ascans")}
    scene = scene_figure(
        setup.specimen,
        setup.transducer,
        poses,
        n_rays=20 if quick else 60,
        title=f"{scenario.name}: the two poses over the thesis block (Figs. 7/9)",
    )
    figures["poses over the specimen (Figs. 7/9)"] = write_figure(scene, out, "scene")
    if progress:
        progress(2, 3)
    samples_frame = pd.DataFrame(
        {"time_us": setup.window.times * 1e6}
        | {label: row for label, row in zip(labels, samples, strict=True)}
    )
    files = write_table(table, out, "ascans") + write_table(samples_frame, out, "ascan_samples")
    result = _finish(
        scenario,
        out,
        t0=t0,
        setup=setup.description,
        quick=quick,
        seeds=[seed],
        findings=[finding],
        notes=[
            "Each pose points along the true optimum of its point (normal to the facet below).",
            "Expected times of flight from the closed-form facet planes, τ = 2d/c₀ (eq. 24).",
        ],
        runs=table,
        summary=None,
        tables={"ascans": table},
        files=files,
        figures=figures,
    )
    if progress:
        progress(3, 3)
    return result


def _map_range(records: Sequence[RunRecord], truth: np.ndarray) -> tuple[tuple, tuple]:
    """Cost-map axes [deg] framing the plotted paths and the truth (within the limits)."""
    pts = np.vstack([r.evaluation.result.iterates for r in records] + [truth[None, :]])
    pts = pts[np.all(np.abs(pts - truth) <= (60.0, 40.0), axis=1)]  # diverged far away
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = np.maximum(0.15 * (hi - lo), 2.0)
    lo, hi = np.minimum(lo - pad, truth - 5.0), np.maximum(hi + pad, truth + 5.0)
    lo[1], hi[1] = max(lo[1], -45.0), min(hi[1], 45.0)
    return (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1]))


def _slug(group: str) -> str:
    for greek, latin in (("μ", "mu"), ("λ", "lambda"), ("ε", "eps"), ("η", "eta")):
        group = group.replace(greek, latin)
    keep = "".join(c if c.isascii() and c.isalnum() else "-" for c in group.lower())
    return "-".join(p for p in keep.split("-") if p)[:40]


def _run_table(
    scenario: Scenario,
    out: Path,
    *,
    quick: bool,
    seed: int,
    progress: Progress | None,
    study: Callable[[Bench, bool], studies.Study],
) -> ScenarioResult:
    from echocal.evaluation import cost_map

    t0 = time.perf_counter()
    bench = studies.thesis_bench(seed)
    spec = study(bench, quick)
    seeds = list(range(seed, seed + (QUICK_SEEDS if quick else FULL_SEEDS)))
    total = len(spec.configs) * len(seeds) + 1
    done = [0]

    def tick() -> None:
        done[0] += 1
        if progress:
            progress(done[0], total)

    records = bench.run_all(spec.configs, seeds, progress=tick)
    runs = runs_frame(records, scenario.name)
    summary = summarize_configs(runs)
    chosen = representative(records)
    truth = bench.truth()
    a_range, b_range = _map_range(list(chosen.values()), truth)
    cmap = cost_map(
        bench.setup,
        bench.position,
        parameterization=PARAMETERIZATION,
        a_range=a_range,
        b_range=b_range,
        n=25 if quick else 61,
    )
    tick()
    figures: dict[str, list[Path]] = {}
    findings: list[Finding] = []
    for group, checks in spec.checks.items():
        picked = {k[1]: r for k, r in chosen.items() if k[0] == group}
        results = {label: r.evaluation.result for label, r in picked.items()}
        values = {
            label: r.evaluation.iterate_values / r.evaluation.optimum_value
            for label, r in picked.items()
        }
        conv = convergence_figure(
            results,
            values,
            optimum_value=1.0,
            ylabel="pseudo-energy / optimum (noiseless)",
            title=f"{scenario.name} [{group}]: pseudo-energy of the estimate "
            f"(median-error run of {len(seeds)} seeds)",
        )
        starts = {tuple(r.config.x0) for r in picked.values()}
        paths = path_figure(
            cmap,
            results,
            x0=sorted(starts),  # one marker per initial guess (table-5 has several)
            truth=truth,
            title=f"{scenario.name} [{group}]: paths over the cost map",
        )
        slug = _slug(group)
        figures[f"convergence [{group}]"] = write_figure(conv, out, f"convergence_{slug}")
        figures[f"paths [{group}]"] = write_figure(paths, out, f"paths_{slug}")
        group_summary = summary[summary["group"] == group].reset_index(drop=True)
        findings += [check(group_summary, group) for check in checks]
    files = write_table(runs, out, "runs") + write_table(summary, out, "summary")
    shown = [
        "group",
        "label",
        "seeds",
        "final_error_deg",
        "n_measurements",
        "measurements_to_0.5deg",
        "measurements_to_0.1deg",
        "iterations_to_90pct",
        "final_metric_rel",
        "oscillations",
    ]
    return _finish(
        scenario,
        out,
        t0=t0,
        setup=f"{bench.setup.description}; position (10, 0, 22) mm; truth "
        f"({truth[0]:.2f}°, {truth[1]:.2f}°) in (azimuth, co-elevation); x0 (0, 0) unless "
        "varied; 30 iterations",
        quick=quick,
        seeds=seeds,
        findings=findings,
        notes=spec.notes,
        runs=runs,
        summary=summary,
        tables={"summary": summary[shown]},
        files=files,
        figures=figures,
    )


def _ascans(points: Sequence[int]) -> Callable[..., ScenarioResult]:
    def run(scenario: Scenario, out: Path, **kw: object) -> ScenarioResult:
        return _run_ascans(scenario, out, points=points, **kw)  # type: ignore[arg-type]

    return run


def _table(study: Callable[[Bench, bool], studies.Study]) -> Callable[..., ScenarioResult]:
    def run(scenario: Scenario, out: Path, **kw: object) -> ScenarioResult:
        return _run_table(scenario, out, study=study, **kw)  # type: ignore[arg-type]

    return run


for _scenario in (
    Scenario(
        "scenario-1",
        "A-scans at (−10, 0, 22) mm vs (0, 0, 20) mm",
        "§12.1.1.1, Figs. 7–8",
        "The probe over the thesis block at two points, each at its optimal orientation; the "
        "two total fields overlaid.",
        _ascans((0, 1)),
    ),
    Scenario(
        "scenario-2",
        "A-scans at (10, 0, 22) mm vs (0, 0, 20) mm",
        "§12.1.1.2, Figs. 9–10",
        "As scenario 1, at the right facet's point instead of the left's.",
        _ascans((2, 1)),
    ),
    Scenario(
        "table-1",
        "gradient ascent: step sizes",
        "§12.2.1.1, Table 1, Figs. 11–12",
        "Finite-difference gradient ascent for several step sizes μ.",
        _table(studies.table_1),
    ),
    Scenario(
        "table-2",
        "gradient ascent with momentum 0.65–0.85",
        "§12.2.1.2, Table 2, Figs. 13–14",
        "Momentum η ∈ {0.65, 0.7, 0.8, 0.85} at a fixed step size.",
        _table(studies.table_2),
    ),
    Scenario(
        "table-3",
        "Nesterov accelerated gradient vs momentum",
        "§12.2.1.2, Table 3, Figs. 15–16",
        "Nesterov with the momentum values of Table 2, beside plain momentum.",
        _table(studies.table_3),
    ),
    Scenario(
        "table-4",
        "SPSA at several SNRs",
        "§12.2.1.3, Table 4, Figs. 17–18",
        "SPSA (ρ = 0.602, γ = 0.101, c′ = 1, A = 5, ε = 0.1) at decreasing SNR.",
        _table(studies.table_4),
    ),
    Scenario(
        "table-5",
        "Newton from near and far initial guesses",
        "§12.2.1.4, Table 5, Figs. 19–20",
        "Newton's method (9-point FD Hessian) from initial guesses at increasing distance.",
        _table(studies.table_5),
    ),
    Scenario(
        "table-6",
        "quasi-Newton scaling factors λ",
        "§12.2.1.5, Table 6, Figs. 21–22",
        "BFGS quasi-Newton with B₀ = λ I for λ ∈ {0.1, 0.5, 0.8}.",
        _table(studies.table_6),
    ),
    Scenario(
        "table-7",
        "all methods compared",
        "§12.2.1.6, Table 7, Figs. 23–24",
        "The six thesis methods under the same scenario (Table 7 presets), plus echocal's "
        "model-based and auto methods (beyond the thesis).",
        _table(studies.table_7),
    ),
):
    _register(_scenario)

_register(WALL_SCENARIO)  # beyond the thesis: echocal.experiments.wall_scenario
