"""Matched filter, time of flight, gates, pseudo-energy and the metric registry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from echocal import EchocalValueError, UnknownNameError
from echocal.signal import (
    GaborPulse,
    Gate,
    RecordingWindow,
    distance,
    energy_db,
    envelope,
    get_metric,
    matched_filter,
    metric_names,
    peak_amplitude,
    pseudo_energy,
    synthesize,
    time_of_flight,
)

FS = 100e6
PULSE = GaborPulse(center_frequency=5e6, bandwidth=60.0, phase=25.0)
WIN = RecordingWindow(fs=FS, start=20e-6, n_samples=2048)


def echo(tau, amplitude=1.0, pulse=PULSE, window=WIN):
    return synthesize([amplitude], [tau], pulse, window, normalize=None)


@pytest.mark.parametrize("frac", [0.0, 0.137, 0.5, 0.81])
def test_time_of_flight_is_sub_sample(frac):
    tau = 27e-6 + frac / FS
    # The matched-filter envelope of a Gabor echo is Gaussian, so log-parabolic interpolation
    # is exact up to synthesis/Hilbert errors: 1e-3 of a sample (10 ps) is a loose bound
    # (measured ~1e-6 sample).
    assert abs(time_of_flight(echo(tau), WIN, PULSE) - tau) * FS < 1e-3


def test_matched_filter_peaks_at_tau_and_equals_autocorrelation():
    tau = 25e-6  # on a sample: matched filter output is R(t_m − τ)
    y = matched_filter(echo(tau), PULSE, FS)
    k = round((tau - WIN.start) * FS)
    assert np.argmax(y) == k
    lags = WIN.times - tau
    # the sum Σ w(t_j−τ) w(t_j−t_m) / fs approximates R exactly for a band-limited pulse
    np.testing.assert_allclose(y, PULSE.autocorrelation(lags), atol=1e-6 * PULSE.energy)


def test_distance():
    assert distance(2e-5, c0=1500.0) == pytest.approx(0.015)


def test_pseudo_energy_matches_gabor_closed_form_and_scales_with_amplitude_squared():
    a, fc, phi = PULSE.alpha, PULSE.center_frequency, math.radians(PULSE.phase)
    closed = (
        0.5
        * math.sqrt(math.pi / (2 * a))
        * (1 + math.exp(-2 * math.pi**2 * fc**2 / a) * math.cos(2 * phi))
    )
    x = echo(26.3e-6, amplitude=2.0)
    # the default window (2 × −20 dB duration) holds all but exp(−4 ln 10·2)≈1e-8 of the energy;
    # the sampled sum / fs equals the integral to ~1e-7 for a band-limited pulse
    assert pseudo_energy(x, WIN, PULSE) / FS == pytest.approx(4 * closed, rel=1e-6)
    # rel 1e-6 in energy is 4.3e-6 dB
    assert energy_db(x, WIN, PULSE) == pytest.approx(10 * math.log10(4 * closed * FS), abs=1e-5)


def test_pseudo_energy_window_centred_on_matched_filter_peak():
    # two echoes: the energy window sits on the stronger one and excludes the other
    x = synthesize([1.0, 0.5], [24e-6, 34e-6], PULSE, WIN, normalize=None)
    strong = echo(24e-6)
    assert pseudo_energy(x, WIN, PULSE) == pytest.approx(pseudo_energy(strong, WIN, PULSE))
    # a short window keeps less energy
    short = pseudo_energy(x, WIN, PULSE, window_length=0.1e-6)
    assert short < 0.5 * pseudo_energy(x, WIN, PULSE)
    with pytest.raises(EchocalValueError, match="window_length"):
        pseudo_energy(x, WIN, PULSE, window_length=-1.0)


def test_batched_metrics_match_single():
    rng = np.random.default_rng(0)
    a = rng.uniform(0.5, 1, (3, 16))
    tau = rng.uniform(22e-6, 35e-6, (3, 16))
    x = synthesize(a, tau, PULSE, WIN)
    for name in metric_names():
        f = get_metric(name)
        batch = f(x, WIN, PULSE)
        assert batch.shape == (3,)
        np.testing.assert_allclose(batch, [f(xi, WIN, PULSE) for xi in x], rtol=1e-12)
    assert time_of_flight(x, WIN, PULSE).shape == (3,)


def test_peak_amplitude_and_envelope():
    x = echo(30e-6, amplitude=0.8)
    # envelope of exp(−αt²)cos(...) peaks at the amplitude (sampled: within a sample's
    # Gaussian drop, exp(−α/(2fs)²) ≈ 1 − 8e-4)
    assert peak_amplitude(x) == pytest.approx(0.8, rel=1e-3)
    assert envelope(x).shape == x.shape


def test_metric_registry():
    assert {"pseudo-energy", "peak-amplitude", "energy-db"} <= set(metric_names())
    with pytest.raises(UnknownNameError, match="pseudo-energy"):
        get_metric("loudness")


def test_gate_first_crossing_and_peak():
    x = synthesize([1.0, 0.5], [24e-6, 34e-6], PULSE, WIN, normalize=None)
    gate = Gate(start=30e-6, width=8e-6, threshold=0.2)
    t_cross = gate.first_crossing(x, WIN)
    # the second echo (|x| ≤ 0.5) crosses 0.2 of full scale (peak ≈ 1) before its centre,
    # where its envelope 0.5·exp(−α t²) = 0.2 → t = −√(ln 2.5/α)
    earliest = 34e-6 - math.sqrt(math.log(2.5) / PULSE.alpha)
    assert earliest - 1e-9 <= t_cross <= 34e-6
    assert abs(x[round((t_cross - WIN.start) * FS)]) == pytest.approx(0.2, abs=0.1)
    t_peak, v_peak = gate.peak(x, WIN)
    # largest sample sits on the carrier crest nearest the envelope peak (phase 25° → 14 ns
    # off: envelope 0.994) and within half a sample of it
    assert abs(t_peak - 34e-6) < 0.2e-6 and v_peak == pytest.approx(0.5, rel=0.02)
    # gated time of flight picks the weaker echo
    assert time_of_flight(x, WIN, PULSE, gate=gate) == pytest.approx(34e-6, abs=1e-10)
    # absolute threshold above the echo: no crossing
    assert np.isnan(
        Gate(start=30e-6, width=8e-6, threshold=0.6, absolute=True).first_crossing(x, WIN)
    )
    with pytest.raises(EchocalValueError, match="gate.width"):
        Gate(start=0.0, width=0.0)
    with pytest.raises(EchocalValueError, match="gate.threshold"):
        Gate(start=0.0, width=1e-6, threshold=1.5)
    with pytest.raises(EchocalValueError, match="holds no sample"):
        Gate(start=0.0, width=1e-6).peak(x, WIN)


def test_silent_ascan_and_bad_samples():
    assert np.isnan(time_of_flight(np.zeros(WIN.n_samples), WIN, PULSE))
    assert pseudo_energy(np.zeros(WIN.n_samples), WIN, PULSE) == 0.0
    with pytest.raises(EchocalValueError, match="samples"):
        pseudo_energy(np.zeros(10), WIN, PULSE)
    bad = np.zeros(WIN.n_samples)
    bad[3] = np.nan
    with pytest.raises(EchocalValueError, match="samples"):
        time_of_flight(bad, WIN, PULSE)


def test_matched_envelope_equals_hilbert_of_matched_filter():
    from echocal.signal import matched_envelope

    x = synthesize([1.0, 0.3], [26e-6, 33e-6], PULSE, WIN, normalize=None)
    ref = envelope(matched_filter(x, PULSE, FS))
    # away from the ends (where the two FFT lengths see different periodic extensions) the
    # one-FFT-pair envelope equals scipy's Hilbert envelope to rounding
    np.testing.assert_allclose(
        matched_envelope(x, PULSE, FS)[200:-200], ref[200:-200], atol=1e-9 * ref.max()
    )


# --- the optimised pseudo-energy against the implementation it replaced ----------------
def _reference_envelope(x, pulse, fs):
    """The former matched_envelope: full complex spectrum built by hand, one ifft."""
    import scipy.fft

    half = math.ceil(pulse.support * fs)
    n_fft = scipy.fft.next_fast_len(x.shape[-1] + half + 1, real=True)
    j = np.arange(-half, half + 1)
    placed = np.zeros(n_fft)
    placed[j % n_fft] = pulse.waveform(j / fs)
    spec = scipy.fft.rfft(x, n=n_fft, axis=-1) * (np.conj(scipy.fft.rfft(placed)) / fs)
    full = np.zeros((*spec.shape[:-1], n_fft), dtype=np.complex128)
    full[..., : spec.shape[-1]] = spec
    full[..., 1 : (n_fft + 1) // 2] *= 2.0
    return np.abs(scipy.fft.ifft(full, axis=-1)[..., : x.shape[-1]])


def _reference_pseudo_energy(x, window, pulse, window_length=None):
    """The former pseudo_energy: cumulative sums of x² differenced at the window's ends."""
    length = 2.0 * pulse.duration if window_length is None else window_length
    half, n = round(0.5 * length * window.fs), x.shape[-1]
    centre = np.argmax(_reference_envelope(x, pulse, window.fs), axis=-1)
    cs = np.concatenate([np.zeros((*x.shape[:-1], 1)), np.cumsum(x * x, axis=-1)], axis=-1)
    lo, hi = np.clip(centre - half, 0, n), np.clip(centre + half + 1, 0, n)
    take = np.take_along_axis
    return np.maximum(take(cs, hi[..., None], -1)[..., 0] - take(cs, lo[..., None], -1)[..., 0], 0)


