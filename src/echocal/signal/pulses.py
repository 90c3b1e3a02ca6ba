"""Transmit pulses (thesis §3.2): Gabor, windowed sinc, Ricker and sampled waveforms.

Every pulse is a frozen, keyword-only dataclass describing the real RF waveform
``w(t)`` that one unit-amplitude ray with time of flight τ = 0 contributes to an
A-scan, so that thesis eq. (28) reads ``x(t) = Σₙ aₙ w(t − τₙ)``.  A pulse gives
its spectrum ``W(f) = ∫ w(t) exp(−i2πft) dt`` (closed form where one exists),
autocorrelation, energy spectral density and the few scalar facts the synthesis
and processing stages need (``support``, ``highest_frequency``, ``duration``).

Registry: :func:`make_pulse` ``(name, **params)`` and :func:`pulse_names`.
"""

from __future__ import annotations

import functools
import inspect
import math
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, fields
from functools import cached_property
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import linalg, optimize

from echocal._validate import finite_array, finite_float, lookup, positive_float, positive_int
from echocal.constants import DEFAULT_CENTER_FREQUENCY
from echocal.errors import DataFileError, EchocalValueError
from echocal.signal.analytic import analytic_signal
from echocal.units import ULTRASONIC_RANGE, format_frequency, parse_quantity

__all__ = [
    "MAX_PULSE_CYCLES",
    "MAX_SAMPLED_PULSE_SAMPLES",
    "SINC_MIN_BANDWIDTH",
    "WINDOW_NAMES",
    "GaborPulse",
    "Pulse",
    "RickerPulse",
    "SampledPulse",
    "SincPulse",
    "make_pulse",
    "parse_bandwidth",
    "plausible_bandwidth",
    "pulse_names",
    "pulse_options",
    "register_pulse",
]

SUPPORT_LEVEL = 1e-7
"""``support`` is the half-width beyond which ``|w| < SUPPORT_LEVEL · max|w|``."""

HIGHEST_FREQUENCY_LEVEL = 1e-3
"""``highest_frequency`` is where ``|W|`` falls below this fraction (−60 dB) of its peak."""

DURATION_LEVEL = 0.1
"""``duration`` is the full width of the envelope above this fraction (−20 dB) of its peak."""

MAX_PULSE_CYCLES = 256
"""Longest pulse whose spectrum is computed numerically (:class:`SincPulse`), in carrier
cycles 2T·(f_c + B).  The work of its spectral scans grows with the square of this number:
256 cycles take about 15 s, the thousands a unit slip gives (B = 60 Hz for 60 kHz) hours."""

MAX_SAMPLED_PULSE_SAMPLES = 4096
"""Most samples a :class:`SampledPulse` may hold: its spectrum is computed numerically at a
cost that grows with the square of the sample count (4096 samples take about 15 s)."""

_LN2 = math.log(2.0)
_F64 = NDArray[np.float64]
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(32)


def _composite_gauss(a: float, b: float, n_nodes: int) -> tuple[_F64, _F64]:
    """Nodes and weights of composite 32-point Gauss–Legendre with >= n_nodes nodes on [a, b]."""
    panels = max(1, math.ceil(n_nodes / 24))
    edges = np.linspace(a, b, panels + 1)
    half = 0.5 * np.diff(edges)
    mid = 0.5 * (edges[:-1] + edges[1:])
    nodes = (mid[:, None] + half[:, None] * _GL_NODES).ravel()
    weights = (half[:, None] * _GL_WEIGHTS).ravel()
    return nodes, weights


def _center_frequency(value: Any) -> float:
    """A centre frequency [Hz] > 0; outside the ultrasonic range it is legal but doubtful."""
    fc = positive_float("center_frequency", value)
    low, high = ULTRASONIC_RANGE
    if not low <= fc <= high:
        warnings.warn(
            f"center_frequency = {format_frequency(fc)} lies outside the ultrasonic range "
            f"({format_frequency(low)} to {format_frequency(high)}); frequencies are in Hz",
            UserWarning,
            stacklevel=4,
        )
    return fc


