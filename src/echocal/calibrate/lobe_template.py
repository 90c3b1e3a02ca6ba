"""The probe's known lobe as a model of the echo far from its peak: where is the peak, seen
from the lobe's tail?

A log-quadratic (``local_model``) is right near a lobe's top, but a diffraction lobe's tail
is not Gaussian: the 12.7 mm 5 MHz probe's pseudo-energy falls to 0.3 of its peak 0.5° out,
to 0.035 at 0.9° and then only slowly (0.016 at 1.4°, 0.01 at 1.8°).  A quadratic fitted to
tail points sees a lobe twice as broad and puts its peak where it is not. Given the lobe's
shape g(d) (relative metric versus misalignment d from the peak, g(0) = 1; from the
simulated probe, :meth:`~echocal.calibrate.Objective.lobe_template`) the measurements y_i at
points x_i are y_i ≈ E₀ g(x_i − c) + noise, whose two unknowns — the peak c and its energy
E₀ — every point constrains, the tail points included (a point in the noise says "the peak
is not near here").

:func:`fit_template` finds them by weighted least squares: E₀ is linear (solved in closed
form for each c) and c is searched on a grid, coarse then fine.

Seen from deep in the tail (a far search's first detection, 4–7° out at 30 dB), one value
with the peak's known energy says how far the peak is, not in which direction: the peaks
that fit lie on an arc, and the fit is not significant.  :func:`seek_point` then measures
where the candidate peaks, each weighted by its likelihood exp(−χ²/2), disagree most about
the echo (in noise σ, capped at :data:`SEEK_CAP`): each such measurement finds the echo or
removes the candidates near it.

:class:`TemplateSteps` puts the template into ``model-based``'s steps: fitted to every
measurement after each tell, its peak is the next point while no measurement lies on the
main lobe's top (:meth:`LobeTemplate.on_top`: not a near-field ring around it); then the
flanks around it are measured and the fitted peak is the recommendation, until
:data:`_QUADRATIC_TOP` measurements lie on the top and the log-quadratic's maximum agrees
with it (:meth:`TemplateSteps._hand_over`).  A fitted peak is kept unless the data clearly
prefer another (``fit_template``'s ``previous``): over a ball the 12.7 mm probe's ring at
about 0.8 of the peak 1.6° out fits a centre across the ring almost as well.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from echocal._curves import first_crossing
from echocal.calibrate._fd import FloatArray
from echocal.calibrate.local_model import REFUTE, QuadraticModel
from echocal.errors import EchocalValueError

__all__ = [
    "COARSE_STEP",
    "SEEK_CAP",
    "LobeTemplate",
    "TemplateFit",
    "TemplateSteps",
    "disc_grid",
    "energy_prior",
    "fit_template",
    "peak_scores",
    "seek_point",
    "tail_reach",
]

COARSE_STEP = 0.2
"""[deg] the first grid of candidate peaks (the 5 MHz probe's lobe falls to e^(−1/2) of its
peak 0.3° out: a candidate within 0.14° of the true peak is on its top)."""
_FINE = 0.01
"""[deg] the second grid, around the best coarse candidates."""
PEAK_PRIOR = 0.25
"""Relative σ of the prior on the peak's metric when it is known (a simulated source:
its receiver's noise, the metric's floor subtraction and the lobe's spread between
directions keep it within a few % of the noiseless value)."""
_TOP = 0.5
"""The lobe's top: where it is above this fraction of its peak (:meth:`LobeTemplate.on_top`)."""
_KEEP = 9.0
"""[χ²] a previous fit's peak is kept unless another fits the data better by more than
this (for the peak's 2 coordinates a likelihood ratio of e^4.5 = 90, about 2.5σ): a lobe
with a ring fits a few points on the ring almost as well with its peak across the ring."""
_CANDIDATES = 4
"""Coarse candidates refined on the fine grid: the best few (often neighbours of one
basin; the tail's mirror images are told apart by the measurement at the chosen peak)."""


SEEK_CAP = 10.0
"""[σ] a predicted echo this far above the noise counts as seen, however strong."""
_KEEP_LIKELIHOOD = 1e-4
"""Candidate peaks less likely than this fraction of the best are left out."""

