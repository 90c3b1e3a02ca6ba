"""The search across a ridge of ``model-based``: when the fitted peak is a ridge, look once
across it for the lobe's true top (a mixin of :class:`~echocal.calibrate.model_based.ModelBased`).

A large probe in its near field over a ball sees a central peak, a dip and a ring; a
local model started beyond the dip climbs the ring, on which it is a ridge — steep across,
flat along — and the centre lies across it.  Once the model has settled on a ridge
(:data:`_ACROSS_AFTER` refinement steps), points at growing offsets on either side are
measured (:data:`_ACROSS_STEPS`), re-measured while they stand above the ridge's top, a
side ended where the lobe has fallen away, and a bump beyond a dip on the line gets a
small hexagon of its own.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from echocal.calibrate._fd import FloatArray
from echocal.calibrate.local_model import REFUTE, REFUTE_RELATIVE, QuadraticModel, hexagon

__all__ = ["RidgeSearch", "is_ridge"]

_RIDGE_RATIO = 1.6
"""A fitted peak whose widths differ by this factor is a ridge: search across it once."""
_ACROSS_AFTER = 6
"""Consecutive refinement steps (no approach step between) on a ridge before it is
searched across: only a settled model is trusted to be on the ridge's top."""
_ACROSS_STEPS = (0.6, 0.9, 1.2, 1.5, 1.8, 2.1, 2.4)
"""[× radius] the offsets of the search across a ridge, nearest first, alternating sides
(first the side where the data fall below the model)."""
_ACROSS_REPEATS = 4
"""At most this many measurements of one point of that search."""
_ACROSS_LOW = 0.15
"""A side of that search ends at a point clearly (2 σ) below this fraction of the
ridge's top: the lobe has fallen away there.  The dip between a near-field ring and
the central peak over a ball is 0.4 of the ring's top, which the search must cross; a
plate's lobe, fitted as a ridge from noisy data, fell to 0.08 of the top 0.9° out on
both sides and the search went on to 2.4° (12 measurements, far start at 30 dB)."""
_BUMP_RADIUS = 0.35
"""[× radius] the hexagon measured around a bump of the search across a ridge."""


def is_ridge(model: QuadraticModel) -> bool:
    """Whether ``model`` is a concave peak whose widths differ by :data:`_RIDGE_RATIO` or
    more: steep across, flat along."""
    eig = np.linalg.eigvalsh(-model.H)  # ascending curvature
    return bool(eig[0] > 0.0 and eig[1] / eig[0] >= _RIDGE_RATIO**2)