class Pulse(ABC):
    """Base of every pulse: numerical defaults for what a subclass has no closed form for.

    Subclasses implement :meth:`waveform`, :attr:`support` and :attr:`_scan_limit`
    (a frequency [Hz] above which the spectrum is negligible, used by numerical scans).
    """

    name: ClassVar[str] = "pulse"

    # --- what a subclass must provide -------------------------------------------------
    @abstractmethod
    def waveform(self, t: ArrayLike) -> _F64:
        """RF waveform w(t) [a.u.] at times ``t`` [s] (any shape; same shape out)."""

    @property
    @abstractmethod
    def support(self) -> float:
        """[s] half-width beyond which ``|w(t)| < 1e-7 · max|w|`` (far rays are skipped)."""

    @property
    @abstractmethod
    def _scan_limit(self) -> float:
        """[Hz] frequency above which numerical spectral scans may stop."""

    # --- numerical defaults -------------------------------------------------------------
    def spectrum(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Complex spectrum W(f) = ∫ w(t) exp(−i2πft) dt [a.u.·s] at frequencies ``f`` [Hz].

        Default: Gauss–Legendre quadrature of the waveform over ``[−support, support]``
        (exact up to rounding for waveforms smooth inside their support).
        """
        f = np.asarray(f, dtype=np.float64)
        s = self.support
        f_max = float(np.max(np.abs(f))) if f.size else 0.0
        n_nodes = int(3.0 * 2.0 * s * (f_max + self._scan_limit)) + 96
        t, wq = _composite_gauss(-s, s, n_nodes)
        wt = self.waveform(t) * wq
        flat = f.ravel()
        out = np.empty(flat.shape, dtype=np.complex128)
        chunk = max(1, 2_000_000 // n_nodes)
        for i in range(0, flat.size, chunk):
            phase = np.exp(-2j * np.pi * np.outer(flat[i : i + chunk], t))
            out[i : i + chunk] = phase @ wt
        return out.reshape(f.shape)

    def psd(self, f: ArrayLike) -> _F64:
        """Energy spectral density |W(f)|² [a.u.²·s/Hz] at ``f`` [Hz].

        A pulse is an energy signal, so its "power spectral density" in the sense of
        thesis §3.2 is the energy spectral density; ∫|W|² df is the pulse energy.
        """
        return np.abs(self.spectrum(f)) ** 2

    def autocorrelation(self, lags: ArrayLike) -> _F64:
        """Autocorrelation R(ℓ) = ∫ w(t) w(t + ℓ) dt [a.u.²·s] at lags ``lags`` [s].

        Default: R(ℓ) = 2∫₀^F |W(f)|² cos(2πfℓ) df by the trapezoidal rule on a grid fine
        enough for both the spectrum and the largest lag (spectrally accurate: the
        integrand is even in f and negligible at F).
        """
        lags = np.asarray(lags, dtype=np.float64)
        lag_max = float(np.max(np.abs(lags))) if lags.size else 0.0
        top = self._scan_limit
        n = int(16.0 * top * (2.0 * self.support + lag_max)) + 257
        f = np.linspace(0.0, top, n)
        weights = np.full(n, f[1] - f[0])
        weights[0] *= 0.5
        weights[-1] *= 0.5
        esd = self.psd(f) * weights
        flat = lags.ravel()
        out = np.empty(flat.shape)
        chunk = max(1, 2_000_000 // n)
        for i in range(0, flat.size, chunk):
            out[i : i + chunk] = 2.0 * (np.cos(2 * np.pi * np.outer(flat[i : i + chunk], f)) @ esd)
        return out.reshape(lags.shape)

    @cached_property
    def _spectral_scan(self) -> tuple[_F64, _F64]:
        """(f [Hz], |W(f)|) on a grid over [0, _scan_limit] fine enough for the support."""
        top = self._scan_limit
        n = int(min(max(4096, 8.0 * top * 2.0 * self.support), 200_000))
        f = np.linspace(0.0, top, n)
        return f, np.abs(self.spectrum(f))

    @property
    def highest_frequency(self) -> float:
        """[Hz] frequency above which |W(f)| < −60 dB of its peak (aliasing check)."""
        f, mag = self._spectral_scan
        above = np.nonzero(mag >= HIGHEST_FREQUENCY_LEVEL * mag.max())[0]
        return float(f[min(above[-1] + 1, f.size - 1)])

    @property
    def center_frequency(self) -> float:
        """[Hz] frequency of the peak of |W(f)| (f > 0)."""
        f, mag = self._spectral_scan
        return float(f[int(np.argmax(mag))])

    @property
    def bandwidth_6db(self) -> tuple[float, float]:
        """[Hz] lower and upper frequency where |W| is −6 dB (half) of its peak."""
        f, mag = self._spectral_scan
        half = 0.5 * mag.max()
        above = np.nonzero(mag >= half)[0]
        lo, hi = above[0], above[-1]

        def cross(i: int, j: int) -> float:  # linear interpolation of the −6 dB crossing
            if mag[i] == mag[j]:
                return float(f[i])
            return float(f[i] + (half - mag[i]) * (f[j] - f[i]) / (mag[j] - mag[i]))

        f_lo = cross(lo - 1, lo) if lo > 0 else float(f[0])
        f_hi = cross(hi, hi + 1) if hi + 1 < f.size else float(f[-1])
        return f_lo, f_hi

    @cached_property
    def _envelope_scan(self) -> tuple[_F64, _F64]:
        """(t [s], analytic envelope) of the waveform on a fine grid over ±2·support."""
        s = self.support
        n = 16385
        t = np.linspace(-2.0 * s, 2.0 * s, n)
        return t, np.abs(analytic_signal(self.waveform(t)))

    @property
    def duration(self) -> float:
        """[s] full width of the analytic envelope above −20 dB of its peak.

        Used as the default length of gates and pseudo-energy windows.
        """
        t, env = self._envelope_scan
        above = np.nonzero(env >= DURATION_LEVEL * env.max())[0]
        return float(t[above[-1]] - t[above[0]])

    @property
    def energy(self) -> float:
        """[a.u.²·s] pulse energy ∫ w(t)² dt = R(0)."""
        return float(self.autocorrelation(np.zeros(1))[0])

    def parameters(self) -> dict[str, Any]:
        """The constructor parameters as a plain dict (JSON-friendly for scalar pulses)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}  # type: ignore[arg-type]

    def summary(self) -> dict[str, Any]:
        """Name, parameters and derived facts (SI units) as a JSON-friendly dict."""
        lo, hi = self.bandwidth_6db
        return {
            "pulse": self.name,
            "parameters": {
                k: v for k, v in self.parameters().items() if not isinstance(v, np.ndarray)
            },
            "center_frequency_hz": self.center_frequency,
            "bandwidth_6db_hz": hi - lo,
            "duration_20db_s": self.duration,
            "support_s": self.support,
            "highest_frequency_hz": self.highest_frequency,
            "energy": self.energy,
        }


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
    phase : [deg] carrier phase φ.
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
        object.__setattr__(self, "phase", finite_float("phase", self.phase))

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
    phase : [deg] carrier phase φ.
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
        object.__setattr__(self, "phase", finite_float("phase", self.phase))
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
        u = optimize.brentq(lambda u: (2 * u - 1) * math.exp(-u) - SUPPORT_LEVEL, 1.5, 60.0)
        return math.sqrt(u) / (math.pi * self.center_frequency)

    @property
    def highest_frequency(self) -> float:
        """[Hz] where (f/f_c)²·exp(1 − f²/f_c²) = 1e-3 above f_c."""
        r = optimize.brentq(
            lambda r: r * r * math.exp(1 - r * r) - HIGHEST_FREQUENCY_LEVEL, 1.0, 10.0
        )
        return r * self.center_frequency

    @property
    def _scan_limit(self) -> float:
        return 6.0 * self.center_frequency


