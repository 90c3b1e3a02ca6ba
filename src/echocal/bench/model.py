"""``Bench``: everything in which a real bench differs from the ideal one."""

from __future__ import annotations

from dataclasses import dataclass, field

from echocal.bench.grain import GrainNoise
from echocal.bench.mount import ProbeMount
from echocal.bench.positioner import PositionerModel
from echocal.bench.receiver import BenchReceiver
from echocal.errors import EchocalValueError

__all__ = ["Bench"]


@dataclass(frozen=True, kw_only=True)
class Bench:
    """The probe's mount, the positioner, the receiver and the part's grains.

    Every part defaults to the ideal bench: an ideal :class:`Bench` measures exactly what
    a simulator without one does, bit for bit.

    Attributes
    ----------
    probe : squint and pivot offset (:class:`~echocal.bench.mount.ProbeMount`).
    positioner : backlash, steps, repeatability, speeds, settling and acquisition time
        (:class:`~echocal.bench.positioner.PositionerModel`).
    receiver : coloured noise, gain curve, jitter and temperature drift
        (:class:`~echocal.bench.receiver.BenchReceiver`).
    grain : the part's grain noise (:class:`~echocal.bench.grain.GrainNoise`), or None.
    """

    probe: ProbeMount = field(default_factory=ProbeMount)
    positioner: PositionerModel = field(default_factory=PositionerModel)
    receiver: BenchReceiver = field(default_factory=BenchReceiver)
    grain: GrainNoise | None = None

    def __post_init__(self) -> None:
        for name, kind in (
            ("probe", ProbeMount),
            ("positioner", PositionerModel),
            ("receiver", BenchReceiver),
        ):
            if not isinstance(getattr(self, name), kind):
                raise EchocalValueError(f"bench.{name} must be a {kind.__name__}")
        if self.grain is not None and not isinstance(self.grain, GrainNoise):
            raise EchocalValueError("bench.grain must be a GrainNoise or None")

    @property
    def is_ideal(self) -> bool:
        """True for the ideal bench: nothing to simulate, no time to count."""
        return (
            self.probe.is_ideal
            and self.positioner.is_exact
            and self.positioner.is_timeless
            and self.receiver.is_ideal
            and self.grain is None
        )
