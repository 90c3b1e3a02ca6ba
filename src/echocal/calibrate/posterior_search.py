"""Where is a lost echo most likely to be seen next?  A Bayesian search over the optimum.

A lattice search acts only on detections; but a significance of 2 near the optimum is
likelier than far from it, and two measurements on a weak echo can be told apart from two on
noise.  Every measurement, below the threshold too, updates a posterior over where the
optimum is, and the next one goes where a detection is most likely.

Model (:class:`PosteriorSearch`).  The optimum c lies on a square grid of cells within
``max_radius`` of x0, a priori uniform in *distance* (a density ∝ 1/ρ per area) and
direction, half of it "x0 is good" (within :data:`NEAR_RADIUS`, :data:`NEAR_WEIGHT`) and
half "anywhere within reach": a weak echo's search stays around x0 until that disc is
covered, a strong echo's quiet first ring empties it at once — one search for every SNR. A
measurement at x observes the matched-filter envelope's peak t over the window (in units of
the noise's Rayleigh scale σ·gain, recovered from the detector's significance g), the larger
of the echo's envelope, Rice of the noiseless peak ν(|x − c|) (the lobe profile), and the
largest noise envelope N elsewhere, P(N ≤ t) = exp(−M t e^{−t²/2}) (Rice's formula, the
detector's own calibration): f(t | ν) = f_R(t; ν) F_N(t) + F_R(t; ν) f_N(t).  It multiplies
the posterior at c by f(t | ν(|x − c|)) / f(t | 0) (:class:`EchoLikelihood`). The next point
maximizes the detection chance Σ_c post(c) P_detect(|x − c|) (the posterior convolved with
the detection kernel by FFT: the greedy rule of optimal search theory, Koopman; Stone), the
cell nearest x0 among those within :data:`TIE` of the best (a broad kernel makes the chance
nearly flat over a band of radii).  The search gives up on the log Bayes factor of "an
optimum within reach" against "no echo", log Σ_c π(c) Π LR
(:meth:`PosteriorSearch.log_evidence`, over the optima inside the bounds).

Unknown amplitude (:class:`EchoHypotheses`, for a recording or a rig, which do not say how
strong their echo is, nor without a setup the lobe's shape): one :class:`EchoLikelihood` per
hypothesis, with prior weights; the posterior is over (optimum, hypothesis), the hypotheses
marginalized.  Assumed: the peak t is against the noise σ the detector measures in the
A-scans themselves; ν(θ) = A·s(θ), s(0) = 1, isotropic; A uniform in 20·log10 A over
:data:`AMPLITUDE_DB` (30–60 dB on a 3 dB grid; a weaker echo is not searched for, or the
search could never give up); s from the setup's physics where the source names one
(:func:`scaled_lobe`), else a Lorentzian 1 / (1 + (θ/w)²) of unknown width w, uniform in log
w over :data:`WIDTHS` (:func:`lorentzian_lobes`), which follows a piston probe's diffraction
lobe, tails included (a lobe without tails, the ray model's, is broader under it than it
is).  The measurements behind these choices: docs/benchmarks/auto.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import chndtr, i0e, log_ndtr, logsumexp

from echocal.calibrate._fd import FloatArray
from echocal.calibrate._options import positive_float
from echocal.errors import EchocalValueError

__all__ = [
    "AMPLITUDE_DB",
    "GIVE_UP_EVIDENCE",
    "MOTION_TIE",
    "NEAR_RADIUS",
    "NEAR_WEIGHT",
    "TIE",
    "WIDTHS",
    "EchoHypotheses",
    "EchoLikelihood",
    "PosteriorSearch",
    "lorentzian_lobes",
    "rice_cdf",
    "rice_sf",
    "scaled_lobe",
]

GIVE_UP_EVIDENCE = 1e-3
"""The search gives up once the measurements are this much likelier with no echo within
reach than with one from the prior (:meth:`PosteriorSearch.log_evidence`)."""
NEAR_WEIGHT = 0.5
"""The prior's weight on "x0 is good": the optimum within :data:`NEAR_RADIUS` of x0; the
rest on "anywhere within reach", within ``max_radius`` (:class:`PosteriorSearch`)."""
NEAR_RADIUS = 3.0
"""[deg] "x0 is good": the optimum at most this far from x0 (a near start, 1–3° off)."""
TIE = 0.05
"""Cells whose detection chance is within this fraction of the best are equally good: the
one nearest to x0 is measured next (module docstring)."""
MOTION_TIE = 0.15
"""The detection chance a motion-aware step may give up, as a fraction of the best
(:meth:`PosteriorSearch.next_point` given the moves' times and the price of a
measurement): the cell reached soonest among those within this fraction of the best
chance replaces the plain choice only when the move it saves exceeds the price of
1 / MOTION_TIE measurements (``docs/bench.md``)."""
_MAX_CELLS = 401
"""Cells per side of the posterior's grid at most (161,000 cells: 10–18 ms per point, the
FFT about 6 ms; 2–3 ms at ``max_radius`` 20° and a 0.2° cell)."""
_CELL = 0.25
"""[deg] the grid's cell at most; finer for a narrow detection kernel (a quarter of the
distance at which half of the A-scans detect the echo)."""
_KERNEL_FLOOR = 1e-4
"""Detection probabilities below this are left out of the kernel (its reach)."""
_PEAK_TABLE = np.linspace(1.0, 64.0, 4096)
"""Normalized peaks t tabulated to recover t from a significance (t ≥ 1, as Rice's law)."""

AMPLITUDE_DB = tuple(float(a) for a in np.arange(30.0, 60.5, 3.0))
"""[dB] 20·log10 A of the echo's matched-filter peak at the optimum (in units of the
noise's Rayleigh scale) under each hypothesis, equally likely a priori (module docstring)."""
WIDTHS = (0.3, 0.6, 1.2, 2.4)
"""[deg] the Lorentzian lobe's half width w under each hypothesis, equally likely a priori."""
_LORENTZ_ANGLES = np.arange(0.0, 15.05, 0.1)
"""[deg] misalignments the Lorentzian lobes are tabulated at (beyond: no echo)."""


def rice_cdf(x: ArrayLike, b: ArrayLike) -> FloatArray:
    """P(R ≤ x) of Rice's law with shape ``b`` (x, b ≥ 0, broadcast): the non-central χ²
    CDF with 2 degrees of freedom at x² with non-centrality b² (what ``scipy.stats.rice``
    computes, without importing scipy.stats: ~1 CPU-s at every command-line start)."""
    x, b = np.asarray(x, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return np.asarray(chndtr(x * x, 2.0, b * b), dtype=np.float64)


def rice_sf(x: ArrayLike, b: ArrayLike) -> FloatArray:
    """P(R > x) = 1 − :func:`rice_cdf` (Marcum's Q₁(b, x)), as ``scipy.stats.rice.sf``."""
    return 1.0 - rice_cdf(x, b)


@dataclass(frozen=True, eq=False)
class EchoLikelihood:
    """How one A-scan's matched-filter peak is distributed at a given misalignment.

    Attributes
    ----------
    angles : [deg] misalignments, shape ``(n,)``, increasing from 0.
    echo : ν, the noiseless echo's matched-envelope peak in units of the noise's
        Rayleigh scale (σ · the filter's noise gain), shape ``(n,)``; beyond
        ``angles[-1]`` the echo is taken as 0.
    n_cells : M of Rice's formula for the window (:class:`~echocal.signal.detection.EchoDetector`).
    threshold : the detection threshold on the same normalized peak (the significance
        threshold through the detector).
    """

    angles: FloatArray
    echo: FloatArray
    n_cells: float
    threshold: float

    def __post_init__(self) -> None:
        angles = np.asarray(self.angles, dtype=np.float64)
        echo = np.asarray(self.echo, dtype=np.float64)
        if angles.ndim != 1 or echo.shape != angles.shape or len(angles) < 2:
            raise EchocalValueError(
                f"angles and echo must be 1-D of one length >= 2; got shapes {angles.shape} "
                f"and {echo.shape}"
            )
        if not (np.all(np.isfinite(angles)) and angles[0] == 0.0 and np.all(np.diff(angles) > 0)):
            raise EchocalValueError("angles must increase from 0 deg and be finite")
        if not np.all(np.isfinite(echo) & (echo >= 0.0)):
            raise EchocalValueError("echo must be finite and >= 0 (a normalized envelope peak)")
        for name in ("n_cells", "threshold"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0.0):
                raise EchocalValueError(f"{name} must be finite and > 0; got {value!r}")
        object.__setattr__(self, "angles", angles)
        object.__setattr__(self, "echo", echo)

    def peak_of_significance(self, significance: float) -> float:
        """The normalized peak t whose significance is ``significance`` [σ]: the inverse of
        g = Φ⁻¹(exp(−M t e^{−t²/2}))
        (:meth:`~echocal.signal.detection.EchoDetector.significance_of_peak`), by
        interpolation on t ∈ [1, 64] (exact to about 1e-5 for t in [2, 37]; the detector
        floors every peak below about 1.7 at g = −8.2, which maps back to 1.7, and every
        g beyond double precision's tail, about 38, maps to 64)."""
        with np.errstate(divide="ignore"):  # log_ndtr(g) = 0 for g beyond ~38: t = 64
            log_tail = float(np.log(-log_ndtr(significance))) - np.log(self.n_cells)
        h = np.log(_PEAK_TABLE) - 0.5 * _PEAK_TABLE**2  # decreasing in t >= 1
        return float(np.interp(-log_tail, -h, _PEAK_TABLE))

    def log_ratio(self, peak: float) -> FloatArray:
        """ln f(t | ν(θ)) − ln f(t | 0) for an observed normalized peak t, shape ``(n,)``
        (per :attr:`angles`): how much likelier the observation is with the optimum θ away
        than with no echo (module docstring).  Computed with both densities scaled by
        e^{t²/2}, so a peak far in the tail neither under- nor overflows."""
        t, nu = float(max(peak, 1.0)), self.echo
        noise = np.log(self.n_cells * (t * t - 1.0)) if t > 1.0 else -np.inf  # f_N/F_N · e^{t²/2}
        echo_cell = np.log(t) + np.log(i0e(t * nu)) + t * nu - 0.5 * nu * nu
        with np.errstate(divide="ignore"):
            echo_ratio = np.logaddexp(echo_cell, np.log(rice_cdf(t, nu)) + noise)
            noise_only = np.logaddexp(np.log(t), np.log(-np.expm1(-0.5 * t * t)) + noise)
        return np.asarray(echo_ratio - noise_only, dtype=np.float64)

    def detection_probability(self) -> FloatArray:
        """P(t > threshold) at the echo's cell, shape ``(n,)``: Marcum's Q (``rice.sf``)."""
        return rice_sf(self.threshold, self.echo)


@dataclass(frozen=True, eq=False)
class EchoHypotheses:
    """One :class:`EchoLikelihood` per hypothesis on
    the echo's unknown amplitude (and lobe width), and the hypotheses' prior weights.

    Attributes
    ----------
    likelihoods : the hypotheses' likelihoods, shape ``(k,)``; all on the same
        ``angles``, ``n_cells`` and ``threshold`` (one detector).
    log_weights : ln of the prior weights, shape ``(k,)`` (normalized here).
    label : what the hypotheses are (reported with the result).
    """

    likelihoods: tuple[EchoLikelihood, ...]
    log_weights: FloatArray
    label: str = "hypotheses"

    def __post_init__(self) -> None:
        likes = tuple(self.likelihoods)
        weights = np.asarray(self.log_weights, dtype=np.float64)
        if not likes or weights.shape != (len(likes),) or not np.all(np.isfinite(weights)):
            raise EchocalValueError(
                f"log_weights must be finite, one per likelihood ({len(likes)}); got shape "
                f"{weights.shape}"
            )
        first = likes[0]
        for like in likes[1:]:
            same = (
                np.array_equal(like.angles, first.angles)
                and like.n_cells == first.n_cells
                and like.threshold == first.threshold
            )
            if not same:
                raise EchocalValueError(
                    "every hypothesis must share the angles, n_cells and threshold (one detector)"
                )
        weights = weights - np.logaddexp.reduce(weights)
        object.__setattr__(self, "likelihoods", likes)
        object.__setattr__(self, "log_weights", weights)

    @property
    def angles(self) -> FloatArray:
        """[deg] the misalignments every hypothesis is tabulated at, shape ``(n,)``."""
        return self.likelihoods[0].angles

    def detection_probability(self) -> FloatArray:
        """P(t > threshold) at the echo's cell under the prior, shape ``(n,)``: the
        hypotheses' Marcum Q weighted by their prior weights."""
        weights = np.exp(self.log_weights)
        return np.asarray(
            sum(
                w * like.detection_probability()
                for w, like in zip(weights, self.likelihoods, strict=True)
            ),
            dtype=np.float64,
        )


def _amplitudes(amplitudes_db: ArrayLike) -> FloatArray:
    """A for each 20·log10 A [dB] of ``amplitudes_db``, shape ``(k,)``."""
    db = np.asarray(amplitudes_db, dtype=np.float64).reshape(-1)
    if db.size == 0 or not np.all(np.isfinite(db)):
        raise EchocalValueError(f"amplitudes_db must be finite dB values; got {db!r}")
    return np.asarray(10.0 ** (db / 20.0), dtype=np.float64)


def scaled_lobe(
    angles: ArrayLike,
    shape: ArrayLike,
    n_cells: float,
    threshold: float,
    amplitudes_db: ArrayLike = AMPLITUDE_DB,
) -> EchoHypotheses:
    """The hypotheses for a known lobe shape ``shape`` (s(θ) at ``angles`` [deg], shape
    ``(n,)``, normalized here to 1 at θ = 0) of unknown amplitude: one per 20·log10 A in
    ``amplitudes_db`` [dB], equally likely; ``n_cells`` and ``threshold`` as
    :class:`EchoLikelihood`'s (the detector's)."""
    s = np.asarray(shape, dtype=np.float64)
    if s.ndim != 1 or not s.size or not s[0] > 0.0:
        raise EchocalValueError("shape must be 1-D and > 0 at 0 deg (the lobe's peak)")
    s = s / s[0]
    amps = _amplitudes(amplitudes_db)
    likes = tuple(
        EchoLikelihood(
            angles=np.asarray(angles, float), echo=a * s, n_cells=n_cells, threshold=threshold
        )
        for a in amps
    )
    return EchoHypotheses(likes, np.zeros(len(likes)), label="lobe-shape")


def lorentzian_lobes(
    n_cells: float,
    threshold: float,
    widths: ArrayLike = WIDTHS,
    amplitudes_db: ArrayLike = AMPLITUDE_DB,
) -> EchoHypotheses:
    """The hypotheses for a lobe of unknown shape: a Lorentzian 1 / (1 + (θ/w)²) for each
    width w of ``widths`` [deg] times each amplitude of ``amplitudes_db`` [dB], equally
    likely, tabulated out to 15° (module docstring)."""
    w = np.asarray(widths, dtype=np.float64).reshape(-1)
    if w.size == 0 or not np.all(np.isfinite(w) & (w > 0.0)):
        raise EchocalValueError(f"widths must be finite and > 0 deg; got {w!r}")
    amps = _amplitudes(amplitudes_db)
    theta = _LORENTZ_ANGLES
    likes = tuple(
        EchoLikelihood(
            angles=theta,
            echo=a / (1.0 + (theta / width) ** 2),
            n_cells=n_cells,
            threshold=threshold,
        )
        for width in w
        for a in amps
    )
    return EchoHypotheses(likes, np.zeros(len(likes)), label="lorentzian")


class PosteriorSearch:
    """The posterior over the optimum on a grid around ``centre``, and the next point.

    Parameters
    ----------
    centre : [deg] x0, shape ``(2,)``.
    max_radius : [deg] the optimum lies within this distance of ``centre`` (the prior).
    likelihood : the echo's :class:`EchoLikelihood`, or :class:`EchoHypotheses` when its
        amplitude (and lobe width) are unknown: the posterior is then over (optimum,
        hypothesis), and the detection chance and the evidence sum over the hypotheses.
    bounds : [deg] shape ``(2, 2)``: the next point lies inside, and the evidence counts
        the optima inside (:meth:`log_evidence`).
    near_radius : [deg] the reach of the prior's "x0 is good" half (:data:`NEAR_RADIUS`).
    """

    def __init__(
        self,
        centre: FloatArray,
        max_radius: float,
        likelihood: EchoLikelihood | EchoHypotheses,
        bounds: FloatArray,
        near_radius: float = NEAR_RADIUS,
    ) -> None:
        self.likelihood = likelihood
        if isinstance(likelihood, EchoLikelihood):
            self._models: tuple[EchoLikelihood, ...] = (likelihood,)
            self._log_weights = np.zeros(1)
        else:
            self._models = likelihood.likelihoods
            self._log_weights = likelihood.log_weights
        detect = likelihood.detection_probability()
        half = likelihood.angles[detect >= 0.5]
        cell = min(_CELL, 0.25 * float(half[-1])) if half.size else _CELL
        cell = max(cell, 2.0 * max_radius / (_MAX_CELLS - 1))
        self.cell = cell
        """[deg] the grid's cell."""
        n = int(np.ceil(max_radius / cell))
        axis = np.arange(-n, n + 1) * cell
        self._x = centre[0] + axis[None, :]
        self._y = centre[1] + axis[:, None]
        rho = np.hypot(*np.meshgrid(axis, axis))
        self._rho = rho  # [deg] each cell's distance from the centre
        inside_x = (self._x >= bounds[0, 0]) & (self._x <= bounds[0, 1])
        inside_y = (self._y >= bounds[1, 0]) & (self._y <= bounds[1, 1])
        self._candidate = inside_x & inside_y
        near_radius = positive_float("near_radius", near_radius)
        self._log_prior = _mixture_prior(rho, max_radius, cell, near_radius)
        self._log_like = np.zeros((len(self._models), *rho.shape))  # per hypothesis
        # the evidence counts the optima inside the bounds: mass beyond them is never
        # measured, so it would neither deplete nor let the search give up
        self._measurable = np.where(self._candidate, self._log_prior, -np.inf)
        if not np.isfinite(self._measurable).any():
            raise EchocalValueError(
                f"no point within max_radius {max_radius:g} deg of the start lies inside the "
                "bounds: move the start inside them"
            )
        self._measurable -= _logsumexp(self._measurable)
        self._kernels = [self._kernel_of(model, cell) for model in self._models]
        self._reach = float(likelihood.angles[-1])

    @staticmethod
    def _kernel_of(model: EchoLikelihood, cell: float) -> FloatArray:
        """P_detect at each offset [cells] from the optimum out to its reach, square."""
        detect = model.detection_probability()
        reach = model.angles[detect > _KERNEL_FLOOR]
        k = int(np.ceil((float(reach[-1]) if reach.size else cell) / cell))
        offsets = np.arange(-k, k + 1) * cell
        kernel_distance = np.hypot(*np.meshgrid(offsets, offsets))
        return np.asarray(np.interp(kernel_distance, model.angles, detect, right=0.0))

    def update(self, points: FloatArray, significances: FloatArray) -> None:
        """Fold measurements in: ``points`` [deg] shape ``(k, 2)``, their detection
        significances ``(k,)`` [σ] (NaN: no evidence, skipped)."""
        models = self._models
        for (px, py), g in zip(np.asarray(points), np.asarray(significances), strict=True):
            if not np.isfinite(g):
                continue
            peak = models[0].peak_of_significance(float(g))  # one detector for all
            cols = np.abs(self._x[0] - px) <= self._reach
            rows = np.abs(self._y[:, 0] - py) <= self._reach
            if not (cols.any() and rows.any()):
                continue
            dist = np.hypot(self._x[0, cols][None, :] - px, self._y[rows, 0][:, None] - py)
            block = np.ix_(rows, cols)
            for log_like, like in zip(self._log_like, models, strict=True):
                log_like[block] += np.interp(dist, like.angles, like.log_ratio(peak), right=0.0)

    def exclude(self, point: FloatArray) -> None:
        """Never propose the cell of ``point`` [deg] (2,) again (it measured NaN: out of
        the positioner's reach, a dead A-scan)."""
        col = int(np.argmin(np.abs(self._x[0] - point[0])))
        row = int(np.argmin(np.abs(self._y[:, 0] - point[1])))
        self._candidate[row, col] = False

    def _log_joint(self) -> FloatArray:
        """ln of the posterior over (hypothesis, cell), normalized, shape ``(k, m, m)``."""
        log_joint = self._log_weights[:, None, None] + self._log_prior + self._log_like
        return np.asarray(log_joint - _logsumexp(log_joint), dtype=np.float64)

    def log_posterior(self) -> FloatArray:
        """ln of the posterior over the grid's cells (normalized; the hypotheses on the
        echo's amplitude marginalized), shape ``(m, m)``."""
        return np.asarray(logsumexp(self._log_joint(), axis=0), dtype=np.float64)

    def log_evidence(self) -> float:
        """ln Σ_h w_h Σ_c π(c) Π LR_h(c) over the cells inside the bounds (π the prior
        restricted to them, w_h the hypotheses' prior weights): the log Bayes factor of a
        measurable optimum drawn from the prior against no echo within reach of any
        measurement."""
        return _logsumexp(self._log_weights[:, None, None] + self._measurable + self._log_like)

    def detection_chances(self) -> FloatArray:
        """P(detect) of a measurement at each cell under the posterior, shape ``(m, m)``
        (0 outside the bounds): the posterior convolved with each hypothesis's detection
        kernel, summed (hypotheses holding below 10⁻⁶ of the posterior left out)."""
        from scipy.signal import fftconvolve  # lazy: scipy.signal costs a start ~1 CPU-s

        if len(self._models) == 1:
            log_post = self.log_posterior()
            post = np.exp(log_post - log_post.max())
            post /= post.sum()
            chance = fftconvolve(post, self._kernels[0], mode="same")
        else:
            joint = np.exp(self._log_joint())
            mass = joint.sum(axis=(1, 2))
            chance = sum(
                fftconvolve(joint[h], self._kernels[h], mode="same")
                for h in np.flatnonzero(mass >= 1e-6 * mass.max())
            )
        return np.where(self._candidate, np.clip(chance, 0.0, 1.0), 0.0)

    def next_point(
        self,
        move_time: Callable[[FloatArray], FloatArray | None] | None = None,
        price: float = 0.0,
    ) -> FloatArray:
        """[deg] shape ``(2,)``: of the cells where a detection is most likely (within
        :data:`TIE` of the best chance), the one nearest to the centre — the plain choice.

        Given ``move_time`` (points [deg] ``(k, 2)`` → the positioner's time [s] to reach
        each, ``(k,)``, or None) and ``price`` [s], a measurement's bench time apart from
        its travel: the cell reached soonest among those within :data:`MOTION_TIE` of the
        best chance replaces the plain choice when it saves more than
        ``price / MOTION_TIE`` of its move — so over 1 / MOTION_TIE such steps, which lose
        at most one measurement's chance, the walk saves at least as many measurements'
        price.  Where every move is short against the price, the plain search's points."""
        chance = self.detection_chances()
        distance = np.where(chance >= (1.0 - TIE) * chance.max(), self._rho, np.inf)
        row, col = np.unravel_index(int(np.argmin(distance)), chance.shape)
        plain = np.array([self._x[0, col], self._y[row, 0]])
        if move_time is None:
            return plain
        rows, cols = np.nonzero(chance >= (1.0 - MOTION_TIE) * chance.max())
        window = np.column_stack([self._x[0, cols], self._y[rows, 0]])
        times = move_time(np.vstack([plain[None, :], window]))
        if times is None:
            return plain
        best = int(np.argmin(times[1:]))
        if times[0] - times[1 + best] > price / MOTION_TIE:
            return window[best]
        return plain


def _mixture_prior(
    rho: FloatArray, max_radius: float, cell: float, near_radius: float
) -> FloatArray:
    """ln of the prior over the optimum per cell, normalized, shape of ``rho`` (each cell's
    distance [deg] from x0): uniform in distance in a uniform direction (a density ∝ 1/ρ
    per area, the first cell's capped at 1/``cell``), with probability
    :data:`NEAR_WEIGHT` within ``near_radius`` ("x0 is good"), else within
    ``max_radius`` ("anywhere within reach")."""
    anywhere = np.where(rho <= max_radius, -np.log(np.maximum(rho, cell)), -np.inf)
    near = np.where(rho <= min(near_radius, max_radius), anywhere, -np.inf)
    return np.asarray(
        np.logaddexp(
            np.log(NEAR_WEIGHT) + near - _logsumexp(near),
            np.log1p(-NEAR_WEIGHT) + anywhere - _logsumexp(anywhere),
        ),
        dtype=np.float64,
    )


def _logsumexp(a: FloatArray) -> float:
    """ln Σ exp(a) over every element, as a float (scipy's, which keeps −∞ out of sums)."""
    return float(logsumexp(a))
