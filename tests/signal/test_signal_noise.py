"""Receiver noise at a requested SNR, reproducibility, saturation and quantization."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from echocal import EchocalValueError
from echocal.signal import (
    GaborPulse,
    Receiver,
    RecordingWindow,
    noise_sigma_for_snr,
    signal_power,
    synthesize,
)

PULSE = GaborPulse()
WIN = RecordingWindow(fs=100e6, start=20e-6, n_samples=4096)
REF = synthesize([1.0], [30e-6], PULSE, WIN, normalize=None)


def test_sigma_follows_the_snr_definition():
    power = signal_power(REF, WIN, PULSE)
    # P_signal = mean of x² over the energy window (2 × −20 dB duration, ~107 samples)
    n_win = 2 * round(PULSE.duration * WIN.fs) + 1
    assert power == pytest.approx(np.sum(REF**2) / n_win, rel=1e-6)
    for snr in (0.0, 20.0, 30.0):
        sigma = noise_sigma_for_snr(REF, snr, WIN, PULSE)
        assert 10 * math.log10(power / sigma**2) == pytest.approx(snr, abs=1e-12)


def test_noise_power_matches_requested_snr():
    snr = 20.0
    receiver = Receiver.from_snr(REF, snr, WIN, PULSE)
    silence = np.zeros((16, WIN.n_samples))
    noise = receiver.receive(silence, rng=123)
    n = noise.size
    var = np.sum(noise**2) / n  # zero-mean known: n degrees of freedom
    # (n·var/σ²) ~ χ²(n): the 99.9 % two-sided interval, about ±1.3 % for n = 65536
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n) / n
    assert lo <= var / receiver.noise_sigma**2 <= hi
    measured_snr = 10 * math.log10(signal_power(REF, WIN, PULSE) / var)
    assert abs(measured_snr - snr) < 10 * math.log10(hi)


def test_noise_is_fixed_per_setup_not_rescaled():
    receiver = Receiver.from_snr(REF, 30.0, WIN, PULSE)
    weak = 0.1 * REF
    # same seed → the same noise realization (same σ) added to any signal; the difference is
    # only the rounding of (x + n) − x, ≤ 1 ulp of the samples (~1e-16)
    np.testing.assert_allclose(
        receiver.receive(weak, rng=5) - weak, receiver.receive(REF, rng=5) - REF, atol=1e-15
    )


def test_seeds_reproduce_bit_for_bit():
    r = Receiver(noise_sigma=0.01, adc_bits=12, full_scale=1.0)
    a = r.receive(REF, rng=42)
    np.testing.assert_array_equal(a, r.receive(REF, rng=42))
    np.testing.assert_array_equal(a, r.receive(REF, rng=np.random.default_rng(42)))
    assert not np.array_equal(a, r.receive(REF, rng=43))


def test_saturation_and_quantization():
    x = np.linspace(-2.0, 2.0, 1001)
    clipped = Receiver(full_scale=0.5).receive(x)
    assert clipped.max() == 0.5 and clipped.min() == -0.5
    np.testing.assert_array_equal(clipped[np.abs(x) <= 0.5], x[np.abs(x) <= 0.5])
    r = Receiver(adc_bits=4, full_scale=1.0, gain=2.0)
    y = r.receive(x)
    step = 2.0 / 16
    assert r.lsb == step
    levels = np.unique(y)
    assert len(levels) == 16  # 2^4 levels, −8Δ … 7Δ
    np.testing.assert_allclose(levels / step, np.arange(-8, 8))
    inside = np.abs(2 * x) < 1.0 - step
    assert np.max(np.abs(y[inside] - 2 * x[inside])) <= step / 2 + 1e-12


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"noise_sigma": -1.0}, "noise_sigma"),
        ({"noise_sigma": math.nan}, "noise_sigma"),
        ({"adc_bits": 8}, "full_scale"),
        ({"adc_bits": 0, "full_scale": 1.0}, "adc_bits"),
        ({"full_scale": 0.0}, "full_scale"),
        ({"gain": 0.0}, "gain"),
    ],
)
def test_receiver_validation(kwargs, field):
    with pytest.raises(EchocalValueError, match=field):
        Receiver(**kwargs)


def test_bad_snr_and_reference():
    with pytest.raises(EchocalValueError, match="snr_db"):
        noise_sigma_for_snr(REF, math.nan, WIN, PULSE)
    with pytest.raises(EchocalValueError, match="reference_samples"):
        noise_sigma_for_snr(np.zeros(WIN.n_samples), 20.0, WIN, PULSE)


def test_scan_noise_sigma_of_an_overflowing_trace_is_unknown_not_inf():
    """A trace of infinite or overflowing samples (a receiver fault) has no noise level:
    None ("cannot tell"), never an infinite σ that a detector then refuses with
    "sigma must be finite"."""
    from echocal.signal.noise import scan_noise_sigma

    rng = np.random.default_rng(0)
    noise = rng.normal(size=256)
    for trace in (
        np.full(256, np.inf),
        np.where(np.arange(256) % 2 == 0, np.inf, -np.inf),
        np.where(np.arange(256) < 200, 1e308, -1e308) * np.sign(noise),
    ):
        assert scan_noise_sigma(trace) == (None, False)
    sigma, _ = scan_noise_sigma(noise)
    assert 0.8 < sigma < 1.2  # a normal trace still measures its σ (1, within 20 %)
