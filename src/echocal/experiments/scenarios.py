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
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from echocal.errors import EchocalValueError
from echocal.experiments import _findings as fnd
from echocal.experiments._ascan import ascan_overlay_figure, ascan_study
from echocal.experiments._findings import Finding
from echocal.experiments._output import check_out_dir, write_figure, write_table
from echocal.experiments._runs import (
    Bench,
    RunConfig,
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

PARAMETERIZATION = "azimuth-coelevation"
"""The thesis's parameterization: every table scenario runs in it."""

THESIS_MU = 0.05
"""The thesis's step size μ (Tables 2, 3, 5, 6, 7) on energy normalized to a peak of ~1."""

TABLE1_STEP_SIZES = (0.05, 0.5, 2.0, 5.0, 20.0)
"""Step sizes μ of ``table-1``: the thesis's 0.05 and multiples ×10, ×40, ×100, ×400.

The thesis does not list its step sizes.  On our setup (energy normalized to ~1,
angles in degrees, main lobe ±8° at half energy) the gradient is ~0.1 per degree
near x0, so μ = 0.05 moves the estimate ~0.005° per iteration: it crawls.  The
multiples span crawling to the largest step that stays stable; μ ≳ 50 jumps out
of the main lobe (measured: final errors of 14–39°)."""

RESCALED_MU = 5.0
"""μ of the "rescaled" groups of tables 2 and 3: 100 × the thesis's 0.05, the largest
``table-1`` value that never diverged in our runs (see :data:`TABLE1_STEP_SIZES`)."""

FULL_SEEDS = 7
QUICK_SEEDS = 2


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


# ------------------------------------------------------------------ table scenarios
@dataclass(frozen=True)
class _Study:
    """The configurations of a table scenario, its checks per group and its notes."""

    configs: list[RunConfig]
    checks: dict[str, list[Callable[[pd.DataFrame, str], Finding]]]
    notes: list[str]


def _thesis_bench(seed: int) -> Bench:
    from echocal.setups import load_setup

    setup = load_setup("thesis", seed=seed)
    return Bench(setup, setup.reference_position, PARAMETERIZATION)


def _fmt(v: float) -> str:
    return f"{v:g}"


def _study_table1(bench: Bench, quick: bool) -> _Study:
    group = "step sizes"
    configs = [
        RunConfig(
            group=group,
            label=f"μ = {_fmt(mu)}",
            method="gradient",
            parameter="mu",
            value=mu,
            preset="thesis-table-1",
            options={"mu": mu},
        )
        for mu in TABLE1_STEP_SIZES
    ]
    return _Study(
        configs,
        {
            group: [
                lambda s, g: fnd.faster_with_order(
                    s, claim="larger step sizes converge faster", group=g, increasing=True
                ),
                lambda s, g: fnd.reaches_truth(
                    s,
                    claim="with the largest step size the estimate reaches the true solution "
                    "within the 30 iterations",
                    group=g,
                    tol=0.5,
                ),
            ]
        },
        [
            "Step sizes: the thesis's μ = 0.05 and ×10, ×40, ×100, ×400 (the thesis does not "
            "list its values). μ = 0.05 crawls on our energy/degree scale; μ ≳ 50 leaves the "
            "main lobe. See TABLE1_STEP_SIZES.",
            "In (azimuth, co-elevation) the azimuth gradient vanishes at the pole x0 = (0, 0) "
            "and stays small near the optimum (co-elevation 6°), so the azimuth converges slowly.",
        ],
    )


def _momentum_groups() -> list[tuple[str, float]]:
    return [(f"thesis μ = {_fmt(THESIS_MU)}", THESIS_MU), (f"μ = {_fmt(RESCALED_MU)}", RESCALED_MU)]


_ETAS = (0.65, 0.7, 0.8, 0.85)
_MU_NOTE = (
    f"Two groups: the thesis's μ = {_fmt(THESIS_MU)} (Table 2), which crawls on our scale, and "
    f"μ = {_fmt(RESCALED_MU)} (RESCALED_MU, the largest stable table-1 step), where the "
    "momentum dynamics show within 30 iterations."
)


def _study_table2(bench: Bench, quick: bool) -> _Study:
    configs, checks = [], {}
    for group, mu in _momentum_groups():
        for eta in _ETAS:
            configs.append(
                RunConfig(
                    group=group,
                    label=f"momentum {_fmt(eta)}",
                    method="momentum",
                    parameter="momentum",
                    value=eta,
                    preset="thesis-table-2",
                    options={"mu": mu, "momentum": eta},
                )
            )
        checks[group] = [
            lambda s, g: fnd.faster_but_oscillates(
                s, claim="larger momentum converges faster but oscillates", group=g
            )
        ]
    return _Study(configs, checks, [_MU_NOTE])


def _study_table3(bench: Bench, quick: bool) -> _Study:
    configs, checks = [], {}
    for group, mu in _momentum_groups():
        for method in ("momentum", "nesterov"):
            for eta in _ETAS:
                configs.append(
                    RunConfig(
                        group=group,
                        label=f"{method} {_fmt(eta)}",
                        method=method,
                        parameter="momentum",
                        value=eta,
                        # each method's own preset (both normalize the energy)
                        preset="thesis-table-3" if method == "nesterov" else "thesis-table-2",
                        options={"mu": mu, "momentum": eta},
                    )
                )
        checks[group] = [
            lambda s, g: fnd.less_oscillation(
                s,
                claim="Nesterov oscillates less than momentum at high momentum",
                group=g,
                high=("0.8", "0.85"),
            )
        ]
    return _Study(configs, checks, [_MU_NOTE, "Momentum runs repeated here as the reference."])


def _study_table4(bench: Bench, quick: bool) -> _Study:
    snrs = (30.0, 10.0) if quick else (30.0, 20.0, 10.0, 0.0)
    groups = [
        ("thesis gains (ε = 0.1, c′ = 1)", {}),
        ("Spall-calibrated ε", {"eps": None}),
    ]
    configs, checks = [], {}
    for group, extra in groups:
        for snr in snrs:
            configs.append(
                RunConfig(
                    group=group,
                    label=f"SNR {_fmt(snr)} dB",
                    method="spsa",
                    parameter="snr_db",
                    value=snr,
                    preset="thesis-table-4",
                    options=extra,
                    snr_db=snr,
                )
            )
        checks[group] = [
            lambda s, g: fnd.stable_but_less_accurate(
                s, claim="SPSA stays stable at lower SNR but is less accurate", group=g
            )
        ]
    return _Study(
        configs,
        checks,
        [
            "The receiver's noise σ is fixed by the SNR of the reference echo (DESIGN.md).",
            "Second group: ε calibrated by Spall's rule (first step ≈ 0.5°), other gains as "
            "Table 4.",
        ],
    )


_NEWTON_DISTANCES = (2.0, 4.0, 12.0, 20.0, 30.0)
_NEAR_MAX = 6.0


def _study_table5(bench: Bench, quick: bool) -> _Study:
    truth = bench.truth()
    starts = [((0.0, 0.0), "x0 = (0, 0) (thesis)")]
    for d in _NEWTON_DISTANCES:
        # along the meridian through the optimum: the angular distance is exactly d
        starts.append(((float(truth[0]), float(truth[1] + d)), f"{_fmt(d)}° from optimum"))
    configs, checks = [], {}
    for group, mu in ((f"thesis μ = {_fmt(THESIS_MU)}", THESIS_MU), ("full step μ = 1", 1.0)):
        for x0, label in starts:
            configs.append(
                RunConfig(
                    group=group,
                    label=label,
                    method="newton",
                    parameter="x0",
                    value=f"({x0[0]:.1f}, {x0[1]:.1f})",
                    preset="thesis-table-5",
                    options={"mu": mu},
                    x0=x0,
                )
            )
        checks[group] = [
            lambda s, g: fnd.diverges_far(
                s, claim="Newton diverges from far initial guesses", group=g, near_max=_NEAR_MAX
            )
        ]
    return _Study(
        configs,
        checks,
        [
            f"Initial guesses: the thesis's (0, 0) (6° from the optimum (−15°, −6°) ≡ (165°, 6°)) "
            f"and points {', '.join(_fmt(d) for d in _NEWTON_DISTANCES)}° away along the "
            f"optimum's meridian; 'near' means ≤ {_fmt(_NEAR_MAX)}°.",
            "Our Newton is damped (Levenberg shift where H is not negative definite) and rejects "
            "downhill steps (DESIGN.md errata), so it stalls rather than run away.",
        ],
    )


def _study_table6(bench: Bench, quick: bool) -> _Study:
    configs, checks = [], {}
    for group, mu in ((f"thesis μ = {_fmt(THESIS_MU)}", THESIS_MU), ("μ = 1", 1.0)):
        for lam in (0.1, 0.5, 0.8):
            configs.append(
                RunConfig(
                    group=group,
                    label=f"λ = {_fmt(lam)}",
                    method="quasi-newton",
                    parameter="lam",
                    value=lam,
                    preset="thesis-table-6",
                    options={"mu": mu, "lam": lam},
                )
            )
        checks[group] = [
            lambda s, g: fnd.faster_with_order(
                s, claim="smaller scaling factors converge faster", group=g, increasing=False
            )
        ]
    return _Study(
        configs,
        checks,
        [
            "B₀ = λ I approximates the Hessian of −f; the first step is μ ĝ / λ (capped at 2°).",
            "Second group: μ = 1 (echocal's default full quasi-Newton step).",
        ],
    )


_THESIS_METHODS = ("gradient", "momentum", "nesterov", "spsa", "newton", "quasi-newton")


def _study_table7(bench: Bench, quick: bool) -> _Study:
    configs, checks = [], {}
    thesis_group = "thesis presets (Table 7)"
    for method in _THESIS_METHODS:
        configs.append(
            RunConfig(
                group=thesis_group,
                label=method,
                method=method,
                parameter="method",
                value=method,
                preset="thesis-table-7",
            )
        )
    for method in ("model-based", "auto"):
        configs.append(
            RunConfig(
                group=thesis_group,
                label=f"{method} (beyond the thesis)",
                method=method,
                parameter="method",
                value=method,
                beyond_thesis=True,
            )
        )
    auto_group = "echocal automatic gains"
    for method in _THESIS_METHODS:
        configs.append(
            RunConfig(
                group=auto_group,
                label=f"{method} (auto gains)",
                method=method,
                parameter="method",
                value=method,
            )
        )

    def spsa_fewest(gains: str) -> Callable[[pd.DataFrame, str], Finding]:
        return lambda s, g: fnd.fewest_measurements(
            s,
            claim="SPSA needs the fewest measurements among the thesis methods",
            group=g,
            method="spsa",
            gains=gains,
        )

    checks[thesis_group] = [spsa_fewest("the thesis's gains")]
    checks[auto_group] = [spsa_fewest("automatic gains")]
    return _Study(
        configs,
        checks,
        [
            "Thesis presets: μ = 0.05, momentum 0.7, λ = 0.9, SPSA ε = 0.1, c′ = 1, A = 5 on "
            "energy normalized to ~1 (calibrate/presets.py).",
            "'model-based' and 'auto' are echocal's own methods — beyond the thesis.",
            "Second group: the six thesis methods with echocal's automatic gain calibration "
            "(no preset): first step ≈ 0.5° whatever the energy unit.",
            "Measurements per iteration: 4 for the FD gradient methods and quasi-Newton, 2 for "
            "SPSA, 9 for Newton.",
        ],
    )


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
    study: Callable[[Bench, bool], _Study],
) -> ScenarioResult:
    from echocal.evaluation import cost_map

    t0 = time.perf_counter()
    bench = _thesis_bench(seed)
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
            x0=next(iter(starts)) if len(starts) == 1 else None,
            truth=truth,
            title=f"{scenario.name} [{group}]: paths over the cost map",
        )
        if len(starts) > 1:  # one marker per initial guess (table-5)
            ax = paths.axes[0]
            for x0 in starts:
                ax.plot(*x0, marker="o", mfc="none", mec="w", ms=9, mew=1.4, ls="")
            ax.plot([], [], marker="o", mfc="none", mec="k", ls="", label="initial guesses")
            ax.legend(fontsize=7, loc="upper right", framealpha=0.6)
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