class RidgeSearch:
    """The search across a ridge, for a local method that keeps its measurements in
    ``_x`` [deg] (n, 2) and ``_y`` (n,), its design radius in ``radius`` [deg], and
    provides ``_floor()``, ``_sigmas(values)`` and ``clip(points)`` and counts its refinement
    steps since the last approach step in ``_streak``."""

    _x: FloatArray
    _y: FloatArray
    radius: float
    _streak: int  # refinement steps since the last approach step

    if TYPE_CHECKING:  # provided by the method

        def _floor(self) -> float: ...

        def _sigmas(self, values: FloatArray) -> FloatArray | None: ...

        def clip(self, points: ArrayLike) -> FloatArray: ...

    def _init_ridge_search(self) -> None:
        self._across = np.zeros((0, 2))  # queued points of a search across a ridge
        self._across_done = False
        self._across_top = 0.0
        self._across_from = np.zeros(2)
        self._across_line_points: FloatArray | None = None
        self._across_bump = False

    def _start_ridge_search(self, m: QuadraticModel, xs: FloatArray) -> bool:
        """Queue the search across the ridge through the model's maximum ``xs`` [deg] (2,)
        once the model has settled on a ridge (:data:`_ACROSS_AFTER` refinement steps);
        True when queued (done once per run)."""
        if self._across_done or self._streak < _ACROSS_AFTER:
            return False
        line = self._across_line(m, xs)
        if line is None:
            return False
        self._across_done = True
        self._across = line
        self._across_line_points = line.copy()
        self._across_top = float(m.energy(xs[None, :])[0])
        self._across_from = xs.copy()
        return True

    def _across_line(self, m: QuadraticModel, xs: FloatArray) -> FloatArray | None:
        """The points of a search across a ridge through ``xs`` (see :data:`_ACROSS_STEPS`),
        or None when the fitted peak is not a ridge (its widths' ratio below
        :data:`_RIDGE_RATIO`).

        A large probe in its near field over a ball sees a lobe made of a central peak,
        a dip (0.32 of the peak 0.8° out) and a ring (0.8 of the peak, 1.6° out): a local
        model started beyond the dip climbs the ring, on which it is a ridge — steep across
        (the radius), flat along it — and the centre lies across it.  The side where the
        data fall below the model (the dip) is searched first, alternating sides."""
        if not is_ridge(m):
            return None
        _, vec = np.linalg.eigh(-m.H)  # ascending curvature: vec[:, 1] is the steepest
        e = vec[:, 1]
        s = (self._x - xs) @ e
        t = (self._x - xs) @ vec[:, 0]
        y = self._y - self._floor()
        band = (np.abs(t) <= self.radius) & (np.abs(s) >= 0.25 * self.radius)
        resid = y - m.energy(self._x)
        plus = float(np.mean(resid[band & (s > 0)])) if np.any(band & (s > 0)) else 0.0
        minus = float(np.mean(resid[band & (s < 0)])) if np.any(band & (s < 0)) else 0.0
        first = 1.0 if plus < minus else -1.0
        steps = np.asarray(_ACROSS_STEPS) * self.radius
        offsets = np.stack([first * steps, -first * steps], axis=1).reshape(-1)
        return self.clip(xs[None, :] + offsets[:, None] * e[None, :])

    def _across_step(self, point: FloatArray, value: float) -> None:
        """After measuring a point of the search across a ridge: re-measure it (up to
        :data:`_ACROSS_REPEATS` times) while its mean is above the ridge's top by more
        than 2 σ of that mean, else go on to the next point.  A point that clearly
        exceeds the top refutes the model, which then re-fits around it (``_refit``)
        and the search ends; a point of the line clearly below :data:`_ACROSS_LOW` of the
        top ends that side of it (not the hexagon around a bump, which lies on one side)."""
        here = np.all(np.abs(self._x - point) <= 1e-9, axis=1)
        y = self._y[here] - self._floor()
        sig = self._sigmas(np.maximum(y, 0.0))
        mean = float(np.mean(y))
        noise = None if sig is None else float(np.mean(sig)) / np.sqrt(len(y))  # of the mean
        excess = mean - self._across_top
        if np.isfinite(value) and noise is not None and len(y) <= _ACROSS_REPEATS:
            if excess > REFUTE * noise and excess > REFUTE_RELATIVE * self._across_top:
                self._across = np.zeros((0, 2))  # found: the refit moves to it
                return
            if excess > 2.0 * noise and len(y) < _ACROSS_REPEATS:
                return  # measure it again
        self._across = self._across[1:]
        if not self._across_bump and noise is not None and np.isfinite(value):
            if mean + 2.0 * noise < _ACROSS_LOW * self._across_top:  # this side fell away
                beyond = (self._across - self._across_from) @ (point - self._across_from) > 0.0
                self._across = self._across[~beyond]
        if not len(self._across) and not self._across_bump:
            self._across_bump = True
            bump = self._across_bump_point()
            if bump is not None:
                self._across = self.clip(hexagon(bump, _BUMP_RADIUS * self.radius)[1:])

    def _across_bump_point(self) -> FloatArray | None:
        """The line's strongest point beyond a dip on either side of the ridge: clearly
        (3 σ) above the weakest point between it and the ridge — a line that passes near,
        not through, a central peak (its direction is the fitted ridge's, a few degrees off
        at 10 dB) crosses it as such a bump; None when there is none."""
        xs = self._across_from
        line = self._across_line_points
        if line is None or not len(line):
            return None
        floor = self._floor()
        vals = []
        for p in line:
            here = np.all(np.abs(self._x - p) <= 1e-9, axis=1)
            vals.append(float(np.mean(self._y[here])) - floor if here.any() else np.nan)
        v = np.asarray(vals)
        sig = self._sigmas(np.maximum(np.nan_to_num(v), 0.0))
        if sig is None:
            return None
        e = line[-1] - xs
        side = np.sign((line - xs) @ e)
        dist = np.hypot(*(line - xs).T)
        best, best_v = None, -np.inf
        for sgn in (-1.0, 1.0):
            idx = np.flatnonzero((side == sgn) & np.isfinite(v))
            idx = idx[np.argsort(dist[idx])]
            for k in range(1, len(idx)):
                j = idx[k]
                low = float(np.min(v[idx[:k]]))
                if v[j] - low > 3.0 * sig[j] and v[j] > best_v:
                    best, best_v = line[j], v[j]
        return None if best is None else best.copy()
