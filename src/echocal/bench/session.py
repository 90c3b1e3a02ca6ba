"""``BenchSession``: one simulator's bench at work — the positioner's state, the bench
time so far, and how a batch of commanded poses becomes A-scans on this bench."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from echocal.bench.grain import GrainField
from echocal.bench.model import Bench
from echocal.bench.positioner import PositionerState
from echocal.bench.receiver import ar_noise
from echocal.geometry import Pose, poses_to_arrays, tilt_frame
from echocal.signal import Pulse, Receiver, RecordingWindow

__all__ = ["BenchSession"]

FloatArray = NDArray[np.float64]


class Simulator(Protocol):
    """What a bench session needs of the simulator (:class:`echocal.measurement.VirtualSetup`)."""

    @property
    def window(self) -> RecordingWindow: ...
    @property
    def pulse(self) -> Pulse: ...
    @property
    def grain_field(self) -> GrainField | None: ...
    @property
    def grain_scale(self) -> float: ...
    @property
    def noise_sigma(self) -> float: ...
    @property
    def _generator(self) -> np.random.Generator: ...
    @property
    def _digitizer(self) -> Receiver: ...
    def _check_outside(
        self, positions: FloatArray, *, poses: Sequence[Pose] | None = None, what: str = "pose"
    ) -> None: ...
    def _ideal(self, positions: FloatArray, frames: FloatArray) -> FloatArray: ...


class BenchSession:
    """The state of a simulator's bench.

    Parameters
    ----------
    bench : the bench.
    rng : the bench's own random stream (repeatability, jitter): the receiver's noise
        keeps the setup's stream, so a bench that only moves the probe draws the same
        noise as the ideal bench.
    """

    def __init__(self, bench: Bench, rng: np.random.Generator) -> None:
        self.bench = bench
        self.rng = rng
        self.state = PositionerState(bench.positioner)
        self.clock = 0.0
        """[s] the bench time spent so far (motion, settling and acquisition)."""

    def measure(
        self, setup: Simulator, poses: Sequence[Pose]
    ) -> tuple[FloatArray, list[dict[str, Any]]]:
        """Noisy A-scans ``(P, n_samples)`` of ``poses`` visited in order, and each one's
        bench facts: ``bench_time`` [s] (its motion + settling + acquisition),
        ``motion_time``, ``settling_time``, ``acquisition_time``, ``bench_clock`` [s]
        (the bench time when it was recorded) and ``reached_pose`` (x, y, z [m], tilt_x,
        tilt_y [deg] that the positioner actually reached)."""
        bench, window = self.bench, setup.window
        commands = np.array([[p.x, p.y, p.z, *p.tilt] for p in poses])
        reached, motion, settling = self.state.move(commands, self.rng)
        acquisition = bench.positioner.acquisition_time
        cost = motion + settling + acquisition
        clock = self.clock + np.cumsum(cost)
        self.clock = float(clock[-1])
        if bench.positioner.is_exact:
            positions, frames = poses_to_arrays(poses)
        else:
            positions, frames = reached[:, :3], tilt_frame(reached[:, 3], reached[:, 4])
        faces, acoustic = bench.probe.place(positions, frames)
        setup._check_outside(faces, poses=list(poses))
        samples = setup._ideal(faces, acoustic)
        if setup.grain_field is not None:
            grain = setup.grain_field.ascans(faces, acoustic, setup.pulse, window)
            samples += setup.grain_scale * grain
        receiver = bench.receiver
        if receiver.warps_time:
            delay = receiver.jitter * self.rng.standard_normal(len(poses))
            samples = receiver.warp(
                samples, window.start, window.fs, receiver.speed_ratio(clock), delay
            )
        if setup.noise_sigma:
            noise = ar_noise(samples.shape, receiver.noise_ar, setup._generator)
            noise *= setup.noise_sigma
            samples = noise + samples
        if receiver.gain_curve:
            samples *= receiver.gain(window.times)[None, :]
        samples = setup._digitizer._receive_unchecked(samples, setup._generator)
        facts = [
            {
                "bench_time": float(cost[i]),
                "motion_time": float(motion[i]),
                "settling_time": float(settling[i]),
                "acquisition_time": float(acquisition),
                "bench_clock": float(clock[i]),
                "reached_pose": tuple(float(v) for v in reached[i]),
            }
            for i in range(len(poses))
        ]
        return samples, facts
