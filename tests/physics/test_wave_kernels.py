"""The fast paths of the wave model's kernels against quadrature the test does itself.

1. The quadratic B-spline coefficients of a flat disc's spatial impulse response h and of
   its direction-weighted h_m (one closed-form value per bin away from the breakpoints,
   interpolated deep inside the support) agree with adaptive quadrature (scipy.integrate.quad,
   split at the breakpoints) of Stepanishen's closed form, written here independently:
   within 2·10⁻⁴ of the largest coefficient away from the breakpoints, 10⁻³ next to them
   (Gauss–Legendre after a √-substitution there).
2. The correlation split over threads equals the one-thread sum to round-off.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate

from echocal.wave import sir, threads

C = 1480.0
A = 6.35e-3
DT = 20e-9


def _h_disc(t: float, r: float, z: float) -> tuple[float, float]:
    """(h, ∫(m·R̂)δ(t − R/c)/(2πR) dA) with m = (sin 20°, 0, cos 20°) along x, sample on x."""
    s2 = (C * t) ** 2 - z * z
    if s2 <= 0.0:
        return 0.0, 0.0
    s = math.sqrt(s2)
    if s <= A - r:
        om, mean_r = math.pi, 0.0
    elif abs(r - A) < s < r + A:
        cw = (s2 + r * r - A * A) / (2.0 * r * s)
        om = math.acos(cw)
        mean_r = s * math.sin(om) / om
    else:
        return 0.0, 0.0
    mx, mz = math.sin(math.radians(20.0)), math.cos(math.radians(20.0))
    h = C * om / math.pi
    return h, h * (mz * z + mx * mean_r) / (C * t)


def _bspline(u: float) -> float:
    """Centred uniform quadratic B-spline."""
    u = abs(u)
    if u < 0.5:
        return 0.75 - u * u
    if u < 1.5:
        return 0.5 * (1.5 - u) ** 2
    return 0.0


@pytest.mark.parametrize(("r", "z"), [(0.5e-3, 0.02), (4e-3, 0.02), (9e-3, 0.05), (14e-3, 0.1)])
def test_disc_coefficients_match_quadrature(r: float, z: float) -> None:
    lo = math.hypot(z, max(r - A, 0.0)) / C
    mid = math.hypot(z, A - r) / C if r < A else lo
    hi = math.hypot(z, r + A) / C
    t0 = 1.234e-9
    n_bins = sir.scratch_bins(C, DT, 2 * A)
    h, hm, work = np.zeros(n_bins), np.zeros(n_bins), np.zeros((2, n_bins))
    mx, mz = math.sin(math.radians(20.0)), math.cos(math.radians(20.0))
    geo = np.zeros(5)
    assert sir._sample_geometry(sir.DISC, np.array([A, 0.0, 0.0]), r, 0.0, z, mx, 0.0, mz, geo)
    k0, n = sir._bin_sir(
        sir.DISC, np.array([A, 0.0, 0.0]), geo, C, lo, mid, hi, t0, DT, h, hm, work
    )
    assert n > 12  # long enough to exercise the smooth and the interpolated rules
    want = np.zeros((2, n))
    for j in range(n):
        centre = t0 + (k0 + j + 0.5) * DT
        a, b = centre - 1.5 * DT, centre + 1.5 * DT
        cuts = [p for p in (lo, mid, hi) if a < p < b]
        for part in (0, 1):
            want[part, j] = (
                scipy.integrate.quad(
                    lambda t, p=part, tc=centre: _h_disc(t, r, z)[p] * _bspline((t - tc) / DT),
                    a,
                    b,
                    points=cuts or None,
                    limit=200,
                    epsabs=1e-6,
                )[0]
                / DT
            )
    centres = t0 + (k0 + np.arange(n) + 0.5) * DT
    smooth = np.min(np.abs(centres[:, None] - np.array([lo, mid, hi])), axis=1) > 3 * DT
    assert np.count_nonzero(smooth) > n // 3
    for got, ref in ((h[:n], want[0]), (hm[:n], want[1])):
        scale = np.max(np.abs(ref))
        # next to a breakpoint: Gauss–Legendre after the √-substitution (within ~5e-4)
        assert np.max(np.abs(got - ref)) < 1e-3 * scale
        # elsewhere: one closed-form value per bin, h + δ²h/8, and the interpolated ones
        assert np.max(np.abs(got - ref)[smooth]) < 2e-4 * scale


def test_threads_sum_to_the_one_thread_grid() -> None:
    rng = np.random.default_rng(1)
    n = 600
    points = np.stack(
        [rng.uniform(-12e-3, 12e-3, n), rng.uniform(-12e-3, 12e-3, n), rng.uniform(0.04, 0.05, n)]
    )
    unit_m = np.tile(np.array([[0.0], [0.05], [1.0]]) / math.hypot(0.05, 1.0), (1, n))
    weights = rng.uniform(0.0, 1.0, n)
    weights[::7] = 0.0
    delays = np.zeros(n)
    prm = np.array([A, 0.0, 0.0])
    t0, n_grid = 2 * 0.04 / C - 1e-6, 1024
    n_scratch = sir.scratch_bins(C, DT, 2 * A)
    one = np.zeros(n_grid)
    swt, sw = sir.accumulate_two_way(
        sir.DISC, prm, points, unit_m, weights, delays, C, t0, DT, one, np.zeros((5, 2 * n_scratch))
    )
    grid, swt2, sw2 = threads.two_way_grid(
        sir.DISC, prm, points, unit_m, weights, delays, C, t0, DT, n_grid, n_scratch
    )
    assert np.max(np.abs(one)) > 0.0
    np.testing.assert_allclose(grid, one, rtol=0, atol=1e-12 * np.max(np.abs(one)))
    assert swt2 == pytest.approx(swt, rel=1e-12)
    assert sw2 == pytest.approx(sw, rel=1e-12)
