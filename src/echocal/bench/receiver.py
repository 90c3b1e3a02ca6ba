"""The receiver's imperfections: coloured noise, a gain curve, timing jitter, and the
water's temperature drifting during a run.

- **Coloured noise**: an autoregressive AR(p) process ``n[k] = Σᵢ aᵢ n[k−i] + e[k]``
  (``noise_ar = (a₁, …, a_p)``), scaled to unit stationary variance, so the setup's SNR
  keeps its meaning: σ is still the standard deviation of the noise per sample.
- **Gain curve** (DAC / TGC): ``gain_curve = ((t₀, g₀), (t₁, g₁), …)``, times [s] from the
  transmit pulse and gains [dB], linear in dB between the points and held beyond them;
  applied to signal plus noise, before saturation and the ADC.
- **Jitter**: the trigger's timing error, a normal delay of standard deviation
  ``jitter`` [s] per A-scan.
- **Temperature drift** [°C/s]: the water warms (or cools) at this rate over the bench
  time, so the sound speed — pure water's, Marczak (1997), J. Acoust. Soc. Am. 102, 2776,
  within 0.02 m/s of Del Grosso & Mader (1972) — and with it every time of flight changes:
  an A-scan recorded at speed c′ is the one at c₀ with its time axis scaled by c′/c₀.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_array, finite_float, in_range, nonnegative_float
from echocal.errors import EchocalValueError
from echocal.materials import _MARCZAK

__all__ = [
    "GAIN_DB_RANGE",
    "MAX_AR_POLE",
    "BenchReceiver",
    "ar_burn_in",
    "ar_noise",
    "check_ar",
    "water_sound_speed",
]

FloatArray = NDArray[np.float64]

MAX_AR_POLE = 0.999
"""The largest pole radius an AR noise model may have: a pole nearer the unit circle is a
near-constant drift, not receiver noise (and would need a burn-in of thousands of samples)."""

GAIN_DB_RANGE = (-120.0, 120.0)
"""[dB] the gains a gain curve may give: a receiver's range (a pulser-receiver's gain spans
some 0-110 dB).  Beyond it the A-scan's samples overflow (10^(g/20) is inf past ~6000 dB)
or vanish."""

_BURN_IN_DECAY = 1e-8
"""The AR filter's memory of its zero start left after the burn-in (of its impulse response)."""


def water_sound_speed(temperature: ArrayLike) -> FloatArray:
    """[m/s] sound speed of pure water at ``temperature`` [°C] (0 to 95), shape as given:
    Marczak (1997)'s fifth-degree polynomial."""
    t = np.asarray(temperature, dtype=np.float64)
    return np.asarray(np.polynomial.polynomial.polyval(t, _MARCZAK), dtype=np.float64)


def check_ar(name: str, coefficients: ArrayLike) -> tuple[float, ...]:
    """``coefficients`` (a₁, …, a_p) of a stationary AR model as a tuple (one clear error
    otherwise: a pole on or outside radius :data:`MAX_AR_POLE`)."""
    a = finite_array(name, coefficients).reshape(-1)
    if a.size == 0:
        return ()
    radius = float(np.max(np.abs(np.roots(np.concatenate([[1.0], -a])))))
    if radius > MAX_AR_POLE:
        raise EchocalValueError(
            f"{name}: the AR model is not stationary enough (a pole at radius {radius:.4g}; "
            f"at most {MAX_AR_POLE}); lower the coefficients (e.g. [0.7] for noise "
            "correlated over a few samples)"
        )
    return tuple(float(v) for v in a)


def ar_burn_in(coefficients: tuple[float, ...]) -> int:
    """Samples the AR filter runs before its output is kept: its impulse response has then
    decayed to :data:`_BURN_IN_DECAY` of its start."""
    if not coefficients:
        return 0
    radius = float(np.max(np.abs(np.roots(np.concatenate([[1.0], -np.asarray(coefficients)])))))
    if radius == 0.0:
        return len(coefficients)
    return len(coefficients) + math.ceil(math.log(_BURN_IN_DECAY) / math.log(radius))


def _ar_gain(coefficients: tuple[float, ...]) -> float:
    """The AR filter's stationary output standard deviation for unit white input:
    √Σh[k]² over its impulse response h."""
    import scipy.signal  # here, not at module level: ~1 CPU-s a CLI start need not pay

    impulse = np.zeros(ar_burn_in(coefficients) + 1)
    impulse[0] = 1.0
    h = scipy.signal.lfilter([1.0], np.concatenate([[1.0], -np.asarray(coefficients)]), impulse)
    return float(np.sqrt(np.sum(h * h)))


