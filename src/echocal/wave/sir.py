"""Spatial impulse responses (SIR) of a baffled piston, binned, and their two-way correlation.

The transmit field of a rigid-baffled piston with uniform normal velocity v(t) is
p(x, t) = ρ ∂ₜ[v * h](x, t), with the spatial impulse response (Stepanishen, JASA 49
(1971) 1629; Penttinen & Luukkala, J. Phys. D 9 (1976) 1547 for a spherical bowl)

    h(x, t) = ∫_A δ(t − |x − a|/c) / (2π|x − a|) dA      [m/s].

For a disc and a bowl the points of the face at distance ρ = ct from x form one circular
arc, so h has the closed form

    h(x, t) = c · J · Ω(t)/π,

where Ω ∈ [0, π] is the half-angle of the part of that circle that lies on the face and
J = 1 for a flat disc, J = R_f/D for a bowl of radius of curvature R_f whose centre (the
geometric focus) is at distance D from x.  For a flat rectangle (Lockwood & Willette,
JASA 53 (1973) 735; San Emeterio & Ullate, JASA 92 (1992) 651) the circle of radius
σ = √((ct)² − z²) about x's projection on the face crosses the rectangle in up to four
arcs, and h = c·Θ(t)/(2π) with Θ their total angle: the signed sum of the angles the
circle spends in the four quadrants {x′ < u, y′ < v} cornered at the rectangle's corners
(u, v), each the overlap of two arcs in closed form.  The same arc gives the
direction-weighted response

    h_m(x, t) = ∫_A (m·R̂) δ(t − R/c) / (2πR) dA = h(x, t) · m·⟨x − a⟩_arc / (ct),

because every point of the arc is at R = ct; the arc mean ⟨x − a⟩ is closed form too
(the mean of a unit vector over an arc of half-angle Ω is sinΩ/Ω along its bisector;
over a rectangle's arcs, ∫cos φ dφ and ∫sin φ dφ of each arc).

The kernels below project h and h_m onto quadratic B-splines on a uniform time grid of
spacing Δ (integrals split at the breakpoints of the closed form — three for a disc or a
bowl, up to ten for a rectangle (its edges and corners) — 2-point Gauss–Legendre
on each smooth piece) and accumulate the two-way correlation g(t) = (h * h_m)(t) of every
surface sample into one grid.  The projection is a smoothing filter of transform sinc³(fΔ) per
factor, undone exactly in the frequency domain by dividing by sinc⁶(fΔ) (see
:mod:`echocal.wave.model`); it keeps the aliases of the SIR, which is not band-limited,
below 10⁻³ at a grid of five samples per period of the pulse's highest frequency.

All kernels are plain Python loops over numpy arrays, compiled by numba when it is
installed (the ``fast`` extra) and run as they are otherwise (correct, much slower).
Importing this module imports numba: :mod:`echocal.wave` is loaded only when a wave
model is used.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from echocal._numba import HAVE_NUMBA, USE_NUMBA, jit


def _jit(func: Callable[..., Any]) -> Callable[..., Any]:
    """numba.njit (lazy compilation, cached on disk) when numba is installed, else ``func``.

    ``error_model="numpy"``: a division by zero gives inf/nan instead of raising, which
    spares a check on every division of the inner loops (none of them divides by zero)."""
    if not (USE_NUMBA and HAVE_NUMBA):
        return func
    return jit(func, error_model="numpy")


def _jit_inline(func: Callable[..., Any]) -> Callable[..., Any]:
    """:func:`_jit`, and inlined into its callers: the small closed-form helpers called
    for every quadrature node (about 40 % of the kernels' time went to the calls)."""
    if not (USE_NUMBA and HAVE_NUMBA):
        return func
    return jit(func, error_model="numpy", inline="always")


# 2-point Gauss–Legendre nodes and weights on [0, 1] (smooth pieces), and 3-point ones
# (pieces at a breakpoint, after the substitution t = t_b ± span·u²)
_GL_X = np.array([0.2113248654051871, 0.7886751345948129])
_GL_W = np.array([0.5, 0.5])
_GL3_X = np.array([0.1127016653792583, 0.5, 0.8872983346207417])
_GL3_W = np.array([5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0])

DISC = 0
"""Aperture code: flat circular piston (parameters: radius)."""
BOWL = 1
"""Aperture code: spherically focused bowl (parameters: radius, radius of curvature)."""
RECT = 2
"""Aperture code: flat rectangle (parameters: half-diagonal, half-width, half-height)."""
MAX_BREAKPOINTS = 10
"""At most this many breakpoints of the closed form per sample: start, end and eight inside
(a rectangle's four edges and four corners)."""
GEOMETRY_SIZE = 6
"""Length of a sample's geometry record (see :func:`_sample_geometry`)."""


@_jit_inline
def _arc_disc(t, c, r, z, a, mx_r, mz):
    """(Ω [rad], m·⟨x − a⟩ [m]) of a flat disc of radius ``a`` seen from (r, z) at time t.

    ``mx_r`` and ``mz`` are the radial and axial components of the unit vector m."""
    ct = c * t
    s2 = ct * ct - z * z
    if s2 <= 0.0:
        return 0.0, 0.0
    s = math.sqrt(s2)
    if r + s <= a:
        return math.pi, mz * z  # the whole circle lies on the face: the arc mean is x⊥
    if s >= r + a or s <= r - a:
        return 0.0, 0.0
    cw = (s2 + r * r - a * a) / (2.0 * r * s)
    cw = min(1.0, max(-1.0, cw))
    om = math.acos(cw)
    mean_r = s * math.sqrt(1.0 - cw * cw) / om if om > 0.0 else s  # s·sinΩ/Ω
    return om, mz * z + mx_r * mean_r


@_jit_inline
def _arc_bowl(t, c, rf, d, cos_beta, sin_beta, cos_tmax, m_e, m_e1):
    """(Ω [rad], m·⟨x − a⟩ [m]) of a bowl (radius of curvature ``rf``, half-aperture angle
    θmax) seen from a point at distance ``d`` from the focus, at angle β from the axis
    direction focus → apex.  ``m_e`` and ``m_e1`` are the components of m along
    e = (x − F)/D and along e₁ ⊥ e in the plane of e and the axis (towards the apex)."""
    rho = c * t
    cos_psi = (rf * rf + d * d - rho * rho) / (2.0 * rf * d)
    if cos_psi > 1.0 or cos_psi < -1.0:
        return 0.0, 0.0
    sin_psi = math.sqrt(max(0.0, 1.0 - cos_psi * cos_psi))
    den = sin_psi * sin_beta
    num = cos_tmax - cos_psi * cos_beta
    if den <= 1e-15:
        om = math.pi if num <= 0.0 else 0.0
    else:
        q = num / den
        if q >= 1.0:
            return 0.0, 0.0
        om = math.pi if q <= -1.0 else math.acos(q)
    if om == 0.0:
        return 0.0, 0.0
    sinc = math.sin(om) / om
    # x − a = D e − R_f u, ⟨u⟩ = cosψ e + sinψ (sinΩ/Ω) e₁
    return om, m_e * (d - rf * cos_psi) - m_e1 * rf * sin_psi * sinc


@_jit_inline
def _quadrant(p, q):
    """(angle [rad], ∫cos φ dφ, ∫sin φ dφ) over the part of the unit circle where
    cos φ < p and sin φ < q: the overlap of the arcs [α, 2π − α] (α = acos p) and
    [π/2 + β, 5π/2 − β] (β = acos q), the latter also shifted by −2π."""
    al = math.acos(min(1.0, max(-1.0, p)))
    be = math.acos(min(1.0, max(-1.0, q)))
    ang = 0.0
    int_cos = 0.0
    int_sin = 0.0
    for shift in (0.0, -2.0 * math.pi):
        lo = max(al, 0.5 * math.pi + be + shift)
        hi = min(2.0 * math.pi - al, 2.5 * math.pi - be + shift)
        if hi > lo:
            ang += hi - lo
            int_cos += math.sin(hi) - math.sin(lo)
            int_sin += math.cos(lo) - math.cos(hi)
    return ang, int_cos, int_sin


@_jit_inline
def _arc_rect(t, c, x, y, z, ax, ay, mx, my, mz):
    """(Θ [rad], m·∫(x − a) dφ [m·rad]) of the rectangle |x′| ≤ ``ax``, |y′| ≤ ``ay``
    seen from (x, y, z) at time t: Θ the total angle of the arcs of the circle of radius
    σ = √((ct)² − z²) about (x, y) on the face, the integral over those arcs."""
    ct = c * t
    s2 = ct * ct - z * z
    if s2 <= 0.0:
        return 0.0, 0.0
    s = math.sqrt(s2)
    theta = 0.0
    int_cos = 0.0
    int_sin = 0.0
    # the rectangle's indicator is Σ ± 1[x′ < u]·1[y′ < v] over its corners (u, v)
    for corner in range(4):
        u = ax if corner == 0 or corner == 3 else -ax
        v = ay if corner == 0 or corner == 2 else -ay
        sign = 1.0 if corner == 0 or corner == 1 else -1.0
        ang, ic, is_ = _quadrant((u - x) / s, (v - y) / s)
        theta += sign * ang
        int_cos += sign * ic
        int_sin += sign * is_
    if theta <= 0.0:
        return 0.0, 0.0
    # x − a = (−σ cos φ, −σ sin φ, z) for the point a = (x + σ cos φ, y + σ sin φ, 0)
    return theta, mz * z * theta - s * (mx * int_cos + my * int_sin)


@_jit_inline
def _values(kind, prm, geo, c, t):
    """(h [m/s], h_m [m/s]) of one sample (geometry ``geo``) at time t [s]."""
    if kind == DISC:
        om, mdot = _arc_disc(t, c, geo[0], geo[1], prm[0], geo[2], geo[3])
        hv = c * om / math.pi
    elif kind == BOWL:
        om, mdot = _arc_bowl(t, c, prm[1], geo[0], geo[1], geo[2], prm[2], geo[3], geo[4])
        hv = c * prm[1] / geo[0] * om / math.pi
    else:
        theta, mint = _arc_rect(
            t, c, geo[0], geo[1], geo[2], prm[1], prm[2], geo[3], geo[4], geo[5]
        )
        return c * theta / (2.0 * math.pi), mint / (2.0 * math.pi * t)
    return hv, hv * mdot / (c * t)


@_jit_inline
def _add_node(kind, prm, geo, c, t, weight, k, b_lo, dt, h, hm):
    """Add one quadrature node at time t [s] with weight [s] to the B-spline coefficients
    k, k+1, k+2 of h and h_m (bin k starts at ``b_lo``)."""
    hv, hmv = _values(kind, prm, geo, c, t)
    hv *= weight / dt
    hmv *= weight / dt
    u = (t - b_lo) / dt
    w_prev = 0.5 * (1.0 - u) * (1.0 - u)
    w_next = 0.5 * u * u
    w_here = 1.0 - w_prev - w_next
    h[k] += w_prev * hv
    h[k + 1] += w_here * hv
    h[k + 2] += w_next * hv
    hm[k] += w_prev * hmv
    hm[k + 1] += w_here * hmv
    hm[k + 2] += w_next * hmv


@_jit_inline
def _add_singular(kind, prm, geo, c, lo, hi, at_lo, k, b_lo, dt, h, hm):
    """[lo, hi] with a √-type breakpoint at ``lo`` (``at_lo``) or at ``hi``: substitute
    t = t_b ± span·u² (a polynomial integrand in u) and use 3-point Gauss–Legendre."""
    span = hi - lo
    for j in range(3):
        x = _GL3_X[j]
        t = lo + span * x * x if at_lo else hi - span * x * x
        _add_node(kind, prm, geo, c, t, _GL3_W[j] * 2.0 * span * x, k, b_lo, dt, h, hm)


@_jit_inline
def _add_piece(kind, prm, geo, c, lo, hi, singular_lo, singular_hi, k, b_lo, dt, h, hm):
    """Integrate the smooth piece [lo, hi] of one bin against the B-splines.

    Inside the support, 2-point Gauss–Legendre (exact for the quadratic B-spline weight
    times a locally linear SIR).  At a breakpoint of the closed form the SIR behaves like
    √(t − t_b): :func:`_add_singular`; a piece with breakpoints at both ends is split."""
    if singular_lo and singular_hi:
        mid = 0.5 * (lo + hi)
        _add_singular(kind, prm, geo, c, lo, mid, True, k, b_lo, dt, h, hm)
        _add_singular(kind, prm, geo, c, mid, hi, False, k, b_lo, dt, h, hm)
    elif singular_lo or singular_hi:
        _add_singular(kind, prm, geo, c, lo, hi, singular_lo, k, b_lo, dt, h, hm)
    else:
        span = hi - lo
        for j in range(2):
            t = lo + span * _GL_X[j]
            _add_node(kind, prm, geo, c, t, _GL_W[j] * span, k, b_lo, dt, h, hm)


_EXACT_BINS = 3
"""Bins this close to a breakpoint of the closed form are integrated by quadrature."""
_INTERPOLATED_BINS = 8
"""From this many bins away from every breakpoint, every other centre value is interpolated."""


@_jit_inline
def _bins_to_breakpoint(k, marks, nb):
    """Bins from bin ``k`` to the nearest of the ``nb`` breakpoint bins ``marks``."""
    d = abs(k - marks[0])
    for i in range(1, nb):
        d = min(d, abs(k - marks[i]))
    return d


@_jit
def _bin_sir(kind, prm, geo, c, bps, nb, t0, dt, h, hm, work):
    """Quadratic B-spline coefficients of h [m/s] and h_m [m/s] on a grid of spacing ``dt``.

    Coefficient k is (1/Δ)∫ h(t) N(t/Δ − k) dt with N the uniform quadratic B-spline
    centred on bin k = [t0 + kΔ, t0 + (k+1)Δ): a smoothing projection whose transform is
    sinc³(fΔ), so the aliases of the (not band-limited) SIR fall off as sinc³ and the
    projection itself is undone exactly in the frequency domain.  ``geo`` holds the
    sample's geometry (see :func:`_sample_geometry`); ``bps[:nb]`` are the breakpoints of
    the closed form in increasing order (see :func:`breakpoints`): the support is
    [bps[0], bps[nb − 1]].  Two rules, one per kind of coefficient:

    * within :data:`_EXACT_BINS` bins of a breakpoint, every smooth piece of every bin is
      integrated by :func:`_add_piece` (Gauss–Legendre, √-substitution at a breakpoint);
    * elsewhere h is smooth over the B-spline's support and its moments give
      (1/Δ)∫ h N = h(tₖ) + Δ²h″(tₖ)/8 + O(Δ⁴h⁗), tₖ the bin centre: the coefficient is
      h(tₖ) + (h(tₖ₊₁) − 2h(tₖ) + h(tₖ₋₁))/8, in error by 0.004·Δ⁴|h⁗|, with one
      evaluation of the closed form per bin.  Next to a √-type breakpoint that error is
      0.003·d⁻⁴ of h at d bins from it (10⁻⁵ at the first such bin, d = 4).  From
      :data:`_INTERPOLATED_BINS` bins on, the centre values of odd bins are the cubic
      interpolant of their even neighbours, (9(hₖ₋₁ + hₖ₊₁) − hₖ₋₃ − hₖ₊₃)/16, in error by
      0.375·Δ⁴|h⁗| (0.35·d⁻⁴ of h next to a √-breakpoint: 9·10⁻⁵ at d = 8).

    ``work`` is scratch ``(2, ≥ K)``.  Writes coefficients k0 − 1 … k0 + K to
    ``h[0 : K + 2]`` and ``hm[0 : K + 2]`` and returns (k0 − 1, K + 2)."""
    t_lo = bps[0]
    t_hi = bps[nb - 1]
    k0 = int(math.floor((t_lo - t0) / dt))  # noqa: RUF046 (numba)
    k1 = int(math.floor((t_hi - t0) / dt))  # noqa: RUF046 (numba)
    n = min(k1 - k0 + 1, h.shape[0] - 2)
    marks = np.empty(nb, dtype=np.int64)  # the bin of each breakpoint
    for i in range(nb):
        bin_i = int(math.floor((bps[i] - t0) / dt)) - k0  # noqa: RUF046
        marks[i] = min(n - 1, max(0, bin_i))
    marks[nb - 1] = n - 1
    for i in range(n + 2):
        h[i] = 0.0
        hm[i] = 0.0
    vh = work[0]
    vhm = work[1]
    for k in range(n):
        d = _bins_to_breakpoint(k, marks, nb)
        b_lo = t0 + (k0 + k) * dt
        if d >= _EXACT_BINS - 1 and (d < _INTERPOLATED_BINS or k % 2 == 0):  # in use
            vh[k], vhm[k] = _values(kind, prm, geo, c, b_lo + 0.5 * dt)
        if d > _EXACT_BINS:
            continue
        b_hi = b_lo + dt
        for piece in range(nb - 1):
            p_lo = bps[piece]
            p_hi = bps[piece + 1]
            lo = max(b_lo, p_lo)
            hi = min(b_hi, p_hi)
            if hi <= lo:
                continue
            _add_piece(kind, prm, geo, c, lo, hi, lo == p_lo, hi == p_hi, k, b_lo, dt, h, hm)
    for k in range(_INTERPOLATED_BINS + 1, n - _INTERPOLATED_BINS, 2):  # odd, far inside
        if _bins_to_breakpoint(k, marks, nb) >= _INTERPOLATED_BINS:
            vh[k] = (9.0 * (vh[k - 1] + vh[k + 1]) - vh[k - 3] - vh[k + 3]) / 16.0
            vhm[k] = (9.0 * (vhm[k - 1] + vhm[k + 1]) - vhm[k - 3] - vhm[k + 3]) / 16.0
    # coefficient j is centred on bin j − 1: smooth when no breakpoint lies within _EXACT_BINS − 1
    for j in range(_EXACT_BINS + 1, n + 1 - _EXACT_BINS):
        if _bins_to_breakpoint(j - 1, marks, nb) < _EXACT_BINS:
            continue
        h[j] = vh[j - 1] + 0.125 * (vh[j] - 2.0 * vh[j - 1] + vh[j - 2])
        hm[j] = vhm[j - 1] + 0.125 * (vhm[j] - 2.0 * vhm[j - 1] + vhm[j - 2])
    return k0 - 1, n + 2


@_jit_inline
def _support_disc(c, r, z, a):
    """(t_lo, t_mid, t_hi) [s]: start, end of the full-circle part, end of the SIR."""
    lo = math.sqrt(z * z + max(r - a, 0.0) ** 2) / c
    mid = math.sqrt(z * z + (a - r) ** 2) / c if r < a else lo
    hi = math.sqrt(z * z + (r + a) ** 2) / c
    return lo, mid, hi


@_jit_inline
def _support_bowl(c, rf, d, beta, tmax):
    """(t_lo, t_mid, t_hi) [s] of a bowl: ρ(ψ) = √(R_f² + D² − 2R_f D cosψ) at the breaks."""
    psi_lo = max(0.0, beta - tmax)
    psi_mid = max(psi_lo, tmax - beta)
    psi_hi = min(math.pi, beta + tmax)
    lo = math.sqrt(max(rf * rf + d * d - 2.0 * rf * d * math.cos(psi_lo), 0.0)) / c
    mid = math.sqrt(max(rf * rf + d * d - 2.0 * rf * d * math.cos(psi_mid), 0.0)) / c
    hi = math.sqrt(max(rf * rf + d * d - 2.0 * rf * d * math.cos(psi_hi), 0.0)) / c
    return lo, max(lo, mid), hi


@_jit_inline
def _insert_time(bps, nb, c, z2, sigma):
    """Insert the time √(σ² + z²)/c of the in-plane radius ``sigma`` into the sorted
    ``bps[:nb]``; return the new count."""
    t = math.sqrt(sigma * sigma + z2) / c
    i = nb
    while i > 0 and bps[i - 1] > t:
        bps[i] = bps[i - 1]
        i -= 1
    bps[i] = t
    return nb + 1


@_jit_inline
def _breakpoints_rect(c, x, y, z, ax, ay, bps):
    """Fill ``bps`` with the sorted breakpoints [s] of a rectangle's SIR seen from
    (x, y, z): the start (the nearest point of the rectangle), the radii σ at which the
    circle about (x, y) becomes tangent to an edge's line or passes a corner, and the end
    (the farthest corner); return their count."""
    gx = max(0.0, -ax - x, x - ax)
    gy = max(0.0, -ay - y, y - ay)
    s_lo = math.sqrt(gx * gx + gy * gy)
    fx = abs(x) + ax
    fy = abs(y) + ay
    s_hi = math.sqrt(fx * fx + fy * fy)
    z2 = z * z
    bps[0] = math.sqrt(s_lo * s_lo + z2) / c
    nb = 1
    for i in range(4):
        side = ax if i < 2 else ay
        along = x if i < 2 else y
        edge = abs(along - side) if i % 2 == 0 else abs(along + side)
        if s_lo < edge < s_hi:
            nb = _insert_time(bps, nb, c, z2, edge)
    for i in range(4):
        u = ax if i == 0 or i == 3 else -ax
        v = ay if i == 0 or i == 2 else -ay
        corner = math.sqrt((u - x) ** 2 + (v - y) ** 2)
        if s_lo < corner < s_hi:
            nb = _insert_time(bps, nb, c, z2, corner)
    bps[nb] = math.sqrt(s_hi * s_hi + z2) / c
    return nb + 1


@_jit_inline
def breakpoints(kind, prm, geo, c, tmax, bps):
    """Fill ``bps`` (length ≥ :data:`MAX_BREAKPOINTS`) with the breakpoints [s] of the SIR
    of a sample whose geometry ``geo`` was filled by :func:`_sample_geometry`, in
    increasing order, and return their count: the support is [bps[0], bps[count − 1]]
    (``tmax`` [rad]: a bowl's half-aperture angle θmax)."""
    if kind == RECT:
        return _breakpoints_rect(c, geo[0], geo[1], geo[2], prm[1], prm[2], bps)
    if kind == DISC:
        lo, mid, hi = _support_disc(c, geo[0], geo[1], prm[0])
    else:
        lo, mid, hi = _support_bowl(c, prm[1], geo[0], math.acos(geo[1]), tmax)
    bps[0] = lo
    bps[1] = mid
    bps[2] = hi
    return 3


@_jit_inline
def _sample_geometry(kind, prm, x, y, z, mx, my, mz, geo):
    """Fill ``geo`` (length :data:`GEOMETRY_SIZE`) for a sample at (x, y, z) [m] (aperture
    frame: face centre or bowl apex at the origin, beam along +z; a rectangle's sides along
    x and y) with unit vector m; return False if it cannot contribute."""
    if kind == RECT:
        if z <= 0.0:
            return False
        geo[0] = x
        geo[1] = y
        geo[2] = z
        geo[3] = mx
        geo[4] = my
        geo[5] = mz
        return True
    if kind == DISC:
        if z <= 0.0:
            return False
        r = math.sqrt(x * x + y * y)
        geo[0] = r
        geo[1] = z
        geo[2] = (mx * x + my * y) / r if r > 0.0 else 0.0
        geo[3] = mz
        return True
    rf = prm[1]
    fx, fy, fz = x, y, z - rf  # x − F
    d = math.sqrt(fx * fx + fy * fy + fz * fz)
    if z <= 0.0:
        return False
    if d < 1e-9 * rf:  # at the geometric focus: every point of the bowl is R_f away
        fz = 1e-9 * rf  # a nanometre-scale offset keeps the closed form finite and exact
        d = fz

    ex, ey, ez = fx / d, fy / d, fz / d
    cos_beta = -ez  # u0 = (0, 0, −1): from the focus towards the apex
    sin_beta = math.sqrt(max(0.0, 1.0 - cos_beta * cos_beta))
    geo[0] = d
    geo[1] = cos_beta
    geo[2] = sin_beta
    geo[3] = mx * ex + my * ey + mz * ez
    if sin_beta > 1e-12:  # e₁ = (u0 − cosβ e)/sinβ
        e1x = (0.0 - cos_beta * ex) / sin_beta
        e1y = (0.0 - cos_beta * ey) / sin_beta
        e1z = (-1.0 - cos_beta * ez) / sin_beta
        geo[4] = mx * e1x + my * e1y + mz * e1z
    else:
        geo[4] = 0.0
    return True


@_jit
def accumulate_two_way(kind, prm, points, unit_m, weights, delays, c, t0, dt, grid, scratch):
    """Add Σₛ wₛ·(h̄ₛ * h̄_m,ₛ)(t)·Δ of every sample to ``grid`` (two-way times).

    Parameters
    ----------
    kind : :data:`DISC`, :data:`BOWL` or :data:`RECT`.
    prm : aperture parameters: ``(a, R_f, cos θmax)`` [m, m, 1] (R_f, cos θmax unused for a
        disc); a rectangle's ``(half-diagonal, half-width, half-height)`` [m].
    points : [m] samples in the aperture frame, shape ``(3, n)``.
    unit_m : unit vectors m (the surface normal pointing away from the probe), ``(3, n)``.
    weights : [m²·…] per-sample weights (area × reflection coefficient × normalization), ``(n,)``.
    delays : [s] per-sample two-way delays added to the geometric times, ``(n,)`` (zeros in
        the coupling medium; the interior's equivalent-path correction inside a part).
    c : [m/s] sound speed.
    t0 : [s] two-way time of grid point 0; grid point j is at t0 + jΔ.
    dt : [s] grid spacing Δ.
    grid : float64 ``(n_grid,)``, accumulated in place.
    scratch : float64 ``(5, 2·n_scratch)`` work space (one sample's SIR and correlation).

    Returns
    -------
    [s·weight] Σₛ |wₛ|·(two-way time of sample s) and Σₛ |wₛ| (for the mean path of the echo).
    """
    n = points.shape[1]
    n_grid = grid.shape[0]
    geo = np.zeros(GEOMETRY_SIZE)
    bps = np.zeros(MAX_BREAKPOINTS)
    t1 = 0.5 * t0  # one-way bins start at half the two-way origin, so bins p, q → p + q + 1
    tmax = math.acos(prm[2]) if kind == BOWL else 0.0
    h = scratch[0]
    hm = scratch[1]
    sum_wt = 0.0
    sum_w = 0.0
    for s in range(n):
        w = weights[s]
        if w == 0.0:
            continue
        x, y, z = points[0, s], points[1, s], points[2, s]
        if not _sample_geometry(kind, prm, x, y, z, unit_m[0, s], unit_m[1, s], unit_m[2, s], geo):
            continue
        nb = breakpoints(kind, prm, geo, c, tmax, bps)
        delay = delays[s]
        k0, nk = _bin_sir(kind, prm, geo, c, bps, nb, t1 - 0.5 * delay, dt, h, hm, scratch[3:5])
        base = 2 * k0 + 1
        scale = w * dt
        acc = scratch[2]
        for j in range(2 * nk - 1):
            acc[j] = 0.0
        for p in range(nk):
            hp = h[p] * scale
            if hp != 0.0:
                for q in range(nk):
                    acc[p + q] += hp * hm[q]
        j_lo = max(0, -base)
        j_hi = min(2 * nk - 1, n_grid - base)
        for j in range(j_lo, j_hi):
            grid[base + j] += acc[j]
        r_centre = math.sqrt(x * x + y * y + z * z)
        sum_wt += abs(w) * (2.0 * r_centre / c + delay)
        sum_w += abs(w)
    return sum_wt, sum_w


def scratch_bins(c: float, dt: float, extent: float) -> int:
    """Bins one sample's SIR can span: its support is at most 2·extent/c [s] (extent [m],
    the aperture's largest dimension), plus two for partial bins."""
    return math.ceil(2.0 * extent / (c * dt)) + 5


@_jit
def accumulate_one_way(kind, prm, points, weights, delays, c, t0, dt, grid, scratch):
    """Add Σₛ wₛ·h̄ₛ(t) of every point to ``grid``: the piston's own SIR h at each point,
    projected onto quadratic B-splines centred on the grid points (see :func:`_bin_sir`).

    The image form of the pulse-echo response over a plane integrates h over the probe's
    mirror image (``echocal.wave.image``): the points are the image face's quadrature nodes,
    whose distance from the probe is already the two-way path.

    Parameters
    ----------
    kind, prm, c, dt : as :func:`accumulate_two_way`.
    points : [m] points in the aperture frame, ``(3, n)``.
    weights : [m²·…] per-point weights (quadrature weight × reflection coefficient), ``(n,)``.
    delays : [s] per-point delays added to the points' times, ``(n,)``.
    t0 : [s] time of grid point 0; grid point j is at t0 + jΔ.
    grid : float64 ``(n_grid,)``, accumulated in place.
    scratch : float64 ``(4, n_scratch)`` work space.

    Returns
    -------
    [s·weight] Σₛ |wₛ|·(time of point s from the aperture's origin) and Σₛ |wₛ|.
    """
    n = points.shape[1]
    n_grid = grid.shape[0]
    geo = np.zeros(GEOMETRY_SIZE)
    bps = np.zeros(MAX_BREAKPOINTS)
    tmax = math.acos(prm[2]) if kind == BOWL else 0.0
    h = scratch[0]
    hm = scratch[1]
    sum_wt = 0.0
    sum_w = 0.0
    for s in range(n):
        w = weights[s]
        if w == 0.0:
            continue
        x, y, z = points[0, s], points[1, s], points[2, s]
        if not _sample_geometry(kind, prm, x, y, z, 0.0, 0.0, 1.0, geo):
            continue
        nb = breakpoints(kind, prm, geo, c, tmax, bps)
        delay = delays[s]
        # bins centred on the grid points: bin k = [t0 − Δ/2 + kΔ, t0 + Δ/2 + kΔ)
        origin = t0 - 0.5 * dt - delay
        k0, nk = _bin_sir(kind, prm, geo, c, bps, nb, origin, dt, h, hm, scratch[2:4])
        j_lo = max(0, -k0)
        j_hi = min(nk, n_grid - k0)
        for j in range(j_lo, j_hi):
            grid[k0 + j] += w * h[j]
        sum_wt += abs(w) * (math.sqrt(x * x + y * y + z * z) / c + delay)
        sum_w += abs(w)
    return sum_wt, sum_w
