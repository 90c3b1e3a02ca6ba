"""The image form over a plane for a flat disc, as a sum over pairs of abscissae: one
direction of each face in closed form.

The image form (:mod:`echocal.wave.image`) integrates the disc's spatial impulse response
over its mirror image; written out, it is the double surface integral

    H(t) = ∫_A ∫_A δ(t − R/c) / (2πR) dA_a dA_b,   R = |a − M b|,

M the mirror across the plane.  In the face's frame with x along the plane's tilt
direction (plane normal n = (sin α, 0, cos α), distance h from the face centre), for a and
b on the face

    R² = (2h + s·(a_x + b_x))² + cos²α·(a_x − b_x)² + (a_y − b_y)²,   s = sin α,

so the y-coordinates enter only through their difference w = a_y − b_y.  For fixed
abscissae (a_x, b_x) the ordinates run over |a_y| ≤ Y_a, |b_y| ≤ Y_b (Y = √(a² − x²)),
and w has the density T(w) = overlap of the two chords (2·min(Y_a, Y_b) up to
|Y_a − Y_b|, then falling linearly to 0 at Y_a + Y_b): the convolution of the two chords'
indicators.  With R(w) = √(Q + w²), Q the part without w, the w-integral is in closed
form in time, and smooth in w:

    H(t) dt = Σ_pairs ∫₀^{Y_a+Y_b} T(w) / (π R(w)) · [R(w)/c ∈ dt] dw.

Each pair's response lasts (√(Q + (Y_a + Y_b)²) − √Q)/c ≤ a²/(h c) whatever the tilt
(0.5 µs for a 12.7 mm probe at 50 mm), where a face node's SIR lasts about 2a·sin α/c
(2.9 µs at 20°), and the pairs are about as many as the face rule's nodes: that is the
saving at large tilts.

**Nodes.** a_x = a cos φ (dA's chord 2Y_a = 2a sin φ): the integrand, continued evenly in
φ, is smooth and 2π-periodic, and at one frequency its φ-harmonics are bounded by
β = k_hi·a·sin(α + asin(a/h)) (the path's rate of change along x is at most the sine of
its angle to the face normal, :func:`echocal.wave.image.angular_bandwidth`).  The uniform
rule with :func:`echocal.wave.image.trapezoid_count` (β) nodes on the full circle is then
exact below its harmonics; by the evenness half of them (φ in (0, π)) carry the sum.  R is
symmetric in a ↔ b, so the pairs i ≤ j carry it, those off the diagonal weighted twice.

**Time grid.** The pairs go onto the grid of ``echocal.wave.sir.accumulate_one_way``
(grid point g at t₀ + gΔ), projected onto B-splines of degree :data:`_DEGREE` rather than
2: each pair's response starts like 1/√(t − t_start), whose aliases the quadratic splines
do not hold down (the extra sinc^(degree − 2)(fΔ) is divided out downstream,
:func:`smoothing`).  The projection is Gauss–Legendre: in w (where the integrand is smooth)
on the pieces between the bins' edges and T's kink in a pair's first bins, its kink's bin
and its last; at fixed nodes in time in every other bin (:func:`_accumulate_pairs`).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import NDArray

from echocal.wave import image, threads
from echocal.wave.sir import _jit

__all__ = ["abscissae", "mean_image_distance", "pair_count", "pair_grid", "pays", "smoothing"]

FloatArray = NDArray[np.float64]

_GL2_X = np.array([0.2113248654051871, 0.7886751345948129])
_GL3_X = np.array([0.1127016653792583, 0.5, 0.8872983346207417])
_GL3_W = np.array([5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0])


@functools.lru_cache(maxsize=64)
def _abscissae(radius: float, n_circle: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    j = np.arange(n_circle // 2)
    phi = math.pi * (2.0 * j + 1.0) / n_circle
    x = radius * np.cos(phi)
    half_chord = radius * np.sin(phi)
    weight = (2.0 * math.pi / n_circle) * half_chord
    return x, half_chord, weight


def abscissae(radius: float, n_circle: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The pair rule's nodes along x on a disc of radius ``radius`` [m]: ``n_circle``/2 nodes
    x = a cos φ, φ = π(2j + 1)/``n_circle`` (the uniform rule on the full circle, kept on
    (0, π)).

    Returns x [m], the half-chords Y = a sin φ [m] and the weights [m] (dx = a sin φ dφ,
    ∑ weights·f(x) ≈ ∫₋ₐᵃ f(x) dx), each ``(n_circle // 2,)``."""
    x, half_chord, weight = _abscissae(radius, n_circle)
    return x.copy(), half_chord.copy(), weight.copy()


