"""A-scan processing: matched filter, envelope, gates, time of flight and energy metrics.

All functions take samples of shape ``(..., n_samples)`` (batch axes first, time last) and
return one value per A-scan, shape ``(...,)``, unless they return signals.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from types import MappingProxyType

import numpy as np
import scipy.fft
from numpy.typing import ArrayLike, NDArray

from echocal._numba import compiled
from echocal._validate import finite_array, finite_float, lookup, nonnegative_float
from echocal.constants import SOUND_SPEED_WATER
from echocal.errors import EchocalValueError
from echocal.signal.analytic import analytic_signal
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow

__all__ = [
    "METRICS",
    "Gate",
    "distance",
    "energy_db",
    "envelope",
    "get_metric",
    "matched_envelope",
    "matched_filter",
    "metric_names",
    "peak_amplitude",
    "pseudo_energy",
    "pseudo_energy_with_peak",
    "register_metric",
    "time_of_flight",
]

_F64 = NDArray[np.float64]
Metric = Callable[..., _F64]
"""``metric(samples, window, pulse)`` -> shape ``(...,)``; pseudo-energy also takes an
optional window length [s] as a fourth argument."""


def _samples(samples: ArrayLike, window: RecordingWindow | None = None) -> _F64:
    x = finite_array("samples", samples)
    if x.ndim == 0:
        raise EchocalValueError("samples must have a time axis (last axis)")
    if window is not None and x.shape[-1] != window.n_samples:
        raise EchocalValueError(
            f"samples must have window.n_samples = {window.n_samples} samples on the last "
            f"axis; got shape {x.shape}"
        )
    return x


@lru_cache(maxsize=32)
def _matched_transfer(pulse: Pulse, fs: float, n: int) -> tuple[int, NDArray[np.complex128]]:
    """(FFT length, conj(DFT of the template w(j/fs), j = −J..J) / fs) for length-n A-scans."""
    half = math.ceil(pulse.support * fs)
    n_fft = scipy.fft.next_fast_len(n + half + 1, real=True)
    j = np.arange(-half, half + 1)
    placed = np.zeros(n_fft)
    placed[j % n_fft] = pulse.waveform(j / fs)
    transfer = np.conj(scipy.fft.rfft(placed)) / fs
    transfer.setflags(write=False)
    return n_fft, transfer


@lru_cache(maxsize=32)
def _analytic_transfer(pulse: Pulse, fs: float, n: int) -> tuple[int, NDArray[np.complex128]]:
    """(FFT length, matched-filter transfer × the one-sided analytic-signal weights).

    The weights are 1 at f = 0 (and at N/2 for even N) and 2 at positive frequencies, so
    ifft(rfft(x)·H, n=N) is the analytic signal of the matched filter's output.
    """
    n_fft, transfer = _matched_transfer(pulse, fs, n)
    weights = np.full(transfer.size, 2.0)
    weights[0] = 1.0
    if n_fft % 2 == 0:
        weights[-1] = 1.0
    out = transfer * weights
    out.setflags(write=False)
    return n_fft, out


def _matched_spectrum(x: _F64, pulse: Pulse, fs: float) -> tuple[int, NDArray[np.complex128]]:
    n_fft, transfer = _matched_transfer(pulse, float(fs), x.shape[-1])
    return n_fft, scipy.fft.rfft(x, n=n_fft, axis=-1) * transfer


def _analytic(x: _F64, pulse: Pulse, fs: float) -> NDArray[np.complex128]:
    """Analytic signal of the matched filter's output, shape ``(..., n_fft)`` (first
    ``n_samples`` are the A-scan's): one real FFT and one inverse complex FFT."""
    n_fft, transfer = _analytic_transfer(pulse, float(fs), x.shape[-1])
    spec = scipy.fft.rfft(x, n=n_fft, axis=-1)
    spec *= transfer
    return scipy.fft.ifft(spec, n=n_fft, axis=-1, overwrite_x=True)


def matched_filter(samples: ArrayLike, pulse: Pulse, fs: float) -> _F64:
    """Correlate each A-scan with the transmitted pulse w sampled at ``fs`` [Hz].

    y[m] = Σⱼ x[m + j]·w(j/fs) / fs ≈ ∫ x(t)·w(t − t_m) dt, same length as ``samples``,
    so a single echo w(t − τ) peaks at sample m = (τ − start)·fs.  Computed by FFT with
    zero padding (linear, not circular, correlation).

    Returns
    -------
    [a.u.²·s] shape ``(..., n_samples)``.
    """
    x = _samples(samples)
    n_fft, spec = _matched_spectrum(x, pulse, fs)
    return scipy.fft.irfft(spec, n=n_fft, axis=-1)[..., : x.shape[-1]]


