"""The any-search bounds against the exact optimum of small search problems.

K cells on a line, the optimum uniform among them; a measurement at cell x answers
"echo" with probability ``lobe[|x − c|]`` (else "no echo"), independently.  The best
adaptive policy's chance to name c exactly after n measurements is computed here by
dynamic programming over every history (no echocal code), and the bounds of
``benchmarks/information_bound.py`` must never ask for more measurements than it needs.
The capacity, the divergence and the dual are checked against closed forms."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
import information_bound as ib  # noqa: E402

PROBLEMS = {
    # 5 cells, a lobe with a noisy tail: the optimum after up to 5 measurements
    "broad": (np.array([0.9, 0.35, 0.08, 0.03, 0.03]), 5),
    # 12 cells, a narrow lobe: finding it is most of the work (4 measurements deep)
    "narrow": (np.array([0.95, 0.2, 0.03] + [0.02] * 9), 4),
}
"""P(echo) at distance 0, 1, … cells from the optimum (one per cell), and the depth."""


def optimal_success(lobe: np.ndarray, depth: int) -> list[float]:
    """The best adaptive policy's success P*_n for n = 0 … ``depth`` (exact: every
    history, every next cell; the estimate is the posterior's mode)."""
    cells = len(lobe)
    dist = np.abs(np.arange(cells)[:, None] - np.arange(cells)[None, :])  # [x, c]
    like = np.stack([1.0 - lobe[dist], lobe[dist]], axis=1)  # [x, y, c]
    out = []
    for n in range(depth + 1):
        # unnormalized beliefs of every history of n measurements, shape (histories, c)
        beliefs = np.full((1, cells), 1.0 / cells)
        for _ in range(n):
            beliefs = (beliefs[:, None, None, :] * like[None]).reshape(-1, cells)
        value = beliefs.max(axis=1)  # the mode's mass: success of the best estimate
        for _ in range(n):
            value = value.reshape(-1, cells, 2).sum(axis=2).max(axis=1)  # Σ_y, best x
        out.append(float(value[0]))
    return out


def bounds_of(lobe: np.ndarray):
    """The two bounds' inputs for the cells on a line: a ball of radius r cells holds at
    most 2r + 1 of them (prior mass (2r + 1)/K); the zones are the distances 0, 1, …;
    the change of measure's reference is the lobe's far value (no echo)."""
    cells = len(lobe)
    masses = [min(1.0, (2 * r + 1) / cells) for r in range(cells - 1)]
    rows = np.stack([1.0 - lobe, lobe], axis=1)
    caps = [ib.blahut_arimoto(rows[k:]) for k in range(cells)]
    far = lobe[-1]
    divergences = [
        max(ib.kl_bernoulli(float(v), float(far)) for v in lobe[r + 1 :]) for r in range(cells - 1)
    ]

    def cover(k: int, n: int) -> float:
        return min(1.0, n * (2 * k + 1) / cells)

    return 1.0 / cells, ib.zone_step(masses, caps), divergences, cover


def test_the_optimum_of_the_small_problem_is_what_dynamic_programming_says():
    # hand check: with no measurement any guess is right 1/5 of the time; with one the best
    # is to measure an end cell, guess it on an echo (0.9), else a cell 3 or 4 away (0.97)
    p = optimal_success(PROBLEMS["broad"][0], 1)
    assert p[0] == pytest.approx(0.2)
    assert p[1] == pytest.approx((0.9 + 0.97) / 5)


@pytest.mark.parametrize("name", list(PROBLEMS))
def test_no_bound_asks_more_than_the_best_adaptive_search_needs(name):
    lobe, depth = PROBLEMS[name]
    success_mass, step, divergences, cover = bounds_of(lobe)
    p_star = optimal_success(lobe, depth)
    assert all(np.diff(p_star) > 0.0)  # each measurement helps the optimum
    for n, p in enumerate(p_star[1:], start=1):
        # the optimum reaches P*_n in n measurements, so no bound may ask for more
        assert ib.information_bound(p, success_mass, [step])[0] <= n
        assert ib.hit_bound(p, success_mass, divergences, cover) <= n
    # not vacuous: certainty is out of reach of the first measurements
    assert ib.information_bound(0.999, success_mass, [step])[0] >= 3
    assert ib.hit_bound(0.999, success_mass, divergences, cover) >= 2


def test_the_binary_symmetric_channel_has_its_closed_form_capacity():
    eps = 0.11
    w = np.array([[1 - eps, eps], [eps, 1 - eps]])
    h = -eps * math.log(eps) - (1 - eps) * math.log(1 - eps)
    assert ib.blahut_arimoto(w) == pytest.approx(math.log(2) - h, abs=2e-6)


def test_a_weak_rice_channel_carries_little_and_a_strong_one_log_amplitude():
    # small ν: the envelope's law moves by O(ν²), so I = O(ν⁴): far below the coherent ν²/2
    assert ib.rice_capacity(0.3) < 0.01
    # large ν: t ≈ N(ν, 1), capacity ≈ ½ ln(1 + A²/(2πe)·…) — between ln(A/√(2πe)) − 0.1
    # and ln(1 + A) (an amplitude-limited Gaussian's known bounds), here A = 20
    c = ib.rice_capacity(20.0)
    assert math.log(20 / math.sqrt(2 * math.pi * math.e)) - 0.1 < c < math.log(21.0)


def test_the_zone_dual_bounds_the_constrained_maximum():
    # brute force over a grid of laws of 3 zones: never above the dual's value
    caps, b = [2.0, 1.0, 0.1], [0.05, 0.3]
    best = -math.inf
    for p0 in np.linspace(0.0, 0.05, 26):
        for p1 in np.linspace(0.0, 0.3 - p0, 40):
            p = np.array([p0, p1, 1.0 - p0 - p1])
            h = -sum(v * math.log(v) for v in p if v > 0)
            best = max(best, h + float(p @ caps))
    value = ib.zone_information(b, caps)
    assert best <= value + 1e-9
    assert value - best < 0.02  # and tight (the grid's resolution)


def test_the_disc_mass_on_an_annulus():
    # a small disc at the inner edge: the density there times its area (the area bound)
    assert ib.disc_mass(0.1, (5.0, 20.0)) == pytest.approx(0.01 / (2 * 5 * 15), rel=0.05)
    # a disc reaching over the whole annulus holds all of it
    assert ib.disc_mass(41.0, (5.0, 20.0)) == 1.0


def test_the_rice_divergence_is_the_gaussian_shift_for_a_strong_echo():
    # ν ≫ 1: Rice(ν) ≈ N(ν, 1) against a Rayleigh near 1; D ≈ ν²/2 − ln ν − ½ ln(2π)
    # + ½ (the Rayleigh's log density at t ≈ ν, minus the Gaussian's entropy): within 2 %
    nu = 30.0
    expected = nu**2 / 2 - math.log(nu) - 0.5 * math.log(2 * math.pi) - 0.5
    assert ib.rice_divergence(nu) == pytest.approx(expected, rel=0.02)
    # a weak echo is hard to tell from noise: the likelihood ratio is I₀(tν) e^{−ν²/2} ≈
    # 1 + ν² (E − 1)/2 with E = t²/2 ~ Exp(1) under noise, so D ≈ χ²/2 = ν⁴ Var(E)/8 = ν⁴/8
    # (the next order is O(ν⁶): 1.3 % below at ν = 0.2)
    assert ib.rice_divergence(0.2) == pytest.approx(0.2**4 / 8, rel=0.05)
