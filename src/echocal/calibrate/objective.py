"""The calibration objective: measure values at orientation points, count and log everything.

An :class:`Objective` wraps a vectorized "measure the pseudo-energy at these angles"
function.  It is the single place where measurements are counted, logged, limited by a
budget and kept inside the positioner's angle bounds, so optimizers never have to trust each
other's bookkeeping.

Subclasses override one method, :meth:`Objective._evaluate`.  Angles are degrees; the two
axes are either (azimuth, co-elevation) or (tilt-x, tilt-y) — the optimizers do not care
which.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._rng import RngLike, as_generator
from echocal._validate import finite_array, finite_float, nonnegative_float, one_of, positive_int
from echocal.calibrate.lobe_template import LobeTemplate
from echocal.calibrate.posterior_search import EchoHypotheses, EchoLikelihood
from echocal.errors import BudgetExhaustedError, EchocalValueError, LimitError

__all__ = [
    "PARAMETERIZATIONS",
    "FunctionObjective",
    "MeasurementLog",
    "Objective",
    "as_bounds",
    "as_points",
]

FloatArray = NDArray[np.float64]

PARAMETERIZATIONS: dict[str, tuple[str, str]] = {
    "azimuth-coelevation": ("azimuth", "coelevation"),
    "tilt": ("tilt_x", "tilt_y"),
}
"""The two angle parameterizations and the names of their axes [deg]."""

_UNBOUNDED = np.array([[-np.inf, np.inf], [-np.inf, np.inf]])


def as_points(name: str, points: ArrayLike) -> FloatArray:
    """Return ``points`` as a finite float array of shape ``(k, 2)`` [deg].

    A single point of shape ``(2,)`` becomes ``(1, 2)``.
    """
    arr = finite_array(name, points)
    if arr.ndim == 1 and arr.shape == (2,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise EchocalValueError(f"{name} must have shape (k, 2) [deg]; got shape {arr.shape}")
    return arr


def as_bounds(bounds: ArrayLike | None) -> FloatArray:
    """Return angle bounds as shape ``(2, 2)`` ``[[lo0, hi0], [lo1, hi1]]`` [deg].

    ``None`` means unbounded.  Infinite entries are allowed; NaN and lo > hi are not.
    """
    if bounds is None:
        return _UNBOUNDED.copy()
    try:
        arr = np.asarray(bounds, dtype=np.float64)
    except (TypeError, ValueError):
        raise EchocalValueError(f"bounds must be numeric; got {bounds!r}") from None
    if arr.shape != (2, 2):
        raise EchocalValueError(
            f"bounds must have shape (2, 2) [[lo0, hi0], [lo1, hi1]] [deg]; got shape {arr.shape}"
        )
    if np.any(np.isnan(arr)) or np.any(arr[:, 0] > arr[:, 1]):
        raise EchocalValueError(f"bounds must be intervals with lo <= hi and no NaN; got {arr}")
    return arr


@dataclass(frozen=True, slots=True)
class MeasurementLog:
    """Every measurement of an objective, in order.

    Attributes
    ----------
    points : [deg], shape (n_measurements, 2) — the angles actually measured (after clipping).
    values : [energy units], shape (n_measurements,) — raw values, NaN kept.
    times : [s], shape (n_measurements,) — wall-clock time (``time.time()``) of each value.
    """

    points: FloatArray
    values: FloatArray
    times: FloatArray


class Objective:
    """Base class: a counted, logged, budgeted and bounded measurement of f(θ).

    Parameters
    ----------
    bounds : [deg], shape (2, 2) ``[[lo0, hi0], [lo1, hi1]]``, or None (unbounded).
    budget : maximum number of measurements (every repeat counts), or None.
    out_of_bounds : ``"clip"`` (measure the nearest reachable point; the log holds
        the clipped point) or ``"error"`` (raise :class:`~echocal.errors.LimitError`).
    repeats : measure each point this many times and return the mean of the
        finite repeats (NaN only if all repeats are NaN); each repeat is counted and logged.
    parameterization : ``"azimuth-coelevation"`` or ``"tilt"``.
    description : one line for logs and reports.
    noise_sigma : [energy units] the standard deviation of the additive
        measurement noise when known (used by the acquisition phase), else None.
    noise_floor : [energy units] the mean value of pure noise (no echo) when known, else None.
    """

    def __init__(
        self,
        *,
        bounds: ArrayLike | None = None,
        budget: int | None = None,
        out_of_bounds: str = "clip",
        repeats: int = 1,
        parameterization: str = "azimuth-coelevation",
        description: str = "objective",
        noise_sigma: float | None = None,
        noise_floor: float | None = None,
    ) -> None:
        self.bounds = as_bounds(bounds)
        self.budget = None if budget is None else positive_int("budget", budget)
        self.out_of_bounds = one_of("out_of_bounds", out_of_bounds, ("clip", "error"))
        self.repeats = positive_int("repeats", repeats)
        self.parameterization = one_of("parameterization", parameterization, PARAMETERIZATIONS)
        self.names: tuple[str, str] = PARAMETERIZATIONS[self.parameterization]
        self.description = str(description)
        self.noise_sigma = (
            None if noise_sigma is None else nonnegative_float("noise_sigma", noise_sigma)
        )
        self.noise_floor = None if noise_floor is None else finite_float("noise_floor", noise_floor)
        self._points: list[FloatArray] = []
        self._values: list[FloatArray] = []
        self._times: list[FloatArray] = []
        self.n_measurements = 0
        self.n_nan = 0
        self._last_significance: FloatArray | None = None
        self.search_snr_db: float | None = None
        """[dB] the echo's peak SNR that the last :meth:`passes_for_measured_noise` sized
        its passes for; None before, or when it gave none."""
        self.bench_time: float | None = None
        """[s] the bench time of every measurement so far (motion, settling, acquisition)
        as its source reported it; None while the source reports none."""

    # -- to override -------------------------------------------------------------------
    def _evaluate(self, points: FloatArray) -> ArrayLike:
        """Measure f at ``points`` [deg], shape (k, 2); return values, shape (k,)."""
        raise NotImplementedError

    def _significance(self) -> FloatArray | None:
        """Detection significance of each point of the last :meth:`_evaluate`, shape (k,),
        or None when this objective cannot tell (the default)."""
        return None

    # -- what a source may know; the base class (an analytic function) knows none: None --
    def echo_floor(self) -> float | None:
        """[objective units] a level the optimum's echo is known to exceed (half a
        simulator's noiseless echo at normal incidence): an estimate below it found a side
        lobe or grain noise, not the surface's main lobe."""
        return None

    def bench_uncertainty(self) -> float | None:
        """[deg] the RMS angle between a commanded and a reached orientation (a simulated
        bench's positioner): a calibration cannot resolve the optimum below it."""
        return None

    def _bench_spent(self) -> float | None:
        """[s] the bench time the last :meth:`_evaluate` cost."""
        return None

    def move_times(self, points: FloatArray) -> FloatArray | None:
        """[s] ``(k,)`` the predicted time (motion and settling) to reach each of ``points``
        [deg] ``(k, 2)`` from where the positioner is, for a motion-aware objective."""
        return None

    def measurement_price(self) -> float | None:
        """[s] the bench time of one point apart from its travel (acquisitions, settling),
        for a motion-aware objective: :meth:`move_times`' moves are weighed against it."""
        return None

    # -- public ------------------------------------------------------------------------
    @property
    def remaining(self) -> int | None:
        """Measurements left in the budget (None when unlimited)."""
        return None if self.budget is None else self.budget - self.n_measurements

    @property
    def log(self) -> MeasurementLog:
        """All measurements so far as arrays (copies)."""
        if not self._points:
            return MeasurementLog(np.zeros((0, 2)), np.zeros(0), np.zeros(0))
        return MeasurementLog(
            np.concatenate(self._points), np.concatenate(self._values), np.concatenate(self._times)
        )

    def noise_estimate(self) -> tuple[float | None, float | None]:
        """Current ``(noise_floor, noise_sigma)`` of the values [energy units], None if unknown.

        The base class returns the fixed attributes; a subclass that can measure its
        noise (e.g. from the quiet part of each A-scan) returns live estimates.
        """
        return self.noise_floor, self.noise_sigma

    def detections(self) -> FloatArray | None:
        """How surely each point of the last call shows an echo, shape (k,), or None.

        Gaussian-equivalent significances (≈ N(0, 1) where there is only noise; see
        :class:`~echocal.signal.detection.EchoDetector`), repeats combined as Σg/√n.
        None when the objective has no such channel (e.g. an analytic function): the
        acquisition phase then tests the values themselves.
        """
        return None if self._last_significance is None else self._last_significance.copy()

    def search_passes(self) -> tuple[float, ...] | None:
        """[deg] the spacings of a blind search's passes, coarse first, sized from the
        probe (:func:`echocal.measurement.detection_radius.search_passes`); None: the
        method's defaults."""
        return None

    def passes_for_measured_noise(self) -> tuple[float, ...] | None:
        """[deg] the passes for the echo predicted against the noise measured so far
        (:func:`echocal.measurement.detection_radius.passes_for_noise`; its SNR kept in
        :attr:`search_snr_db`); None when no echo is predicted, or one too weak for any."""
        return None

    def echo_likelihood(self) -> EchoLikelihood | EchoHypotheses | None:
        """How each measurement's echo significance is distributed versus misalignment,
        against the noise measured so far (:mod:`echocal.calibrate.posterior_search`), for
        a Bayesian search of a lost echo."""
        return None

    def lobe_template(self) -> LobeTemplate | None:
        """The probe's lobe: the metric relative to its peak versus misalignment
        (:mod:`echocal.calibrate.lobe_template`)."""
        return None

    def normal_echo(self) -> float | None:
        """[objective units] the noiseless echo at the probe's best direction of normal
        incidence: the optimum's is at least this, so a refined peak far below is a side
        lobe."""
        return None

    def resolution(self) -> float | None:
        """[deg] the finest detail the values resolve (a replay's grid step); None:
        continuous."""
        return None

    def cost(self, n_points: int) -> int:
        """Measurements needed to evaluate ``n_points`` points (``n_points * repeats``)."""
        return int(n_points) * self.repeats

    def check_point(self, name: str, point: ArrayLike) -> FloatArray:
        """Return ``point`` (shape (2,)) if inside the bounds, else raise LimitError naming it."""
        p = as_points(name, point)[0]
        self._check_bounds(name, p[None, :])
        return p

    def _check_bounds(self, name: str, pts: FloatArray) -> None:
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        bad = np.any((pts < lo) | (pts > hi), axis=1)
        if np.any(bad):
            p = pts[int(np.argmax(bad))]
            raise LimitError(
                f"{name} ({self.names[0]}={p[0]:g}, {self.names[1]}={p[1]:g}) deg is outside "
                f"the bounds {self.names[0]} in [{lo[0]:g}, {hi[0]:g}], "
                f"{self.names[1]} in [{lo[1]:g}, {hi[1]:g}]"
            )

    def __call__(self, points: ArrayLike) -> FloatArray:
        """Measure f at ``points`` [deg], shape (k, 2) (or (2,)); return values, shape (k,).

        Raises
        ------
        BudgetExhaustedError : if the batch does not fit in the remaining budget
            (nothing of the batch is measured then).
        LimitError : if a point is outside the bounds and ``out_of_bounds="error"``.
        """
        pts = as_points("points", points)
        if self.out_of_bounds == "error":
            self._check_bounds("point", pts)
        else:
            pts = np.clip(pts, self.bounds[:, 0], self.bounds[:, 1])
        need = self.cost(len(pts))
        if self.budget is not None and need > self.budget - self.n_measurements:
            raise BudgetExhaustedError(
                f"measurement budget exhausted: {len(pts)} point(s) x {self.repeats} repeat(s) "
                f"need {need} measurements but only {self.budget - self.n_measurements} of "
                f"budget={self.budget} remain"
            )
        reps = []
        significances: list[FloatArray] = []
        for _ in range(self.repeats):
            vals = np.asarray(self._evaluate(pts.copy()), dtype=np.float64).reshape(-1)
            if vals.shape != (len(pts),):
                raise EchocalValueError(
                    f"_evaluate must return shape ({len(pts)},); got shape {vals.shape}"
                )
            now = time.time()
            self._points.append(pts.copy())
            self._values.append(vals.copy())
            self._times.append(np.full(len(pts), now))
            self.n_measurements += len(pts)
            self.n_nan += int(np.count_nonzero(np.isnan(vals)))
            reps.append(vals)
            spent = self._bench_spent()
            if spent is not None:
                self.bench_time = (self.bench_time or 0.0) + spent
            sig = self._significance()
            if sig is not None:
                significances.append(np.asarray(sig, dtype=np.float64).reshape(len(pts)))
        self._last_significance = _stouffer(significances) if significances else None
        stack = np.stack(reps)
        finite = np.isfinite(stack)
        counts = finite.sum(axis=0)
        sums = np.where(finite, stack, 0.0).sum(axis=0)
        out = np.full(len(pts), np.nan)
        np.divide(sums, counts, out=out, where=counts > 0)
        return out


