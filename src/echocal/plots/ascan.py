"""A-scan figure: raw samples, envelope, noise level, detection threshold, gate and the
detected echo, with a zoom panel on the echo."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from echocal.constants import ECHO_THRESHOLD
from echocal.plots._figure import new_figure
from echocal.plots._style import few_ticks
from echocal.signal.gates import TimeGate
from echocal.signal.processing import Gate, envelope, time_of_flight
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow

__all__ = ["plot_ascan"]

_ZOOM_DURATIONS = 3.0
"""The zoom panel spans the time of flight ± this many pulse durations."""


def plot_ascan(
    samples: ArrayLike,
    window: RecordingWindow,
    *,
    pulse: Pulse | None = None,
    gate: Gate | None = None,
    gate_label: str = "detection gate",
    gates: Sequence[TimeGate] = (),
    title: str | None = None,
    noise_sigma: float | None = None,
    expected_amplitude: float | None = None,
    significance: float = ECHO_THRESHOLD,
    echo: bool = True,
) -> Figure:
    """One A-scan (shape ``(n_samples,)``) against time [µs].

    Top panel, the whole recording window: the raw RF samples (solid), their analytic
    envelope (dashed), the noise level ±σ (dotted), with ``pulse`` the detection threshold
    (long dashes: the envelope peak of an echo the matched-filter detector sees at
    ``significance`` σ, :meth:`~echocal.signal.detection.EchoDetector.threshold_amplitude`),
    the gate (bar at its threshold) and,
    with ``pulse``, the time of flight of the strongest echo (matched-filter peak,
    dash-dotted).  With ``pulse`` and an echo, a bottom panel zooms on it (± 3 pulse
    durations) at its own amplitude scale, so a sub-microsecond echo in a long window, and
    a weak echo beside a strong one, is seen cycle by cycle.

    Parameters
    ----------
    gate : a detection gate (bar at its threshold; the time of flight is taken inside it).
    gate_label : its legend entry (calibrate draws its pseudo-energy window there).
    gates : measurement gates (:class:`~echocal.signal.gates.TimeGate`), each shaded over
        its span on this A-scan (a triggered gate where the front wall put it, its
        interface trigger marked); the time of flight is taken inside the first.
    noise_sigma : [a.u.] the receiver's noise σ; default: estimated from the samples
        (1.4826 · MAD, robust to the echo).  0 draws no noise level.
    expected_amplitude : [a.u.] the peak an echo would have (e.g. the reference echo's).
        When the A-scan holds no echo (``pulse`` None) and its peak is below this, the
        axes are drawn at ± this scale, so noise is not autoscaled into looking like a
        signal.
    significance : [σ] the detector's threshold g drawn (default: calibrate's, 4.5).
    echo : False when the detector found no echo in this A-scan: with ``pulse`` the
        detection threshold is still drawn (the noise stays below it), but no time of
        flight and no zoom, and the axes are at the ``expected_amplitude`` scale.

    The legend sits beside the top panel, off the trace.
    """
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"plot_ascan takes one A-scan, shape (n_samples,); got {x.shape}")
    t_us = window.times * 1e6
    tof = None
    if echo and pulse is not None and np.any(x):
        gated = gates[0].apply(x, window) if gates and gate is None else x
        tof = float(time_of_flight(gated, window, pulse, gate=gate)) if np.any(gated) else None
        tof = tof if tof is not None and np.isfinite(tof) else None
    zoom = tof is not None and pulse is not None
    fig = new_figure(figsize=(12, 5.8 if zoom else 3.6), layout="constrained")
    axes = fig.subplots(2 if zoom else 1, 1, squeeze=False)[:, 0]
    sigma = _noise_sigma(x) if noise_sigma is None else float(noise_sigma)
    env = envelope(x)
    detect = _detection_level(pulse, window, sigma, significance)
    for k, ax in enumerate(axes):
        ax.plot(t_us, x, lw=0.8, color="C0", ls="-", label="A-scan")
        ax.plot(t_us, env, lw=1.2, color="C1", ls="--", label="envelope")
        if sigma > 0:
            ax.axhline(sigma, color="0.3", ls=":", lw=1.0, label=noise_label(sigma))
            ax.axhline(-sigma, color="0.3", ls=":", lw=1.0)
        if detect:
            label = threshold_label(detect, significance)
            ax.axhline(detect, color="C4", ls=(0, (6, 3)), lw=1.2, label=label)
        if gate is not None:
            level = float(gate.level(x[None, :])[0])
            ax.hlines(level, gate.start * 1e6, gate.end * 1e6, colors="C2", lw=3, label=gate_label)
        _draw_gates(ax, gates, x, window)
        if tof is not None:
            ax.axvline(tof * 1e6, color="C3", ls="-.", lw=1, label=f"τ = {tof * 1e6:.4f} µs")
        ax.grid(alpha=0.3)
        few_ticks(ax)
        ax.set_ylabel("amplitude [a.u.]")
        if k == 0:
            ax.set_xlim(t_us[0], t_us[-1])
            ax.set_title(title or "A-scan")
    if zoom:
        assert tof is not None and pulse is not None
        half = _ZOOM_DURATIONS * pulse.duration * 1e6
        lo, hi = max(tof * 1e6 - half, t_us[0]), min(tof * 1e6 + half, t_us[-1])
        axes[0].axvspan(lo, hi, color="C3", alpha=0.08, label="zoom below")
        axes[1].set_xlim(lo, hi)
        inside = (t_us >= lo) & (t_us <= hi)  # the zoom's own scale: a weak echo fills it
        top = max(float(np.max(env[inside], initial=0.0)), 1.5 * detect, 3.0 * sigma)
        if top > 0:
            axes[1].set_ylim(-1.15 * top, 1.15 * top)
        axes[1].set_title(f"zoom on the echo (τ ± {half:.2g} µs)", fontsize=10)
    elif expected_amplitude is not None:
        scale = float(expected_amplitude)
        if scale > 0 and np.max(np.abs(x), initial=0.0) < scale:
            axes[0].set_ylim(-1.1 * scale, 1.1 * scale)
            axes[0].text(
                0.01,
                0.95,
                f"no echo: drawn at the scale of the expected echo (peak {scale:.3g})",
                transform=axes[0].transAxes,
                va="top",
                fontsize=9,
            )
    axes[-1].set_xlabel("time [µs]")
    _legend(axes[0])
    return fig


def _legend(ax) -> None:
    """The A-scan's legend, beside its top panel: never over the trace."""
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))


