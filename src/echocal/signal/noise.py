"""Receiver noise, saturation and quantization (thesis §12.2.1.3).

The noise power belongs to the instrument (docs/physics.md, "The thesis's errata"): it is
fixed once per setup from the SNR of a *reference* echo — the echo at normal incidence, the
best orientation — and then stays the same for every measurement, so off-optimum
orientations really have lower SNR.

SNR definition used throughout::

    SNR [dB] = 10·log10(P_signal / σ²)

with σ the standard deviation of the additive white Gaussian noise per sample and
P_signal the mean power (1/K)·Σ x[k]² of the K reference samples inside the pseudo-energy
window centred on the matched-filter peak (:func:`echocal.signal.processing.pseudo_energy`,
default length 2 × the pulse's −20 dB duration).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._rng import RngLike, as_generator
from echocal._validate import finite_array, finite_float, nonnegative_float, positive_float
from echocal.errors import EchocalValueError
from echocal.signal.processing import _energy_window
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow

__all__ = [
    "SNR_DB_RANGE",
    "Receiver",
    "check_snr_db",
    "mad_sigma",
    "noise_sigma_for_snr",
    "scan_noise_sigma",
    "signal_power",
    "snr_for_noise_sigma",
]


def signal_power(
    reference_samples: ArrayLike,
    window: RecordingWindow,
    pulse: Pulse,
    *,
    window_length: float | None = None,
) -> NDArray[np.float64]:
    """[a.u.²] mean power of the reference echo inside its pseudo-energy window, ``(...,)``."""
    energy, count, _peak = _energy_window(reference_samples, window, pulse, window_length)
    return energy / np.maximum(count, 1)


SNR_DB_RANGE = (-100.0, 200.0)
"""[dB] the SNRs a receiver may have: beyond 200 dB the noise is below any float's
resolution of the echo (use no noise instead), below -100 dB no echo is measurable."""


def check_snr_db(name: str, snr_db: Any) -> float:
    """``snr_db`` [dB] as a float within :data:`SNR_DB_RANGE` (one clear error otherwise)."""
    low, high = SNR_DB_RANGE
    if isinstance(snr_db, float | np.floating) and not np.isfinite(snr_db):
        raise EchocalValueError(
            f"{name} must be finite, a number of dB in [{low:g}, {high:g}] (for a noiseless "
            f"receiver give 'none'); got {float(snr_db)}"
        )
    snr = finite_float(name, snr_db)
    if not low <= snr <= high:
        raise EchocalValueError(
            f"{name} must lie in [{low:g}, {high:g}] dB (for a noiseless receiver give "
            f"'none'); got {snr:g}"
        )
    return snr


def noise_sigma_for_snr(
    reference_samples: ArrayLike,
    snr_db: float,
    window: RecordingWindow,
    pulse: Pulse,
    *,
    window_length: float | None = None,
) -> float | NDArray[np.float64]:
    """[a.u.] noise standard deviation σ giving ``snr_db`` [dB] for the reference echo.

    σ = √(P_signal / 10^(SNR/10)), P_signal as in the module docstring.  Returns a float
    for one reference A-scan, shape ``(...,)`` for a batch.

    Raises
    ------
    EchocalValueError
        ``snr_db`` not finite, or a reference echo with zero power.
    """
    snr = check_snr_db("snr_db", snr_db)
    power = signal_power(reference_samples, window, pulse, window_length=window_length)
    if np.any(power <= 0.0):
        raise EchocalValueError("reference_samples must hold an echo; its power is zero")
    sigma = np.sqrt(power / 10.0 ** (snr / 10.0))
    return float(sigma) if sigma.ndim == 0 else sigma


def snr_for_noise_sigma(
    reference_samples: ArrayLike,
    noise_sigma: float,
    window: RecordingWindow,
    pulse: Pulse,
) -> float:
    """[dB] the SNR of the reference echo against white noise of ``noise_sigma`` [a.u.]
    per sample: 10·log10(P_signal / σ²), the inverse of :func:`noise_sigma_for_snr` (inf
    for σ = 0, -inf for an echo of zero power)."""
    sigma = nonnegative_float("noise_sigma", noise_sigma)
    power = float(signal_power(reference_samples, window, pulse))
    with np.errstate(divide="ignore"):
        return float(10.0 * np.log10(power) - 20.0 * np.log10(sigma))


@dataclass(frozen=True, kw_only=True)
class Receiver:
    """A receiver's analogue front end and digitizer.

    ``receive`` computes y = gain·(x + n), n ~ N(0, noise_sigma²) white, then clips y to
    ±full_scale (saturation), then rounds it to one of the 2^adc_bits levels
    k·Δ, k = −2^(b−1) … 2^(b−1) − 1, Δ = 2·full_scale / 2^b (mid-tread quantizer).

    Attributes
    ----------
    noise_sigma : [a.u.] input-referred noise standard deviation (>= 0).
    adc_bits : number of ADC bits (1..32), or None for no quantization.
    full_scale : [a.u.] saturation level (> 0) after gain, or None for no limit; needed
        by ``adc_bits``.
    gain : amplification (> 0) applied to signal plus noise.
    """

    noise_sigma: float = 0.0
    adc_bits: int | None = None
    full_scale: float | None = None
    gain: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "noise_sigma", nonnegative_float("noise_sigma", self.noise_sigma))
        object.__setattr__(self, "gain", positive_float("gain", self.gain))
        if self.full_scale is not None:
            object.__setattr__(self, "full_scale", positive_float("full_scale", self.full_scale))
        if self.adc_bits is not None:
            bits = self.adc_bits
            if (
                isinstance(bits, bool)
                or not isinstance(bits, int | np.integer)
                or not (1 <= bits <= 32)
            ):
                raise EchocalValueError(f"adc_bits must be an integer in 1..32; got {bits!r}")
            if self.full_scale is None:
                raise EchocalValueError("full_scale is required when adc_bits is set")
            object.__setattr__(self, "adc_bits", int(bits))

    @classmethod
    def from_snr(
        cls,
        reference_samples: ArrayLike,
        snr_db: float,
        window: RecordingWindow,
        pulse: Pulse,
        *,
        window_length: float | None = None,
        adc_bits: int | None = None,
        full_scale: float | None = None,
        gain: float = 1.0,
    ) -> Receiver:
        """A receiver whose noise gives ``snr_db`` [dB] on the reference echo (1-D)."""
        sigma = noise_sigma_for_snr(
            reference_samples, snr_db, window, pulse, window_length=window_length
        )
        if not isinstance(sigma, float):
            raise EchocalValueError("reference_samples must be one A-scan, shape (n_samples,)")
        return cls(noise_sigma=sigma, adc_bits=adc_bits, full_scale=full_scale, gain=gain)

    @property
    def lsb(self) -> float | None:
        """[a.u.] quantization step Δ, or None without ADC."""
        if self.adc_bits is None or self.full_scale is None:
            return None
        return 2.0 * self.full_scale / 2.0**self.adc_bits

    def receive(self, samples: ArrayLike, rng: RngLike = None) -> NDArray[np.float64]:
        """Add noise, amplify, saturate and quantize ``samples`` (shape ``(..., n_samples)``).

        ``rng``: Generator, int seed or None; the same seed gives bit-for-bit the same output.
        """
        return self._receive_unchecked(finite_array("samples", samples), as_generator(rng))

    def _receive_unchecked(
        self, x: NDArray[np.float64], gen: np.random.Generator
    ) -> NDArray[np.float64]:
        """:meth:`receive` of finite float64 samples (the simulator's, checked by construction)."""
        if self.noise_sigma:
            y = gen.standard_normal(x.shape)
            y *= self.noise_sigma
            y += x  # σ·n + x: the same sum as x + σ·n
        else:
            y = x.copy()
        if self.gain != 1.0:
            y *= self.gain
        if self.full_scale is not None:
            np.clip(y, -self.full_scale, self.full_scale, out=y)
        step = self.lsb
        if step is not None:
            top = 2 ** (self.adc_bits - 1)  # type: ignore[operator]
            y = np.clip(np.round(y / step), -top, top - 1) * step
        return y


def mad_sigma(samples: ArrayLike) -> NDArray[np.float64]:
    """[a.u.] the robust noise σ of each A-scan, shape ``(...,)``: 1.4826 × the median
    absolute deviation of its samples (last axis) — the σ of Gaussian noise, unmoved by
    an echo that fills a small part of the recording; 0 when most samples share one
    value (noise below the ADC step, or none)."""
    x = np.asarray(samples, dtype=np.float64)
    return 1.4826 * np.median(np.abs(x - np.median(x, axis=-1, keepdims=True)), axis=-1)


def scan_noise_sigma(samples: np.ndarray) -> tuple[float | None, bool]:
    """[a.u.] the receiver's per-sample noise σ estimated from one A-scan (None if it
    cannot tell), and whether the noise is below the ADC step.

    The echo fills a small part of a recording, so 1.4826 · MAD of the samples is a robust
    estimate.  When the noise is below the ADC step Δ most samples share one level and the
    MAD is 0; then the RMS deviation of the samples within ±3 Δ of that level measures the
    quantized noise the receiver actually delivers (the echo's large samples excluded).
    σ is None for a constant trace (nothing to tell), and when it would not be finite (a
    trace of infinite or overflowing samples: a receiver fault, not a noise level).
    "Below the ADC step" means the MAD is 0 and the sample values lie on a grid (an
    ADC's levels).
    """
    samples = np.asarray(samples, dtype=np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        sigma = float(mad_sigma(samples))
    if not np.isfinite(sigma):
        return None, False
    if sigma > 0.0:
        return sigma, False
    dev = samples - np.median(samples)
    levels = np.unique(samples)
    if levels.size < 2:
        return None, False
    step = float(np.min(np.diff(levels)))
    near = np.abs(dev) <= 3.0 * step
    with np.errstate(over="ignore", invalid="ignore"):
        sigma = float(np.sqrt(np.mean(dev[near] ** 2)))
        # an ADC's levels lie on a grid of its step; a noiseless float trace's do not
        on_grid = np.allclose(levels / step, np.round(levels / step), rtol=0.0, atol=1e-6)
    if not np.isfinite(sigma):  # levels so far apart their squares overflow: a fault
        return None, False
    return sigma, bool(on_grid)
