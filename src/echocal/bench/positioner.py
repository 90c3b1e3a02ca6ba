"""The positioner's imperfections and the time its moves take.

Five axes — ``x``, ``y``, ``z`` [m] and the gimbal tilts ``tilt_x``, ``tilt_y`` [deg] — each
with (units: the axis's, m or deg):

- ``step``: the controller reaches only multiples of it (the commanded value is rounded
  to the nearest);
- ``backlash``: lost motion on a reversal.  The axis is calibrated approaching in its
  positive direction; approached in the negative direction the carriage stops
  ``backlash`` short, i.e. at ``target + backlash``;
- ``repeatability``: the standard deviation of where a move ends (a fresh draw per move
  of that axis; an axis that does not move stays where it is);
- ``speed`` [unit/s] and ``settling`` [s]: the axes move together, so a move takes the
  longest axis's travel / speed (a reversal travels the backlash too) plus the longest
  settling of the axes that moved.

Every A-scan also costs ``acquisition_time`` [s] (averaging, PRF).  With ``approach =
"positive"`` the controller compensates the backlash, as many do: every move ends in the
positive direction — a move in the negative direction overshoots the target by the
backlash and comes back — so the target is reached without the backlash's offset, at the
cost of the extra travel (the overshoot and the return, and the lost motion of the two
reversals: 4 × backlash).  The state (where each axis is and which way it last moved) is
:class:`PositionerState`'s.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from echocal._validate import nonnegative_float, positive_float
from echocal.errors import EchocalValueError

__all__ = ["APPROACHES", "AXES", "Axis", "PositionerModel", "PositionerState"]

FloatArray = NDArray[np.float64]

AXES = ("x", "y", "z", "tilt_x", "tilt_y")
"""The positioner's axes: positions [m] then gimbal tilts [deg]."""

APPROACHES = ("both", "positive")
"""How moves end: from either side (``both``: the backlash shows) or always in the
positive direction (``positive``: the controller's backlash compensation)."""


@dataclass(frozen=True, kw_only=True)
class Axis:
    """One axis (units: m and m/s for x, y, z; deg and deg/s for the tilts).

    Attributes
    ----------
    backlash : [unit] lost motion on a reversal (>= 0).
    step : [unit] resolution (>= 0; 0: continuous).
    repeatability : [unit] standard deviation of a move's end point (>= 0).
    speed : [unit/s] travel speed (> 0; inf: instantaneous).
    settling : [s] wait after a move of this axis (>= 0).
    """

    backlash: float = 0.0
    step: float = 0.0
    repeatability: float = 0.0
    speed: float = math.inf
    settling: float = 0.0

    def __post_init__(self) -> None:
        for name in ("backlash", "step", "repeatability", "settling"):
            object.__setattr__(self, name, nonnegative_float(name, getattr(self, name)))
        speed = self.speed
        if not (isinstance(speed, int | float) and speed == math.inf):
            speed = positive_float("speed", speed)
        object.__setattr__(self, "speed", float(speed))

    @property
    def is_exact(self) -> bool:
        """True when the axis reaches every commanded value exactly."""
        return self.backlash == 0.0 and self.step == 0.0 and self.repeatability == 0.0

    @property
    def rms_error(self) -> float:
        """[unit] the RMS difference between a commanded and a reached value when the
        approach direction is equally often either way: √(σ² + step²/12 + backlash²/2) —
        the repeatability, a uniform rounding error over one step, and an offset of 0 or
        ``backlash`` (mean square backlash²/2)."""
        return math.sqrt(self.repeatability**2 + self.step**2 / 12.0 + self.backlash**2 / 2.0)


