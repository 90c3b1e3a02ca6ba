"""Spreading kernel of the fast A-scan synthesis: numba when available, numpy otherwise.

The NUFFT of :mod:`echocal.signal.synthesis` spreads each impulse aₙ δ(t − τₙ) onto a
uniform grid with a compact kernel of ``width`` taps.  Evaluating the "exponential of
semicircle" exp(β(√(1 − z²) − 1)) at every tap costs a square root and an exponential per
tap; instead each tap's kernel is a polynomial in the impulse's fractional grid offset,
evaluated by Horner's rule (as FINUFFT does).  The polynomials *are* the kernel: its
transform φ̂, which the synthesis divides out, is computed for the piecewise polynomial
itself (:func:`kernel_transform`), so the approximation to the semicircle exponential only
has to be close enough to keep its small Fourier tails (~1e-8 at the defaults).

Both implementations of :func:`spread` add the same products in the same order (ray by
ray, tap by tap), so they agree to the last bit up to the compiler's choice of fused
multiply-adds; :data:`echocal._numba.USE_NUMBA` selects one (tests switch it off to check
the fallback).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.polynomial import chebyshev as _cheb
from numpy.polynomial import polynomial as _poly
from numpy.typing import NDArray

from echocal._numba import compiled

__all__ = ["horner_coefficients", "kernel_transform", "spread"]

NUMBA_MIN_RAYS = 256
"""Below this many rays × poses the numpy kernel is used (no JIT compile for tiny inputs)."""

_F64 = NDArray[np.float64]


def _semicircle_exp(z: _F64, beta: float) -> _F64:
    """φ(z) = exp(β(√(1 − z²) − 1)) on [−1, 1] (peak 1)."""
    return np.exp(beta * (np.sqrt(np.maximum(1.0 - z * z, 0.0)) - 1.0))


def horner_coefficients(width: int, beta: float, tol: float = 1e-9) -> _F64:
    """Polynomial kernel of ``width`` taps, shape ``(degree + 1, width)``, highest power first.

    Tap k of an impulse at fractional grid position u (first tap j₀ = ⌈u − width/2⌉) has
    weight Σ_d c[d, k]·t^(degree−d) with t = 2(j₀ − u + width/2) − 1 ∈ [−1, 1), fitted to
    φ((j₀ + k − u)/(width/2)) by Chebyshev interpolation.  The degree is the lowest that
    brings the interior taps within ``tol`` of φ (the two edge taps cannot do better than
    φ's jump e^−β at |z| = 1, which the semicircle kernel has as well).
    """
    half = 0.5 * width
    t_check = np.linspace(-1.0, 1.0, 1025)
    coefs = np.empty((0, width))
    for degree in range(max(width, 6), width + 16):
        coefs = np.empty((degree + 1, width))
        err = 0.0
        for k in range(width):

            def tap(t: _F64, k: int = k) -> _F64:
                return _semicircle_exp(((t + 1.0) * 0.5 + k) / half - 1.0, beta)

            mono = np.zeros(degree + 1)
            # numpy's stub wants a scalar function; chebinterpolate calls it on an array
            low = _cheb.cheb2poly(_cheb.chebinterpolate(tap, degree))  # type: ignore[arg-type,type-var]
            mono[: low.size] = low
            coefs[:, k] = mono[::-1]
            if 0 < k < width - 1:
                err = max(err, float(np.max(np.abs(_poly.polyval(t_check, mono) - tap(t_check)))))
        if err <= tol:
            break
    coefs.setflags(write=False)
    return coefs


def kernel_transform(xi: _F64, coefs: _F64) -> _F64:
    """Fourier transform K̂(ξ) = ∫ K(x) cos(2πξx) dx of the piecewise-polynomial kernel.

    ``xi`` in cycles per grid point; K(x), x ∈ [−width/2, width/2) the grid offset, is tap
    k's polynomial on [k − width/2, k + 1 − width/2) (even up to round-off).  Gauss-Legendre
    quadrature per tap, exact to round-off for |ξ| ≤ 1/2.
    """
    degree, width = coefs.shape[0] - 1, coefs.shape[1]
    t, wq = np.polynomial.legendre.leggauss(degree // 2 + 24)
    vals = np.zeros((width, t.size))
    for d in range(degree + 1):
        vals = vals * t + coefs[d][:, None]
    x = (0.5 * (t + 1.0))[None, :] + (np.arange(width) - 0.5 * width)[:, None]  # (width, q)
    weights = (0.5 * wq * vals).ravel()
    nodes = 2.0 * math.pi * x.ravel()
    xi = np.asarray(xi, dtype=np.float64)
    flat = xi.ravel()
    out = np.empty(flat.size)
    for lo in range(0, flat.size, _XI_BLOCK):  # (block, width · q) at a time: bounded memory
        out[lo : lo + _XI_BLOCK] = np.cos(np.outer(flat[lo : lo + _XI_BLOCK], nodes)) @ weights
    return out.reshape(xi.shape)


_XI_BLOCK = 8192
"""Frequencies per block in :func:`kernel_transform` (8192 × ~170 nodes ≈ 11 MB)."""


def _spread_numpy(
    amps: _F64,
    taus: _F64,
    t_lo: float,
    t_hi: float,
    t0: float,
    scale: float,
    coefs: _F64,
    grid: _F64,
) -> tuple[int, int]:
    n_batch, n_rays = amps.shape
    width = coefs.shape[1]
    half = 0.5 * width
    n_grid = grid.shape[1]
    hit = (amps != 0.0) & (taus < np.inf)
    keep = hit & (taus > t_lo) & (taus < t_hi)
    a = np.where(keep, amps, 0.0)
    park = t0 + (half + 1.0) / scale  # any place whose taps stay inside the grid
    u = (np.where(keep, taus, park) - t0) * scale
    j0 = np.ceil(u - half)
    t = 2.0 * (j0 - (u - half)) - 1.0
    w = np.broadcast_to(coefs[0], (n_batch, n_rays, width))
    for d in range(1, coefs.shape[0]):
        w = w * t[..., None] + coefs[d]
    first = j0.astype(np.int64) + (np.arange(n_batch) * n_grid)[:, None]
    idx = first[..., None] + np.arange(width)
    grid += np.bincount(
        idx.ravel(), (a[..., None] * w).ravel(), minlength=n_batch * n_grid
    ).reshape(grid.shape)
    return int(np.count_nonzero(hit)), int(np.count_nonzero(keep))


_BLOCK = 512  # rays whose kernel weights are evaluated together (stays in L1)


def _spread_loops(amps, taus, t_lo, t_hi, t0, scale, coefs, grid):
    """:func:`spread` as plain loops, compiled by numba (:func:`echocal._numba.compiled`).

    Per block of rays: gather the kept rays' offsets t, first taps j₀ and amplitudes;
    evaluate the tap polynomials for the whole block with the ray axis innermost (SIMD,
    independent Horner chains); then add the taps ray by ray, tap by tap (the fallback's
    order, so both give the same sums).
    """
    n_batch, n_rays = amps.shape
    n_coef, width = coefs.shape
    half = 0.5 * width
    tb = np.empty(_BLOCK)
    ab = np.empty(_BLOCK)
    jb = np.empty(_BLOCK, dtype=np.int64)
    wb = np.empty((width, _BLOCK))
    n_hit = 0
    n_keep = 0
    for b in range(n_batch):
        n = 0
        while n < n_rays:
            m = 0  # kept rays gathered into this block
            while n < n_rays and m < _BLOCK:
                a = amps[b, n]
                tau = taus[b, n]
                n += 1
                if a == 0.0 or not tau < np.inf:
                    continue
                n_hit += 1
                if not (tau > t_lo and tau < t_hi):
                    continue
                u = (tau - t0) * scale
                j0 = math.ceil(u - half)
                tb[m] = 2.0 * (j0 - (u - half)) - 1.0
                jb[m] = j0
                ab[m] = a
                m += 1
            n_keep += m
            for k in range(width):
                wk = wb[k]
                c0 = coefs[0, k]
                for r in range(m):
                    wk[r] = c0
                for d in range(1, n_coef):
                    c = coefs[d, k]
                    for r in range(m):
                        wk[r] = wk[r] * tb[r] + c
                for r in range(m):
                    wk[r] = ab[r] * wk[r]
            g = grid[b]
            for r in range(m):
                j = jb[r]
                for k in range(width):
                    g[j + k] += wb[k, r]
    return n_hit, n_keep


def spread(
    amps: _F64,
    taus: _F64,
    *,
    t_lo: float,
    t_hi: float,
    t0: float,
    scale: float,
    coefs: _F64,
    grid: _F64,
) -> tuple[int, int]:
    """Add every kept impulse's kernel taps into ``grid`` (in place).

    Parameters
    ----------
    amps : [a.u.] shape ``(n_batch, n_rays)``, C-contiguous float64.
    taus : [s] shape ``(n_batch, n_rays)``; ``inf`` for a miss.
    t_lo, t_hi : [s] impulses with τ outside (t_lo, t_hi) are dropped.
    t0 : [s] time of grid point 0.
    scale : [1/s] grid points per second.
    coefs : kernel polynomials from :func:`horner_coefficients`.
    grid : shape ``(n_batch, n_grid)``, C-contiguous; every kept impulse's taps must fit.

    Returns
    -------
    (number of rays that hit, i.e. a ≠ 0 and finite τ; number of those kept).
    """
    if amps.size >= NUMBA_MIN_RAYS:
        kernel = compiled(_spread_loops)
        if kernel is not None:
            n_hit, n_keep = kernel(amps, taus, t_lo, t_hi, t0, scale, coefs, grid)
            return int(n_hit), int(n_keep)
    return _spread_numpy(amps, taus, t_lo, t_hi, t0, scale, coefs, grid)