@pytest.mark.parametrize(
    ("shape", "window_length"), [((), None), ((3, 5), None), ((40,), 3e-7), ((2,), 1e-4)]
)
def test_pseudo_energy_equals_the_former_implementation(shape, window_length):
    """Random echoes plus noise, batches larger than one processing chunk (40 × 2048 > 2^15
    samples), a short window and one longer than the A-scan."""
    from echocal.signal.processing import matched_envelope

    rng = np.random.default_rng(sum(shape) + 1)
    n = int(np.prod(shape))
    taus = rng.uniform(WIN.start, WIN.end, (n, 5))
    x = synthesize(rng.uniform(0.1, 1.0, (n, 5)), taus, PULSE, WIN, normalize=None)
    x = (x + 0.05 * rng.standard_normal(x.shape)).reshape((*shape, WIN.n_samples))
    env = matched_envelope(x, PULSE, FS)
    ref_env = _reference_envelope(x, PULSE, FS)
    # the same FFTs, the analytic weights folded into the template: round-off only
    np.testing.assert_allclose(env, ref_env, rtol=0, atol=1e-13 * np.max(ref_env))
    got = pseudo_energy(x, WIN, PULSE, window_length)
    want = _reference_pseudo_energy(x, WIN, PULSE, window_length)
    assert got.shape == shape
    # The window sits at the same peak; direct sums against differences of cumulative
    # sums, whose round-off is ~1e-16 of the whole A-scan's energy: bound 1e-13 of that.
    total = np.sum(x * x, axis=-1)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * np.max(total))
    assert np.all(got > 0)