def _table(study: Callable[[Bench, bool], _Study]) -> Callable[..., ScenarioResult]:
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
        _table(_study_table1),
    ),
    Scenario(
        "table-2",
        "gradient ascent with momentum 0.65–0.85",
        "§12.2.1.2, Table 2, Figs. 13–14",
        "Momentum η ∈ {0.65, 0.7, 0.8, 0.85} at a fixed step size.",
        _table(_study_table2),
    ),
    Scenario(
        "table-3",
        "Nesterov accelerated gradient vs momentum",
        "§12.2.1.2, Table 3, Figs. 15–16",
        "Nesterov with the momentum values of Table 2, beside plain momentum.",
        _table(_study_table3),
    ),
    Scenario(
        "table-4",
        "SPSA at several SNRs",
        "§12.2.1.3, Table 4, Figs. 17–18",
        "SPSA (ρ = 0.602, γ = 0.101, c′ = 1, A = 5, ε = 0.1) at decreasing SNR.",
        _table(_study_table4),
    ),
    Scenario(
        "table-5",
        "Newton from near and far initial guesses",
        "§12.2.1.4, Table 5, Figs. 19–20",
        "Newton's method (9-point FD Hessian) from initial guesses at increasing distance.",
        _table(_study_table5),
    ),
    Scenario(
        "table-6",
        "quasi-Newton scaling factors λ",
        "§12.2.1.5, Table 6, Figs. 21–22",
        "BFGS quasi-Newton with B₀ = λ I for λ ∈ {0.1, 0.5, 0.8}.",
        _table(_study_table6),
    ),
    Scenario(
        "table-7",
        "all methods compared",
        "§12.2.1.6, Table 7, Figs. 23–24",
        "The six thesis methods under the same scenario (Table 7 presets), plus echocal's "
        "model-based and auto methods (beyond the thesis).",
        _table(_study_table7),
    ),
):
    _register(_scenario)

_register(WALL_SCENARIO)  # beyond the thesis: echocal.experiments.wall_scenario
