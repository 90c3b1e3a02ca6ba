"""Calibration benchmark: measurements to the optimum, ours against the peers (issues 5 and 7).

Run from the repository root::

    python benchmarks/bench_calibration.py            # full run: 50 runs per cell (hours)
    python benchmarks/bench_calibration.py --runs 10  # the published run (61 min on 2 cores)
    python benchmarks/bench_calibration.py --quick    # 10 runs per cell, 30/10 dB (~3 min)
    python benchmarks/bench_calibration.py --smoke    # 2 runs of one cell (seconds)
    # CI: --quick on one cell
    python benchmarks/bench_calibration.py --quick --cases thesis --starts near --snr 30 --runs 2
    python benchmarks/bench_calibration.py --methods auto,model-based --runs 20
    # hold-out seeds: runs 100-199 (a run's seed is its case, start, SNR and run index)
    python benchmarks/bench_calibration.py --methods auto --runs 100 --seed-offset 100

Cases (the simulator knows the truth; the methods do not):

* ``immersion-5mhz``: 12.7 mm 5 MHz probe, 50 mm water path over a tilted plate, on the
  wave model (diffraction: the exact lobe, its tails and the distance loss) — a narrow
  main lobe (about 1° wide), at the setup's reference position;
* ``immersion-5mhz-ray``: the same rig on the thesis's ray model (a lobe 14 % too narrow,
  no tails), for comparison;
* ``thesis``: the thesis block with a 4 mm 1 MHz probe — a broad lobe — at the thesis's
  reference position (10, 0, 22) mm.

Each case runs at SNR 30, 20 and 10 dB with starts 1–3° and 5–20° from the true optimum
(tilt parameterization, uniform distance in the band, uniform direction).  Every method of
a cell sees the same starts and the same noise seeds (common random numbers), measures
through the same :class:`~echocal.measurement.SourceObjective` (the same counter and a
budget of 80 measurements), and is judged by the angle between its estimate's beam and the
true optimum's.

The estimate after n measurements is the method's recommendation at that point: for
echocal's methods the iterate after the last iteration completed within n measurements
(``iterates`` and ``iteration_measurements`` of the result; for the model-based methods
this is the fitted model's maximum); for the peers the best point evaluated so far (what
scipy, Py-BOBYQA and scikit-optimize return), or, for nevergrad, its own
``provide_recommendation()``, or, for CMA-ES, its distribution's mean after the last
generation told, or, for BoTorch, the measured point of highest posterior mean (below).
Per (case, method) the report gives

* success within 0.05° / 0.1°: the estimate at the budget (80) is within the tolerance;
* measurements to 0.05° / 0.1° (median and 90th percentile over the runs, ``>80`` when
  more than half / a tenth of the runs never got there): the first n after which the
  estimate stays within the tolerance up to the budget;
* the fraction within 0.05° / 0.1° and the median error at fixed budgets 20, 40, 80
  (read from the same runs' histories; a method that does not look at its budget behaves
  identically when run with a budget of 20).

Our methods' options ("best presets"): the thesis methods with echocal's scale-free gains
(the step size calibrated so the first step is 0.5°, Spall's automatic SPSA gains, Newton
with Levenberg damping, BFGS from a calibrated identity) — the thesis's fixed μ = 0.05
(preset ``thesis``) stalls far from the peak of a narrow lobe; model-based and auto with
their defaults.  Peers: scipy Nelder–Mead (initial simplex of 1°, bounds), Py-BOBYQA
(``objfun_has_noise=True``, ``seek_global_minimum=False``, ``rhobeg=1``), scikit-optimize's
GP minimizer, nevergrad ``NGOpt`` told that the function is noisy, pycma's CMA-ES (σ₀ = 1°,
its default population of 6, inside the box below), and BoTorch's noisy expected
improvement.  The GP peer is
``gp_minimize``'s loop written out with ``skopt.Optimizer`` ask/tell: the same surrogate
(``cook_estimator("GP", noise="gaussian")``, a Matérn-5/2 GP whose white-noise term learns the
noise level), the same random stream, x0 as the first point then 10 random ones, ``gp_hedge``
over 2000 sampled candidates, the best point evaluated as the estimate — with one change:
the GP's hyperparameters (amplitude, length scales, noise level) are fitted by maximum
likelihood with gp_minimize's 2 random restarts at the first model update and every 5th
after (``GP_REFIT_EVERY``) and held in between, while the posterior still conditions on
every measurement.  The likelihood fits were 80 % of gp_minimize's ~8 s of CPU per
80-measurement run; now a run costs ~3 s and every method gets the full run count.  On the
60 seed-paired runs of the previous full benchmark (5 per cell, refit at every update) the
success within 0.1° was 30 % both ways and the median final error 0.24° before, 0.23° after.
(EI instead of ``gp_hedge``, the other cheap option, was clearly worse at 10 dB: skopt's EI
takes the noisy best observation as incumbent.)  The BoTorch peer (``botorch-qlognei``,
issue 19) is BoTorch's standard loop for noisy problems: a ``SingleTaskGP`` (BoTorch's
default kernel and priors, a homoskedastic noise level inferred with the other
hyperparameters) on the angles normalized to the box (``Normalize``) and the standardized
metric (``Standardize``), refitted by ``fit_gpytorch_mll`` after every measurement (warm-
started from the previous fit's hyperparameters); x0 first, then 10 scrambled Sobol points
in the box (``BOTORCH_N_SOBOL``), then each next point maximizes
``qLogNoisyExpectedImprovement`` (128 quasi-MC samples, ``prune_baseline=True``) by
``optimize_acqf`` (4 restarts from 128 raw samples); float64, torch seeded by the run's seed
(a run is reproducible), one torch thread.  Its estimate after n measurements is the
measured point of highest posterior mean under the GP fitted to those n (x0 after one) —
BoTorch's usual recommendation on noisy problems, where the best observation tends to be a
lucky noise draw rather than the best point.  A run costs ~12 s (the mean of 80 wave-model
runs on a 2-core machine busy with other jobs, where skopt-gp took ~5 s), the likelihood
fits and the acquisition optimization about equally.  botorch is not in the ``bench``
extra: it brings torch, by default a CUDA build (about 3 GB of wheels with its NVIDIA libraries);
with a CPU-only torch it adds ~0.9 GB.  Install it with
``pip install "torch==2.13.0+cpu" botorch`` where pip finds a CPU-only torch wheel (on the
project's machines, in its local wheel directory), else install torch from PyTorch's CPU
wheel index first and then ``pip install botorch``.  The bounded peers (BOBYQA, the GP
peer, nevergrad, CMA-ES, BoTorch) search the box x0 ± (the start band's outer distance + 1°),
clipped to the positioner's limits — information the echocal methods are not given.  Each
peer minimizes −metric (BoTorch maximizes the metric); the budget is enforced by the
objective itself (:class:`~echocal.errors.BudgetExhaustedError` ends a peer's run).  Peers
are optional (``pip install echocal[bench]``; botorch as above); a peer that is not
installed or fails to import is skipped with a message.

On a bench (``--cases immersion-5mhz-ray-bench``, the cases of ``BENCH_CASES``) each run
also keeps the bench clock after every measurement, and the tables add the median bench
time to 0.1° and over the budget; ``--methods auto-motion-aware`` runs ``auto`` on a
motion-aware objective beside it (docs/bench.md has the measured cells).

Output: a Markdown table per case on stdout (headline lines start with ``HEADLINE``);
``--json OUT`` / ``--out-md OUT`` / ``--plot OUT``; ``--render JSON`` writes the page and
figure again from a run's JSON; ``--update JSON --methods auto`` runs ``auto`` again on
that JSON's cells and seeds, keeps every other method's runs and rewrites the JSON (and the
docs' page, when it is the docs' JSON), which records the rerun's command and commit (the
full benchmark takes hours at 50 runs per cell; a change to one method needs only its own
runs again).  A full run (every case, start, SNR and
method; ``--runs`` may change the count) writes ``docs/benchmarks/calibration.{md,json,png}``,
the page headed by the command that made it.  Two worker processes by default
(``--workers``); BLAS is pinned to one thread per worker.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy is imported

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import shlex  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any, NamedTuple  # noqa: E402

import numpy as np  # noqa: E402
from _calibration_cases import (  # noqa: E402
    AUTO_TARGETS,
    BUDGET,
    CASES,
    DEFAULT_CASES,
    FIXED_BUDGETS,
    FRONT_FIRST,
    MOTION_AWARE,
    OURS,
    PARAM,
    SETTLE,
    SNRS,
    STARTS,
    TOLERANCES,
    TWIN_RATIO,
)
from _calibration_report import (  # noqa: E402
    _winner_sentence,
    case_table,
    plot_ecdf,
    report_markdown,
    winner,
)
from _common import machine_info  # noqa: E402
from _peers import (  # noqa: E402
    _PEER_FUNCS,
    INSTALL_HINT,
    PEERS,
    _box,
    _Stop,
    _Tracker,
    available_peers,
)

from echocal.calibrate import calibrate  # noqa: E402
from echocal.evaluation import angular_error  # noqa: E402
from echocal.io import atomic_write_text  # noqa: E402
from echocal.measurement import ReceiverSettings, SourceObjective  # noqa: E402
from echocal.measurement.objective import default_bounds  # noqa: E402
from echocal.setups import load_setup  # noqa: E402
from echocal.setups.bench_schema import BenchConfig, build_bench  # noqa: E402
from echocal.signal.gates import TimeGate, resolve_gate  # noqa: E402
from echocal.specimen.builtins import builtin_specimen  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs" / "benchmarks"


# ----------------------------------------------------------------------------- cases
class Case(NamedTuple):
    """A case made ready to run (cached per process)."""

    setup: Any
    position: np.ndarray
    """[m] (3,)"""
    truth: np.ndarray
    """[deg] (2,) the true optimum in tilts (inside ``gate`` when there is one)"""
    optima: np.ndarray
    """[deg] (k, 2) every equal optimum"""
    gate: TimeGate | None


_CASES_READY: dict[str, Case] = {}


def _case(case: str) -> Case:
    """``case`` of :data:`CASES` made ready: its setup, position, truth and gate."""
    if case not in _CASES_READY:
        spec = CASES[case]
        setup = load_setup(spec["setup"], seed=0)
        if "specimen" in spec:
            setup = dataclasses.replace(setup, specimen=builtin_specimen(spec["specimen"]))
        if "bench" in spec:
            config = BenchConfig.model_validate(spec["bench"])
            setup = dataclasses.replace(setup, bench=build_bench(config, None))
        if "probe_width" in spec:
            width = spec["probe_width"]
            probe = dataclasses.replace(setup.transducer, width=width, height=width)
            setup = dataclasses.replace(setup, transducer=probe)
        pos = np.asarray(
            setup.reference_position if spec["position"] is None else spec["position"], float
        )
        gate = (
            resolve_gate(
                spec["gate"],
                pulse=setup.pulse,
                thickness=setup.thickness,
                material=setup.material,
            )
            if "gate" in spec
            else None
        )
        optima = setup.true_optima(pos, parameterization=PARAM, gate=gate, ratio=TWIN_RATIO)
        _CASES_READY[case] = Case(setup, pos, optima[0], optima, gate)
    return _CASES_READY[case]


def tilt_bounds(setup: Any) -> np.ndarray:
    """[deg] (2, 2): the objective's default tilt box (:func:`default_bounds`, the largest
    tilt box inside the positioner's co-elevation cone), 1e-6° inside, so a corner's
    rounding never leaves the cone."""
    return default_bounds(setup, PARAM) + np.array([1e-6, -1e-6])


def run_seed(case: str, start: str, snr: float, run: int) -> int:
    """Seed of one run, the same for every method (common random numbers)."""
    return int(
        np.random.SeedSequence(
            [list(CASES).index(case), list(STARTS).index(start), int(snr), run]
        ).generate_state(1)[0]
    )


def start_point(truth: np.ndarray, start: str, seed: int, bounds: np.ndarray) -> np.ndarray:
    """x0 [deg] at a uniform distance in the start band and a uniform direction."""
    rng = np.random.default_rng(seed)
    lo, hi = STARTS[start]
    for _ in range(100):
        dist = rng.uniform(lo, hi)
        ang = rng.uniform(0.0, 2.0 * np.pi)
        x0 = truth + dist * np.array([np.cos(ang), np.sin(ang)])
        if np.all((x0 >= bounds[:, 0]) & (x0 <= bounds[:, 1])):
            return x0
    raise RuntimeError("no start inside the bounds")  # pragma: no cover


def case_setup(case: str, snr: float, seed: int) -> Any:
    """``case``'s setup at ``snr`` [dB] with the noise stream of ``seed``."""
    base = _case(case).setup
    return dataclasses.replace(base, receiver=ReceiverSettings(snr_db=snr), rng=seed)


