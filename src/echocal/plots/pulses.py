"""Pulse figure (thesis §3.2): waveform, autocorrelation and energy spectral density."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from echocal.plots._figure import new_figure
from echocal.signal.analytic import analytic_signal
from echocal.signal.pulses import Pulse

__all__ = ["plot_pulse"]


def plot_pulse(pulse: Pulse, *, fs: float | None = None, title: str | None = None) -> Figure:
    """Three panels side by side: w(t) with its envelope (and samples at ``fs`` [Hz] if
    given), normalized autocorrelation R(ℓ)/R(0), and |W(f)|² in dB re its peak."""
    s = pulse.support
    t = np.linspace(-s, s, 2001)
    w = pulse.waveform(t)
    lags = np.linspace(-2 * s, 2 * s, 2001)
    r = pulse.autocorrelation(lags)
    f_top = 1.5 * pulse.highest_frequency
    f = np.linspace(0.0, f_top, 1501)
    esd = pulse.psd(f)
    with np.errstate(divide="ignore"):
        esd_db = 10 * np.log10(esd / esd.max())

    fig = new_figure(figsize=(13, 3.6), layout="constrained")
    ax_w, ax_r, ax_p = fig.subplots(1, 3)
    us = 1e6
    ax_w.plot(t * us, w, lw=1.2, label="w(t)")
    env = np.abs(analytic_signal(w))
    ax_w.plot(t * us, env, "--", lw=0.9, color="0.4", label="envelope")
    if fs is not None:
        ts = np.arange(np.ceil(-s * fs), np.floor(s * fs) + 1) / fs
        ax_w.plot(
            ts * us, pulse.waveform(ts), ".", ms=3, color="C3", label=f"samples @ {fs / 1e6:g} MHz"
        )
    ax_w.set(xlabel="time [µs]", ylabel="amplitude [a.u.]", title="pulse")
    ax_w.legend(fontsize=8, loc="upper right")
    ax_r.plot(lags * us, r / r[np.argmin(np.abs(lags))], lw=1.2, color="C1")
    ax_r.set(xlabel="lag [µs]", ylabel="R(ℓ) / R(0)", title="autocorrelation")
    ax_p.plot(f / 1e6, esd_db, lw=1.2, color="C2")
    ax_p.axvline(pulse.center_frequency / 1e6, color="0.5", lw=0.8, ls=":")
    ax_p.axhline(-6.0, color="0.5", lw=0.8, ls=":")
    ax_p.set(
        xlabel="frequency [MHz]",
        ylabel="|W(f)|² [dB re peak]",
        title="spectral density",
        ylim=(-80, 3),
        xlim=(0, f_top / 1e6),
    )
    for ax in (ax_w, ax_r, ax_p):
        ax.grid(alpha=0.3)
    fig.suptitle(title or f"{pulse.name} pulse, fc = {pulse.center_frequency / 1e6:.3g} MHz")
    return fig