def ar_noise(
    shape: tuple[int, ...], coefficients: tuple[float, ...], rng: np.random.Generator
) -> FloatArray:
    """Stationary AR noise of unit variance, shape ``shape`` (time on the last axis); white
    standard normal noise for no coefficients.  Each row starts from the filter's
    stationary state (a burn-in of :func:`ar_burn_in` samples is drawn and dropped)."""
    import scipy.signal  # here, not at module level: ~1 CPU-s a CLI start need not pay

    if not coefficients:
        return rng.standard_normal(shape)
    burn = ar_burn_in(coefficients)
    white = rng.standard_normal((*shape[:-1], shape[-1] + burn))
    denominator = np.concatenate([[1.0], -np.asarray(coefficients)])
    coloured = scipy.signal.lfilter([1.0], denominator, white, axis=-1)[..., burn:]
    return np.ascontiguousarray(coloured / _ar_gain(coefficients))


@dataclass(frozen=True, kw_only=True)
class BenchReceiver:
    """Coloured noise, gain curve, jitter and temperature drift (see the module).

    Attributes
    ----------
    noise_ar : AR coefficients (a₁, …, a_p); () for white noise.
    gain_curve : ((t [s], gain [dB]), …) in increasing time; () for a flat gain.
    jitter : [s] standard deviation of the trigger's timing error per A-scan.
    temperature : [°C] the water's temperature at the run's start (0 to 95).
    temperature_drift : [°C/s] its rate of change over the bench time.
    """

    noise_ar: tuple[float, ...] = ()
    gain_curve: tuple[tuple[float, float], ...] = ()
    jitter: float = 0.0
    temperature: float = 20.0
    temperature_drift: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "noise_ar", check_ar("bench.receiver.noise_ar", self.noise_ar))
        curve = self.gain_curve
        if len(curve):
            points = finite_array("bench.receiver.gain_curve", curve, shape_tail=(2,))
            if points.ndim != 2 or np.any(np.diff(points[:, 0]) <= 0.0):
                raise EchocalValueError(
                    "bench.receiver.gain_curve: give [time, dB] points in increasing time, "
                    'e.g. [[0, 0], ["30 us", 12]]'
                )
            low, high = GAIN_DB_RANGE
            if np.any(points[:, 1] < low) or np.any(points[:, 1] > high):
                raise EchocalValueError(
                    f"bench.receiver.gain_curve: gains must lie in [{low:g}, {high:g}] dB (a "
                    f"receiver's range; beyond it the A-scan overflows or vanishes); got "
                    f"{', '.join(f'{g:g}' for g in points[:, 1])} dB"
                )
            curve = tuple((float(t), float(g)) for t, g in points)
        object.__setattr__(self, "gain_curve", tuple(curve))
        object.__setattr__(self, "jitter", nonnegative_float("bench.receiver.jitter", self.jitter))
        object.__setattr__(
            self, "temperature", in_range("medium.temperature", self.temperature, 0.0, 95.0)
        )
        object.__setattr__(
            self,
            "temperature_drift",
            finite_float("bench.receiver.temperature_drift", self.temperature_drift),
        )

    @property
    def is_ideal(self) -> bool:
        """True for white noise, a flat gain, no jitter and no drift."""
        return not (self.noise_ar or self.gain_curve or self.jitter or self.temperature_drift)

    @property
    def warps_time(self) -> bool:
        """True when A-scans are resampled (jitter or drift)."""
        return bool(self.jitter or self.temperature_drift)

    def gain(self, times: FloatArray) -> FloatArray:
        """The gain curve's amplitude factor at ``times`` [s] (any shape)."""
        if not self.gain_curve:
            return np.ones_like(times)
        t, db = np.asarray(self.gain_curve).T
        return np.asarray(10.0 ** (np.interp(times, t, db) / 20.0), dtype=np.float64)

    def speed_ratio(self, elapsed: FloatArray) -> FloatArray:
        """c(T(t)) / c(T₀) after ``elapsed`` [s] of bench time, ``(P,)`` (T kept in 0–95 °C)."""
        now = np.clip(self.temperature + self.temperature_drift * elapsed, 0.0, 95.0)
        return water_sound_speed(now) / water_sound_speed(self.temperature)

    def warp(
        self,
        samples: FloatArray,
        start: float,
        fs: float,
        speed_ratio: FloatArray,
        delay: FloatArray,
    ) -> FloatArray:
        """A-scans ``(P, n)`` recorded at ``speed_ratio`` × c₀ and triggered ``delay`` [s]
        late, ``(P,)`` each: ``y(t) = x((t − delay)·ratio)``, resampled by cubic splines
        (zero outside the recording; one row at a time, rows never mix)."""
        import scipy.ndimage  # here, not at module level: most runs never warp

        times = start + np.arange(samples.shape[-1]) / fs
        source = ((times[None, :] - delay[:, None]) * speed_ratio[:, None] - start) * fs
        out = np.empty_like(samples)
        for row, (scan, coords) in enumerate(zip(samples, source, strict=True)):
            out[row] = scipy.ndimage.map_coordinates(scan, coords[None], order=3, mode="constant")
        return out
