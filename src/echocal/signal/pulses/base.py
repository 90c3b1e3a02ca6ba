"""The :class:`Pulse` interface and the numerical facts every pulse derives from its
waveform and spectrum (see :mod:`echocal.signal.pulses`)."""

from __future__ import annotations

import math
import warnings
from abc import ABC, abstractmethod
from dataclasses import fields
from functools import cached_property
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from echocal._validate import positive_float
from echocal.signal.analytic import analytic_signal
from echocal.units import ULTRASONIC_RANGE, format_frequency

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