def pair_count(bandwidth: float, radius: float) -> int:
    """Nodes on the full circle of the pair rule for a path phase rate ``bandwidth``
    [rad/m] (:func:`echocal.wave.image.angular_bandwidth`) on a disc of radius ``radius``
    [m]: :func:`echocal.wave.image.trapezoid_count` (bandwidth·radius); the rule keeps half
    of them, and n/2·(n/2 + 1)/2 pairs."""
    return image.trapezoid_count(bandwidth * radius)


_DEGREE = 6
"""Degree of the B-splines the pairs are projected onto (even: centred on the grid points).
Each pair's response rises like 1/√t at its start (the w-integral's stationary point), so
its spectrum falls only like f^(−1/2), and what the sum over pairs leaves of it above the
band folds back into the band at the grid's sampling; each degree multiplies those aliases
by sinc(fΔ) ≈ 0.19 at the first fold (measured on a 12.7 mm probe at 50 mm, the echo's
error against the face rule's: 37 % of the local echo at 20° with degree 2, 0.75 % with 4,
0.16 % with 6)."""


def _power_basis(degree: int) -> FloatArray:
    """``(degree + 1, degree + 1)``: row b holds the power coefficients (u⁰ … u^degree) of
    the b-th uniform B-spline of ``degree`` on the unit interval it overlaps (b = 0 the
    one that ends there, (1 − u)^degree/degree!), by the Cox–de Boor recurrence."""
    from numpy.polynomial import Polynomial

    u = Polynomial([0.0, 1.0])
    basis = [Polynomial([1.0])]
    for k in range(1, degree + 1):
        previous = [Polynomial([0.0]), *basis, Polynomial([0.0])]
        basis = [
            ((u + (k - j)) * previous[j] + (1.0 - u + j) * previous[j + 1]) / k
            for j in range(k + 1)
        ]
    out = np.zeros((degree + 1, degree + 1))
    for b, poly in enumerate(basis):
        coef = poly.coef
        out[b, : coef.size] = coef
    return out


_BASIS = _power_basis(_DEGREE)
_NODE_POWERS = np.concatenate([_GL2_X, _GL3_X])[:, None] ** np.arange(_DEGREE + 1)
_NODE_BASIS = _NODE_POWERS @ _BASIS.T
"""``(5, _DEGREE + 1)``: the B-splines overlapping a bin at the fixed nodes of its smooth
bins (the 2- then the 3-point Gauss–Legendre nodes)."""
_CURVED_BINS = 8
"""A pair's first bins (from its start), where its response 1/√(t − t_start) curves most:
3 Gauss–Legendre nodes per piece (3 in the first 4 bins only left 2.2·10⁻³ and 8.2·10⁻³ of
the local echo at 20° and 30°, 50 mm, against a dense face rule; 8 bins 0.9 and 4.5·10⁻³)."""
_START_BINS = 2
"""A pair's first bins, integrated in w (smooth there, where the response in time is not);
from the third on the bins take fixed nodes in time (the start a whole bin or more away)."""