def matched_envelope(samples: ArrayLike, pulse: Pulse, fs: float) -> _F64:
    """Envelope |analytic signal| of :func:`matched_filter`'s output, shape of ``samples``.

    One FFT pair: the analytic signal is formed directly from the correlation's spectrum.
    """
    x = _samples(samples)
    return np.abs(_analytic(x, pulse, fs)[..., : x.shape[-1]])


def envelope(samples: ArrayLike) -> _F64:
    """Analytic-signal envelope |x + i·H{x}|, shape of ``samples``."""
    return np.abs(analytic_signal(_samples(samples)))


def _peak_position(env: _F64) -> _F64:
    """Sub-sample index of the maximum of ``env`` along the last axis, shape ``(...,)``.

    Gaussian (log-parabolic) interpolation through the peak and its two neighbours: exact
    for a Gaussian envelope (the Gabor pulse's matched-filter output), plain parabolic
    where a neighbour is zero.  NaN where ``env`` is zero everywhere.
    """
    n = env.shape[-1]
    k = np.argmax(env, axis=-1)
    km, kp = np.clip(k - 1, 0, n - 1), np.clip(k + 1, 0, n - 1)
    e0 = np.take_along_axis(env, k[..., None], -1)[..., 0]
    em = np.take_along_axis(env, km[..., None], -1)[..., 0]
    ep = np.take_along_axis(env, kp[..., None], -1)[..., 0]
    interior = (k > 0) & (k < n - 1) & (e0 > 0)
    positive = interior & (em > 0) & (ep > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        lm, l0, lp = np.log(em), np.log(e0), np.log(ep)
        den_log = lm - 2 * l0 + lp
        d_log = np.where(den_log < 0, 0.5 * (lm - lp) / den_log, 0.0)
        den = em - 2 * e0 + ep
        d_par = np.where(den < 0, 0.5 * (em - ep) / den, 0.0)
    delta = np.where(positive, d_log, np.where(interior, d_par, 0.0))
    pos = k + np.clip(delta, -0.5, 0.5)
    return np.where(e0 > 0, pos, np.nan)


@dataclass(frozen=True, kw_only=True)
class Gate:
    """A time gate as on a flaw detector.

    Attributes
    ----------
    start : [s] gate start (same time axis as the recording window).
    width : [s] gate width (> 0).
    threshold : crossing level; a fraction of full scale (0..1) unless ``absolute``.
    absolute : if True, ``threshold`` is an amplitude [a.u.] instead of a fraction.
    """

    start: float
    width: float
    threshold: float = 0.0
    absolute: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", finite_float("gate.start", self.start))
        w = finite_float("gate.width", self.width)
        if w <= 0:
            raise EchocalValueError(f"gate.width must be > 0; got {w:g}")
        object.__setattr__(self, "width", w)
        thr = nonnegative_float("gate.threshold", self.threshold)
        if not self.absolute and thr > 1.0:
            raise EchocalValueError(
                f"gate.threshold is a fraction of full scale and must lie in [0, 1]; got {thr:g}"
                " (set absolute=True for an amplitude)"
            )
        object.__setattr__(self, "threshold", thr)

    @property
    def end(self) -> float:
        """[s] gate end."""
        return self.start + self.width

    def mask(self, window: RecordingWindow) -> NDArray[np.bool_]:
        """Which samples of ``window`` lie inside the gate, shape ``(n_samples,)``."""
        t = window.times
        return (t >= self.start) & (t <= self.end)

    def level(self, samples: _F64, full_scale: float | None = None) -> _F64:
        """Threshold amplitude, shape ``(...,)``: absolute, or fraction × full scale
        (``full_scale`` [a.u.] if given, else each A-scan's own peak |x|)."""
        if self.absolute:
            return np.full(samples.shape[:-1], self.threshold)
        ref = (
            np.max(np.abs(samples), axis=-1)
            if full_scale is None
            else np.full(samples.shape[:-1], float(full_scale))
        )
        return self.threshold * ref

    def first_crossing(
        self,
        samples: ArrayLike,
        window: RecordingWindow,
        *,
        full_scale: float | None = None,
        floor: ArrayLike | None = None,
    ) -> _F64:
        """[s] first time inside the gate where |x| reaches the threshold (linearly
        interpolated between samples), shape ``(...,)``; NaN where it never does.
        ``floor`` [a.u.], shape ``(...,)`` or scalar: the least level that counts (e.g.
        above the noise), when the threshold lies below it."""
        x = np.abs(_samples(samples, window))
        level = self.level(x, full_scale)
        if floor is not None:
            level = np.maximum(level, np.asarray(floor, dtype=np.float64))
        level = level[..., None]
        above = (x >= level) & self.mask(window) & (x > 0)
        hit = np.any(above, axis=-1)
        k = np.argmax(above, axis=-1)
        km = np.maximum(k - 1, 0)
        xk = np.take_along_axis(x, k[..., None], -1)[..., 0]
        xm = np.take_along_axis(x, km[..., None], -1)[..., 0]
        lv = level[..., 0]
        inside_prev = self.mask(window)[km]
        with np.errstate(divide="ignore", invalid="ignore"):
            frac = np.where((k > 0) & inside_prev & (xk > xm), (lv - xm) / (xk - xm), 1.0)
        t = window.start + (k - 1 + np.clip(frac, 0.0, 1.0)) / window.fs
        t = np.where((k > 0) & inside_prev, t, window.start + k / window.fs)
        return np.where(hit, t, np.nan)

    def peak(self, samples: ArrayLike, window: RecordingWindow) -> tuple[_F64, _F64]:
        """(time [s], |x| [a.u.]) of the largest |x| inside the gate, each shape ``(...,)``."""
        x = np.abs(_samples(samples, window))
        m = self.mask(window)
        if not np.any(m):
            raise EchocalValueError(
                f"gate [{self.start:.6g} s, {self.end:.6g} s] holds no sample of the window "
                f"[{window.start:.6g} s, {window.end:.6g} s]"
            )
        xm = np.where(m, x, -np.inf)
        k = np.argmax(xm, axis=-1)
        return window.start + k / window.fs, np.take_along_axis(x, k[..., None], -1)[..., 0]


def time_of_flight(
    samples: ArrayLike, window: RecordingWindow, pulse: Pulse, *, gate: Gate | None = None
) -> _F64:
    """[s] time of flight of the strongest echo, shape ``(...,)``; NaN for an all-zero A-scan.

    The peak of the matched-filter envelope (inside ``gate`` if given), refined to a
    fraction of a sample by Gaussian interpolation.
    """
    x = _samples(samples, window)
    env = matched_envelope(x, pulse, window.fs)
    if gate is not None:
        env = np.where(gate.mask(window), env, 0.0)
    return window.start + _peak_position(env) / window.fs


def distance(tof: ArrayLike, c0: float = SOUND_SPEED_WATER) -> _F64:
    """[m] one-way distance c₀·τ/2 for a pulse-echo time of flight ``tof`` [s]."""
    return np.asarray(tof, dtype=np.float64) * float(c0) / 2.0


_ENERGY_CHUNK = 1 << 15  # samples of A-scans processed at once (temporaries stay in cache)


def _energy_window(
    samples: ArrayLike, window: RecordingWindow, pulse: Pulse, window_length: float | None
) -> tuple[_F64, NDArray[np.int64], _F64]:
    """(Σx² in the window centred on the matched-filter peak, number of samples summed,
    the matched-filter envelope's peak [a.u.]) — one matched filter for all three."""
    x = _samples(samples, window)
    length = 2.0 * pulse.duration if window_length is None else window_length
    length = finite_float("window_length", length)
    if length <= 0:
        raise EchocalValueError(f"window_length must be > 0; got {length:g}")
    half = round(0.5 * length * window.fs)
    n = x.shape[-1]
    batch = x.shape[:-1]
    rows = x.reshape(-1, n)
    energy = np.empty(rows.shape[0])
    count = np.empty(rows.shape[0], dtype=np.int64)
    peak = np.empty(rows.shape[0])
    step = max(1, _ENERGY_CHUNK // n)
    for lo in range(0, rows.shape[0], step):
        sl = slice(lo, lo + step)
        energy[sl], count[sl], peak[sl] = _window_sums(rows[sl], pulse, window.fs, half)
    return energy.reshape(batch), count.reshape(batch), peak.reshape(batch)


def _window_sums(
    x: _F64, pulse: Pulse, fs: float, half: int
) -> tuple[_F64, NDArray[np.int64], _F64]:
    """Σx² over [peak − half, peak + half] of rows ``x`` (n_rows, n), the counts, and the
    matched-filter envelope's peak value of each row."""
    n = x.shape[-1]
    z = _analytic(x, pulse, fs)
    energy = np.empty(x.shape[0])
    count = np.empty(x.shape[0], dtype=np.int64)
    peak_power = np.empty(x.shape[0])
    kernel = compiled(_peak_window_loops)
    if kernel is not None:
        kernel(z, x, half, energy, count, peak_power)
        return energy, count, np.sqrt(peak_power)
    z = z[:, :n]
    power = z.real * z.real
    power += z.imag * z.imag  # |z|²: the same peak as the envelope |z|
    centre = np.argmax(power, axis=-1)
    peak_power = np.take_along_axis(power, centre[:, None], axis=-1)[:, 0]
    lo = np.clip(centre - half, 0, n)
    hi = np.clip(centre + half + 1, 0, n)
    for i, (a, b) in enumerate(zip(lo.tolist(), hi.tolist(), strict=True)):
        seg = x[i, a:b]
        energy[i] = seg @ seg  # a few dozen samples: cheaper per row than any gather
    return energy, hi - lo, np.sqrt(peak_power)


def _peak_window_loops(z, x, half, energy, count, peak_power):
    """Compiled :func:`_window_sums` after the FFTs: per row, the first maximum of |z|² over
    the ``n`` samples of ``x`` (n_rows, n) (kept in ``peak_power``), then Σx² over
    [peak − half, peak + half]."""
    n = x.shape[1]
    for i in range(x.shape[0]):
        best = -1.0
        centre = 0
        for m in range(n):
            w = z[i, m]
            pw = w.real * w.real + w.imag * w.imag
            if pw > best:
                best = pw
                centre = m
        lo = min(max(centre - half, 0), n)
        hi = min(max(centre + half + 1, 0), n)
        acc = 0.0
        for m in range(lo, hi):
            acc += x[i, m] * x[i, m]
        energy[i] = acc
        count[i] = hi - lo
        peak_power[i] = best


def pseudo_energy(
    samples: ArrayLike,
    window: RecordingWindow,
    pulse: Pulse,
    window_length: float | None = None,
) -> _F64:
    """Pseudo-energy E = Σ x[k]² (thesis eq. 79) over an energy window, shape ``(...,)``.

    The energy window is centred on the peak of the matched-filter envelope (thesis
    §12.2.1.1) and spans ``window_length`` [s]; default 2 × ``pulse.duration`` (the −20 dB
    envelope width), which holds all but ~1e-8 of a Gabor echo's energy.  The sum is over
    samples (no 1/fs factor), as in eq. 79; it is clipped at the ends of the A-scan.
    """
    return _energy_window(samples, window, pulse, window_length)[0]


def pseudo_energy_with_peak(
    samples: ArrayLike,
    window: RecordingWindow,
    pulse: Pulse,
    window_length: float | None = None,
) -> tuple[_F64, _F64]:
    """:func:`pseudo_energy` and the matched-filter envelope's peak [a.u.] (the value
    :func:`matched_envelope` peaks at), both shape ``(...,)``, from one matched filter."""
    energy, _count, peak = _energy_window(samples, window, pulse, window_length)
    return energy, peak


def peak_amplitude(
    samples: ArrayLike, window: RecordingWindow | None = None, pulse: Pulse | None = None
) -> _F64:
    """[a.u.] peak of the analytic envelope of each A-scan, shape ``(...,)``."""
    x = _samples(samples, window)
    return np.max(envelope(x), axis=-1)


def energy_db(
    samples: ArrayLike,
    window: RecordingWindow,
    pulse: Pulse,
    window_length: float | None = None,
    *,
    reference: float = 1.0,
) -> _F64:
    """[dB] 10·log₁₀(pseudo-energy / ``reference``), shape ``(...,)``; −inf for silence."""
    return energy_to_db(pseudo_energy(samples, window, pulse, window_length), reference)


def energy_to_db(energy: ArrayLike, reference: float = 1.0) -> _F64:
    """[dB] 10·log₁₀(``energy`` / ``reference``), shape of ``energy``; −inf for silence:
    :func:`energy_db` of a pseudo-energy already computed."""
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(np.asarray(energy, dtype=np.float64) / float(reference))


_METRICS: dict[str, Metric] = {}
METRICS = MappingProxyType(_METRICS)
"""Read-only view of the metric registry: name → f(samples, window, pulse) -> (...,)."""


def register_metric(name: str, metric: Metric) -> None:
    """Register ``metric(samples, window, pulse) -> (...,)`` under ``name`` (no duplicates)."""
    if name in _METRICS:
        raise EchocalValueError(f"metric name {name!r} is already registered")
    _METRICS[name] = metric


def metric_names() -> tuple[str, ...]:
    """Registered metric names, sorted."""
    return tuple(sorted(_METRICS))


def get_metric(name: str) -> Metric:
    """The metric registered as ``name``; an unknown name lists the valid ones."""
    return lookup("metric", name, _METRICS)


register_metric("pseudo-energy", pseudo_energy)
register_metric("peak-amplitude", peak_amplitude)
register_metric("energy-db", energy_db)
