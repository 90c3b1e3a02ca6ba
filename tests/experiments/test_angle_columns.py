"""Stored angles are named for their parameterization; files with the old `a`/`b` still read.

Sweep tables (runs/history Parquet) and scan point records name the two angles
``tilt_x_deg``/``tilt_y_deg`` or ``azimuth_deg``/``coelevation_deg``; tables and records
written before (``a``, ``b``, ``x0_a``, ``truth_b``, ...) are read with the same names.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from echocal.angle_columns import angle_columns, named_angles, record_angles
from echocal.errors import UnknownNameError
from echocal.experiments import storage
from echocal.experiments.runner import history_columns, run_columns
from echocal.scanning.dataset import surface_dataset
from echocal.scanning.grid import ScanGrid


def test_angle_columns_name_both_parameterizations():
    assert angle_columns("tilt") == ("tilt_x_deg", "tilt_y_deg")
    assert angle_columns("azimuth-coelevation", "truth") == (
        "truth_azimuth_deg",
        "truth_coelevation_deg",
    )
    with pytest.raises(UnknownNameError, match="parameterization"):
        angle_columns("polar")


def test_table_columns_follow_the_parameterization_and_keep_a_fixed_order():
    tilt, polar = run_columns("tilt"), run_columns("azimuth-coelevation")
    assert "x0_tilt_x_deg" in tilt and "estimate_tilt_y_deg" in tilt
    assert "x0_azimuth_deg" in polar and "truth_coelevation_deg" in polar
    assert not any(c.endswith(("_a", "_b")) for c in (*tilt, *polar))
    assert len(tilt) == len(polar)  # the same table, only the angle names differ
    assert list(history_columns("azimuth-coelevation")) == [
        "case_id",
        "index",
        "azimuth_deg",
        "coelevation_deg",
        "value",
    ]


def _old_folder(tmp_path, parameterization: str):
    """A results folder as echocal wrote it before the angles were named."""
    spec = {"name": "old", "parameterization": parameterization}
    (tmp_path / storage.SWEEP_JSON).write_text(json.dumps({"format": 1, "spec": spec}))
    runs = {c: [None] for c in run_columns("tilt") if "tilt" not in c}
    runs.update(case_id=["c0"], x0_a=[1.0], x0_b=[2.0], estimate_a=[3.0], estimate_b=[4.0])
    runs.update(truth_a=[5.0], truth_b=[6.0], index=[0])
    frame = pd.DataFrame(runs).drop(columns="index")
    for column, dtype in run_columns("tilt").items():
        if column in frame and dtype in ("float64", "int64", "bool", "Int64"):
            frame[column] = frame[column].fillna(0).astype(dtype)
    frame.to_parquet(tmp_path / storage.RUNS, index=False)
    history = pd.DataFrame(
        {"case_id": ["c0", "c0"], "index": [0, 1], "a": [0.5, 1.5], "b": [-1.0, 2.0]}
    )
    history.assign(value=[0.1, 0.2]).to_parquet(tmp_path / storage.HISTORY, index=False)


@pytest.mark.parametrize("parameterization", ["tilt", "azimuth-coelevation"])
def test_an_old_results_folder_reads_with_named_columns(tmp_path, parameterization):
    _old_folder(tmp_path, parameterization)
    history = storage.read_history(tmp_path)
    first, second = angle_columns(parameterization)
    assert list(history.columns) == list(history_columns(parameterization))
    assert history[first].tolist() == [0.5, 1.5] and history[second].tolist() == [-1.0, 2.0]
    runs = storage.read_runs(tmp_path)
    assert list(runs.columns) == list(run_columns(parameterization))
    row = runs.iloc[0]
    assert [row[c] for c in angle_columns(parameterization, "x0")] == [1.0, 2.0]
    assert [row[c] for c in angle_columns(parameterization, "estimate")] == [3.0, 4.0]
    assert [row[c] for c in angle_columns(parameterization, "truth")] == [5.0, 6.0]


def test_named_angles_leaves_named_tables_alone():
    frame = pd.DataFrame({"tilt_x_deg": [1.0], "tilt_y_deg": [2.0], "label": ["a"]})
    assert named_angles(frame, "tilt") is frame


def test_scan_records_old_and_new_give_the_same_surface():
    grid = ScanGrid(x=(0.0, 0.001), y=(0.0,), z=0.025)
    base = {"status": 0, "tof": 33e-6, "snr": 20.0, "n_measurements": 10}
    new = {
        (0, 0): {**base, "tilt_x_deg": 1.0, "tilt_y_deg": -2.0},
        (0, 1): {**base, "tilt_x_deg": 0.0, "tilt_y_deg": 0.5},
    }
    old = {k: {**base, "a": r["tilt_x_deg"], "b": r["tilt_y_deg"]} for k, r in new.items()}
    assert record_angles(old[(0, 0)], "tilt").tolist() == [1.0, -2.0]
    built = [
        surface_dataset(grid, records, parameterization="tilt", sound_speed=1480.0).dataset
        for records in (new, old)
    ]
    for name in ("tilt_x", "tilt_y", "azimuth", "coelevation", "surface_z"):
        np.testing.assert_array_equal(built[0][name].values, built[1][name].values)
    # the stored tilts are the record's, recomputed through (azimuth, co-elevation): 1e-9 deg
    np.testing.assert_allclose(built[0]["tilt_x"].values[0], [1.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(built[0]["tilt_y"].values[0], [-2.0, 0.5], atol=1e-9)
