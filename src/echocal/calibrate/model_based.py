"""Model-based trust-region ascent: a quadratic model of log-energy fitted to every measurement.

Near its peak a beam's pseudo-energy is close to a Gaussian in the two angles, whose log is
exactly quadratic, so a quadratic of log f holds over the whole peak.  With additive noise
of fixed σ, var(log y) ≈ σ²/y²: the weighted least-squares fit weighs y² (relative, so the
energy unit does not matter; non-positive and NaN values are left out).

One measurement per iteration after the initial design:

1. Design: x0 and a hexagon of ``radius`` (skipped where a warm-start ``history`` covers x0).
2. Fit m(x) = c + bᵀd + ½ dᵀHd (d = x − centre) within a neighbourhood of the incumbent
   (``locality``): it halves where a measurement refutes the fit or a ridge's residuals
   lack fit (a rod's two humps), widens again where too few points remain, is refitted
   around a ridge hump's own maximum, at its smallest follows its fitted maximum, and on a
   replay spans at least two grid steps.
3. Approach: while the model's maximum x* lies outside the trust region around the
   incumbent (the measured point with the highest *model* value), measure m's maximizer in
   the ball of radius Δ; Δ doubles after a successful step to the boundary and halves when
   the value falls short of the incumbent's by more than 2 σ̂ (log units, from the fit's
   residuals, at most :data:`_MAX_SIGMA_LOG` once the incumbent is a significant echo).
4. Refine: x* is learned best from its flanks (the Fisher information of a point at
   distance r is ∝ r² e^{−r²/w²}, largest at r ≈ w): points on an ellipse ``ring`` ×
   (−H)^{−1/2} around x*, at golden-angle steps.
5. ``recommend()`` is x* when the model is concave and supported, else the incumbent.

With the probe's lobe (``lobe_template``) the steps from the lobe's tail follow the lobe
instead, and the recommendation is its fitted peak until the quadratic takes over
(:class:`~echocal.calibrate.lobe_template.TemplateSteps`; a diffraction lobe's tail is not
Gaussian); a warm start deep in the tail seeks the peak
(:func:`~echocal.calibrate.lobe_template.seek_point`).  On a ridge or a side lobe it
searches across (:mod:`~echocal.calibrate.ridge_search`).  ``space="linear"`` fits f
itself with equal weights (for objectives that can be negative).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal._validate import one_of
from echocal.calibrate._fd import FloatArray
from echocal.calibrate._options import finite_float, in_range, optional, positive_float
from echocal.calibrate.base import Optimizer
from echocal.calibrate.evidence import energy_sigma
from echocal.calibrate.lobe_template import LobeTemplate, TemplateSteps
from echocal.calibrate.local_model import (
    REFUTE,
    REFUTE_RELATIVE,
    QuadraticModel,
    fit_quadratic,
    hexagon,
    trust_region_max,
)
from echocal.calibrate.objective import as_points
from echocal.calibrate.registry import register_method
from echocal.calibrate.ridge_search import RidgeSearch, is_ridge
from echocal.errors import EchocalValueError

__all__ = ["ModelBased", "QuadraticModel", "fit_quadratic", "hexagon", "trust_region_max"]

_GOLDEN = np.pi * (3.0 - np.sqrt(5.0))
_MISFIT = 2.0
"""The strongest measurement more than this factor (and ``REFUTE`` σ) above the model's
own value at that point refutes the model too: a log-quadratic fitted mostly to a lobe's
flat tail can predict 1/1000 of the peak it was given and send every step away from it."""
_SAME_POINT = 0.01
"""[× radius] proposals this close count as the same point (measured twice: look elsewhere)."""
_MAX_SHRINK = 4
"""At most this many halvings of the fitting neighbourhood per refit."""
_RING_REACH = 0.7
"""[× the fitting neighbourhood] the farthest a refinement point goes from the fitted
maximum: beyond the neighbourhood it would not be fitted."""
_MAX_SIGMA_LOG = 1.0
"""The largest log-space noise the trust-region test allows for (a factor e) once the
model's value at the incumbent is a significant echo (``REFUTE`` σ of the measurement
noise): the residuals of a just-refuted model would otherwise pass every step.  In the
noise (no significant echo) the residuals keep their scale, so the steps explore."""

MIN_FIT = 0.5
"""[× radius] the smallest fitting neighbourhood (the central peak over a ball is 0.3°
wide at half its energy, with a dip to 0.32 of it 0.8° out)."""
_LACK_OF_FIT = 0.999
"""A fit whose residuals' χ² exceeds this quantile lacks fit: its neighbourhood halves."""
_LACK_OF_FIT_MIN = 12
"""Fewer fitted measurements than this are not tested for lack of fit (6 parameters)."""
LACK_OF_FIT_RADIUS = 1.0
"""[× radius] lack of fit shrinks the fitting neighbourhood down to this radius, no less."""
_OFF_CENTRE = 0.2
"""[× the fitting neighbourhood] a ridge's fitted maximum farther than this from the
neighbourhood's centre is fitted again around itself."""
_RECENTRE_STEPS = 2
"""At most this many fits around the previous fit's maximum per refit."""


