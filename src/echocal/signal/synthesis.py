"""A-scan synthesis (thesis eq. 28): x(t) = Σₙ aₙ w(t − τₙ), sampled in a recording window.

Two implementations of the same sum:

``direct``
    eq. (28) evaluated literally, O(rays × samples), chunked to bound memory: the reference.
``fast`` (default)
    a type-1 non-uniform FFT.  Each impulse aₙ δ(t − τₙ) is spread onto a uniform grid
    (spacing 1/(σ·fs), σ ∈ {1, 2}) with a compact "exponential of semicircle" kernel
    φ(z) = exp(β(√(1 − z²) − 1)) of ``width`` points; one real FFT turns the grid into
    φ̂(f)·Σₙ aₙ exp(−i2πfτₙ); dividing by the kernel's transform φ̂ and multiplying by the
    pulse spectrum W(f) gives the A-scan's spectrum, and one inverse FFT gives the samples.
    Cost O(rays·width + samples·log samples).  The pulse's spectrum above its
    ``highest_frequency`` f_hi is negligible, so the spreading grid is effectively
    oversampled by σ_F = σ·fs / (2 f_hi) and the kernel error is ≈ exp(−π·width·√(1 − 1/σ_F))
    (Barnett et al., FINUFFT, SIAM J. Sci. Comput. 41 (2019)); width is chosen for 1e-7.

Echoes outside the window are absent, never wrapped around: rays with τ farther than the
pulse support from the window are dropped and the FFT grid is padded by the support on both
sides, so the periodic FFT cannot fold one end of the window onto the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np
import scipy.fft
from numpy.typing import ArrayLike, NDArray

from echocal._validate import one_of
from echocal.errors import EchocalValueError
from echocal.signal.pulses import Pulse
from echocal.signal.window import RecordingWindow, check_echoes, check_window

__all__ = ["SYNTHESIS_METHODS", "synthesize"]

SYNTHESIS_METHODS = ("direct", "fast")
"""Names accepted by ``synthesize(method=...)``."""

Normalize = Literal["rays", "peak"] | None

_KERNEL_TOL = 1e-7
_DIRECT_CHUNK = 1 << 21  # elements of the (rays × samples) block evaluated at once


def synthesize(
    amplitudes: ArrayLike,
    tofs: ArrayLike,
    pulse: Pulse,
    window: RecordingWindow,
    *,
    method: str = "fast",
    normalize: Normalize = "rays",
) -> NDArray[np.float64]:
    """Sample the A-scan x(t) = Σₙ aₙ w(t − τₙ) (thesis eq. 28) in ``window``.

    Parameters
    ----------
    amplitudes : [a.u.] ray amplitudes aₙ·βₙ, shape ``(..., n_rays)`` (any batch axes,
        e.g. ``(n_poses, n_rays)``); finite.
    tofs : [s] times of flight τₙ, broadcastable to ``amplitudes``; ``inf`` marks a miss.
    pulse : the transmitted pulse w(t).
    window : sampling frequency, start delay and length of the recording.
    method : ``"fast"`` (NUFFT, default) or ``"direct"`` (literal eq. 28, the reference).
    normalize : ``"rays"`` divides by n_rays, the full ray count including misses (thesis
        §3.1); ``"peak"`` scales each A-scan to unit peak |x|; ``None`` leaves it as is.

    Returns
    -------
    samples : [a.u.] shape ``(..., n_samples)``.

    Raises
    ------
    EchocalValueError
        NaN/inf ``amplitudes``, NaN ``tofs``, ``fs`` too low for the pulse (aliasing), or a
        window that cannot contain any echo of the rays that hit.
    """
    one_of("method", method, SYNTHESIS_METHODS)
    if normalize not in ("rays", "peak", None):
        raise EchocalValueError(f"normalize must be 'rays', 'peak' or None; got {normalize!r}")
    amps, taus = _validated_rays(amplitudes, tofs)
    check_window(window, pulse)
    batch_shape, n_rays = amps.shape[:-1], amps.shape[-1]
    check_echoes(window, pulse, np.where(amps != 0.0, taus, np.inf))
    a2 = amps.reshape(-1, n_rays)
    t2 = taus.reshape(-1, n_rays)
    if n_rays == 0:
        out = np.zeros((a2.shape[0], window.n_samples))
    elif method == "direct":
        out = _direct(a2, t2, pulse, window)
    else:
        out = _fast(a2, t2, pulse, window)
    if normalize == "rays" and n_rays:
        out /= n_rays
    elif normalize == "peak":
        peak = np.max(np.abs(out), axis=-1, keepdims=True)
        out /= np.where(peak > 0.0, peak, 1.0)
    return out.reshape((*batch_shape, window.n_samples))


def _validated_rays(
    amplitudes: ArrayLike, tofs: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    try:
        amps = np.asarray(amplitudes, dtype=np.float64)
        taus = np.asarray(tofs, dtype=np.float64)
    except (TypeError, ValueError):
        raise EchocalValueError("amplitudes and tofs must be numeric arrays") from None
    if not np.all(np.isfinite(amps)):
        raise EchocalValueError("amplitudes must be finite everywhere; got NaN or inf")
    if np.any(np.isnan(taus)) or np.any(taus == -np.inf):
        raise EchocalValueError("tofs must be finite or +inf (a miss); got NaN or -inf")
    try:
        amps, taus = np.broadcast_arrays(amps, taus)
    except ValueError:
        raise EchocalValueError(
            f"amplitudes shape {amps.shape} and tofs shape {taus.shape} do not broadcast"
        ) from None
    if amps.ndim == 0:
        raise EchocalValueError("amplitudes and tofs must have a ray axis (last axis)")
    return amps, taus


def _direct(
    amps: NDArray[np.float64], taus: NDArray[np.float64], pulse: Pulse, window: RecordingWindow
) -> NDArray[np.float64]:
    t = window.times
    out = np.zeros((amps.shape[0], t.size))
    chunk = max(1, _DIRECT_CHUNK // t.size)
    for b in range(amps.shape[0]):
        keep = np.isfinite(taus[b]) & (amps[b] != 0.0)
        a, tau = amps[b, keep], taus[b, keep]
        for i in range(0, a.size, chunk):
            out[b] += a[i : i + chunk] @ pulse.waveform(t[None, :] - tau[i : i + chunk, None])
    return out


# --- fast path -------------------------------------------------------------------------
@dataclass(frozen=True)
class _Plan:
    n_fft: int  # N: output-rate FFT length (window + padding)
    sigma: int  # spreading grid = sigma * N points
    width: int  # kernel width [grid points]
    beta: float  # kernel shape
    pad: int  # samples of padding before the window
    transfer: NDArray[np.complex128]  # fs·W(f_k)/φ̂(ξ_k), k = 0..N/2


def _kernel_parameters(sigma_f: float) -> tuple[int, float]:
    root = math.sqrt(max(1.0 - 1.0 / sigma_f, 1e-3))
    width = math.ceil(math.log(1.0 / _KERNEL_TOL) / (math.pi * root))
    width = min(max(width, 4), 16)
    beta = 0.97 * math.pi * width * (1.0 - 0.5 / sigma_f)
    return width, beta


def _kernel_transform(xi: NDArray[np.float64], width: int, beta: float) -> NDArray[np.float64]:
    """φ̂(ξ) = (w/2)∫₋₁¹ exp(β(√(1−z²)−1)) cos(πξwz) dz, ξ in cycles per grid point."""
    z, wq = np.polynomial.legendre.leggauss(4 * width + 40)
    phi = np.exp(beta * (np.sqrt(1.0 - z * z) - 1.0)) * wq
    return 0.5 * width * (np.cos(np.pi * width * np.outer(xi, z)) @ phi)


@lru_cache(maxsize=32)
def _plan(pulse: Pulse, fs: float, n_samples: int) -> _Plan:
    ratio = fs / (2.0 * pulse.highest_frequency)
    sigma = 1 if ratio >= 2.0 else 2
    width, beta = _kernel_parameters(sigma * ratio)
    pad = math.ceil(pulse.support * fs) + width + 1
    n_fft = scipy.fft.next_fast_len(n_samples + 2 * pad, real=True)
    if sigma * n_fft % 2:  # keep the spreading grid even so its rfft holds bin N/2
        n_fft = scipy.fft.next_fast_len(n_fft + 1, real=True)
    k = np.arange(n_fft // 2 + 1)
    f = k * fs / n_fft
    phihat = _kernel_transform(k / (sigma * n_fft), width, beta)
    transfer = fs * math.exp(-beta) * pulse.spectrum(f) / phihat
    transfer.setflags(write=False)
    return _Plan(n_fft, sigma, width, beta, pad, transfer)


def _fast(
    amps: NDArray[np.float64], taus: NDArray[np.float64], pulse: Pulse, window: RecordingWindow
) -> NDArray[np.float64]:
    plan = _plan(pulse, window.fs, window.n_samples)
    n_batch = amps.shape[0]
    n_grid = plan.sigma * plan.n_fft
    t0 = window.start - plan.pad / window.fs  # time of grid point 0
    s = pulse.support
    with np.errstate(invalid="ignore"):
        keep = (taus > window.start - s) & (taus < window.end + s) & (amps != 0.0)
    a = np.where(keep, amps, 0.0)
    # grid position of each impulse; the padding keeps every kernel point inside the grid
    u = np.where(keep, taus - t0, plan.pad / window.fs) * (plan.sigma * window.fs)
    half = 0.5 * plan.width
    j0 = np.ceil(u - half)
    z = ((j0 - u) * (1.0 / half))[..., None] + np.arange(plan.width) * (1.0 / half)
    z *= z
    np.subtract(1.0, z, out=z)
    np.maximum(z, 0.0, out=z)
    np.sqrt(z, out=z)
    z *= plan.beta
    np.exp(z, out=z)  # φ·e^β; e^−β is folded into the transfer function
    z *= a[..., None]
    first = j0.astype(np.int64)
    if n_batch > 1:
        first += (np.arange(n_batch) * n_grid)[:, None]
    idx = first[..., None] + np.arange(plan.width)
    grid = np.bincount(idx.ravel(), z.ravel(), minlength=n_batch * n_grid)
    spec = scipy.fft.rfft(grid.reshape(n_batch, n_grid), axis=-1)[:, : plan.n_fft // 2 + 1]
    spec *= plan.transfer
    x = scipy.fft.irfft(spec, n=plan.n_fft, axis=-1)
    return x[:, plan.pad : plan.pad + window.n_samples]
