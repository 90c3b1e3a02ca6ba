"""Analytic fake sources for the measurement tests (stand-ins until VirtualSetup lands).

``GaussianEchoSource``: the echo is a Gabor pulse arriving at ``2 z / c`` whose
amplitude is a Gaussian of the angle between the beam normal and a known
``true_normal`` orientation — so the optimum orientation is known exactly —
plus white noise drawn from a seeded generator (reproducible from the seed).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from echocal.ascan import AScan
from echocal.errors import EchocalError
from echocal.geometry import Pose, angle_between, orientation_normal
from echocal.measurement.base import BaseSource
from echocal.measurement.limits import PositionerLimits

FS = 50e6  # [Hz]
N_SAMPLES = 256
START_TIME = 20e-6  # [s]
C0 = 1480.0  # [m/s]
F0 = 5e6  # [Hz] pulse carrier


class GaussianEchoSource(BaseSource):
    """Echo amplitude ``exp(-angle² / (2 width²))``; angle from ``true`` orientation [deg]."""

    def __init__(
        self,
        *,
        true_azimuth: float = 30.0,
        true_coelevation: float = 4.0,
        width: float = 6.0,
        noise_std: float = 0.0,
        seed: int = 0,
        limits: PositionerLimits | None = None,
    ) -> None:
        self.true_normal = orientation_normal(true_azimuth, true_coelevation)
        self.width = width
        self.noise_std = noise_std
        self.rng = np.random.default_rng(seed)
        self.limits = limits or PositionerLimits(
            x=(-0.01, 0.01), y=(-0.01, 0.01), z=(0.015, 0.03), coelevation=(-20.0, 20.0)
        )
        self.description = f"gaussian echo fake (width {width} deg, noise {noise_std})"
        self.measured: list[Pose] = []
        self.closed = False

    def amplitude(self, pose: Pose) -> float:
        """Noiseless echo amplitude at ``pose`` (the analytic truth)."""
        angle = float(angle_between(pose.normal, self.true_normal))
        return float(np.exp(-(angle**2) / (2 * self.width**2)))

    def clean_samples(self, pose: Pose) -> np.ndarray:
        """Noiseless A-scan samples, shape ``(N_SAMPLES,)``."""
        t = START_TIME + np.arange(N_SAMPLES) / FS
        t0 = 2 * pose.z / C0
        sigma = 0.4e-6  # [s] pulse envelope width
        pulse = np.exp(-((t - t0) ** 2) / (2 * sigma**2)) * np.cos(2 * np.pi * F0 * (t - t0))
        return self.amplitude(pose) * pulse

    def measure(self, pose: Pose) -> AScan:
        if self.closed:
            raise EchocalError("fake source is closed")
        self.limits.check(pose)
        samples = self.clean_samples(pose)
        if self.noise_std:
            samples = samples + self.noise_std * self.rng.standard_normal(N_SAMPLES)
        self.measured.append(pose)
        return AScan(samples=samples, fs=FS, start_time=START_TIME, pose=pose)

    def close(self) -> None:
        self.closed = True


class InterruptingSource(BaseSource):
    """Wraps a source and raises KeyboardInterrupt on the measurement after ``after`` ones."""

    def __init__(self, inner: BaseSource, after: int) -> None:
        self.inner = inner
        self.after = after
        self.count = 0
        self.description = inner.description
        self.limits = inner.limits

    def measure(self, pose: Pose) -> AScan:
        if self.count >= self.after:
            raise KeyboardInterrupt
        self.count += 1
        return self.inner.measure(pose)

    def measure_many(self, poses: Sequence[Pose]) -> list[AScan]:
        return [self.measure(p) for p in poses]
