"""The search across a ridge or a side lobe of ``model-based`` (a mixin of
:class:`~echocal.calibrate.model_based.ModelBased`).

A large probe in its near field over a ball sees a central peak, a dip and a ring; a local
model started beyond the dip climbs the ring, a ridge (steep across, flat along) with the
centre across it.  Once the model has settled on a ridge, points at growing offsets
(:data:`_ACROSS_STEPS`) on either side are measured, re-measured while above the ridge's
top, a side ended where the lobe has fallen away, and a bump beyond a dip gets a small
hexagon.  The same search along both axes leaves a side lobe: a refined peak whose echo is
far below the echo at normal incidence (``normal_echo``, which the optimum's is at least;
over a rod the 12.7 mm probe's side maximum is 0.17 of it, 1.6° across the rod).  A point
of either search clearly above the top restarts the fit around it; the next search waits
until the model has settled again.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from echocal.calibrate._fd import FloatArray
from echocal.calibrate._options import positive_float
from echocal.calibrate.local_model import REFUTE, REFUTE_RELATIVE, QuadraticModel, hexagon
from echocal.errors import EchocalValueError

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
ridge's top: the lobe has fallen away there (the dip between a near-field ring and the
central peak over a ball, which the search must cross, is 0.4 of the ring's top)."""
_SIDE_LOBE = 0.4
"""A peak refined :data:`_SIDE_LOBE_AFTER` times whose fitted echo is below this fraction
of the echo at normal incidence (and is an echo: :data:`_ECHO_SIGMAS`) is a side lobe,
searched along both axes (again after a search that was dropped:
:meth:`RidgeSearch._drop_search`): over the rod the side maximum's echo is 0.17 of
normal incidence's, the optimum's at least 1 — 0.4 leaves a factor 2.4 either way."""
_SIDE_LOBE_AFTER = 2
"""Consecutive refinement steps before a peak is tested for a side lobe: the test needs
the peak's echo, not its shape, and two steps pin it."""
_ECHO_SIGMAS = 3.0
"""A refined peak's fitted echo must stand this many σ of one measurement's noise above
the floor to be a side lobe; below, the local method refines noise the acquisition
handed it, and a search around it is no lobe's."""
_SAME_RAY = 0.7
"""Points of that search whose offsets' directions agree within 45° are on one side."""
_BUMP_RADIUS = 0.35
"""[× radius] the hexagon measured around a bump of the search across a ridge."""


def is_ridge(model: QuadraticModel) -> bool:
    """Whether ``model`` is a concave peak whose widths differ by :data:`_RIDGE_RATIO` or
    more: steep across, flat along."""
    eig = np.linalg.eigvalsh(-model.H)  # ascending curvature
    return bool(eig[0] > 0.0 and eig[1] / eig[0] >= _RIDGE_RATIO**2)


def _usable_echo(echo: object) -> float | None:
    """``normal_echo()``'s answer as a positive float, or None (with a warning naming it
    when it is neither None nor one: the run goes on without it, nothing measured lost)."""
    if echo is None:
        return None
    try:
        return positive_float("normal_echo()", echo)
    except EchocalValueError:
        warnings.warn(
            f"normal_echo() returned {echo!r}, not a positive number: the side-lobe check "
            "is off for this run (return the echo in the objective's units, or None)",
            UserWarning,
            stacklevel=2,
        )
        return None


