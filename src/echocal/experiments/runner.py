"""One run of a sweep: a pure function of a :class:`~echocal.experiments.sweep.RunCase`.

:func:`run_case` builds the setup at the case's SNR with a noise seed derived from the
case, calibrates, and judges the result against the simulator's truth.  Every random
draw comes from seeds derived from the case (:attr:`RunCase.run_seed`,
:attr:`RunCase.x0_seed`), so the same case gives bit-identical numbers in any
process, on any worker, in any order.

The true optimum (a deterministic Nelder–Mead search, a few tenths of a second) is
memoized per process and (setup, position, parameterization): a cache of a pure
function, which changes how fast a worker runs, never what it returns.
"""

from __future__ import annotations

import functools
import time
import traceback
import warnings
from typing import Any

import numpy as np
import pandas as pd

from echocal.angle_columns import ANGLE_ROLES, angle_columns
from echocal.errors import EchocalError
from echocal.experiments.sweep import RunCase
from echocal.experiments.sweep_values import _thawed, offset_start

__all__ = [
    "HISTORY_COLUMNS",
    "RUN_COLUMNS",
    "history_columns",
    "history_frame",
    "run_case",
    "run_columns",
    "runs_frame",
]

RUN_COLUMNS: dict[str, str] = {
    "case_id": "object",
    "sweep": "object",
    "method": "object",
    "label": "object",
    "preset": "object",
    "params": "object",
    "snr_db": "float64",
    "x0_kind": "object",
    "x0_label": "object",
    "x0_tilt_x_deg": "float64",
    "x0_tilt_y_deg": "float64",
    "seed": "int64",
    "run_seed": "int64",
    "error_deg": "float64",
    "measurements_to_tol": "Int64",
    "iterations_to_tol": "Int64",
    "success": "bool",
    "n_measurements": "int64",
    "n_iterations": "int64",
    "status": "int64",
    "message": "object",
    "estimate_tilt_x_deg": "float64",
    "estimate_tilt_y_deg": "float64",
    "truth_tilt_x_deg": "float64",
    "truth_tilt_y_deg": "float64",
    "tolerance": "float64",
    "wall_time": "float64",
    "warnings": "object",
}
"""Columns of the runs table of a tilt sweep and their pandas dtypes (:func:`run_columns`
names the angles of either parameterization).

Angles [deg] in the sweep's parameterization (``x0_*``, ``estimate_*``, ``truth_*``: here
``x0_tilt_x_deg``, ``x0_tilt_y_deg``, ...);
``error_deg`` [deg] angle between the estimate's beam and the truth's; ``snr_db`` [dB]
(NaN = noiseless); ``measurements_to_tol`` / ``iterations_to_tol`` (<NA> if the final
estimate misses the tolerance); ``status`` from :data:`echocal.calibrate.STATUS_MESSAGES`,
or -1 when the run raised (``message`` holds the error); ``wall_time`` [s].
"""

HISTORY_COLUMNS: dict[str, str] = {
    "case_id": "object",
    "index": "int64",
    "tilt_x_deg": "float64",
    "tilt_y_deg": "float64",
    "value": "float64",
}
"""Columns of the history table of a tilt sweep: every measurement of every run, in order
(``tilt_x_deg``, ``tilt_y_deg`` [deg]; ``value`` the metric, NaN kept); :func:`history_columns`
names the angles of either parameterization."""


def _renamed(columns: dict[str, str], parameterization: str) -> dict[str, str]:
    """``columns`` (a tilt sweep's) with the angles named for ``parameterization``."""
    tilt = {
        old: new
        for role in (None, *ANGLE_ROLES)
        for old, new in zip(
            angle_columns("tilt", role), angle_columns(parameterization, role), strict=True
        )
    }
    return {tilt.get(name, name): dtype for name, dtype in columns.items()}


def run_columns(parameterization: str) -> dict[str, str]:
    """:data:`RUN_COLUMNS` with the angles named for ``parameterization``."""
    return _renamed(RUN_COLUMNS, parameterization)


def history_columns(parameterization: str) -> dict[str, str]:
    """:data:`HISTORY_COLUMNS` with the angles named for ``parameterization``."""
    return _renamed(HISTORY_COLUMNS, parameterization)


FAILED = -1
"""``status`` of a run that raised an error (its message is in ``message``)."""


def runs_frame(rows: list[dict[str, Any]], parameterization: str) -> pd.DataFrame:
    """Rows of :func:`run_case` as a DataFrame with the :func:`run_columns` dtypes."""
    columns = run_columns(parameterization)
    return pd.DataFrame(rows, columns=list(columns)).astype(columns)


def history_frame(frames: list[pd.DataFrame], parameterization: str) -> pd.DataFrame:
    """Concatenated history parts with the :func:`history_columns` dtypes."""
    columns = history_columns(parameterization)
    if not frames:
        return pd.DataFrame(columns=list(columns)).astype(columns)
    return pd.concat(frames, ignore_index=True).astype(columns)