@_jit
def _w_piece(q, flat, kink, top, w_lo, w_hi, n_nodes, scale, u_shift):
    """The moments Σ value·uᵐ (m = 0 … 6) of ∫ T(w)/R dw · ``scale`` over [w_lo, w_hi]
    (no kink inside) by ``n_nodes``-point Gauss–Legendre in w; u = R·``u_shift[0]`` +
    ``u_shift[1]`` the place in the bin."""
    span = w_hi - w_lo
    m0 = m1 = m2 = m3 = m4 = m5 = m6 = 0.0
    for k in range(n_nodes):
        if n_nodes == 3:
            w = w_lo + span * _GL3_X[k]
            wk = _GL3_W[k]
        else:
            w = w_lo + span * _GL2_X[k]
            wk = 0.5
        r = math.sqrt(q + w * w)
        chord = flat if w <= kink else top - w
        value = scale * wk * span * chord / r
        u = min(1.0, max(0.0, r * u_shift[0] + u_shift[1]))
        m0 += value
        value *= u
        m1 += value
        value *= u
        m2 += value
        value *= u
        m3 += value
        value *= u
        m4 += value
        value *= u
        m5 += value
        m6 += value * u
    return m0, m1, m2, m3, m4, m5, m6


@_jit
def _accumulate_pairs(x, half_chord, weight, rows, distance, s, c, t0, dt, delay, moments, nodes):
    """Add the pairs' T(w)/(πR) projected onto the degree-:data:`_DEGREE` B-splines centred
    on the grid points (grid point g at t0 + gΔ); see the module: the pairs (i, j ≥ i) of
    the abscissae i in ``rows``.

    A pair's first :data:`_START_BINS` bins (where the time is quadratic in w), the bin of
    T's kink and its last bin are cut into pieces between their edges and the kink, each
    integrated in w by Gauss–Legendre (3 nodes within :data:`_CURVED_BINS` of the start,
    else 2); their moments Σ value·uᵐ (u the node's place in the bin) go to ``moments``
    ``(n, _DEGREE + 1)``.  Every other bin is smooth in time: Gauss–Legendre in R at the
    bin's fixed nodes (3 within :data:`_CURVED_BINS` of the start, else 2) of the integrand
    T(w)/(πw) dR, the sums at each node going to ``nodes`` ``(n, 5)`` (see
    :data:`_NODE_BASIS`).  Both become B-spline coefficients in :func:`_moments_to_grid`.
    Returns the first and the last bin touched."""
    n = x.shape[0]
    n_bins = moments.shape[0]
    cos2 = 1.0 - s * s
    step = c * dt  # the bins' width in path length
    shift = (delay - t0) / dt + 0.5  # a path r lies at u = r/step + shift − g in bin g
    u_shift = np.zeros(2)
    u_shift[0] = 1.0 / step
    g_first = n_bins
    g_last = -1
    for i in rows:
        for j in range(i, n):
            w_pair = weight[i] * weight[j] / (math.pi * dt)
            if i != j:
                w_pair *= 2.0
            sigma = x[i] + x[j]
            diff = x[i] - x[j]
            z = 2.0 * distance + s * sigma
            q = z * z + cos2 * diff * diff
            ya = half_chord[i]
            yb = half_chord[j]
            kink = abs(ya - yb)
            top = ya + yb
            flat = 2.0 * min(ya, yb)
            r_start = math.sqrt(q)
            r_kink = math.sqrt(q + kink * kink)
            r_end = math.sqrt(q + top * top)
            g = int(math.floor(r_start / step + shift))  # noqa: RUF046 (numba)
            g_first = min(g_first, g)
            g_last = max(g_last, int(math.floor(r_end / step + shift)))  # noqa: RUF046
            bins = 0
            r_lo = r_start
            while r_lo < r_end:
                r_hi = min(r_end, (g + 1.0 - shift) * step)
                inside = 0 <= g < n_bins
                smooth = bins >= _START_BINS and r_hi < r_end and not (r_lo < r_kink < r_hi)
                if inside and smooth and bins < _CURVED_BINS:
                    for k in range(3):
                        r = (g - shift + _GL3_X[k]) * step
                        w = math.sqrt(r * r - q)
                        chord = flat if w <= kink else top - w
                        nodes[g, 2 + k] += w_pair * _GL3_W[k] * step * chord / w
                elif inside and smooth:
                    for k in range(2):
                        r = (g - shift + _GL2_X[k]) * step
                        w = math.sqrt(r * r - q)
                        chord = flat if w <= kink else top - w
                        nodes[g, k] += w_pair * 0.5 * step * chord / w
                elif inside and r_hi > r_lo:
                    u_shift[1] = shift - g
                    w_lo = math.sqrt(max(0.0, r_lo * r_lo - q)) if bins > 0 else 0.0
                    w_hi = top if r_hi >= r_end else math.sqrt(max(0.0, r_hi * r_hi - q))
                    n_nodes = 3 if bins < _CURVED_BINS else 2
                    if w_lo < kink < w_hi:
                        parts = _w_piece(q, flat, kink, top, w_lo, kink, n_nodes, w_pair, u_shift)
                        for m in range(_DEGREE + 1):
                            moments[g, m] += parts[m]
                        w_lo = kink
                    parts = _w_piece(q, flat, kink, top, w_lo, w_hi, n_nodes, w_pair, u_shift)
                    for m in range(_DEGREE + 1):
                        moments[g, m] += parts[m]
                bins += 1
                r_lo = r_hi
                g += 1
    return max(0, g_first), min(n_bins - 1, g_last)


