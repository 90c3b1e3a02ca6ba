"""Refusing a scan whose every point would fail, before anything is measured or written."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array, one_of, positive_int
from echocal.calibrate import build_optimizer, method_names
from echocal.errors import EchocalError, EchocalValueError, LimitError
from echocal.geometry import PARAMETERIZATIONS
from echocal.measurement.base import MeasurementSource
from echocal.measurement.objective import SourceObjective
from echocal.scanning.defaults import point_options
from echocal.scanning.grid import ScanGrid
from echocal.signal import Pulse

__all__ = ["check_scan"]

FloatArray = NDArray[np.float64]


def check_scan(
    source: MeasurementSource,
    grid: ScanGrid,
    *,
    method: str = "auto",
    parameterization: str = "tilt",
    budget_per_point: int = 80,
    tof_repeats: int = 2,
    x0: ArrayLike = (0.0, 0.0),
    pulse: Pulse | None = None,
    method_options: Mapping[str, Any] | None = None,
) -> int:
    """Refuse a scan whose every point would fail, before anything is measured or written.

    Checks the method and parameterization names, the probe heights against the
    positioner's z limits, that some grid point lies within its x/y limits (a point
    outside them is a per-point ``source-error``, as at a part's edge), and that
    ``budget_per_point`` covers one iteration of ``method`` (with ``method_options``)
    plus the ``tof_repeats`` time-of-flight A-scans.  On a simulator, also that the
    first measurement (at ``x0``) does not fail at every grid point — the probe inside
    the specimen, a window that cannot contain the echo.  Raises
    :class:`~echocal.errors.EchocalValueError` or :class:`~echocal.errors.LimitError`
    naming the setting and what is allowed.  Returns the fewest measurements one attempt
    at a point needs (that iteration and the time-of-flight A-scans).
    """
    one_of("parameterization", parameterization, PARAMETERIZATIONS)
    one_of("method", method, method_names())
    budget = positive_int("budget_per_point", budget_per_point)
    tof_repeats = positive_int("tof_repeats", tof_repeats)
    start = finite_array("x0", x0)
    if start.shape != (2,):
        raise EchocalValueError(f"x0 must be 2 angles [deg], shape (2,); got shape {start.shape}")
    limits = source.limits
    heights = grid.heights()
    (z_lo, z_hi), (x_lo, x_hi), (y_lo, y_hi) = limits.z, limits.x, limits.y
    low, high = heights < z_lo, heights > z_hi
    if np.any(low | high):
        z = float(heights[low | high][0])
        raise LimitError(
            f"probe height z={z * 1e3:g} mm is outside the positioner's z limits "
            f"[{z_lo * 1e3:g}, {z_hi * 1e3:g}] mm ({np.count_nonzero(low | high)} of "
            f"{grid.size} points): every such point would fail; choose a stand-off "
            "within the limits (--z)"
        )
    positions = grid.positions().reshape(-1, 3)
    reach = (
        (positions[:, 0] >= x_lo)
        & (positions[:, 0] <= x_hi)
        & (positions[:, 1] >= y_lo)
        & (positions[:, 1] <= y_hi)
    )
    if not np.any(reach):
        raise LimitError(
            f"no grid point lies within the positioner's limits x in [{x_lo * 1e3:g}, "
            f"{x_hi * 1e3:g}] mm, y in [{y_lo * 1e3:g}, {y_hi * 1e3:g}] mm; move the grid "
            "(--grid)"
        )
    objective = SourceObjective(
        source, positions[int(np.argmax(reach))], parameterization=parameterization, pulse=pulse
    )
    start = np.clip(start, objective.bounds[:, 0], objective.bounds[:, 1])
    try:
        opt, _ = build_optimizer(
            objective,
            method,
            start,
            rng=np.random.default_rng(0),
            options=dict(point_options(method, method_options or {})),
        )
    except EchocalError:
        raise
    except Exception as exc:  # a method's own check that is not an echocal error
        raise EchocalValueError(
            f"method_options for method {method!r}: {type(exc).__name__}: {exc}"
        ) from None
    _check_echo_possible(source, positions[reach], start, parameterization)
    need = objective.cost(opt.min_budget)
    if budget < need + tof_repeats:
        raise EchocalValueError(
            f"budget_per_point={budget} is too small: method {method!r} needs {need} "
            f"measurements for one iteration, plus {tof_repeats} time-of-flight A-scans; "
            f"allowed: budget_per_point >= {need + tof_repeats} (--budget-per-point)"
        )
    return need + tof_repeats


def _check_echo_possible(
    source: MeasurementSource, positions: FloatArray, start: FloatArray, parameterization: str
) -> None:
    """Refuse a scan whose every point fails its first measurement (simulators only).

    Each point's calibration starts cold at ``start`` [deg] until a neighbour is found, so
    when the simulation at ``start`` fails at every reachable position [m] ``(N, 3)`` —
    the probe inside the specimen, a window that cannot contain the echo — no point can
    be found.  The centre position is checked first; only when it fails are the others.
    """
    from echocal.geometry import pose_from_angles
    from echocal.measurement.recording import simulation_errors

    def error_at(k: int) -> str | None:
        pose = pose_from_angles(positions[k], float(start[0]), float(start[1]), parameterization)
        (error,) = simulation_errors(source, [pose])
        return error

    centre = int(np.argmin(np.sum((positions - positions.mean(axis=0)) ** 2, axis=1)))
    error = error_at(centre)
    if error is None or any(error_at(k) is None for k in range(len(positions)) if k != centre):
        return
    x, y, z = (1e3 * v for v in positions[centre])
    raise EchocalValueError(
        f"every grid point would fail ({len(positions)} of {len(positions)}), e.g. at "
        f"({x:g}, {y:g}, {z:g}) mm: {error}; choose another stand-off (--z), grid (--grid) "
        "or setup"
    )