@dataclass(frozen=True, kw_only=True)
class PositionerModel:
    """The five axes and the acquisition time of one A-scan [s] (see the module)."""

    x: Axis = field(default_factory=Axis)
    y: Axis = field(default_factory=Axis)
    z: Axis = field(default_factory=Axis)
    tilt_x: Axis = field(default_factory=Axis)
    tilt_y: Axis = field(default_factory=Axis)
    acquisition_time: float = 0.0
    approach: str = "both"

    def __post_init__(self) -> None:
        if self.approach not in APPROACHES:
            raise EchocalValueError(
                f"bench.positioner.approach must be one of {', '.join(APPROACHES)}; "
                f"got {self.approach!r}"
            )
        for name in AXES:
            if not isinstance(getattr(self, name), Axis):
                raise EchocalValueError(f"bench.positioner.{name} must be an Axis")
        object.__setattr__(
            self,
            "acquisition_time",
            nonnegative_float("bench.positioner.acquisition_time", self.acquisition_time),
        )

    def _column(self, name: str) -> FloatArray:
        return np.array([getattr(getattr(self, axis), name) for axis in AXES])

    @property
    def is_exact(self) -> bool:
        """True when every axis reaches every commanded value exactly."""
        return all(getattr(self, axis).is_exact for axis in AXES)

    @property
    def tilt_error(self) -> float:
        """[deg] the RMS angle between a commanded and a reached orientation:
        √(e_x² + e_y²) of the tilt axes' :attr:`Axis.rms_error` (small angles), without
        the backlash's share when the controller compensates it (``approach =
        "positive"``)."""
        axes = [self.tilt_x, self.tilt_y]
        if self.approach == "positive":
            axes = [dataclasses.replace(axis, backlash=0.0) for axis in axes]
        return math.hypot(axes[0].rms_error, axes[1].rms_error)

    @property
    def is_timeless(self) -> bool:
        """True when moves and acquisitions take no time."""
        return self.acquisition_time == 0.0 and all(
            getattr(self, a).speed == math.inf and getattr(self, a).settling == 0.0 for a in AXES
        )


class PositionerState:
    """Where each axis is and which way it last moved; :meth:`move` advances it.

    The positioner starts at rest at the first commanded pose, having approached it in the
    positive direction of every axis (where a calibrated positioner reads true).
    """

    def __init__(self, model: PositionerModel) -> None:
        self.model = model
        self._target: FloatArray | None = None  # (5,) the last quantized command
        self._actual: FloatArray | None = None  # (5,) where the axes are
        self._direction = np.ones(len(AXES))  # +1 / −1: the last motion's sign per axis

    def move(
        self, commands: FloatArray, rng: np.random.Generator
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Visit ``commands`` ``(P, 5)`` (x, y, z [m], tilt_x, tilt_y [deg]) in order.

        Returns the poses reached ``(P, 5)``, each visit's motion time [s] ``(P,)`` and
        settling time [s] ``(P,)``.
        """
        model = self.model
        step, backlash = model._column("step"), model._column("backlash")
        sigma, speed = model._column("repeatability"), model._column("speed")
        settling = model._column("settling")
        targets = np.where(
            step > 0.0, np.round(commands / np.where(step > 0, step, 1.0)) * step, commands
        )
        previous = np.vstack(
            [targets[:1] if self._target is None else self._target[None], targets[:-1]]
        )
        delta = targets - previous
        moved = delta != 0.0
        # the direction of each visit's approach: the sign of its move, else the last one's
        signs = np.vstack([self._direction[None], np.sign(delta)])
        index = np.where(signs != 0.0, np.arange(len(signs))[:, None], 0)
        direction = np.take_along_axis(signs, np.maximum.accumulate(index, axis=0), axis=0)[1:]
        reversed_ = moved & (direction != np.vstack([self._direction[None], direction[:-1]]))
        if model.approach == "positive":  # overshoot, reverse, return: every move ends going +
            travel = np.abs(delta) + np.where(moved & (delta < 0.0), 4.0 * backlash, 0.0)
            direction = np.ones_like(direction)
        else:
            travel = np.abs(delta) + np.where(reversed_, backlash, 0.0)
        reached = targets + np.where(direction < 0.0, backlash, 0.0)
        if np.any(sigma > 0.0):
            draws = rng.standard_normal(targets.shape) * sigma
            reached = reached + np.where(moved, draws, 0.0)
        # an axis that does not move stays where it was (its last draw included)
        before = reached[:1] if self._actual is None else self._actual[None]
        index = np.vstack(
            [
                np.zeros((1, len(AXES)), dtype=np.int64),
                np.where(moved, np.arange(1, len(reached) + 1)[:, None], 0),
            ]
        )
        chain = np.vstack([before, reached])
        actual = np.take_along_axis(chain, np.maximum.accumulate(index, axis=0), axis=0)[1:]
        with np.errstate(invalid="ignore"):
            motion = np.where(moved, travel / speed, 0.0).max(axis=1)
        settle = np.where(moved, settling, 0.0).max(axis=1)
        self._target, self._actual = targets[-1].copy(), actual[-1].copy()
        self._direction = direction[-1].copy()
        return actual, motion, settle