@_jit
def _moments_to_grid(moments, nodes, first, last, grid):
    """Add the B-spline coefficients of every bin's ``moments`` ``(n, _DEGREE + 1)`` and of
    its fixed-node sums ``nodes`` ``(n, 2)`` (at u = the 2-point Gauss–Legendre nodes; see
    :func:`_accumulate_pairs`) of bins ``first`` … ``last`` to ``grid`` ``(n,)``: bin g's
    spline b is centred on grid point g − _DEGREE/2 + b."""
    half = _DEGREE // 2
    n = grid.shape[0]
    for g in range(max(half, first), min(n - half, last + 1)):
        for b in range(_DEGREE + 1):
            acc = 0.0
            for m in range(_DEGREE + 1):
                acc += _BASIS[b, m] * moments[g, m]
            for k in range(_NODE_POWERS.shape[0]):
                acc += _NODE_BASIS[k, b] * nodes[g, k]
            grid[g - half + b] += acc


def smoothing(frequencies: FloatArray, dt: float) -> FloatArray:
    """The pair grid's B-spline transform relative to the quadratic B-splines of
    ``echocal.wave.sir.accumulate_one_way``: sinc^(degree − 2)(fΔ) at ``frequencies``
    [Hz] (Δ = ``dt`` [s]); divide a pair grid's spectrum by it before the image form's
    transfer."""
    return np.asarray(np.sinc(frequencies * dt) ** (_DEGREE - 2), dtype=np.float64)


_Y_RULE = np.polynomial.legendre.leggauss(4)


def mean_image_distance(radius: float, distance: float, sin_incidence: float) -> float:
    """[m] the mean distance from the face centre to the points of the disc's mirror image
    (radius ``radius`` [m], plane ``distance`` [m] away at incidence sine
    ``sin_incidence``): |M b|² = |b|² + 4h² + 4h·s·b_x, averaged over the disc by a 16 × 4
    node product rule (within the 1.4 µm standard error of 2·10⁶ random points at 20°,
    50 mm)."""
    x, half_chord, weight = _abscissae(radius, 32)
    y_nodes, y_weights = _Y_RULE
    b_y = np.outer(half_chord, y_nodes)
    w = np.outer(weight * half_chord, y_weights)
    r = np.sqrt((x * x + 4.0 * distance * (distance + sin_incidence * x))[:, None] + b_y * b_y)
    return float(np.sum(w * r) / np.sum(w))


