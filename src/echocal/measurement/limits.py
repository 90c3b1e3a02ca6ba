"""The reachable poses of a positioner."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from echocal.errors import EchocalValueError, LimitError
from echocal.geometry import Pose

__all__ = ["PositionerLimits"]

_INF = float("inf")


def _interval(name: str, bounds: tuple[float, float]) -> tuple[float, float]:
    low, high = (float(b) for b in bounds)
    if np.isnan(low) or np.isnan(high) or low > high:
        raise EchocalValueError(f"{name} must be an interval (low <= high); got {bounds}")
    return low, high


@dataclass(frozen=True, slots=True)
class PositionerLimits:
    """Box limits of a positioner: positions [m] and orientation angles [deg].

    Infinite bounds mean "unlimited".  The co-elevation range may be signed.
    """

    x: tuple[float, float] = (-_INF, _INF)
    y: tuple[float, float] = (-_INF, _INF)
    z: tuple[float, float] = (-_INF, _INF)
    azimuth: tuple[float, float] = (-180.0, 180.0)
    coelevation: tuple[float, float] = (-60.0, 60.0)

    def __post_init__(self) -> None:
        for name in ("x", "y", "z", "azimuth", "coelevation"):
            object.__setattr__(self, name, _interval(f"limits.{name}", getattr(self, name)))

    def violations(self, pose: Pose) -> list[str]:
        """Human-readable list of the limits ``pose`` breaks (empty if reachable)."""
        out = []
        for name in ("x", "y", "z", "azimuth", "coelevation"):
            low, high = getattr(self, name)
            value = getattr(pose, name)
            if not low <= value <= high:
                out.append(f"{name}={value:g} outside [{low:g}, {high:g}]")
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
        values = [
            float(np.clip(getattr(pose, n), *getattr(self, n)))
            for n in ("x", "y", "z", "azimuth", "coelevation")
        ]
        return Pose(*values)

    def as_dict(self) -> dict[str, list[float]]:
        """Plain-data form (for JSON / NetCDF attributes)."""
        return {n: list(getattr(self, n)) for n in ("x", "y", "z", "azimuth", "coelevation")}
