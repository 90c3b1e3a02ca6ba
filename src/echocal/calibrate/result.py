"""The result of a calibration run: plain data with the full history (scipy OptimizeResult-like)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal.errors import DataFileError
from echocal.io import atomic_write_text

__all__ = ["NO_ECHO_STATUSES", "STATUS_MESSAGES", "SUCCESS_STATUSES", "CalibrationResult"]

FloatArray = NDArray[np.float64]

STATUS_MESSAGES: dict[int, str] = {
    0: "converged: the iterate moved less than xtol",
    1: "iteration limit reached",
    2: "measurement budget exhausted",
    3: "stopped by the callback",
    4: "acquisition failed: no echo clearly above the noise floor within the search radius",
    5: "search complete",
    6: "no finite measurement: every value was NaN",
    7: "converged: the recommendation settled (stayed within settle tolerance)",
    8: "estimate at the positioner's angle limit: the optimum may lie beyond reach",
    9: "no echo clearly above the noise floor at the estimate",
    10: "not converged: the measurements do not support the estimate",
}
"""The one status table: status code -> message."""

SUCCESS_STATUSES = frozenset({0, 5, 7})
"""Statuses of a run that met its convergence rule (``xtol``: 0, ``settle``: 7; an
exhaustive search that measured all its points: 5) with the evidence behind it (see
:mod:`echocal.calibrate.evidence`) — what ``success`` means, as scipy's does.  A run
stopped by its budget (2), its iteration limit (1) or a callback (3) still returns its
last estimate, with ``success`` False."""

NO_ECHO_STATUSES = frozenset({4, 6, 9})
"""Statuses of a run that found no echo: ``x`` is not an estimate of anything."""

UNSUPPORTED_STATUSES = frozenset({8, 10})
"""Statuses of a run whose estimate the measurements do not support as the optimum (on the
positioner's limits; a side lobe, a point stronger than the estimate): no uncertainty
radius is reported around it."""

_ARRAYS = ("x", "points", "values", "iterates", "iteration_measurements", "times")
_OPTIONAL_NUMBERS = (
    "fun",
    "final_value",
    "search_snr_db",
    "bench_time",
    "bench_time_saved",
    "bench_uncertainty",
    "uncertainty",
)
"""Fields that are a number or None; a non-finite one is stored as None."""


@dataclass(frozen=True)
class CalibrationResult:
    """Outcome of :func:`echocal.calibrate.calibrate`.

    Attributes
    ----------
    x : [deg], shape (2,) — the estimate (the method's recommendation).
    fun : [energy units] — the mean of the final measurements at ``x`` when it was
        measured (the default), else the model's value at ``x`` if the method has a
        model, else the mean of the values measured exactly at ``x``, else None.
    success : the run met its convergence rule with evidence (:data:`SUCCESS_STATUSES`).
    status, message : why the run stopped (:data:`STATUS_MESSAGES`).
    n_measurements : every measurement of this run (setup, repeats, acquisition, checks).
    n_iterations : completed iterations.
    points : [deg], shape (n_measurements, 2) — all measured points in order.
    values : [energy units], shape (n_measurements,) — raw values, NaN kept.
    iterates : [deg], shape (n_iterations + 1, 2) — x0 then the iterate after each iteration.
    iteration_measurements : shape (n_iterations + 1,) — cumulative measurements at each iterate.
    method, options : the method name and the options it ran with: every option of the
        method with its effective value (defaults included); inputs the objective supplied
        (its noise estimate, its echo detector) are named ``"objective"``.
    wall_time : [s] duration of the run.
    n_nan : measurements that returned NaN (replaced by the worst value seen, at most 0).
    parameterization, names : the angle convention of the objective.
    times : [s], shape (n_measurements,) — wall-clock time of each measurement.
    acquisition_measurements : measurements the acquisition phase spent before it found
        the echo and handed over (None without an acquisition phase or if it never did).
    search_passes : [deg] the passes the acquisition searched beyond x0's first ring, coarse
        first, when it sized them for the noise that ring measured (``replan``); else None.
    search_snr_db : [dB] the echo's peak SNR those passes are sized for; else None.
    posterior_search : the acquisition searched beyond x0's first ring by the posterior
        over the optimum (:mod:`echocal.calibrate.posterior_search`), not on passes.
    final_value : [energy units] the mean of the ``final_check`` measurements at ``x``
        (counted in ``n_measurements``); None when the run did not measure its estimate.
    bench_time : [s] the bench time (motion, settling, acquisition) of the run's
        measurements as the source reported it; None when it reports none.
    bench_time_saved : [s] the motion and settling time a motion-aware objective's order
        saved against the plain order; None without one.
    uncertainty : [deg] the radius around ``x`` that holds the optimum with probability
        ``uncertainty_level``, from the measurements on the lobe's top (measurement noise
        only; ``echocal.calibrate.evidence.estimate_radius``); None when no echo was found,
        the estimate is not supported (:data:`UNSUPPORTED_STATUSES`), the noise is unknown
        or those measurements show no peak.
    uncertainty_level : the confidence level of ``uncertainty`` (0.9).
    false_alarms : detections the local method did not confirm (the search resumed).
    bench_uncertainty : [deg] the RMS angle between a commanded and a reached orientation
        of the source's positioner, which the estimate carries besides the measurement
        noise; None when the source does not know it.
    """

    x: FloatArray
    fun: float | None
    success: bool
    status: int
    message: str
    n_measurements: int
    n_iterations: int
    points: FloatArray
    values: FloatArray
    iterates: FloatArray
    iteration_measurements: NDArray[np.int64]
    method: str
    options: dict[str, Any] = field(default_factory=dict)
    wall_time: float = 0.0
    n_nan: int = 0
    parameterization: str = "azimuth-coelevation"
    names: tuple[str, str] = ("azimuth", "coelevation")
    times: FloatArray = field(default_factory=lambda: np.zeros(0))
    acquisition_measurements: int | None = None
    search_passes: tuple[float, ...] | None = None
    search_snr_db: float | None = None
    posterior_search: bool = False
    final_value: float | None = None
    bench_time: float | None = None
    bench_time_saved: float | None = None
    bench_uncertainty: float | None = None
    false_alarms: int = 0
    uncertainty: float | None = None
    uncertainty_level: float = 0.9

    @property
    def nfev(self) -> int:
        """Alias of ``n_measurements`` (scipy's name)."""
        return self.n_measurements

    @property
    def nit(self) -> int:
        """Alias of ``n_iterations`` (scipy's name)."""
        return self.n_iterations

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict (arrays as lists, NaN as None)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name in _ARRAYS:
                arr = np.asarray(v)
                if arr.dtype.kind == "f":
                    arr = arr.astype(object)
                    arr[np.isnan(arr.astype(float))] = None
                v = arr.tolist()
            elif f.name == "names":
                v = list(v)
            elif f.name in _OPTIONAL_NUMBERS and v is not None and not math.isfinite(v):
                v = None
            elif f.name == "options":
                v = _jsonable(v)
            out[f.name] = v
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CalibrationResult:
        """Inverse of :meth:`to_dict` (a stored ``provenance`` is not part of the result)."""
        kw = {k: v for k, v in data.items() if k != "provenance"}
        for name in _ARRAYS:
            if name in kw:
                raw = kw[name]
                if name == "iteration_measurements":
                    kw[name] = np.asarray(raw, dtype=np.int64)
                else:
                    arr = np.asarray(_none_to_nan(raw), dtype=np.float64)
                    if name in ("points", "iterates"):
                        arr = arr.reshape(-1, 2)
                    kw[name] = arr
        if "names" in kw:
            kw["names"] = tuple(kw["names"])
        if kw.get("search_passes") is not None:
            kw["search_passes"] = tuple(float(v) for v in kw["search_passes"])
        if kw.get("search_snr_db") is not None:
            kw["search_snr_db"] = float(kw["search_snr_db"])
        return cls(**kw)

    def save_json(
        self, path: str | os.PathLike[str], *, provenance: dict[str, Any] | None = None
    ) -> None:
        """Write the result as JSON, atomically; ``provenance`` (a record of
        :mod:`echocal.provenance`) is stored beside it under ``"provenance"``."""
        data = self.to_dict()
        if provenance is not None:
            data["provenance"] = provenance
        atomic_write_text(path, json.dumps(data, indent=1))

    @classmethod
    def load_json(cls, path: str | os.PathLike[str]) -> CalibrationResult:
        """Read a result written by :meth:`save_json`."""
        try:
            with open(path, encoding="utf-8") as fh:
                return cls.from_dict(json.load(fh))
        except (OSError, TypeError, ValueError) as exc:  # ValueError: bad JSON or numbers
            raise DataFileError(f"cannot read calibration result {str(path)!r}: {exc}") from exc


def _none_to_nan(raw: Any) -> Any:
    if isinstance(raw, list):
        return [_none_to_nan(r) for r in raw]
    return np.nan if raw is None else raw


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if v is None or isinstance(v, bool | int | float | str):
        return v
    if callable(v):  # a user's callable option: its name, not a memory address
        name = getattr(v, "__qualname__", type(v).__qualname__)
        return f"callable {getattr(v, '__module__', None) or '?'}.{name}"
    text = repr(v)
    return text if " at 0x" not in text else f"<{type(v).__module__}.{type(v).__qualname__}>"
