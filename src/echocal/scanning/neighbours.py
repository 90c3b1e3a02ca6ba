"""A scan's neighbours: warm starts from the found points around a position, and the
second look — which points are suspicious, which of two attempts to keep, and demoting an
echo far weaker than the scan's strong ones (see :mod:`echocal.scanning.scan`, steps 1
and 4)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.scanning.dataset import STATUS

__all__ = ["attempt_score", "demote_weak", "predict", "suspicious_points"]

FloatArray = NDArray[np.float64]


def predict(
    done: Mapping[tuple[int, int], FloatArray],
    here: FloatArray,
    xy: Mapping[tuple[int, int], FloatArray],
    radius: float,
) -> FloatArray | None:
    """Warm start [deg] (2,) at ``here`` [m] (2,) from found neighbours within ``radius``:
    a least-squares plane a + g·(p − centroid) (minimum-norm where the neighbours are
    collinear or alone), so a steady slope of the normal along a row is extrapolated."""
    keys = [k for k in done if np.hypot(*(xy[k] - here)) <= radius]
    if not keys:
        return None
    pos = np.array([xy[k] for k in keys])
    val = np.array([done[k] for k in keys])
    centre = pos.mean(axis=0)
    scale = max(radius, 1e-12)
    design = np.column_stack([np.ones(len(keys)), (pos - centre) / scale])
    coef, *_ = np.linalg.lstsq(design, val, rcond=1e-6)
    at = np.concatenate([[1.0], (here - centre) / scale])
    return at @ coef


def attempt_score(rec: Mapping[str, Any]) -> tuple[bool, float]:
    """Which of two attempts at a point to keep: a found one, then the stronger echo."""
    snr = rec.get("snr")
    return rec["status"] == 0, float(snr) if snr is not None and np.isfinite(snr) else -np.inf


def demote_weak(rec: dict[str, Any], relative_snr: float, snr_ref: float) -> dict[str, Any]:
    """Demote a found point whose echo is below ``relative_snr`` × the scan's strong
    echoes (its 90th-percentile echo ``snr_ref``)."""
    if rec["status"] == 0 and rec["snr"] < relative_snr * snr_ref:
        rec = {
            **rec,
            "status": STATUS["weak-echo"],
            "message": f"echo {rec['snr']:.3g} < {relative_snr:g} x the scan's "
            f"90th-percentile echo {snr_ref:.3g}: a side lobe or a partial footprint",
        }
    return rec


def suspicious_points(
    records: Mapping[tuple[int, int], Mapping[str, Any]],
    found: Mapping[tuple[int, int], FloatArray],
    xy: FloatArray,
    radius: float,
    *,
    relative_snr: float,
    outlier: float,
) -> tuple[set[tuple[int, int]], float]:
    """Points worth a second, warm look, and the 90th-percentile echo of the found points.

    * missing after a cold start (no neighbour to start from then);
    * found with an echo below ``relative_snr`` × the 90th-percentile echo (a side lobe);
    * found more than ``outlier`` [deg] away from the plane through its trusted
      neighbours (converged to another peak).
    """
    snrs = np.array([records[k]["snr"] for k in found], dtype=np.float64)
    snrs = snrs[np.isfinite(snrs)]
    # the reference is the 90th percentile, not the median: where most points locked
    # onto side lobes (cold starts far from the normal) their median is a side lobe's
    snr_ref = float(np.percentile(snrs, 90)) if snrs.size else np.inf
    weak = {k for k in found if not records[k]["snr"] >= relative_snr * snr_ref}
    good = {k: v for k, v in found.items() if k not in weak}
    pos = {k: xy[k] for k in good}
    outliers = set()
    for key, est in good.items():
        others = {k: v for k, v in good.items() if k != key}
        pred = predict(others, xy[key], pos, radius)
        if pred is not None and np.hypot(*(pred - est)) > outlier:
            outliers.add(key)
    cold = {k for k, r in records.items() if r["status"] != 0 and not r.get("warm")}
    return weak | outliers | cold, snr_ref