@register_method("model-based")
class ModelBased(TemplateSteps, RidgeSearch, Optimizer):
    """Trust-region ascent on a log-quadratic model of all measurements (1 per iteration).

    Parameters
    ----------
    radius : [deg] initial design radius and trust-region radius (≈ the expected peak width).
    max_radius, min_radius : [deg] trust-region limits (default 4×radius, radius/10).
    ring : flank distance of refinement points in units of the fitted peak width.
    space : ``"log"`` (default) or ``"linear"``.
    locality : fit only points within ``locality`` × max(radius, trust radius) of the incumbent.
    floor : leave out of the log fit points below ``floor`` × the largest value (noise floor).
    history : optional (points (n, 2) [deg], values (n,)) already measured (warm start),
        e.g. by an acquisition phase; the initial design is skipped where these cover x0.
    noise_floor : [energy units] mean value of pure noise, subtracted before the fit
        (None: ``noise_model``'s, else 0; at 10 dB left in it broadens log f).
    noise_model : callable returning the objective's live ``(noise_floor, noise_sigma)``
        (e.g. :meth:`~echocal.calibrate.Objective.noise_estimate`).
    lobe_template : callable returning the probe's
        :class:`~echocal.calibrate.lobe_template.LobeTemplate` or None (e.g.
        :meth:`~echocal.calibrate.Objective.lobe_template`; called once, when needed):
        steps from the lobe's tail go to the fitted template's peak.
    normal_echo : callable returning the echo at the probe's best direction of normal
        incidence [objective units] or None (e.g.
        :meth:`~echocal.calibrate.Objective.normal_echo`; called once, when needed): a
        peak refined below 0.4 of it is a side lobe (:mod:`~echocal.calibrate.ridge_search`;
        ``normalize="none"`` only).
    resolution : [deg] the finest detail the values resolve, e.g. a replay's grid step
        (None: continuous): no lack-of-fit test, refinement points up to two steps out.
    """

    batch_size = 1

    def __init__(
        self,
        x0: ArrayLike,
        *,
        radius: float = 1.0,
        max_radius: float | None = None,
        min_radius: float | None = None,
        ring: float = 0.8,
        space: str = "log",
        locality: float = 4.0,
        floor: float = 0.05,
        history: tuple[ArrayLike, ArrayLike] | None = None,
        noise_floor: float | None = None,
        noise_model: Callable[[], tuple[float | None, float | None]] | None = None,
        lobe_template: Callable[[], LobeTemplate | None] | None = None,
        normal_echo: Callable[[], float | None] | None = None,
        resolution: float | None = None,
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        super().__init__(x0, bounds=bounds, rng=rng, normalize=normalize)
        self.resolution = optional(positive_float, "resolution", resolution)
        self.noise_floor = optional(finite_float, "noise_floor", noise_floor)
        self.noise_model = noise_model
        self.normal_echo = normal_echo
        self._init_template_steps(lobe_template)
        self.radius = positive_float("radius", radius)
        self.max_radius = positive_float(
            "max_radius", 4.0 * self.radius if max_radius is None else max_radius
        )
        self.min_radius = positive_float(
            "min_radius", self.radius / 10.0 if min_radius is None else min_radius
        )
        self.ring = positive_float("ring", ring)
        self.space = one_of("space", space, ("log", "linear"))
        self.locality = positive_float("locality", locality)
        self.floor = in_range("floor", floor, 0.0, 1.0)
        self._x = np.zeros((0, 2))
        self._y = np.zeros(0)
        if history is not None:
            hp = as_points("history points", history[0])
            hv = np.asarray(history[1], dtype=np.float64).reshape(-1)
            if hv.shape != (len(hp),):
                raise EchocalValueError(
                    f"history values must have shape ({len(hp)},); got shape {hv.shape}"
                )
            ok = np.isfinite(hv)
            self._x, self._y = hp[ok], hv[ok]
        self._trust = self.radius
        self._loc_scale = 1.0  # shrinks the fitting neighbourhood when the data refute the fit
        self._init_ridge_search()
        self._recentred: FloatArray | None = None
        self._streak = 0  # refinement steps since the last approach step
        self._tried = np.zeros((0, 2))  # every point this method asked for, NaN ones too
        self._n_fresh = 0
        self._model: QuadraticModel | None = None
        self._mode = "design"
        self._n_ring = 0
        self._sigma_log = 0.0
        self._incumbent = self.x0.copy()
        self._pred: tuple[float, float] | None = None  # (m(center), m(candidate))
        self._step_len = 0.0
        self._design = self._initial_design()
        if len(self._x) and not len(self._design):
            self._update_model()  # a warm start's first step already uses what it was given

    def _initial_design(self) -> FloatArray:
        """x0 and a hexagon of ``radius`` around it — none for a warm start whose history
        has 6 points within 2 × radius of x0, or that the lobe's template already fits (its
        fitted peak is the first step) or will seek (:meth:`_start_seek`)."""
        if len(self._x):
            near = np.hypot(*(self._x - self.x0).T) <= 2.0 * self.radius
            if np.count_nonzero(near) >= 6:
                return np.zeros((0, 2))
            self._fit_template()
            if self._tfit is not None or self._start_seek():
                return np.zeros((0, 2))
        return self.clip(hexagon(self.x0, self.radius))

    @property
    def min_budget(self) -> int:
        return max(len(self._design), 1)

    @property
    def model(self) -> QuadraticModel | None:
        """The current fitted model (None before enough data)."""
        return self._model

    # -- internals --------------------------------------------------------------------
    def _floor(self) -> float:
        """[energy units, method scale] noise floor to subtract (0 when unknown)."""
        floor = self.noise_floor
        if floor is None and self.noise_model is not None:
            floor = self.noise_model()[0]
        if floor is None or not np.isfinite(floor):
            return 0.0
        return float(floor) / self._scale

    def _fit_radius(self) -> float:
        """[deg] the fitting neighbourhood's radius: ``locality`` × max(radius, trust),
        shrunk (never below ``MIN_FIT`` × radius) where the data refuted the model."""
        return max(
            self.locality * max(self.radius, self._trust) * self._loc_scale, MIN_FIT * self.radius
        )

    def _sigmas(self, values: FloatArray) -> FloatArray | None:
        """[method scale] the noise σ of measurements whose echo energies (floor removed)
        are ``values`` (k,), from the live noise model; None when it cannot tell."""
        if self.noise_model is None:
            return None
        floor, sigma = self.noise_model()
        if floor is None or sigma is None or not (np.isfinite(floor) and np.isfinite(sigma)):
            return None
        if sigma <= 0.0:
            return None
        floor_s, sigma_s = float(floor) / self._scale, float(sigma) / self._scale
        return energy_sigma(np.asarray(values) + floor_s, floor_s, sigma_s)

    def _refuting_point(
        self, model: QuadraticModel, y_all: FloatArray, local: np.ndarray
    ) -> int | None:
        """Index of the strongest local measurement clearly above everything the model
        allows (its maximum in the fitted neighbourhood or at a measured point): ``REFUTE``
        σ of its noise and 5 %; else the strongest local measurement if it stands
        :data:`_MISFIT` times and ``REFUTE`` σ above the model's own value there; else None
        (also when the noise is unknown; log space only).  A quadratic fitted across
        several lobes puts its maximum between them, below the central peak's values."""
        if self.space != "log" or not local.any():
            return None
        sig = self._sigmas(np.maximum(y_all, 0.0))
        if sig is None:
            return None
        top = float(np.max(model.energy(self._x[local])))
        if model.concave:
            xs = model.argmax()
            if np.all(np.isfinite(xs)) and np.hypot(*(xs - model.center)) <= self._fit_radius():
                top = max(top, float(model.energy(xs[None, :])[0]))
        # repeats of one point are averaged: their mean's noise is σ/√n
        _, group, count = np.unique(
            np.round(self._x, 9), axis=0, return_inverse=True, return_counts=True
        )
        group = group.reshape(-1)
        mean = np.bincount(group, weights=y_all) / count
        excess = mean[group] - top
        noise = sig / np.sqrt(count[group])
        refuted = local & (excess > REFUTE * noise) & (excess > REFUTE_RELATIVE * top)
        if not refuted.any():
            strongest = int(np.flatnonzero(local)[np.argmax(mean[group][local])])
            own = float(model.energy(self._x[strongest][None, :])[0])
            under = mean[group][strongest] - own
            if under > REFUTE * noise[strongest] and mean[group][strongest] > _MISFIT * own:
                return strongest  # the model does not hold its own best measurement
            return None
        idx = np.flatnonzero(refuted)
        return int(idx[np.argmax(mean[group][idx])])

    def _refit(self) -> None:
        center = self._incumbent
        y_all = self._y - self._floor()
        grown = False
        for _ in range(_MAX_SHRINK + 1):
            model = self._fit_around(center, y_all)
            if model is None or not model.concave:
                if self._loc_scale >= 1.0:
                    break
                # too few measurements in a shrunk neighbourhood to fit, or too few to
                # show a peak (at 10 dB): widen it again
                self._loc_scale = min(2.0 * self._loc_scale, 1.0)
                grown = True
                continue
            # any measurement refutes the model's maximum, the far ones included: they may
            # lie on the stronger peak
            refuting = self._refuting_point(model, y_all, np.ones(len(y_all), dtype=bool))
            if self._fit_radius() <= MIN_FIT * self.radius:
                break
            if refuting is None:
                if grown or self._fit_radius() <= LACK_OF_FIT_RADIUS * self.radius:
                    break
                if not self._lacks_fit(model, y_all):
                    break
                self._loc_scale *= 0.5  # the same centre, a neighbourhood the quadratic fits
                continue
            # the data refute the model: fit a smaller neighbourhood of the strongest echo
            center = self._x[refuting].copy()
            self._incumbent = center
            self._loc_scale *= 0.5
            self._recentred = center
        self._model = model
        if model is None:
            best = self._x[int(np.argmax(y_all))] if len(y_all) else self.x0
            self._incumbent = best
            return
        pred = model(self._x)
        local = np.hypot(*(self._x - center).T) <= self._fit_radius()
        if not local.any():
            local[:] = True
        if self.space == "log":
            ymax = float(y_all[local].max())
            cand = np.flatnonzero(local & (y_all > max(self.floor * ymax, 0.0)))
            if cand.size:
                self._incumbent = self._x[cand[int(np.argmax(pred[cand]))]]
            e = np.exp(np.minimum(pred, np.log(ymax) + 3.0)) if ymax > 0 else pred * 0.0
            top = float(e[local].max())
            near = local & (e >= 0.3 * top)
            n = int(near.sum())
            if n > 6 and top > 0:
                sig = float(np.sqrt(np.sum((y_all[near] - e[near]) ** 2) / (n - 6)))
                inc = float(np.exp(min(float(model(self._incumbent[None, :])[0]), 700.0)))
                self._sigma_log = sig / max(inc, 1e-300)
                noise = self._sigmas(np.array([inc]))
                if noise is not None and inc > REFUTE * float(noise[0]):
                    self._sigma_log = min(self._sigma_log, _MAX_SIGMA_LOG)
        else:
            idx = np.flatnonzero(local)
            self._incumbent = self._x[idx[int(np.argmax(pred[idx]))]]
            n = len(idx)
            if n > 6:
                sig = float(np.sqrt(np.sum((y_all[idx] - pred[idx]) ** 2) / (n - 6)))
                self._sigma_log = sig
        model = self._centred_on_max(model, y_all)
        self._follow_max(model, y_all)
        # re-centre the model on the incumbent (same function, better numbers)
        d = self._incumbent - model.center
        self._model = QuadraticModel(
            center=self._incumbent.copy(),
            c=float(model(self._incumbent[None, :])[0]),
            b=model.b + model.H @ d,
            H=model.H,
            space=model.space,
        )

    def _supported_max(self) -> FloatArray | None:
        m = self._model
        if m is None or not m.concave:
            return None
        xs = m.argmax()
        if not np.all(np.isfinite(xs)):
            return None
        dist = float(np.min(np.hypot(*(self._x - xs).T)))
        return xs if dist <= self._trust else None

    def _ask(self) -> FloatArray:
        """The next point: the design, else the model's proposal (:meth:`_propose`) —
        unless that point was measured twice already (see :meth:`_fresh_point`)."""
        if len(self._design):
            return self._design
        cand = self._propose()
        if self._mode != "across" and self._times_measured(cand[0]) >= 2:
            cand = self._fresh_point()[None, :]
            self._mode = "approach"
            self._step_len = float(np.hypot(*(cand[0] - self._incumbent)))
        return cand

    def _propose(self) -> FloatArray:
        m = self._model
        xs = self._supported_max()
        if len(self._across):
            self._mode = "across"
            self._pred = None
            return self._across[:1].copy()
        target = self._seek_step()
        if target is None:
            target = self._template_step()
        if target is not None:
            self._mode = "approach"
            self._streak = 0
            self._pred = None  # not the quadratic's step: no trust-radius verdict on it
            self._step_len = float(np.hypot(*(target - self._incumbent)))
            return target[None, :]
        top = self._template_top()
        if top is not None:
            assert self._template is not None  # a fit implies a template
            # on the lobe's top before the quadratic is: the flanks around the template's
            # peak, where a measurement says most about where the peak is
            self._mode = "refine"
            self._n_ring += 1
            ang = self._n_ring * _GOLDEN
            self._pred = None
            off = self.ring * self._template.width * np.array([np.cos(ang), np.sin(ang)])
            return self.clip(top + off)[None, :]
        if m is not None and xs is not None and np.hypot(*(xs - m.center)) <= self._trust:
            if self._start_ridge_search(m, xs):
                self._mode = "across"
                self._pred = None
                return self._across[:1].copy()
            self._mode = "refine"
            self._n_ring += 1
            self._streak += 1
            ang = self._n_ring * _GOLDEN
            u = np.array([np.cos(ang), np.sin(ang)])
            eig, vec = np.linalg.eigh(m.width())
            eig = np.clip(eig, 0.25 * self.radius, self.max_radius)
            off = self.ring * (vec @ np.diag(eig) @ vec.T @ u)
            norm = float(np.hypot(*off))
            reach = min(self.max_radius, max(_RING_REACH * self._fit_radius(), self._finest()))
            if norm > reach:
                off *= reach / norm
            self._pred = None
            return (xs + off)[None, :]
        self._mode = "approach"
        self._streak = 0
        if m is not None:
            cand = trust_region_max(m, self._trust)
            self._pred = (m.c, float(m(cand[None, :])[0]))
        else:
            ang = self.rng.uniform(0.0, 2.0 * np.pi)
            cand = self._incumbent + self._trust * np.array([np.cos(ang), np.sin(ang)])
            self._pred = None
        self._step_len = float(np.hypot(*(cand - self._incumbent)))
        return cand[None, :]

    def _times_measured(self, point: FloatArray) -> int:
        """How often ``point`` [deg] (as the positioner reaches it: clipped) was measured,
        NaN results included — to ``_SAME_POINT`` × radius: a model that barely changes
        proposes points that differ in the third decimal of a degree, and measuring them
        again teaches it nothing."""
        if not len(self._tried):
            return 0
        near = np.all(np.abs(self._tried - self.clip(point)) <= _SAME_POINT * self.radius, axis=1)
        return int(np.count_nonzero(near))

    def _fresh_point(self) -> FloatArray:
        """A point [deg] on the trust circle around the incumbent, at golden-angle steps of
        direction, that was measured fewer than twice: the model's own proposal was (it
        cannot learn more there — measured twice already, e.g. clipped onto a limit — and
        re-measuring it froze the estimate for 49 measurements), so it looks elsewhere."""
        self._pred = None  # not the model's step: no trust-radius verdict on it
        for k in range(1, 64):
            self._n_fresh += 1
            ang = self._n_fresh * _GOLDEN
            radius = self._trust * (1.0 + (k // 16))  # all directions tried: farther out
            cand = self._incumbent + radius * np.array([np.cos(ang), np.sin(ang)])
            if self._times_measured(cand) < 2:
                return cand
        return cand

    def _tell(self, points: FloatArray, values: FloatArray) -> bool:
        ok = ~self.last_nan
        self._tried = np.vstack([self._tried, points])
        self._x = np.vstack([self._x, points[ok]])
        self._y = np.concatenate([self._y, values[ok]])
        self._design = np.zeros((0, 2))
        if self._mode == "across" and len(self._across):
            self._across_step(points[0], values[0] if ok.all() else np.nan)
        if self._mode == "approach" and self._pred is not None and ok.all():
            m_center, m_cand = self._pred
            y = float(values[0]) - self._floor()
            actual = (np.log(y) if y > 0 else -np.inf) if self.space == "log" else y
            predicted = m_cand - m_center
            noise = 2.0 * self._sigma_log
            if actual - m_center >= 0.25 * predicted - noise:
                if self._step_len >= 0.9 * self._trust:
                    self._trust = min(2.0 * self._trust, self.max_radius)
            elif actual - m_center < -noise:
                self._trust = max(0.5 * self._trust, self.min_radius)
        self._update_model()
        return True

    def _update_model(self) -> None:
        """Refit (:meth:`_refit`) and the lobe's template (:meth:`_fit_template`); when
        the data moved the model to a new, narrower peak, trust a step of half the design
        radius there and measure a hexagon of that radius around it unless its
        neighbourhood is measured already or the template already says where the peak is."""
        self._recentred = None
        self._refit()
        self._fit_template()
        if self._recentred is not None:
            self._trust = max(0.5 * self.radius, self.min_radius)
            near = np.hypot(*(self._x - self._recentred).T) <= 0.75 * self.radius
            if np.count_nonzero(near) < 7 and self._tfit is None:
                self._design = self._fresh_design(hexagon(self._recentred, 0.5 * self.radius)[1:])
                self._drop_search()
        self._hand_over()

    def _fresh_design(self, points: FloatArray) -> FloatArray:
        """``points`` [deg] (k, 2) clipped to the bounds, in order, without those the
        clipping folded onto an earlier one (a hexagon at a corner of the limits) or
        measured twice already."""
        keep: list[FloatArray] = []
        for p in self.clip(points):
            if self._times_measured(p) < 2 and all(np.any(p != q) for q in keep):
                keep.append(p)
        return np.array(keep).reshape(-1, 2)

    def _recommend(self) -> FloatArray:
        xs = self._template_top()
        if xs is None:
            xs = self._supported_max()
        return xs if xs is not None else self._incumbent

    @property
    def concave(self) -> bool:
        """True when a peak model's maximum, supported by the data, is the recommendation
        (not the incumbent fallback): the lobe's template with a measurement on its top,
        or the fitted log-quadratic, concave."""
        return self._template_top() is not None or self._supported_max() is not None

    def recommend_value(self) -> float | None:
        """The model's echo energy (noise floor removed) at the recommendation [objective
        units]: the template's fitted peak energy while it is in charge, else the
        log-quadratic's value there; None before a model."""
        if self._template_top() is not None and self._tfit is not None:
            return self._tfit.energy * self._scale
        if self._model is None:
            return None
        return float(self._model.energy(self.recommend()[None, :])[0]) * self._scale

    @property
    def iterate(self) -> FloatArray:
        return self.recommend()

    def _lacks_fit(self, model: QuadraticModel, y_all: FloatArray) -> bool:
        """Whether a ridge's measurements in the fitted neighbourhood scatter about the
        model clearly more than their noise: χ² of the residuals (each over its σ) above
        the :data:`_LACK_OF_FIT` quantile with n − 6 degrees of freedom (over a rod a fit 4°
        around either hump spans both).  Log space with a known noise and a ridge only (a
        round lobe's diffraction tails fit only roughly); not on a replay, whose
        interpolation error lacks fit at any scale."""
        if self.space != "log" or self.resolution is not None or not is_ridge(model):
            return False
        local = np.hypot(*(self._x - model.center).T) <= self._fit_radius()
        n = int(np.count_nonzero(local))
        sig = self._sigmas(np.maximum(y_all[local], 0.0))
        if sig is None or n <= _LACK_OF_FIT_MIN:
            return False
        resid = (y_all[local] - model.energy(self._x[local])) / sig
        from scipy.stats import chi2  # lazy: scipy.stats costs a CLI start ~1 CPU-s

        return bool(np.sum(resid**2) > chi2.ppf(_LACK_OF_FIT, n - 6))

    def _fit_around(self, center: FloatArray, y_all: FloatArray) -> QuadraticModel | None:
        """The quadratic fitted to the measurements (values ``y_all`` (n,), floor removed)
        within the fitting neighbourhood around ``center`` [deg] (2,); None when too few."""
        return fit_quadratic(
            self._x,
            y_all,
            center,
            space=self.space,
            scale=self.radius,
            locality=self._fit_radius(),
            floor=self.floor,
        )

    def _centred_on_max(self, model: QuadraticModel, y_all: FloatArray) -> QuadraticModel:
        """``model`` fitted again around its own maximum, in a neighbourhood of the same
        radius, when that lies more than :data:`_OFF_CENTRE` of it from the centre (at most
        :data:`_RECENTRE_STEPS` times): a rod's hump is not symmetric, and a neighbourhood
        centred down one flank puts the maximum towards it.  Only for a ridge (log space)
        in a neighbourhood of :data:`LACK_OF_FIT_RADIUS` × radius or less, and only while
        the refit is a ridge; the incumbent stays (:meth:`_follow_max` moves it)."""
        radius = self._fit_radius()
        if self.space != "log" or radius > LACK_OF_FIT_RADIUS * self.radius * (1.0 + 1e-9):
            return model
        for _ in range(_RECENTRE_STEPS):
            if not is_ridge(model):
                return model
            xs = model.argmax()
            off = float(np.hypot(*(xs - model.center)))
            if not np.isfinite(off) or off <= _OFF_CENTRE * radius or off > radius:
                return model
            refit = self._fit_around(xs, y_all)
            if refit is None or not is_ridge(refit):
                return model
            model = refit
        return model

    def _finest(self) -> float:
        """[deg] the smallest neighbourhood whose shape the objective's values resolve:
        two of its ``resolution`` steps (0 when continuous)."""
        return 0.0 if self.resolution is None else 2.0 * self.resolution

    def _follow_max(self, model: QuadraticModel, y_all: FloatArray) -> None:
        """At the smallest neighbourhood (:data:`MIN_FIT`) only (at any size a noisy maximum
        drags the centre about): when the model's maximum lies beyond half the neighbourhood
        from the incumbent, move the incumbent (the next fit's centre) to the measured echo
        (above ``floor`` of the largest) nearest the maximum, if one lies within half of it
        — else a neighbourhood shrunk around a flank point keeps its maximum at its edge."""
        radius = self._fit_radius()
        if not model.concave or radius > MIN_FIT * self.radius * (1.0 + 1e-9):
            return
        xs = model.argmax()
        if not np.all(np.isfinite(xs)) or np.hypot(*(xs - self._incumbent)) <= 0.5 * radius:
            return
        dist = np.hypot(*(self._x - xs).T)
        echo = (dist <= 0.5 * radius) & (y_all > max(self.floor * float(y_all.max()), 0.0))
        if echo.any():
            idx = np.flatnonzero(echo)
            self._incumbent = self._x[idx[int(np.argmin(dist[idx]))]].copy()
