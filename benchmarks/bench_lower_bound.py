"""How many measurements must a blind search spend — and how many ``auto`` spends.

For a probe, an SNR and a band of start distances, this benchmark prints two **lower
bounds** on the measurements a search needs to reach 0.1° from the optimum in 99 % of the
runs, beside what ``auto`` achieves on the same starts: the *detection bound* (items 1–3
below), which holds for searches that act on threshold detections, and the *any-search
bound* (:mod:`information_bound`), which holds for every search — adaptive, reading every
value below the threshold, knowing the probe — under the Rice noise model.

The bound, and the searches it holds for:

1. The detection probability p(θ) of one measurement θ from the optimum is *measured*
   (``detection_range.detection_curves``: noise draws in 8 directions, the acquisition
   phase's matched-filter detector at g > 4.5).
2. The benchmark's optimum lies at a distance ρ uniform in the band [R₁, R₂] around the
   start, in a uniform direction.  A search that chooses each point from the detections
   so far (whether a measurement had g > 4.5) measures a fixed sequence m₁, m₂, … until
   its first detection, so within N measurements it detects an optimum at x with
   probability 1 − Πᵢ (1 − p(|x − mᵢ|)) ≤ min(1, Σᵢ p(|x − mᵢ|)) (the union bound; noise
   is independent).  Averaged over the optimum's direction (min(1, ·) is concave), this is
   at most min(1, Σᵢ P̄(ρ, sᵢ)), where sᵢ = |mᵢ| and P̄(ρ, s) is p averaged over the angle
   between a point at distance ρ and one at s (:func:`ring_kernel`).  So only the
   measurements' distances from the start matter, and N must satisfy

       (1 / (R₂ − R₁)) ∫ min(1, Σᵢ P̄(ρ, sᵢ)) dρ ≥ 0.99          (ρ from R₁ to R₂)

   for some s₁ … s_N — whatever the order of the points and whatever the search does
   after a detection. The fewest such N is bounded below by a linear programme
   (:func:`covering_bound`: counts per cell of s — 0.1°, or 1/50 of the 90 % detection
   radius where that is less — relaxed to real numbers, P̄ taken at its largest over
   each cell and each bin of ρ, so any real search is a feasible point) — the covering
   optimized over the band the benchmark draws from, edges included. It replaces the
   area bound N ≥ 0.99 · A / K (A = π(R₂² − R₁²), K = 2π ∫ p(θ) θ dθ, the area one
   measurement "sees"), still printed: that one integrates p over the whole plane, so it
   ignores what the band's edges waste, and it asks 0.99 at every point of the annulus,
   not on average over the benchmark's starts (whose distance, not area, is uniform) —
   at 10 dB it was *above* the programme's bound, so it did not hold for the benchmark's
   99 %. A search that also reads the values below the threshold places later points
   better than a fixed sequence can: for it this bound is a reference, not a proof, and a
   ratio below 1 is no contradiction (``auto`` is one: beyond x0's first ring it follows
   the posterior over the optimum, which every significance updates,
   ``echocal.calibrate.posterior_search``); the any-search bound covers it. p is taken
   as measured up
   to ``--max-angle`` and 0 beyond (choose it where p has fallen to the false-alarm
   level).
3. Once detected, reaching 0.1° needs at least 3 more measurements: a lobe of known
   shape still has three unknowns (two angles and the amplitude).  This is the count of
   the unknowns, a convention rather than a proof: the detecting value is one equation
   of the three, and a noisy climb from the lobe's tail needs more.

So N_bound = ⌈LP⌉ + 3.  It is a bound, not a design.  Beside it: the hexagonal
lattice whose every point lies within the 90 % (and the 99 %) detection radius of a
measurement (``detection_range.cover``), what a simple non-adaptive search spends to be
that sure of one detection (+3 to refine for the 99 % one): a design, an upper
reference.  And the best hexagonal lattice (:func:`lattice_search`: spacing optimized,
points chosen greedily, each measurement's soft detection p(θ) counted, not just its
radius) that detects 99 % of the optima in the band, + 3: what an optimized
non-adaptive covering spends — a design again, the bound's counterpart from above.

The any-search bound (:func:`information_bound.search_bound`) is the larger of two, each
derived in :mod:`information_bound`: the information recursion (Fano's inequality, the
chain rule over the measurements, the capacity of the Rice channel at the amplitude the
lobe has at each distance, capped by how likely a point lands near the optimum given
what is known so far) and the change of measure (until a measurement comes within r of
the optimum, every value is within D(Rice(ν_r) ‖ Rayleigh) nats of noise; a search that
has not come within r cannot place its estimate better than by chance, and N points
placed by chance hold at most a covering programme's share of the optima within r).  It
reads the lobe's noiseless matched-envelope peak ν(θ) (the setup's cached lobe profile,
the largest over its directions) against white noise at the stated SNR.

``auto`` runs through :mod:`bench_calibration` (the same seeds, starts and budget of 80 as
the calibration benchmark: uniform distance in the band, uniform direction; ``--budget``
allows more, for a cell whose bound is beyond 80).  Reported: the
fraction within 0.1° after 60 measurements, the median / 90th / 99th percentile of the
measurements after which the estimate stays within 0.1° (``>80`` where runs never got
there), the median measurements the acquisition phase spent before handing over, and the
ratio of the 99th percentile to the bound::

    python benchmarks/bench_lower_bound.py                       # immersion-5mhz, 30 dB
    python benchmarks/bench_lower_bound.py --snr 30,10 --runs 100 \\
        --out-md docs/benchmarks/lower-bound.md
    python benchmarks/bench_lower_bound.py --smoke               # seconds (CI)
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy is imported

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from multiprocessing import get_context  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from _calibration_cases import BUDGET, CASES, GATED_CASES, STARTS  # noqa: E402
from _common import machine_info, markdown_table  # noqa: E402
from bench_calibration import measurements_to, run_one  # noqa: E402
from detection_range import cover, detection_curves, radius  # noqa: E402
from information_bound import search_bound  # noqa: E402
from scipy import sparse  # noqa: E402
from scipy.optimize import linprog  # noqa: E402

from echocal.calibrate.acquisition import hex_spiral  # noqa: E402
from echocal.io import atomic_write_text  # noqa: E402
from echocal.measurement.detection_radius import cached_lobe_profile  # noqa: E402
from echocal.setups import load_setup  # noqa: E402
from echocal.signal.detection import shared_detector  # noqa: E402
from echocal.signal.noise import noise_sigma_for_snr  # noqa: E402

DETECTOR = "matched-filter peak"
"""The acquisition phase's detector (``EchoDetector``: significance g > 4.5)."""
SUCCESS = 0.99
REFINE_UNKNOWNS = 3
"""Measurements a detected lobe of known shape still needs: two angles and the amplitude."""
TOLERANCE = 0.1
AT = 60
BOUND_CELL = 0.1
"""[deg] the covering programme's widest cell of distance (and bin of ρ)."""
MAX_LATTICE = 150
"""The best lattice is searched only where the r90 lattice has at most this many points
(the greedy choice costs points² × samples: at 10 dB, ~780 points, it would take hours)."""