# ---------------------------------------------------------------------------------------
_PAD = 16  # zero samples added on each side of a sampled pulse before spline fitting


def _bspline3(u: _F64) -> _F64:
    """Centred cubic B-spline β³(u)."""
    a = np.abs(u)
    return np.where(
        a < 1.0, 2.0 / 3.0 - a * a + 0.5 * a**3, np.where(a < 2.0, (2.0 - a) ** 3 / 6.0, 0.0)
    )


@dataclass(frozen=True, kw_only=True, eq=False)
class SampledPulse(Pulse):
    """A user-supplied pulse sampled at ``fs`` (for example a measured reference echo).

    Between samples the waveform is the cubic B-spline interpolant (zero beyond the padded
    ends), and :meth:`spectrum` is that interpolant's exact Fourier transform
    W(f) = Δt·sinc⁴(fΔt)·Σₖ cₖ exp(−i2πf tₖ), so direct and fast synthesis agree.

    Attributes
    ----------
    samples : shape ``(n_samples,)`` waveform [a.u.]; should taper to zero at both ends.
    fs : [Hz] sampling frequency of ``samples``.
    start_time : [s] time of the first sample relative to the pulse origin (the instant a
        ray's τ refers to).  ``None``: the origin is the peak of the analytic envelope.
    """

    samples: NDArray[np.float64]
    fs: float
    start_time: float | None = None
    name: ClassVar[str] = "sampled"

    def __post_init__(self) -> None:
        w = finite_array("samples", self.samples)
        if w.ndim != 1 or w.size < 4:
            raise EchocalValueError(
                f"samples must be a 1-D array of at least 4 values; got shape {w.shape}"
            )
        if w.size > MAX_SAMPLED_PULSE_SAMPLES:
            raise EchocalValueError(
                f"samples: a sampled pulse holds at most {MAX_SAMPLED_PULSE_SAMPLES} samples; "
                f"got {w.size} — cut the recording to the pulse (its spectrum is computed "
                "numerically, at a cost growing as the square of the length)"
            )
        peak = float(np.max(np.abs(w)))
        if peak == 0.0:
            raise EchocalValueError("samples must not be all zero")
        w = w.copy()
        w.setflags(write=False)
        object.__setattr__(self, "samples", w)
        fs = positive_float("fs", self.fs)
        object.__setattr__(self, "fs", fs)
        if self.start_time is None:
            k = int(np.argmax(np.abs(analytic_signal(w))))
            object.__setattr__(self, "start_time", -k / fs)
        else:
            object.__setattr__(self, "start_time", finite_float("start_time", self.start_time))
        if max(abs(w[0]), abs(w[-1])) > 0.01 * peak:
            warnings.warn(
                "samples do not taper to zero at the ends (> 1 % of the peak); the pulse is "
                "cut off there",
                stacklevel=3,
            )

    @classmethod
    def from_file(
        cls, path: str | Path, *, fs: float | None = None, start_time: float | None = None
    ) -> SampledPulse:
        """Load a pulse from ``.npy`` or ``.csv``/``.txt``.

        One column (or a 1-D array): amplitudes, ``fs`` [Hz] required.  Two columns: time
        [s], amplitude; ``fs`` follows from the (uniform) time step and, unless given,
        ``start_time`` is the first time value.  CSV may have ``#`` comments and one header
        line.
        """
        path = Path(path)
        if not path.is_file():
            raise DataFileError(f"pulse file {str(path)!r} does not exist")
        try:
            if path.suffix.lower() == ".npy":
                data = np.load(path, allow_pickle=False)
            else:
                with warnings.catch_warnings():  # an empty file: refused below, by name
                    warnings.simplefilter("ignore", UserWarning)
                    try:
                        data = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
                    except ValueError:
                        data = np.loadtxt(path, delimiter=",", comments="#", ndmin=2, skiprows=1)
        except (ValueError, OSError, EOFError) as exc:
            raise DataFileError(
                f"pulse file {str(path)!r} is not a numeric .npy or CSV file: {exc}"
            ) from None
        data = np.asarray(data)
        if data.size == 0:
            raise DataFileError(f"pulse file {str(path)!r} holds no samples")
        if not np.issubdtype(data.dtype, np.number):
            raise DataFileError(f"pulse file {str(path)!r} must hold numbers; got {data.dtype}")
        data = data.astype(np.float64)
        if data.ndim == 2 and data.shape[1] == 1:
            data = data[:, 0]
        if data.ndim == 1:
            if fs is None:
                raise EchocalValueError(
                    f"fs is required for {str(path)!r}: it holds amplitudes only (one column)"
                )
            return cls(samples=data, fs=fs, start_time=start_time)
        if data.ndim != 2 or data.shape[1] != 2:
            raise DataFileError(
                f"pulse file {str(path)!r} must have 1 column (amplitude) or 2 columns "
                f"(time [s], amplitude); got shape {data.shape}"
            )
        t, w = data[:, 0], data[:, 1]
        if t.size < 4 or not np.all(np.isfinite(t)):
            raise DataFileError(f"pulse file {str(path)!r}: time column must be finite, >= 4 rows")
        dt = np.diff(t)
        step = float(np.median(dt))
        if step <= 0 or np.max(np.abs(dt - step)) > 1e-3 * step:
            raise DataFileError(
                f"pulse file {str(path)!r}: time column must increase in uniform steps"
            )
        if fs is None:
            fs = 1.0 / step
        return cls(samples=w, fs=fs, start_time=float(t[0]) if start_time is None else start_time)

    @cached_property
    def _spline(self) -> tuple[_F64, float]:
        """(coefficients, time of coefficient 0 [s]) of the cardinal cubic B-spline."""
        v = np.concatenate([np.zeros(_PAD), self.samples, np.zeros(_PAD)])
        n = v.size
        ab = np.empty((3, n))
        ab[0], ab[1], ab[2] = 1.0, 4.0, 1.0
        c = linalg.solve_banded((1, 1), ab, 6.0 * v)
        start = self.start_time
        assert start is not None  # __post_init__ sets it
        return c, start - _PAD / self.fs

    def waveform(self, t: ArrayLike) -> _F64:
        t = np.asarray(t, dtype=np.float64)
        c, t0 = self._spline
        x = (t - t0) * self.fs
        k0 = np.floor(x).astype(np.int64)
        out = np.zeros(t.shape)
        for j in (-1, 0, 1, 2):
            k = k0 + j
            ok = (k >= 0) & (k < c.size)
            out += np.where(ok, c[np.clip(k, 0, c.size - 1)], 0.0) * _bspline3(x - k)
        return out

    def spectrum(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Exact transform of the spline interpolant (closed form, see the class docstring)."""
        f = np.asarray(f, dtype=np.float64)
        c, t0 = self._spline
        dt = 1.0 / self.fs
        tk = t0 + np.arange(c.size) * dt
        flat = f.ravel()
        out = np.empty(flat.shape, dtype=np.complex128)
        chunk = max(1, 2_000_000 // c.size)
        for i in range(0, flat.size, chunk):
            fi = flat[i : i + chunk]
            out[i : i + chunk] = (np.exp(-2j * np.pi * np.outer(fi, tk)) @ c) * (
                dt * np.sinc(fi * dt) ** 4
            )
        return out.reshape(f.shape)

    @property
    def support(self) -> float:
        c, t0 = self._spline
        first, last = t0 - 2.0 / self.fs, t0 + (c.size + 1) / self.fs
        return max(abs(first), abs(last))

    @property
    def _scan_limit(self) -> float:
        return self.fs / 2.0


# ---------------------------------------------------------------------------------------
def _gabor_factory(
    *,
    center_frequency: float = DEFAULT_CENTER_FREQUENCY,
    bandwidth: float | None = None,
    alpha: float | None = None,
    phase: float = 0.0,
) -> GaborPulse:
    if alpha is not None and bandwidth is not None:
        raise EchocalValueError("give either alpha [1/s²] or bandwidth [%], not both")
    if alpha is not None:
        return GaborPulse.from_alpha(alpha=alpha, center_frequency=center_frequency, phase=phase)
    return GaborPulse(
        center_frequency=center_frequency,
        bandwidth=60.0 if bandwidth is None else bandwidth,
        phase=phase,
    )


def _sampled_factory(
    *,
    samples: ArrayLike | None = None,
    fs: float | None = None,
    file: str | Path | None = None,
    start_time: float | None = None,
) -> SampledPulse:
    if (samples is None) == (file is None):
        raise EchocalValueError("a sampled pulse needs exactly one of samples or file")
    if file is not None:
        return SampledPulse.from_file(file, fs=fs, start_time=start_time)
    if fs is None:
        raise EchocalValueError("fs is required with samples")
    return SampledPulse(samples=np.asarray(samples), fs=fs, start_time=start_time)


_PULSES: dict[str, Callable[..., Pulse]] = {}


def register_pulse(name: str, factory: Callable[..., Pulse]) -> None:
    """Add a pulse factory ``factory(**params) -> Pulse`` under ``name`` (no duplicates)."""
    if name in _PULSES:
        raise EchocalValueError(f"pulse name {name!r} is already registered")
    _PULSES[name] = factory


def pulse_names() -> tuple[str, ...]:
    """Registered pulse names, sorted."""
    return tuple(sorted(_PULSES))


def make_pulse(name: str, **params: Any) -> Pulse:
    """Build the pulse registered as ``name`` with keyword parameters (SI units, degrees).

    Example: ``make_pulse("gabor", center_frequency=5e6, bandwidth=60)``.
    """
    factory = lookup("pulse", name, _PULSES)
    valid = pulse_options(name)
    if valid is not None:
        for key in params:
            if key not in valid:
                raise EchocalValueError(
                    f"{key}: unknown option for {name}; valid: {', '.join(valid)}"
                )
    try:
        return factory(**params)
    except TypeError as exc:
        raise EchocalValueError(f"bad parameters for pulse {name!r}: {exc}") from None


def pulse_options(name: str) -> tuple[str, ...] | None:
    """Keyword options of the pulse registered as ``name``, sorted (None: any keyword).

    ``pulse_options("gabor")`` is ``("alpha", "bandwidth", "center_frequency", "phase")``.
    """
    return _factory_options(lookup("pulse", name, _PULSES))


@functools.cache
def _factory_options(factory: Callable[..., Pulse]) -> tuple[str, ...] | None:
    """:func:`pulse_options` of one factory, inspected once (make_pulse checks every call's
    keywords against it; a re-registered name is a new factory, inspected anew)."""
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):  # a builtin or C callable: cannot tell
        return None
    kinds = (inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in signature.parameters.values()):
        return None
    return tuple(sorted(p.name for p in signature.parameters.values() if p.kind in kinds))


SINC_MIN_BANDWIDTH = 1e3
"""[Hz] the smallest plausible one-sided bandwidth B of a :class:`SincPulse` at the user
boundary (a bare ``60`` meant as 60 % is 60 Hz for sinc)."""


def plausible_bandwidth(
    name: str,
    bandwidth: float,
    center_frequency: float,
    *,
    field: str = "bandwidth",
    bare: bool = False,
    lobes: int = 4,
) -> float:
    """Return ``bandwidth`` (as :func:`parse_bandwidth` gives it) unless it is implausible.

    A sinc B [Hz] below :data:`SINC_MIN_BANDWIDTH` is refused; when the user typed a
    ``bare`` number the message suggests the readings (``'60%'``, ``'60 kHz'``,
    ``'60 MHz'``) that give a computable pulse of B <= f_c [Hz].  Other pulses pass.
    """
    if name != "sinc" or not SINC_MIN_BANDWIDTH > bandwidth > 0:
        return bandwidth
    hints = []
    if bare:
        fc = center_frequency
        for text, b in (
            (f"'{bandwidth:g}%'", bandwidth / 100.0 * fc / 2.0),
            (f"'{bandwidth:g} kHz'", bandwidth * 1e3),
            (f"'{bandwidth:g} MHz'", bandwidth * 1e6),
        ):
            if SINC_MIN_BANDWIDTH <= b <= fc and lobes * (fc + b) / b <= MAX_PULSE_CYCLES:
                hints.append(f"{text} (B = {format_frequency(b)})")
    raise EchocalValueError(
        f"{field}: B = {format_frequency(bandwidth)} is implausible for the sinc pulse (its "
        "bandwidth is the one-sided B in Hz, at least "
        f"{format_frequency(SINC_MIN_BANDWIDTH)}; gabor's is in %)"
        + (f" — did you mean {' or '.join(hints)}?" if hints else "")
    )


def parse_bandwidth(
    name: str, value: Any, center_frequency: float, field: str = "bandwidth"
) -> float:
    """A ``bandwidth`` as typed by a user → the value the pulse ``name`` takes.

    The pulses disagree on units: ``gabor``/``gaussian`` take the fractional −6 dB
    bandwidth in %, ``sinc`` the one-sided baseband bandwidth B in Hz.  So:

    * ``"60%"`` is 60 % for gabor; for sinc the −6 dB passband 2B is 60 % of
      ``center_frequency`` [Hz] (B = 0.3·f_c);
    * a frequency with a unit (``"3 MHz"``) is the full −6 dB width for gabor
      (converted to % of f_c) and B for sinc;
    * a bare number is % for gabor and Hz for sinc.

    Other pulses and non-numbers are returned unchanged (the pulse refuses them by name).
    """
    gabor = name in ("gabor", "gaussian")
    if not (gabor or name == "sinc") or isinstance(value, bool):
        return value
    if isinstance(value, int | float):
        return float(value)
    if not isinstance(value, str):
        return value
    text = value.strip()
    if text.endswith("%"):
        pct = parse_quantity(field, text[:-1], "frequency", "Hz")  # a plain number
        return pct if gabor else pct / 100.0 * center_frequency / 2.0
    if gabor:
        try:
            return float(text)  # bare number: percent
        except ValueError:
            return 100.0 * parse_quantity(field, text, "frequency", "Hz") / center_frequency
    return parse_quantity(field, text, "frequency", "Hz")


register_pulse("gabor", _gabor_factory)
register_pulse("gaussian", _gabor_factory)
register_pulse("sinc", SincPulse)
register_pulse("ricker", RickerPulse)
register_pulse("sampled", _sampled_factory)
