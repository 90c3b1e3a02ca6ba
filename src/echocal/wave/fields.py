"""The probe's transmit field at many points and frequencies at once (numba).

``echocal.wave.probe.transmit_field`` gives one frequency at a time; a field on a grid
over a band (the tangent-plane model of a curved wall, :mod:`echocal.wave.curved_wall`)
needs thousands of points at tens of frequencies.  Each point's spatial impulse response is
binned once (:func:`echocal.wave.sir._bin_sir`, quadratic B-splines of width Δ) and
Fourier-transformed at every frequency by a rotating phasor; the B-spline projection's
transform sinc³(fΔ) is divided out, as ``transmit_field`` does.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import NDArray

from echocal.wave import sir, threads
from echocal.wave.probe import Aperture

__all__ = ["transmit_spectra"]

_MIN_POINTS_PER_THREAD = 256
"""A thread is worth starting for this many points (each costs tens of µs)."""
_BINS_PER_PERIOD = 16
"""Δ = 1/(16 f_max): with the sinc³ correction the field agrees with the single-frequency
``transmit_field`` (Δ = 1/(64 f)) to 2e-3 of the largest value (tests/physics)."""


@sir._jit
def _spectra(kind, prm, points, omegas, c, dt, scratch, out):  # pragma: no cover - numba
    """out[s, j] = Σ_q h̄_s[q]·exp(iω_j t_q)·Δ for every point s (aperture frame, (3, n))."""
    n = points.shape[1]
    m = omegas.shape[0]
    geo = np.zeros(sir.GEOMETRY_SIZE)
    bps = np.zeros(sir.MAX_BREAKPOINTS)
    tmax = math.acos(prm[2]) if kind == sir.BOWL else 0.0
    h = scratch[0]
    hm = scratch[1]
    for s in range(n):
        x, y, z = points[0, s], points[1, s], points[2, s]
        if not sir._sample_geometry(kind, prm, x, y, z, 0.0, 0.0, 1.0, geo):
            continue
        nb = sir.breakpoints(kind, prm, geo, c, tmax, bps)
        k0, nk = sir._bin_sir(kind, prm, geo, c, bps, nb, 0.0, dt, h, hm, scratch[2:4])
        for j in range(m):
            w = omegas[j]
            phase = w * (k0 + 0.5) * dt
            cr, ci = math.cos(phase), math.sin(phase)
            sr, si = math.cos(w * dt), math.sin(w * dt)
            re = 0.0
            im = 0.0
            for q in range(nk):
                re += h[q] * cr
                im += h[q] * ci
                cr, ci = cr * sr - ci * si, cr * si + ci * sr
            out[s, j] = complex(re * dt, im * dt)


def transmit_spectra(
    probe: Aperture, points: NDArray[np.float64], frequencies: NDArray[np.float64], c: float
) -> NDArray[np.complex128]:
    """Normalized transmit pressure p/(ρcv₀) = −ik·H(ω) (time convention e^{−iωt}).

    Parameters
    ----------
    probe : the aperture.
    points : [m] field points in the aperture frame (face centre or bowl apex at the
        origin, beam along +z), shape ``(3, n)``.
    frequencies : [Hz] shape ``(m,)``, all > 0.
    c : [m/s] sound speed.

    Returns
    -------
    complex ``(n, m)``; 0 at points behind the face.
    """
    f = np.asarray(frequencies, dtype=np.float64)
    dt = 1.0 / (_BINS_PER_PERIOD * float(f.max()))
    n_bins = sir.scratch_bins(c, dt, 2.0 * probe.radius)
    out = np.zeros((points.shape[1], f.size), dtype=np.complex128)
    pts = np.ascontiguousarray(points, dtype=np.float64)
    omegas = 2.0 * math.pi * f

    def kernel(lo: int, hi: int) -> None:  # rows lo:hi; the kernel releases the GIL
        scratch = np.zeros((4, n_bins))
        rows = np.ascontiguousarray(pts[:, lo:hi])
        _spectra(probe.kind, probe.parameters, rows, omegas, c, dt, scratch, out[lo:hi])

    n = pts.shape[1]
    workers = min(threads.MAX_THREADS, threads.cores(), max(1, n // _MIN_POINTS_PER_THREAD))
    bounds = np.linspace(0, n, workers + 1).astype(int)
    if workers == 1:
        kernel(0, n)
    else:
        pool = threads.pool(workers)
        for future in [pool.submit(kernel, lo, hi) for lo, hi in itertools.pairwise(bounds)]:
            future.result()
    k = 2.0 * math.pi * f / c
    return out * (-1j * k / np.sinc(f * dt) ** 3)
