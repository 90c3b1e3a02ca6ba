"""Names of the two angles [deg] in stored tables and records, for their parameterization.

Sweep tables (Parquet) and surface-scan point records (``points.jsonl``) name the angles
of the parameterization they were run in.

A tilt sweep stores ``tilt_x_deg`` / ``tilt_y_deg`` (history) and ``x0_tilt_x_deg``,
``estimate_tilt_x_deg``, ``truth_tilt_x_deg``, ... (runs); an (azimuth, co-elevation)
sweep ``azimuth_deg`` / ``coelevation_deg`` and ``x0_azimuth_deg``, ...  Tables written
before the angles were named (columns ``a``/``b``, ``x0_a``, ``estimate_b``, ...) are read
by :func:`named_angles`, which renames those columns for the sweep's parameterization;
a scan record is read by :func:`record_angles` (``a``/``b`` in older records).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from echocal._validate import one_of

__all__ = ["ANGLE_ROLES", "angle_columns", "named_angles", "record_angles"]

ANGLE_ROLES = ("x0", "estimate", "truth")
"""The runs table's angle pairs [deg]: the start, the final estimate, the true optimum."""


def angle_columns(parameterization: str, role: str | None = None) -> tuple[str, str]:
    """The two angle columns [deg] of ``parameterization``, prefixed by ``role`` if given:
    ``("tilt_x_deg", "tilt_y_deg")``, ``("x0_azimuth_deg", "x0_coelevation_deg")``."""
    from echocal.calibrate.objective import PARAMETERIZATIONS  # lazy: the calibrate package

    one_of("parameterization", parameterization, PARAMETERIZATIONS)
    prefix = f"{role}_" if role else ""
    first, second = PARAMETERIZATIONS[parameterization]
    return f"{prefix}{first}_deg", f"{prefix}{second}_deg"


def named_angles(frame: pd.DataFrame, parameterization: str) -> pd.DataFrame:
    """``frame`` with legacy angle columns (``a``, ``b``, ``x0_a``, ``truth_b``, ...)
    renamed for ``parameterization``; a frame without them is returned as it is."""
    legacy = {"a": angle_columns(parameterization)[0], "b": angle_columns(parameterization)[1]}
    for role in ANGLE_ROLES:
        first, second = angle_columns(parameterization, role)
        legacy.update({f"{role}_a": first, f"{role}_b": second})
    found = {old: new for old, new in legacy.items() if old in frame.columns}
    return frame.rename(columns=found) if found else frame


def record_angles(record: Mapping[str, Any], parameterization: str) -> np.ndarray:
    """[deg] the two angles of a scan point ``record``, shape ``(2,)``: its
    :func:`angle_columns` keys, or ``a``/``b`` in a record written before they were named."""
    keys = angle_columns(parameterization)
    if keys[0] not in record and "a" in record:
        keys = ("a", "b")
    return np.array([record[keys[0]], record[keys[1]]], dtype=np.float64)