_SEEK_MAX = 8
"""Seek measurements (:func:`seek_point`) at most, after a
warm start the template does not fit yet, before the usual steps take over."""

_TEMPLATE_MISFIT = 25.0
"""A template fit whose χ² per degree of freedom (against the measurement noise) exceeds
this refutes the template for the run: the log-quadratic alone, as without one (a lobe
that is not the probe's; fits of the probe's own stay at 1–4)."""
_QUADRATIC_TOP = 6
"""Measurements on the lobe's top before the log-quadratic (6 parameters) takes over from
the template there."""

_AGREE = 0.25
"""[× the lobe's width] the log-quadratic's maximum and the template's peak agree within
this distance before the quadratic takes over."""


@dataclass(frozen=True, eq=False)
class LobeTemplate:
    """The lobe's relative metric versus misalignment from its peak.

    Attributes
    ----------
    angles : [deg] misalignments from the peak, ascending from 0, shape ``(n,)``.
    directions : [rad] directions of the misalignment in the plane of the two angles,
        evenly spaced from 0, shape ``(k,)``.
    values : relative metric (1 at the peak), shape ``(k, n)``; beyond ``angles[-1]``
        the last value holds.
    peak : [metric units] the metric at the peak, noise excluded, when the objective
        knows it in its own units (a simulated source); None otherwise (a rig's twin: a
        setup file does not give the rig's echo amplitude in the rig's units).
    """

    angles: FloatArray
    directions: FloatArray
    values: FloatArray
    peak: float | None = None

    def __post_init__(self) -> None:
        k, n = len(self.directions), len(self.angles)
        if self.values.shape != (k, n) or n < 2 or k < 1:
            raise EchocalValueError(
                f"a lobe template needs values of shape (directions, angles) = ({k}, {n}) "
                f"with at least 2 angles; got {self.values.shape}"
            )
        if self.angles[0] != 0.0 or np.any(np.diff(self.angles) <= 0.0):
            raise EchocalValueError("a lobe template's angles must ascend from 0 [deg]")
        even = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
        if not np.allclose(self.directions, even):
            raise EchocalValueError(
                "a lobe template's directions must be evenly spaced from 0 [rad]"
            )
        if not np.allclose(self.values[:, 0], 1.0, rtol=1e-6):
            raise EchocalValueError("a lobe template's values must be 1 at the peak (angle 0)")

    @cached_property
    def width(self) -> float:
        """[deg] the misalignment at which the lobe, averaged over directions, falls to
        e^(−1/2) of its peak (a Gaussian's σ)."""
        return first_crossing(self.angles, self.values.mean(axis=0), float(np.exp(-0.5)))

    @cached_property
    def _running_min(self) -> np.ndarray:
        """Shape ``(k, n)``: each direction's lowest relative value so far, outward."""
        return np.minimum.accumulate(self.values, axis=1)

    @cached_property
    def _fallen(self) -> np.ndarray:
        """Shape ``(k, n)``: True from each direction's first value below half the peak on
        (past the main lobe)."""
        return self._running_min < _TOP

    @cached_property
    def rise(self) -> float:
        """The most the lobe rises again, relative to its peak, after falling in any
        direction (0 for a lobe that only falls)."""
        return float((self.values - self._running_min).max())

    @cached_property
    def side_lobe(self) -> float:
        """The highest relative value past the main lobe (from each direction's first value
        below half the peak on): below half for a lobe without a ring, the ring's height
        for one (0.82 for the 12.7 mm probe's near field over a ball)."""
        return float(self.values[self._fallen].max(initial=0.0))

    @cached_property
    def _main_lobe(self) -> LobeTemplate:
        """The template with each direction's values set to 0 beyond its first value below
        half the peak (kept, so the edge interpolates as before): the main lobe alone, a
        ring beyond a dip removed."""
        beyond = np.zeros_like(self._fallen)
        beyond[:, 1:] = self._fallen[:, :-1]
        return LobeTemplate(self.angles, self.directions, np.where(beyond, 0.0, self.values))

    def on_top(self, offsets: FloatArray) -> np.ndarray:
        """True where ``offsets`` [deg] from the peak, shape ``(..., 2)``, lie on the main
        lobe's top: above half the peak before the lobe first falls below half along each
        direction (interpolated between directions as the values are) — not on a ring
        around it (the 12.7 mm probe over a ball: a ring at about 0.8 of the peak 1.6° out,
        beyond a dip to about 0.3).  A direction that never falls below half is top to the
        end, and beyond (its last value holds)."""
        return self._main_lobe(offsets) >= _TOP

    def __call__(self, offsets: FloatArray) -> FloatArray:
        """Relative metric at ``offsets`` [deg] from the peak, shape ``(..., 2)`` ->
        ``(...)``: linear in the misalignment along each direction, then linear in the
        direction between the two nearest."""
        d = np.hypot(offsets[..., 0], offsets[..., 1])
        k = len(self.directions)
        along = np.stack([np.interp(d, self.angles, row) for row in self.values])
        if k == 1:
            return along[0]
        phi = np.mod(np.arctan2(offsets[..., 1], offsets[..., 0]), 2.0 * np.pi)
        pos = phi / (2.0 * np.pi / k)
        lo = np.floor(pos).astype(int) % k
        t = pos - np.floor(pos)
        take = np.take_along_axis
        first = take(along, lo[None, ...], axis=0)[0]
        second = take(along, ((lo + 1) % k)[None, ...], axis=0)[0]
        return (1.0 - t) * first + t * second


