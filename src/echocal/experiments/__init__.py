"""Experiments: Monte-Carlo sweeps over calibration methods, parameters, SNRs and seeds.

A sweep file (TOML, see ``docs/sweeps.md``) crosses methods × parameter grid × SNRs ×
initial guesses × seeds on one setup; :func:`run_sweep` runs every case (local
processes or a Dask cluster), writing tidy Parquet results incrementally so that an
interrupted sweep resumes where it stopped::

    from echocal.experiments import run_sweep
    results = run_sweep("quick", "out/quick")    # built-in sweep, 2 local processes
    print(results.summary())

Thesis scenarios, reports and the demo live in ``echocal.experiments.scenarios``,
``echocal.experiments.report`` and ``echocal.experiments.demo`` (import them by their
full module path; this package imports only the sweep machinery).
"""

from echocal.experiments.execution import SweepResults, load_results, run_sweep
from echocal.experiments.runner import (
    HISTORY_COLUMNS,
    RUN_COLUMNS,
    history_columns,
    run_case,
    run_columns,
)
from echocal.experiments.summary import summarize
from echocal.experiments.sweep import (
    MethodSpec,
    RunCase,
    SweepSpec,
    X0Spec,
    builtin_sweep_names,
    expand,
    load_sweep,
    run_problems,
    spec_hash,
)

__all__ = [
    "HISTORY_COLUMNS",
    "RUN_COLUMNS",
    "MethodSpec",
    "RunCase",
    "SweepResults",
    "SweepSpec",
    "X0Spec",
    "builtin_sweep_names",
    "expand",
    "history_columns",
    "load_results",
    "load_sweep",
    "run_case",
    "run_columns",
    "run_problems",
    "run_sweep",
    "spec_hash",
    "summarize",
]
