"""The one interface every data source implements: simulator, replay, hardware."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, Self, runtime_checkable

from echocal._rng import RngLike
from echocal.ascan import AScan
from echocal.geometry import Pose
from echocal.measurement.limits import PositionerLimits

__all__ = ["BaseSource", "MeasurementSource"]


@runtime_checkable
class MeasurementSource(Protocol):
    """Anything that moves a transducer to a pose and returns an A-scan.

    Calibration algorithms only ever see this interface, so the same code runs
    on the simulator, on a recorded dataset and on a real rig.
    """

    @property
    def description(self) -> str:
        """One line saying what this source is (for logs and reports)."""
        ...

    @property
    def limits(self) -> PositionerLimits:
        """The reachable positions [m] and angles [deg]."""
        ...

    def measure(self, pose: Pose) -> AScan:
        """Move to ``pose``, fire, and return the A-scan (its ``pose`` is the one reached)."""
        ...

    def measure_many(self, poses: Sequence[Pose]) -> list[AScan]:
        """Measure several poses, in order (a simulator vectorizes this)."""
        ...

    def close(self) -> None:
        """Release connections or files; further measurements are an error."""
        ...


class BaseSource:
    """Convenience base: ``measure_many`` loops over ``measure``; ``close`` does nothing.

    Sources may also be used as context managers (``with source: ...``).
    """

    description: str = "measurement source"
    limits: PositionerLimits = PositionerLimits()

    def measure(self, pose: Pose) -> AScan:  # pragma: no cover - abstract
        raise NotImplementedError

    def measure_many(self, poses: Sequence[Pose]) -> list[AScan]:
        """Measure each pose in turn."""
        return [self.measure(p) for p in poses]

    def close(self) -> None:
        """Nothing to release by default."""

    def grid_step(self, parameterization: str) -> float | None:
        """[deg] the finest detail this source's measurements resolve in the calibration's
        angles (``parameterization``): a replay's recorded grid step.  None by default: a
        simulator or a rig measures any pose as it is."""
        return None

    def reseed(self, rng: RngLike) -> None:
        """Restart the source's random stream (simulated noise, random repeats) from
        ``rng`` — so a job can give each of its parts numbers of their own, the same when
        the part is measured again after an interruption.  A source whose noise is
        physical (a rig) has nothing to restart: the default does nothing."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