class SeededRun(NamedTuple):
    """One run of a cell made ready by :func:`seeded_run` (every method of the cell gets
    the same: common random numbers)."""

    setup: Any
    """the case's setup at the cell's SNR, with the run's noise stream"""
    seed: int
    position: np.ndarray
    """[m] (3,)"""
    bounds: np.ndarray
    """[deg] (2, 2) the tilt box x0 lies in"""
    x0: np.ndarray
    """[deg] (2,) the start"""
    optima: np.ndarray
    """[deg] (k, 2) every equal optimum"""
    gate: TimeGate | None


def seeded_run(
    case: str, start: str, snr: float, run: int, bounds: np.ndarray | None = None
) -> SeededRun:
    """Run ``run`` of the cell ``(case, start, snr)``: its seed (:func:`run_seed`), setup
    (:func:`case_setup`) and start (:func:`start_point`) inside ``bounds`` [deg] (2, 2)
    (default :func:`tilt_bounds`)."""
    _, pos, truth, optima, gate = _case(case)
    seed = run_seed(case, start, snr, run)
    setup = case_setup(case, snr, seed)
    box = tilt_bounds(setup) if bounds is None else bounds
    return SeededRun(setup, seed, pos, box, start_point(truth, start, seed, box), optima, gate)


# ----------------------------------------------------------------------------- one run
def run_ours(
    objective: Any,
    method: str,
    x0: np.ndarray,
    budget: int,
    seed: int,
    settle: tuple[float, int] | None = None,
    **options: Any,
) -> Any:
    """echocal's ``method`` on ``objective`` from ``x0`` [deg] (2,) with ``budget``
    measurements, seeded by ``seed``, its warnings silenced; ``settle=None`` (the default)
    measures to the budget, so the estimate can be read after every measurement."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(
            objective,
            method=method,
            x0=x0,
            budget=budget,
            max_iter=10_000,
            settle=settle,
            rng=seed,
            **options,
        )


def error_history(estimates: np.ndarray, optima: np.ndarray) -> np.ndarray:
    """[deg] (n,): the angle between each estimate of ``estimates`` [deg] (n, 2) and the
    nearest of the equal ``optima`` [deg] (k, 2)."""
    return np.min([angular_error(estimates, t, PARAM) for t in optima], axis=0)


def auto_errors(objective: Any, run: SeededRun, budget: int) -> tuple[Any, np.ndarray]:
    """``auto`` on ``objective`` from ``run``'s start, to the ``budget``: (its result, its
    error after n = 0..budget measurements [deg] (budget + 1,))."""
    res = run_ours(objective, "auto", run.x0, budget, run.seed)
    return res, error_history(_estimates_ours(res, run.x0, budget), run.optima)


def rounded(errors: np.ndarray) -> list[float]:
    """``errors`` [deg] as a JSON list, to a µ° (a run's stored error history)."""
    return [round(float(e), 6) for e in errors]


def _estimates_ours(result: Any, x0: np.ndarray, budget: int) -> np.ndarray:
    """Estimate after n = 0..budget measurements [deg], shape (budget + 1, 2)."""
    counts = np.asarray(result.iteration_measurements)
    its = np.asarray(result.iterates)
    n = np.arange(budget + 1)
    idx = np.searchsorted(counts, n, side="right") - 1
    est = its[np.clip(idx, 0, len(its) - 1)].copy()
    est[-1] = result.x  # the final recommendation at the end of the run
    if result.n_measurements < budget:
        est[result.n_measurements :] = result.x
    return est


AUTO_MIN_BUDGET = 8
"""The least budget ``auto`` accepts: x0 and its first ring of 6, and the final
measurement at the estimate."""


def _front_first(
    setup: Any, pos: np.ndarray, gate: TimeGate | None, x0: np.ndarray, budget: int
) -> tuple[np.ndarray, str, int | None, int]:
    """:data:`FRONT_FIRST`: (estimate after n = 0..budget measurements [deg] (budget + 1,
    2), the two stages' statuses, the first's acquisition measurements, the measurements
    the stages made)."""
    seed = int(setup.rng)
    stages: list[tuple[Any, np.ndarray, int]] = []
    start, left, measured = x0, budget, 0
    for stage_gate, settle in ((None, SETTLE), (gate, None)):
        if left < AUTO_MIN_BUDGET:
            break  # no room for another stage: the estimate stays
        stage_setup = dataclasses.replace(setup, rng=seed + len(stages))  # fresh noise
        objective = SourceObjective(
            stage_setup, pos, parameterization=PARAM, budget=left, bounds=tilt_bounds(setup),
            gate=stage_gate,
        )  # fmt: skip
        res = run_ours(objective, "auto", start, left, seed, settle=settle)
        measured += res.n_measurements
        spent = res.n_measurements if settle is not None else left  # the last runs to the end
        stages.append((res, _estimates_ours(res, start, spent), spent))
        start, left = res.x, left - spent
    est = np.vstack([stages[0][1], *(e[1:] for _, e, _ in stages[1:])])
    est = np.vstack([est, np.repeat(est[-1:], budget + 1 - len(est), axis=0)])
    status = "/".join(str(res.status) for res, _, _ in stages)
    return est, status, stages[0][0].acquisition_measurements, measured


class ClockedObjective(SourceObjective):
    """A :class:`SourceObjective` that keeps the bench clock [s] after each measurement
    (:attr:`clock`, one entry per measurement, the batch's end for each of its points;
    empty where the source reports no bench time)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.clock: list[float] = []

    def __call__(self, points: Any) -> np.ndarray:
        before = self.n_measurements
        values = super().__call__(points)
        if self.bench_time is not None:
            self.clock += [self.bench_time] * (self.n_measurements - before)
        return values


def bench_time_to(clock: list[float], n_to: float) -> float | None:
    """[s] the bench time of the first ``n_to`` measurements (the clock after the n-th;
    0 for n = 0), None when the run never got there (inf) or reports no bench time."""
    if not clock or not np.isfinite(n_to):
        return None
    return 0.0 if n_to == 0 else float(clock[int(n_to) - 1])


def run_one(task: tuple[Any, ...]) -> dict[str, Any]:
    """One seeded run of one method, ``(case, start, snr, run, method[, budget])`` (budget
    default :data:`BUDGET`); returns its error after each measurement."""
    case, start, snr, run, method, *rest = task
    budget = int(rest[0]) if rest else BUDGET
    setup, seed, pos, bounds, x0, optima, gate = seeded_run(case, start, snr, run)
    objective = ClockedObjective(
        setup, pos, parameterization=PARAM, budget=budget, bounds=bounds, gate=gate,
        motion_aware=method == MOTION_AWARE,
    )  # fmt: skip
    t0 = time.perf_counter()
    status = ""
    acquisition = None
    n_measurements = None
    if method == FRONT_FIRST:
        est, status, acquisition, n_measurements = _front_first(setup, pos, gate, x0, budget)
    elif method in OURS or method == MOTION_AWARE:
        name = "auto" if method == MOTION_AWARE else method
        res = run_ours(objective, name, x0, budget, seed, **OURS.get(method, {}))
        est = _estimates_ours(res, x0, budget)
        status = str(res.status)
        acquisition = res.acquisition_measurements
    else:
        tr = _Tracker(objective)
        try:
            box = _box(x0, STARTS[start][1] + 1.0, objective.bounds)
            _PEER_FUNCS[method](tr, x0, box, seed)
        except _Stop:
            pass
        hist = tr.history_override or tr.history
        est = np.empty((budget + 1, 2))
        est[0] = x0
        for n in range(1, budget + 1):
            est[n] = hist[min(n, len(hist)) - 1] if hist else x0
    return {
        "case": case,
        "start": start,
        "snr": snr,
        "run": run,
        "method": method,
        "errors": rounded(error_history(est, optima)),
        "n_measurements": int(
            objective.n_measurements if n_measurements is None else n_measurements
        ),
        "acquisition_measurements": acquisition,
        "bench_time": objective.bench_time,
        "bench_clock": [round(t, 4) for t in objective.clock],
        "bench_time_saved": objective.bench_time_saved,
        "status": status,
        "seconds": time.perf_counter() - t0,
    }


# ----------------------------------------------------------------------------- metrics
def measurements_to(errors: np.ndarray, tol: float) -> float:
    """First n after which the error stays <= tol through the budget (inf if never)."""
    outside = np.nonzero(errors > tol)[0]
    if outside.size == 0:
        return 0.0
    last = int(outside[-1])
    return float(last + 1) if last + 1 < len(errors) else np.inf


def summarize(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Per-method metrics of the runs of one cell (or one case)."""
    errs = np.array([r["errors"] for r in runs])  # (n_runs, BUDGET + 1)
    out: dict[str, Any] = {"runs": len(runs)}
    for tol in TOLERANCES:
        m = np.array([measurements_to(e, tol) for e in errs])
        key = f"{tol:g}"
        out[f"success_{key}"] = float(np.mean(errs[:, -1] <= tol))
        out[f"median_n_{key}"] = float(np.median(m))
        out[f"p90_n_{key}"] = float(np.percentile(m, 90, method="higher"))
        out[f"n_to_{key}"] = [None if not np.isfinite(v) else int(v) for v in m]
        for b in FIXED_BUDGETS:
            out[f"within_{key}_at_{b}"] = float(np.mean(errs[:, b] <= tol))
    for b in FIXED_BUDGETS:
        out[f"median_error_at_{b}"] = float(np.median(errs[:, b]))
    clocks = [r.get("bench_clock") or [] for r in runs]
    if all(clocks):  # every run reports its bench time: to 0.1° (inf: never) and in all
        n_to = [np.inf if v is None else v for v in out["n_to_0.1"]]
        to = [bench_time_to(c, n) for c, n in zip(clocks, n_to, strict=True)]
        out["bench_to_0.1"] = to
        out["median_bench_to_0.1"] = float(np.median([np.inf if t is None else t for t in to]))
        out["median_bench_time"] = float(np.median([c[-1] for c in clocks]))
    out["seconds_per_run"] = float(np.mean([r["seconds"] for r in runs]))
    return out


# ----------------------------------------------------------------------------- main
def _summaries(
    results: list[dict[str, Any]],
    cells: list[tuple[str, str, float]],
    methods: list[str],
    peers: list[str],
) -> dict[str, Any]:
    """The runs ``results`` summarized per cell and per case (:func:`summarize`), the
    winner per case against ``peers``, and ``auto``'s targets where its cells were run."""
    per_cell: dict[str, dict[str, Any]] = {}
    per_case: dict[str, dict[str, Any]] = {}
    for c, s, snr in cells:
        per_cell[f"{c}|{s}|{snr:g}"] = {
            m: summarize(
                [
                    r
                    for r in results
                    if (r["case"], r["start"], r["snr"], r["method"]) == (c, s, snr, m)
                ]
            )
            for m in methods
        }
    for c in dict.fromkeys(cell[0] for cell in cells):
        per_case[c] = {
            m: summarize([r for r in results if r["case"] == c and r["method"] == m])
            for m in methods
        }
    auto_targets = {}
    if "auto" in methods:
        for case, targets in AUTO_TARGETS.items():
            for s, snr, tol, b, goal in targets:
                key = f"{case}|{s}|{snr:g}"
                if key not in per_cell:
                    continue
                got = per_cell[key]["auto"][f"within_{tol:g}_at_{b}"]
                name = f"{case}, {s} start, {snr:g} dB: within {tol:g} deg after {b} measurements"
                auto_targets[name] = {"got": got, "goal": goal, "met": got >= goal}
    return {
        "cells": per_cell,
        "cases": per_case,
        "winners": {c: winner(summary, peers) for c, summary in per_case.items()},
        "auto_targets": auto_targets,
    }


def _plan(
    mode: str, runs: int | None, cases: tuple[str, ...] = DEFAULT_CASES
) -> tuple[list[tuple[str, str, float]], int]:
    cells = [(c, s, snr) for c in cases for s in STARTS for snr in SNRS]
    if mode == "smoke":
        return [("thesis", "near", 30.0)], runs or 2
    if mode == "quick":
        quick = [c for c in cells if c[2] in (30.0, 10.0)]
        return quick, runs or 10
    return cells, runs or 50


def _run_tasks(tasks: list[tuple[Any, ...]], workers: int, t0: float) -> list[dict[str, Any]]:
    """:func:`run_one` on every task, on ``workers`` processes, with progress every 5 %."""
    if workers <= 1:
        return [run_one(t) for t in tasks]
    results: list[dict[str, Any]] = []
    with ProcessPoolExecutor(workers) as pool:
        for i, r in enumerate(pool.map(run_one, tasks, chunksize=4)):
            results.append(r)
            if (i + 1) % max(1, len(tasks) // 20) == 0:
                el = time.perf_counter() - t0
                print(f"  {i + 1}/{len(tasks)} runs, {el:.0f} s", flush=True)
    return results


def _command(argv: list[str] | None) -> str:
    """The command line that reruns this invocation."""
    args = sys.argv[1:] if argv is None else argv
    return " ".join(["python", "benchmarks/bench_calibration.py", *map(shlex.quote, args)])


def _update(path: Path, rerun: list[str], workers: int, argv: list[str] | None) -> int:
    """``--update JSON --methods M``: run the methods ``rerun`` again on the cells and run
    count of a run's JSON, keep the other methods' runs, summarize again and write the JSON
    back (the docs' page and figure with it when it is the docs' ``calibration.json``).  The
    JSON's ``updates`` records each such rerun: its methods, command, commit and time."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        methods, n_runs, raw = list(data["methods"]), int(data["runs_per_cell"]), data["raw"]
        offset = int(data.get("seed_offset", 0))
        cells = [(c, s, float(snr)) for c, s, snr in (k.split("|") for k in data["cells"])]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        print(f"error: --update {path}: not a calibration benchmark's JSON ({exc!r})")
        return 2
    if data.get("budget") != BUDGET:
        print(f"error: --update {path}: its budget {data.get('budget')} is not this run's {BUDGET}")
        return 2
    unknown = sorted(set(rerun) - set(methods))
    if unknown:
        print(f"error: --methods {unknown}: not in {path}'s methods {methods}")
        return 2
    runs = range(offset, offset + n_runs)
    tasks = [(c, s, snr, r, m) for (c, s, snr) in cells for r in runs for m in rerun]
    print(f"calibration benchmark (update {path}): {len(tasks)} runs of {rerun}", flush=True)
    machine = machine_info(["nevergrad", "Py-BOBYQA", "scikit-optimize", "botorch", "torch"])
    t0 = time.perf_counter()
    results = _run_tasks(tasks, workers, t0)
    kept = [r for r in raw if r["method"] not in rerun]
    data.update(_summaries(kept + results, cells, methods, [m for m in methods if m in PEERS]))
    data["raw"] = kept + results
    data.setdefault("updates", []).append(
        {
            "methods": rerun,
            "command": _command(argv),
            "echocal_git": machine["echocal_git"],
            "elapsed_s": time.perf_counter() - t0,
        }
    )
    atomic_write_text(path, json.dumps(data, indent=None))
    if path.resolve() == (DOCS / "calibration.json").resolve():
        _write_report(data, DOCS / "calibration.md", DOCS / "calibration.png")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="~10 runs per cell, SNR 30 and 10 dB")
    g.add_argument("--smoke", action="store_true", help="2 runs of one cell")
    ap.add_argument("--runs", type=int, default=None, help="runs per cell")
    ap.add_argument(
        "--seed-offset",
        type=int,
        default=0,
        metavar="N",
        help="run indices N, N+1, ...: seeds no run with the default 0 used (hold-out runs)",
    )
    ap.add_argument("--methods", default=None, help="comma-separated subset of methods")
    ap.add_argument("--cases", default=None, help="comma-separated subset of cases")
    ap.add_argument("--snr", default=None, help="comma-separated subset of SNRs [dB]")
    ap.add_argument("--starts", default=None, help="comma-separated subset of near,far")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--out-md", type=Path, default=None)
    ap.add_argument("--plot", type=Path, default=None)
    ap.add_argument(
        "--render",
        type=Path,
        default=None,
        metavar="JSON",
        help="write --out-md / --plot again from a run's --json, without running",
    )
    ap.add_argument(
        "--update",
        type=Path,
        default=None,
        metavar="JSON",
        help="run --methods again on a run's JSON (its cells and runs), keep the rest, rewrite it",
    )
    args = ap.parse_args(argv)
    if args.update is not None:
        chosen = (args.cases, args.snr, args.starts, args.runs, args.json, args.out_md, args.plot)
        fixed = args.quick or args.smoke or args.seed_offset != 0
        if not args.methods or fixed or any(v is not None for v in chosen):
            ap.error(
                "--update JSON takes --methods (and --workers) only: the JSON's cells and runs"
            )
        return _update(
            args.update, list(dict.fromkeys(args.methods.split(","))), args.workers, argv
        )
    if args.render is not None:
        if not (args.out_md or args.plot):
            ap.error("--render needs --out-md and/or --plot: what to write")
        return _render(args.render, args.out_md, args.plot)
    mode = "smoke" if args.smoke else "quick" if args.quick else "full"
    chosen = tuple(args.cases.split(",")) if args.cases else DEFAULT_CASES
    unknown_cases = sorted(set(chosen) - set(CASES))
    if unknown_cases:
        ap.error(f"unknown case(s) {unknown_cases}; choose from {list(CASES)}")
    cells, n_runs = _plan(mode, args.runs, chosen)
    if args.snr:
        cells = [c for c in cells if c[2] in [float(s) for s in args.snr.split(",")]]
    if args.starts:
        cells = [c for c in cells if c[1] in args.starts.split(",")]
    wanted = args.methods.split(",") if args.methods else [*OURS, *PEERS]
    workflows = (FRONT_FIRST, MOTION_AWARE)
    unknown = sorted(set(wanted) - {*OURS, *workflows, *PEERS})
    if unknown:
        ap.error(f"unknown method(s) {unknown}; choose from {[*OURS, *workflows, *PEERS]}")
    peers, skipped = available_peers([m for m in wanted if m in PEERS])
    for name, why in skipped.items():
        hint = INSTALL_HINT.get(name, "pip install echocal[bench]")
        print(f"SKIPPED peer {name}: not available ({why}); {hint}")
    methods = [m for m in wanted if m in OURS or m in workflows] + peers
    if args.seed_offset < 0:
        ap.error(f"--seed-offset must be >= 0; got {args.seed_offset}")
    runs = range(args.seed_offset, args.seed_offset + n_runs)
    tasks = [(c, s, snr, r, m) for (c, s, snr) in cells for r in runs for m in methods]
    print(
        f"calibration benchmark ({mode}): {len(cells)} cell(s) x {n_runs} runs x "
        f"{len(methods)} methods = {len(tasks)} runs, budget {BUDGET}, {args.workers} worker(s)",
        flush=True,
    )
    machine = machine_info(["nevergrad", "Py-BOBYQA", "scikit-optimize", "botorch", "torch"])
    t0 = time.perf_counter()
    results = _run_tasks(tasks, args.workers, t0)
    elapsed = time.perf_counter() - t0

    summaries = _summaries(results, cells, methods, peers)
    per_case, auto_targets = summaries["cases"], summaries["auto_targets"]
    for c, w in summaries["winners"].items():
        print(f"HEADLINE {c}: {_winner_sentence(w)}")
    for name, t in auto_targets.items():
        print(
            f"HEADLINE auto target ({name}): {100 * t['got']:.0f} % "
            f"(goal >= {100 * t['goal']:.0f} %) {'met' if t['met'] else 'NOT met'}"
        )
    for c, summary in per_case.items():
        print()
        print(f"## {c}")
        print(case_table(summary))
    print(f"HEADLINE total time {elapsed:.0f} s")

    data = {
        "command": _command(argv),
        "mode": mode,
        "budget": BUDGET,
        "runs_per_cell": n_runs,
        "seed_offset": args.seed_offset,
        "workers": args.workers,
        "methods": methods,
        "skipped_peers": skipped,
        **summaries,
        "elapsed_s": elapsed,
        "machine": machine,
        "raw": results,
    }
    json_path, md_path, png_path = args.json, args.out_md, args.plot
    subset = args.seed_offset != 0 or any(
        v is not None for v in (args.methods, args.cases, args.snr, args.starts)
    )
    if mode == "full" and not subset:  # every cell and method (any --runs) refreshes the docs
        DOCS.mkdir(parents=True, exist_ok=True)
        json_path = json_path or DOCS / "calibration.json"
        md_path = md_path or DOCS / "calibration.md"
        png_path = png_path or DOCS / "calibration.png"
    if json_path:
        atomic_write_text(json_path, json.dumps(data, indent=None))
    _write_report(data, md_path, png_path)
    return 0


def _write_report(data: dict[str, Any], md_path: Path | None, png_path: Path | None) -> None:
    """Write the Markdown page and the figure of a run's ``data`` (where asked)."""
    if md_path:
        name = png_path.name if png_path else "calibration.png"
        method = "Cases (the simulator" + (__doc__ or "").split("Cases (the simulator", 1)[1]
        method = method.split("Output:", 1)[0]
        atomic_write_text(md_path, report_markdown(data, name, method))
    if png_path:
        plot_ecdf(data["cases"], png_path)


def _render(path: Path, md_path: Path | None, png_path: Path | None) -> int:
    """``--render JSON``: the page and figure again from a run's JSON, without running."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        _write_report(data, md_path, png_path)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        print(f"error: --render {path}: not a calibration benchmark's JSON ({exc!r})")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