def _stouffer(significances: list[FloatArray]) -> FloatArray:
    """Σg/√n over the non-NaN entries of each column of a (n_repeats, k) list; NaN if none."""
    stack = np.stack(significances)
    finite = ~np.isnan(stack)
    counts = finite.sum(axis=0)
    total = np.where(finite, stack, 0.0).sum(axis=0)
    out = np.full(stack.shape[1], np.nan)
    np.divide(total, np.sqrt(counts), out=out, where=counts > 0)
    return out


class FunctionObjective(Objective):
    """An analytic objective f(θ) plus seeded Gaussian noise (for tests and studies).

    Parameters
    ----------
    func : vectorized callable, points [deg] shape (k, 2) -> values shape (k,).
    noise_sigma : [energy units] standard deviation of the additive noise (fixed,
        so relative noise grows off-peak, as on a real instrument).
    rng : seed or Generator for the noise.
    optimum : [deg], shape (2,), the known maximizer if any (for error reports).
    noise_floor : [energy units] f far from the peak, if known (e.g. 0 for a peak on zero).

    Notes
    -----
    Other keywords as :class:`Objective`.
    """

    def __init__(
        self,
        func: Callable[[FloatArray], ArrayLike],
        *,
        bounds: ArrayLike | None = None,
        budget: int | None = None,
        noise_sigma: float = 0.0,
        rng: RngLike = None,
        out_of_bounds: str = "clip",
        repeats: int = 1,
        parameterization: str = "azimuth-coelevation",
        description: str = "analytic function",
        optimum: ArrayLike | None = None,
        noise_floor: float | None = None,
    ) -> None:
        if not callable(func):
            raise EchocalValueError(f"func must be callable; got {type(func).__name__}")
        super().__init__(
            bounds=bounds,
            budget=budget,
            out_of_bounds=out_of_bounds,
            repeats=repeats,
            parameterization=parameterization,
            description=description,
            noise_sigma=noise_sigma,
            noise_floor=noise_floor,
        )
        self.func = func
        self.rng = as_generator(rng)
        self.optimum = None if optimum is None else as_points("optimum", optimum)[0]

    def _evaluate(self, points: FloatArray) -> FloatArray:
        vals = np.asarray(self.func(points), dtype=np.float64).reshape(-1)
        if self.noise_sigma:
            vals = vals + self.noise_sigma * self.rng.standard_normal(vals.shape)
        return vals
