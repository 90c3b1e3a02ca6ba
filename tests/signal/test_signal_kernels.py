"""Spreading kernel of the fast synthesis: numba and numpy agree, the polynomial kernel and
its transform, and the simulator's unchecked entry point."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.polynomial import polynomial as P
from numpy.testing import assert_allclose, assert_array_equal

from echocal import EchocalValueError
from echocal import _numba as N
from echocal.signal import GaborPulse, RecordingWindow, synthesize
from echocal.signal import _kernels as K
from echocal.signal.synthesis import _kernel_parameters, _plan, _synthesize_unchecked

FS = 100e6
PULSE = GaborPulse(center_frequency=5e6, bandwidth=60.0)
WINDOW = RecordingWindow(fs=FS, start=20e-6, n_samples=2048)


def rays(rng, shape):
    """Amplitudes and τ around the window, with zeros, misses (inf) and far-away echoes."""
    a = rng.uniform(-1.0, 1.0, shape)
    tau = rng.uniform(WINDOW.start - 2e-6, WINDOW.end + 2e-6, shape)
    a[rng.random(shape) < 0.1] = 0.0
    tau[rng.random(shape) < 0.1] = np.inf
    return a, tau


def test_numba_and_numpy_spread_the_same():
    if not N.HAVE_NUMBA:
        pytest.skip("numba not installed")
    rng = np.random.default_rng(2)
    a, tau = rays(rng, (3, 1500))
    plan = _plan(PULSE, FS, WINDOW.n_samples)
    kw = {
        "t_lo": WINDOW.start - PULSE.support,
        "t_hi": WINDOW.end + PULSE.support,
        "t0": WINDOW.start - plan.pad / FS,
        "scale": plan.sigma * FS,
        "coefs": plan.coefs,
    }
    g_numba = np.zeros((3, plan.sigma * plan.n_fft))
    g_numpy = np.zeros_like(g_numba)
    counts_numba = N.compiled(K._spread_loops)(a, tau, grid=g_numba, **kw)
    counts_numpy = K._spread_numpy(a, tau, grid=g_numpy, **kw)
    # Same products added in the same order: equal to the last bit (no FMA contraction
    # without fastmath); allow 1e-15 relative in case a compiler fuses them anyway.
    assert_allclose(g_numba, g_numpy, rtol=0, atol=1e-15 * np.max(np.abs(g_numpy)))
    assert tuple(counts_numba) == counts_numpy
    hit = (a != 0) & np.isfinite(tau)
    inside = hit & (tau > kw["t_lo"]) & (tau < kw["t_hi"])
    assert counts_numpy == (hit.sum(), inside.sum())


def test_synthesize_same_with_and_without_numba(monkeypatch):
    rng = np.random.default_rng(3)
    a, tau = rays(rng, (2, 4096))
    with_numba = synthesize(a, tau, PULSE, WINDOW)
    monkeypatch.setattr(N, "USE_NUMBA", False)
    without = synthesize(a, tau, PULSE, WINDOW)
    assert_allclose(with_numba, without, rtol=0, atol=1e-15 * np.max(np.abs(without)))


@pytest.mark.parametrize("sigma_f", [1.2, 2.0, 5.14, 10.0])
def test_tap_polynomials_follow_the_semicircle_exponential(sigma_f):
    width, beta = _kernel_parameters(sigma_f)
    coefs = K.horner_coefficients(width, beta, tol=1e-8)
    t = np.linspace(-1.0, 1.0, 301)
    half = width / 2
    for k in range(width):
        z = ((t + 1.0) / 2 + k) / half - 1.0
        exact = np.exp(beta * (np.sqrt(np.maximum(1 - z * z, 0.0)) - 1.0))
        approx = P.polyval(t, coefs[::-1, k])
        # interior taps within the requested 1e-8 (checked on a finer grid when fitted);
        # the edge taps meet the kernel's own jump e^−β at |z| = 1 (√ singularity there).
        bound = 1e-8 if 0 < k < width - 1 else 10 * math.exp(-beta)
        assert np.max(np.abs(approx - exact)) <= bound


def test_kernel_transform_is_the_piecewise_polynomials_integral():
    width, beta = _kernel_parameters(5.14)
    coefs = K.horner_coefficients(width, beta)
    xi = np.array([0.0, 0.05, 0.2, 0.5])
    got = K.kernel_transform(xi, coefs)
    # Independent: tap k covers x ∈ [k − w/2, k + 1 − w/2), x = k − w/2 + (t + 1)/2; a fine
    # midpoint rule (1e5 points per tap, error ~1e-11 relative) of K(x)·cos(2πξx).
    m = 100_000
    s = (np.arange(m) + 0.5) / m
    ref = np.zeros_like(xi)
    for k in range(width):
        vals = P.polyval(2 * s - 1, coefs[::-1, k])
        x = k - width / 2 + s
        ref += (np.cos(2 * np.pi * np.outer(xi, x)) @ vals) / m
    assert_allclose(got, ref, rtol=1e-9)
    # K̂(0) = Σ_k ∫ P_k: integrate each tap's polynomial exactly
    exact0 = sum(
        np.diff(P.polyval([-1.0, 1.0], P.polyint(coefs[::-1, k])))[0] / 2 for k in range(width)
    )
    assert got[0] == pytest.approx(exact0, rel=1e-13)


@pytest.mark.parametrize("method", ["fast", "direct"])
@pytest.mark.parametrize("normalize", ["rays", "peak", None])
def test_unchecked_entry_equals_synthesize(method, normalize):
    rng = np.random.default_rng(5)
    a, tau = rays(rng, (3, 300))
    want = synthesize(a, tau, PULSE, WINDOW, method=method, normalize=normalize)
    got = _synthesize_unchecked(a, tau, PULSE, WINDOW, method=method, normalize=normalize)
    assert_array_equal(got, want)


@pytest.mark.parametrize("method", ["fast", "direct"])
def test_unchecked_entry_refuses_a_window_without_echoes(method):
    a = np.ones((2, 400))
    tau = np.full((2, 400), 1e-3)  # 1 ms: far after the window
    with pytest.raises(EchocalValueError, match="cannot contain any echo"):
        _synthesize_unchecked(a, tau, PULSE, WINDOW, method=method)
    # all misses: silence, not an error
    out = _synthesize_unchecked(a, np.full_like(tau, np.inf), PULSE, WINDOW, method=method)
    assert_array_equal(out, 0.0)


def test_small_and_large_inputs_agree_across_the_numba_threshold():
    """Below NUMBA_MIN_RAYS the numpy kernel runs: synthesis stays linear across it."""
    rng = np.random.default_rng(9)
    n = K.NUMBA_MIN_RAYS
    a, tau = rays(rng, 2 * n)
    whole = synthesize(a, tau, PULSE, WINDOW, normalize=None)
    parts = sum(
        synthesize(a[i : i + n // 2], tau[i : i + n // 2], PULSE, WINDOW, normalize=None)
        for i in range(0, 2 * n, n // 2)
    )
    # sums of the same terms in a different order: round-off only
    assert_allclose(whole, parts, rtol=0, atol=1e-12 * np.max(np.abs(whole)))


def test_kernel_transform_in_blocks_equals_small_pieces():
    # the blocked evaluation (bounded memory for 2^20-sample windows) must not depend on
    # where the block boundaries fall: compare with pieces far smaller than one block
    coefs = K.horner_coefficients(6, 7)
    xi = np.linspace(-0.5, 0.5, 3 * K._XI_BLOCK + 17)
    pieces = np.concatenate([K.kernel_transform(p, coefs) for p in np.array_split(xi, 997)])
    np.testing.assert_allclose(K.kernel_transform(xi, coefs), pieces, rtol=0, atol=1e-14)