def seen_area(angles: np.ndarray, prob: np.ndarray) -> float:
    """[deg²] K = 2π ∫ p(θ) θ dθ (trapezoid on the measured angles, p = 0 beyond)."""
    return float(2.0 * np.pi * np.trapezoid(prob * angles, angles))


def area_bound(band: tuple[float, float], k: float, success: float = SUCCESS) -> int:
    """The area bound (the module docstring's item 2): measurements a search that acts on
    detections needs to detect the echo with probability ``success`` at every point of the
    annulus ``band`` [deg], each seeing ``k`` [deg²] of the whole plane.  Printed beside
    :func:`covering_bound`, which replaces it."""
    lo, hi = band
    return math.ceil(success * math.pi * (hi**2 - lo**2) / k)


def bound_cell(r90: float) -> float:
    """[deg] the programme's cell: 1/50 of the 90 % detection radius ``r90``, at most
    :data:`BOUND_CELL` (which is also the cell when ``r90`` is 0)."""
    return min(BOUND_CELL, r90 / 50.0) if r90 > 0.0 else BOUND_CELL


def ring_kernel(
    rho: np.ndarray, s: np.ndarray, angles: np.ndarray, prob: np.ndarray, *, n_phi: int = 129
) -> np.ndarray:
    """P̄(ρ, s): the detection probability of one measurement at distance ``s`` [deg] from
    the start for an optimum at distance ``rho`` [deg], averaged over the angle between
    them — p(θ) (``prob`` at ``angles`` [deg], linear between, 0 beyond) on the distance
    θ = √(ρ² + s² − 2ρs cos φ), by the trapezoid over ``n_phi`` angles φ from 0 to where θ
    passes the last angle.  Returns shape (len(rho), len(s))."""
    far = float(angles[-1])  # p = 0 beyond the last measured angle
    rho, s = np.asarray(rho, float), np.asarray(s, float)
    out = np.zeros((len(rho), len(s)))
    t = np.linspace(0.0, 1.0, n_phi)
    for start in range(0, len(rho), 32):  # rows in chunks: (32, len(s), n_phi) at a time
        r = rho[start : start + 32, None, None]
        near = np.flatnonzero(np.abs(s - rho[start : start + 32, None]).min(axis=0) <= far)
        d = s[None, near, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_edge = np.where(r * d > 0.0, (r**2 + d**2 - far**2) / (2.0 * r * d), -1.0)
        phi_edge = np.arccos(np.clip(cos_edge, -1.0, 1.0))  # p = 0 beyond: the arc that sees
        theta = np.sqrt(np.maximum(r**2 + d**2 - 2.0 * r * d * np.cos(phi_edge * t), 0.0))
        seen = np.trapezoid(np.interp(theta, angles, prob, right=0.0), axis=-1)
        out[start : start + 32, near] = seen * phi_edge[..., 0] / ((n_phi - 1) * np.pi)
    return out


def _cell_max(values: np.ndarray, fine: int, axis: int) -> np.ndarray:
    """The largest of each run of ``fine`` + 1 samples along ``axis`` (consecutive runs
    share their end sample): a cell's maximum from its samples, edges included."""
    v = np.moveaxis(values, axis, 0)
    n = (v.shape[0] - 1) // fine
    body = v[:-1].reshape(n, fine, *v.shape[1:]).max(axis=1)
    return np.moveaxis(np.maximum(body, v[fine::fine]), 0, axis)


def _cell_kernel(
    band: tuple[float, float], angles: np.ndarray, prob: np.ndarray, cell: float, fine: int
) -> np.ndarray:
    """P̄⁺: the largest :func:`ring_kernel` value over each bin of ρ in ``band`` × cell of
    s (both ``cell`` [deg] wide, s out to R₂ + the last angle), sampled ``fine`` times per
    side, edges included; shape (bins, cells)."""
    lo, hi = band
    n_rho = max(1, math.ceil((hi - lo) / cell))
    n_s = math.ceil((hi + float(angles[-1])) / cell)
    rho = np.linspace(lo, hi, n_rho * fine + 1)
    s = np.linspace(0.0, n_s * cell, n_s * fine + 1)
    return _cell_max(_cell_max(ring_kernel(rho, s, angles, prob), fine, 0), fine, 1)


def reach_kernel(band: tuple[float, float], reach: float, *, cell: float = 0.25) -> np.ndarray:
    """P̄⁺ (:func:`_cell_kernel`) for "within ``reach`` [deg]" (1 up to it, falling
    linearly to 0 over the next 1e-3°: a superset, so a bound from it holds), for optima
    at a distance uniform in ``band`` [deg]; ``cell`` [deg]: any width gives a bound (P̄⁺
    is the largest over each cell), finer is tighter."""
    angles = np.array([0.0, reach, reach + 1e-3])
    return _cell_kernel(band, angles, np.array([1.0, 1.0, 0.0]), cell, 2)


def covered_mass(kernel: np.ndarray, n: int) -> float:
    """At most the prior mass within reach of ``n`` points placed independently of the
    optimum, for the :func:`reach_kernel` ``kernel``: the programme of
    :func:`covering_bound` turned round (maximize mean(y) subject to Σ w ≤ n)."""
    n_rho, n_s = kernel.shape
    rows = sparse.hstack([-sparse.csr_array(kernel), sparse.eye_array(n_rho)])
    budget_row = sparse.hstack([sparse.csr_array(np.ones((1, n_s))), sparse.csr_array((1, n_rho))])
    res = linprog(
        np.r_[np.zeros(n_s), np.full(n_rho, -1.0 / n_rho)],
        A_ub=sparse.vstack([rows, budget_row]).tocsr(),
        b_ub=np.r_[np.zeros(n_rho), float(n)],
        bounds=[(0.0, None)] * n_s + [(0.0, 1.0)] * n_rho,
        method="highs",
    )
    if res.status != 0:
        raise RuntimeError(f"covered-mass programme: {res.message}")
    return float(-res.fun)


def covering_bound(
    band: tuple[float, float],
    angles: np.ndarray,
    prob: np.ndarray,
    success: float = SUCCESS,
    *,
    cell: float | None = None,
    fine: int = 2,
) -> float:
    """Fewest measurements (a real number: round up) of any search that acts on detections
    to detect, with probability ``success``, an optimum at a distance uniform in ``band``
    [deg] and a uniform direction — the linear programme of the module docstring.

    Unknowns: w_k ≥ 0, the measurements at distances in cell k of width ``cell`` [deg]
    (default: 1/50 of the 90 % detection radius, at most 0.1°), out to R₂ + the last
    angle; y_j ∈ [0, 1], the detection probability in bin j of ρ (same width).  Minimize
    Σ w subject to y_j ≤ Σ_k P̄⁺_jk w_k and mean(y) ≥ ``success``, where P̄⁺_jk is the
    largest :func:`ring_kernel` value over bin j × cell k (sampled ``fine`` times per side,
    edges included).  Solved by HiGHS (``scipy.optimize.linprog``).  Numerically: at 30 dB
    the value, 16.0146, moves in the fifth digit with 513 or 2049 arc angles instead of
    129 and with 4 samples per side instead of 2; it is as exact as the measured p."""
    if cell is None:
        cell = bound_cell(radius(angles, prob, 0.9))
    upper = _cell_kernel(band, angles, prob, cell, fine)
    n_rho, n_s = upper.shape
    rows = sparse.hstack([-sparse.csr_array(upper), sparse.eye_array(n_rho)])
    mean_row = sparse.hstack([sparse.csr_array((1, n_s)), np.full((1, n_rho), -1.0 / n_rho)])
    res = linprog(
        np.r_[np.ones(n_s), np.zeros(n_rho)],
        A_ub=sparse.vstack([rows, mean_row]).tocsr(),
        b_ub=np.r_[np.zeros(n_rho), -success],
        bounds=[(0.0, None)] * n_s + [(0.0, 1.0)] * n_rho,
        method="highs",
    )
    if res.status != 0:
        raise RuntimeError(f"covering programme: {res.message}")
    return float(res.fun)


def lattice_search(
    band: tuple[float, float],
    angles: np.ndarray,
    prob: np.ndarray,
    success: float = SUCCESS,
    *,
    samples: int = 10_000,
    seed: int = 0,
    r90: float | None = None,
) -> tuple[int, float]:
    """The fewest measurements of a hexagonal lattice around x0 that detect the echo with
    probability ≥ ``success`` for an optimum at a distance uniform in ``band`` [deg] and a
    uniform direction (as the benchmark draws its starts) — its
    spacing optimized (0.6–2.4 × the 90 % detection radius, 0.1 apart) and its points
    chosen greedily, each the one that adds most to the mean detection probability
    (1 − Π(1 − p(|x − mᵢ|)): every measurement detects independently with the measured
    ``prob`` at ``angles`` [deg], 0 beyond).  The mean is over ``samples`` optima drawn
    with ``seed``; ``r90`` [deg], the 90 % radius, when the caller has it.  A design —
    what an optimized non-adaptive covering spends — not a bound.  Returns (measurements,
    spacing [deg]); (∞, NaN) when no spacing gets there."""
    lo, hi = band
    rng = np.random.default_rng(seed)
    dist = rng.uniform(lo, hi, samples)  # as the benchmark's starts: distance uniform
    phi = rng.uniform(0.0, 2.0 * np.pi, samples)
    optima = np.column_stack([dist * np.cos(phi), dist * np.sin(phi)])
    seen = angles[np.flatnonzero(prob > 0.0)]
    far = float(seen.max()) if seen.size else 0.0  # p = 0 beyond: farther points see nothing
    best: tuple[int, float] = (math.inf, math.nan)  # type: ignore[assignment]
    r90 = radius(angles, prob, 0.9) if r90 is None else r90
    if not r90 > 0.0:
        return best
    for spacing in r90 * np.round(np.arange(0.6, 2.45, 0.1), 2):
        # ring k's nearest points are k · spacing · √3/2 out: enough rings to pass hi + reach
        n_rings = math.ceil((hi + far) / (spacing * math.sqrt(3.0) / 2.0)) + 1
        rings = hex_spiral(np.zeros(2), spacing, n_rings)
        points = np.vstack(rings)
        points = points[np.hypot(*points.T) <= hi + far]
        p = np.interp(
            np.hypot(*(optima[:, None, :] - points[None]).transpose(2, 0, 1)),
            angles,
            prob,
            right=0.0,
        )
        miss = np.ones(samples)
        for n in range(1, min(len(points), best[0]) + 1):
            j = int(np.argmax(miss @ p))
            miss *= 1.0 - p[:, j]
            p[:, j] = 0.0
            if 1.0 - miss.mean() >= success:
                best = (n, float(spacing))
                break
    return best


def echo_amplitude(setup_name: str, snr: float) -> tuple[np.ndarray, np.ndarray]:
    """The probe's lobe as the information bound reads it: misalignments [deg] and ν(θ),
    the noiseless matched-envelope peak in units of the noise's Rayleigh scale at peak
    SNR ``snr`` [dB], the largest over the profile's directions (the setup's cached
    :func:`~echocal.measurement.detection_radius.cached_lobe_profile` at its reference
    position, which ends where a 30 dB echo is no longer seen: beyond, the bound takes
    its last value, more than the lobe has there)."""
    setup = load_setup(setup_name, seed=0)
    profile = cached_lobe_profile(setup, np.asarray(setup.reference_position, float))
    detector = shared_detector(setup.pulse, setup.window.fs, setup.window.n_samples)
    sigma = float(noise_sigma_for_snr(profile.reference, snr, setup.window, setup.pulse))
    return profile.angles, profile.peaks.max(axis=0) / (sigma * detector.noise_gain)


def any_search_bound(
    setup_name: str, snr: float, band: tuple[float, float], *, step: float = 0.25
) -> tuple[int, int]:
    """The bounds of :func:`information_bound.search_bound` that hold for any search
    (the information recursion, the change of measure) on this probe at ``snr`` [dB] for
    optima ``band`` [deg] away, to 0.1° in 99 %, with radii ``step`` [deg] apart (coarser
    is cheaper and still a bound)."""
    angles, nu = echo_amplitude(setup_name, snr)
    kernels: dict[float, np.ndarray] = {}

    def cover(reach: float, n: int) -> float:
        if reach not in kernels:
            kernels[reach] = reach_kernel(band, reach)
        return covered_mass(kernels[reach], n)

    return search_bound(
        angles,
        nu,
        band,
        cover,
        tolerance=TOLERANCE,
        success=SUCCESS,
        zone_step_deg=step,
        hit_step_deg=step,
    )


def _percentile(values: list[float], q: float) -> float:
    """The q-th percentile, 'never' (inf) counting as larger than every number."""
    if not values:
        return math.nan
    ordered = np.sort(np.asarray(values, dtype=float))
    return float(ordered[min(len(ordered) - 1, math.ceil(q / 100 * len(ordered)) - 1)])


def _ratios(p50: float, p99: float, bound: int) -> str:
    """The median and p99 over ``bound`` ("–" where a percentile is missing or never
    reached)."""
    if not (math.isfinite(p50) and math.isfinite(p99)):
        return "–"
    return f"{p50 / bound:.2f} / {p99 / bound:.2f}"


def _n(v: float, budget: int) -> str:
    return f">{budget}" if not math.isfinite(v) else f"{v:.0f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    # p(θ) is measured on the whole recording: a gated case's detection is not modelled
    ap.add_argument(
        "--case", default="immersion-5mhz", choices=[c for c in CASES if c not in GATED_CASES]
    )
    ap.add_argument("--snr", default="30", help="comma-separated SNRs [dB]")
    ap.add_argument("--start", default="far", choices=list(STARTS))
    ap.add_argument("--runs", type=int, default=100, help="auto runs per SNR (0: the bounds alone)")
    ap.add_argument("--draws", type=int, default=400, help="noise draws per angle")
    ap.add_argument("--max-angle", type=float, default=10.0, help="p(θ) measured up to [deg]")
    ap.add_argument(
        "--budget",
        default=str(BUDGET),
        help=f"measurements per auto run (default {BUDGET}, the calibration benchmark's); "
        "comma-separated: one per SNR",
    )
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--smoke", action="store_true", help="2 runs, 40 draws, coarse angles")
    ap.add_argument("--out-md", type=Path, default=None)
    args = ap.parse_args(argv)
    snrs = [float(v) for v in args.snr.split(",")]
    try:
        budgets = [int(v) for v in args.budget.split(",")]
    except ValueError:
        ap.error(f"--budget must be whole numbers of measurements; got {args.budget!r}")
    budgets = budgets * len(snrs) if len(budgets) == 1 else budgets
    if len(budgets) != len(snrs):
        ap.error(f"--budget gives {len(budgets)} budgets for {len(snrs)} SNRs: one, or one per SNR")
    if min(budgets) < AT:
        ap.error(
            f"--budget must be at least {AT}: the fraction within {TOLERANCE:g} deg "
            f"is read after {AT} measurements"
        )
    runs = 2 if args.smoke else args.runs
    draws = 40 if args.smoke else args.draws
    step = 1.0 if args.smoke else 0.25
    band = STARTS[args.start]
    setup_name = CASES[args.case]["setup"]
    angles = np.round(np.arange(0.0, args.max_angle + step / 2, step), 3)
    machine = machine_info()
    t0 = time.perf_counter()
    rows: list[list[str]] = []
    for snr, budget in zip(snrs, budgets, strict=True):
        prob = detection_curves(setup_name, snr, angles, draws)[DETECTOR]
        k = seen_area(angles, prob)
        r90 = radius(angles, prob, 0.9)
        bound = math.ceil(covering_bound(band, angles, prob, cell=bound_cell(r90)))
        bound += REFINE_UNKNOWNS
        area = area_bound(band, k) + REFINE_UNKNOWNS
        lattice = cover(band, r90)
        lattice99 = cover(band, radius(angles, prob, SUCCESS)) + REFINE_UNKNOWNS
        best, spacing = (
            lattice_search(band, angles, prob, r90=r90)
            if lattice <= MAX_LATTICE
            else (math.inf, math.nan)
        )
        best += REFINE_UNKNOWNS
        info_n, hit_n = any_search_bound(setup_name, snr, band, step=1.0 if args.smoke else 0.25)
        any_bound = max(info_n, hit_n)
        tasks = [(args.case, args.start, snr, r, "auto", budget) for r in range(runs)]
        results: list[dict[str, Any]] = []
        if tasks:  # spawn, not fork: the wave model's threads can deadlock a fork
            with ProcessPoolExecutor(args.workers, mp_context=get_context("spawn")) as pool:
                results = list(pool.map(run_one, tasks))
        to_tol = [measurements_to(np.asarray(r["errors"]), TOLERANCE) for r in results]
        within = np.mean([r["errors"][AT] <= TOLERANCE for r in results]) if results else math.nan
        found = [r["acquisition_measurements"] for r in results]
        found_n = [float(v) for v in found if v is not None]
        p99 = _percentile(to_tol, 99)
        p50 = _percentile(to_tol, 50)
        rows.append(
            [
                f"{snr:g}",
                f"{budget}",
                f"{k:.1f}",
                f"{lattice:.0f}",
                f"{bound}",
                f"{area}",
                f"{lattice99:.0f}",
                f"{best} ({spacing:.2f}°)" if math.isfinite(best) else "–",
                f"{100 * within:.0f} %" if results else "–",
                " / ".join(_n(_percentile(to_tol, q), budget) for q in (50, 90, 99)),
                f"{np.median(found_n):.0f}" if found_n else "–",
                f"{p99 / bound:.2f}" if math.isfinite(p99) else "∞" if results else "–",
                f"{p99 / lattice99:.2f}" if math.isfinite(p99) else "∞" if results else "–",
                f"{p99 / best:.2f}" if math.isfinite(p99 * best) else "–",
                f"{any_bound} ({info_n} / {hit_n})",
                _ratios(p50, p99, any_bound),
            ]
        )
        print(
            f"HEADLINE {args.case} {args.start} {snr:g} dB: bound {bound} measurements, auto "
            f"p99 {_n(p99, budget)} (ratio {rows[-1][-5]}; {rows[-1][-4]} of the r99 lattice, "
            f"{rows[-1][-3]} of the best lattice), "
            f"{100 * within:.0f} % within "
            f"{TOLERANCE:g}° at {AT}; any search needs at least {any_bound} "
            f"(median / p99 over it: {rows[-1][-1]})",
            flush=True,
        )
    header = [
        "SNR [dB]",
        "auto's budget",
        "K: area one measurement sees [deg²]",
        "hexagonal lattice at r90 (a design)",
        f"lower bound to {TOLERANCE:g}° in {100 * SUCCESS:.0f} % (the covering programme + 3)",
        "area bound 0.99 A/K + 3 (before 2026-11-29)",
        "hexagonal lattice at r99 + 3",
        "best hexagonal lattice: 99 % detection + 3 (spacing)",
        f"auto within {TOLERANCE:g}° at {AT}",
        f"auto measurements to {TOLERANCE:g}° (median / p90 / p99)",
        "auto: acquisition hand-over (median)",
        "ratio p99 / bound",
        "ratio p99 / r99 lattice",
        "ratio p99 / best lattice",
        "bound for any search (information / change of measure)",
        "ratio median / p99 over the any-search bound",
    ]
    table = markdown_table(header, rows)
    elapsed = time.perf_counter() - t0
    print(table)
    print(f"HEADLINE lower-bound benchmark: {elapsed:.0f} s")
    if args.out_md:
        text = [
            f"# Lower bound on measurements vs `auto` — {args.case}, starts "
            f"{band[0]:g}–{band[1]:g}° off",
            "",
            f"Run: `python benchmarks/bench_lower_bound.py --case {args.case} --snr {args.snr} "
            f"--runs {runs} --start {args.start} --budget {args.budget}` "
            f"({elapsed:.0f} s; {machine['cpu']}; echocal {machine['echocal_git']}).",
            "",
            "\n\n".join(__doc__.split("\n\n")[1:8]).strip().rstrip(":"),
            "",
            f"{runs} auto runs per SNR; p(θ) from {draws} noise draws per angle, 0–"
            f"{args.max_angle:g}° in {step:g}° steps.",
            "",
            table,
            "",
        ]
        atomic_write_text(args.out_md, "\n".join(text) + "\n" + _kept_sections(args.out_md))
    return 0


KEEP_MARKER = "<!-- written by hand below: kept when the benchmark rewrites this page -->"
"""The line after which the page's hand-written sections (reading, derivation) start."""


def _kept_sections(path: Path) -> str:
    """The hand-written tail of the page at ``path`` (from :data:`KEEP_MARKER` on), or ''."""
    try:
        old = path.read_text(encoding="utf-8")
    except OSError:
        return ""
    at = old.find(KEEP_MARKER)
    return "\n" + old[at:] if at >= 0 else ""


if __name__ == "__main__":
    sys.exit(main())