class RidgeSearch:
    """The search across a ridge, for a local method that keeps its measurements in
    ``_x`` [deg] (n, 2) and ``_y`` (n,), its design radius in ``radius`` [deg], and
    provides ``_floor()``, ``_sigmas(values)`` and ``clip(points)``, fits around
    ``_incumbent`` within ``_loc_scale`` of its full neighbourhood, counts its refinement
    steps since the last approach step in ``_streak``, and may know the echo at normal
    incidence (``normal_echo``, a callable returning it in the objective's units, or None;
    compared with the model's energy × ``_scale`` when ``normalize`` is ``"none"``)."""

    _x: FloatArray
    _y: FloatArray
    radius: float
    _streak: int  # refinement steps since the last approach step
    normal_echo: Callable[[], float | None] | None
    normalize: str
    _scale: float
    _incumbent: FloatArray  # the next fit's centre [deg] (2,)
    _loc_scale: float  # the fitting neighbourhood's share of its full size

    if TYPE_CHECKING:  # provided by the method

        def _floor(self) -> float: ...

        def _sigmas(self, values: FloatArray) -> FloatArray | None: ...

        def clip(self, points: ArrayLike) -> FloatArray: ...

    def _init_ridge_search(self) -> None:
        self._across = np.zeros((0, 2))  # queued points of a search across a ridge
        self._across_done = False
        self._side_lobe_done = False
        self._across_side_lobe = False  # the search under way is from a side lobe
        self._normal_echo: float | None = None
        self._normal_echo_asked = False
        self._across_top = 0.0
        self._across_from = np.zeros(2)
        self._across_line_points: FloatArray | None = None
        self._across_bump = False

    def _start_ridge_search(self, m: QuadraticModel, xs: FloatArray) -> bool:
        """Queue the search through the model's maximum ``xs`` [deg] (2,) once the model has
        settled on a ridge (:data:`_ACROSS_AFTER` refinement steps: across it) or on a side
        lobe (:meth:`_on_side_lobe`, :data:`_SIDE_LOBE_AFTER` steps: along both its axes,
        as a side lobe fitted from noisy data has no telling direction); True when queued.
        Each once per run, a side lobe's again after a dropped search
        (:meth:`_drop_search`)."""
        if self._streak < _SIDE_LOBE_AFTER:
            return False
        if not self._across_done and self._streak >= _ACROSS_AFTER and is_ridge(m):
            self._across_done, self._across_side_lobe = True, False
        elif not self._side_lobe_done and self._on_side_lobe(m, xs):
            self._side_lobe_done, self._across_side_lobe = True, True
        else:
            return False
        line = self._across_line(m, xs, (1, 0) if self._across_side_lobe else (1,))
        self._across = line
        self._across_line_points = line.copy()
        self._across_top = float(m.energy(xs[None, :])[0])
        self._across_from = xs.copy()
        self._across_bump = False
        return True

    def _drop_search(self) -> None:
        """Drop the queued points of a search under way (the fit moves to a new centre): the
        next waits until the model has settled again, and a side lobe's may be made again
        (its peak tested afresh); each needs an echo clearly (4 σ and 5 %) above the last
        peak's, so they do not repeat without end."""
        if not len(self._across):
            return
        if self._across_side_lobe:
            self._side_lobe_done = False
        self._across = np.zeros((0, 2))
        self._streak = 0

    def _on_side_lobe(self, m: QuadraticModel, xs: FloatArray) -> bool:
        """Whether the fitted echo at ``xs`` is below :data:`_SIDE_LOBE` of the echo at
        normal incidence (asked of ``normal_echo`` once, when first needed) but is an echo
        (:data:`_ECHO_SIGMAS`); False when the echo at normal incidence is unknown or the
        values are normalized."""
        if self.normal_echo is None or self.normalize != "none":
            return False
        energy = float(m.energy(xs[None, :])[0])
        sig = self._sigmas(np.array([max(energy, 0.0)]))
        if sig is None or not energy > _ECHO_SIGMAS * float(sig[0]):
            return False  # noise, not a lobe: nothing to leave
        if not self._normal_echo_asked:
            self._normal_echo_asked = True
            self._normal_echo = _usable_echo(self.normal_echo())
        echo = self._normal_echo
        if echo is None:
            return False
        return energy * self._scale < _SIDE_LOBE * echo

    def _across_line(
        self, m: QuadraticModel, xs: FloatArray, axes: tuple[int, ...] = (1,)
    ) -> FloatArray:
        """The points [deg] (k, 2) of a search across the peak through ``xs`` along its
        steepest direction (``axes`` (1,); (1, 0): and its flattest, interleaved), at the
        offsets :data:`_ACROSS_STEPS`, nearest first, alternating sides: on each axis first
        the side where the data fall below the model (over a ball, the dip before the
        central peak)."""
        _, vec = np.linalg.eigh(-m.H)  # ascending curvature: vec[:, 1] is the steepest
        y = self._y - self._floor()
        resid = y - m.energy(self._x)
        rays = []
        for axis in axes:
            e = vec[:, axis]
            s = (self._x - xs) @ e
            t = (self._x - xs) @ vec[:, 1 - axis]
            band = (np.abs(t) <= self.radius) & (np.abs(s) >= 0.25 * self.radius)
            plus = float(np.mean(resid[band & (s > 0)])) if np.any(band & (s > 0)) else 0.0
            minus = float(np.mean(resid[band & (s < 0)])) if np.any(band & (s < 0)) else 0.0
            first = 1.0 if plus < minus else -1.0
            rays += [first * e, -first * e]
        steps = np.asarray(_ACROSS_STEPS) * self.radius
        offsets = steps[:, None, None] * np.asarray(rays)[None, :, :]
        points = self.clip(xs[None, :] + offsets.reshape(-1, 2))
        # a ray that leaves the bounds folds onto them: each point once, none on xs
        keep = [
            k
            for k, p in enumerate(points)
            if np.hypot(*(p - xs)) > 1e-9 and not np.any(np.all(p == points[:k], axis=1))
        ]
        return points[keep]

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
                # found: the refit starts over around it, from the whole neighbourhood —
                # one shrunk to its smallest around the side lobe would not see it
                self._incumbent = point.copy()
                self._loc_scale = 1.0
                self._drop_search()
                return
            if excess > 2.0 * noise and len(y) < _ACROSS_REPEATS:
                return  # measure it again
        self._across = self._across[1:]
        if not self._across_bump and noise is not None and np.isfinite(value):
            if mean + 2.0 * noise < _ACROSS_LOW * self._across_top:  # this side fell away
                out, ray = self._across - self._across_from, point - self._across_from
                same = out @ ray > _SAME_RAY * np.hypot(*out.T) * float(np.hypot(*ray))
                self._across = self._across[~same]
        if not len(self._across) and not (self._across_bump or self._across_side_lobe):
            self._across_bump = True
            bump = self._across_bump_point()
            if bump is not None:
                self._across = self.clip(hexagon(bump, _BUMP_RADIUS * self.radius)[1:])
        if not len(self._across):
            self._streak = 0

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
