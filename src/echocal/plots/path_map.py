"""The noiseless cost map behind a calibration's path plot, within a budget.

A map of the metric around a simulated calibration's path is a picture, but on the wave
model each of its points is an A-scan, and a far start puts most of them at large tilts,
where an A-scan costs 10–100 times one at normal incidence: a 21 × 21 map of a far-start
calibration cost twice the calibration.  :func:`path_cost_map` draws it from what is
already known where it can:

* **the lobe**: when the setup's lobe profile applies (the whole-recording
  pseudo-energy, a lobe peaking at normal incidence:
  :meth:`~echocal.measurement.detection_radius.LobeProfile.energy_template`), every point
  within the profile's reach of the map's centre (the true optimum) takes the profile's
  noiseless pseudo-energy, interpolated in misalignment and direction, on a fine
  :data:`FINE` × :data:`FINE` grid — no A-scan at all (the profile is computed once per
  setup and position, and cached on disk: :mod:`echocal.measurement.lobe_cache`);
* **a coarse grid**: beyond that reach (or everywhere, without a profile) the metric is
  simulated on the finest grid of the map's square whose points to simulate fit in
  ``max_points`` (by default none beyond a profile's reach, which stays blank, and
  :data:`DEFAULT_MAP_POINTS` without a profile), nearest the centre first, with a
  progress bar, until the budget of ``max_seconds`` runs out (the points left are blank,
  and :attr:`PathMap.stopped` says so); the fine grid takes the coarse grid's values
  interpolated in log scale.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array
from echocal.constants import MAP_POINTS, MAP_SECONDS
from echocal.errors import EchocalValueError
from echocal.evaluation import CostMap, map_resolution
from echocal.geometry import convert_angles
from echocal.measurement.virtual import VirtualSetup
from echocal.signal.gates import TimeGate

__all__ = ["DEFAULT_MAP_POINTS", "DEFAULT_MAP_SECONDS", "FINE", "PathMap", "path_cost_map"]

FloatArray = NDArray[np.float64]

DEFAULT_MAP_POINTS = MAP_POINTS
"""The most noiseless A-scans a path plot's map simulates by default (its budget in points,
:data:`echocal.constants.MAP_POINTS`)."""
DEFAULT_MAP_SECONDS = MAP_SECONDS
"""[s] the map stops simulating after this long (:data:`echocal.constants.MAP_SECONDS`)."""
FINE = 101
"""Grid points per axis where the lobe profile gives the map's values (no A-scan)."""
_CHUNK = 8
"""Points simulated per call (the progress bar's step and the time budget's check)."""
_MAX_COARSE = 41
"""The coarse grid never has more points per axis (a finer one adds nothing to a picture)."""


@dataclass(frozen=True)
class PathMap:
    """A path plot's cost map and what it cost.

    Attributes
    ----------
    cost_map : the map (NaN where nothing was computed).
    simulated : noiseless A-scans simulated for it.
    planned : A-scans the coarse grid asked for (``simulated < planned``: stopped).
    from_lobe : True when the points near the centre come from the lobe profile.
    reach : [deg] how far from the centre the lobe profile gives the map (0 without one).
    seconds : [s] wall-clock time the simulations took.
    """

    cost_map: CostMap
    simulated: int
    planned: int
    from_lobe: bool
    reach: float
    seconds: float

    @property
    def stopped(self) -> bool:
        """True when the time budget ended the simulations before the grid was done."""
        return self.simulated < self.planned

    def to_dict(self) -> dict[str, Any]:
        """Plain data for JSON (no map values)."""
        return {
            "simulated": self.simulated,
            "planned": self.planned,
            "from_lobe": self.from_lobe,
            "reach_deg": self.reach,
            "seconds": self.seconds,
            "stopped": self.stopped,
            "grid": [len(self.cost_map.a), len(self.cost_map.b)],
        }