@dataclass(frozen=True)
class TemplateFit:
    """The best peak of a template fit.

    centre : [deg] the lobe's peak, shape (2,); energy : E₀ [metric units, as the values
    given], with the prior on the peak when one was given; measured : E₀ from the
    measurements alone, and energy_sigma its standard error (how clearly the data show
    an echo); chi2 : the weighted residual sum of squares (the prior's term included).
    """

    centre: FloatArray
    energy: float
    measured: float
    energy_sigma: float
    chi2: float


def fit_template(
    template: LobeTemplate,
    points: FloatArray,
    values: FloatArray,
    sigmas: FloatArray,
    around: FloatArray,
    radius: float,
    peak: float | None = None,
    previous: FloatArray | None = None,
) -> TemplateFit | None:
    """Weighted least-squares fit of y_i ≈ E₀ g(x_i − c) over peaks c within ``radius``
    [deg] of ``around`` (2,): for each c the best E₀ ≥ 0 in closed form, c on a 0.2° grid,
    then on a 0.01° grid around the best few (a lobe narrower than 0.2° — its
    e^(−1/2) width — is searched on a grid of its width first).

    ``points`` [deg] (n, 2), ``values`` (n,) the echo's metric (noise floor removed),
    ``sigmas`` (n,) their noise σ (> 0).  ``peak``: the metric expected at the peak (same
    units), a Gaussian prior on E₀ of relative σ :data:`PEAK_PRIOR` — it breaks the
    tail's trade between the peak's energy and its distance (a lobe 10× stronger twice as
    far looks alike); None: no prior.  ``previous`` [deg] (2,): the peak of the previous
    fit, kept — refined on the fine grid within the coarse step of it, so along a curve of
    equally good peaks it moves at most that far per fit — unless the best peak fits
    better by more than :data:`_KEEP` in χ²; ignored when farther than ``radius`` from
    ``around``.  None when no point carries weight or none of the
    best coarse candidates gives a positive E₀.
    """
    ok = np.isfinite(values) & (sigmas > 0.0)
    if not ok.any():
        return None
    x, y, w = points[ok], values[ok], 1.0 / sigmas[ok] ** 2
    prior = None if peak is None or not peak > 0.0 else energy_prior(peak)
    step = min(COARSE_STEP, template.width)  # a narrower lobe than 0.2° gets a finer grid
    coarse = disc_grid(around, radius, step)
    chi2, energy, *_ = peak_scores(template, coarse, x, y, w, prior)
    order = np.argsort(chi2)[:_CANDIDATES]
    order = order[energy[order] > 0.0]
    if not order.size:
        return None
    fine = np.concatenate([disc_grid(c, step, _FINE) for c in coarse[order]])
    chi2, energy, measured, info = peak_scores(template, fine, x, y, w, prior)
    best = int(np.argmin(np.where(energy > 0.0, chi2, np.inf)))
    if not energy[best] > 0.0:
        return None
    if previous is not None and np.hypot(*(previous - around)) <= radius:
        near = disc_grid(previous, step, _FINE)
        kept = peak_scores(template, near, x, y, w, prior)
        k = int(np.argmin(np.where(kept[1] > 0.0, kept[0], np.inf)))
        if kept[1][k] > 0.0 and kept[0][k] <= chi2[best] + _KEEP:
            fine, (chi2, energy, measured, info), best = near, kept, k
    return TemplateFit(
        centre=fine[best].copy(),
        energy=float(energy[best]),
        measured=float(measured[best]),
        energy_sigma=float(1.0 / np.sqrt(info[best])),
        chi2=float(chi2[best]),
    )