def _draw_gates(ax, gates: Sequence[TimeGate], x: np.ndarray, window: RecordingWindow) -> None:
    """Shade each gate's span on the A-scan ``x`` and mark a triggered gate's interface
    trigger (the front-wall crossing) with a triangle on the time axis."""
    from echocal.signal.gates import interface_trigger

    for i, g in enumerate(gates):
        colour = f"C{(4 + i) % 10}"
        lo, hi = (float(v) for v in g.spans(x, window))
        if not np.isfinite(lo):
            continue
        ax.axvspan(lo * 1e6, hi * 1e6, color=colour, alpha=0.18, label=f"gate {g.label()}")
        if g.triggered:
            t = float(interface_trigger(x[None, :], window, g.threshold)[0])
            ax.plot([t * 1e6], [0.0], marker="^", ms=7, color=colour, ls="none")


def noise_label(sigma: float) -> str:
    """The legend of the noise lines: the σ of the raw samples."""
    return f"sample noise ±σ (σ = {sigma:.3g})"


def threshold_label(level: float, significance: float) -> str:
    """The legend of the detection threshold: the echo envelope peak whose matched-filter
    significance is g.  g counts the matched filter's output noise σ, which filtering
    makes far smaller than the samples' σ, so the level is not g times the samples' σ."""
    return f"detection threshold {level:.3g} (g = {significance:g} matched-filter σ)"


def _noise_sigma(x: np.ndarray) -> float:
    """[a.u.] robust per-sample noise σ (1.4826 · MAD); 0 for a constant trace."""
    from echocal.signal.noise import scan_noise_sigma

    sigma, _ = scan_noise_sigma(x)
    return 0.0 if sigma is None else float(sigma)


def _detection_level(
    pulse: Pulse | None, window: RecordingWindow, sigma: float, significance: float
) -> float:
    """[a.u.] the detector's threshold as an echo envelope peak; 0 (not drawn) without a
    pulse or a noise level."""
    if pulse is None or sigma <= 0:
        return 0.0
    from echocal.signal.detection import shared_detector

    detector = shared_detector(pulse, float(window.fs), int(window.n_samples))
    return detector.threshold_amplitude(sigma, significance)