def path_cost_map(
    setup: VirtualSetup,
    position: ArrayLike,
    centre: ArrayLike,
    half_span: float,
    *,
    parameterization: str = "tilt",
    gate: TimeGate | None = None,
    max_points: int | None = None,
    max_seconds: float = DEFAULT_MAP_SECONDS,
    progress: bool = False,
) -> PathMap:
    """The noiseless pseudo-energy (inside ``gate``, if given) on the square of half-side
    ``half_span`` [deg] around ``centre`` [deg] (the true optimum, in
    ``parameterization``) at ``position`` [m], within ``max_points`` simulated A-scans
    (≥ 0; 0: only what the lobe profile gives; None: 0 where a lobe profile describes the
    metric, else :data:`DEFAULT_MAP_POINTS`) and ``max_seconds`` [s, > 0]; ``progress``
    shows a bar on stderr (see the module docstring)."""
    if max_points is not None and (
        isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 0
    ):
        raise EchocalValueError(f"map points must be a whole number >= 0; got {max_points!r}")
    if not (isinstance(max_seconds, (int, float)) and max_seconds > 0):
        raise EchocalValueError(f"map seconds must be > 0; got {max_seconds!r}")
    c = finite_array("centre", centre, shape_tail=(2,)).reshape(2)
    pos = finite_array("position", position, shape_tail=(3,)).reshape(3)
    if not (math.isfinite(half_span) and half_span > 0.0):
        raise EchocalValueError(f"half_span must be > 0 deg; got {half_span!r}")
    lobe_of = _lobe_template(setup, pos, gate)
    if max_points is None:
        max_points = 0 if lobe_of is not None else DEFAULT_MAP_POINTS
    if lobe_of is None:
        n = min(map_resolution(setup, half_span), max(math.isqrt(max_points), 0))
        n = max(n, 2)
        a, b = (np.linspace(v - half_span, v + half_span, n) for v in c)
        need = np.ones((n, n), dtype=bool) if max_points >= 4 else np.zeros((n, n), dtype=bool)
        values, done, seconds = _simulate(
            setup, pos, a, b, need, c, parameterization, gate, max_seconds, progress
        )
        names = _names(parameterization)
        return PathMap(CostMap(a, b, values, names), done, int(need.sum()), False, 0.0, seconds)
    template, origin = lobe_of
    reach = float(template.angles[-1])
    peak = float(template.peak) if template.peak is not None else 1.0

    def lobe(a: FloatArray, b: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
        offsets = _tilt_offsets(a, b, origin, parameterization)
        inside = np.hypot(offsets[..., 0], offsets[..., 1]) <= reach
        return np.where(inside, peak * template(offsets), np.nan), inside

    a, b = (np.linspace(v - half_span, v + half_span, FINE) for v in c)
    fine, inside = lobe(a[:, None], b[None, :])
    n = _coarse_size(c, origin, half_span, reach, parameterization, max_points)
    if n == 0 or np.all(inside):
        names = _names(parameterization)
        return PathMap(CostMap(a, b, fine, names), 0, 0, True, reach, 0.0)
    ac, bc = (np.linspace(v - half_span, v + half_span, n) for v in c)
    known, known_inside = lobe(ac[:, None], bc[None, :])
    need = ~known_inside
    simulated, done, seconds = _simulate(
        setup, pos, ac, bc, need, c, parameterization, gate, max_seconds, progress
    )
    coarse = np.where(known_inside, known, simulated)
    fine = np.where(inside, fine, _log_interp(ac, bc, coarse, a, b))
    names = _names(parameterization)
    return PathMap(CostMap(a, b, fine, names), done, int(need.sum()), True, reach, seconds)


def _names(parameterization: str) -> tuple[str, str]:
    from echocal.calibrate.objective import PARAMETERIZATIONS

    return PARAMETERIZATIONS[parameterization]


def _lobe_template(
    setup: VirtualSetup, position: FloatArray, gate: TimeGate | None
) -> tuple[Any, FloatArray] | None:
    """The setup's pseudo-energy lobe template at ``position`` (absolute peak) and the
    gimbal tilts [deg] (2,) it is centred on, or None (a gate: the profile is the whole
    recording's; a lobe the profile cannot describe; no normal incidence from here)."""
    if gate is not None:
        return None
    from echocal.errors import GeometryError
    from echocal.measurement.detection_radius import cached_lobe_profile

    try:
        profile = cached_lobe_profile(setup, position)
    except GeometryError:
        return None
    template = profile.energy_template(absolute=True)
    if template is None or profile.centre is None:
        return None
    return template, np.asarray(profile.centre, dtype=np.float64)


def _tilt_offsets(a: ArrayLike, b: ArrayLike, origin: FloatArray, param: str) -> FloatArray:
    """[deg] gimbal-tilt offsets of the orientations ``(a, b)`` (in ``param``) from the
    tilts ``origin`` (2,), shape ``(..., 2)`` (the lobe profile's misalignments)."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    ta, tb = convert_angles(a, b, param, "tilt")
    return np.stack([np.asarray(ta) - origin[0], np.asarray(tb) - origin[1]], axis=-1)


def _coarse_size(
    centre: FloatArray,
    origin: FloatArray,
    half_span: float,
    reach: float,
    param: str,
    max_points: int,
) -> int:
    """Points per axis of the finest coarse grid (≤ :data:`_MAX_COARSE`) of the square of
    half-side ``half_span`` [deg] about ``centre`` (in ``param``) whose points beyond
    ``reach`` [deg] of the tilts ``origin`` fit in ``max_points``; 0 when none does."""
    for n in range(_MAX_COARSE, 1, -1):
        axis = np.linspace(-half_span, half_span, n)
        offsets = _tilt_offsets(centre[0] + axis[:, None], centre[1] + axis[None, :], origin, param)
        if int(np.count_nonzero(np.hypot(offsets[..., 0], offsets[..., 1]) > reach)) <= max_points:
            return n
    return 0


def _simulate(
    setup: VirtualSetup,
    position: FloatArray,
    a: FloatArray,
    b: FloatArray,
    need: NDArray[np.bool_],
    centre: FloatArray,
    param: str,
    gate: TimeGate | None,
    max_seconds: float,
    progress: bool,
) -> tuple[FloatArray, int, float]:
    """The noiseless metric at the grid points ``need`` (shape ``(len(a), len(b))``),
    nearest ``centre`` first, in chunks, until ``max_seconds`` [s] have passed; NaN
    elsewhere.  Returns the values, the points simulated and the seconds taken."""
    from echocal._progress import ProgressBar

    values = np.full(need.shape, np.nan)
    ia, ib = np.nonzero(need)
    order = np.argsort(np.hypot(a[ia] - centre[0], b[ib] - centre[1]), kind="stable")
    ia, ib = ia[order], ib[order]
    t0 = time.perf_counter()
    done = 0
    with ProgressBar(
        "path map", total=ia.size, enabled=progress and ia.size > 0, unit="A-scans"
    ) as bar:
        for lo in range(0, ia.size, _CHUNK):
            if time.perf_counter() - t0 > max_seconds:
                break
            sl = slice(lo, lo + _CHUNK)
            values[ia[sl], ib[sl]] = setup.metric_values(
                position, a[ia[sl]], b[ib[sl]], parameterization=param, gate=gate
            )
            done += len(ia[sl])
            for _ in range(len(ia[sl])):
                bar.advance()
    return values, done, time.perf_counter() - t0


def _log_interp(
    ac: FloatArray, bc: FloatArray, coarse: FloatArray, a: FloatArray, b: FloatArray
) -> FloatArray:
    """The coarse grid's values (> 0, NaN where unknown) at the fine grid ``a × b``,
    interpolated linearly in their logarithm (a lobe's tails span decades)."""
    from scipy.interpolate import RegularGridInterpolator

    tiny = np.finfo(np.float64).tiny
    with np.errstate(invalid="ignore"):
        logs = np.log(np.maximum(coarse, tiny))
    interp = RegularGridInterpolator((ac, bc), logs, method="linear")
    grid = np.stack(np.meshgrid(a, b, indexing="ij"), axis=-1)
    return np.asarray(np.exp(interp(grid)), dtype=np.float64)