@functools.lru_cache(maxsize=8)
def _truth_setup(setup: str):
    """A noiseless-truth copy of ``setup``; its own cache memoizes the true optima."""
    from echocal.setups import load_setup

    return load_setup(setup, seed=0)


def _random_start(case: RunCase, truth: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """[deg] a start at a uniform distance in ``case.x0`` and a uniform direction from truth."""
    start = offset_start(case.x0_seed, case.x0, truth)
    # `sweep check` refuses a sweep whose starts lie outside; a case built by hand is clipped
    return np.clip(start, bounds[:, 0], bounds[:, 1])


def run_case(case: RunCase) -> tuple[dict[str, Any], pd.DataFrame]:
    """Run one case; return its row of the runs table and its measurement history.

    Never raises for a failing run: an error inside the run gives a row with
    ``status = -1`` and the error in ``message`` (so one bad case does not stop a sweep).
    """
    from echocal.calibrate import calibrate
    from echocal.evaluation import evaluate_run
    from echocal.measurement.objective import SourceObjective
    from echocal.setups import setup_with_overrides

    t0 = time.perf_counter()
    seeds = np.random.SeedSequence(case.run_seed).generate_state(2, dtype=np.uint32)
    noise_seed, method_seed = (int(s) for s in seeds)
    position = np.array(case.position, dtype=np.float64)
    row: dict[str, Any] = {
        "case_id": case.case_id,
        "sweep": case.sweep,
        "method": case.method,
        "label": case.label,
        "preset": case.preset,
        "params": case.params_json,
        "snr_db": np.nan if case.snr_db is None else case.snr_db,
        "x0_kind": case.x0_kind,
        "x0_label": case.x0_label,
        "seed": case.seed,
        "run_seed": case.run_seed,
        "tolerance": case.tolerance,
    }
    names = {role: angle_columns(case.parameterization, role) for role in ANGLE_ROLES}
    angles = angle_columns(case.parameterization)
    history = history_frame([], case.parameterization)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            truth_setup = _truth_setup(case.setup)
            virtual = setup_with_overrides(case.setup, snr_db=case.snr_db, seed=noise_seed)
            gate = None
            if case.gate is not None:  # checked with the sweep; resolved for this setup
                from echocal.signal.gates import plate_layers, resolve_gate

                gate = resolve_gate(
                    case.gate,
                    pulse=virtual.pulse,
                    thickness=virtual.thickness,
                    material=virtual.material,
                    defined=virtual.gates,
                    field="gate",
                    layers=plate_layers(virtual),
                )
            objective = SourceObjective(
                virtual, position, parameterization=case.parameterization, gate=gate
            )
            if case.x0_kind == "offset":
                truth = np.array(
                    truth_setup.true_optimum(position, parameterization=case.parameterization)
                )
                x0 = _random_start(case, truth, objective.bounds)
            else:
                x0 = np.array(case.x0, dtype=np.float64)
            row.update(zip(names["x0"], (float(v) for v in x0), strict=True))
            result = calibrate(
                objective,
                case.method,
                x0,
                budget=case.budget,
                max_iter=case.max_iter,
                xtol=case.xtol,
                settle=case.settle,
                rng=method_seed,
                preset=case.preset,
                **{k: _thawed(v) for k, v in case.params},
            )
            evaluation = evaluate_run(truth_setup, position, result)
        except EchocalError as exc:
            row.update(_failed(str(exc)))
        except Exception as exc:  # a bug in one run must not stop a sweep
            row.update(_failed(f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}"))
        else:
            row.update(
                error_deg=evaluation.error,
                measurements_to_tol=evaluation.measurements_to(case.tolerance),
                iterations_to_tol=evaluation.iterations_to(case.tolerance),
                success=bool(evaluation.error <= case.tolerance),
                n_measurements=result.n_measurements,
                n_iterations=result.n_iterations,
                status=result.status,
                message=result.message,
            )
            row.update(zip(names["estimate"], (float(v) for v in result.x), strict=True))
            row.update(zip(names["truth"], (float(v) for v in evaluation.truth), strict=True))
            history = history_frame(
                [
                    pd.DataFrame(
                        {
                            "case_id": case.case_id,
                            "index": np.arange(result.n_measurements),
                            **dict(zip(angles, result.points.T, strict=True)),
                            "value": result.values,
                        }
                    )
                ],
                case.parameterization,
            )
    row["warnings"] = "\n".join(sorted({str(w.message) for w in caught}))
    row["wall_time"] = time.perf_counter() - t0
    return row, history


def _failed(message: str) -> dict[str, Any]:
    return {
        "error_deg": np.nan,
        "measurements_to_tol": None,
        "iterations_to_tol": None,
        "success": False,
        "n_measurements": 0,
        "n_iterations": 0,
        "status": FAILED,
        "message": message,
    }  # the angle columns it lacks are NaN in runs_frame