def pair_grid(
    radius: float,
    distance: float,
    sin_incidence: float,
    bandwidth: float,
    sound_speed: float,
    t0: float,
    dt: float,
    n_grid: int,
    delay: float = 0.0,
) -> FloatArray:
    """H(t) of a flat disc over a plane by the pair rule, on the image form's one-way
    B-spline grid: the same grid as ``echocal.wave.sir.accumulate_one_way`` summed
    over the image face's nodes with unit weights would give.  The abscissae's rows of
    pairs are split over threads like the face rule's nodes
    (``echocal.wave.threads.split``), from ``echocal.wave.threads.PAIRS_PER_NODE``
    × ``echocal.wave.threads.MIN_NODES_PER_THREAD`` pairs a thread.

    Parameters
    ----------
    radius : [m] the disc's radius a.
    distance : [m] the plane's distance h from the face centre (along its normal).
    sin_incidence : sin α, α the beam axis's incidence on the plane.
    bandwidth : [rad/m] the path phase rate bound (:func:`pair_count`).
    sound_speed : [m/s] c.
    t0, dt : [s] the time of grid point 0 and the spacing Δ.
    n_grid : grid points.
    delay : [s] a delay added to every path (an interior's equivalent path).

    Returns
    -------
    [m³/s] ``(n_grid,)``.
    """
    x, half_chord, weight = _abscissae(radius, pair_count(bandwidth, radius))

    def kernel(grid: FloatArray, rows: NDArray[np.intp]) -> tuple[float, float]:
        moments = np.zeros((n_grid, _DEGREE + 1))
        nodes = np.zeros((n_grid, 5))
        first, last = _accumulate_pairs(
            x,
            half_chord,
            weight,
            np.ascontiguousarray(rows),
            distance,
            sin_incidence,
            sound_speed,
            t0,
            dt,
            delay,
            moments,
            nodes,
        )
        _moments_to_grid(moments, nodes, first, last, grid)
        return 0.0, 0.0

    # rows i carry n − i pairs each: about n/2 on average
    rows_per_thread = max(
        1, round(threads.PAIRS_PER_NODE * threads.MIN_NODES_PER_THREAD / (0.5 * x.size))
    )
    grid, _, _ = threads.split(weight, n_grid, kernel, rows_per_thread)
    return grid


_PAIR_COST = (80.0, 0.24, 0.0072)
_FACE_COST = (230.0, 1.34, 0.027)
"""Cost models [µs of CPU on one thread] of the two rules for :func:`pays`: a fixed cost,
and per pair (per face node) a cost and one per bin of its response: a pair's lasts at
most a²/(2h) of path, a face node's SIR about 2a·sin α + a²/(2h).  Fitted to both rules'
CPU time for 3 and 12.7 mm probes at 10–100 mm and 0.5–30° (44 poses: measured 0.7–1.3×
the model; it takes the cheaper rule at all but one, a tie, docs/benchmarks/wave.md)."""


def pays(
    radius: float,
    distance: float,
    sin_incidence: float,
    bandwidth: float,
    face_nodes: int,
    step: float,
) -> bool:
    """Whether the pair rule is estimated cheaper than the face rule's ``face_nodes`` nodes
    (:data:`_PAIR_COST`, :data:`_FACE_COST`): a flat disc of radius ``radius`` [m] over a
    plane ``distance`` [m] away at incidence sine ``sin_incidence``, path phase rate bound
    ``bandwidth`` [rad/m], time bins ``step`` [m] of path long."""
    half = pair_count(bandwidth, radius) // 2
    n_pairs = half * (half + 1) // 2
    near = radius * radius / (2.0 * distance) / step
    sir_bins = 2.0 * radius * sin_incidence / step + near
    pair = _PAIR_COST[0] + n_pairs * (_PAIR_COST[1] + _PAIR_COST[2] * near)
    face = _FACE_COST[0] + face_nodes * (_FACE_COST[1] + _FACE_COST[2] * sir_bins)
    return pair < face
