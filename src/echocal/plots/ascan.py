"""A-scan figure: raw samples, envelope, gate and the detected echo."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from echocal.signal.processing import Gate, envelope, time_of_flight
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow

__all__ = ["plot_ascan"]


def plot_ascan(
    samples: ArrayLike,
    window: RecordingWindow,
    *,
    pulse: Pulse | None = None,
    gate: Gate | None = None,
    title: str | None = None,
) -> Figure:
    """One A-scan (shape ``(n_samples,)``) against time [µs]: the raw RF samples, their
    analytic envelope, the gate (bar at its threshold) and, with ``pulse``, the time of
    flight of the strongest echo (matched-filter peak)."""
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"plot_ascan takes one A-scan, shape (n_samples,); got {x.shape}")
    t_us = window.times * 1e6
    fig = Figure(figsize=(10, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.plot(t_us, x, lw=0.8, color="C0", label="A-scan")
    env = envelope(x)
    ax.plot(t_us, env, lw=1.2, color="C1", label="envelope")
    if gate is not None:
        level = float(gate.level(x[None, :])[0])
        ax.hlines(level, gate.start * 1e6, gate.end * 1e6, colors="C2", lw=3, label="gate")
    if pulse is not None and np.any(x):
        tof = float(time_of_flight(x, window, pulse, gate=gate))
        ax.axvline(tof * 1e6, color="C3", ls="--", lw=1, label=f"τ = {tof * 1e6:.4f} µs")
    ax.set(xlabel="time [µs]", ylabel="amplitude [a.u.]", title=title or "A-scan")
    ax.set_xlim(t_us[0], t_us[-1])
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    return fig
