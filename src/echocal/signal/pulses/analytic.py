"""The closed-form pulses: Gabor, windowed sinc and Ricker (see
:mod:`echocal.signal.pulses`)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import finite_float, in_range, lookup, positive_float, positive_int
from echocal.constants import DEFAULT_CENTER_FREQUENCY
from echocal.errors import EchocalValueError
from echocal.signal.pulses.base import (
    _F64,
    _LN2,
    DURATION_LEVEL,
    HIGHEST_FREQUENCY_LEVEL,
    MAX_PULSE_CYCLES,
    SUPPORT_LEVEL,
    Pulse,
    _center_frequency,
)
from echocal.units import format_frequency


# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class GaborPulse(Pulse):
    """Gaussian-enveloped carrier (thesis eqs. 25, 35–37): w(t) = exp(−αt²)·cos(2πf_c t + φ).

    Attributes
    ----------
    center_frequency : [Hz] carrier frequency f_c (> 0).
    bandwidth : [%] fractional −6 dB bandwidth of the amplitude spectrum |W(f)|, in (0, 200].
        The bandwidth factor follows as α = (π·f_c·bandwidth/100 / 2)² / ln 2 [1/s²]:
        |W(f)| ∝ exp(−π²(f − f_c)²/α) falls to one half at f_c ± √(α ln 2)/π, so the
        full −6 dB width is 2√(α ln 2)/π (the same convention as scipy.signal.gausspulse;
        exact for the positive-frequency lobe, whose overlap with the negative one is
        negligible for bandwidths below ~150 %).  Use :meth:`from_alpha` to give α.
    phase : [deg] carrier phase φ, within ±360°.
    """

    center_frequency: float = DEFAULT_CENTER_FREQUENCY
    bandwidth: float = 60.0
    phase: float = 0.0
    name: ClassVar[str] = "gabor"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center_frequency", _center_frequency(self.center_frequency))
        bw = positive_float("bandwidth", self.bandwidth)
        if bw > 200.0:
            raise EchocalValueError(f"bandwidth must lie in (0, 200] %; got {bw:g}")
        object.__setattr__(self, "bandwidth", bw)
        object.__setattr__(self, "phase", in_range("phase", self.phase, -360.0, 360.0))

    @classmethod
    def from_alpha(
        cls, *, alpha: float, center_frequency: float = DEFAULT_CENTER_FREQUENCY, phase=0.0
    ) -> GaborPulse:
        """Build from the bandwidth factor α [1/s²] of thesis eq. (35)."""
        alpha = positive_float("alpha", alpha)
        fc = positive_float("center_frequency", center_frequency)
        bandwidth = 200.0 * math.sqrt(alpha * _LN2) / (math.pi * fc)
        return cls(center_frequency=fc, bandwidth=bandwidth, phase=phase)

    @property
    def alpha(self) -> float:
        """[1/s²] bandwidth factor α of the Gaussian envelope exp(−αt²)."""
        return (math.pi * self.center_frequency * self.bandwidth / 200.0) ** 2 / _LN2

    def waveform(self, t: ArrayLike) -> _F64:
        t = np.asarray(t, dtype=np.float64)
        phi = math.radians(self.phase)
        return np.exp(-self.alpha * t * t) * np.cos(2 * np.pi * self.center_frequency * t + phi)

    def spectrum(self, f: ArrayLike) -> NDArray[np.complex128]:
        """W(f) = ½√(π/α)[e^{iφ} e^{−π²(f−f_c)²/α} + e^{−iφ} e^{−π²(f+f_c)²/α}] (closed form)."""
        f = np.asarray(f, dtype=np.float64)
        a, fc, phi = self.alpha, self.center_frequency, math.radians(self.phase)
        g = 0.5 * math.sqrt(math.pi / a)
        k = math.pi**2 / a
        return g * (
            np.exp(1j * phi) * np.exp(-k * (f - fc) ** 2)
            + np.exp(-1j * phi) * np.exp(-k * (f + fc) ** 2)
        )

    def autocorrelation(self, lags: ArrayLike) -> _F64:
        """R(ℓ) = ½√(π/2α)·e^{−αℓ²/2}[cos(2πf_cℓ) + cos(2φ)e^{−2π²f_c²/α}] (closed form)."""
        lags = np.asarray(lags, dtype=np.float64)
        a, fc, phi = self.alpha, self.center_frequency, math.radians(self.phase)
        c = math.cos(2 * phi) * math.exp(-2 * math.pi**2 * fc**2 / a)
        return (
            0.5
            * math.sqrt(math.pi / (2 * a))
            * np.exp(-a * lags**2 / 2)
            * (np.cos(2 * np.pi * fc * lags) + c)
        )

    @property
    def support(self) -> float:
        return math.sqrt(math.log(1.0 / SUPPORT_LEVEL) / self.alpha)

    @property
    def highest_frequency(self) -> float:
        """[Hz] f_c + √(α ln 1000)/π: the −60 dB point of the positive-frequency lobe."""
        return (
            self.center_frequency
            + math.sqrt(self.alpha * math.log(1.0 / HIGHEST_FREQUENCY_LEVEL)) / math.pi
        )

    @property
    def _scan_limit(self) -> float:
        return self.center_frequency + 2.0 * math.sqrt(self.alpha * 20.0) / math.pi

    @property
    def duration(self) -> float:
        """[s] −20 dB width of the Gaussian envelope: 2√(ln 10 / α)."""
        return 2.0 * math.sqrt(math.log(1.0 / DURATION_LEVEL) / self.alpha)


# ---------------------------------------------------------------------------------------
def _cosine_window(coefs: tuple[float, ...]) -> Callable[[_F64, float], _F64]:
    def window(z: _F64, _param: float) -> _F64:
        x = np.pi * (z + 1.0)  # 2π·n/(N−1) for z ∈ [−1, 1]
        return sum(((-1) ** k) * c * np.cos(k * x) for k, c in enumerate(coefs))

    return window


_WINDOWS: dict[str, Callable[[_F64, float], _F64]] = {
    "boxcar": lambda z, _p: np.ones_like(z),
    "hann": _cosine_window((0.5, 0.5)),
    "hamming": _cosine_window((0.54, 0.46)),
    "blackman": _cosine_window((0.42, 0.5, 0.08)),
    "blackmanharris": _cosine_window((0.35875, 0.48829, 0.14128, 0.01168)),
    "nuttall": _cosine_window((0.3635819, 0.4891775, 0.1365995, 0.0106411)),
    "bartlett": lambda z, _p: 1.0 - np.abs(z),
    "kaiser": lambda z, beta: np.i0(beta * np.sqrt(np.clip(1.0 - z * z, 0.0, None))) / np.i0(beta),
}
WINDOW_NAMES = tuple(sorted(_WINDOWS))
"""Truncation windows of :class:`SincPulse`, continuous versions of the scipy.signal.get_window
windows of the same name (symmetric, ``fftbins=False``)."""


@dataclass(frozen=True, kw_only=True)
class SincPulse(Pulse):
    """Windowed sinc pulse (thesis eqs. 29–31): w(t) = sinc(2Bt)·win(t/T)·cos(2πf_c t + φ).

    The baseband sinc is the impulse response of the ideal low-pass P(f) = A'·rect(f/2B)
    (eq. 29) with A' = 1/(2B), so that the pulse peaks at 1 like the others (sinc(x) =
    sin(πx)/(πx)); modulated, its passband is f_c ± B with |W| ≈ 1/(4B) there.  It is
    truncated to |t| ≤ T by the named window.

    Attributes
    ----------
    center_frequency : [Hz] carrier f_c.
    bandwidth : [Hz] B, the one-sided baseband bandwidth of eq. (29) (passband f_c ± B).
    window : truncation window, one of :data:`WINDOW_NAMES` (``kaiser`` uses ``kaiser_beta``).
    lobes : number of sinc zero crossings kept on each side: T = lobes / (2B).
    length : [s] full truncated length 2T; overrides ``lobes`` when given.
    phase : [deg] carrier phase φ, within ±360°.
    kaiser_beta : shape parameter β of the ``kaiser`` window.
    """

    center_frequency: float = DEFAULT_CENTER_FREQUENCY
    bandwidth: float = 1.5e6
    window: str = "hann"
    lobes: int = 4
    length: float | None = None
    phase: float = 0.0
    kaiser_beta: float = 8.6
    name: ClassVar[str] = "sinc"

    def __post_init__(self) -> None:
        fc = _center_frequency(self.center_frequency)
        b = positive_float("bandwidth", self.bandwidth)
        object.__setattr__(self, "center_frequency", fc)
        object.__setattr__(self, "bandwidth", b)
        lookup("window", self.window, _WINDOWS)
        object.__setattr__(self, "lobes", positive_int("lobes", self.lobes))
        if self.length is not None:
            object.__setattr__(self, "length", positive_float("length", self.length))
        object.__setattr__(self, "phase", in_range("phase", self.phase, -360.0, 360.0))
        object.__setattr__(self, "kaiser_beta", finite_float("kaiser_beta", self.kaiser_beta))
        if b > fc:
            warnings.warn(
                f"bandwidth B = {b:g} Hz exceeds center_frequency = {fc:g} Hz: the passband "
                "reaches negative frequencies",
                stacklevel=3,
            )
        cycles = 2.0 * self.half_length * (fc + b)
        if cycles > MAX_PULSE_CYCLES:
            if self.length is not None:
                raise EchocalValueError(
                    f"length: {self.length:g} s makes the sinc pulse {cycles:.3g} carrier cycles "
                    f"long (2T·(f_c + B)); at most {MAX_PULSE_CYCLES} can be computed — give a "
                    "shorter length (it is in seconds)"
                )
            if 4 * (fc + b) / b <= MAX_PULSE_CYCLES:
                raise EchocalValueError(  # B is fine with the default 4 lobes: too many lobes
                    f"lobes: {self.lobes} lobes make the sinc pulse {cycles:.3g} carrier cycles "
                    f"long (T = lobes / 2B = {self.half_length:.3g} s); at most "
                    f"{MAX_PULSE_CYCLES} can be computed — use fewer lobes"
                )
            raise EchocalValueError(
                f"bandwidth: B = {format_frequency(b)} makes the sinc pulse {cycles:.3g} carrier "
                f"cycles long (T = lobes / 2B = {self.half_length:.3g} s); at most "
                f"{MAX_PULSE_CYCLES} can be computed — B is the one-sided bandwidth in Hz "
                f"(e.g. {format_frequency(0.3 * fc)} = 30 % of f_c), not a percentage"
            )

    @property
    def half_length(self) -> float:
        """[s] truncation half-length T."""
        return self.length / 2.0 if self.length is not None else self.lobes / (2 * self.bandwidth)

    def waveform(self, t: ArrayLike) -> _F64:
        t = np.asarray(t, dtype=np.float64)
        big_t, b = self.half_length, self.bandwidth
        z = t / big_t
        inside = np.abs(z) <= 1.0
        zc = np.where(inside, z, 0.0)
        win = _WINDOWS[self.window](zc, self.kaiser_beta)
        carrier = np.cos(2 * np.pi * self.center_frequency * t + math.radians(self.phase))
        return np.where(inside, np.sinc(2 * b * t) * win * carrier, 0.0)

    @property
    def support(self) -> float:
        return self.half_length

    @property
    def _scan_limit(self) -> float:
        return max(
            4.0 * (self.center_frequency + self.bandwidth),
            self.center_frequency + self.bandwidth + 40.0 / self.half_length,
        )


# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class RickerPulse(Pulse):
    """Ricker wavelet (thesis eq. 32): w(t) = (1 − 2π²f_c²t²)·exp(−π²f_c²t²).

    Its spectrum is W(f) = 2f²/(√π f_c³)·exp(−f²/f_c²), so |W| peaks at f_c (the thesis's
    eq. 33 is garbled; this is the correct closed form).

    Attributes
    ----------
    center_frequency : [Hz] peak frequency f_c.
    """

    center_frequency: float = DEFAULT_CENTER_FREQUENCY
    name: ClassVar[str] = "ricker"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center_frequency", _center_frequency(self.center_frequency))

    def waveform(self, t: ArrayLike) -> _F64:
        u = (np.pi * self.center_frequency * np.asarray(t, dtype=np.float64)) ** 2
        return (1.0 - 2.0 * u) * np.exp(-u)

    def spectrum(self, f: ArrayLike) -> NDArray[np.complex128]:
        """W(f) = 2f²/(√π f_c³)·exp(−f²/f_c²) (real, closed form)."""
        f = np.asarray(f, dtype=np.float64)
        fc = self.center_frequency
        return (2.0 * f**2 / (math.sqrt(math.pi) * fc**3) * np.exp(-((f / fc) ** 2))).astype(
            np.complex128
        )

    @property
    def support(self) -> float:
        # |w| = (2u − 1)e^{−u} with u = (π f_c t)²; solve (2u − 1)e^{−u} = 1e-7 for u > 1.5.
        from scipy import optimize  # lazy: costs a CLI start 0.3 CPU-s

        u = optimize.brentq(lambda u: (2 * u - 1) * math.exp(-u) - SUPPORT_LEVEL, 1.5, 60.0)
        return math.sqrt(u) / (math.pi * self.center_frequency)

    @property
    def highest_frequency(self) -> float:
        """[Hz] where (f/f_c)²·exp(1 − f²/f_c²) = 1e-3 above f_c."""
        from scipy import optimize  # lazy: costs a CLI start 0.3 CPU-s

        r = optimize.brentq(
            lambda r: r * r * math.exp(1 - r * r) - HIGHEST_FREQUENCY_LEVEL, 1.0, 10.0
        )
        return r * self.center_frequency

    @property
    def _scan_limit(self) -> float:
        return 6.0 * self.center_frequency
