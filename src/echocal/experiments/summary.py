"""Sweep summaries: how reliably and how cheaply each configuration reaches the tolerance."""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["GROUP_COLUMNS", "summarize"]

GROUP_COLUMNS = ("method", "label", "preset", "params", "snr_db", "x0_kind")
"""One summary row per configuration: method (label, preset), options, SNR, kind of start."""


def _stats(group: pd.DataFrame) -> pd.Series:
    n = len(group)
    success = group["success"].to_numpy(dtype=bool)
    rate = float(success.mean()) if n else float("nan")
    to_tol = group.loc[success, "measurements_to_tol"].dropna().to_numpy(dtype=np.float64)
    iters = group.loc[success, "iterations_to_tol"].dropna().to_numpy(dtype=np.float64)
    mean_meas = float(group["n_measurements"].mean())
    return pd.Series(
        {
            "runs": n,
            "failed": int((group["status"] < 0).sum()),
            "success_rate": rate,
            "median_measurements_to_tol": np.median(to_tol) if to_tol.size else np.nan,
            "p90_measurements_to_tol": np.percentile(to_tol, 90) if to_tol.size else np.nan,
            "median_iterations_to_tol": np.median(iters) if iters.size else np.nan,
            "mean_measurements": mean_meas,
            "expected_measurements_to_success": mean_meas / rate if rate > 0 else np.inf,
            "median_error_deg": float(group["error_deg"].median()),
        }
    )


def summarize(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per configuration (:data:`GROUP_COLUMNS`) of a runs table.

    Columns: ``runs``; ``failed`` (runs that raised); ``success_rate`` (final error ≤
    tolerance); ``median_measurements_to_tol`` and ``p90_measurements_to_tol`` (over the
    successful runs; 90th percentile by linear interpolation; NaN when none succeeded);
    ``median_iterations_to_tol``; ``mean_measurements`` (every measurement a run spent);
    ``expected_measurements_to_success`` = mean_measurements / success_rate (inf when no
    run succeeded: the expected cost of repeating a run until one succeeds);
    ``median_error_deg`` [deg] final angular error.  Rows keep the order of first
    appearance (the sweep's expansion order).
    """
    keys = list(GROUP_COLUMNS)
    if runs.empty:
        return pd.DataFrame(columns=[*keys, *_stats(runs.iloc[:0]).index])
    frame = runs.copy()
    frame["preset"] = frame["preset"].fillna("")
    grouped = frame.groupby(keys, dropna=False, sort=False)
    out = pd.DataFrame(
        [{**dict(zip(keys, key, strict=True)), **_stats(group)} for key, group in grouped]
    )
    out["preset"] = pd.Series([p or None for p in out["preset"]], index=out.index, dtype=object)
    out["runs"] = out["runs"].astype("int64")
    out["failed"] = out["failed"].astype("int64")
    return out.reset_index(drop=True)
