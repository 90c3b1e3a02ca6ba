"""The fast paths of the wave model's kernels against quadrature the test does itself.

1. The quadratic B-spline coefficients of a flat disc's spatial impulse response h and of
   its direction-weighted h_m (one closed-form value per bin away from the breakpoints,
   interpolated deep inside the support) agree with adaptive quadrature (scipy.integrate.quad,
   split at the breakpoints) of Stepanishen's closed form, written here independently:
   within 2·10⁻⁴ of the largest coefficient away from the breakpoints, 10⁻³ next to them
   (Gauss–Legendre after a √-substitution there).
2. The correlation split over threads equals the one-thread sum to round-off.
3. A rectangle's closed form (the arcs of a circle inside it, as a signed sum over its four
   corners' quadrants) against points sampled on that circle, and its coefficients against
   quadrature as in 1.
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
    geo = np.zeros(sir.GEOMETRY_SIZE)
    assert sir._sample_geometry(sir.DISC, np.array([A, 0.0, 0.0]), r, 0.0, z, mx, 0.0, mz, geo)
    bps = np.array([lo, mid, hi])
    k0, n = sir._bin_sir(sir.DISC, np.array([A, 0.0, 0.0]), geo, C, bps, 3, t0, DT, h, hm, work)
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


# --------------------------------------------------------------------------- rectangles
AX, AY = 5e-3, 3e-3
RECT_PRM = np.array([math.hypot(AX, AY), AX, AY])


def _rect_arcs_by_sampling(x: float, y: float, z: float, t: float, n: int = 400_000):
    """(Θ, ∫cos φ dφ, ∫sin φ dφ) of the circle of radius √((ct)² − z²) about (x, y) inside
    the rectangle |x′| ≤ AX, |y′| ≤ AY, by sampling the circle at n equal angles."""
    s2 = (C * t) ** 2 - z * z
    if s2 <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    s = math.sqrt(s2)
    phi = (np.arange(n) + 0.5) * (2.0 * math.pi / n)
    inside = (np.abs(x + s * np.cos(phi)) <= AX) & (np.abs(y + s * np.sin(phi)) <= AY)
    d = 2.0 * math.pi / n
    return s, d * inside.sum(), d * np.cos(phi)[inside].sum(), d * np.sin(phi)[inside].sum()


def test_rectangle_arcs_match_a_sampled_circle() -> None:
    """Θ and m·∫(x − a) dφ of the rectangle's closed form (signed quadrants) against
    400,000 points on the circle, at 200 random points inside, beside and beyond the face.
    Tolerance 10⁻⁴ rad (the sampling's own error is 2π/400,000 per arc end ≈ 1.6·10⁻⁵)."""
    rng = np.random.default_rng(7)
    for _ in range(200):
        x, y = rng.uniform(-9e-3, 9e-3, 2)
        z = rng.uniform(1e-3, 30e-3)
        m = rng.normal(size=3)
        m /= np.linalg.norm(m)
        t = math.hypot(z, rng.uniform(0.0, 13e-3)) / C
        s, theta, int_cos, int_sin = _rect_arcs_by_sampling(x, y, z, t)
        got_theta, got_m = sir._arc_rect(t, C, x, y, z, AX, AY, m[0], m[1], m[2])
        want_m = m[2] * z * theta - s * (m[0] * int_cos + m[1] * int_sin)
        assert abs(got_theta - theta) < 1e-4
        assert abs(got_m - want_m) < 1e-4 * max(s, z)


@pytest.mark.parametrize(
    ("x", "y", "z"), [(1e-3, 2e-3, 0.01), (6e-3, -1e-3, 0.01), (3e-3, 3e-3, 0.005)]
)
def test_rectangle_coefficients_match_quadrature(x: float, y: float, z: float) -> None:
    """The B-spline coefficients of a rectangle's h and h_m (up to ten breakpoints: its
    edges and corners) against adaptive quadrature of the sampled-circle-checked closed
    form, split at those breakpoints.  Tolerance 10⁻³ of the largest coefficient, as for
    the disc (measured 1.2–3.7·10⁻⁴)."""
    dt = 1.0 / (5 * 8.7e6)
    m = np.array([0.2, 0.1, 1.0]) / math.sqrt(1.05)
    geo = np.zeros(sir.GEOMETRY_SIZE)
    bps = np.zeros(sir.MAX_BREAKPOINTS)
    assert sir._sample_geometry(sir.RECT, RECT_PRM, x, y, z, m[0], m[1], m[2], geo)
    nb = sir.breakpoints(sir.RECT, RECT_PRM, geo, C, 0.0, bps)
    assert 3 <= nb <= sir.MAX_BREAKPOINTS and np.all(np.diff(bps[:nb]) >= 0.0)
    n_bins = sir.scratch_bins(C, dt, 2 * RECT_PRM[0])
    h, hm, work = np.zeros(n_bins), np.zeros(n_bins), np.zeros((2, n_bins))
    t0 = 1.234e-9
    k0, n = sir._bin_sir(sir.RECT, RECT_PRM, geo, C, bps, nb, t0, dt, h, hm, work)

    def values(t: float) -> tuple[float, float]:
        closed, mint = sir._arc_rect(t, C, x, y, z, AX, AY, m[0], m[1], m[2])
        return C * closed / (2 * math.pi), mint / (2 * math.pi * t)

    cuts = list(bps[:nb])
    for part, got in ((0, h[:n]), (1, hm[:n])):
        want = np.array(
            [
                scipy.integrate.quad(
                    lambda t, tc=tc, part=part: values(t)[part] * _bspline((t - tc) / dt),
                    tc - 1.5 * dt,
                    tc + 1.5 * dt,
                    points=[p for p in cuts if tc - 1.5 * dt < p < tc + 1.5 * dt] or None,
                    limit=200,
                    epsabs=1e-7,
                )[0]
                / dt
                for tc in t0 + (k0 + np.arange(n) + 0.5) * dt
            ]
        )
        assert np.max(np.abs(got - want)) < 1e-3 * np.max(np.abs(want))
