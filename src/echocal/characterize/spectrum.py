"""Centre frequency and −6 dB bandwidth from the front-wall echo's spectrum.

EN 12668-2's frequency-response measurement: gate the echo of a flat reflector at the
beam axis, take its amplitude spectrum, and read the lower and upper −6 dB frequencies
``f_l``, ``f_u`` (interpolated); the centre frequency is ``f_c = (f_l + f_u)/2``, the
bandwidth ``Δf = f_u − f_l`` and the relative bandwidth ``Δf / f_c``.  The peak frequency
``f_p`` is reported too.  The gate is the span around the envelope peak where the
envelope stays above ``gate_db`` (−40 dB by default), padded by half its length.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_float, positive_int
from echocal.errors import EchocalValueError
from echocal.geometry import Pose
from echocal.measurement.base import MeasurementSource
from echocal.signal.processing import envelope

__all__ = ["EchoSpectrum", "measure_spectrum", "spectrum_band"]

FloatArray = NDArray[np.float64]


def _crossing(f: FloatArray, a: FloatArray, i: int, j: int) -> float:
    """Frequency where ``a`` crosses 1/2 between bins ``i`` and ``j`` (linear)."""
    return float(f[i] + (0.5 - a[i]) * (f[j] - f[i]) / (a[j] - a[i]))


def spectrum_band(freqs: ArrayLike, amplitude: ArrayLike) -> tuple[float, float, float]:
    """Peak frequency and the −6 dB frequencies ``(f_p, f_l, f_u)`` [Hz] of an amplitude
    spectrum ``amplitude`` at ``freqs`` (both shape ``(n,)``), the crossings interpolated
    linearly between bins on either side of the peak."""
    f = np.asarray(freqs, dtype=np.float64)
    a = np.asarray(amplitude, dtype=np.float64)
    peak = int(np.argmax(a))
    a = a / a[peak]
    below = np.flatnonzero(a[:peak] < 0.5)
    above = np.flatnonzero(a[peak:] < 0.5)
    if below.size == 0 or above.size == 0:
        raise EchocalValueError(
            "the echo's spectrum does not fall to -6 dB inside the recorded band: "
            "sample faster or gate the echo alone"
        )
    lo = int(below[-1])
    hi = peak + int(above[0])
    return float(f[peak]), _crossing(f, a, lo, lo + 1), _crossing(f, a, hi - 1, hi)


@dataclass(frozen=True, kw_only=True)
class EchoSpectrum:
    """The front-wall echo's spectrum and its −6 dB band.

    Attributes
    ----------
    freqs : [Hz] frequencies, shape ``(n,)``.
    amplitude : the averaged echo's amplitude spectrum normalised to its peak, ``(n,)``.
    peak_hz, lower_hz, upper_hz : [Hz] f_p, f_l, f_u of the averaged echo.
    center_hz, bandwidth_hz : [Hz] f_c = (f_l + f_u)/2 and Δf = f_u − f_l.
    center_sigma_hz, bandwidth_sigma_hz : [Hz] 1-σ uncertainties of the two from the
        scatter of the single A-scans' values (their standard error; 0 from one A-scan).
    gate_s : [s] start and end of the gate, shape ``(2,)``.
    n_ascans : A-scans averaged.
    """

    freqs: FloatArray
    amplitude: FloatArray
    peak_hz: float
    lower_hz: float
    upper_hz: float
    center_hz: float
    bandwidth_hz: float
    center_sigma_hz: float
    bandwidth_sigma_hz: float
    gate_s: FloatArray
    n_ascans: int

    @property
    def relative_bandwidth(self) -> float:
        """Δf / f_c (a fraction)."""
        return self.bandwidth_hz / self.center_hz

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON (frequencies in Hz)."""
        return {
            "peak_frequency_hz": self.peak_hz,
            "lower_6db_hz": self.lower_hz,
            "upper_6db_hz": self.upper_hz,
            "center_frequency_hz": self.center_hz,
            "center_frequency_sigma_hz": self.center_sigma_hz,
            "bandwidth_6db_hz": self.bandwidth_hz,
            "bandwidth_6db_sigma_hz": self.bandwidth_sigma_hz,
            "relative_bandwidth": self.relative_bandwidth,
            "gate_s": self.gate_s.tolist(),
            "n_ascans": self.n_ascans,
        }


def _gate(env: FloatArray, level: float) -> tuple[int, int]:
    peak = int(np.argmax(env))
    low = env < level * env[peak]
    start = int(np.flatnonzero(low[:peak])[-1]) if low[:peak].any() else 0
    stop = peak + int(np.flatnonzero(low[peak:])[0]) if low[peak:].any() else env.size
    pad = (stop - start) // 2
    return max(start - pad, 0), min(stop + pad, env.size)


def measure_spectrum(
    source: MeasurementSource,
    pose: Pose,
    *,
    n_ascans: int = 16,
    gate_db: float = -40.0,
    zero_pad: int = 8,
) -> EchoSpectrum:
    """Measure the echo's spectrum at ``pose`` (the beam axis over a flat reflector).

    Parameters
    ----------
    source : any :class:`~echocal.measurement.base.MeasurementSource`.
    pose : where to measure (normally :attr:`BeamAxis.pose`).
    n_ascans : A-scans averaged sample by sample (noise falls as 1/√n).
    gate_db : [dB] the gate is where the averaged envelope is above this level re its
        peak, padded by half its length either side (< 0).
    zero_pad : the FFT's length is this many times the gate's (finer bins to interpolate).
    """
    n = positive_int("n_ascans", n_ascans)
    level_db = finite_float("gate_db", gate_db)
    if level_db >= 0:
        raise EchocalValueError(f"gate_db must be < 0 dB; got {level_db:g}")
    pad = positive_int("zero_pad", zero_pad)
    scans = source.measure_many([pose] * n)
    fs = scans[0].fs
    samples = np.array([s.samples for s in scans])
    mean = samples.mean(axis=0)
    start, stop = _gate(envelope(mean), 10.0 ** (level_db / 20.0))
    n_fft = pad * (stop - start)
    freqs = np.asarray(np.fft.rfftfreq(n_fft, 1.0 / fs), dtype=np.float64)
    spectra = np.abs(np.fft.rfft(samples[:, start:stop], n=n_fft, axis=-1))
    mean_spectrum = np.abs(np.fft.rfft(mean[start:stop], n=n_fft))
    f_p, f_l, f_u = spectrum_band(freqs, mean_spectrum)
    if n > 1:
        bands = np.array([spectrum_band(freqs, s)[1:] for s in spectra])
        centres = bands.mean(axis=1)
        widths = bands[:, 1] - bands[:, 0]
        c_sigma = float(centres.std(ddof=1) / np.sqrt(n))
        b_sigma = float(widths.std(ddof=1) / np.sqrt(n))
    else:
        c_sigma = b_sigma = 0.0
    t0 = scans[0].start_time
    return EchoSpectrum(
        freqs=freqs,
        amplitude=mean_spectrum / mean_spectrum.max(),
        peak_hz=f_p,
        lower_hz=f_l,
        upper_hz=f_u,
        center_hz=0.5 * (f_l + f_u),
        bandwidth_hz=f_u - f_l,
        center_sigma_hz=c_sigma,
        bandwidth_sigma_hz=b_sigma,
        gate_s=np.array([t0 + start / fs, t0 + stop / fs]),
        n_ascans=n,
    )
