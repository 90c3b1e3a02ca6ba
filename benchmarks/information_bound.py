"""A lower bound on the measurements of *any* search, from the information each one carries.

The optimum c is drawn from a prior; measurement i at x_i (chosen from everything seen
before, by any rule, randomized or not) observes Y_i, whose law depends on c only through
the echo's amplitude ν(|x_i − c|) (the probe's lobe): Y_i is the matched-filter envelope
at the echo, a Rice variable of ν and unit scale.  (The detector's peak is the larger of
it and the window's noise maximum, which is independent of c: by data processing that
carries less.)  An estimate ĉ within δ of c with probability P needs:

1. **Fano** (the continuous form: data processing on the indicator of |ĉ − c| ≤ δ, whose
   probability is at most π(δ) when ĉ is independent of c):
   kl(P ‖ π(δ)) ≤ I(c; Y₁ … Y_N), with π(r) the largest prior mass of a disc of radius r
   and kl the binary relative entropy.  The same holds for any function of the past,
   the next point x_i included: P(|x_i − c| ≤ r) ≤ q(I(c; Y₁ … Y_{i−1}), π(r)), where
   q(I, π) is the largest p with kl(p ‖ π) ≤ I.
2. **Chain rule** (adaptivity): I(c; Y₁ … Y_N) = Σᵢ I(c; Y_i | Y₁ … Y_{i−1}), and given the
   past, c → ν_i → Y_i, so each term is at most I(ν_i; Y_i | past).
3. **Zones**: with Z_i the zone of |x_i − c| among radii r₁ < … < r_K,
   I(ν_i; Y_i) ≤ H(Z_i) + Σ_k P(Z_i = k) C_k, where C_k is the capacity of the Rice
   channel with amplitude at most the lobe's largest value in zone k (the
   amplitude-constrained capacity, :func:`rice_capacity`).  The right side is concave in
   the zones' law, which (averaged over the past) satisfies P(Z_i ≤ k) ≤ q(I_{i−1}, π(r_k))
   by 1.  Its largest value F(I_{i−1}) under those constraints is bounded above by the
   Lagrange dual (:func:`zone_information`; any multipliers give an upper bound).

So I_N ≤ J_N with J₀ = 0, J_i = J_{i−1} + F(J_{i−1}) (F increases with I, so the
recursion bounds every search), and N measurements can succeed with probability at most
q(J_N, π(δ)) (:func:`information_bound`).  This counts what a measurement *can* say
once it lands on the lobe (at 30 dB, ν ≈ 330 at the optimum: up to 4.4 nats, the ring
|x − c| to a few hundredths of a degree) and is weak where the difficulty is finding
the lobe, so a second bound:

4. **Change of measure** (as in the lower bounds of bandit theory).  Compare the world
   with the world Q where every measurement is noise alone (ν = 0), the same search
   running in both.  Let τ be the first measurement within r of the optimum.  Up to τ
   every measurement is farther than r, so its value's law differs from Q's by at most
   D_r = D(Rice(ν_r) ‖ Rayleigh) (ν_r the lobe's largest beyond r;
   :func:`rice_divergence`), and the history stopped at τ or N differs by at most
   N · D_r.  The event "a measurement came within r, or the estimate is within δ" is
   decided by that history; under Q the points are independent of the optimum, so its
   chance there is at most M_N(r) + π(δ), M_N(r) the most prior mass n points can hold
   within r of themselves (a covering programme).  By data processing,
   kl(P ‖ M_N(r) + π(δ)) ≤ N · D_r for every r (:func:`hit_bound`).

Nothing here assumes how the search reads its values or places its points: both hold for
a search that acts on threshold detections and for one that reads every value below the
threshold too, adaptive or not, knowing the probe or not.  They assume the noise model
(the Rice envelope of white Gaussian noise, independent between measurements; the
waveform's shape and carrier phase carry nothing about the tilt beyond the amplitude)
and the lobe's amplitudes ν(θ).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from scipy.optimize import minimize
from scipy.special import i0e, logsumexp

_BA_UP_TO = 30.0
"""Amplitudes up to which :func:`rice_capacity` runs Blahut–Arimoto (0.3 s at 30)."""

__all__ = [
    "blahut_arimoto",
    "disc_mass",
    "hit_bound",
    "information_bound",
    "kl_bernoulli",
    "largest_probability",
    "rice_capacity",
    "rice_divergence",
    "search_bound",
    "zone_information",
    "zone_step",
]


def kl_bernoulli(p: float, q: float) -> float:
    """[nats] kl(p ‖ q) = p ln(p/q) + (1 − p) ln((1 − p)/(1 − q)), with 0 ln 0 = 0."""
    out = 0.0
    if p > 0.0:
        out += p * math.log(p / q) if q > 0.0 else math.inf
    if p < 1.0:
        out += (1.0 - p) * math.log((1.0 - p) / (1.0 - q)) if q < 1.0 else math.inf
    return out


def largest_probability(info: float, mass: float) -> float:
    """q(I, π): the largest p ∈ [π, 1] with kl(p ‖ π) ≤ ``info`` [nats] (π = ``mass``):
    the highest chance with which an estimate made from ``info`` nats can land in a set
    of prior mass π.  Bisection to 1e-12, rounded up."""
    if mass >= 1.0 or kl_bernoulli(1.0, mass) <= info:
        return 1.0
    lo, hi = mass, 1.0
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if kl_bernoulli(mid, mass) <= info else (lo, mid)
    return hi


def blahut_arimoto(w: np.ndarray, *, tol: float = 1e-6, max_iter: int = 5000) -> float:
    """[nats] an upper bound on the capacity of the discrete channel ``w`` (shape
    (inputs, outputs), rows summing to 1): Blahut–Arimoto on the input law, stopped when
    its upper bound max_x D(w_x ‖ q) and its lower bound I(p; w) differ by < ``tol``;
    returns the upper bound (any output law q gives one)."""
    w = np.asarray(w, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_w = np.where(w > 0.0, np.log(w), 0.0)
    row_entropy = -(w * log_w).sum(axis=1)
    p = np.full(len(w), 1.0 / len(w))
    upper = math.inf
    for _ in range(max_iter):
        q = p @ w
        with np.errstate(divide="ignore"):
            log_q = np.where(q > 0.0, np.log(q), 0.0)
        d = -row_entropy - w @ log_q  # D(w_x ‖ q) per input
        upper = float(d.max())
        lower = float(p @ d)
        if upper - lower < tol:
            break
        p = p * np.exp(d - upper)
        p /= p.sum()
    return upper


def _rice_rows(amplitudes: np.ndarray, t_step: float) -> np.ndarray:
    """The Rice law of unit scale for each amplitude, binned on t ∈ [0, max + 10) in
    steps of ``t_step`` (midpoint rule, rows renormalized), shape (len(amplitudes), bins)."""
    t = (np.arange(math.ceil((amplitudes.max() + 10.0) / t_step)) + 0.5) * t_step
    nu = amplitudes[:, None]
    rows = t * np.exp(-0.5 * (t - nu) ** 2) * i0e(t * nu)
    return rows / rows.sum(axis=1, keepdims=True)


def rice_capacity(amplitude: float, *, nu_step: float = 0.25, t_step: float = 0.05) -> float:
    """[nats] the capacity of the Rice channel t ~ Rice(ν, 1) over amplitudes ν in
    [0, ``amplitude``] (noise's Rayleigh scale units): the most one envelope reading can
    say about anything that sets ν no larger than that.

    The least of two upper bounds.  (a) The envelope is a function of the echo's
    in-phase component ν + n₁ and the independent quadrature n₂, so it says at most what
    ν + n₁ says: the real Gaussian channel with input in an interval of length A, whose
    capacity is at most ln(1 + A/√(2πe)) (McKellips, 2004).  (b) Up to
    :data:`_BA_UP_TO`, :func:`blahut_arimoto` on inputs ``nu_step`` apart (ν's law at
    capacity has a few mass points) and outputs ``t_step`` apart (the binned channel:
    at 0.05, the value moves by < 1e-3 nats with half the step).  Above it (a) is within
    about 0.03 nats of (b) and (b) slow to converge."""
    if amplitude <= 0.0:
        return 0.0
    gaussian = math.log1p(amplitude / math.sqrt(2.0 * math.pi * math.e))
    if amplitude > _BA_UP_TO:
        return gaussian
    n = max(2, math.ceil(amplitude / nu_step) + 1)
    return min(gaussian, blahut_arimoto(_rice_rows(np.linspace(0.0, amplitude, n), t_step)))


def zone_information(bounds: Sequence[float], capacities: Sequence[float]) -> float:
    """[nats] an upper bound on max H(P) + Σ_k P_k C_k over laws P of K + 1 zones with
    P_0 + … + P_k ≤ ``bounds[k]`` (k < K; increasing) and ``capacities`` C_0 … C_K
    (module docstring, item 3).  By the Lagrange dual: for multipliers μ ≥ 0 it is at most
    ln Σ_j exp(C_j − Σ_{k≥j} μ_k) + Σ_k μ_k b_k; the multipliers are optimized (L-BFGS-B)
    and the dual's value at them returned — a bound whatever the optimizer reaches."""
    b = np.asarray(bounds, dtype=np.float64)
    c = np.asarray(capacities, dtype=np.float64)
    if len(c) != len(b) + 1:
        raise ValueError(f"capacities need one more entry than bounds; got {len(c)}, {len(b)}")

    def dual(mu: np.ndarray) -> tuple[float, np.ndarray]:
        tail = np.r_[np.cumsum(mu[::-1])[::-1], 0.0]  # Σ_{k≥j} μ_k per zone j
        e = c - tail
        value = float(logsumexp(e)) + float(mu @ b)
        weights = np.exp(e - logsumexp(e))
        grad = b - np.cumsum(weights)[:-1]  # ∂/∂μ_k = b_k − Σ_{j≤k} P_j
        return value, grad

    if len(b) == 0:
        return float(logsumexp(c))
    res = minimize(
        dual, np.zeros(len(b)), jac=True, method="L-BFGS-B", bounds=[(0.0, None)] * len(b)
    )
    return dual(np.maximum(res.x, 0.0))[0]


def zone_step(masses: Sequence[float], capacities: Sequence[float]) -> Callable[[float], float]:
    """F(J) of item 3 (module docstring): given J nats so far, at most what the next
    measurement says — the smallest of :func:`zone_information` over all the zones at
    once, over each radius alone and over none (the largest capacity; every partition
    gives a bound).  ``masses``: π(r_k) for the zones' radii r₁ < … < r_K;
    ``capacities``: C_0 … C_K [nats], the most one measurement says when the optimum is in
    zone k (θ ≤ r₁, r₁ < θ ≤ r₂, …, θ > r_K)."""
    masses, caps = list(masses), list(capacities)

    def step(info: float) -> float:
        b = [largest_probability(info, m) for m in masses]
        out = min(max(caps), zone_information(b, caps))
        for k in range(len(masses)):  # one radius: zones θ ≤ r_k and θ > r_k
            out = min(out, zone_information([b[k]], [max(caps[: k + 1]), max(caps[k + 1 :])]))
        return out

    return step


def information_bound(
    success: float,
    success_mass: float,
    steps: Sequence[Callable[[float], float]],
    *,
    max_n: int = 100_000,
) -> tuple[int, np.ndarray]:
    """The fewest measurements any search needs to succeed with probability ``success``,
    and the information bounds J₀, J₁, … [nats] up to it (module docstring).

    ``success_mass``: π(δ), the largest prior mass of a success region (a disc of radius
    δ); ``steps``: bounds F(J) on what the next measurement says after J nats
    (:func:`zone_step`), of which the least is used (each
    bounds the true F, which increases with J, so J_i = J_{i−1} + min F(J_{i−1}) bounds
    I_i by induction).  ``max_n + 1`` when J has not reached the need by then."""
    need = kl_bernoulli(success, success_mass) if success > success_mass else 0.0
    j = [0.0]
    while j[-1] < need:
        if len(j) > max_n:
            return max_n + 1, np.asarray(j)
        j.append(j[-1] + min(f(j[-1]) for f in steps))
    return len(j) - 1, np.asarray(j)


def disc_mass(
    radius: float, band: tuple[float, float], *, n_rho: int = 2001, n_centre: int = 801
) -> float:
    """The largest prior mass of a disc of ``radius`` [deg] for an optimum at a distance
    uniform in ``band`` [deg] from the start in a uniform direction: the disc's share of
    each circle (arccos of the law of cosines, / π) averaged over the band, maximized over
    the disc's distance from the start on ``n_centre`` points, plus the most the mass can
    change between them (the disc's rim 2πr times the largest density 1/(2π R₁ (R₂ − R₁))
    times half the spacing), and never above the area bound r² / (2 R₁ (R₂ − R₁)) or 1."""
    lo, hi = band
    area = radius**2 / (2.0 * lo * (hi - lo)) if lo > 0.0 else math.inf
    rho = np.linspace(lo, hi, n_rho)[None, :]
    centre = np.linspace(0.0, hi + radius, n_centre)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        cos_edge = (rho**2 + centre**2 - radius**2) / (2.0 * rho * centre)
    cos_edge = np.where(centre > 0.0, cos_edge, np.where(rho <= radius, -1.0, 1.0))
    share = np.arccos(np.clip(cos_edge, -1.0, 1.0)) / np.pi
    exact = float(np.trapezoid(share, rho, axis=1).max()) / (hi - lo)
    slack = radius / (lo * (hi - lo)) * 0.5 * (hi + radius) / (n_centre - 1) if lo > 0 else 0.0
    return min(1.0, area, exact + slack)


def rice_divergence(amplitude: float, *, t_step: float = 1e-3) -> float:
    """[nats] D(Rice(ν, 1) ‖ Rayleigh(1)) for ν = ``amplitude``: how much one envelope
    reading tells an echo of that amplitude from noise, E[tν − ν²/2 + ln I₀(tν)] under
    the Rice law (midpoint rule on t, ``t_step`` apart, out to ν + 12)."""
    if amplitude <= 0.0:
        return 0.0
    t = (np.arange(math.ceil((amplitude + 12.0) / t_step)) + 0.5) * t_step
    log_ratio = t * amplitude - 0.5 * amplitude**2 + np.log(i0e(t * amplitude))
    f = t * np.exp(-0.5 * (t - amplitude) ** 2) * i0e(t * amplitude)
    return float(f @ log_ratio / f.sum())


def hit_bound(
    success: float,
    success_mass: float,
    divergences: Sequence[float],
    cover: Callable[[int, int], float],
    *,
    max_n: int = 10_000,
) -> int:
    """The fewest measurements N any search needs to succeed with probability ``success``
    by the change of measure (item 4 of the module docstring): for every radius r_k,
    kl(success ‖ min(1, cover(k, N) + π(δ))) ≤ N · D_k or success ≤ that mass.

    ``success_mass``: π(δ); ``divergences``: D_k [nats], the most one measurement farther
    than r_k from the optimum tells the echo from noise; ``cover(k, n)``: at most the
    prior mass within r_k of n points chosen without seeing the echo."""
    for n in range(1, max_n + 1):
        ok = True
        for k, d in enumerate(divergences):
            mass = min(1.0, cover(k, n) + success_mass)
            if success > mass and kl_bernoulli(success, mass) > n * d:
                ok = False
                break
        if ok:
            return n
    return max_n + 1


def search_bound(
    angles: np.ndarray,
    amplitude: np.ndarray,
    band: tuple[float, float],
    cover: Callable[[float, int], float],
    *,
    tolerance: float = 0.1,
    success: float = 0.99,
    zone_step_deg: float = 0.25,
    hit_step_deg: float = 0.25,
) -> tuple[int, int]:
    """The fewest measurements any search needs to bring its estimate within
    ``tolerance`` [deg] of an optimum at a distance uniform in ``band`` [deg] from the
    start (uniform direction) with probability ``success``: (the information recursion,
    items 1–3; the change of measure, item 4) — each a bound, so their larger one is.

    ``amplitude``: ν(θ), the echo's matched-envelope peak in units of the noise's Rayleigh
    scale at the misalignments ``angles`` [deg] (increasing from 0; the largest over the
    lobe's directions), taken as its largest sample from the one at or before each radius
    on (the lobe between two samples is at most the larger) and as its last sample
    beyond the last angle.  ``cover(r, n)``: at
    most the prior mass within r [deg] of n points placed independently of the optimum.
    Zones every ``zone_step_deg``, radii of item 4 every ``hit_step_deg`` degrees out
    to the last angle; item 3's capacities from a table of :func:`rice_capacity` at
    amplitudes 2 % apart (each zone takes the table's next larger entry: capacity grows
    with the amplitude)."""
    angles = np.asarray(angles, dtype=np.float64)
    tail = np.maximum.accumulate(np.asarray(amplitude, dtype=np.float64)[::-1])[::-1]

    def beyond(radii: np.ndarray) -> np.ndarray:
        # from the last sample at or before each radius: the lobe between samples is
        # taken as at most its larger neighbour
        return tail[np.clip(np.searchsorted(angles, radii, side="right") - 1, 0, len(angles) - 1)]

    success_mass = disc_mass(tolerance, band)
    radii = np.arange(zone_step_deg, float(angles[-1]) + 1e-9, zone_step_deg)
    # zone k (r_{k-1} < θ ≤ r_k, r_0 = 0; the last θ > r_K): ν ≤ its largest beyond r_{k-1}
    zone_nu = np.r_[tail[0], beyond(radii)]
    table = np.geomspace(1e-3, max(float(tail[0]), 1e-3) * 1.02, 400)
    slot = np.minimum(np.searchsorted(table, zone_nu), len(table) - 1)
    known = {int(i): rice_capacity(float(table[i])) for i in np.unique(slot)}
    masses = [disc_mass(float(r), band) for r in radii]
    info_n, _ = information_bound(
        success, success_mass, [zone_step(masses, [known[int(i)] for i in slot])]
    )
    hit_radii = np.arange(hit_step_deg, float(angles[-1]) + 1e-9, hit_step_deg)
    divergences = [rice_divergence(float(v)) for v in beyond(hit_radii)]
    hit_n = hit_bound(
        success, success_mass, divergences, lambda k, n: cover(float(hit_radii[k]), n)
    )
    return info_n, hit_n
