"""Echo detection: is there an echo in this A-scan at all, and how sure are we?

While searching for a lost echo the question is not "how much energy" but "is
anything above the noise".  The best single-A-scan answer is the matched filter's
peak: a flaw detector's gate on the filtered trace.  For white Gaussian noise of
per-sample standard deviation σ the matched-filter envelope is a correlated
Rayleigh process of scale σ·s (``s`` = the filter's noise gain); its maximum over
the window behaves like the maximum of ``N_eff`` independent Rayleigh cells, so the
normalized peak Z = max(envelope) / (σ·s) of pure noise follows

    P(Z ≤ t) = exp(−N_eff · exp(−t²/2))          (Gumbel limit of the Rayleigh maximum).

:class:`EchoDetector` measures ``s`` and ``N_eff`` once per (pulse, fs, n_samples)
on unit-variance synthetic noise (a fixed internal seed) and returns for each A-scan
the *Gaussian-equivalent significance*

    g = Φ⁻¹(P(Z ≤ t_observed))                    (≈ N(0, 1) for pure noise),

so thresholds read as "σ": g > 4 happens by chance about 3·10⁻⁵ of the time, and
independent significances combine as Σg/√n (Stouffer).  On the realistic 5 MHz probe
at 30 dB the peak detector finds the echo ≈ 2.5° from the optimum where the
pseudo-energy (an energy sum around the same peak, but over raw unfiltered samples)
loses it at ≈ 2.1° at the same false-alarm rate.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ndtri

from echocal._validate import nonnegative_float
from echocal.signal.processing import _samples, matched_envelope
from echocal.signal.pulses import Pulse

__all__ = ["EchoDetector"]

_F64 = NDArray[np.float64]
_CALIBRATION_SCANS = 1024  # N_eff from the median to ≈ 2 %: mean significance of noise ≈ 0
_CALIBRATION_CHUNK = 128
_CALIBRATION_SEED = 20261122
_FAR_TAIL = -650.0  # ln P below which the tail probability leaves double precision


@dataclass(frozen=True)
class EchoDetector:
    """Matched-filter peak detector for A-scans of one pulse, sampling rate and length.

    Parameters
    ----------
    pulse : the transmitted pulse (the matched filter's template).
    fs : [Hz] sampling rate.
    n_samples : samples per A-scan.

    Attributes (measured on unit-σ noise at construction)
    ----------
    noise_gain : [a.u. per a.u. of σ] Rayleigh scale of the matched envelope per unit σ.
    n_cells : N_eff, the number of independent noise cells of the window.
    """

    pulse: Pulse
    fs: float
    n_samples: int
    noise_gain: float = field(init=False)
    n_cells: float = field(init=False)

    def __post_init__(self) -> None:
        rng = np.random.default_rng(_CALIBRATION_SEED)
        power, peaks = 0.0, []
        for _ in range(_CALIBRATION_SCANS // _CALIBRATION_CHUNK):
            noise = rng.standard_normal((_CALIBRATION_CHUNK, int(self.n_samples)))
            env = matched_envelope(noise, self.pulse, self.fs)
            power += float(np.mean(env * env))
            peaks.append(env.max(axis=-1))
        # Rayleigh scale from the mean power: E|z|² = 2 s² (every cell, not only the peaks)
        gain = float(np.sqrt(power / (_CALIBRATION_SCANS // _CALIBRATION_CHUNK) / 2.0))
        peaks = np.concatenate(peaks) / gain
        # median of the Gumbel law: exp(−N e^{−t²/2}) = 1/2  →  N = ln 2 · e^{t²/2}
        cells = float(np.log(2.0) * np.exp(0.5 * np.median(peaks) ** 2))
        object.__setattr__(self, "noise_gain", gain)
        object.__setattr__(self, "n_cells", cells)

    def peak(self, samples: ArrayLike) -> _F64:
        """[a.u.] maximum of the matched-filter envelope of each A-scan, shape ``(...,)``."""
        return matched_envelope(_samples(samples), self.pulse, self.fs).max(axis=-1)

    def significance_of_peak(self, peak: ArrayLike, sigma: float) -> _F64:
        """Gaussian-equivalent significance of envelope peaks ``peak`` [a.u.], shape ``(...,)``,
        against white noise of per-sample standard deviation ``sigma`` [a.u.].

        σ = 0 (noiseless) gives +∞ where the peak is positive and −∞ where it is zero.
        """
        sigma = nonnegative_float("sigma", sigma)
        p = np.asarray(peak, dtype=np.float64)
        if sigma == 0.0:
            return np.where(p > 0.0, np.inf, -8.2)
        t = p / (sigma * self.noise_gain)
        log_tail = np.log(self.n_cells) - 0.5 * t * t  # ln(N e^{−t²/2})
        with np.errstate(over="ignore", under="ignore"):
            upper = -np.expm1(-np.exp(log_tail))  # P(Z > t) under noise
            g = -ndtri(np.clip(upper, 1e-300, 1.0 - 1e-16))  # g in [−8.2, 37]
        # far tail: P ≈ N e^{−t²/2}; Φ⁻¹(1 − P) ≈ √(L − ln L − ln 2π), L = −2 ln P
        big = -2.0 * np.minimum(log_tail, _FAR_TAIL)
        asymptotic = np.sqrt(big - np.log(big) - np.log(2.0 * np.pi))
        return np.asarray(np.where(log_tail < _FAR_TAIL, asymptotic, g), dtype=np.float64)

    def significance(self, samples: ArrayLike, sigma: float) -> _F64:
        """Gaussian-equivalent significance of each A-scan's strongest echo, shape ``(...,)``.

        ``samples`` : [a.u.], shape ``(..., n_samples)``; ``sigma`` : [a.u.] the receiver's
        per-sample noise standard deviation.  ≈ N(0, 1) for pure noise; large for an echo.
        """
        return self.significance_of_peak(self.peak(samples), sigma)
