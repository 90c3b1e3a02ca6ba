"""The A-scan: what a pulser-receiver returns for one pose."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from echocal._validate import finite_float, positive_float
from echocal.errors import EchocalValueError
from echocal.geometry import Pose

__all__ = ["AScan"]


@dataclass(frozen=True, eq=False)
class AScan:
    """One recorded or simulated A-scan.

    Attributes
    ----------
    samples : shape ``(n_samples,)`` received amplitude [arbitrary units, volts on a rig].
    fs : [Hz] sampling frequency.
    start_time : [s] time of the first sample after the transmit pulse (recording delay).
    pose : the pose actually reached when it was recorded (``None`` if unknown).
    metadata : free-form facts about the measurement (source, repeat index, SNR, ...).
    """

    samples: NDArray[np.float64]
    fs: float
    start_time: float = 0.0
    pose: Pose | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        samples = np.asarray(self.samples, dtype=np.float64)
        if samples is self.samples and samples.flags.writeable:
            samples = samples.copy()  # freeze a copy, never the caller's own array
        if samples.ndim != 1 or samples.size == 0:
            raise EchocalValueError(
                f"AScan.samples must be a non-empty 1-D array; got shape {samples.shape}"
            )
        samples.setflags(write=False)
        object.__setattr__(self, "samples", samples)
        object.__setattr__(self, "fs", positive_float("AScan.fs", self.fs))
        object.__setattr__(self, "start_time", finite_float("AScan.start_time", self.start_time))
        object.__setattr__(self, "metadata", MappingProxyType(dict(self.metadata)))

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.samples.size)

    @property
    def times(self) -> NDArray[np.float64]:
        """[s] time of each sample, shape ``(n_samples,)``."""
        return self.start_time + np.arange(self.n_samples) / self.fs

    @property
    def duration(self) -> float:
        """[s] length of the recording window."""
        return self.n_samples / self.fs

    @property
    def is_finite(self) -> bool:
        """True when every sample is finite (a receiver fault gives NaN)."""
        return bool(np.all(np.isfinite(self.samples)))
