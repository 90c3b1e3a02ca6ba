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
from echocal.signal._kernels import horner_coefficients, kernel_transform, spread
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
    n_batch = math.prod(batch_shape)  # not reshape(-1, 0): ambiguous without rays
    out = _synthesize_2d(
        amps.reshape(n_batch, n_rays),
        taus.reshape(n_batch, n_rays),
        pulse,
        window,
        method,
        normalize,
    )
    return out.reshape((*batch_shape, window.n_samples))


def _synthesize_unchecked(
    amplitudes: NDArray[np.float64],
    tofs: NDArray[np.float64],
    pulse: Pulse,
    window: RecordingWindow,
    *,
    method: str = "fast",
    normalize: Normalize = "rays",
) -> NDArray[np.float64]:
    """:func:`synthesize` for arrays the caller has checked (the simulator's entry point).

    ``amplitudes`` and ``tofs`` must be float64 of the same shape ``(n_batch, n_rays)``,
    amplitudes finite, tofs finite or +inf; ``method`` and ``normalize`` valid.  Nothing
    per ray is validated again.  The window is still checked against the pulse, and a
    window that cannot contain any echo of the rays that hit raises as in
    :func:`synthesize` (the fast path counts those rays while spreading them).

    Returns
    -------
    samples : [a.u.] shape ``(n_batch, n_samples)``.
    """
    check_window(window, pulse)
    if method == "direct":
        check_echoes(window, pulse, np.where(amplitudes != 0.0, tofs, np.inf))
    return _synthesize_2d(amplitudes, tofs, pulse, window, method, normalize, check=True)


def _synthesize_2d(
    amps: NDArray[np.float64],
    taus: NDArray[np.float64],
    pulse: Pulse,
    window: RecordingWindow,
    method: str,
    normalize: Normalize,
    *,
    check: bool = False,
) -> NDArray[np.float64]:
    """Samples ``(n_batch, n_samples)`` of checked rays ``(n_batch, n_rays)``; ``check``
    raises (via :func:`check_echoes`) when rays hit but none lies near the window."""
    n_rays = amps.shape[-1]
    if n_rays == 0:
        return np.zeros((amps.shape[0], window.n_samples))
    if method == "direct":
        out = _direct(amps, taus, pulse, window)
    else:
        out, n_hit, n_keep = _fast(amps, taus, pulse, window)
        if check and n_hit and not n_keep:
            check_echoes(window, pulse, np.where(amps != 0.0, taus, np.inf))
    if normalize == "rays":
        out /= n_rays
    elif normalize == "peak":
        peak = np.max(np.abs(out), axis=-1, keepdims=True)
        out /= np.where(peak > 0.0, peak, 1.0)
    return np.ascontiguousarray(out)


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
    coefs: NDArray[np.float64]  # the kernel's tap polynomials (see _kernels)
    pad: int  # samples of padding before the window
    transfer: NDArray[np.complex128]  # fs·W(f_k)/K̂(ξ_k), k = 0..N/2


def _kernel_parameters(sigma_f: float) -> tuple[int, float]:
    root = math.sqrt(max(1.0 - 1.0 / sigma_f, 1e-3))
    width = math.ceil(math.log(1.0 / _KERNEL_TOL) / (math.pi * root))
    width = min(max(width, 4), 16)
    beta = 0.97 * math.pi * width * (1.0 - 0.5 / sigma_f)
    return width, beta


@lru_cache(maxsize=32)
def _plan(pulse: Pulse, fs: float, n_samples: int) -> _Plan:
    ratio = fs / (2.0 * pulse.highest_frequency)
    sigma = 1 if ratio >= 2.0 else 2
    width, beta = _kernel_parameters(sigma * ratio)
    coefs = horner_coefficients(width, beta, tol=_KERNEL_TOL / 10)
    pad = math.ceil(pulse.support * fs) + width + 1
    n_fft = scipy.fft.next_fast_len(n_samples + 2 * pad, real=True)
    if sigma * n_fft % 2:  # keep the spreading grid even so its rfft holds bin N/2
        n_fft = scipy.fft.next_fast_len(n_fft + 1, real=True)
    k = np.arange(n_fft // 2 + 1)
    f = k * fs / n_fft
    transfer = fs * pulse.spectrum(f) / kernel_transform(k / (sigma * n_fft), coefs)
    transfer.setflags(write=False)
    return _Plan(n_fft, sigma, width, coefs, pad, transfer)


def _fast(
    amps: NDArray[np.float64], taus: NDArray[np.float64], pulse: Pulse, window: RecordingWindow
) -> tuple[NDArray[np.float64], int, int]:
    """(samples (n_batch, n_samples), rays that hit, rays kept inside the window ± support)."""
    plan = _plan(pulse, window.fs, window.n_samples)
    n_grid = plan.sigma * plan.n_fft
    s = pulse.support
    grid = np.zeros((amps.shape[0], n_grid))
    n_hit, n_keep = spread(
        np.ascontiguousarray(amps),
        np.ascontiguousarray(taus),
        t_lo=window.start - s,
        t_hi=window.end + s,
        t0=window.start - plan.pad / window.fs,  # time of grid point 0
        scale=plan.sigma * window.fs,
        coefs=plan.coefs,
        grid=grid,
    )
    spec = scipy.fft.rfft(grid, axis=-1, overwrite_x=True)
    if plan.sigma > 1:
        spec = spec[:, : plan.n_fft // 2 + 1]
    spec *= plan.transfer
    x = scipy.fft.irfft(spec, n=plan.n_fft, axis=-1, overwrite_x=True)
    return x[:, plan.pad : plan.pad + window.n_samples], n_hit, n_keep
