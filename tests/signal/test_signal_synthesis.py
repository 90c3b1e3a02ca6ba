"""A-scan synthesis: fast (NUFFT) against direct (literal eq. 28), windows, normalization."""

from __future__ import annotations

import math

import numpy as np
import pytest

from echocal import EchocalValueError, UnknownNameError
from echocal.signal import (
    GaborPulse,
    RecordingWindow,
    RickerPulse,
    SampledPulse,
    SincPulse,
    check_window,
    synthesize,
)

FS = 100e6


def rel_l2(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def random_rays(rng, n_rays, window, spread=0.6):
    """τ spread over the middle of the window (a few µs), amplitudes in [0.2, 1]."""
    mid, half = window.start + window.duration / 2, spread * window.duration / 2
    return rng.uniform(0.2, 1.0, n_rays), rng.uniform(mid - half, mid + half, n_rays)


def test_fast_matches_direct_at_defaults():
    rng = np.random.default_rng(1)
    p = GaborPulse(center_frequency=5e6, bandwidth=60.0)
    w = RecordingWindow(fs=FS, start=20e-6, n_samples=4096)
    a, tau = random_rays(rng, 4096, w)
    fast = synthesize(a, tau, p, w)
    direct = synthesize(a, tau, p, w, method="direct")
    assert rel_l2(fast, direct) <= 1e-4  # the bound; measured ~3e-7


# Grid: rays 16..65536, samples 1024..16384, fc 1..15 MHz.  Direct is O(rays × samples), so
# for the largest ray counts the comparison uses the first 512 rays of the same set (the fast
# path's error does not depend on ray count: each impulse is spread independently), and the
# full set is checked for linearity (sum of two halves) instead.
@pytest.mark.parametrize("fc", [1e6, 5e6, 15e6])
@pytest.mark.parametrize(("n_rays", "n_samples"), [(16, 1024), (1024, 4096), (65536, 16384)])
def test_fast_matches_direct_on_grid(fc, n_rays, n_samples):
    rng = np.random.default_rng(int(fc) + n_rays)
    p = GaborPulse(center_frequency=fc, bandwidth=60.0, phase=20.0)
    w = RecordingWindow(fs=FS, start=5e-6, n_samples=n_samples)
    a, tau = random_rays(rng, n_rays, w, spread=0.9)
    m = min(n_rays, 512)
    assert (
        rel_l2(synthesize(a[:m], tau[:m], p, w), synthesize(a[:m], tau[:m], p, w, method="direct"))
        <= 1e-4
    )
    if n_rays > m:
        full = synthesize(a, tau, p, w, normalize=None)
        parts = synthesize(a[:m], tau[:m], p, w, normalize=None) + synthesize(
            a[m:], tau[m:], p, w, normalize=None
        )
        assert rel_l2(full, parts) <= 1e-10


@pytest.mark.parametrize(
    "pulse",
    [
        RickerPulse(center_frequency=5e6),
        SincPulse(center_frequency=5e6, bandwidth=2e6, window="hann", lobes=6),
        SampledPulse(samples=GaborPulse(phase=45).waveform(np.arange(-80, 81) / 80e6), fs=80e6),
    ],
    ids=["ricker", "sinc", "sampled"],
)
def test_fast_matches_direct_other_pulses(pulse):
    rng = np.random.default_rng(7)
    w = RecordingWindow(fs=FS, start=10e-6, n_samples=2048)
    a, tau = random_rays(rng, 500, w)
    assert rel_l2(synthesize(a, tau, pulse, w), synthesize(a, tau, pulse, w, method="direct")) <= (
        1e-4
    )


def test_single_ray_is_the_shifted_pulse():
    p = GaborPulse(phase=30.0)
    w = RecordingWindow(fs=FS, start=1e-6, n_samples=1024)
    tau = 4.123456e-6
    x = synthesize([0.7], [tau], p, w, normalize=None)
    # pointwise NUFFT error ~1e-7 of the peak per echo (kernel tolerance 1e-7)
    np.testing.assert_allclose(x, 0.7 * p.waveform(w.times - tau), atol=1e-6)


def test_echoes_outside_window_are_absent_not_wrapped():
    p = GaborPulse()
    w = RecordingWindow(fs=FS, start=10e-6, n_samples=1024)  # 10 .. 20.23 µs
    inside = 15e-6
    # echoes just past each end (partly overlapping) and far away: a periodic FFT of the
    # window length would fold them onto the other end
    outside = [w.end + 0.3e-6, w.start - 0.3e-6, w.end + 3.3e-6, w.start - 10.24e-6]
    for method in ("fast", "direct"):
        x = synthesize([1.0] + [1.0] * 4, [inside, *outside], p, w, method=method, normalize=None)
        expected = sum(p.waveform(w.times - t) for t in [inside, *outside])
        np.testing.assert_allclose(x, expected, atol=1e-6)
    # the partial echoes only touch their own end
    x = synthesize([1.0], [w.end + 0.3e-6], p, w, normalize=None)
    assert np.max(np.abs(x[:512])) < 1e-12


def test_misses_and_zero_amplitudes_contribute_nothing_and_normalization_counts_them():
    p = GaborPulse()
    w = RecordingWindow(fs=FS, start=10e-6, n_samples=1024)
    a = np.array([1.0, 5.0, 0.0, 2.0])
    tau = np.array([14e-6, np.inf, 15e-6, np.inf])
    ref = p.waveform(w.times - 14e-6)
    for method in ("fast", "direct"):
        x = synthesize(a, tau, p, w, method=method, normalize="rays")
        np.testing.assert_allclose(x, ref / 4, atol=1e-6)  # divided by all 4 rays
        y = synthesize(a, tau, p, w, method=method, normalize="peak")
        assert np.max(np.abs(y)) == pytest.approx(1.0)
    all_miss = synthesize([1.0, 1.0], [np.inf, np.inf], p, w, normalize="peak")
    assert np.all(all_miss == 0.0)
    for method in ("fast", "direct"):  # no rays at all (e.g. a batch of empty bundles): silence
        none = synthesize(np.zeros((2, 0)), np.zeros((2, 0)), p, w, method=method)
        assert none.shape == (2, 1024) and not none.any()


def test_batched_poses_equal_one_by_one():
    rng = np.random.default_rng(3)
    p = GaborPulse()
    w = RecordingWindow(fs=FS, start=10e-6, n_samples=2048)
    a = rng.uniform(0, 1, (2, 3, 64))
    tau = rng.uniform(12e-6, 25e-6, (2, 3, 64))
    tau[0, 1, :10] = np.inf
    x = synthesize(a, tau, p, w)
    assert x.shape == (2, 3, 2048)
    for i in range(2):
        for j in range(3):
            np.testing.assert_allclose(x[i, j], synthesize(a[i, j], tau[i, j], p, w), atol=1e-12)
    # a scalar τ broadcast over rays
    np.testing.assert_allclose(
        synthesize(np.ones(3), 15e-6, p, w), synthesize([1.0], [15e-6], p, w), atol=1e-12
    )


def test_bad_inputs_name_the_field():
    p = GaborPulse()
    w = RecordingWindow(fs=FS, start=10e-6, n_samples=1024)
    with pytest.raises(EchocalValueError, match="amplitudes"):
        synthesize([np.nan], [15e-6], p, w)
    with pytest.raises(EchocalValueError, match="tofs"):
        synthesize([1.0], [np.nan], p, w)
    with pytest.raises(EchocalValueError, match="fs"):
        synthesize([1.0], [15e-6], p, RecordingWindow(fs=15e6, start=10e-6, n_samples=1024))
    with pytest.raises(EchocalValueError, match="window"):
        synthesize([1.0], [100e-6], p, w)
    with pytest.raises(EchocalValueError, match="normalize"):
        synthesize([1.0], [15e-6], p, w, normalize="energy")
    with pytest.raises(UnknownNameError, match="direct, fast"):
        synthesize([1.0], [15e-6], p, w, method="magic")


def test_window_validation_and_aliasing_check():
    with pytest.raises(EchocalValueError, match="fs"):
        RecordingWindow(fs=0.0)
    with pytest.raises(EchocalValueError, match="n_samples"):
        RecordingWindow(fs=FS, n_samples=1)
    with pytest.raises(EchocalValueError, match="start"):
        RecordingWindow(fs=FS, start=math.inf)
    p = GaborPulse(center_frequency=5e6)
    check_window(RecordingWindow(fs=2.01 * p.highest_frequency), p)
    with pytest.raises(EchocalValueError, match="fs"):
        check_window(RecordingWindow(fs=1.99 * p.highest_frequency), p)
    with pytest.warns(UserWarning, match="shorter than the pulse"):
        check_window(RecordingWindow(fs=FS, n_samples=8), p)
    w = RecordingWindow.spanning(10e-6, 12e-6, fs=FS, pulse=p)
    assert w.start <= 10e-6 - p.support and w.end >= 12e-6 + p.support
