"""The reachable poses of a positioner."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from echocal.errors import EchocalValueError, LimitError
from echocal.geometry import Pose

__all__ = ["ANGLE_RANGES", "ENDLESS_AZIMUTH", "PositionerLimits", "limit_problems"]

_INF = float("inf")
_AXES = ("x", "y", "z", "azimuth", "coelevation")
_POSITION_AXES = ("x", "y", "z")

ANGLE_RANGES = {"azimuth": (-360.0, 360.0), "coelevation": (-90.0, 90.0)}
"""[deg] where the limits of each orientation angle must lie (thesis eq. 8;
docs/getting-started.md, "Conventions").

Co-elevation θ is measured from straight down (θ = 0 fires along −z) and may be signed;
beyond ±90° the beam points up, away from the specimen.  Azimuth is periodic: one turn
either side of 0 covers every positioner ([-180, 180] and [0, 360] alike); an axis that
turns without end is [-180, 180].  An infinite azimuth range (``-inf inf`` from a rig,
see :mod:`echocal.measurement.protocol`) means exactly that endless axis and is taken as
[-180, 180] (:data:`ENDLESS_AZIMUTH`)."""

ENDLESS_AZIMUTH = (-180.0, 180.0)
"""[deg] the azimuth limits of an axis that turns without end."""


def _endless_azimuth(low: float, high: float) -> bool:
    """Whether azimuth bounds [deg] describe an unlimited axis: ``low <= high`` and a bound
    is infinite (the protocol's ``inf``).  Finite bounds outside :data:`ANGLE_RANGES` stay
    refused: they are more likely a unit slip than a rig with more than two turns."""
    return low <= high and (math.isinf(low) or math.isinf(high))


def _show(name: str, value: float) -> str:
    """A bound or coordinate as the user thinks of it: lengths in mm, angles in degrees."""
    return f"{value * 1e3:g}" if name in _POSITION_AXES else f"{value:g}"


def _unit(name: str) -> str:
    return "mm" if name in _POSITION_AXES else "deg"


def limit_problems(**axes: tuple[float, float]) -> list[str]:
    """Every problem of positioner limits given as ``axis=(low, high)``, ``axis: message`` each.

    Positions are in metres (infinite bounds mean unlimited) and are reported in mm;
    angles in degrees must lie within :data:`ANGLE_RANGES`.  Empty when all are valid.
    """
    problems = []
    for name, bounds in axes.items():
        try:
            low, high = (float(b) for b in bounds)
        except (TypeError, ValueError):
            problems.append(f"{name}: must be an interval [low, high]; got {bounds!r}")
            continue
        unit = _unit(name)
        if math.isnan(low) or math.isnan(high):
            problems.append(f"{name}: bounds must be numbers, not NaN; got [{low}, {high}]")
            continue
        if low == high and math.isinf(low):
            problems.append(
                f"{name}: [{low}, {high}] holds no position; give finite bounds, or "
                "[-inf, inf] for an unlimited axis"
            )
            continue
        if low > high:
            problems.append(
                f"{name}: must be an interval with low <= high; "
                f"got [{_show(name, low)}, {_show(name, high)}] {unit}"
            )
        if name == "azimuth" and _endless_azimuth(low, high):
            continue  # an endless axis: taken as ENDLESS_AZIMUTH by PositionerLimits
        if name in ANGLE_RANGES:
            lo, hi = ANGLE_RANGES[name]
            if not (lo <= low <= hi and lo <= high <= hi):
                meaning = (
                    "co-elevation is measured from straight down; beyond ±90 deg the beam "
                    "points away from the specimen"
                    if name == "coelevation"
                    else "one turn either side of 0 covers every orientation; an endless "
                    "rotation is [-180, 180]"
                )
                problems.append(
                    f"{name}: limits must lie within [{lo:g}, {hi:g}] deg ({meaning}); "
                    f"got [{low:g}, {high:g}] deg"
                )
    return problems


@dataclass(frozen=True, slots=True)
class PositionerLimits:
    """Box limits of a positioner: positions [m] and orientation angles [deg].

    Infinite position bounds mean "unlimited".  The co-elevation range may be signed
    and must lie within [-90, 90] deg, the azimuth range within [-360, 360] deg
    (:data:`ANGLE_RANGES`); an infinite azimuth range means an endless axis and is
    stored as [-180, 180] deg (:data:`ENDLESS_AZIMUTH`).
    """

    x: tuple[float, float] = (-_INF, _INF)
    y: tuple[float, float] = (-_INF, _INF)
    z: tuple[float, float] = (-_INF, _INF)
    azimuth: tuple[float, float] = (-180.0, 180.0)
    coelevation: tuple[float, float] = (-60.0, 60.0)

    def __post_init__(self) -> None:
        axes = {name: getattr(self, name) for name in _AXES}
        problems = limit_problems(**axes)
        if problems:
            raise EchocalValueError("limits." + "; limits.".join(problems))
        for name, bounds in axes.items():
            values = tuple(float(b) for b in bounds)
            if name == "azimuth" and _endless_azimuth(*values):
                values = ENDLESS_AZIMUTH
            object.__setattr__(self, name, values)

    def violations(self, pose: Pose) -> list[str]:
        """Human-readable list of the limits ``pose`` breaks (empty if reachable).

        Positions are shown in mm, angles in degrees: ``"z = -5 mm outside [5, 100] mm"``.
        """
        out = []
        for name in _AXES:
            low, high = getattr(self, name)
            value = getattr(pose, name)
            if not low <= value <= high:
                unit = _unit(name)
                out.append(
                    f"{name} = {_show(name, value)} {unit} outside "
                    f"[{_show(name, low)}, {_show(name, high)}] {unit}"
                )
        return out

    def contains(self, pose: Pose) -> bool:
        """True when ``pose`` is reachable."""
        return not self.violations(pose)

    def check(self, pose: Pose) -> Pose:
        """Return ``pose`` if reachable; raise :class:`LimitError` naming each violated limit."""
        bad = self.violations(pose)
        if bad:
            raise LimitError(f"pose out of positioner limits: {'; '.join(bad)}")
        return pose

    def clip(self, pose: Pose) -> Pose:
        """The nearest reachable pose (each coordinate clipped to its interval)."""
        x, y, z, azimuth, coelevation = (
            float(np.clip(getattr(pose, n), *getattr(self, n))) for n in _AXES
        )
        return Pose(x, y, z, azimuth, coelevation)

    def as_dict(self) -> dict[str, list[float]]:
        """Plain-data form (for JSON / NetCDF attributes)."""
        return {n: list(getattr(self, n)) for n in _AXES}
