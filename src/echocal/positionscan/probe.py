"""A probe from its echo: centre frequency, −6 dB bandwidth, noise level and whiteness,
and a sampled pulse a setup file can use.

The echo is the scan's front-wall echo, its traces aligned and averaged
(:func:`~echocal.positionscan.tof.stacked_template`: the noise falls by √N).  From its
amplitude spectrum |S(f)|:

* centre frequency f_c = (f_lo + f_hi)/2 of the −6 dB band [f_lo, f_hi] around the peak
  (the band where |S| ≥ |S|max/2, the contiguous stretch holding the peak, its edges
  interpolated linearly), and the fractional bandwidth (f_hi − f_lo)/f_c [%];
* the noise: the samples before the front-wall gate of every trace (at least 64 per trace);
  its σ (robust: 1.4826 × the median absolute deviation) and its whiteness — the
  spectral flatness (geometric over arithmetic mean of its Welch spectrum, 1 for a flat
  spectrum) and the Ljung–Box test of its first 20 autocorrelations (white when the
  p-value is above 1 %).

The pulse file has two columns, time [s] (0 at the echo's envelope peak, the instant a
setup's time of flight refers to) and amplitude; ``[pulse] name = "sampled"``, ``file =
"pulse.csv"`` in a setup file uses it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.signal
import scipy.stats
from numpy.typing import NDArray

from echocal.errors import EchocalValueError
from echocal.io import atomic_write_text
from echocal.positionscan.dataset import PositionScan
from echocal.positionscan.tof import front_wall_tof, stacked_template
from echocal.signal.gates import TimeGate, named_gate
from echocal.signal.pulses import SampledPulse

__all__ = ["ProbeEstimate", "probe_from_echo", "whiteness"]

_LAGS = 20
"""Autocorrelation lags of the Ljung–Box test."""

_MIN_NOISE = 64
"""Fewest noise samples per trace."""


@dataclass(frozen=True)
class ProbeEstimate:
    """What a front-wall echo says about the probe and the receiver (plain data)."""

    pulse: SampledPulse
    center_frequency: float
    band: tuple[float, float]
    noise_sigma: float
    spectral_flatness: float
    whiteness_p_value: float

    @property
    def bandwidth_percent(self) -> float:
        """[%] the −6 dB bandwidth over the centre frequency."""
        return 100.0 * (self.band[1] - self.band[0]) / self.center_frequency

    @property
    def white(self) -> bool:
        """The noise passes the Ljung–Box whiteness test at the 1 % level."""
        return self.whiteness_p_value > 0.01

    def summary(self) -> dict[str, Any]:
        """JSON-ready numbers (SI units)."""
        peak = float(np.max(np.abs(self.pulse.samples)))
        return {
            "center_frequency_hz": self.center_frequency,
            "band_6db_hz": list(self.band),
            "bandwidth_percent": self.bandwidth_percent,
            "noise_sigma": self.noise_sigma,
            "echo_peak": peak,
            "snr_db": 20.0 * float(np.log10(peak / self.noise_sigma))
            if self.noise_sigma > 0
            else None,
            "spectral_flatness": self.spectral_flatness,
            "whiteness_p_value": self.whiteness_p_value,
            "white": self.white,
            "pulse_samples": int(self.pulse.samples.size),
        }

    def write_pulse(self, path: str | os.PathLike[str]) -> Path:
        """Write the pulse as CSV (time [s] from the envelope peak, amplitude)."""
        p = self.pulse
        assert p.start_time is not None
        t = p.start_time + np.arange(p.samples.size) / p.fs
        lines = ["time_s,amplitude"] + [
            f"{ti:.9e},{wi:.9e}" for ti, wi in zip(t, p.samples, strict=True)
        ]
        target = Path(path)
        atomic_write_text(target, "\n".join(lines) + "\n")
        return target


def _band(freqs: NDArray[np.float64], mag: NDArray[np.float64]) -> tuple[float, float]:
    """[Hz] the −6 dB band around the spectrum's peak, edges interpolated."""
    k = int(np.argmax(mag))
    half = mag[k] / 2.0
    lo = k
    while lo > 0 and mag[lo - 1] >= half:
        lo -= 1
    hi = k
    while hi < mag.size - 1 and mag[hi + 1] >= half:
        hi += 1

    def edge(inside: int, outside: int) -> float:
        if outside < 0 or outside >= mag.size:
            return float(freqs[inside])
        a, b = mag[outside], mag[inside]
        frac = (half - a) / (b - a) if b != a else 0.0
        return float(freqs[outside] + frac * (freqs[inside] - freqs[outside]))

    return edge(lo, lo - 1), edge(hi, hi + 1)


def whiteness(noise: NDArray[np.float64], fs: float) -> tuple[float, float]:
    """(spectral flatness, Ljung–Box p-value) of noise records, shape ``(n_records, n)``."""
    x = noise - noise.mean(axis=-1, keepdims=True)
    _, psd = scipy.signal.welch(x, fs=fs, nperseg=min(64, x.shape[-1]), axis=-1)
    psd = psd.mean(axis=0)[1:-1]  # without DC (the mean removed) and Nyquist
    flatness = float(np.exp(np.mean(np.log(psd))) / np.mean(psd))
    n = x.shape[-1]
    denom = np.sum(x * x, axis=-1)
    rho = np.array([np.sum(x[:, k:] * x[:, :-k], axis=-1) / denom for k in range(1, _LAGS + 1)])
    # Ljung–Box per record, summed over the independent records: chi2 with lags × records dof
    q = n * (n + 2) * np.sum(rho**2 / (n - np.arange(1, _LAGS + 1))[:, None], axis=0)
    p_value = float(scipy.stats.chi2.sf(float(q.sum()), _LAGS * x.shape[0]))
    return flatness, p_value


def probe_from_echo(scan: PositionScan, *, gate: TimeGate | None = None) -> ProbeEstimate:
    """Estimate the probe and the receiver from ``scan``'s front-wall echo (see the module
    docstring); ``gate`` holds the echo (default: the triggered ``front-wall`` gate)."""
    x = scan.samples.reshape(-1, scan.samples.shape[-1])
    x = x[scan.valid.reshape(-1)]
    window = scan.window
    tof = front_wall_tof(x, window, gate=gate)
    pulse = stacked_template(x, window, tof)
    spec = np.abs(np.fft.rfft(pulse.samples, n=max(4096, 4 * pulse.samples.size))).astype(
        np.float64
    )
    freqs = np.asarray(
        np.fft.rfftfreq(max(4096, 4 * pulse.samples.size), 1.0 / window.fs), dtype=np.float64
    )
    lo, hi = _band(freqs, spec)
    chosen = gate if gate is not None else named_gate("front-wall", pulse=pulse)
    start = np.nanmin(chosen.starts(x, window))
    n_noise = int(np.floor((start - window.start) * window.fs))
    if not n_noise >= _MIN_NOISE:
        raise EchocalValueError(
            f"the recordings hold {max(n_noise, 0)} samples before the front-wall echo; the "
            f"noise estimate needs at least {_MIN_NOISE}: start the recording earlier"
        )
    noise = x[:, :n_noise]
    sigma = float(1.4826 * np.median(np.abs(noise - np.median(noise))))
    flatness, p_value = whiteness(noise, window.fs)
    return ProbeEstimate(
        pulse=pulse,
        center_frequency=0.5 * (lo + hi),
        band=(lo, hi),
        noise_sigma=sigma,
        spectral_flatness=flatness,
        whiteness_p_value=p_value,
    )