def energy_prior(peak: float) -> tuple[float, float]:
    """The Gaussian prior on a fit's peak metric E₀ when the metric at the peak is known to
    be ``peak`` (> 0): ``(mean, weight)`` = (peak, 1 / (:data:`PEAK_PRIOR` · peak)²)."""
    return peak, 1.0 / (PEAK_PRIOR * peak) ** 2


def disc_grid(centre: FloatArray, radius: float, step: float) -> FloatArray:
    """Points of a square grid of ``step`` [deg] within ``radius`` of ``centre``, (m, 2)."""
    k = int(np.ceil(radius / step))
    u = np.arange(-k, k + 1) * step
    gx, gy = np.meshgrid(u, u)
    inside = np.hypot(gx, gy) <= radius + 1e-12
    return centre[None, :] + np.stack([gx[inside], gy[inside]], axis=1)


def peak_scores(
    template: LobeTemplate,
    centres: FloatArray,
    x: FloatArray,
    y: FloatArray,
    w: FloatArray,
    prior: tuple[float, float] | None,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """For each candidate peak (m, 2): χ² (with the prior's term), the best E₀ ≥ 0 (with
    the prior ``(mean, weight)`` on it, if any), E₀ from the data alone, and Σ w g² (the
    data's information on E₀)."""
    g = template(x[None, :, :] - centres[:, None, :])  # (m, n)
    info = np.maximum((w * g * g).sum(axis=1), 1e-300)
    moment = (w * y * g).sum(axis=1)
    measured = moment / info
    if prior is None:
        energy = np.maximum(measured, 0.0)
        penalty = 0.0
    else:
        mean, weight = prior
        energy = np.maximum((moment + weight * mean) / (info + weight), 0.0)
        penalty = weight * (energy - mean) ** 2
    resid = y[None, :] - energy[:, None] * g
    return (w * resid * resid).sum(axis=1) + penalty, energy, measured, info


def tail_reach(template: LobeTemplate, peak: float, sigma: float, level: float = 3.0) -> float:
    """[deg] the largest misalignment at which the lobe of peak metric ``peak`` is still
    ``level`` × ``sigma`` (same units) above the noise in its strongest direction: how far
    from a detection its peak can be."""
    strongest = template.values.max(axis=0)
    seen = template.angles[peak * strongest >= level * sigma]
    return float(seen.max()) if seen.size else 0.0


def seek_point(
    template: LobeTemplate,
    points: FloatArray,
    values: FloatArray,
    sigmas: FloatArray,
    sigma: float,
    peak: float,
    around: FloatArray,
    radius: float,
) -> FloatArray | None:
    """The next point [deg] (2,) of the seek, within ``radius`` [deg] of ``around`` (2,).

    ``points`` [deg] (n, 2), ``values`` (n,) the echo's metric (noise floor removed) and
    ``sigmas`` (n,) their noise σ (> 0), as for
    :func:`fit_template`; ``sigma`` the noise σ of a
    measurement of no echo and ``peak`` the metric at the lobe's peak (same units).  The
    candidate peaks are a 0.2° grid within ``radius`` of ``around``, the candidate points
    a 0.4° grid.  None when no candidate peak gives a positive energy."""
    if not (sigma > 0.0 and peak > 0.0):
        raise EchocalValueError(
            f"seek_point needs a noise sigma > 0 and a peak metric > 0; got {sigma!r}, {peak!r}"
        )
    ok = np.isfinite(values) & (sigmas > 0.0)
    x, y, w = points[ok], values[ok], 1.0 / sigmas[ok] ** 2
    centres = disc_grid(around, radius, COARSE_STEP)
    chi2, energy, *_ = peak_scores(template, centres, x, y, w, energy_prior(peak))
    usable = energy > 0.0
    if not usable.any():
        return None
    log_like = np.where(usable, -0.5 * (chi2 - chi2[usable].min()), -np.inf)
    keep = log_like >= np.log(_KEEP_LIKELIHOOD)
    weight = np.exp(log_like[keep])
    weight /= weight.sum()
    probes = disc_grid(around, radius, 2.0 * COARSE_STEP)
    predicted = energy[keep] * template(probes[:, None, :] - centres[None, keep, :])
    z = np.minimum(predicted / sigma, SEEK_CAP)  # (probes, candidates)
    mean = z @ weight
    spread = (z * z) @ weight - mean * mean
    return probes[int(np.argmax(spread))].copy()


class TemplateSteps:
    """The template's steps, for a local method that keeps its measurements in ``_x``
    [deg] (n, 2) and ``_y`` (n,), its incumbent in ``_incumbent``, its fitted
    log-quadratic in ``_model``, its value scale in ``_scale``, its fitting space in
    ``space``, its normalization in ``normalize`` and its largest step in ``max_radius``
    [deg], and provides ``_floor()``, ``_sigmas(values)``, ``clip(points)``,
    ``_times_measured(point)`` and ``_supported_max()``."""

    x0: FloatArray
    _x: FloatArray
    _y: FloatArray
    _incumbent: FloatArray
    _model: QuadraticModel | None
    _scale: float
    space: str
    normalize: str
    max_radius: float

    if TYPE_CHECKING:  # provided by the method

        def _floor(self) -> float: ...

        def _sigmas(self, values: FloatArray) -> FloatArray | None: ...

        def clip(self, points: ArrayLike) -> FloatArray: ...

        def _times_measured(self, point: FloatArray) -> int: ...

        def _supported_max(self) -> FloatArray | None: ...

    def _init_template_steps(self, lobe_template: Callable[[], LobeTemplate | None] | None) -> None:
        """No template asked for yet, no fit: ``lobe_template`` (called once, when first
        needed) gives the probe's lobe or None."""
        self.lobe_template = lobe_template
        self._template: LobeTemplate | None = None
        self._template_asked = False
        self._tfit: TemplateFit | None = None
        self._n_top = 0  # measurements on the fitted template's top
        self._quadratic_on_top = False  # the log-quadratic has taken over from the template
        self._seeks_left = 0  # seek measurements still allowed (:meth:`_start_seek`)

    def _fit_template(self) -> None:
        """Fit the probe's lobe template to every measurement (:func:`fit_template`, peaks
        within ``max_radius`` of the incumbent, the previous fit's peak kept on ties):
        ``_tfit`` is the fit when its peak is a significant echo (``REFUTE`` standard
        errors), else None; ``_n_top`` counts the measurements on the lobe's main top.  Log
        space with a live noise model only; the prior on the peak's energy only when the
        values keep the objective's units (``normalize="none"``)."""
        previous = None if self._tfit is None else self._tfit.centre  # kept on ties
        self._tfit, self._n_top = None, 0
        if self._quadratic_on_top or self.space != "log" or not len(self._x):
            return
        if not self._template_asked:
            self._template_asked = True
            self._template = None if self.lobe_template is None else self.lobe_template()
        template = self._template
        if template is None:
            return
        y = self._y - self._floor()
        sig = self._sigmas(np.maximum(y, 0.0))
        if sig is None:
            return
        known = template.peak is not None and self.normalize == "none"
        peak = template.peak / self._scale if known and template.peak is not None else None
        fit = fit_template(
            template, self._x, y, sig, self._incumbent, self.max_radius, peak, previous
        )
        if fit is None or fit.measured < REFUTE * fit.energy_sigma:  # the data's own evidence
            return
        if len(y) >= 7 and fit.chi2 > _TEMPLATE_MISFIT * (len(y) - 3):
            self._template = None  # refuted: this lobe is not the probe's, for the whole run
            return
        self._tfit = fit  # only an accepted fit's peak is kept next time: not one of noise
        self._n_top = int(np.count_nonzero(template.on_top(self._x - fit.centre)))

    def _seek_template(self) -> LobeTemplate | None:
        """The template when a seek can use it — the peak's metric known in the objective's
        units (> 0), the values not normalized, the model in log space, the noise known —
        else None."""
        template = self._template
        if template is None or not (template.peak or 0.0) > 0.0 or self.normalize != "none":
            return None
        if self.space != "log" or self._sigmas(np.zeros(1)) is None:
            return None
        return template

    def _start_seek(self) -> bool:
        """For a warm start the template does not fit yet (a detection in the lobe's tail,
        or a false alarm handed on): seek the peak (:meth:`_seek_step`, at most
        :data:`_SEEK_MAX` measurements) instead of a design around x0 — True — when
        :meth:`_seek_template` gives the template; else False."""
        if self._seek_template() is None:
            return False
        self._seeks_left = _SEEK_MAX
        return True

    def _seek_step(self) -> FloatArray | None:
        """While seeking and no template fit is accepted: the point [deg] (2,) where the
        candidate peaks' predicted echoes disagree most (:func:`seek_point`, candidates out
        to where the lobe's tail is 3 σ above the noise, at least ``max_radius``); else
        None, and the seek is over for the run — also when that point, as the positioner
        reaches it, was measured already."""
        template = self._seek_template()
        if self._tfit is not None or template is None or template.peak is None:
            self._seeks_left = 0
            return None
        if self._seeks_left <= 0:
            return None
        y = self._y - self._floor()
        sig, noise = self._sigmas(np.maximum(y, 0.0)), self._sigmas(np.zeros(1))
        if sig is None or noise is None:
            return None
        peak = template.peak / self._scale
        reach = max(self.max_radius, tail_reach(template, peak, float(noise[0])))
        point = seek_point(template, self._x, y, sig, float(noise[0]), peak, self.x0, reach)
        if point is None or self._times_measured(point):
            self._seeks_left = 0
            return None
        self._seeks_left -= 1
        return self.clip(point)

    def _template_step(self) -> FloatArray | None:
        """While no measurement lies on the lobe's top: the fitted template's peak [deg]
        (2,) unless measured already; else None (the log-quadratic's steps)."""
        if self._tfit is None or self._n_top:
            return None
        target = self.clip(self._tfit.centre)
        return None if self._times_measured(target) else target

    def _template_top(self) -> FloatArray | None:
        """The fitted template's peak [deg] (2,), clipped to the bounds, once a measurement
        lies on the lobe's top and until the log-quadratic takes over
        (:meth:`_hand_over`); else None."""
        if self._tfit is None or not self._n_top:
            return None
        return self.clip(self._tfit.centre)

    def _hand_over(self) -> None:
        """Once :data:`_QUADRATIC_TOP` measurements lie on the lobe's top and the
        quadratic's maximum (supported or not: over a broad lobe the flank points lie a
        width out) agrees with the template's peak within :data:`_AGREE` widths, the
        quadratic takes over for good: the template is not fitted again."""
        if self._tfit is None or self._template is None or self._n_top < _QUADRATIC_TOP:
            return
        xs = self._supported_max()
        m = self._model
        if xs is None and m is not None and m.concave:
            xs = m.argmax()  # flank points only (a broad lobe): none near the maximum yet
        centre = self.clip(self._tfit.centre)
        if xs is not None and np.hypot(*(xs - centre)) <= _AGREE * self._template.width:
            self._quadratic_on_top = True
            self._tfit, self._n_top = None, 0