@pytest.mark.parametrize("n", [1, 2, 7, 64, 4097])
def test_analytic_signal_equals_scipy_hilbert(n):
    from scipy.signal import hilbert

    from echocal.signal.analytic import analytic_signal

    x = np.random.default_rng(n).standard_normal((3, n))
    # Same FFT algorithm, same weights: equal to double-precision round-off.
    np.testing.assert_allclose(analytic_signal(x), hilbert(x, axis=-1), rtol=0, atol=1e-12)


@pytest.mark.parametrize("use_numba", [True, False])
def test_pseudo_energy_with_peak_is_both_quantities_from_one_filter(monkeypatch, use_numba):
    import echocal._numba as N
    from echocal.signal import RecordingWindow, make_pulse, matched_envelope, pseudo_energy
    from echocal.signal.processing import pseudo_energy_with_peak

    monkeypatch.setattr(N, "USE_NUMBA", use_numba)
    pulse = make_pulse("gabor", center_frequency=5e6)
    window = RecordingWindow(fs=100e6, start=0.0, n_samples=1024)
    x = np.random.default_rng(4).standard_normal((3, 2, 1024))
    energy, peak = pseudo_energy_with_peak(x, window, pulse)
    # the same numbers the separate functions compute (round-off only)
    np.testing.assert_allclose(energy, pseudo_energy(x, window, pulse), rtol=1e-12)
    np.testing.assert_allclose(peak, matched_envelope(x, pulse, window.fs).max(-1), rtol=1e-12)
    assert energy.shape == peak.shape == (3, 2)
