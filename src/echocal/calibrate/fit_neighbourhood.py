"""Where ``model-based`` fits its local quadratic, and how far it trusts it (a mixin of
:class:`~echocal.calibrate.model_based.ModelBased`).

The log-quadratic is fitted to the measurements within a neighbourhood of the incumbent.
Four rules keep that neighbourhood honest:

* :meth:`FitNeighbourhood._lacks_fit` — a ridge whose residuals scatter clearly more than
  their noise spans more than one hump (a 12.7 mm probe over a rod: two equal humps 3°
  apart): the neighbourhood halves;
* :meth:`FitNeighbourhood._finest` — a replay resolves nothing finer than its grid: two
  of its steps are the least a fit or a refinement point must span;
* :meth:`FitNeighbourhood._centred_on_max` — a ridge's hump, once lack of fit has shrunk
  the neighbourhood, is fitted around its own maximum, or the flat hump's asymmetry biases
  the maximum towards whichever flank the neighbourhood was centred on;
* :meth:`FitNeighbourhood._follow_max` — a neighbourhood at its smallest follows its own
  fitted maximum, or it stays on the flank it was shrunk around.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from echocal.calibrate._fd import FloatArray
from echocal.calibrate.local_model import QuadraticModel, fit_quadratic
from echocal.calibrate.ridge_search import is_ridge

__all__ = ["LACK_OF_FIT_RADIUS", "MIN_FIT", "FitNeighbourhood"]

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


class FitNeighbourhood:
    """The fitting neighbourhood's rules, for a local method that keeps its measurements
    in ``_x`` [deg] (n, 2) and ``_y`` (n,), its design ``radius`` [deg], its ``space``,
    the objective's ``resolution`` [deg] (None: continuous), its ``floor`` (fraction of
    the largest value) and its ``_incumbent`` [deg] (2,)."""

    _x: FloatArray
    _y: FloatArray
    _incumbent: FloatArray
    radius: float
    space: str
    floor: float
    resolution: float | None

    if TYPE_CHECKING:  # provided by the method

        def _fit_radius(self) -> float: ...

        def _sigmas(self, values: FloatArray) -> FloatArray | None: ...

    def _lacks_fit(self, model: QuadraticModel, y_all: FloatArray) -> bool:
        """Whether a ridge's measurements in the fitted neighbourhood scatter about the
        model by clearly more than their noise: χ² of the residuals (each over its
        measurement's σ) above the ``_LACK_OF_FIT`` quantile of χ² with n − 6 degrees of
        freedom (log space with a known noise, a ridge's fit only: a round lobe's
        diffraction tails, which a log-quadratic fits only roughly, are not tested).
        Over a rod a 12.7 mm probe's lobe is a ridge with two humps 3° apart; a quadratic
        fitted 4° around either hump spans both, and its maximum drifts along the ridge.
        Not on a replay (a ``resolution``): its interpolation error, which the noise does
        not include, lacks fit at any scale."""
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
        """``model`` fitted again, in a neighbourhood of the same radius, around its own
        maximum when that lies more than ``_OFF_CENTRE`` of the neighbourhood from its
        centre (at most ``_RECENTRE_STEPS`` times) — for a ridge (log space) whose
        neighbourhood is :data:`LACK_OF_FIT_RADIUS` × radius or less (shrunk by lack of
        fit or a refutation, or a ``locality`` that small); the model unchanged
        otherwise, or when a fit around the maximum is no ridge.

        Only the model moves: the incumbent (the next fit's centre) stays the measured
        point the flank-centred fit ranked highest, and every refit re-centres again —
        moving the incumbent too, to the point nearest the maximum, is what
        :meth:`_follow_max` does at the smallest neighbourhood only (at any size the
        noisy maximum dragged the centre about at 10 dB).  The re-centred fit is not
        tested again for refutation or lack of fit.  (A rod's hump is not symmetric: a
        neighbourhood centred down one flank puts the maximum towards that flank.)"""
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
        """At the smallest neighbourhood (:data:`MIN_FIT`), move the incumbent — the next
        fit's centre — to the measured echo (above ``floor`` of the largest) nearest the
        model's maximum when that lies beyond half the neighbourhood from it, and such an
        echo lies within half of it from the maximum (else a neighbourhood shrunk around a
        flank point keeps its maximum near its edge).  Only at the smallest neighbourhood:
        at any size a noisy maximum drags the centre about."""
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
